"""Every kept specialisation of the map protocol against the general path.

The general :class:`~hybridpd.analysis.hybridmap.SectionMap` on the pair's automaton (exact
flows, saltation ``DP``) is the reference. Kept specialisations:

* :class:`~hybridpd.pair.impactmap.ImpactMap` (compiled closed-form engine, symbolic
  ``DP``): 36 parameter points (both cases, three ``e``, three gain pairs, orders ``n = 1, 3``);
* the LTI orbits' closed forms (exact flights under any LTI controller, ``DP`` by implicit
  differentiation, :func:`~hybridpd.pair.lti.lti_symmetric_orbit`): 20 points (five
  controllers, both cases, two ``e``).

At each point, near the symmetric orbit: ``P`` (phase wrapped), the return time and state,
the signature (the sequence of jumps), ``DP`` (relative to its largest entry), ``P^2``, the
orbit found by the general Newton and its multipliers; on a few points, basin labels.
Tolerances: ``P`` and the return time to ``1e-9`` times the coordinate scale, and times
``max(1, |DP^k| / 100)`` (both are exact up to root location, ``~1e-13``, which ``DP^k``
amplifies: the non-collocated multipliers reach ``3e3``), ``DP`` to ``1e-7`` relative (``1e-4`` where ``ImpactMap`` falls back to finite
differences, off the simple pattern).
"""
import itertools

import control as ct
import numpy as np
import pytest

from hybridpd import ImpactPair, PDGains
from hybridpd.analysis.hybridmap import SectionMap
from hybridpd.analysis.mappers import mapper
from hybridpd.analysis.maps import MapResult, PoincareMap
from hybridpd.analysis.periodic import find_orbit
from hybridpd.loop import pd_controller
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.lti import filtered_pd, filtered_pid, lead_lag, lti_symmetric_orbit
from hybridpd.pair.orbits import symmetric_orbit
from hybridpd.pair.section import impact_pair_section

W = 5.0
CASES = ("collocated", "noncollocated")
PAIR_GRID = list(itertools.product(CASES, (0.3, 0.5, 0.8), ((10, 20), (5, 8), (25, 10)), (1, 3)))
CONTROLLERS = {
    "pd": pd_controller(10, 20),
    "filtered_pd": filtered_pd(10, 20, 0.01),
    "filtered_pid": filtered_pid(10, 2, 20, 0.01),
    "lead_lag": lead_lag(10, 1.0, 0.1, 1.0, 5.0),
    "pid_2input": ct.ss([[0.0]], [[1.0, 0.0]], [[2.0]], [[10.0, 20.0]]),
}
LTI_GRID = list(itertools.product(sorted(CONTROLLERS), CASES, (0.3, 0.5)))


def test_grid_has_at_least_50_points():
    assert len(PAIR_GRID) + len(LTI_GRID) >= 50


def compare(G: SectionMap, S: PoincareMap, s, k=1, dp=True):
    """Compare one application of ``P^k`` of the specialisation ``S`` with the general ``G``."""
    a, b = G.apply(s, k, jacobian=True), S.apply(s, k, jacobian=dp)
    assert isinstance(b, MapResult)
    assert a.ok == b.ok, (a.status, b.status)
    if not a.ok:
        return a, b
    # rounding and root location (~1e-13) are amplified by DP^k
    amp = 1e-9 * max(1.0, np.abs(a.DP).max() / 100) if np.all(np.isfinite(a.DP)) else 1e-6
    sc = np.maximum(1.0, np.abs(a.s))
    np.testing.assert_allclose(G.wrap(b.s - a.s) / sc, 0, atol=amp, err_msg="P")
    np.testing.assert_allclose(b.t_hit, a.t_hit, rtol=0, atol=amp * max(1, a.t_hit),
                               err_msg="return time")
    np.testing.assert_allclose(b.z_hit, a.z_hit, rtol=0,
                               atol=amp * max(1, np.abs(a.z_hit).max()), err_msg="state")
    assert b.signature == a.signature
    assert b.grazing == a.grazing
    if dp and not a.grazing:
        # a non-simple return's DP is a finite difference in ImpactMap (error ~h = 1e-6)
        simple = a.signature == (("wall+", "crossing"), ("wall-", "crossing")) * k
        tol = 1e-7 if simple or not isinstance(S, ImpactMap) else 1e-4
        np.testing.assert_allclose(b.DP, a.DP, rtol=0, atol=tol * np.abs(a.DP).max(),
                                   err_msg="DP")
    return a, b


