"""The impact pair on the generic automaton: impacts, Zeno, sticking, never hanging, CLI."""
import json
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hybridpd import ImpactPair, PDGains, Reference
from hybridpd.hybrid.automaton import TerminationCause
from hybridpd.pair.batch import STATUS_IMPACT, Flight, next_impact, pack_params
from hybridpd.pair.impactpair import ControlledImpactPair
from hybridpd.pair.naive import naive_simulate

CASES = ("collocated", "noncollocated")


def system(case="collocated", e=0.5, kp=10.0, kv=20.0, xm=1.0, mu=0.1, L=0.75, w=5.0):
    return ControlledImpactPair(ImpactPair(mu, e, L), PDGains(kp, kv), Reference(xm, w), case)


def test_200_impacts_against_naive_loop_non_chaotic():
    sysm = system("noncollocated")
    traj = sysm.simulate([0.3, 0.5, 0.0, 0.0], (0.0, 1e4), max_impacts=200)
    ref = naive_simulate(sysm.loop, sysm.initial_state([0.3, 0.5, 0.0, 0.0]), (0, 1e4),
                         max_impacts=200, rtol=1e-13, atol=1e-14)
    assert traj.n_impacts == 200
    np.testing.assert_array_equal(traj.walls, ref.walls)
    assert np.max(np.abs(traj.impact_times - ref.impact_times)) < 1e-8


@pytest.mark.parametrize("case", CASES)
def test_every_flight_against_the_batch_engine(case):
    """Two independent contact locators (Taylor-polynomial automaton, closed-form safe steps)
    agree on each flight started from the automaton's post-impact states."""
    sysm = system(case)
    traj = sysm.simulate([0.3, 0.5, 0.0, 0.0], (0.0, 60.0))
    p = pack_params(10, 20, 1, 0.1, 0.5, 0.75, 5.0, 1.0)
    c = CASES.index(case)
    t_prev = np.concatenate([[0.0], traj.impact_times[:-1]])
    starts = np.vstack([[0.3, 0.5, 0.0, 0.0], traj.post[:-1]])
    assert traj.n_impacts > 50
    for t0, s, t1, w in zip(t_prev, starts, traj.impact_times, traj.walls):
        st_, tau, wall, *_ = next_impact(p, c, Flight(t0, *s), 50.0, 1e-14)
        assert st_ == STATUS_IMPACT and wall == w
        assert abs(t0 + tau - t1) < 1e-9


def test_impact_records_obey_the_law():
    sysm = system()
    traj = sysm.simulate([0.3, 0.5, 0.0, 0.0], (0.0, 30.0))
    gap = traj.pre[:, 0] - traj.pre[:, 2]
    np.testing.assert_allclose(gap, 0.75 * traj.walls, atol=1e-10)
    z4pre = traj.pre[:, 1] - traj.pre[:, 3]
    z4post = traj.post[:, 1] - traj.post[:, 3]
    np.testing.assert_allclose(z4post, -0.5 * z4pre, atol=1e-12)
    assert np.all(z4pre * traj.walls > 0)
    # dense output is right-continuous at the impacts and matches the records
    k = 5
    np.testing.assert_allclose(traj(traj.impact_times[k])[:4], traj.post[k], atol=1e-12)


def test_chattering_case_runs_through_sticking_and_release():
    """e = 0.1: impacts accumulate, the masses stick, release when the force changes sign,
    and the run reaches its end time without hanging."""
    sysm = system(e=0.1)
    traj = sysm.simulate([0.3, 0.5, 0.0, 0.0], (0.0, 40.0), max_impacts=100_000)
    assert traj.termination == TerminationCause.END_TIME
    assert len(traj.sticking) >= 1
    for (a, b), w in zip(traj.sticking, traj.sticking_walls):
        assert b >= a
        mid = traj(0.5 * (a + b))
        # stuck: gap on the wall, equal velocities, force pressing
        assert abs(mid[0] - mid[2] - w * 0.75) < 1e-9
        assert abs(mid[1] - mid[3]) < 1e-9
        assert w * (sysm.loop.force @ mid) <= 1e-9


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(kp=st.floats(0.1, 80), kv=st.floats(0.1, 80), e=st.sampled_from([0.0, 1.0]) | st.floats(0, 1),
       mu=st.floats(0.01, 10), case=st.sampled_from(CASES), xm=st.floats(0, 2),
       x0=st.tuples(st.floats(-0.7, 0.7), st.floats(-3, 3), st.floats(-1, 1), st.floats(-3, 3)))
def test_parameter_sweep_never_hangs_or_crashes(kp, kv, e, mu, case, xm, x0):
    sysm = system(case, e=e, kp=kp, kv=kv, xm=xm, mu=mu)
    x = [x0[2] + x0[0], x0[1], x0[2], x0[3]]
    traj = sysm.simulate(x, (0.0, 5.0), max_impacts=2000)
    assert traj.termination in (TerminationCause.END_TIME, TerminationCause.JUMP_LIMIT,
                                TerminationCause.ZENO)
    assert np.all(np.isfinite(traj.pre)) and np.all(np.isfinite(traj.post))


def test_simulate_validation():
    sysm = system()
    with pytest.raises(ValueError, match="x0"):
        sysm.simulate([0.0, 0.0, 0.0], (0, 1))
    with pytest.raises(ValueError, match="L"):
        sysm.simulate([2.0, 0.0, 0.0, 0.0], (0, 1))
    with pytest.raises(ValueError, match="t_span"):
        sysm.simulate([0.0, 0.0, 0.0, 0.0], (1, 0))


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "hybridpd", *args], capture_output=True,
                          text=True, timeout=300, check=False)


def test_cli_simulate_json_and_errors():
    base = ["simulate", "--case", "collocated", "--mu", "0.1", "--e", "0.5", "--L", "0.75",
            "--omega", "5", "--kp", "10", "--kv", "20", "--xm", "1", "--x0", "0.3", "0.5", "0",
            "0", "--t-end", "3"]
    r = run_cli(*base, "--json")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert d["termination"] == "end_time" and len(d["impacts"]) >= 4
    assert set(d["impacts"][0]) >= {"t", "wall", "pre", "post"}
    assert d["impacts"][0]["wall"] in (1, -1) and len(d["impacts"][0]["pre"]) == 4
    bad = list(base)
    bad[bad.index("--e") + 1] = "1.5"
    r = run_cli(*bad)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "e must" in r.stderr
    r = run_cli("simulate", "--case", "collocated")
    assert r.returncode == 2 and r.stderr.count("\n") == 1
    r = run_cli("--version")
    assert r.returncode == 0 and "hybridpd" in r.stdout
