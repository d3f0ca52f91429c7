"""Certified maps on coarse grids: cells proved where they are of one class.

A coarse cell is subdivided adaptively until all its parts are proved in one class; the
automatic depth cuts a cell holding ``4^k`` cells of the 101 x 101 grid ``2 k`` more times
than those (``k`` halvings along each axis), within a budget of parts per cell. The proved
classes are checked against the package's point classifier at random interior points and
against an independent implementation of the paper (``tests/_paper_orbit.py``: ``expm``
flows, a linear solve of (13)-(14), viability by dense sampling, finite-difference
multipliers) at interior points.
"""
import numpy as np
import pytest
from _paper_orbit import paper_class

import hybridpd as hp
from hybridpd.pair import proofs
from hybridpd.pair.certified import (
    STOPS,
    auto_depth,
    auto_parts,
    certified_map,
    certify_cells,
    resolve_parts,
)
from hybridpd.pair.prooftree import prove_cells

pytest.importorskip("flint")

FIXED = dict(mu=0.1, gamma=0.75, omega=5.0)
POINT = dict(mu=0.1, L=0.75, omega=5.0)


def _point_classes(case, e, kp, kv):
    r = hp.symmetric_orbits(kp, kv, e=e, case=case, **POINT)
    return np.where(~r.exists, 3, np.where(r.stable, 1, 2))


def _leaf_area(tree, cell):
    lv, sel = tree.leaves, tree.leaf_cell == cell
    return float(np.sum((lv.hi["kpt"][sel] - lv.lo["kpt"][sel])
                        * (lv.hi["kvt"][sel] - lv.lo["kvt"][sel])))


def test_coarse_stable_cells_proved_and_checked_independently():
    # collocated, e = 0.1: near kp = 0.1 a multiplier approaches 1 (0.99 at kv = 20) and for
    # kv of 6 to 20 the orbit comes back to within 1-2 % of L of the wall it left; these
    # cells need parts finer than the former automatic depth (9 for 3 x 3 cells) gave
    x, y = ("kp", 0.1, 10.0, 3), ("kv", 3.0, 20.0, 3)
    cm = certified_map("collocated", x=x, y=y, e=[0.1], **FIXED)
    assert cm.depth == auto_depth(9) == 12 and cm.max_parts == auto_parts(12)
    flags = cm.flags[0]
    assert (flags == 1).all(), flags                       # every cell proved stable
    assert cm.arb_unconfirmed.tolist() == [0]
    assert {STOPS[s] for s in cm.stops[0].ravel()} == {"proved"}
    assert "why undecided" not in cm.summary()[0]          # no undecided cell to explain
    # the hardest cell, undecided at depth 9: its subdivision stops at the depth bound there
    xe, ye = cm.x_edges, cm.y_edges
    boxes, _ = proofs.scaled_boxes(kp=(xe[0], xe[1]), kv=(ye[1], ye[2]), e=0.1, m2=1.0,
                                   **FIXED)
    shallow = prove_cells("collocated", 1, boxes, depth=9)
    assert shallow.cls.tolist() == [0] and STOPS[shallow.cell_stop[0]] == "depth"
    rng = np.random.default_rng(1)
    for j in range(3):
        for i in range(3):
            kp = rng.uniform(xe[i], xe[i + 1], 50)
            kv = rng.uniform(ye[j], ye[j + 1], 50)
            assert (_point_classes("collocated", 0.1, kp, kv) == flags[j, i]).all(), (j, i)
            # the independent implementation at the centre and a random interior point
            for a, b in ((0.5, 0.5), tuple(rng.uniform(0.05, 0.95, 2))):
                p, v = xe[i] + a * (xe[i + 1] - xe[i]), ye[j] + b * (ye[j + 1] - ye[j])
                assert paper_class("collocated", p, v, e=0.1, **POINT) == 1, (p, v)


