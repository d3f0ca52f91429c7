"""Sample impacting systems (hybridpd.hybrid.samples) against closed forms and solve_ivp."""
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from hybridpd.hybrid.automaton import TerminationCause
from hybridpd.hybrid.samples import (
    ball_initial_state,
    bouncing_ball,
    impact_oscillator,
    oscillator_initial_state,
)

G = 9.81


def _outside_zeno_tails(traj, ts):
    """Mask of ``ts`` outside the unresolved tails (flow segments ending in a Zeno jump)."""
    zeno_t = {j.t for j in traj.jumps if j.kind == "zeno"}
    mask = np.ones(ts.size, bool)
    for s in traj.segments:
        if s.t_end in zeno_t and s.t_end > s.t_start:
            mask &= ~((ts > s.t_start) & (ts < s.t_end))
    return mask


# ---------------------------------------------------------------------------- bouncing ball
@pytest.mark.parametrize("e", [0.3, 0.6, 0.85])
@pytest.mark.parametrize("v0", [0.5, 3.0])
def test_ball_on_fixed_table_accumulates_then_rests(e, v0):
    t0 = 1.5
    ha = bouncing_ball(e=e)
    tr = ha.simulate(ball_initial_state(0.0, v0, t0=t0), "flight", (t0, 10.0))
    t_inf = t0 + 2 * v0 / (G * (1 - e))
    assert tr.termination is TerminationCause.END_TIME
    assert tr.zeno_times.size == 1
    assert abs(tr.zeno_times[0] - t_inf) <= 1e-9 * t_inf
    assert tr.mode_final == "contact"
    assert tr.mode_at(t_inf + 1e-6) == "contact"
    np.testing.assert_array_equal(tr.x_final, [0.0, 0.0, 0.0, 0.0])
    # never below the table where the impacts are resolved
    ts = np.linspace(t0, 10.0, 4001)
    gap = np.diff(tr(ts)[:, [2, 0]], axis=1)[:, 0]
    assert gap[_outside_zeno_tails(tr, ts)].min() >= -1e-15


def test_ball_without_sticking_stops_with_zeno():
    ha = bouncing_ball(e=0.5, sticking=False)
    assert ha.mode_names == ("flight",)
    tr = ha.simulate(ball_initial_state(0.0, 1.0), "flight", (0.0, 5.0))
    assert tr.termination is TerminationCause.ZENO
    assert tr.zeno_times[0] == pytest.approx(2 / (G * 0.5), rel=1e-9)


def _vibrating(e, a=0.01, f=8.0, t1=4.0, gap0=0.0, v0=0.0):
    w = 2 * math.pi * f
    ha = bouncing_ball(e=e, amplitude=a, omega=w)
    x0 = ball_initial_state(gap0, v0, amplitude=a, omega=w, relative=True)
    return w, ha.simulate(x0, "flight", (0.0, t1), max_jumps=50_000)


@pytest.mark.parametrize("e", [0.0, 0.4, 0.5])
def test_ball_on_vibrating_table_sticks_releases_and_bounces_again(e):
    w, tr = _vibrating(e)
    assert tr.termination is TerminationCause.END_TIME and tr.t_final == 4.0
    releases = [j for j in tr.jumps if j.guard == "release"]
    assert len(releases) >= 3
    for j in releases:
        # the table's acceleration -w^2 x_table drops below -g (x_table rising)
        assert -w * w * j.pre[2] == pytest.approx(-G, rel=1e-10)
        assert j.pre[3] > 0
        np.testing.assert_array_equal(j.pre[:2], j.pre[2:])        # ball on the table
    # after every release but possibly the last the ball lands again
    last_release = releases[-1].t
    for j in releases[:-1]:
        later = [k for k in tr.jumps if k.t > j.t and k.guard == "impact"]
        assert later and later[0].kind in ("crossing", "grazing")
    assert any(k.guard == "impact" for k in tr.jumps if k.t > releases[0].t)
    ts = np.linspace(0.0, 4.0, 8001)
    X = tr(ts)
    gap = X[:, 0] - X[:, 2]
    assert gap[_outside_zeno_tails(tr, ts)].min() >= -1e-12
    assert gap.min() >= -1e-3                                        # tails stay tiny
    modes = np.array(tr.mode_at(ts))
    contact = modes == "contact"
    assert contact.any() and (~contact).any()
    # in contact the contact force g + x_table'' is non-negative
    assert np.min(G - w * w * X[contact, 2]) >= -1e-9
    np.testing.assert_allclose(gap[contact], 0.0, atol=1e-12)
    assert last_release < 4.0


