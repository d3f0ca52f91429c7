"""Sampled-data loops, compliant contacts and a randomized robustness sweep of the general
mechanical path."""
import math
import os

import control as ct
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hybridpd.mechanics import (
    Contact,
    MechanicalSystem,
    Reference,
    build_automaton,
    mechanical_loop,
)
from hybridpd.mechanics.naive import naive_mechanical
from hybridpd.mechanics.simulate import simulate

PAIR = MechanicalSystem(["x1", "x2"], M=[[0.1, 0.0], [0.0, 1.0]], B=[0.0, 1.0])
REF = Reference.sine(1.0, 5.0, feedforward=1.0)
X0 = [0.3, 0.5, 0.0, 0.0]


def pair_model(controller, measure="x1", contact=None, delay=0):
    loop = mechanical_loop(PAIR, controller, REF, measure, delay=delay)
    c = contact or Contact([1.0, -1.0], -0.75, 0.75, restitution=0.5)
    return build_automaton(loop, [c])


def discrete_pd(dt, kp=10.0, kv=20.0):
    return ct.ss(np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)), [[kp, kv]], dt)


@pytest.mark.parametrize("delay", [0, 2])
def test_sampling_instants_are_exact_and_the_force_is_held(delay):
    dt = 0.01
    ma = pair_model(discrete_pd(dt), delay=delay)
    tr = simulate(ma, X0, (0.0, 3.0))
    k = np.arange(1, tr.samples.size + 1)
    assert tr.samples.size == 300 or tr.samples.size == 299    # t = 3.0 may round either way
    assert np.max(np.abs(tr.samples - k * dt)) < 1e-13
    loop = ma.loop
    # the held force between two samples is constant and is the law applied at the sample
    # 'delay' samples before
    jt = tr.hybrid.jumps
    samp = [i for i, g in enumerate(jt.guard) if g == "sample"]
    u_law = []
    for i in samp:
        z = jt.pre[i]
        xd, vd, ad = REF(jt.t[i])
        u_law.append(1.0 * ad + 10.0 * (xd - z[0]) + 20.0 * (vd - z[1]))
    for m in range(delay + 1, 40):
        a, b = tr.samples[m], tr.samples[m + 1]
        ts = np.linspace(a, b, 7)[:-1]
        u = tr(ts) @ loop.force
        np.testing.assert_allclose(u, u_law[m - delay], rtol=1e-12, atol=1e-12)


def test_sampled_loop_converges_to_the_continuous_one_at_first_order():
    """Zero-order hold of the sampled PD: the trajectory (impact times and the state at the
    end) converges to the continuous loop's like dt. Where a sample falls relative to an
    impact changes the error constant (the measured velocity jumps), so the order is
    measured as the least-squares slope over two and a half decades of dt."""
    t_end = 1.5                                     # 3 impacts, the same sequence for all dt
    cont = simulate(pair_model((10.0, 20.0), "x2"), X0, (0.0, t_end))
    dts = 0.004 * 2.0 ** -np.arange(9)
    errs = []
    for dt in dts:
        tr = simulate(pair_model(discrete_pd(dt), "x2"), X0, (0.0, t_end))
        assert tr.n_impacts == cont.n_impacts == 3
        np.testing.assert_array_equal(tr.walls, cont.walls)
        e_state = np.abs(tr.mechanical(t_end) - cont.mechanical(t_end)).max()
        e_imp = np.abs(tr.impact_times - cont.impact_times).max()
        errs.append(max(e_state, e_imp))
    order = np.polyfit(np.log(dts), np.log(errs), 1)[0]
    assert errs[-1] < 1e-4
    assert abs(order - 1.0) < 0.15, order


ZERO = np.zeros((2, 2))


@pytest.mark.parametrize("measure,c", [("x2", [0.0, 1.0]), ("x1", [1.0, 0.0])])
def test_sampled_loop_against_an_independent_zoh_solve_ivp_loop(measure, c):
    tr = simulate(pair_model(discrete_pd(0.01), measure), X0, (0.0, 5.0), max_impacts=30)
    ref = naive_mechanical(PAIR.M, ZERO, ZERO, PAIR.B, [([1, -1], -0.75, 0.75, 0.5)], 10.0,
                           20.0, c, 1.0, 5.0, 1.0, X0, (0.0, 5.0), max_impacts=30, dt=0.01,
                           rtol=1e-13, atol=1e-14)
    k = min(tr.n_impacts, ref.impact_times.size)
    assert k >= 9
    np.testing.assert_array_equal(tr.walls[:k], ref.walls[:k])
    assert np.max(np.abs(tr.impact_times[:k] - ref.impact_times[:k])) < 1e-8


