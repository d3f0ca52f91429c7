"""A basin's shares are of all points of the slice: points off the section or inadmissible
are their own class, in no basin, and the summary says how many there are in one line."""
import json
from pathlib import Path

import numpy as np

from hybridpd.analysis.basins import Attractor, BasinResult, outcome
from hybridpd.cli import main

DRIVETRAIN = Path(__file__).resolve().parents[1] / "examples" / "models" / "drivetrain.toml"


def _basin():
    # 2 x 5 slice: 4 points reach the orbit, 2 off the section, 3 inadmissible, 1 diverged
    lab = np.array([[0, 0, 0, 0, -2], [-5, -5, -6, -6, -6]])
    atts = (Attractor(0, "period-1 orbit", 1), outcome(-2), outcome(-5), outcome(-6))
    return BasinResult(np.arange(5.0), np.arange(2.0), lab, atts,
                       metadata={"model": "m.toml"})


def test_shares_are_of_all_points_of_the_slice():
    b = _basin()
    assert b.converged_fraction == 0.4 and b.fraction(0) == 0.4
    assert b.fraction(-2) == 0.1 and b.fraction(-5) == 0.2 and b.fraction(-6) == 0.3
    assert abs(sum(b.fraction(a.label) for a in b.attractors) - 1.0) < 1e-12
    assert b.outside == 5
    d = b.to_dict()
    assert d["converged_fraction"] == 0.4 and d["points"] == 10 and d["outside"] == 5
    assert [a["fraction"] for a in d["attractors"]] == [0.4, 0.1, 0.2, 0.3]


def test_summary_says_in_one_line_how_many_points_are_outside():
    lines = _basin().summary()
    outside = [ln for ln in lines if ln.startswith("off the section or inadmissible")]
    assert outside == [("off the section or inadmissible: 5 of the 10 points (50.00 %), in no "
                        "basin: every share below is of all 10 points")]
    assert "period-1 orbit: 40.00 % of the 10 points, area 4" in lines
    full = BasinResult(np.arange(2.0), np.arange(2.0), np.zeros((2, 2), int),
                       (Attractor(0, "period-1 orbit", 1),))
    assert not any("off the section" in ln for ln in full.summary())


def test_model_basin_never_counts_off_section_points_as_converged(capsys):
    # the release section of the drivetrain: the slice's points with motor_dot of the wrong
    # sign are off the section; every point on it reaches the orbit
    rc = main(["basin", "--model", str(DRIVETRAIN), "--event", "release", "--set",
               "controller.kv", "2", "--x", "motor", "-1.5", "1.5", "5", "--y", "motor_dot",
               "-6", "6", "5", "--iterations", "50", "--quiet", "--json"])
    d = json.loads(capsys.readouterr().out)
    assert rc == 0
    lab = np.array(d["labels"])
    n0 = int((lab == 0).sum())
    assert d["outside"] > 0 and d["points"] == lab.size == 25
    assert d["converged_fraction"] == n0 / lab.size < 1.0
    assert n0 + d["outside"] <= lab.size