def test_ball_vibrating_table_impacts_against_free_flight_formula():
    # between impacts the ball is a parabola and the table a sinusoid: check every impact
    a, f = 0.02, 3.0
    w = 2 * math.pi * f
    ha = bouncing_ball(e=0.9, amplitude=a, omega=w)
    tr = ha.simulate(ball_initial_state(0.3, 0.0, amplitude=a, omega=w), "flight", (0.0, 3.0))
    for j in tr.jumps:
        if j.guard != "impact" or j.kind != "crossing":
            continue
        table = a * math.sin(w * j.t)
        assert j.pre[2] == pytest.approx(table, abs=1e-12)
        assert j.pre[0] == pytest.approx(table, abs=1e-12)
        # Newton's law in the table frame
        assert (j.post[1] - j.post[3]) == pytest.approx(-0.9 * (j.pre[1] - j.pre[3]),
                                                         abs=1e-12)


def test_ball_initial_state_helper():
    x = ball_initial_state(0.5, 1.0, t0=0.25, amplitude=0.1, omega=2 * math.pi)
    np.testing.assert_allclose(x, [0.6, 1.0, 0.1, 0.0], atol=1e-15)
    x = ball_initial_state(0.0, 1.0, amplitude=0.1, omega=2.0, relative=True)
    np.testing.assert_allclose(x, [0.0, 1.2, 0.0, 0.2])
    with pytest.raises(ValueError, match="gap"):
        ball_initial_state(-1.0, 0.0)
    with pytest.raises(ValueError, match="velocity"):
        ball_initial_state(1.0, np.nan)


def test_sample_parameter_validation():
    with pytest.raises(ValueError, match="e must"):
        bouncing_ball(e=1.5)
    with pytest.raises(ValueError, match="g must"):
        bouncing_ball(g=-1.0)
    with pytest.raises(ValueError, match="omega"):
        bouncing_ball(omega=np.nan)
    with pytest.raises(ValueError, match="omega0"):
        impact_oscillator(omega0=0.0)
    with pytest.raises(ValueError, match="mass"):
        impact_oscillator(mass=-1.0)
    with pytest.raises(ValueError, match="stop"):
        impact_oscillator(stop=np.inf)
    with pytest.raises(ValueError, match="x must"):
        oscillator_initial_state(np.nan, 0.0)


# ---------------------------------------------------------------------------- impact oscillator
def _reference_impacts(w0, zeta, F, W, s, e, x0, v0, T, phase=0.0, m=1.0):
    """Independent solve_ivp loop with terminal events (DOP853, tight tolerances)."""
    def rhs(t, y):
        return [y[1], -w0 * w0 * y[0] - 2 * zeta * w0 * y[1] + F * math.cos(W * t + phase) / m]

    def hit(t, y):
        return s - y[0]
    hit.terminal = True
    hit.direction = -1
    t, y, times = 0.0, [x0, v0], []
    while t < T:
        sol = solve_ivp(rhs, (t, T), y, method="DOP853", rtol=1e-12, atol=1e-12, events=hit)
        if sol.status != 1:
            break
        t = float(sol.t_events[0][0])
        ye = sol.y_events[0][0]
        times.append(t)
        y = [s, -e * ye[1]]
    return np.array(times)


@pytest.mark.parametrize("params", [
    {"w0": 1.0, "zeta": 0.05, "F": 1.0, "W": 0.8, "s": 0.5, "e": 0.8, "x0": 0.0, "v0": 0.0, "T": 80.0},
    {"w0": 2.0, "zeta": 0.02, "F": 3.0, "W": 2.7, "s": 0.3, "e": 0.6, "x0": -0.2, "v0": 1.0, "T": 30.0},
    {"w0": 1.0, "zeta": 0.0, "F": 0.7, "W": 1.3, "s": 0.4, "e": 0.95, "x0": 0.1, "v0": 0.0, "T": 60.0},
])
def test_oscillator_impacts_against_solve_ivp(params):
    p = params
    ha = impact_oscillator(p["w0"], p["zeta"], p["F"], p["W"], p["s"], p["e"])
    x0 = oscillator_initial_state(p["x0"], p["v0"], force=p["F"], omega=p["W"])
    tr = ha.simulate(x0, "free", (0.0, p["T"]))
    ref = _reference_impacts(p["w0"], p["zeta"], p["F"], p["W"], p["s"], p["e"], p["x0"],
                             p["v0"], p["T"])
    assert "zeno" not in tr.jumps.kind
    assert len(tr.jumps) == ref.size >= 8
    np.testing.assert_allclose(tr.jumps.t, ref, rtol=0, atol=1e-8)
    for j in tr.jumps:
        assert j.pre[0] == pytest.approx(p["s"], abs=1e-13) and j.pre[1] > 0
        assert j.post[1] == pytest.approx(-p["e"] * j.pre[1], rel=1e-15)
    # the forcing exosystem is exact: f_c = F cos(W t)
    ts = np.linspace(0, p["T"], 101)
    np.testing.assert_allclose(tr(ts)[:, 2], p["F"] * np.cos(p["W"] * ts), atol=1e-12)


