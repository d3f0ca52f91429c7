"""Generic guard/reset hybrid automaton (hybridpd.hybrid.automaton)."""
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from hybridpd.hybrid.automaton import (
    Guard,
    HybridAutomaton,
    HybridTrajectory,
    Mode,
    TerminationCause,
    ZenoOptions,
)

G = 9.81
FREE_FALL = np.array([[0.0, 1.0], [0.0, 0.0]])
OSC = np.array([[0.0, 1.0], [-1.0, 0.0]])


def _ball(e, sticking=True):
    rest = (np.zeros((2, 2)), np.zeros(2))
    floor = Guard("floor", c=[1.0, 0.0], d=0.0, direction=-1,
                  reset=([[1.0, 0.0], [0.0, -e]], [0.0, 0.0]), target="flight",
                  zeno_target="rest" if sticking else None,
                  zeno_reset=rest if sticking else None)
    modes = [Mode("flight", FREE_FALL, b=[0.0, -G], guards=(floor,))]
    if sticking:
        modes.append(Mode("rest", np.zeros((2, 2))))
    return HybridAutomaton(modes, state_names=("x", "v"))


# ---------------------------------------------------------------------------- flows
@pytest.mark.parametrize("seed", range(6))
def test_dense_output_without_guards_matches_solve_ivp(seed):
    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(2, 6))
    A = rng.normal(size=(n, n))
    A = A - A.T - 0.1 * np.eye(n) if seed % 2 else A - (np.linalg.eigvals(A).real.max()
                                                        + 0.2) * np.eye(n)
    b = rng.normal(size=n)
    z0 = rng.normal(size=n)
    ha = HybridAutomaton([Mode("m", A, b=b)])
    traj = ha.simulate(z0, "m", (1.0, 16.0))
    assert traj.termination is TerminationCause.END_TIME and traj.t_final == 16.0
    ts = np.sort(rng.uniform(1.0, 16.0, 50))
    sol = solve_ivp(lambda t, z: A @ z + b, (1.0, 16.0), z0, method="DOP853", rtol=1e-12,
                    atol=1e-12, t_eval=ts, dense_output=True)
    np.testing.assert_allclose(traj(ts), sol.y.T, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(traj.x_final, sol.sol(16.0), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(traj(1.0), z0, rtol=0, atol=0)


def test_trajectory_api_and_right_continuity():
    ha = _ball(0.5, sticking=False)
    traj = ha.simulate([1.0, 0.0], "flight", (0.0, 1.2))
    assert isinstance(traj, HybridTrajectory)
    assert traj.termination is TerminationCause.END_TIME
    t1 = math.sqrt(2 / G)
    jp = traj.jumps[0]
    assert jp.t == pytest.approx(t1, rel=1e-15) and jp.j == 1 and jp.kind == "crossing"
    assert (jp.source, jp.target, jp.guard) == ("flight", "flight", "floor")
    np.testing.assert_allclose(jp.pre, [0.0, -G * t1], atol=1e-14)
    np.testing.assert_allclose(jp.post, [0.0, 0.5 * G * t1], atol=1e-14)
    np.testing.assert_array_equal(traj(jp.t), jp.post)          # right-continuous
    np.testing.assert_allclose(traj(jp.t - 1e-12), jp.pre, atol=1e-10)
    assert len(traj.segments) == len(traj.jumps) + 1
    s = traj.segments[1]
    assert s.t_start == jp.t and s.mode == "flight" and s.j == 1
    assert traj.segments.t_end[0] == jp.t
    assert traj.mode_at(0.1) == "flight" and traj.mode_at([0.1, 0.2]) == ["flight"] * 2
    assert [j.j for j in traj.jumps] == list(range(1, len(traj.jumps) + 1))
    assert traj(np.array([0.0, 0.3])).shape == (2, 2)
    with pytest.raises(ValueError, match="t must"):
        traj(1.3)
    with pytest.raises(ValueError, match="t must"):
        traj(np.nan)


# ---------------------------------------------------------------------------- Zeno
@pytest.mark.parametrize("e", [0.2, 0.5, 0.8, 0.9])
@pytest.mark.parametrize("v0", [0.3, 2.0])
def test_zeno_accumulation_time_matches_closed_form(e, v0):
    t0 = 0.25
    t_inf = t0 + 2 * v0 / (G * (1 - e))
    traj = _ball(e).simulate([0.0, v0], "flight", (t0, t_inf + 1.0))
    assert traj.termination is TerminationCause.END_TIME
    assert traj.zeno_times.size == 1
    assert traj.zeno_times[0] == pytest.approx(t_inf, rel=1e-9)
    z = traj.jumps[-1]
    assert z.kind == "zeno" and z.guard == "floor" and z.target == "rest"
    assert z.t == traj.zeno_times[0]
    assert traj.mode_final == "rest"
    np.testing.assert_array_equal(traj.x_final, [0.0, 0.0])
    # the resolved impacts are the exact geometric sequence
    imp = traj.jumps.t[np.array(traj.jumps.kind) == "crossing"]
    k = np.arange(1, imp.size + 1)
    np.testing.assert_allclose(imp, t0 + 2 * v0 / G * (1 - e ** k) / (1 - e), rtol=1e-13)


def test_zeno_without_target_terminates_with_estimate():
    e, v0 = 0.5, 1.0
    traj = _ball(e, sticking=False).simulate([0.0, v0], "flight", (0.0, 10.0))
    assert traj.termination is TerminationCause.ZENO
    assert traj.zeno_times[0] == pytest.approx(2 * v0 / (G * (1 - e)), rel=1e-9)
    assert traj.t_final == traj.jumps.t[-1] < traj.zeno_times[0]
    np.testing.assert_array_equal(traj(traj.t_final), traj.x_final)


def test_zeno_predicted_after_end_time_is_ignored():
    e, v0 = 0.5, 1.0
    t_inf = 2 * v0 / (G * (1 - e))
    traj = _ball(e, sticking=False).simulate([0.0, v0], "flight", (0.0, t_inf - 1e-3))
    assert traj.termination is TerminationCause.END_TIME
    assert traj.zeno_times.size == 0


def test_immediate_accumulation_with_zero_restitution():
    # e = 0 under gravity: the first impact is followed by an immediate accumulation
    tr = _ball(0.0).simulate([1.0, 0.0], "flight", (0.0, 2.0))
    t1 = math.sqrt(2 / G)
    assert [j.kind for j in tr.jumps] == ["crossing", "zeno"]
    assert tr.jumps[1].t == tr.jumps[0].t == pytest.approx(t1, rel=1e-15)
    assert tr.zeno_times[0] == tr.jumps[0].t
    assert tr.mode_final == "rest" and tr.termination is TerminationCause.END_TIME
    tr = _ball(0.0, sticking=False).simulate([1.0, 0.0], "flight", (0.0, 2.0))
    assert tr.termination is TerminationCause.ZENO
    assert tr.zeno_times[0] == pytest.approx(t1, rel=1e-15)


def test_sticking_mode_released_by_force_guard():
    # block on a floor (x >= 0) under the force x'' = cos t - 0.5 (exosystem c = cos, s = sin)
    # state [x, v, c, s]; stuck while the contact force N = 0.5 - cos t >= 0
    A = np.zeros((4, 4))
    A[0, 1] = 1.0
    A[1, 2] = 1.0
    A[2, 3] = -1.0
    A[3, 2] = 1.0
    b = np.array([0.0, -0.5, 0.0, 0.0])
    proj = np.diag([0.0, 0.0, 1.0, 1.0])
    zero = np.zeros(4)
    As = A.copy()
    As[:2] = 0.0
    release = Guard("release", [0, 0, -1, 0], 0.5, reset=(proj, zero), target="free")
    for e, n_release in ((0.0, 5), (0.3, 2)):
        floor = Guard("floor", [1, 0, 0, 0], 0.0, reset=(np.diag([1.0, -e, 1, 1]), zero),
                      zeno_target="stuck", zeno_reset=(proj, zero))
        ha = HybridAutomaton([Mode("free", A, b=b, guards=(floor,)),
                              Mode("stuck", As, guards=(release,))])
        tr = ha.simulate([0.0, 0.0, 1.0, 0.0], "stuck", (0.0, 30.0))
        assert tr.termination is TerminationCause.END_TIME
        rel = [j for j in tr.jumps if j.guard == "release"]
        assert len(rel) == n_release
        assert rel[0].t == 0.0                        # N < 0 at the start: leaves at once
        for j in rel[1:]:
            # cos t = 0.5 while increasing: t = -pi/3 mod 2 pi
            assert math.remainder(j.t + math.pi / 3, 2 * math.pi) == pytest.approx(0, abs=1e-12)
        assert [j.kind for j in tr.jumps].count("zeno") >= n_release - 1
        ts = np.linspace(0, 30, 3001)
        x = tr(ts)[:, 0]
        assert x.min() > (-1e-12 if e == 0 else -1e-4)   # e > 0: unresolved Zeno tails


# ---------------------------------------------------------------------------- semantics
def test_post_reset_no_retrigger_and_genuine_reimpact():
    # tiny restitution: the rebound is tiny but the re-impact is found, not re-fired at once
    e = 1e-3
    tr = _ball(e, sticking=False).simulate([1.0, 0.0], "flight", (0.0, 0.5),
                                           zeno=ZenoOptions(enabled=False), max_jumps=4)
    t1 = math.sqrt(2 / G)
    v1 = G * t1
    dts = np.diff(tr.jumps.t)
    # (differences of absolute times: ~1e-16 absolute resolution)
    np.testing.assert_allclose(dts, 2 * v1 * e ** np.arange(1, 4) / G, rtol=1e-9, atol=1e-15)
    assert tr.termination is TerminationCause.JUMP_LIMIT


def test_grazing_is_reported_and_flow_continues():
    # x = sin t touches x = 1 at pi/2 + 2 k pi; the reset (identity) keeps the flow going
    touch = Guard("top", [1.0, 0.0], -1.0, direction=+1)
    ha = HybridAutomaton([Mode("osc", OSC, guards=(touch,))])
    tr = ha.simulate([0.0, 1.0], "osc", (0.0, 20.0))
    assert tr.termination is TerminationCause.END_TIME
    assert list(tr.jumps.kind) == ["grazing"] * 3
    np.testing.assert_allclose(tr.jumps.t, math.pi / 2 + 2 * math.pi * np.arange(3), atol=1e-7)
    np.testing.assert_allclose(tr.x_final, [math.sin(20.0), math.cos(20.0)], atol=1e-9)


def test_priority_decides_simultaneous_guards():
    low = Guard("low", [1.0, 0.0], 0.0, target="a", priority=0)
    high = Guard("high", [1.0, 0.0], 0.0, target="b", priority=3)
    ha = HybridAutomaton([Mode("m", FREE_FALL, b=[0, -G], guards=(low, high)),
                          Mode("a", np.zeros((2, 2))), Mode("b", np.zeros((2, 2)))])
    tr = ha.simulate([1.0, 0.0], "m", (0.0, 1.0))
    assert tr.jumps[0].guard == "high" and tr.mode_final == "b"
    # equal priorities: declaration order
    g1 = Guard("first", [1.0, 0.0], 0.0, target="a")
    g2 = Guard("second", [1.0, 0.0], 0.0, target="b")
    ha = HybridAutomaton([Mode("m", FREE_FALL, b=[0, -G], guards=(g1, g2)),
                          Mode("a", np.zeros((2, 2))), Mode("b", np.zeros((2, 2)))])
    assert ha.simulate([1.0, 0.0], "m", (0.0, 1.0)).jumps[0].guard == "first"


def test_earliest_of_several_guards_wins():
    lo = Guard("low_wall", [1.0, 0.0], 0.5, target="done")           # x = -0.5
    hi = Guard("high_wall", [-1.0, 0.0], 0.5, target="done")         # x = +0.5
    ha = HybridAutomaton([Mode("osc", OSC, guards=(lo, hi)), Mode("done", np.zeros((2, 2)))])
    tr = ha.simulate([0.0, -1.0], "osc", (0.0, 10.0))
    assert tr.jumps[0].guard == "low_wall"
    assert tr.jumps[0].t == pytest.approx(math.pi / 6, abs=1e-14)


def test_initial_state_in_jump_set_fires_at_start():
    ha = _ball(0.5, sticking=False)
    tr = ha.simulate([-0.1, 1.0], "flight", (0.0, 0.1), max_jumps=1)
    assert tr.jumps[0].t == 0.0


def test_instant_jump_loop_is_bounded():
    # two modes whose guards are both violated: ping-pong at one instant
    ga = Guard("ga", [1.0], 1.0, target="b")      # fires while x <= -1
    gb = Guard("gb", [1.0], 1.0, target="a")
    ha = HybridAutomaton([Mode("a", [[0.0]], guards=(ga,)), Mode("b", [[0.0]], guards=(gb,))])
    tr = ha.simulate([-2.0], "a", (0.0, 1.0), zeno=ZenoOptions(max_instant_jumps=10))
    assert tr.termination is TerminationCause.ZENO
    assert len(tr.jumps) == 11 and np.all(tr.jumps.t == 0.0)
    tr = ha.simulate([-2.0], "a", (0.0, 1.0), zeno=ZenoOptions(enabled=False), max_jumps=50)
    assert tr.termination is TerminationCause.JUMP_LIMIT and len(tr.jumps) == 50


# ---------------------------------------------------------------------------- termination
def test_every_termination_cause_is_reachable():
    assert _ball(1.0).simulate([1.0, 0.0], "flight", (0.0, 1.0)).termination \
        is TerminationCause.END_TIME
    tr = _ball(1.0).simulate([1.0, 0.0], "flight", (0.0, 100.0), max_jumps=7)
    assert tr.termination is TerminationCause.JUMP_LIMIT and len(tr.jumps) == 7
    # stops at the 8th event with the pre-jump state
    assert tr.x_final[0] == pytest.approx(0.0, abs=1e-12) and tr.x_final[1] < 0
    tr = _ball(0.5, sticking=False).simulate([1.0, 0.0], "flight", (0.0, 100.0))
    assert tr.termination is TerminationCause.ZENO
    tr = HybridAutomaton([Mode("up", [[800.0]])]).simulate([1.0], "up", (0.0, 10.0))
    assert tr.termination is TerminationCause.NONFINITE and tr.t_final < 1.0
    boom = Guard("boom", [1.0], -2.0, direction=+1, reset=([[1e308]], [0.0]))
    tr = HybridAutomaton([Mode("m", [[1.0]], guards=(boom,))]).simulate([1.0], "m", (0, 3))
    assert tr.termination is TerminationCause.NONFINITE
    assert tr.t_final == pytest.approx(math.log(2.0), rel=1e-14)
    tr = HybridAutomaton([Mode("osc", OSC * 100)]).simulate([1.0, 0.0], "osc", (0.0, 100.0),
                                                            max_steps=50)
    assert tr.termination is TerminationCause.STEP_LIMIT and tr.n_steps == 50
    assert 0.0 < tr.t_final < 100.0
    np.testing.assert_allclose(tr.x_final, [math.cos(100 * tr.t_final),
                                            -math.sin(100 * tr.t_final)], atol=1e-12)
    grow = Guard("grow", [1.0], -2.0, direction=+1, reset=([[1e12]], [0.0]))
    tr = HybridAutomaton([Mode("m", [[1.0]], guards=(grow,))]).simulate(
        [1.0], "m", (0, 3), max_state=1e10)
    assert tr.termination is TerminationCause.DIVERGED
    assert tr.t_final == pytest.approx(math.log(2.0), rel=1e-14)
    two = (Guard("a", [1.0, 0.0], -1.0, direction=+1, group=1),
           Guard("b", [0.0, 1.0], -1.0, direction=+1, group=1))
    ha = HybridAutomaton([Mode("m", np.zeros((2, 2)), b=[1.0, 1.0], guards=two)])
    tr = ha.simulate([0.0, 0.0], "m", (0, 3), resolver=lambda *a: None)
    assert tr.termination is TerminationCause.SIMULTANEOUS
    assert tr.t_final == pytest.approx(1.0, rel=1e-14) and len(tr.jumps) == 0
    assert {c.name for c in TerminationCause} == {"END_TIME", "JUMP_LIMIT", "ZENO",
                                                  "NONFINITE", "STEP_LIMIT", "SIMULTANEOUS",
                                                  "DIVERGED"}


def test_long_runs_resume_across_buffers():
    # more jumps than one output buffer holds
    tr = _ball(1.0).simulate([0.0, 1.0], "flight", (0.0, 1000.0), max_jumps=100_000)
    period = 2 / G
    assert len(tr.jumps) == int(1000.0 / period)
    np.testing.assert_allclose(np.diff(tr.jumps.t), period, rtol=1e-9)
    assert len(tr.segments) == len(tr.jumps) + 1


# ---------------------------------------------------------------------------- validation
def test_validation_errors_name_the_parameter():
    ok = Guard("g", [1.0, 0.0], 0.0)
    with pytest.raises(ValueError, match="direction"):
        Guard("g", [1.0, 0.0], 0.0, direction=0)
    with pytest.raises(ValueError, match="c must be finite"):
        Guard("g", [np.nan, 0.0], 0.0)
    with pytest.raises(ValueError, match="name"):
        Guard("", [1.0], 0.0)
    with pytest.raises(ValueError, match="zeno_reset"):
        Guard("g", [1.0], 0.0, zeno_reset=(np.eye(1), [0.0]))
    with pytest.raises(ValueError, match="A"):
        Mode("m", [[1.0, 2.0]])
    with pytest.raises(ValueError, match="b"):
        Mode("m", OSC, b=[1.0])
    with pytest.raises(ValueError, match="guard names"):
        Mode("m", OSC, guards=(ok, ok))
    with pytest.raises(ValueError, match="modes"):
        HybridAutomaton([])
    with pytest.raises(ValueError, match="names must be unique"):
        HybridAutomaton([Mode("m", OSC), Mode("m", OSC)])
    with pytest.raises(ValueError, match="shape"):
        HybridAutomaton([Mode("m", OSC), Mode("k", np.eye(3))])
    with pytest.raises(ValueError, match="c must have shape"):
        HybridAutomaton([Mode("m", OSC, guards=(Guard("g", [1.0], 0.0),))])
    with pytest.raises(ValueError, match="target"):
        HybridAutomaton([Mode("m", OSC, guards=(Guard("g", [1.0, 0], 0.0, target="x"),))])
    with pytest.raises(ValueError, match="zeno_target"):
        HybridAutomaton([Mode("m", OSC, guards=(Guard("g", [1.0, 0], 0.0, zeno_target="x"),))])
    with pytest.raises(ValueError, match="reset"):
        HybridAutomaton([Mode("m", OSC, guards=(Guard("g", [1.0, 0], 0.0,
                                                      reset=(np.eye(3), [0, 0])),))])
    with pytest.raises(ValueError, match="state_names"):
        HybridAutomaton([Mode("m", OSC)], state_names=("a",))
    ha = HybridAutomaton([Mode("m", OSC, guards=(ok,))])
    with pytest.raises(ValueError, match="x0"):
        ha.simulate([1.0], "m", (0, 1))
    with pytest.raises(ValueError, match="x0"):
        ha.simulate([np.inf, 1.0], "m", (0, 1))
    with pytest.raises(ValueError, match="unknown mode"):
        ha.simulate([1.0, 0.0], "nope", (0, 1))
    with pytest.raises(ValueError, match="t_span"):
        ha.simulate([1.0, 0.0], "m", (1, 0))
    with pytest.raises(ValueError, match="t_span"):
        ha.simulate([1.0, 0.0], "m", (0, np.nan))
    with pytest.raises(ValueError, match="max_jumps"):
        ha.simulate([1.0, 0.0], "m", (0, 1), max_jumps=-1)
    with pytest.raises(ValueError, match="max_steps"):
        ha.simulate([1.0, 0.0], "m", (0, 1), max_steps=0)
    with pytest.raises(ValueError, match="ratio_max"):
        ZenoOptions(ratio_max=1.5)


# ---------------------------------------------------------------------------- robustness
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1))
def test_random_automata_never_hang_or_crash(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 4))
    modes = []
    names = ["m0", "m1", "m2"][: int(rng.integers(1, 4))]
    for name in names:
        A = rng.normal(size=(n, n)) * rng.choice([0.1, 1.0, 5.0])
        b = rng.normal(size=n) if rng.random() < 0.5 else None
        guards = []
        for k in range(int(rng.integers(0, 3))):
            R = np.eye(n) + 0.5 * rng.normal(size=(n, n)) * (rng.random() < 0.5)
            zt = str(rng.choice(names)) if rng.random() < 0.3 else None
            guards.append(Guard(f"g{k}", rng.normal(size=n), float(rng.normal()),
                                direction=int(rng.choice([-1, 1])),
                                reset=(R, 0.1 * rng.normal(size=n)),
                                target=str(rng.choice(names)),
                                priority=int(rng.integers(0, 3)), zeno_target=zt))
        modes.append(Mode(name, A, b=b, guards=tuple(guards)))
    ha = HybridAutomaton(modes)
    tr = ha.simulate(rng.normal(size=n), "m0", (0.0, float(rng.uniform(0.1, 20.0))),
                     max_jumps=2000, max_steps=200_000)
    assert isinstance(tr.termination, TerminationCause)
    assert len(tr.jumps) <= 2000 and tr.n_steps <= 200_000
    assert np.all(np.diff(tr.jumps.t) >= 0)
    if tr.termination is TerminationCause.END_TIME:
        assert tr.t_final == tr.segments.t_end[-1]
    if np.all(np.isfinite(tr.x_final)):
        np.testing.assert_array_equal(tr(tr.t_final), tr.x_final)


