"""Basin mapper: labels against direct long simulations; early exits change no label."""
import numpy as np
import pytest

from hybridpd import ImpactPair, PDGains
from hybridpd.analysis.impactmap import ImpactMap
from hybridpd.analysis.orbits import symmetric_orbit
from hybridpd.sweeps.basins import (
    LABELS,
    ImpactMapper,
    basin_of_attraction,
    load_basin,
    section_grid,
)

CASES = [("collocated", 0.5, 10.0, 20.0), ("collocated", 0.1, 10.0, 20.0),
         ("noncollocated", 0.1, 5.4, 2.5), ("noncollocated", 0.5, 10.0, 20.0)]


def mapper_for(case, e, kp, kv, **kw):
    o = symmetric_orbit(ImpactPair(0.1, e, 0.75), PDGains(kp, kv), 5.0, case=case)
    assert o.exists
    return o, ImpactMapper(ImpactMap(o.pair, o.gains, o.reference(), case), o.fixed_point, **kw)


@pytest.mark.parametrize("case,e,kp,kv", CASES)
def test_early_exits_give_identical_labels(case, e, kp, kv):
    _o, fast = mapper_for(case, e, kp, kv)
    _, slow = mapper_for(case, e, kp, kv, early_exit=False)
    b1 = basin_of_attraction(fast, (-3, 5, 13), (-2, 10, 13))
    b2 = basin_of_attraction(slow, (-3, 5, 13), (-2, 10, 13))
    np.testing.assert_array_equal(b1.labels, b2.labels)
    assert b2.iterations.max() <= 1500


@pytest.mark.parametrize("case,e,kp,kv", CASES[:3])
def test_labels_agree_with_direct_long_simulation(case, e, kp, kv):
    """Sampled grid points: iterate P 1500 times directly and apply the paper's criterion."""
    o, m = mapper_for(case, e, kp, kv)
    P = m.map
    xs, ys = np.linspace(-3, 5, 7), np.linspace(-2, 10, 7)
    grid = section_grid(o.fixed_point, 0.75, xs, ys).reshape(-1, 4)
    lab, _ = m.labels(grid)
    T = P.period
    rng = np.random.default_rng(0)
    for i in rng.choice(len(grid), 12, replace=False):
        s = grid[i]
        if s[3] <= 0:
            assert LABELS[lab[i]] == "off_section"
            continue
        traj = P.iterate(s, 1500)
        last = traj[-1]
        if not np.all(np.isfinite(last)):
            assert LABELS[lab[i]] in ("diverged", "zeno_sticking", "unresolved")
            continue
        dphi = (last[0] - o.fixed_point[0] + T / 2) % T - T / 2
        d = np.array([last[1] - o.fixed_point[1],
                      last[2] + last[3] - o.fixed_point[2] - o.fixed_point[3],
                      last[2] - o.fixed_point[2], dphi])
        expect = "converged" if d @ d < 1e-3 else "not_converged"
        assert LABELS[lab[i]] == expect


def test_certified_ball_is_invariant_under_iteration():
    o, m = mapper_for("collocated", 0.5, 10.0, 20.0)
    assert m.certified_radius > 0
    Lq = np.linalg.cholesky(m.cert_Q)
    rng = np.random.default_rng(3)
    for _ in range(20):
        u = rng.normal(size=4)
        u /= np.linalg.norm(u)
        d = np.linalg.solve(Lq.T, u) * m.certified_radius * 0.99
        traj = m.map.iterate(o.fixed_point + d, 30)
        dev = traj - o.fixed_point
        q = np.einsum("ij,jk,ik->i", dev, m.cert_Q, dev)
        assert np.all(q <= m.cert_r2 * 1.0001)


def test_basin_save_load_and_executors_agree(tmp_path):
    _o, m = mapper_for("collocated", 0.5, 10.0, 20.0)
    b1 = basin_of_attraction(m, (-3, 5, 9), (-2, 10, 8))
    b2 = basin_of_attraction(m, (-3, 5, 9), (-2, 10, 8), executor="processes", max_workers=2,
                             chunk_size=10)
    np.testing.assert_array_equal(b1.labels, b2.labels)
    b1.save(tmp_path / "b.npz")
    b3 = load_basin(tmp_path / "b.npz")
    np.testing.assert_array_equal(b3.labels, b1.labels)
    assert b3.metadata["kp"] == 10.0 and b3.converged_fraction == b1.converged_fraction


def test_bad_grids_and_mapper_input():
    o, m = mapper_for("collocated", 0.5, 10.0, 20.0)
    for bad in ((1, 0, 5), (0, 1, 0), (0, float("nan"), 3), (0, 1, 2.5)):
        with pytest.raises(ValueError, match="x1"):
            basin_of_attraction(m, bad, (0, 1, 3))
    with pytest.raises(ValueError, match="fixed_point"):
        ImpactMapper(m.map, [0, 1, 2])
    with pytest.raises(ValueError, match="n_iter"):
        ImpactMapper(m.map, o.fixed_point, n_iter=0)
