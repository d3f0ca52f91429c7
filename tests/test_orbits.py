"""Symmetric orbits, viability, the impact map and stability against independent checks."""
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from hybridpd import ImpactPair, PDGains
from hybridpd.loop import closed_loop
from hybridpd.pair.impactmap import ImpactMap, stability
from hybridpd.pair.orbits import symmetric_orbit, symmetric_orbits

CASES = ("collocated", "noncollocated")
PAPER = dict(mu=0.1, L=0.75, omega=5.0)


def orbit(kp=10.0, kv=20.0, e=0.5, case="collocated", n=1, mu=0.1, L=0.75, omega=5.0, x10=1.0):
    return symmetric_orbit(ImpactPair(mu, e, L), PDGains(kp, kv), omega, x10=x10, n=n, case=case)


def richardson_fd(P, s, h):
    """Central differences at h and h/2 combined (error O(h^4)), phase unwrapped."""
    return (4 * P.jacobian_fd(s, h=h / 2) - P.jacobian_fd(s, h=h)) / 3


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(kp=st.floats(1, 60), kv=st.floats(1, 60), e=st.floats(0.05, 0.95),
       mu=st.floats(0.02, 1.0), case=st.sampled_from(CASES))
def test_DP_against_finite_differences_of_simulated_map(kp, kv, e, mu, case):
    o = orbit(kp, kv, e, case, mu=mu)
    assume(o.exists and o.viability_margin > 1e-3 and o.spectral_radius < 1e4)
    P = ImpactMap(o.pair, o.gains, o.reference(), case)
    # P is strongly nonlinear in phi near grazing: the differences must converge to DP as
    # h shrinks, so the best of a few step sizes is compared.
    err = min(np.abs(richardson_fd(P, o.fixed_point, h) - o.DP).max() for h in (1e-5, 2e-6))
    assert err <= 1e-6 * np.abs(o.DP).max()


@pytest.mark.parametrize("case", CASES)
def test_fixed_point_of_simulated_map(case):
    for e in (0.1, 0.5):
        o = orbit(e=e, case=case)
        assert o.exists
        P = ImpactMap(o.pair, o.gains, o.reference(), case)
        s = P(o.fixed_point)
        assert np.abs(s - o.fixed_point).max() < 1e-10


def test_spectral_radius_against_iterated_perturbations_stable():
    o = orbit(e=0.5)
    assert o.stable
    P = ImpactMap(o.pair, o.gains, o.reference())
    rng = np.random.default_rng(1)
    d0 = rng.normal(size=4) * 1e-3
    traj = P.iterate(o.fixed_point + d0, 16)
    dist = np.linalg.norm(traj - o.fixed_point, axis=1)
    # iterations 6..16: the faster multipliers (|.| < 0.15) have died out, and the
    # distance (~1e-7) is still far above rounding and far inside the linear regime
    rate = (dist[16] / dist[6]) ** (1 / 10)
    assert rate == pytest.approx(o.spectral_radius, rel=2e-3)


def test_spectral_radius_against_iterated_perturbations_unstable():
    o = orbit(e=0.1, case="noncollocated")
    assert o.exists and not o.stable
    P = ImpactMap(o.pair, o.gains, o.reference(), "noncollocated")
    d0 = np.array([1e-12, 0, 0, 0])
    traj = P.iterate(o.fixed_point + d0, 3)
    dist = np.linalg.norm(traj - o.fixed_point, axis=1)
    # after one iteration the perturbation is aligned with the unstable direction; by the
    # third it is ~1e-2 and nonlinear effects start
    rate = dist[3] / dist[2]
    assert rate == pytest.approx(o.spectral_radius, rel=5e-3)


def test_long_run_stays_on_stable_orbit():
    """1500 iterations of P (3000 impacts) started on the orbit stay on it."""
    o = orbit(e=0.5)
    P = ImpactMap(o.pair, o.gains, o.reference())
    traj = P.iterate(o.fixed_point, 1500)
    assert np.all(np.isfinite(traj))
    assert np.abs(traj - o.fixed_point).max() < 1e-10


