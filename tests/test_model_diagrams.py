"""Brute-force diagrams of model files: the detected periods confirmed by iterating the map."""
import json

import numpy as np
from _pair_model import PAIR, PAIR_TOML

from hybridpd.analysis.diagrams import load_diagram
from hybridpd.analysis.model_orbits import SectionSpec
from hybridpd.cli import main
from hybridpd.mechanics.params import ModelTemplate
from hybridpd.sweeps.model_diagrams import model_diagram


def test_pair_file_diagram_periods_confirmed(tmp_path, capsys):
    d = model_diagram(PAIR, ("controller.kv", 2.0, 30.0, 5), iterations=150, keep=30,
                      event="impact", progress=False)
    assert d.points.shape == (5, 30, 4) and d.names == ("phi", "x1_dot", "x2", "x2_dot")
    tpl = ModelTemplate(PAIR)
    for i, v in enumerate(d.values):
        if d.periods[i] == 0:
            continue
        P = SectionSpec(event="impact").section_map(tpl.model({"controller.kv": v}))
        s = d.points[i, -1]
        img = P.iterate(s, int(d.periods[i]))[-1]
        np.testing.assert_allclose(P.section.wrap(img - s), 0.0, atol=1e-5,
                                   err_msg=f"kv = {v}: not periodic with period "
                                           f"{d.periods[i]}")
    assert d.counts()["periodic"] >= 1
    out = tmp_path / "d.nc"
    assert main(["bifurcation", "--model", "-", "--param", "controller.kv", "2", "30",
                 "5", "--out", str(out), "--case", "collocated"]) == 2
    assert "--case" in capsys.readouterr().err
    d.save(out)
    back = load_diagram(out)
    np.testing.assert_allclose(back.points, d.points, rtol=0, atol=0)
    assert main(["plot", str(out), "--out", str(tmp_path / "d.png")]) == 0


def test_bifurcation_cli_with_a_model_file(tmp_path, capsys):
    f = tmp_path / "pair.toml"
    f.write_text(PAIR_TOML)
    out = tmp_path / "d.zarr"
    assert main(["bifurcation", "--model", str(f), "--param", "contact.0.restitution", "0.3",
                 "0.7", "3", "--iterations", "100", "--keep", "20", "--out", str(out),
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["parameter"] == "contact.0.restitution" and len(d["classification"]) == 3
    np.testing.assert_allclose(d["values"], [0.3, 0.5, 0.7], rtol=1e-15)
