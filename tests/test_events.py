"""Guaranteed first-crossing event location (hybridpd.hybrid.events)."""
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp
from scipy.linalg import expm

from hybridpd.hybrid.events import (
    EV_CROSSING,
    EV_NONE,
    EV_START,
    advance,
    first_crossing,
    lti_flow,
    prepare_lti_mode,
)

G = 9.81
FREE_FALL = [[0.0, 1.0], [0.0, 0.0]]


# ---------------------------------------------------------------------------- helpers
def _abar(A, b):
    n = A.shape[0]
    Ab = np.zeros((n + 1, n + 1))
    Ab[:n, :n] = A
    Ab[:n, n] = b
    return Ab


def _grid_values(A, b, fhat, z0, t_max, N):
    """Guard values on a uniform grid by repeated doubling of exact transition matrices."""
    E = expm(_abar(A, b) * (t_max / N))
    W = np.append(z0, 1.0)[:, None]
    P = E
    while W.shape[1] < N + 1:
        W = np.hstack([W, P @ W])
        P = P @ P
    W = W[:, :N + 1]
    return np.linspace(0.0, t_max, N + 1), fhat @ W, np.abs(fhat) @ np.abs(W)


def _exact_value(A, b, fhat, z0, t):
    return fhat @ expm(_abar(A, b) * t) @ np.append(z0, 1.0)


def _random_case(rng):
    n = int(rng.integers(1, 5))
    A = rng.normal(size=(n, n)) * rng.choice([0.3, 1.0, 3.0])
    if rng.random() < 0.5:
        A -= np.eye(n) * rng.random()
    b = rng.normal(size=n) if rng.random() < 0.5 else np.zeros(n)
    c = rng.normal(size=n)
    z0 = rng.normal(size=n)
    t_max = float(rng.uniform(0.1, 10.0))
    # put the guard through the trajectory at a random time, offset by a random tiny amount
    ts = rng.uniform(0.0, t_max)
    zs = (expm(_abar(A, b) * ts) @ np.append(z0, 1.0))[:n]
    d = -c @ zs + rng.normal() * 10 ** rng.uniform(-12, 0)
    if c @ z0 + d < 0:
        c, d = -c, -d
    direction = -1
    if rng.random() < 0.5:
        c, d, direction = -c, -d, 1
    return A, b, c, float(d), z0, t_max, direction


def _check_against_grid(seed, N=3000):
    rng = np.random.default_rng(seed)
    A, b, c, d, z0, t_max, direction = _random_case(rng)
    ev = np.linalg.eigvals(A)
    if np.max(np.abs(ev)) * t_max > 30 or np.max(ev.real) * t_max > 6:
        return None     # scipy's expm (the oracle) loses digits on strongly growing flows
    res = first_crossing(A, c, d, z0, t_max, b=b, direction=direction)
    fhat = -direction * np.append(c, d)
    tg, fg, scale = _grid_values(A, b, fhat, z0, t_max, N)
    tol = 1e-9 * max(1.0, scale.max())
    if res.kind == "none":
        assert fg.min() > -tol, f"missed a crossing near t = {tg[np.argmin(fg)]}"
        assert res.time is None
    else:
        assert 0.0 <= res.time <= t_max
        assert abs(_exact_value(A, b, fhat, z0, res.time)) <= tol, "invented event"
        before = fg[tg < res.time - 1e-9]
        if before.size:
            assert before.min() > -tol, "an earlier crossing was skipped"
        np.testing.assert_allclose(
            res.state, (expm(_abar(A, b) * res.time) @ np.append(z0, 1.0))[:-1],
            rtol=1e-9, atol=1e-9 * max(1.0, scale.max()))
    return res.kind


# ---------------------------------------------------------------------------- exact flows
@pytest.mark.parametrize("seed", range(12))
def test_lti_flow_matches_solve_ivp(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 6))
    A = rng.normal(size=(n, n))
    if seed % 2:
        A = A - A.T - 0.05 * np.eye(n)          # oscillatory, lightly damped
    else:
        A = A - (np.max(np.linalg.eigvals(A).real) + 0.3) * np.eye(n)   # stable
    b = rng.normal(size=n)
    z0 = rng.normal(size=n)
    ts = np.sort(rng.uniform(0.0, 12.0, 40))
    sol = solve_ivp(lambda t, z: A @ z + b, (0.0, 12.0), z0, method="DOP853", rtol=1e-12,
                    atol=1e-12, t_eval=ts)
    ours = lti_flow(A, z0, ts, b=b)
    np.testing.assert_allclose(ours, sol.y.T, rtol=1e-9, atol=1e-9)
    exact = np.array([(expm(_abar(A, b) * t) @ np.append(z0, 1.0))[:n] for t in ts])
    np.testing.assert_allclose(ours, exact, rtol=1e-12, atol=1e-12)