@pytest.mark.parametrize("k", [1e4, 1e6])
def test_compliant_contact_against_an_independent_solve_ivp_loop(k):
    con = kelvin_voigt(k, 0.2)
    ma = pair_model((10.0, 20.0), "x1", contact=con)
    tr = simulate(ma, X0, (0.0, 2.0))
    entries = np.array([e[0] for e in compliant_events(ma, tr)])
    ref = naive_mechanical(PAIR.M, ZERO, ZERO, PAIR.B,
                           [([1, -1], -0.75, 0.75, None, con.stiffness, con.damping)], 10.0,
                           20.0, [1.0, 0.0], 1.0, 5.0, 1.0, X0, (0.0, 2.0), max_impacts=1000,
                           rtol=1e-13, atol=1e-14)
    assert entries.size == ref.impact_times.size >= 40
    assert np.max(np.abs(entries - ref.impact_times)) < 1e-8


def kelvin_voigt(k, zeta):
    mstar = 0.1 / 1.1
    return Contact([1.0, -1.0], -0.75, 0.75, stiffness=k, damping=2 * zeta * math.sqrt(k * mstar))


def compliant_events(ma, tr):
    """(entry time, entry speed, exit speed) of each engagement of the compliant contact."""
    jt = tr.hybrid.jumps
    out, entry = [], None
    for t, src, g, pre in zip(jt.t, jt.source, jt.guard, jt.pre):
        kind = ma.guards[(src, g)].kind
        s_dot = pre[1] - pre[3]
        if kind == "enter":
            entry = (t, s_dot)
        elif kind == "leave" and entry is not None:
            out.append((entry[0], entry[1], s_dot))
            entry = None
    return out


def test_compliant_contact_converges_to_the_rigid_one_with_matching_restitution():
    zeta = 0.2
    e_eq = math.exp(-zeta * math.pi / math.sqrt(1 - zeta ** 2))
    assert kelvin_voigt(1e4, zeta).equivalent_restitution(PAIR.M) == pytest.approx(e_eq)
    rigid_c = Contact([1.0, -1.0], -0.75, 0.75, restitution=e_eq)
    t_end = 0.6
    rigid = simulate(pair_model((10.0, 20.0), contact=rigid_c), X0, (0.0, t_end))
    n = 4                                           # the first impacts (a rattling sequence)
    assert rigid.n_impacts >= n
    ks = [1e4, 1e5, 1e6, 1e7]
    err_t, err_e = [], []
    for k in ks:
        ma = pair_model((10.0, 20.0), contact=kelvin_voigt(k, zeta))
        tr = simulate(ma, X0, (0.0, t_end))
        ev = compliant_events(ma, tr)
        assert len(ev) >= n and tr.n_impacts == 0
        err_t.append(max(abs(ev[i][0] - rigid.impact_times[i]) for i in range(n)))
        err_e.append(max(abs(-ev[i][2] / ev[i][1] - e_eq) for i in range(n)))
    # contact duration ~ pi / omega_d ~ k^-1/2: both errors shrink like k^-1/2
    order_t = np.log10(np.array(err_t[:-1]) / np.array(err_t[1:]))
    order_e = np.log10(np.array(err_e[:-1]) / np.array(err_e[1:]))
    assert err_t[-1] < 1e-3 and err_e[-1] < 1e-2
    assert np.all(order_t > 0.35) and np.all(order_e > 0.35), (order_t, order_e)


@st.composite
def random_spec(draw):
    """A small, printable description of a random well-posed system (built by ``build``)."""
    return {
        "n": draw(st.integers(1, 5)), "seed": draw(st.integers(0, 2 ** 31 - 1)),
        "k_scale": draw(st.sampled_from([0.0, 1.0, 10.0])),
        "c_scale": draw(st.sampled_from([0.0, 0.3])),
        "contacts": draw(st.lists(st.tuples(st.sampled_from(["stop", "clearance", "normal"]),
                                            st.sampled_from(["both", "lo", "hi"]),
                                            st.booleans()), max_size=3)),
        "dt": draw(st.sampled_from([0.0, 0.05])),
        "delay": draw(st.integers(0, 1)),
        "lead": draw(st.booleans()),
    }


