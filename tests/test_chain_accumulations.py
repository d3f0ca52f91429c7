"""Chains of masses with clearances at low restitution: impacts that accumulate between
coupled contacts (in time, and at one instant), sticking of groups of contacts, and runs that
always reach their end time or say why not.

The motion is checked against an independent event loop written from the equations
(tests/_chain_reference.py: solve_ivp between events, Newton's law and the sticking rule by
enumerating the active sets of their complementarity problems)."""
import subprocess
import sys

import numpy as np
import pytest
from _chain_reference import ReferenceChain

from hybridpd.hybrid.automaton import Guard, HybridAutomaton, Mode, ZenoOptions
from hybridpd.mechanics import simulate
from hybridpd.mechanics.impact import impact_cascade, solve_lcp
from hybridpd.mechanics.samples import mass_chain


@pytest.mark.parametrize("n, e", [
    (3, 0.1), (4, 0.05), (6, 0.0),
    pytest.param(3, 0.0, marks=pytest.mark.slow), pytest.param(3, 0.05, marks=pytest.mark.slow),
    pytest.param(4, 0.0, marks=pytest.mark.slow), pytest.param(4, 0.1, marks=pytest.mark.slow),
    pytest.param(6, 0.05, marks=pytest.mark.slow), pytest.param(6, 0.1, marks=pytest.mark.slow),
])
def test_small_chain_against_an_independent_event_loop(n, e):
    """Positions over 2 s (every 2.5 ms) and the contacts that stick, in order.

    Tolerance 1e-8 on positions of order 1 (clearances 0.05): solve_ivp at rtol 1e-11,
    events located to ~1e-15 s, and the reference's plastic threshold v_stick = 1e-5 (its
    last resolved rebound rises at most v_stick^2 / (2 a) ~ 1e-12 and its relative velocity,
    below 1e-5, is removed a few microseconds early) keep the two within ~1e-10 (5e-11
    measured at every n and e here); 1e-8 leaves room for their growth over the run. The
    sticking starts differ by the unresolved tail of the reference's accumulations (below
    2 v_stick / ((1 - e) a), 1e-5 s with a >= 2)."""
    T = 2.0
    ref = ReferenceChain(n, e).run(T)
    tr = simulate(mass_chain(n, restitution=e), np.zeros(2 * n), (0.0, T), max_impacts=100000)
    assert tr.termination == "end_time" and tr.reason == ""
    ts = np.linspace(0.0, T, 801)
    np.testing.assert_allclose(tr.mechanical(ts)[:, 0::2], ref.positions(ts), rtol=0, atol=1e-8)
    assert [k for _, k in sorted((a, k) for a, _, k in tr.sticking)] == \
        [s[0] for _, s in ref.sticks] and len(tr.sticking) > 3
    np.testing.assert_allclose([a for a, _, _ in tr.sticking], [t for t, _ in ref.sticks],
                               rtol=0, atol=1e-5)


def _check_chain(m, e, T):
    ma = mass_chain(m + 1, restitution=e)
    tr = simulate(ma, np.zeros(2 * (m + 1)), (0.0, T), max_impacts=200000)
    assert tr.termination == "end_time", tr.reason
    assert tr.sticking and all(b > a for a, b, _ in tr.sticking), "a sticking interval of length 0"
    _, per_instant = np.unique(tr.hybrid.jumps.t, return_counts=True)
    assert per_instant.max() <= ZenoOptions().max_instant_jumps
    # every gap within its bound (the event location's rounding, and the drift of a held
    # contact's constrained flow), except inside the unresolved tails of accumulations
    ts = np.linspace(0.0, T, 4001)
    tails = [(a, b) for a, b, _ in tr.zeno_tails if b > a]
    ts = ts[[not any(a <= t <= b for a, b in tails) for t in ts]]
    q = tr.mechanical(ts)[:, 0::2]
    gaps = q[:, :-1] - q[:, 1:]
    tol = 1e-9 * (1 + 0.05) + 1e-12 * 2 * np.abs(q).max()
    assert np.abs(gaps).max() <= 0.05 + tol
    return tr


@pytest.mark.parametrize("e", [0.0, 0.05, 0.1])
@pytest.mark.parametrize("m", [3, 8])
def test_low_restitution_chains_reach_the_end(m, e):
    _check_chain(m, e, 2.0)


@pytest.mark.slow
@pytest.mark.parametrize("e", [0.0, 0.05, 0.1])
@pytest.mark.parametrize("m", range(3, 16))
def test_low_restitution_chains_reach_the_end_every_length(m, e):
    _check_chain(m, e, 5.0)


_FROZEN = """
import resource, sys, numpy as np
from hybridpd.mechanics import simulate
from hybridpd.mechanics.samples import mass_chain
n, e = int(sys.argv[1]), float(sys.argv[2])
tr = simulate(mass_chain(n, restitution=e), np.zeros(2 * n), (0.0, 10.0), max_impacts=200000)
print(tr.termination, len(tr.hybrid.jumps), min([b - a for a, b, _ in tr.sticking] + [1.0]),
      resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024)
"""