def test_lti_flow_scalar_and_order():
    x = lti_flow([[0.0, 1.0], [-1.0, 0.0]], [1.0, 0.0], [math.pi, 0.5 * math.pi, 0.0])
    np.testing.assert_allclose(x, [[-1, 0], [0, -1], [1, 0]], atol=1e-14)
    assert lti_flow([[-1.0]], [2.0], 1.0).shape == (1,)
    with pytest.raises(ValueError, match="times"):
        lti_flow([[-1.0]], [2.0], [-1.0])


def test_units_of_constant_input_do_not_change_steps():
    # the homogeneous coordinate is balanced: the same physics in mm takes the same steps
    m = prepare_lti_mode(FREE_FALL, [0.0, -G])
    mm = prepare_lti_mode(FREE_FALL, [0.0, -G * 1000.0])
    assert mm.h == pytest.approx(m.h, rel=1.0)
    r1 = first_crossing(FREE_FALL, [1, 0], 0.0, [1.0, 0.0], 2.0, b=[0, -G])
    r2 = first_crossing(FREE_FALL, [1, 0], 0.0, [1000.0, 0.0], 2.0, b=[0, -G * 1000])
    assert r1.time == pytest.approx(math.sqrt(2 / G), rel=1e-14)
    assert r2.time == pytest.approx(math.sqrt(2 / G), rel=1e-14)


# ---------------------------------------------------------------------------- basics
def test_free_fall_exact_time():
    r = first_crossing(FREE_FALL, [1, 0], 0.0, [1.0, 1.0], 5.0, b=[0, -G])
    assert r.kind == "crossing"
    assert r.time == pytest.approx((1 + math.sqrt(1 + 2 * G)) / G, rel=1e-15, abs=1e-15)
    assert r.state[0] <= 0.0 and abs(r.state[0]) < 1e-14   # first float time on the far side


def test_direction_plus_one():
    # x = sin t reaches 0.5 from below at pi/6
    r = first_crossing([[0, 1], [-1, 0]], [1, 0], -0.5, [0.0, 1.0], 3.0, direction=1)
    assert r.kind == "crossing" and r.time == pytest.approx(math.pi / 6, abs=1e-14)
    r = first_crossing([[0, 1], [-1, 0]], [1, 0], -0.5, [0.0, 1.0], 0.5, direction=1)
    assert r.kind == "none" and r.time is None
    np.testing.assert_allclose(r.state, [math.sin(0.5), math.cos(0.5)], atol=1e-15)


def test_multi_step_horizon_and_many_periods():
    # fast oscillator, first crossing after hundreds of steps
    w = 50.0
    r = first_crossing([[0, 1], [-w * w, 0]], [-1, 0], 0.9999, [0.0, 0.5], 400.0)
    assert r.kind == "none"
    r = first_crossing([[-1e-3, 1], [-w * w, -1e-3]], [1, 0], 0.0, [1.0, 0.0], 10.0)
    assert r.time == pytest.approx(math.pi / (2 * w), rel=1e-3)


def test_input_validation():
    with pytest.raises(ValueError, match="A"):
        first_crossing([[1.0, 2.0]], [1], 0.0, [1.0], 1.0)
    with pytest.raises(ValueError, match="z0"):
        first_crossing([[1.0]], [1], 0.0, [1.0, 2.0], 1.0)
    with pytest.raises(ValueError, match="z0"):
        first_crossing([[1.0]], [1], 0.0, [np.nan], 1.0)
    with pytest.raises(ValueError, match="c"):
        first_crossing([[1.0]], [1, 2], 0.0, [1.0], 1.0)
    with pytest.raises(ValueError, match="t_max"):
        first_crossing([[1.0]], [1], 0.0, [1.0], -1.0)
    with pytest.raises(ValueError, match="direction"):
        first_crossing([[1.0]], [1], 0.0, [1.0], 1.0, direction=0)
    with pytest.raises(ValueError, match="b"):
        first_crossing([[1.0]], [1], 0.0, [1.0], 1.0, b=[1.0, 2.0])
    with pytest.raises(ValueError, match="d"):
        first_crossing([[1.0]], [1], np.inf, [1.0], 1.0)