# ---------------------------------------------------------------------------- modes on demand
def _ladder_builder(calls):
    """Modes ``L0, L1, ...``: in ``Lk`` the state grows at rate ``k + 1`` and a guard at
    ``x = 1`` resets it to 0 and enters ``L{k+1}`` (an unbounded family of modes)."""
    def build(name):
        if not (name.startswith("L") and name[1:].isdigit()):
            raise ValueError(f"unknown mode {name!r}")
        k = int(name[1:])
        calls.append(k)
        g = Guard("top", [1.0], -1.0, direction=+1, reset=([[0.0]], [0.0]), target=f"L{k + 1}")
        return Mode(name, [[0.0]], b=[k + 1.0], guards=(g,))
    return build


def test_modes_are_built_when_a_run_enters_them():
    calls = []
    build = _ladder_builder(calls)
    ha = HybridAutomaton([build("L0")], mode_builder=build, max_modes=50)
    assert ha.n_built == 1 and calls == [0]
    tr = ha.simulate([0.0], "L0", (0.0, 1.0 + 1 / 2 + 1 / 3 + 0.01))
    # three jumps at t = 1, 1.5, 1.8333...: modes L1..L3 built on entry, nothing more
    assert ha.n_built == 4 and calls == [0, 1, 2, 3]
    np.testing.assert_allclose(tr.jumps.t, np.cumsum([1, 1 / 2, 1 / 3]), rtol=1e-14)
    assert tr.jumps.target == ("L1", "L2", "L3") and tr.mode_final == "L3"
    np.testing.assert_allclose(tr(1.6), [0.1 * 3], rtol=1e-13)   # dense output in L2
    assert ha.mode_index("L7") == 4 and ha.n_built == 5          # looked up: built
    with pytest.raises(ValueError, match="unknown mode"):
        ha.mode_index("X")
    with pytest.raises(ValueError, match="max_modes"):
        ha.materialize()                                          # the family is unbounded


