"""The general impact map, its DP and periodic orbits, on the pair and the sample automata."""
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from hybridpd import ImpactPair, PDGains
from hybridpd.analysis.hybridmap import (
    MAP_STATUS,
    Section,
    SectionMap,
    exosystem,
)
from hybridpd.analysis.mappers import mapper
from hybridpd.analysis.periodic import find_orbit, measured_contraction
from hybridpd.hybrid.samples import (
    ball_initial_state,
    bouncing_ball,
    impact_oscillator,
    oscillator_initial_state,
)
from hybridpd.pair.basins import section_grid
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.orbits import symmetric_orbit
from hybridpd.pair.section import impact_pair_section
from hybridpd.sweeps.basins import basin_of_attraction

PAIR = ImpactPair(0.1, 0.5, 0.75)


@pytest.fixture(scope="module", params=["collocated", "noncollocated"])
def pair_orbit(request):
    orb = symmetric_orbit(PAIR, PDGains(10, 20), 5.0, case=request.param)
    assert orb.exists
    return orb, SectionMap(impact_pair_section(orb.system()))


def test_pair_fixed_point_and_dp_match_symbolic(pair_orbit):
    orb, P = pair_orbit
    r = P.apply(orb.fixed_point, jacobian=True)
    assert r.ok and r.status == "returned"
    assert [g for g, _ in r.signature] == ["wall+", "wall-"]
    assert np.max(np.abs(P.section.wrap(r.s - orb.fixed_point))) < 1e-10
    scale = np.max(np.abs(orb.DP))
    assert np.max(np.abs(r.DP - orb.DP)) < 1e-9 * scale


def test_pair_dp_matches_finite_differences(pair_orbit):
    orb, P = pair_orbit
    s = orb.fixed_point + np.array([0.003, -0.002, 0.001, 0.004])
    DP = P.jacobian(s)
    fd = P.jacobian_fd(s, h=1e-7)
    assert np.max(np.abs(DP - fd)) < 1e-6 * max(1.0, np.max(np.abs(DP)))


def test_pair_general_map_equals_closed_form_engine(pair_orbit):
    orb, P = pair_orbit
    Q = ImpactMap(orb.pair, orb.gains, orb.reference(), orb.case)
    s = orb.fixed_point + np.array([0.01, 0.02, -0.01, 0.03])
    for _ in range(5):
        a, b = P(s), Q(s)
        assert np.max(np.abs(P.section.wrap(a - b))) < 1e-9
        s = a


def test_pair_newton_reproduces_symmetric_orbit(pair_orbit):
    orb, P = pair_orbit
    eps = 1e-2 if orb.stable else 1e-6
    po = find_orbit(P, orb.fixed_point + eps * np.array([1.0, 1.0, -1.0, 1.0]))
    assert po.converged, po.reason
    assert np.max(np.abs(P.section.wrap(po.s - orb.fixed_point))) < 1e-9
    rho = orb.spectral_radius
    assert np.max(np.abs(np.sort_complex(po.multipliers) - np.sort_complex(orb.multipliers))) \
        < 1e-9 * max(1.0, rho)
    assert po.stable == orb.stable
    assert abs(po.t_period - orb.T) < 1e-9
    d = po.to_dict()
    assert d["exists"] and len(d["multipliers"]) == 4


def test_fd_jacobian_newton_agrees():
    orb = symmetric_orbit(PAIR, PDGains(10, 20), 5.0)
    P = SectionMap(impact_pair_section(orb.system()))
    po = find_orbit(P, orb.fixed_point + 1e-3, jacobian="fd", tol=1e-10)
    assert po.converged
    assert np.max(np.abs(po.s - orb.fixed_point)) < 1e-8


def test_spectral_radius_against_iterated_perturbations():
    orb = symmetric_orbit(PAIR, PDGains(10, 20), 5.0)
    P = SectionMap(impact_pair_section(orb.system()))
    rho = measured_contraction(P, orb.fixed_point, n_iter=30, eps=1e-7)
    assert abs(rho - orb.spectral_radius) < 2e-3 * orb.spectral_radius


def test_period_two_power_is_square_of_dp():
    orb = symmetric_orbit(PAIR, PDGains(10, 20), 5.0)
    P = SectionMap(impact_pair_section(orb.system()))
    s = orb.fixed_point + np.array([0.002, 0.001, 0.0, -0.002])
    D2 = P.jacobian(s, 2)
    D1b = P.jacobian(P(s))
    assert np.max(np.abs(D2 - D1b @ P.jacobian(s))) < 1e-9 * np.max(np.abs(D2))
    assert np.allclose(P(s, 2), P(P(s)), atol=1e-12)


# ---- the bouncing ball: closed-form map derivative -------------------------------------
G, E_BALL, A_T, W_T = 9.81, 0.5, 0.1, 6 * math.pi