def test_overflow_and_step_limit_are_reported():
    with pytest.raises(FloatingPointError):
        first_crossing([[800.0]], [1.0], 1.0, [1.0], 5.0)
    with pytest.raises(RuntimeError, match="max_steps"):
        first_crossing([[0, 1], [-1e4, 0]], [-1, 0], 2.0, [1.0, 0.0], 100.0, max_steps=10)


# ---------------------------------------------------------------------------- random vs grid
@settings(max_examples=1000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1))
def test_random_states_against_dense_sampling(seed):
    _check_against_grid(seed)


@pytest.mark.slow
@settings(max_examples=6000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1))
def test_random_states_against_dense_sampling_many(seed):
    _check_against_grid(seed, N=6000)


# ---------------------------------------------------------------------------- near grazing
def _oscillator_max_case(w, R, ts, eta):
    """``x = R cos(w (t - ts))`` against the guard ``x <= R - eta``; min of ``f`` is ``-eta``."""
    A = [[0.0, 1.0], [-w * w, 0.0]]
    z0 = [R * math.cos(w * ts), R * w * math.sin(w * ts)]
    return A, z0


@settings(max_examples=1500, deadline=None)
@given(w=st.floats(0.2, 5.0), logR=st.floats(-3, 3), frac=st.floats(0.05, 0.95),
       lev=st.floats(-16, -2), sign=st.sampled_from([-1, 1]))
def test_near_grazing_double_crossing_and_near_miss(w, logR, frac, lev, sign):
    R = 10.0 ** logR
    T = 2 * math.pi / w
    ts = frac * T                      # the first maximum, somewhere inside a step
    eta = sign * R * 10.0 ** lev
    dt = math.acos(max(-1.0, (R - abs(eta)) / R)) / w
    if ts - dt < 1e-3 or T - ts < dt + 1e-3:
        return
    A, z0 = _oscillator_max_case(w, R, ts, eta)
    r = first_crossing(A, [-1.0, 0.0], R - eta, z0, ts + 0.5 / w)
    if abs(eta) > 1e-12 * R:
        if eta > 0:
            # a genuine pair of crossings 2*dt apart: the first one, accurately
            assert r.kind == "crossing"
            slope = R * w * math.sin(w * dt)
            assert abs(r.time - (ts - dt)) * slope <= 1e-13 * R
        else:
            assert r.kind == "none"          # a near miss never fires
    else:
        # within rounding of a tangency: grazing (or a crossing / nothing) at the maximum
        if r.kind != "none":
            assert abs(r.time - ts) * w < 2e-6


@pytest.mark.parametrize("delta", [1e-2, 1e-4, 1e-5, 1e-6])
@pytest.mark.parametrize("tstar", [0.0123, 0.37, 0.999, 1.5])
def test_polynomial_double_crossing(delta, tstar):
    # g(t) = (t - t*)^2 - delta^2 from the triple integrator: two crossings 2 delta apart
    A = [[0, 1, 0], [0, 0, 1], [0, 0, 0]]
    z0 = [tstar ** 2 - delta ** 2, -2 * tstar, 2.0]
    r = first_crossing(A, [1, 0, 0], 0.0, z0, 2.0)
    if tstar - delta <= 0:
        return
    assert r.kind == "crossing"
    assert abs(r.time - (tstar - delta)) <= 1e-13 / delta + 1e-15
    # the near miss with the same tiny margin does not fire
    z0m = [tstar ** 2 + delta ** 2, -2 * tstar, 2.0]
    assert first_crossing(A, [1, 0, 0], 0.0, z0m, 2.0).kind == "none"


@pytest.mark.parametrize("delta", [1e-8, 1e-9, 0.0])
def test_tangency_within_rounding_is_grazing(delta):
    A = [[0, 1, 0], [0, 0, 1], [0, 0, 0]]
    for sgn in (1, -1):
        z0 = [0.37 ** 2 - sgn * delta ** 2, -2 * 0.37, 2.0]
        r = first_crossing(A, [1, 0, 0], 0.0, z0, 2.0)
        assert r.kind == "grazing"
        assert r.time == pytest.approx(0.37, abs=1e-8)


def test_exact_tangency_of_oscillator_is_grazing():
    # x = sin t touches 1 at pi/2
    r = first_crossing([[0, 1], [-1, 0]], [1, 0], -1.0, [0.0, 1.0], 3.0, direction=1)
    assert r.kind == "grazing"
    assert r.time == pytest.approx(math.pi / 2, abs=1e-7)
    assert abs(r.state[1]) < 1e-12