def first_extra_contact(o):
    """Brute force: integrate the candidate orbit's flight with solve_ivp and events."""
    cl = closed_loop(o.pair, o.gains, o.reference(), o.case)
    z0 = cl.initial_state(o.post_plus, o.t0)
    L = o.pair.L

    def right(t, z):
        return L - (z[0] - z[2])

    def left(t, z):
        return z[0] - z[2] + L

    # a tiny positive offset keeps the initial contact from counting
    for ev in (right, left):
        ev.direction = -1
    ts = np.linspace(0, o.tau, 4001)
    sol = solve_ivp(lambda t, z: cl.A @ z, (0, o.tau), z0, method="DOP853", rtol=1e-12,
                    atol=1e-13, t_eval=ts, events=(right, left))
    gap = sol.y[0] - sol.y[2]
    inner = (ts > 1e-6 * o.tau) & (ts < o.tau * (1 - 1e-6))
    extra = np.any(np.abs(gap[inner]) > L * (1 + 1e-9))
    ev_times = np.concatenate([sol.t_events[0], sol.t_events[1]])
    extra = extra or np.any((ev_times > 1e-6 * o.tau) & (ev_times < o.tau * (1 - 1e-6)))
    end_ok = abs(gap[-1] + L) < 1e-8
    return extra, end_ok


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(kp=st.floats(0.5, 80), kv=st.floats(0.5, 80), e=st.floats(0.05, 0.95),
       case=st.sampled_from(CASES))
def test_existence_flag_against_brute_force(kp, kv, e, case):
    o = orbit(kp, kv, e, case)
    assume(np.isfinite(o.xm) and o.xm > 0)
    assume(abs(o.viability_margin) > 1e-6)   # not at the grazing boundary itself
    extra, end_ok = first_extra_contact(o)
    assert end_ok
    assert o.exists == (not extra)


def test_violation_reports_where_and_when():
    o = orbit(e=0.9, case="noncollocated")
    assert not o.exists and o.violation is not None
    assert 0 < o.violation["t"] < o.tau and o.violation["wall"] in (-1, 1)
    assert "wall" in o.reason and o.stable is None and o.viability_margin < 0


@pytest.mark.parametrize("case", CASES)
def test_order_three_orbits(case):
    o = orbit(kp=10, kv=20, e=0.5, case=case, n=3)
    assert o.tau == pytest.approx(3 * o.T / 2)
    if o.exists:
        P = ImpactMap(o.pair, o.gains, o.reference(), case)
        assert np.abs(P(o.fixed_point) - o.fixed_point).max() < 1e-9
        J = richardson_fd(P, o.fixed_point, 1e-5)
        assert np.abs(J - o.DP).max() <= 1e-6 * np.abs(o.DP).max()


def test_symmetry_of_orbit():
    o = orbit()
    fl = o.flight(np.array([o.t0 + o.tau]))[0]
    np.testing.assert_allclose(fl, o.pre_minus, atol=1e-12)
    # the second half is the first one mirrored: x(t + tau) = -x(t)
    mid = o.flight(np.array([o.t0 + 0.3 * o.tau]))[0]
    cl = closed_loop(o.pair, o.gains, o.reference())
    from scipy.linalg import expm

    z = expm(cl.A * o.tau) @ cl.initial_state(o.post_minus, o.t0 + o.tau)   # second flight
    np.testing.assert_allclose(z[:4], o.pre_plus, atol=1e-11)
    assert np.all(np.isfinite(mid))


@pytest.mark.parametrize("case", CASES)
def test_continuity_across_critical_damping(case):
    kp = 10.0
    kvc = math.sqrt(4 * kp)
    vals = [orbit(kp, kvc * (1 + d), 0.5, case) for d in (-1e-7, -1e-12, 0.0, 1e-12, 1e-7)]
    xm = np.array([v.xm for v in vals])
    assert np.all(np.isfinite(xm)) and np.ptp(xm) < 1e-5
    rho = np.array([v.spectral_radius if v.exists else np.nan for v in vals])
    ex = [v.exists for v in vals]
    assert len(set(ex)) == 1
    if ex[0]:
        assert np.ptp(rho) < 1e-5 * max(1.0, rho.max())


def test_vectorised_agrees_with_scalar():
    kp = np.array([2.0, 10.0, 40.0])
    kv = np.array([[1.0], [20.0]])
    r = symmetric_orbits(kp, kv, e=0.5, **PAPER)
    for i in range(2):
        for j in range(3):
            o = orbit(kp[j], kv[i, 0], 0.5)
            assert r.exists[i, j] == o.exists
            if o.exists:
                assert r.spectral_radius[i, j] == pytest.approx(o.spectral_radius, rel=1e-12)


def test_stability_helper_and_validation():
    s = stability(np.diag([0.5, -0.2, 1.0 + 1e-12, 0.1]))
    assert not s.hyperbolic and not s.stable and s.spectral_radius == pytest.approx(1.0)
    with pytest.raises(ValueError, match="DP"):
        stability(np.ones((2, 3)))
    with pytest.raises(ValueError, match="odd"):
        orbit(n=2)
    with pytest.raises(ValueError, match="e"):
        symmetric_orbits(1.0, 1.0, e=1.5, **PAPER)
    with pytest.raises(ValueError, match="kp"):
        symmetric_orbits(np.array([1.0, np.nan]), 1.0, e=0.5, **PAPER)
