"""Branch switching at a branch point, a period doubling and a grazing point.

Every new branch is checked independently of the switch that found it: its orbits are
re-evaluated on a freshly built impact map (fixed points of ``P^K`` to 1e-10, not of a lower
power), and where the new orbits are attracting they are compared with brute-force iteration
of the simulated map.
"""
import json
from dataclasses import replace

import numpy as np
import pytest

from hybridpd import ImpactPair, PDGains, Reference
from hybridpd.analysis.continuation import continue_orbit
from hybridpd.analysis.periodic import find_orbit
from hybridpd.pair.continuation import branch_map, continue_symmetric, switch_branch
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.orbits import symmetric_orbit

W = 5.0


def _d(a, b, T):
    d = np.asarray(a, float) - np.asarray(b, float)
    d[..., 0] = (d[..., 0] + T / 2) % T - T / 2
    return np.max(np.abs(d))


def _fresh_map(branch, p):
    """The map at parameter p rebuilt from scratch (not via the switching code)."""
    f = branch.fixed
    kw = {k: f[k] for k in ("kp", "kv") if k in f}
    kw[branch.parameter_name] = p
    pair = ImpactPair(f["mu"], f["e"], f["L"], f["m2"])
    xm = f["xm"] if "xm" in f else symmetric_orbit(pair, PDGains(kw["kp"], kw["kv"]), W,
                                                   x10=f["x10"], case=f["case"]).xm
    return ImpactMap(pair, PDGains(kw["kp"], kw["kv"]), Reference(xm, W), f["case"])


def _check_new_branch(b, K):
    """Orbits of the new branch are fixed points of P^K to 1e-10 and not of P^(K/2)."""
    assert len(b) >= 3 and b.period == K
    for i in range(len(b)):
        P = _fresh_map(b, b.parameter[i])
        s = b.points[i]
        img = P.iterate(s, K)
        assert _d(img[K], s, P.period) < 1e-10
        if K > 1:
            assert _d(img[K // 2], s, P.period) > 1e-6


@pytest.fixture(scope="module")
def pitchfork():
    br = continue_symmetric(ImpactPair(0.1, 0.5, 0.75), PDGains(55, 0.5), W, "kp", 62.0)
    return br, br.events_of("fold")[0]


def test_branch_point_switch_gives_both_nonsymmetric_branches(pitchfork):
    br, ev = pitchfork
    sw = switch_branch(br, ev, 60.0)
    assert sw.kind == "branch_point" and sw.period == 1 and len(sw.starts) == 2
    assert abs(sw.critical_multiplier - 1) < 1e-8
    kc = ev.parameter
    o = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(sw.start_parameters[0], 0.5), W)
    for orb, p in zip(sw.starts, sw.start_parameters):
        assert abs(p - kc) < 1e-4                       # starts at the located branch point
        assert orb.converged and orb.minimal_period == 1
        assert _d(orb.s, o.fixed_point, orb.parameters["omega"] and 2 * np.pi / W) > 1e-4
    # the two branches are distinct (symmetric partners), each a family of fixed points
    b1, b2 = sw.branches
    assert b1.parameter[-1] == b2.parameter[-1] == 60.0
    assert np.max(np.abs(b1.points[-1] - b2.points[-1])) > 0.1
    for b in sw.branches:
        _check_new_branch(b, 1)
    # brute force at kp = 60: iterating P from the (unstable) symmetric orbit lands on one
    o60 = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(60, 0.5), W)
    P = ImpactMap(o60.pair, o60.gains, o60.reference())
    tr = P.iterate(o60.fixed_point + np.array([0, 1e-3, 0, 0]), 20000)
    assert np.linalg.norm(tr[-1] - tr[-2]) < 1e-10
    assert min(_d(b.points[-1], tr[-1], P.period) for b in sw.branches) < 1e-8


@pytest.fixture(scope="module")
def flip():
    o = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(60, 0.5), W)
    P = ImpactMap(o.pair, o.gains, o.reference())
    r = find_orbit(P, P.iterate(o.fixed_point + np.array([0, 1e-3, 0, 0]), 3000)[-1])
    br = continue_orbit(P.family("kp"), 60.0, 99.3, r)
    pd = min(br.events_of("period_doubling"), key=lambda ev: abs(ev.parameter - 99.24))
    return br, pd


def test_period_doubling_switch_starts_at_the_flip(flip):
    br, pd = flip
    kc = pd.parameter
    sw = switch_branch(br, pd, kc - 0.004)
    assert sw.kind == "period_doubling" and sw.period == 2 and len(sw.starts) == 1
    assert abs(sw.critical_multiplier + 1) < 1e-7
    orb, p = sw.starts[0], sw.start_parameters[0]
    # the start lies a step a along the flip eigenvector from the located flip point, at a
    # parameter O(a^2) away
    T = 2 * np.pi / W
    assert abs(p - kc) < 10 * sw.amplitude ** 2
    assert 0.5 * sw.amplitude < _d(orb.s, pd.point, T) < 2 * sw.amplitude
    assert orb.minimal_period == 2
    b = sw.branches[0]
    assert b.termination == "reached stop" and abs(b.parameter[0] - p) < 1e-12
    _check_new_branch(b, 2)
    # below the (supercritical) flip the 2-cycle attracts: brute force agrees to 1e-8
    Q = ImpactMap(ImpactPair(0.1, 0.5, 0.75), PDGains(kc - 0.004, 0.5),
                  Reference(br.fixed["xm"], W))
    tr = Q.iterate(pd.point + np.array([0, 1e-4, 0, 0]), 20000)
    assert _d(tr[-1], tr[-3], T) < 1e-10
    assert min(_d(b.points[-1], tr[-1], T), _d(b.points[-1], tr[-2], T)) < 1e-8
    assert b.stable[-1]