def _ball():
    ha = bouncing_ball(g=G, e=E_BALL, amplitude=A_T, omega=W_T)
    sec = Section(ha, "flight", "impact",
                  reference=(ball_initial_state(0.0, 0.0, amplitude=A_T, omega=W_T), 0.0))
    return SectionMap(sec)


def _ball_dp(t, v, t1, v1, e=E_BALL, a=A_T, w=W_T):
    """Closed-form Jacobian of the exact ball map (t, v) -> (t', v') (table a sin w t).

    From x_t(t) + u D - g D^2 / 2 = x_t(t + D), u = (1 + e) v_t(t) - e v, v' = u - g D by
    implicit differentiation; r' = v' - v_t(t') is the relative approach speed at t'.
    """
    xt = lambda s: a * math.sin(w * s)
    vt = lambda s: a * w * math.cos(w * s)
    at = lambda s: -a * w ** 2 * math.sin(w * s)
    D = t1 - t
    u = (1 + e) * vt(t) - e * v
    r1 = u - G * D - vt(t1)                       # relative pre-impact velocity at t'
    Gt = vt(t) + (1 + e) * at(t) * D - vt(t1)
    assert abs(xt(t) + u * D - G * D * D / 2 - xt(t1)) < 1e-11 * max(1.0, abs(u * D))
    return np.array([[1 - Gt / r1, e * D / r1],
                     [(1 + e) * at(t) + G * Gt / r1, -e - G * e * D / r1]])


def test_ball_period_one_orbit_closed_form():
    P = _ball()
    T = 2 * math.pi / W_T
    assert P.section.names == ("phi", "v_ball") and abs(P.section.period - T) < 1e-15
    # period one: flight time T, v+ = g T / 2 = (1 + e) v_table - e v-, v- = -g T / 2
    th = math.acos(G * T * (1 - E_BALL) / (2 * (1 + E_BALL) * A_T * W_T))
    s_star = np.array([th / W_T, -G * T / 2])
    po = find_orbit(P, s_star + [0.002, 0.05])
    assert po.converged
    assert np.max(np.abs(po.s - s_star)) < 1e-10
    assert np.max(np.abs(po.DP - _ball_dp(po.s[0], po.s[1], po.s[0] + T, po.s[1]))) < 1e-9
    assert abs(np.linalg.det(po.DP) - E_BALL ** 2) < 1e-10     # r = r' on the orbit
    fd = P.jacobian_fd(po.s, h=1e-7)
    assert np.max(np.abs(po.DP - fd)) < 1e-6 * np.max(np.abs(po.DP))


def test_ball_dp_closed_form_off_orbit():
    P = _ball()
    s = np.array([0.01, -1.2])
    r = P.apply(s, jacobian=True)
    assert r.ok
    assert np.max(np.abs(r.DP - _ball_dp(s[0], s[1], r.t_hit, r.s[1]))) < 1e-9 * \
        np.max(np.abs(r.DP))


# ---- the forced oscillator against a stop ----------------------------------------------
def _oscillator(section_mode, guard, **kw):
    F, W = kw.get("force", 1.0), kw.get("omega", 0.8)
    ha = impact_oscillator(**kw)
    return SectionMap(Section(ha, section_mode, guard,
                              reference=(oscillator_initial_state(0, 0, force=F, omega=W), 0.0)))


def test_oscillator_orbit_dp_and_contraction():
    P = _oscillator("free", "impact", omega0=1.0, zeta=0.1, omega=0.8, stop=1.0, e=0.8)
    assert exosystem(P.section.automaton)[0] == (2, 3)
    po = find_orbit(P, [7.7, 1.66])
    assert po.converged and po.stable
    assert np.iscomplexobj(po.multipliers) and abs(po.multipliers[0].imag) > 0.1
    fd = P.jacobian_fd(po.s, h=1e-7)
    assert np.max(np.abs(po.DP - fd)) < 1e-6
    # a complex pair: the per-step growth oscillates, the mean converges like 1/n_iter
    rho = measured_contraction(P, po.s, n_iter=60)
    assert abs(rho - po.spectral_radius) < 2e-2 * po.spectral_radius


def test_oscillator_sticking_orbit_through_zeno_and_release():
    # section on the release guard: free flight, impacts, accumulation, sticking, release
    P = _oscillator("stuck", "release", omega0=1.0, zeta=0.1, omega=0.5, stop=0.5, e=0.3)
    po = find_orbit(P, [2.1, 0.0])
    assert po.converged
    kinds = [k for _, k in po.signature]
    assert "zeno" in kinds and kinds.count("crossing") >= 3
    # the release phase does not depend on where the run started: DP = 0, confirmed by FD
    fd = P.jacobian_fd(po.s, h=1e-6)
    assert np.max(np.abs(fd)) < 1e-7 and np.max(np.abs(po.DP)) < 1e-9