def test_materialize_builds_every_reachable_mode_in_reservation_order():
    ga = Guard("ga", [1.0], -1.0, direction=+1, target="b", zeno_target="c")
    gb = Guard("gb", [1.0], -2.0, direction=+1, target="a")
    built = {"a": Mode("a", [[0.0]], b=[1.0], guards=(ga,)),
             "b": Mode("b", [[0.0]], b=[1.0], guards=(gb,)), "c": Mode("c", [[0.0]])}

    def build(name):
        if name not in built:
            raise ValueError(f"unknown mode {name!r}")
        return built[name]
    ha = HybridAutomaton([built["a"]], mode_builder=build)
    assert ha.n_built == 1
    assert ha.mode_names == ("a", "b", "c") and ha.packed.ng.tolist() == [1, 1, 0]
    np.testing.assert_array_equal(ha.packed.target[:2, 0], [1, 0])
    assert ha.packed.zt[0, 0] == 2
    # a fully given automaton refuses unknown targets as before
    with pytest.raises(ValueError, match="unknown target mode 'b'"):
        HybridAutomaton([built["a"]])


# ---------------------------------------------------------------------------- compiled-code cache
_TINY = '''
import logging, sys
logging.basicConfig(level=logging.INFO, stream=sys.stderr, format="%(message)s")
from hybridpd._jit import njit

@njit(cache=True)
def twice(x):
    return 2.0 * x

print(twice(1.5), twice.dispatcher.stats.cache_hits.total(),
      twice.dispatcher.stats.cache_misses.total())
'''