def test_two_close_crossings_near_step_boundary():
    # both crossings of a narrow dip straddle the boundary between two steps
    md = prepare_lti_mode([[0, 1, 0], [0, 0, 1], [0, 0, 0]])
    for k in range(1, 4):
        tstar = k * md.h
        for delta in (1e-3, 1e-6):
            z0 = [tstar ** 2 - delta ** 2, -2 * tstar, 2.0]
            r = first_crossing([[0, 1, 0], [0, 0, 1], [0, 0, 0]], [1, 0, 0], 0.0, z0, 5.0)
            assert r.kind == "crossing"
            assert abs(r.time - (tstar - delta)) <= 1e-13 / delta


# ---------------------------------------------------------------------------- start on guard
def test_on_guard_leaving_does_not_fire_and_rebound_is_found():
    # the ball sits on the floor moving up: no event at t = 0, the return is found
    for v in (1.0, 1e-3, 1e-6, 1e-9, 1e-12):
        r = first_crossing(FREE_FALL, [1, 0], 0.0, [0.0, v], 1.0, b=[0, -G])
        assert r.kind == "crossing"
        assert r.time == pytest.approx(2 * v / G, rel=1e-12)


def test_on_guard_pushed_back_fires_at_once():
    # e = 0 under gravity: g = g' = 0, g'' < 0
    r = first_crossing(FREE_FALL, [1, 0], 0.0, [0.0, 0.0], 1.0, b=[0, -G])
    assert r.kind == "crossing" and r.time == 0.0
    # moving into the guard
    r = first_crossing(FREE_FALL, [1, 0], 0.0, [0.0, -1.0], 1.0, b=[0, -G])
    assert r.time == 0.0
    # strictly on the forbidden side
    r = first_crossing(FREE_FALL, [1, 0], 0.0, [-1e-3, 1.0], 1.0, b=[0, -G])
    assert r.time == 0.0


def test_on_guard_higher_order_contact():
    # g = g' = g'' = 0, g''' > 0 (release from contact): no event; g''' < 0: at once
    A = [[0, 1, 0], [0, 0, 1], [0, 0, 0]]
    assert first_crossing(A, [1, 0, 0], 0.0, [0.0, 0.0, 0.0], 1.0, b=[0, 0, 1.0]).kind == "none"
    r = first_crossing(A, [1, 0, 0], 0.0, [0.0, 0.0, 0.0], 1.0, b=[0, 0, -1.0])
    assert r.time == 0.0
    # ... and a return after a cubic departure is still found: x = t^3/6 - t^4/24 -> t = 4
    A4 = np.diag([1.0, 1.0, 1.0], 1)
    r = first_crossing(A4, [1, 0, 0, 0], 0.0, [0.0, 0.0, 0.0, 1.0], 10.0, b=[0, 0, 0, -1.0])
    assert r.kind == "crossing" and r.time == pytest.approx(4.0, rel=1e-12)


def test_identically_zero_guard_never_fires():
    r = first_crossing([[0.0, 0.0], [0.0, 0.0]], [1, -1], 0.0, [2.0, 2.0], 10.0)
    assert r.kind == "none"


def test_rounding_level_offsets_count_as_on_guard():
    # a state a few ulps inside the wall after an impact must not re-fire
    for x in (-1e-17, 1e-17, -4e-16):
        r = first_crossing(FREE_FALL, [1, 0], 0.0, [x, 2.0], 1.0, b=[0, -G])
        assert r.time == pytest.approx(4 / G, rel=1e-12)


# ---------------------------------------------------------------------------- kernel contract
def test_kernel_hot_guard_and_priorities():
    md = prepare_lti_mode(FREE_FALL, [0, -G], [([1, 0], 0.0, -1), ([1, 0], 0.0, -1)],
                          priorities=[0, 5])
    w_out = np.empty(3)
    ft = md.flow_tables()
    assert ft.ng == 2 and ft.G is md.G
    code, t, g, _, err = advance(np.array([1.0, 0.0, 1.0]), 0.0, 3.0, ft, -1, 0.0, 1000, w_out)
    assert code == EV_CROSSING and g == 1 and err > 0
    assert t == pytest.approx(math.sqrt(2 / G), rel=1e-14)
    code, t, g, _, err = advance(np.array([0.0, 0.0, 1.0]), 0.0, 3.0, ft, -1, 0.0, 1000, w_out)
    assert code == EV_START and t == 0.0 and g == 1
    code, t, g, _, err = advance(np.array([1.0, 0.0, 1.0]), 0.0, 0.1, ft, -1, 0.0, 1000, w_out)
    assert code == EV_NONE and t == 0.1
    np.testing.assert_allclose(w_out, [1 - G * 0.005, -G * 0.1, 1.0], rtol=1e-15)
