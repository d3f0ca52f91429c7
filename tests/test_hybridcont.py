"""Continuation of periodic orbits of the general impact map, against the pair's engine."""
import copy
import dataclasses

import numpy as np
import pytest

from hybridpd import ImpactPair, PDGains, Reference
from hybridpd.analysis.continuation import EVENT_KINDS
from hybridpd.analysis.continuation import continue_orbit as continue_any
from hybridpd.analysis.hybridmap import SectionMap
from hybridpd.analysis.periodic import find_orbit
from hybridpd.hybrid.samples import impact_oscillator, oscillator_initial_state
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.impactpair import ControlledImpactPair
from hybridpd.pair.orbits import symmetric_orbit
from hybridpd.pair.section import impact_pair_section

W = 5.0


def _kv_builder(pair, xm):
    """``kv -> SectionMap``; the loop matrices are affine in ``kv`` (one python-control build)."""
    base = ControlledImpactPair(pair, PDGains(10, 20), Reference(xm, W))
    one = ControlledImpactPair(pair, PDGains(10, 21), Reference(xm, W))
    dA, df = one.loop.A - base.loop.A, one.loop.force - base.loop.force

    def build(kv):
        s = copy.copy(base)
        s.loop = dataclasses.replace(base.loop, A=base.loop.A + (kv - 20) * dA,
                                     force=base.loop.force + (kv - 20) * df)
        s.automaton = s._build_automaton()
        return SectionMap(impact_pair_section(s))
    return build


def test_fold_of_the_period2_cycle_matches_the_pair_engine():
    pair = ImpactPair(0.1, 0.1, 0.75)
    xm = symmetric_orbit(pair, PDGains(10, 20), W).xm
    P = ImpactMap(pair, PDGains(10, 20), Reference(xm, W))
    orb = find_orbit(P, P.iterate(np.array([0.3, -2.1, -2.3, 0.5]), 200)[-1], period=2)
    ref = continue_any(P.family("kv"), 20.0, 5.0, orb, period=2).events_of("fold")[0].parameter
    br = continue_any(_kv_builder(pair, xm), 18.5, 5.0, orb.s, period=2, step=0.3,
                       max_step=0.5)
    assert br.termination.startswith("turned back")
    folds = br.events_of("fold")
    assert len(folds) == 1 and abs(folds[0].p - ref) < 1e-8
    assert min(br.parameter) >= folds[0].p - 1e-9
    assert br.events_of("stability_change")       # the fold is where the cycle loses stability
    d = br.to_dict()
    assert {e["kind"] for e in d["events"]} <= set(EVENT_KINDS)


def test_natural_continuation_points_are_fixed_points_of_the_pair_engine():
    pair = ImpactPair(0.1, 0.5, 0.75)
    orb = symmetric_orbit(pair, PDGains(10, 20), W)
    br = continue_any(_kv_builder(pair, orb.xm), 20.0, 24.0, orb.fixed_point,
                       method="natural", step=1.0, max_step=1.5)
    assert br.termination == "reached" and len(br.points) >= 5
    for pt in br:
        Q = ImpactMap(pair, PDGains(10, pt.p), Reference(orb.xm, W))
        assert np.max(np.abs(Q(pt.s) - pt.s)) < 1e-9
        fd = SectionMap(_kv_builder(pair, orb.xm)(pt.p).section).jacobian_fd(pt.s, h=1e-7)
        # the branch's multipliers against the eigenvalues of a finite-difference Jacobian
        np.testing.assert_allclose(np.sort(np.abs(pt.multipliers)),
                                   np.sort(np.abs(np.linalg.eigvals(fd))), rtol=1e-5,
                                   atol=1e-6)