def test_compiled_kernels_are_cached_once_in_a_private_directory(tmp_path):
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).parents[1]
    (tmp_path / "tinymod.py").write_text(_TINY)
    cache = tmp_path / "nb"
    env = dict(os.environ, PYTHONPATH=f"{root}{os.pathsep}{tmp_path}",
               HYBRIDPD_NUMBA_CACHE_DIR=str(cache))
    run = [sys.executable, "-c", "import tinymod"]
    first = subprocess.run(run, env=env, capture_output=True, text=True, timeout=120,
                           check=False)
    second = subprocess.run(run, env=env, capture_output=True, text=True, timeout=120,
                           check=False)
    assert first.stdout.split() == ["3.0", "0", "1"], first.stderr
    assert "compiling the numba kernels" in first.stderr
    assert second.stdout.split() == ["3.0", "1", "0"], second.stderr   # loaded, not compiled
    assert "compiling" not in second.stderr
    assert cache.stat().st_mode & 0o777 == 0o700 and any(cache.rglob("*.nbi"))
    # a directory that others can write is never used: compiled in memory, nothing loaded
    os.chmod(cache, 0o777)
    third = subprocess.run(run, env=env, capture_output=True, text=True, timeout=120,
                           check=False)
    assert third.stdout.split()[:2] == ["3.0", "0"], third.stderr      # nothing loaded
    assert "not private" in third.stderr
