"""``hybridpd bifurcation``: JSON output against independent orbits, files, bad input."""
import json
import subprocess
import sys

import numpy as np
import pytest

from hybridpd import ImpactPair, PDGains
from hybridpd.analysis.diagrams import load_diagram
from hybridpd.cli import main
from hybridpd.pair.orbits import symmetric_orbit

BASE = ["bifurcation", "--case", "collocated", "--mu", "0.1", "--e", "0.1", "--gamma", "0.75",
        "--omega", "5", "--n", "1", "--kp", "10"]


def test_cli_bifurcation_json_files_and_orbits(tmp_path):
    out, png = tmp_path / "kv.nc", tmp_path / "kv.png"
    r = subprocess.run([sys.executable, "-m", "hybridpd", *BASE, "--param", "kv", "18", "24",
                        "4", "--iterations", "400", "--keep", "40", "--follow", "--out",
                        str(out), "--plot", str(png), "--json"],
                       capture_output=True, text=True, timeout=600, check=False)
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert d["parameter"] == "kv" and d["values"] == [18.0, 20.0, 22.0, 24.0]
    # following from the symmetric orbit: period 1 up to its grazing (kv = 21.938), then
    # the period-2 double-impact motion
    assert d["period"] == [1, 1, 2, 2] and d["classification"] == ["periodic"] * 4
    T = 2 * np.pi / 5
    for i, kv in enumerate((18.0, 20.0)):
        o = symmetric_orbit(ImpactPair(0.1, 0.1, 0.75), PDGains(10, kv), 5.0)
        c = np.array(d["cycles"][i])
        dphi = (c[0, 0] - o.fixed_point[0] + T / 2) % T - T / 2
        assert abs(dphi) < 1e-8 and np.max(np.abs(c[0, 1:] - o.fixed_point[1:])) < 1e-8
        assert d["xm"][i] == pytest.approx(o.xm, rel=1e-12)
        # 30 averaged iterates; a complex dominant pair converges like 1/N (the precise
        # cross-checks are in test_bifdiagram.py)
        assert d["lyapunov"][i] == pytest.approx(np.log(o.spectral_radius), abs=1 / 30)
    assert len(d["cycles"][2]) == 2 and d["counts"]["periodic"] == 4
    diag = load_diagram(out)
    assert list(diag.period) == d["period"] and diag.follow and diag.fixed["kp"] == 10.0
    assert png.stat().st_size > 10_000


@pytest.mark.parametrize("extra,match", [
    (["--kv", "3", "--param", "kv", "10", "35", "5"], "must not also be given as --kv"),
    (["--kv", "3", "--param", "L", "1", "2", "5"], "--param NAME must be one of"),
    (["--param", "kv", "30", "10", "5"], "MIN must be < MAX"),
    (["--param", "kv", "10", "30", "1"], "NUM must be an integer >= 2"),
    (["--param", "kv", "10", "30", "x"], "must be numbers"),
    (["--param", "kv", "10", "30", "5", "--keep", "50", "--iterations", "20"],
     "must not exceed --iterations"),
    (["--param", "kv", "10", "30", "5", "--n", "2"], "odd"),
    (["--param", "kv", "10", "30", "5", "--out", "x.csv"], ".nc"),
    (["--param", "kp", "1", "30", "5"], "kp is swept"),
])
def test_cli_bifurcation_bad_input_one_line_exit_2(extra, match, capsys, tmp_path):
    argv = [*BASE, *extra]
    if "--out" not in extra:
        argv += ["--out", str(tmp_path / "d.nc")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and match in err and "Traceback" not in err


def test_cli_bifurcation_requires_the_unswept_parameters(capsys, tmp_path):
    i = BASE.index("--omega")
    argv = BASE[:i] + BASE[i + 2:]
    assert main([*argv, "--param", "kv", "10", "20", "3", "--out",
                 str(tmp_path / "d.nc")]) == 2
    err = capsys.readouterr().err
    assert "missing --omega" in err and err.count("\n") == 1


def test_cli_help_lists_the_command(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    assert "bifurcation" in capsys.readouterr().out
