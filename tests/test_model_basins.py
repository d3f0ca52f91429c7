"""Basins of model files: labelled by attractor, checked by iterating the map, drawn by
``hybridpd plot``."""
import json

import numpy as np
from _basins import model_basin
from _pair_model import PAIR, PAIR_TOML

from hybridpd.analysis.basins import load_basin
from hybridpd.analysis.model_orbits import SectionSpec
from hybridpd.cli import main
from hybridpd.mechanics.params import ModelTemplate


def test_pair_file_basin_labels_confirmed_by_iterating_the_map(tmp_path, capsys):
    b = model_basin(PAIR, ("x2", -1.0, 1.0, 5), ("x1_dot", -1.0, 3.0, 5), n_iter=150,
                    event="impact")
    assert b.labels.shape == (5, 5) and b.attractors[0].label == 0
    assert b.attractors[0].stable and b.axes == ("x2", "x1_dot")
    assert (b.labels == 0).sum() >= 1
    # independently: iterate the simulated map from every point labelled 0
    P = SectionSpec(event="impact").section_map(ModelTemplate(PAIR).model())
    names = P.section.names
    ix, iy = names.index("x2"), names.index("x1_dot")
    for r, c in np.argwhere(b.labels == 0):
        s = b.fixed_point.copy()
        s[ix], s[iy] = b.x[c], b.y[r]
        it = P.iterate(s, 300)
        d = P.section.wrap(it[-1] - b.fixed_point)
        np.testing.assert_allclose(d, 0.0, atol=1e-6, err_msg=f"cell {r, c} labelled 0")
    for r, c in np.argwhere(b.labels == -5):        # off the section: the flow does not fire
        s = b.fixed_point.copy()
        s[ix], s[iy] = b.x[c], b.y[r]
        assert not P.apply(s).ok
    out = tmp_path / "b.nc"
    assert main(["basin", "--model", "-", "--x", "x2", "-1", "1", "3"]) == 2   # no --y
    capsys.readouterr()
    path = b.save(out)
    back = load_basin(path)
    np.testing.assert_allclose(back.labels, b.labels, rtol=0, atol=0)
    assert back.summary() == b.summary()
    assert main(["plot", str(out), "--out", str(tmp_path / "b.png")]) == 0
    assert (tmp_path / "b.png").stat().st_size > 10_000


def test_basin_cli_with_a_model_file(tmp_path, capsys):
    f = tmp_path / "pair.toml"
    f.write_text(PAIR_TOML)
    assert main(["basin", "--model", str(f), "--x", "x2", "-0.5", "0.5", "3", "--y",
                 "x1_dot", "0", "2", "3", "--set", "controller.kp", "12", "--iterations",
                 "100", "--json", "--quiet"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["metadata"]["values"] == {"controller.kp": 12.0}
    assert np.array(d["labels"]).shape == (3, 3)
    assert main(["basin", "--model", str(f), "--x", "x2", "-0.5", "0.5", "3", "--y",
                 "x1_dot", "0", "2", "3", "--set", "controller.kq", "12"]) == 2
    assert "controller.kq" in capsys.readouterr().err


def test_basin_cli_without_axes_takes_the_default_slice_through_the_orbit(tmp_path, capsys):
    from matplotlib.image import imread

    from hybridpd.analysis.model_orbits import default_axes

    f = tmp_path / "pair.toml"
    f.write_text(PAIR_TOML)
    png = tmp_path / "b.png"
    assert main(["basin", "--model", str(f), "--iterations", "60", "--json", "--quiet",
                 "--plot", str(png)]) == 0
    d = json.loads(capsys.readouterr().out)
    labels = np.array(d["labels"])
    assert labels.shape == (21, 21)
    # the same slice given explicitly: first two section coordinates, s_i +- max|s_0|, |s_1|
    b = model_basin(f, n_iter=60)
    x, y = default_axes(b.fixed_point, b.names)
    assert (b.x_name, b.y_name) == (x[0], y[0]) == (b.names[0], b.names[1])
    r = max(abs(b.fixed_point[0]), abs(b.fixed_point[1]))
    np.testing.assert_allclose([b.x[0], b.x[-1]], [b.fixed_point[0] - r, b.fixed_point[0] + r])
    same = model_basin(f, x, y, n_iter=60)
    assert np.array_equal(same.labels, b.labels) and np.array_equal(labels, b.labels)
    assert imread(png).shape[1] == 1050                       # 3.5 in at 300 dpi
    assert main(["basin", "--model", str(f), "--x", "x2", "-1", "1", "3"]) == 2  # x alone
    assert "or neither" in capsys.readouterr().err