# ---- statuses and validation ------------------------------------------------------------
def test_statuses_and_bad_input():
    P = _oscillator("free", "impact", omega0=1.0, zeta=0.1, omega=0.8, stop=1.0, e=0.8)
    r = P.apply([1.0, -0.5])                  # moving away from the stop: not pre-impact
    assert not r.ok and r.status == "bad_start"
    assert set(MAP_STATUS.values()) >= {"returned", "end_time", "jump_limit", "bad_start"}
    Pf = _oscillator("free", "impact", omega0=1.0, zeta=0.1, omega=0.8, stop=50.0, e=0.8)
    assert Pf.apply([0.0, 0.5]).status == "end_time"   # never reaches a far stop
    Pj = SectionMap(P.section, max_jumps=1)
    assert Pj.apply([7.7, 1.66]).ok          # one jump, then the pending return
    assert Pj.apply([7.7, 1.66], k=3).status == "jump_limit"
    with pytest.raises(RuntimeError, match="bad_start"):
        P([1.0, -0.5])
    with pytest.raises(ValueError, match="guard"):
        Section(P.section.automaton, "free", "nope", exo_state=[1.0, 0.0])
    with pytest.raises(ValueError, match="exo_state"):
        Section(P.section.automaton, "free", "impact")
    with pytest.raises(ValueError, match="coords"):
        Section(P.section.automaton, "free", "impact", exo_state=[1.0, 0.0],
                coords=np.zeros((2, 4)))
    with pytest.raises(ValueError, match="k"):
        P.apply([7.7, 1.66], k=0)
    with pytest.raises(ValueError, match="s must"):
        P.apply([7.7])


def test_section_round_trip_and_embedding():
    orb = symmetric_orbit(PAIR, PDGains(10, 20), 5.0)
    sec = impact_pair_section(orb.system())
    s = orb.fixed_point
    z, t = sec.to_state(s)
    assert np.allclose(z[:4], orb.pre_plus) and t == s[0]
    assert np.allclose(sec.from_state(z, t + 3 * sec.period), s)
    J = sec.embedding(s)
    h = 1e-6
    for j in range(4):
        d = np.zeros(4)
        d[j] = h
        fd = (sec.to_state(s + d)[0] - sec.to_state(s - d)[0]) / (2 * h)
        assert np.allclose(J[:, j], fd, atol=1e-8)


# ---- basins ----------------------------------------------------------------------------
def test_section_mapper_agrees_with_pair_mapper():
    orb = symmetric_orbit(PAIR, PDGains(10, 20), 5.0)
    P = SectionMap(impact_pair_section(orb.system()))
    m = mapper(P, orb.fixed_point, n_iter=200)
    m0 = mapper(ImpactMap(orb.pair, orb.gains, orb.reference()), orb.fixed_point, n_iter=200)
    pts = section_grid(orb.fixed_point, PAIR.L, np.linspace(-2, 2, 9),
                       np.linspace(-5, 5, 9)).reshape(-1, 4)
    lab, _its = m.labels(pts)
    lab0, _ = m0.labels(pts)
    assert np.array_equal(lab, lab0)
    assert m.certified_radius > 0
    m_slow = mapper(P, orb.fixed_point, n_iter=200, early_exit=False)
    assert np.array_equal(m_slow.labels(pts)[0], lab)
    b = basin_of_attraction(m, (-1.0, 1.0, 4), (0.5, 3.0, 3), axes=("z1", "z4"), max_period=0)
    assert b.labels.shape == (3, 4) and b.axes == ("z1", "z4")


@settings(max_examples=40, deadline=None)
@given(e=st.floats(0.05, 0.95), a=st.floats(0.005, 0.2), f=st.floats(1.0, 4.0),
       phase=st.floats(0.0, 1.0), v=st.floats(-6.0, -0.3))
def test_ball_dp_closed_form_random(e, a, f, phase, v):
    """Saltation-chain DP of the ball map against its closed form at random section points."""
    w = 2 * math.pi * f
    ha = bouncing_ball(g=G, e=e, amplitude=a, omega=w)
    P = SectionMap(Section(ha, "flight", "impact",
                           reference=(ball_initial_state(0.0, 0.0, amplitude=a, omega=w), 0.0)),
                   max_jumps=20)
    s = np.array([phase * 2 * math.pi / w, v + a * w * math.cos(phase * 2 * math.pi)])
    r = P.apply(s, jacobian=True)
    assume(r.ok and not r.grazing)
    vt1 = a * w * math.cos(w * r.t_hit)
    assume(abs(r.s[1] - vt1) > 0.05)              # not a near-grazing return
    ref = _ball_dp(s[0], s[1], r.t_hit, r.s[1], e, a, w)
    assert np.max(np.abs(r.DP - ref)) < 1e-8 * max(1.0, np.max(np.abs(ref)))
