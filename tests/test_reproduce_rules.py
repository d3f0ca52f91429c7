"""The verdict rules (CONVENTIONS.md, "Verdict rules") on hand-made data, one rule at a time."""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from hybridpd.reproduce import conclusions as C
from hybridpd.reproduce import rules as R
from hybridpd.reproduce.basins import boundary_distance
from hybridpd.reproduce.study import EndPoint, StableInterval, choose_m2, series_125


def test_four_verdicts_only():
    assert R.VERDICTS == ("agrees", "contradicted", "depends", "unresolved")
    with pytest.raises(ValueError, match="verdict"):
        R.combine(["agrees", "not measured"])
    with pytest.raises(ValueError, match="verdict"):
        R.resolution("maybe", "agrees")


def test_share_reports_cells_and_grid():
    rec = R.share(7 / 1681, (41, 41))
    assert rec["cells"] == 7 and rec["of"] == 1681 and rec["grid"] == [41, 41]
    for bad in (-0.1, 1.1):
        with pytest.raises(ValueError, match="fraction"):
            R.share(bad, (4, 4))


@pytest.mark.parametrize("vs, expected", [
    (["agrees", "agrees"], "agrees"),
    (["contradicted"], "contradicted"),
    (["agrees", "contradicted"], "depends"),
    (["agrees", "contradicted", "unresolved"], "depends"),
    (["agrees", "unresolved"], "unresolved"),
    (["depends", "agrees"], "depends"),
    ([], "unresolved"),
])
def test_combine_across_conventions_and_m2(vs, expected):
    assert R.combine(vs) == expected


def test_resolution_two_grids():
    assert R.resolution("agrees", "agrees") == "agrees"
    assert R.resolution("depends", "depends") == "depends"
    assert R.resolution("agrees", "contradicted") == "unresolved"
    assert R.resolution("contradicted", "unresolved") == "unresolved"


def test_trend_looks_at_the_whole_range_not_consecutive_steps():
    x = [0.1, 0.2, 0.4, 0.8]
    cells = 1000
    # every step but one goes down, yet the share ends above where it was at 0.2
    s = np.array([0.600, 0.585, 0.590, 0.683])
    t = R.trend(x, s, cells)
    assert t["verdict"] == "contradicted"
    assert t["interval"] == [0.2, 0.8]          # names where it increases
    np.testing.assert_allclose(t["violation_cells"], (0.683 - 0.585) * cells, rtol=1e-12)
    # a last value below the first says nothing about the middle
    s = np.array([0.60, 0.50, 0.58, 0.55])
    t = R.trend(x, s, cells)
    assert s[-1] < s[0] and t["verdict"] == "contradicted" and t["interval"] == [0.2, 0.4]


def test_trend_tolerates_two_cells_and_no_more():
    x = [1, 2, 3]
    cells = 100
    assert R.trend(x, [0.50, 0.52, 0.40], cells)["verdict"] == "agrees"       # +2 cells
    # 7 then 9 cells of 1681: exactly two cells, whatever the rounding of 9/1681 - 7/1681
    t = R.trend([1e-4, 0.1], [7 / 1681, 9 / 1681], 1681)
    assert t["verdict"] == "agrees"
    np.testing.assert_allclose(t["violation_cells"], 2.0, rtol=0, atol=1e-9)
    assert R.trend(x, [0.50, 0.53, 0.40], cells)["verdict"] == "contradicted"  # +3 cells
    inc = R.trend(x, [0.99, 1.00, 0.98], cells, direction="increasing")
    assert inc["verdict"] == "agrees"                                          # saturated
    inc = R.trend(x, [0.40, 0.80, 0.70], cells, direction="increasing")
    assert inc["verdict"] == "contradicted" and inc["interval"] == [2.0, 3.0]
    with pytest.raises(ValueError, match="direction"):
        R.trend(x, [0, 0, 0], cells, direction="up")
    with pytest.raises(ValueError, match="same length"):
        R.trend(x, [0, 0], cells)


def _touch(c, n):
    return {"collocated": c, "noncollocated": n}


def test_basin_comparison_cannot_be_decided_by_a_full_window():
    # both basins fill the window: equal areas measure the window, not the basins
    r = R.basin_comparison([323.2], [323.2], _touch([True], [True]))
    assert r["verdict"] == "unresolved" and r["ratio_bounds"] == [[0.0, None]]
    # inside the window: decided
    assert R.basin_comparison([10.0, 4.0], [12.0, 5.0],
                              _touch([False] * 2, [False] * 2))["verdict"] == "agrees"
    assert R.basin_comparison([10.0], [3.0], _touch([False], [False]))["verdict"] \
        == "contradicted"