def test_oscillator_sticks_to_the_stop_and_releases():
    F, W, s = 2.0, 0.4, 0.1
    ha = impact_oscillator(1.0, 0.05, F, W, s, 0.5)
    tr = ha.simulate(oscillator_initial_state(-0.5, 0.0, force=F, omega=W), "free", (0, 100))
    assert tr.termination is TerminationCause.END_TIME
    rel = [j for j in tr.jumps if j.guard == "release"]
    assert len(rel) >= 3 and [j.kind for j in tr.jumps].count("zeno") >= 3
    for j in rel:
        # the spring pulls harder than the forcing pushes: f_c = w0^2 s, decreasing
        assert j.pre[2] == pytest.approx(s, abs=1e-12) and j.pre[3] > 0
        np.testing.assert_array_equal(j.pre[:2], [s, 0.0])
    ts = np.linspace(0, 100, 5001)
    X = tr(ts)
    stuck = np.array(tr.mode_at(ts)) == "stuck"
    assert stuck.any()
    np.testing.assert_array_equal(X[stuck, 0], s)
    assert np.min(X[stuck, 2] - s) >= -1e-12                  # pressed into the stop
    assert X[_outside_zeno_tails(tr, ts), 0].max() <= s + 1e-14


# ---------------------------------------------------------------------------- robustness
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(e=st.floats(0.0, 1.0), a=st.floats(0.0, 0.05), f=st.floats(0.5, 20.0),
       gap=st.floats(0.0, 0.5), v=st.floats(-3.0, 3.0), phase=st.floats(0.0, 6.3))
def test_random_balls_run_to_the_end(e, a, f, gap, v, phase):
    w = 2 * math.pi * f
    ha = bouncing_ball(e=e, amplitude=a, omega=w)
    x0 = ball_initial_state(gap, v, amplitude=a, omega=w, phase=phase)
    tr = ha.simulate(x0, "flight", (0.0, 3.0), max_jumps=20_000)
    assert tr.termination in (TerminationCause.END_TIME, TerminationCause.JUMP_LIMIT)
    ts = np.linspace(0.0, tr.t_final, 2001)
    X = tr(ts)
    gap_t = X[:, 0] - X[:, 2]
    assert gap_t[_outside_zeno_tails(tr, ts)].min() >= -1e-9 * max(1.0, a)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(e=st.floats(0.0, 1.0), F=st.floats(0.0, 3.0), W=st.floats(0.1, 4.0),
       s=st.floats(-0.5, 1.0), zeta=st.floats(0.0, 0.3))
def test_random_oscillators_run_to_the_end(e, F, W, s, zeta):
    ha = impact_oscillator(1.0, zeta, F, W, s, e)
    x0 = oscillator_initial_state(min(s, 0.0) - 0.1, 0.0, force=F, omega=W)
    tr = ha.simulate(x0, "free", (0.0, 60.0), max_jumps=20_000)
    if tr.termination is TerminationCause.ZENO:
        # only an instant loop (e.g. a force of 1e-57 that releases and re-impacts at one
        # instant for ever) may stop the run: more than max_instant_jumps jumps at t_final
        assert np.count_nonzero(tr.jumps.t == tr.t_final) > 100
    else:
        assert tr.termination in (TerminationCause.END_TIME, TerminationCause.JUMP_LIMIT)
    ts = np.linspace(0.0, tr.t_final, 2001)
    x = tr(ts)[:, 0]
    assert x[_outside_zeno_tails(tr, ts)].max() <= s + 1e-9


@pytest.mark.slow
def test_long_chaotic_ball_run():
    _, tr = _vibrating(0.7, a=0.05, f=5.0, t1=300.0, gap0=0.1)
    assert tr.termination is TerminationCause.END_TIME
    assert len(tr.jumps) > 300
    ts = np.linspace(0.0, 300.0, 200_001)
    X = tr(ts)
    assert (X[:, 0] - X[:, 2])[_outside_zeno_tails(tr, ts)].min() >= -1e-12