def test_builder_returning_an_automaton_and_bad_input():
    def build(W_):
        return impact_oscillator(omega0=1.0, zeta=0.1, omega=W_, stop=1.0, e=0.8)

    sec = {"mode": "free", "guard": "impact",
           "reference": (oscillator_initial_state(0, 0, omega=0.8), 0.0)}
    br = continue_any(build, 0.8, 0.82, [7.7, 1.66], section=sec, step=0.01)
    assert br.termination == "reached"
    assert abs(br[-1].p - 0.82) < 1e-12
    with pytest.raises(ValueError, match="section"):
        continue_any(build, 0.8, 0.82, [7.7, 1.66])
    with pytest.raises(ValueError, match="method"):
        continue_any(build, 0.8, 0.82, [7.7, 1.66], section=sec, method="newton")
    with pytest.raises(ValueError, match="p_end"):
        continue_any(build, 0.8, 0.8, [7.7, 1.66], section=sec)
    bad = continue_any(build, 0.8, 0.82, [1.0, -0.5], section=sec)
    assert bad.termination.startswith("start failed") and len(bad) == 0


def test_design_gains_for_a_desired_amplitude_matches_the_symmetric_orbit():
    from hybridpd.analysis.hybriddesign import design_gains, orbit_amplitude

    pair = ImpactPair(0.1, 0.5, 0.75)
    orb = symmetric_orbit(pair, PDGains(10, 20), W)
    base = ControlledImpactPair(pair, PDGains(10, 20), orb.reference())
    d = {}
    for name, g in (("kp", PDGains(11, 20)), ("kv", PDGains(10, 21))):
        o = ControlledImpactPair(pair, g, orb.reference())
        d[name] = (o.loop.A - base.loop.A, o.loop.force - base.loop.force)

    def build(g):       # the loop matrices are affine in (kp, kv)
        s = copy.copy(base)
        s.loop = dataclasses.replace(
            base.loop, A=base.loop.A + (g[0] - 10) * d["kp"][0] + (g[1] - 20) * d["kv"][0],
            force=base.loop.force + (g[0] - 10) * d["kp"][1] + (g[1] - 20) * d["kv"][1])
        s.automaton = s._build_automaton()
        return SectionMap(impact_pair_section(s))

    r = design_gains(build, [12.0, 20.0], orb.fixed_point, state="x1", amplitude=1.0,
                     bounds=[(1, 60), (1, 60)])
    assert r.success, r.message
    assert r.spectral_radius < 0.5 * r.initial_spectral_radius
    # independent check: the closed-form symmetric orbit at the designed gains needs the same
    # reference amplitude for x10 = 1 and has the same multipliers
    kp, kv = r.gains
    chk = symmetric_orbit(pair, PDGains(kp, kv), W)
    assert chk.exists and abs(chk.xm - orb.xm) < 1e-6
    assert abs(chk.spectral_radius - r.spectral_radius) < 1e-6
    P = build(r.gains)
    assert abs(orbit_amplitude(P, r.orbit, "x1") - 1.0) < 1e-6
    with pytest.raises(ValueError, match="bounds"):
        design_gains(build, [12.0, 20.0], orb.fixed_point, state="x1", amplitude=1.0,
                     bounds=[(1, 60)])


def test_the_pair_on_the_one_engine_through_its_family_hook():
    # the collocated orbit at e = 0.1, kp = 10 grazes at kv = 21.938: on the one engine with
    # the pair's family (ImpactMap.family: the pair's rules) the branch ends there
    pair = ImpactPair(0.1, 0.1, 0.75)
    orb = symmetric_orbit(pair, PDGains(10, 20), W)
    P = ImpactMap(pair, orb.gains, orb.reference())
    br = continue_any(P.family("kv"), 20.0, 23.0, orb.fixed_point, step=0.25, max_step=0.25)
    assert len(br) and br[0].stable
    for pt in list(br)[::4]:        # fixed points of an independently built map
        Q = ImpactMap(pair, PDGains(10, pt.p), Reference(orb.xm, W))
        np.testing.assert_allclose(Q(pt.s), pt.s, rtol=0, atol=1e-9)
    last = br[-1].p
    assert 21.5 < last < 21.95, br.termination    # the orbit ends at grazing (kv = 21.938)
    assert "ends at grazing" in br.termination and br.events_of("grazing")
    # next to grazing the tangent bends without a multiplier at +1: not a fold
    assert not br.events_of("fold"), br.events
    with pytest.raises(ValueError, match="parameter"):
        P.family("kd")