@pytest.mark.stored_data
def test_grazing_switch_finds_the_e01_double_impact_cycle():
    """Collocated, e = 0.1, kp = 10: the symmetric orbit (x10 = 1) is stable up to grazing
    at kv = 21.938 and has no flip or branch point; past grazing the motion settles on a
    2-cycle with a double impact. Followed back to kv = 20 it is the attractor that takes
    most of the basin slice there (found here by iterating from a grid point of that slice)."""
    pair = ImpactPair(0.1, 0.1, 0.75)
    br = continue_symmetric(pair, PDGains(10, 20), W, "kv", 23.0)
    assert not br.events_of("period_doubling") and not br.events_of("fold")
    g = br.events_of("grazing")[0]
    assert abs(g.parameter - 21.938) < 1e-3
    sw = switch_branch(br, g, 20.0)
    assert sw.kind == "grazing" and sw.period == 2 and sw.design == {"x10": 1.0, "n": 1}
    b = sw.branches[0]
    assert b.termination == "reached stop" and b.parameter[-1] == 20.0
    assert b.parameter[0] > g.parameter
    _check_new_branch(b, 2)
    walls = sorted(tuple(w for w, _ in it) for it in b.patterns[-1])
    assert walls == [(-1, -1, 1), (1,)]                     # the double impact
    assert b.stable[-1] and 0.5 < b.spectral_radius[-1] < 0.55
    # brute force at kv = 20 from a point of the basin slice
    o = symmetric_orbit(pair, PDGains(10, 20), W)
    P = ImpactMap(pair, PDGains(10, 20), o.reference())
    tr = P.iterate(np.array([0.3, -2.1, -2.3, 0.5]), 2000)
    assert min(_d(b.points[-1], tr[-1], P.period), _d(b.points[-1], tr[-2], P.period)) < 1e-8
    json.dumps(sw.to_dict())


def test_branch_map_rebuilds_the_map_on_the_parent_path(pitchfork):
    br, _ = pitchfork
    i = len(br) // 2
    P = branch_map(br, br.parameter[i])
    assert abs(P.reference.xm - br.xm[i]) < 1e-12 and P.gains.kp == br.parameter[i]
    assert _d(P(br.points[i]), br.points[i], P.period) < 1e-10


def test_switch_rejects_what_it_cannot_switch_at(pitchfork):
    br, ev = pitchfork
    with pytest.raises(ValueError, match="event.kind"):
        switch_branch(br, replace(ev, kind="neimark_sacker"))
    turning = replace(ev, detail="fold: the branch turns back (a real multiplier crosses +1)")
    with pytest.raises(ValueError, match="turning point"):
        switch_branch(br, turning)
    with pytest.raises(ValueError, match="amplitudes"):
        switch_branch(br, ev, amplitudes=(-1e-3,))
    with pytest.raises(ValueError, match="branch"):
        switch_branch("not a branch", ev)


@pytest.mark.slow
def test_the_switched_2cycle_takes_most_of_the_basin_slice():
    """The paper's basin slice at kv = 20 (x1 in [-3, 5], y1 in [-2, 10], y2 and phi of the
    symmetric fixed point; 60 x 60 grid, 1500 iterations, the paper's criterion): the 2-cycle
    found by branch switching attracts about 98.5 %, the symmetric orbit the rest."""
    from hybridpd.pair.basins import section_grid
    from hybridpd.pair.batch import impact_map

    pair = ImpactPair(0.1, 0.1, 0.75)
    br = continue_symmetric(pair, PDGains(10, 20), W, "kv", 23.0)
    b = switch_branch(br, br.events_of("grazing")[0], 20.0).branches[0]
    P = branch_map(b, 20.0)
    c0 = b.points[-1]
    c1 = P(c0)
    o = symmetric_orbit(pair, PDGains(10, 20), W)
    G = section_grid(o.fixed_point, 0.75, np.linspace(-3, 5, 60), np.linspace(-2, 10, 60))
    S = np.ascontiguousarray(G.reshape(-1, 4))
    assert np.all(S[:, 3] > 0)
    ok = np.ones(len(S), bool)
    for _ in range(1500):
        idx = np.flatnonzero(ok)
        out, st, _n = impact_map(P.params, P._c, np.ascontiguousarray(S[idx]), P.tol,
                                 P.max_impacts)
        S[idx] = out
        ok[idx] = st == 0
    T = P.period

    def crit(f):
        dphi = (S[:, 0] - f[0] + T / 2) % T - T / 2
        return ((S[:, 1] - f[1]) ** 2 + (S[:, 2] + S[:, 3] - f[2] - f[3]) ** 2
                + (S[:, 2] - f[2]) ** 2 + dphi ** 2)

    to2 = ok & ((crit(c0) < 1e-3) | (crit(c1) < 1e-3))
    to1 = ok & (crit(o.fixed_point) < 1e-3)
    # every point reaches one of the two (counts, not a sum of rounded shares)
    assert 0.98 < to2.mean() < 0.99 and int(to1.sum()) + int(to2.sum()) == to1.size