def test_basin_comparison_uses_lower_bounds():
    # the collocated basin touches the edge and is already 10x the other: contradicted
    r = R.basin_comparison([100.0], [10.0], _touch([True], [False]))
    assert r["verdict"] == "contradicted"
    np.testing.assert_allclose(r["ratio_bounds"][0], [0.0, 0.1], rtol=1e-12)
    # touching, and similar so far: the true ratio may leave the range
    assert R.basin_comparison([10.0], [12.0], _touch([True], [False]))["verdict"] \
        == "unresolved"
    # an empty basin beside a non-empty one: no window makes them similar
    assert R.basin_comparison([None], [5.0], _touch([False], [True]))["verdict"] \
        == "contradicted"
    assert R.basin_comparison([None], [None], _touch([False], [False]))["verdict"] \
        == "unresolved"


def test_conclusion_checks_on_hand_made_shares():
    g = (10, 10)
    big = {"exists": [0.5, 0.8, 1.0], "stability": [1.0, 1.0, 1.0], "both": [0.5, 0.8, 1.0]}
    small = {"exists": [0.3, 0.2, 0.1], "stability": [0.05, 0.03, 0.01],
             "both": [0.05, 0.03, 0.01]}
    e = [0.1, 0.5, 0.9]
    c1 = C.check_1(big, small, g)
    assert c1["verdict"] == "agrees" and c1["by_quantity"]["exists"]["verdict"] == "contradicted"
    assert c1["by_quantity"]["both"]["collocated"][0]["cells"] == 50
    assert C.check_1(small, big, g)["verdict"] == "contradicted"
    assert C.check_2(big, small, g, e)["verdict"] == "agrees"
    assert C.check_2(small, big, g, e)["verdict"] == "contradicted"
    assert C.check_3(big, g)["verdict"] == "agrees"
    assert C.check_3(small, g)["verdict"] == "contradicted"
    assert C.check_4([0.5, 0.5, 0.5], [0.4, 0.6, 0.3])["verdict"] == "agrees"
    assert C.check_4([0.5, 0.5, 0.5], [None, 0.6, 0.3])["verdict"] == "contradicted"
    assert C.check_4_necessary([True] * 3, [True, False, True]) == "contradicted"
    assert C.check_4_necessary([True] * 3, [True] * 3) == "unresolved"


def test_series_125_and_the_m2_rule():
    assert series_125(0.15, 1.1) == [0.2, 0.5, 1.0]
    assert series_125(100, 100) == [100.0]
    end = lambda m2, kind="stability": EndPoint(m2, kind, 0.0, True)
    top = end(1000.0, "window")
    ivs = {("n", 0.1): [StableInterval(end(3.6968), top)],
           ("n", 0.9): [StableInterval(end(53.786), top)],
           ("c", 0.1): [StableInterval(end(0.91355), top)]}
    assert choose_m2(ivs, (0.1, 1000.0)) == 100.0
    # independent of where the study stops
    top2 = end(1e5, "window")
    assert choose_m2({k: [StableInterval(v[0].lo, top2)] for k, v in ivs.items()},
                     (0.1, 1e5)) == 100.0
    # a threshold on a series value is itself chosen
    assert choose_m2({1: [StableInterval(end(50.0), top)]}, (0.1, 1000.0)) == 50.0
    # a closed common interval: the smallest series value inside it
    assert choose_m2({1: [StableInterval(end(3.0), end(40.0))]}, (0.1, 1000.0)) == 5.0
    assert choose_m2({1: [StableInterval(end(3.0), end(4.0))]}, (0.1, 1000.0)) is None
    assert choose_m2({1: [], 2: [StableInterval(end(3.0), top)]}) is None


def test_boundary_distance_on_a_hand_made_basin():
    x1 = np.linspace(-2.0, 2.0, 41)
    y1 = np.linspace(0.0, 20.0, 41)
    X, Y = np.meshgrid(x1, y1)
    omega, x10, L = 5.0, 1.0, 0.75
    fx, fy = 0.0, 10.0                  # fixed point: x1* = z1 + L, y1* = z2 + z4
    inside = np.hypot(X - fx, (Y - fy) / omega) < 1.0
    labels = np.where(inside, 0, -2)
    b = SimpleNamespace(x1=x1, y1=y1, labels=labels, window=(-2.0, 2.0, 0.0, 20.0),
                        fixed_point=np.array([0.0, fx - L, 4.0, fy - 4.0]),
                        metadata={"L": L})
    d = boundary_distance(b, x10=x10, omega=omega)
    assert not d["lower_bound"]
    # the nearest grid point outside the unit disc, within one cell
    assert 1.0 <= d["distance"] <= 1.0 + d["cell"]
    # a basin filling the window: the distance to the nearest edge, as a lower bound
    b.labels = np.zeros_like(labels)
    d = boundary_distance(b, x10=x10, omega=omega)
    assert d["lower_bound"] and math.isclose(d["distance"], 2.0, rel_tol=1e-12)