@pytest.mark.slow
@pytest.mark.parametrize("n, e", [(11, 0.1), (16, 0.05), (11, 0.0)])
def test_chains_that_used_to_freeze_reach_the_end(n, e):
    """These runs stopped at about t = 0.3 after 2e5 jumps at one instant (3 GB): now they
    reach t = 10 in a few thousand jumps, in a fresh process below 1.5 GB."""
    out = subprocess.run([sys.executable, "-c", _FROZEN, str(n), str(e)], capture_output=True,
                         text=True, check=True).stdout.split()
    termination, jumps, shortest, rss_mb = out[0], int(out[1]), float(out[2]), int(out[3])
    assert termination == "end_time" and jumps < 10000 and shortest > 0 and rss_mb < 1500


def test_joint_jumps_that_change_nothing_cannot_repeat():
    """Two guards of one group reached together, and a resolver that leaves the state as it
    is: the guards fire again at once; from their third firing at that instant the resolver
    is told so (refire = 1, 2, ...), and the run stops after max_instant_jumps jumps there,
    saying why."""
    A = np.zeros((2, 2))
    guards = (Guard("x", c=[1.0, 0.0], d=0.0, group=1), Guard("y", c=[0.0, 1.0], d=0.0, group=1))
    ha = HybridAutomaton([Mode("m", A, b=[-1.0, -1.0], guards=guards)],
                         zeno=ZenoOptions(max_instant_jumps=20))
    calls = []

    def resolver(mode, guard, t, z, refire=0):
        calls.append(refire)
        return z, "m", ["x", "y"]

    tr = ha.simulate([1.0, 1.0], "m", (0.0, 5.0), resolver=resolver)
    assert tr.termination.name == "ZENO" and "max_instant_jumps = 20" in tr.reason
    assert abs(tr.t_final - 1.0) < 1e-12 and len(tr.jumps) == 2 * (20 + 2)
    assert calls[:2] == [0, 0] and calls[2:] == list(range(1, len(calls) - 1))


def test_jump_limit_says_why():
    tr = simulate(mass_chain(4, restitution=0.8), np.zeros(8), (0.0, 50.0), max_impacts=40)
    assert tr.termination == "jump_limit"
    assert tr.reason.startswith("jump_limit: max_jumps = 40 jumps reached at t = ")
    assert tr.t_final < 50.0


def test_small_closing_speeds_are_not_rounded_away():
    """The LCP's tolerance is relative to q: closing speeds of 1e-13 still get their
    impulses (by hand: A = [[2, 1], [1, 2]], q = -1.5e-13 [1, 1], z = 0.5e-13 [1, 1])."""
    z = solve_lcp([[2.0, 1.0], [1.0, 2.0]], [-1.5e-13, -1.5e-13])
    np.testing.assert_allclose(z, [0.5e-13, 0.5e-13], rtol=1e-9, atol=0)


@pytest.mark.parametrize("e", [0.0, 0.3, 0.7, 1.0])
@pytest.mark.parametrize("m0, v0", [(1.0, [1.0, 0.0, 0.0]), (2.0, [1.0, -0.2, 0.3])])
def test_impact_cascade_against_single_impacts_by_hand(e, m0, v0):
    """Three masses (m0, 1, 1), both clearances closed: the cascade equals the single
    impacts of two bodies applied by hand, most closing contact first, until none closes or
    (for an accumulation) their closing speeds are below 1e-13; then the contacts of an
    accumulation move together (the common velocity of the two or three masses involved,
    from momentum)."""
    M = np.array([m0, 1.0, 1.0])
    W = np.array([[-1.0, 1.0, 0.0], [0.0, -1.0, 1.0]])        # u = v1 - v0, v2 - v1
    v = np.array(v0, float)
    first = max(-(W @ v).min(), 0.0)
    for _ in range(100000):
        u = W @ v
        i = int(np.argmin(u))
        if u[i] >= -1e-13 * first:
            break
        a, b = (0, 1) if i == 0 else (1, 2)      # bodies a | b, u = v_b - v_a < 0
        p = (1 + e) * (-u[i]) / (1 / M[a] + 1 / M[b])
        v[a] -= p / M[a]
        v[b] += p / M[b]
    out = impact_cascade(np.diag(1 / M), W, v0, [e, e])
    if out.accumulated:
        # by hand: the masses of the contacts at rest move with their common momentum
        together = np.abs(W @ v) <= 1e-9 * first
        lo, hi = (0, 2) if together.all() else ((0, 1) if together[0] else (1, 2))
        p = M[lo:hi + 1] @ v[lo:hi + 1] / M[lo:hi + 1].sum()
        v[lo:hi + 1] = p
    np.testing.assert_allclose(out.v, v, rtol=0, atol=1e-9 * max(first, 1.0))
    # momentum is conserved and energy not gained (unit-consistent checks of the law)
    np.testing.assert_allclose(M @ out.v, M @ np.asarray(v0), rtol=1e-12, atol=1e-12)
    assert M @ out.v ** 2 <= M @ np.asarray(v0) ** 2 * (1 + 1e-12)