def build(spec):
    n, rng = spec["n"], np.random.default_rng(spec["seed"])
    A = rng.normal(size=(n, n))
    M = A @ A.T + 0.3 * np.eye(n)
    Kh = rng.normal(size=(n, n)) * spec["k_scale"]
    Ch = rng.normal(size=(n, n)) * spec["c_scale"]
    sysm = MechanicalSystem([f"q{i}" for i in range(n)], M, Ch @ Ch.T, Kh @ Kh.T,
                            rng.normal(size=n))
    contacts = []
    for i, (kind, sides, rigid) in enumerate(spec["contacts"]):
        w = np.zeros(n)
        if kind == "stop" or n == 1:
            w[rng.integers(n)] = 1.0
        elif kind == "clearance":
            a, b = rng.choice(n, 2, replace=False)
            w[a], w[b] = 1.0, -1.0
        else:
            w = rng.normal(size=n)
        lo = None if sides == "hi" else -float(rng.uniform(0.05, 1.0))
        hi = None if sides == "lo" else float(rng.uniform(0.05, 1.0))
        if rigid:
            contacts.append(Contact(w, lo, hi, restitution=float(rng.uniform(0, 1))))
        else:
            contacts.append(Contact(w, lo, hi, stiffness=float(10 ** rng.uniform(1, 4)),
                                    damping=float(rng.uniform(0, 5))))
    kp, kv = float(rng.uniform(0, 20)), float(rng.uniform(0, 10))
    dt = spec["dt"]
    if spec["lead"]:                               # a dynamic controller from err alone
        ctrl = ct.tf([kv, kp], [0.05, 1.0])
        ctrl = ctrl if dt == 0 else ct.c2d(ctrl, dt, "tustin")
    else:
        ctrl = (kp, kv) if dt == 0 else discrete_pd(dt, kp, kv)
    ref = Reference.sine(float(rng.uniform(0, 1)), float(rng.uniform(0.5, 10)),
                         float(rng.uniform(0, 1)))
    loop = mechanical_loop(sysm, ctrl, ref, f"q{rng.integers(n)}",
                           delay=spec["delay"] if dt else 0)
    x0 = np.zeros(2 * n)
    x0[1::2] = rng.normal(size=n)
    return build_automaton(loop, contacts), x0


ALLOWED = {"end_time", "jump_limit", "zeno", "nonfinite", "step_limit", "simultaneous_contact",
           "diverged"}


# HYBRIDPD_SWEEP_EXAMPLES=400 for a longer sweep
@settings(max_examples=int(os.environ.get("HYBRIDPD_SWEEP_EXAMPLES", "40")), deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(random_spec())
def test_random_systems_never_hang_crash_or_violate_a_contact(spec):
    ma, x0 = build(spec)
    tr = simulate(ma, x0, (0.0, 3.0), max_impacts=3000, max_steps=300_000)
    assert tr.termination in ALLOWED
    assert tr.t_final <= 3.0
    if tr.termination == "nonfinite":
        return
    ts = np.linspace(0.0, tr.t_final, 2001)
    for a, b, _ in tr.zeno_tails:                  # documented exception (simulate docs)
        ts = ts[(ts < a) | (ts > b)]
    jt = tr.hybrid.jumps
    # after the last jump at each instant (the states between jumps at one instant, e.g. a
    # projection onto one contact and the impact it causes on another, are intermediate)
    last = np.flatnonzero(np.r_[np.diff(jt.t) > 0, True]) if len(jt) else np.arange(0)
    z = np.vstack([tr(ts), jt.post[last]])
    z = z[np.all(np.isfinite(z), axis=1)]
    q = z[:, ma.layout["q"]]
    q_scale = np.abs(q).max() if q.size else 0.0
    for c in ma.contacts:
        if not c.rigid:
            continue
        gap = q @ c.normal
        # the documented tolerance (simulate's module docstring)
        tol = 1e-9 * (1.0 + max(abs(c.lo or 0.0), abs(c.hi or 0.0))) \
            + 1e-12 * np.abs(c.normal).sum() * q_scale
        if c.hi is not None:
            assert gap.max() <= c.hi + tol
        if c.lo is not None:
            assert gap.min() >= c.lo - tol