def test_proved_cells_of_a_coarse_noncollocated_grid_agree_with_their_points():
    # three classes' boundaries cross this grid: every proved cell must agree with 50
    # random interior points of the package's point classifier and, at its centre, with the
    # independent implementation; an undecided cell says why its subdivision stopped
    x, y = ("kp", 5.0, 9.0, 4), ("kv", 0.1, 4.0, 4)
    cm = certified_map("noncollocated", x=x, y=y, e=[0.5], **FIXED)
    flags, stops = cm.flags[0], cm.stops[0]
    assert {1, 2} <= set(flags.ravel().tolist())
    assert cm.arb_unconfirmed.tolist() == [0]
    if (flags == 0).any():
        assert "why undecided: mixed" in cm.summary()[0]
    assert cm.to_dict()["stops"] == cm.stops.tolist()
    xe, ye = cm.x_edges, cm.y_edges
    rng = np.random.default_rng(2)
    for j in range(4):
        for i in range(4):
            if flags[j, i] == 0:
                assert STOPS[stops[j, i]] in ("mixed", "depth", "budget"), stops[j, i]
                continue
            assert STOPS[stops[j, i]] == "proved"
            kp = rng.uniform(xe[i], xe[i + 1], 50)
            kv = rng.uniform(ye[j], ye[j + 1], 50)
            assert (_point_classes("noncollocated", 0.5, kp, kv) == flags[j, i]).all(), (j, i)
            c = paper_class("noncollocated", 0.5 * (xe[i] + xe[i + 1]),
                            0.5 * (ye[j] + ye[j + 1]), e=0.5, **POINT)
            assert c == flags[j, i], (j, i)


def test_a_cell_over_its_budget_is_never_proved_by_its_other_parts():
    # two cells subdivided together: when the budget stops one while the other goes on, the
    # stopped cell's undecided parts still count (a cell is proved only when its leaves
    # cover it)
    kp = (np.array([3.831, 8.806]), np.array([6.319, 11.29]))
    kv = (np.array([0.1, 0.1]), np.array([3.219, 3.219]))
    boxes, _ = proofs.scaled_boxes(kp=kp, kv=kv, mu=0.1, e=0.1, gamma=0.75, omega=5.0,
                                   m2=1.0)
    areas = (boxes.hi["kpt"] - boxes.lo["kpt"]) * (boxes.hi["kvt"] - boxes.lo["kvt"])
    seen = set()
    for budget in (100, 150, 400):
        tree = prove_cells("collocated", 1, boxes, depth=10, max_parts=budget)
        for c in range(2):
            seen.add(STOPS[tree.cell_stop[c]])
            if tree.cls[c] != 0:
                assert STOPS[tree.cell_stop[c]] == "proved"
                np.testing.assert_allclose(_leaf_area(tree, c), areas[c], rtol=1e-12)
            else:
                assert STOPS[tree.cell_stop[c]] == "budget"
                assert _leaf_area(tree, c) == 0.0
    assert seen == {"proved", "budget"}


def test_budget_and_depth_rules():
    assert [auto_depth(n) for n in (101 * 101, 51 * 51, 81, 9, 1)] == [3, 5, 10, 12, 12]
    assert auto_depth(200 * 200) == 3
    assert [auto_parts(d) for d in (0, 3, 8, 9, 12)] == [1, 15, 511, 512, 512]
    assert resolve_parts("auto", 3) == 15 and resolve_parts(None, 3) is None
    assert resolve_parts(7, 3) == 7
    with pytest.raises(ValueError, match="max_parts"):
        resolve_parts("many", 3)
    with pytest.raises(ValueError, match="max_parts"):
        resolve_parts(0, 3)
    with pytest.raises(ValueError, match="max_parts"):
        certify_cells("collocated", kp=(9.0, 10.0), kv=(19.0, 20.0), e=0.5, max_parts=-1,
                      **FIXED)
    with pytest.raises(ValueError, match="max_parts"):
        certified_map("collocated", x=("kp", 9, 11, 2), y=("kv", 19, 21, 2), e=[0.5],
                      max_parts="lots", **FIXED)
    r = certify_cells("collocated", kp=(9.0, 10.0), kv=(19.0, 20.0), e=0.5, **FIXED)
    assert r.stops.shape == r.flags.shape and STOPS[int(r.stops)] == "proved"