@pytest.mark.parametrize("case,e,gains,n", PAIR_GRID)
def test_impact_map_equals_the_general_map(case, e, gains, n):
    pair = ImpactPair(0.1, e, 0.75)
    orb = symmetric_orbit(pair, PDGains(*gains), W, n=n, case=case)
    if not orb.exists:
        # no orbit here: compare from a generic pre-impact point instead
        orb = symmetric_orbit(pair, PDGains(10, 20), W, case=case)
        s = orb.fixed_point + np.array([0.05, 0.02, -0.1, 0.2])
        Q = ImpactMap(pair, PDGains(*gains), orb.reference(), case)
        G = SectionMap(impact_pair_section(Q_system(Q)))
        compare(G, Q, s)
        return
    Q = ImpactMap(pair, orb.gains, orb.reference(), case)
    G = SectionMap(impact_pair_section(orb.system()))
    rng = np.random.default_rng(len(case) + int(10 * e) + gains[0] + n)
    s = orb.fixed_point + 1e-3 * rng.normal(size=4)
    compare(G, Q, s)
    compare(G, Q, s, k=2, dp=False)
    # the orbit: the general Newton from a perturbed start lands on the closed-form point
    po = find_orbit(G, orb.fixed_point + 1e-5 * rng.normal(size=4))
    assert po.converged, po.reason
    np.testing.assert_allclose(G.wrap(po.s - orb.fixed_point), 0, atol=1e-9)
    mu_gen = np.sort_complex(np.asarray(po.multipliers))
    mu_cf = np.sort_complex(np.asarray(Q.stability(orb.fixed_point).multipliers))
    np.testing.assert_allclose(mu_cf, mu_gen, rtol=0, atol=1e-7 * max(1, np.abs(mu_gen).max()))


def Q_system(Q: ImpactMap):
    """The controlled pair (automaton) of an :class:`ImpactMap`'s parameters."""
    from hybridpd.pair.impactpair import ControlledImpactPair
    return ControlledImpactPair(Q.pair, Q.gains, Q.reference, Q.case)


@pytest.mark.parametrize("name,case,e", LTI_GRID)
def test_lti_orbit_agrees_with_the_general_map(name, case, e):
    o = lti_symmetric_orbit(ImpactPair(0.1, e, 0.75), CONTROLLERS[name], W, case=case)
    assert o.exists, o.reason
    G = SectionMap(impact_pair_section(o.system()))
    assert G.dim == o.fixed_point.size
    # the closed-form fixed point returns under the general map, twice
    r = G.apply(o.fixed_point, 2)
    assert r.ok and r.signature == (("wall+", "crossing"), ("wall-", "crossing")) * 2
    sc = o.coordinate_scale()
    amp = 1e-9 * max(1.0, o.spectral_radius ** 2 / 100)
    np.testing.assert_allclose(G.wrap(r.s - o.fixed_point) / sc, 0, atol=amp, err_msg="P^2")
    np.testing.assert_allclose(G.jacobian(o.fixed_point), o.DP, rtol=0,
                               atol=1e-7 * np.abs(o.DP).max(), err_msg="orbit DP")


@pytest.mark.parametrize("e", [0.3, 0.5, 0.8])
def test_basin_labels_agree(e):
    """Labels of the closed-form mapper and the general one on a grid around the orbit.

    Collocated (the non-collocated orbits of the grid are unstable). Both iterate 60 times
    without early exit; the criteria differ in their coordinates
    (``(x1, y1, y2, phi)`` against ``(phi, z1, z2, z4)``), so only points whose two distances
    fall on the same side of the threshold are compared (all but a boundary layer).
    """
    pair = ImpactPair(0.1, e, 0.75)
    orb = symmetric_orbit(pair, PDGains(10, 20), W)
    assert orb.exists and orb.stable
    Q = ImpactMap(pair, orb.gains, orb.reference())
    G = SectionMap(impact_pair_section(orb.system()))
    d1, d2 = np.meshgrid(np.linspace(-1.5, 1.5, 6), np.linspace(-3, 3, 6))
    S = np.tile(orb.fixed_point, (d1.size, 1))
    S[:, 1] += d1.ravel()
    S[:, 2] += d2.ravel()
    lab_q = mapper(Q, orb.fixed_point, n_iter=60, early_exit=False)
    lab_g = mapper(G, orb.fixed_point, n_iter=60, early_exit=False)
    a = np.array([lab_q(s) for s in S])
    b, _ = lab_g.labels(S)[:2]
    assert np.any(a == 0), "no converged point: the comparison would be empty"
    np.testing.assert_array_equal(a, b)


def test_the_batch_call_of_the_closed_form_map_agrees_with_single_points():
    orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), W)
    Q = ImpactMap(orb.pair, orb.gains, orb.reference())
    S = orb.fixed_point + np.array([[0.0, 0.0, 0.0, 0.0], [0.01, -0.02, 0.03, 0.1]])
    with pytest.raises(ValueError, match="s"):     # apply takes one point: apply_batch many
        Q.apply(S)
    new = Q.apply_batch(S)
    assert new.ok.all()
    for s, img in zip(S, new.s):      # the protocol's single-point result is the same image
        np.testing.assert_allclose(Q.apply(s).s, img, rtol=0, atol=1e-15)
