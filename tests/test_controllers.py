"""Several controllers in one mechanical loop: the loop written out by hand (continuous) and
an exact sampled-data loop written by hand (two sampling periods), model files with repeated
[[controller]] tables and their errors, keys that set several entries (patterns and lists),
and the shipped three-joint arm."""
import copy
import json
import math
from pathlib import Path

import control as ct
import numpy as np
import pytest
from scipy.linalg import expm

from hybridpd.cli import main
from hybridpd.loop import Controller
from hybridpd.mechanics import (
    ControlChannel,
    MechanicalSystem,
    Reference,
    build_automaton,
    mechanical_loop,
    simulate,
)
from hybridpd.mechanics.loop import common_period
from hybridpd.mechanics.modelfile import load_model, model_from_dict
from hybridpd.mechanics.params import (
    ModelTemplate,
    check_path,
    resolve_path,
    set_values,
)

MODELS = Path(__file__).resolve().parents[1] / "examples" / "models"

# a 3-DOF plant with a full mass matrix, damping and stiffness
M3 = np.array([[2.0, 0.3, 0.0], [0.3, 1.0, 0.1], [0.0, 0.1, 0.5]])
C3 = np.array([[0.2, -0.1, 0.0], [-0.1, 0.3, 0.0], [0.0, 0.0, 0.1]])
K3 = np.array([[5.0, -2.0, 0.0], [-2.0, 4.0, -1.0], [0.0, -1.0, 1.0]])
A0 = np.array([1.0, 0.0, -0.5])            # where controller 0 acts


def _three_channel_loop():
    """Controller 0: PD on q_a along A0, tracking a sine with feed-forward 0.7; controller 1:
    a first-order controller from err alone on b + c, acting on b, tracking the same sine
    (no feed-forward, so it shares the exosystem); controller 2: a python-control system of
    [err, err_dot] with position of c and velocity of b, acting on c, tracking a set-point."""
    sysm = MechanicalSystem(["a", "b", "c"], M=M3, C=C3, K=K3)
    sine = Reference.sine(0.4, 2.0, feedforward=0.7)
    ch = [ControlChannel((8.0, 1.5), "a", actuate=A0, reference=sine),
          ControlChannel(Controller([[-3.0]], [[1.0]], [[6.0]], [[2.0]]), [0.0, 1.0, 1.0],
                         actuate="b", reference=Reference.sine(0.4, 2.0)),
          ControlChannel(ct.ss([[-1.0]], [[0.5, 0.2]], [[3.0]], [[4.0, 0.5]]), "c",
                         actuate="c", reference=Reference.constant(0.25),
                         measure_velocity="b")]
    return mechanical_loop(sysm, ch)


def _hand_A():
    """The flow of _three_channel_loop written out from the equations, state
    [a, a', b, b', c, c', pc, ps, r, x1, x2]."""
    N, w = 11, 2.0
    qa, va, qb, vb, qc, vc, pc, ps, r, x1, x2 = np.eye(N)
    xd, vd, ad = pc, -w * ps, -w * w * pc
    u0 = 0.7 * ad + 8.0 * (xd - qa) + 1.5 * (vd - va)
    e1 = xd - (qb + qc)
    u1 = 6.0 * x1 + 2.0 * e1
    e2, e2dot = r - qc, 0.0 - vb
    u2 = 3.0 * x2 + 4.0 * e2 + 0.5 * e2dot
    Q, V = np.array([qa, qb, qc]), np.array([va, vb, vc])
    force = np.outer(A0, u0) + np.outer([0, 1, 0], u1) + np.outer([0, 0, 1], u2)
    acc = np.linalg.solve(M3, -K3 @ Q - C3 @ V + force)
    A = np.zeros((N, N))
    A[[0, 2, 4]] = V
    A[[1, 3, 5]] = acc
    A[6], A[7] = -w * ps, w * pc
    A[9] = -3.0 * x1 + e1
    A[10] = -1.0 * x2 + 0.5 * e2 + 0.2 * e2dot
    return A, np.array([u0, u1, u2])


def test_three_continuous_controllers_against_the_flow_written_by_hand():
    loop = _three_channel_loop()
    assert loop.state_names == ("a", "a_dot", "b", "b_dot", "c", "c_dot", "k0.pc", "k0.ps",
                                "k2.r", "k1.c1", "k2.c1")
    A, forces = _hand_A()
    np.testing.assert_allclose(loop.A, A, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(loop.forces, forces, rtol=1e-13, atol=1e-13)
    np.testing.assert_array_equal(loop.layout["exo"], [6, 7, 8])
    np.testing.assert_array_equal(loop.layout["ctrl"], [9, 10])
    assert loop.layout["clock"] == -1 and loop.clocks == () and not loop.sampled
    assert loop.reference_period == pytest.approx(math.pi, rel=1e-15)
    assert [r.feedforward for r in loop.references] == [0.7, None, None]

    # a contact-free run against the matrix exponential of the hand-written flow
    ma = build_automaton(loop, [])
    t0, q0, v0 = 0.3, np.array([0.1, -0.2, 0.3]), np.array([0.0, 0.5, -0.1])
    z0 = np.zeros(11)
    z0[[0, 2, 4]], z0[[1, 3, 5]] = q0, v0
    z0[6:9] = 0.4 * math.cos(2.0 * t0), 0.4 * math.sin(2.0 * t0), 0.25
    z0[9:] = [0.05, -0.02]
    tr = simulate(ma, np.ravel(np.column_stack([q0, v0])), (t0, 2.5),
                  controller_state=[0.05, -0.02])
    for t in (0.3, 0.71, 1.6, 2.5):
        np.testing.assert_allclose(tr(t), expm(A * (t - t0)) @ z0, rtol=1e-10, atol=1e-11)


# ---------------------------------------------------------------------------------------------
# two sampled controllers with different periods

M2 = np.array([[1.0, 0.2], [0.2, 0.5]])
C2 = np.array([[0.1, 0.0], [0.0, 0.05]])
K2 = np.array([[3.0, -1.0], [-1.0, 1.0]])
DT0, DT1 = 0.01, 0.025                    # common period 0.05
W0, W1 = 2.0 * math.pi, 3.0
C1 = np.array([0.5, 1.0])                 # controller 1 measures and acts along this


def _sampled_loop():
    sysm = MechanicalSystem(["x", "y"], M=M2, C=C2, K=K2)
    ch = [ControlChannel(ct.ss([], [], [], [[12.0, 2.0]], DT0), "x", actuate="x",
                         reference=Reference.sine(0.3, W0, feedforward=0.5)),
          ControlChannel(Controller([[0.9]], [[0.05]], [[4.0]], [[1.5]], DT1), C1,
                         actuate=C1, reference=Reference.sine(0.2, W1), delay=1)]
    return mechanical_loop(sysm, ch)


def _hand_sampled_run(t0, x0, times):
    """Exact flows between the samples and the controllers' difference equations, written
    out here: the mechanical state at ``times`` (sorted, none a sampling instant), and the
    state of controller 1, its hold register and both held forces at the last one."""
    Ap = np.zeros((4, 4))
    Ap[0, 1] = Ap[2, 3] = 1.0
    Minv = np.linalg.inv(M2)
    Ap[1::2, 0::2], Ap[1::2, 1::2] = -Minv @ K2, -Minv @ C2
    G = np.zeros((10, 10))                # [plant 4, exo0 2, exo1 2, u0, u1]
    G[:4, :4] = Ap
    G[4, 5], G[5, 4], G[6, 7], G[7, 6] = -W0, W0, -W1, W1
    G[1::2, 8][:2] = Minv @ [1.0, 0.0]
    G[1::2, 9][:2] = Minv @ C1
    w = np.zeros(10)
    w[:4] = x0
    w[4:8] = (0.3 * math.cos(W0 * t0), 0.3 * math.sin(W0 * t0), 0.2 * math.cos(W1 * t0),
              0.2 * math.sin(W1 * t0))
    c1, h0, h1 = 0.0, 0.0, 0.0
    # instants in units of 5 ms: controller 0 every 2, controller 1 every 5, both at 0
    unit = 0.005
    t, out = t0, []
    for m in range(1 + int((times[-1] - t0) / unit)):
        ts = t0 + m * unit
        for tq in [tq for tq in times if t <= tq < ts]:
            out.append(expm(G * (tq - t)) @ w)
        w = expm(G * (ts - t)) @ w
        t = ts
        q, v = w[0:4:2], w[1:4:2]
        if m % 2 == 0:
            xd, vd, ad = w[4], -W0 * w[5], -W0 * W0 * w[4]
            w[8] = 0.5 * ad + 12.0 * (xd - q[0]) + 2.0 * (vd - v[0])
        if m % 5 == 0:
            err = w[6] - C1 @ q
            u = 4.0 * c1 + 1.5 * err
            c1 = 0.9 * c1 + 0.05 * err
            h0, h1 = u, h0
            w[9] = h1
    for tq in [tq for tq in times if tq >= t]:
        out.append(expm(G * (tq - t)) @ w)
    return np.array(out), (c1, h0, h1)


def test_two_sampled_controllers_with_their_own_periods_against_a_hand_written_loop():
    loop = _sampled_loop()
    assert loop.state_names == ("x", "x_dot", "y", "y_dot", "k0.pc", "k0.ps", "k1.pc",
                                "k1.ps", "k1.c1", "k0.h0", "k0.s", "k1.h0", "k1.h1", "k1.s")
    assert loop.clocks == ((10, DT0), (13, DT1))
    np.testing.assert_allclose(loop.dt, 0.05, rtol=1e-12, atol=0)   # their common period
    np.testing.assert_array_equal(loop.layout["hold"], [9, 11, 12])
    assert loop.layout["clock"] == 10
    ma = build_automaton(loop, [])
    assert {g.name for g in ma.automaton.modes[0].guards} == {"sample0", "sample1"}
    assert ma.guards[("free", "sample1")].controller == 1
    t0, x0 = 0.2, np.array([0.1, 0.0, -0.05, 0.3])
    times = [0.2137, 0.5031, 0.7702, 1.3049]
    tr = simulate(ma, x0, (t0, times[-1]))
    ref, (c1, h0, h1) = _hand_sampled_run(t0, x0, times)
    for t, w in zip(times, ref):
        np.testing.assert_allclose(tr.mechanical(t), w[:4], rtol=1e-10, atol=1e-11)
        np.testing.assert_allclose(tr(t)[[9, 12]], w[8:10], rtol=1e-10, atol=1e-11)
    z = tr(times[-1])
    np.testing.assert_allclose(z[[8, 11, 12]], [c1, h0, h1], rtol=1e-10, atol=1e-11)
    # the samples of each: at t0 + k dt, counted by guard, the common ones taken by both
    jt = tr.hybrid.jumps
    for g, dt in (("sample0", DT0), ("sample1", DT1)):
        ts = np.array([jt.t[i] for i in range(len(jt.t)) if jt.guard[i] == g])
        k = np.arange(1, ts.size + 1)
        assert ts.size == int((times[-1] - t0) / dt + 1e-9)
        np.testing.assert_allclose(ts, t0 + k * dt, rtol=0, atol=1e-13)


def test_a_continuous_and_a_sampled_controller_and_the_single_sample_guard():
    """One sampled controller among two keeps the guard name 'sample'; its GuardInfo names
    the controller it samples, and the continuous one is written into the flow."""
    sysm = MechanicalSystem(["x", "y"], M=M2, K=K2)
    ref = Reference.sine(0.3, W0)
    loop = mechanical_loop(sysm, [ControlChannel((5.0, 1.0), "y", actuate="y"),
                                  ControlChannel(ct.ss([], [], [], [[12.0, 2.0]], DT0), "x",
                                                 actuate="x")], ref)
    assert loop.state_names == ("x", "x_dot", "y", "y_dot", "pc", "ps", "k1.h0", "k1.s")
    assert loop.dt == DT0 and loop.clocks == ((7, DT0),)
    ma = build_automaton(loop, [])
    assert [g.name for g in ma.automaton.modes[0].guards] == ["sample"]
    info = ma.guards[("free", "sample")]
    assert (info.kind, info.controller) == ("sample", 1)
    # continuous force row by hand: u = 5 (pc - y) + 1 (-W0 ps - y')
    np.testing.assert_allclose(loop.forces[0], [0, 0, -5, -1, 5, -W0, 0, 0], rtol=0,
                               atol=1e-15)


def test_the_old_signature_is_the_one_controller_channel():
    sysm = MechanicalSystem(["x1", "x2"], M=[[0.1, 0], [0, 1.0]], B=[0, 1])
    ref = Reference.sine(1.0, 5.0, 1.0)
    for ctrl, delay in (((10.0, 20.0), 0), (ct.ss([[0.5]], [[1.0, 0]], [[2.0]], [[10, 3]],
                                                  0.01), 1)):
        old = mechanical_loop(sysm, ctrl, ref, "x2", delay)
        new = mechanical_loop(sysm, [ControlChannel(ctrl, "x2", actuate=[0, 1.0],
                                                    delay=delay)], ref)
        assert old.state_names == new.state_names
        np.testing.assert_array_equal(old.A, new.A)
        np.testing.assert_array_equal(old.force, new.force)
        assert old.clocks == new.clocks and old.layout["clock"] == new.layout["clock"]
    assert "h0" in old.state_names and "s" in old.state_names


def test_channel_and_loop_errors_name_the_parameter():
    sysm = MechanicalSystem(["x", "y"], M=M2)
    ref = Reference.constant(0.0)
    with pytest.raises(ValueError, match=r"^controller\[1\]\.actuate is required"):
        mechanical_loop(sysm, [ControlChannel((1, 1), "x", actuate="x"),
                               ControlChannel((1, 1), "y")], ref)
    with pytest.raises(ValueError, match=r"^controller\[0\]\.measure: all 2 weights are zero"):
        mechanical_loop(sysm, [ControlChannel((1, 1), [0, 0], actuate="x"),
                               ControlChannel((1, 1), "y", actuate="y")], ref)
    with pytest.raises(ValueError, match=r"^controller\.actuate: unknown dof 'z'"):
        mechanical_loop(sysm, [ControlChannel((1, 1), "x", actuate="z")], ref)
    with pytest.raises(ValueError, match="reference is required"):
        mechanical_loop(sysm, [ControlChannel((1, 1), "x", actuate="x")])
    with pytest.raises(ValueError, match="belong to each ControlChannel"):
        mechanical_loop(sysm, [ControlChannel((1, 1), "x", actuate="x")], ref, "x")
    with pytest.raises(ValueError, match="delay"):
        ControlChannel((1, 1), "x", delay=1)
    with pytest.raises(ValueError, match="interconnect"):
        mechanical_loop(sysm, [ControlChannel((1, 1), "x", actuate="x"),
                               ControlChannel((1, 1), "y", actuate="y")], ref,
                        method="interconnect")
    with pytest.raises(ValueError, match="no input direction B"):
        _ = sysm.Minv_B
    with pytest.raises(ValueError, match="no input direction B: give MechanicalSystem"):
        mechanical_loop(sysm, (1.0, 1.0), ref, "x")          # the one-controller signature


def test_common_and_reference_periods():
    np.testing.assert_allclose(common_period([0.01, 0.025]), 0.05, rtol=1e-12, atol=0)
    np.testing.assert_allclose(common_period([1.0, 1.0 + 1e-12]), 1.0, rtol=1e-11, atol=0)
    assert common_period([1.0, math.sqrt(2.0)]) is None
    assert common_period([1.0, 66.0 / 65.0]) is None     # denominator above 64
    sysm = MechanicalSystem(["x", "y"], M=M2)

    def loop(*refs):
        return mechanical_loop(sysm, [ControlChannel((1, 1), "x", actuate="x", reference=r)
                                      for r in refs])

    assert loop(Reference.constant(1.0)).reference_period is None
    T = loop(Reference.sine(1, 2.0), Reference.sum_of_sines([1, 1], [3.0, 6.0])).reference_period
    np.testing.assert_allclose(T, 2 * math.pi, rtol=1e-12, atol=0)
    with pytest.raises(ValueError, match="no common period"):
        _ = loop(Reference.sine(1, 1.0), Reference.sine(1, math.sqrt(2.0))).reference_period
    # two sampled controllers without a common period: dt is NaN, each is in clocks
    lp = mechanical_loop(sysm, [ControlChannel(ct.ss([], [], [], [[1.0, 0.0]], 0.01), "x",
                                               actuate="x"),
                                ControlChannel(ct.ss([], [], [], [[1.0, 0.0]], 0.01 * math.pi),
                                               "y", actuate="y")], Reference.constant(0.0))
    assert math.isnan(lp.dt) and lp.sampled and len(lp.clocks) == 2


# ---------------------------------------------------------------------------------------------
# model files

def _two_controller_dict():
    return {
        "system": {"dofs": ["x", "y"], "mass": M2.tolist(), "stiffness": K2.tolist()},
        "contact": [{"between": ["x", "y"], "lo": -0.5, "hi": 0.5, "restitution": 0.5}],
        "controller": [
            {"type": "pd", "kp": 12.0, "kv": 2.0, "measure": "x", "actuate": "x", "dt": DT0},
            {"type": "pid", "kp": 3.0, "ki": 1.0, "kd": 0.2, "filter_time": 0.01,
             "measure": [0.5, 1.0], "actuate": [0.5, 1.0], "dt": DT1, "delay": 1,
             "reference": {"type": "sine", "amplitude": 0.2, "omega": W1}}],
        "reference": {"type": "sine", "amplitude": 0.3, "omega": W0,
                      "feedforward_mass": 0.5},
    }


def test_model_file_controllers_match_the_api():
    d = _two_controller_dict()
    m = model_from_dict(copy.deepcopy(d))
    loop = m.automaton.loop
    assert loop.references[0].feedforward == 0.5 and loop.references[1].omegas == (W1,)
    assert loop.reference is loop.references[0]          # the file's [reference]
    assert loop.clocks == ((11, DT0), (14, DT1))
    assert loop.state_names[8:10] == ("k1.c1", "k1.c2")
    # the PID's exact zero-order-hold discretisation, written out: integral and filter
    c = loop.channels[1].controller
    a = math.exp(-DT1 / 0.01)
    np.testing.assert_allclose(c.A, np.diag([1.0, a]), rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(c.B, [[DT1, 0.0], [0.0, 1.0 - a]], rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(c.C, [[1.0, 0.2]], rtol=0, atol=0)
    np.testing.assert_allclose(c.D, [[3.0, 0.0]], rtol=0, atol=0)
    tr = m.simulate(0.99)
    assert tr.termination == "end_time" and tr.samples.size == 99 + 39
    # without a [reference] table the loop's reference is the first controller's own
    d2 = copy.deepcopy(d)
    d2["controller"][0]["reference"] = d2.pop("reference")
    loop2 = model_from_dict(d2).automaton.loop
    assert loop2.reference.omegas == (W0,) and loop2.reference.feedforward == 0.5
    np.testing.assert_array_equal(loop2.A, loop.A)


def _del(key):
    return lambda t: t.pop(key)


BAD = [
    (lambda d: d["controller"][1].update(actuate=[0.0, 0.0]), "controller.1.actuate",
     "all 2 weights are zero"),
    (lambda d: d["controller"][0].update(measure=[0.0, 0.0]), "controller.0.measure",
     "all 2 weights are zero"),
    (lambda d: d["controller"][1].pop("actuate"), "controller.1.actuate", "required"),
    (lambda d: d["system"].update(input=[1.0, 0.0]), "system.input", "not used"),
    (lambda d: d["controller"][0].update(actuate="z"), "controller.0.actuate", "unknown dof"),
    (lambda d: d["controller"][1].update(actuate=[1.0]), "controller.1.actuate", "shape"),
    (lambda d: d["controller"][1].update(kq=1.0), "controller.1.kq", "unknown key"),
    (lambda d: d["controller"][0].update(ki=1.0), "controller.0.ki", "not a key of type"),
    (lambda d: d["controller"][1].update(dt=0.0), "controller.1.dt", "must be > 0"),
    (lambda d: d["controller"][0].update(delay=2, dt=None) or d["controller"][0].pop("dt"),
     "controller.0.delay", "needs a discrete-time"),
    (lambda d: d["controller"][1]["reference"].pop("omega"), "controller.1.reference.omega",
     "required"),
    (lambda d: d["controller"][1]["reference"].update(amplitude=-1.0),
     "controller.1.reference.amplitude", ">= 0"),
    (lambda d: d["controller"][0].update(type="lqr"), "controller.0.type", "must be one of"),
    (lambda d: d["controller"][1].update(filter_time=-1.0), "controller.1.filter_time",
     ">= 0"),
    (lambda d: d.update(controller=[]), "controller", "non-empty array"),
]


@pytest.mark.parametrize("edit,key,what", BAD, ids=[b[1] + ":" + b[2] for b in BAD])
def test_model_file_errors_name_the_key(edit, key, what):
    d = _two_controller_dict()
    edit(d)
    with pytest.raises(ValueError, match=r"^" + key.replace(".", r"\.") + r"\b.*" + what):
        model_from_dict(d)


def test_single_controller_table_keeps_its_rules():
    d = _two_controller_dict()
    single = dict(d["controller"][0])
    single.pop("actuate")
    d["controller"] = single
    with pytest.raises(ValueError, match=r"^system\.input: required"):
        model_from_dict(copy.deepcopy(d))
    d["system"]["input"] = [1.0, 0.0]
    loop = model_from_dict(copy.deepcopy(d)).automaton.loop
    assert loop.state_names[-2:] == ("h0", "s")
    assert [g.name for g in build_automaton(loop, []).automaton.modes[0].guards] == ["sample"]
    d["controller"]["actuate"] = "x"        # both: input would act nowhere
    with pytest.raises(ValueError, match=r"^system\.input: not used"):
        model_from_dict(copy.deepcopy(d))
    d["system"].pop("input")                # a single table may say where it acts itself
    loop2 = model_from_dict(d).automaton.loop
    np.testing.assert_array_equal(loop2.A, loop.A)


# ---------------------------------------------------------------------------------------------
# keys that set several entries

def test_patterns_and_lists_set_every_matched_entry():
    d = _two_controller_dict()
    assert resolve_path(d, "controller.*.kp") == ("controller.0.kp", "controller.1.kp")
    assert resolve_path(d, "controller.1.kd,controller.0.kv") == ("controller.0.kv",
                                                                  "controller.1.kd")
    assert resolve_path(d, "controller.*.reference.omega") == ("controller.1.reference.omega",)
    assert resolve_path(d, "system.stiffness.*.1") == ("system.stiffness.0.1",
                                                       "system.stiffness.1.1")
    assert check_path(d, "controller.*.kp") == "controller.*.kp"
    out = set_values(d, {"controller.*.kp": 7.0, "controller.0.kv, controller.1.kd": 0.5})
    assert [c["kp"] for c in out["controller"]] == [7.0, 7.0]
    assert (out["controller"][0]["kv"], out["controller"][1]["kd"]) == (0.5, 0.5)
    assert d["controller"][0]["kp"] == 12.0                   # never modified
    for bad, msg in (("controller.*.kq", "matches no numeric entry.*controller.0.kp"),
                     ("controller.0.kp,controller.7.kp", "'controller.7.kp' is no numeric"),
                     ("controller.k*", "one whole path segment"),
                     ("controller.0.kp,,controller.1.kp", "empty path")):
        with pytest.raises(ValueError, match=msg):
            check_path(d, bad)
    with pytest.raises(ValueError, match="controller.0.kp is set by both"):
        set_values(d, {"controller.*.kp": 1.0, "controller.0.kp": 2.0})
    t = ModelTemplate(d)
    with pytest.raises(ValueError, match="different values"):
        t.value("controller.*.kp")
    assert ModelTemplate(out).value("controller.*.kp") == 7.0
    loop = t.model({"controller.*.kp": 20.0}).automaton.loop
    h0 = loop.state_names.index("k0.h0")
    R0 = loop.channels[0].sample_reset[0]
    assert R0[h0, 0] == -20.0                      # the held force's row: -kp q_x


PAIR_TWO_PD = """
[system]
dofs = ["x1", "x2"]
masses = [0.1, 1.0]

[[contact]]
between = ["x1", "x2"]
lo = -0.75
hi = 0.75
restitution = 0.5

[[controller]]                     # two PDs on x2: their gains add up
type = "pd"
kp = {kp0}
kv = {kv0}
measure = "x2"
actuate = "x2"

[[controller]]
type = "pd"
kp = {kp1}
kv = {kv1}
measure = "x2"
actuate = "x2"
[controller.reference]             # the same sine (shared exosystem), no feed-forward
type = "sine"
amplitude = {xm!r}
omega = 5.0

[reference]
type = "sine"
amplitude = {xm!r}
omega = 5.0
feedforward_mass = 1.0

[initial]
q = [0.3, 0.0]
v = [0.5, 0.0]
"""


def _pair_orbit():
    from hybridpd.model import ImpactPair, PDGains
    from hybridpd.pair.orbits import symmetric_orbit

    return symmetric_orbit(ImpactPair(mu=0.1, e=0.5, L=0.75), PDGains(10, 20), 5.0)


def test_cli_set_with_a_pattern_and_a_region_axis_named_by_its_key(tmp_path, capsys):
    """Two PDs on the pair's x2 add up: --set controller.*.kv 10 gives kv = 20 in all, whose
    symmetric orbit the closed forms know; region axes given as a pattern and a list set both
    controllers, and the dataset's coordinates carry the keys as given."""
    orb = _pair_orbit()
    f = tmp_path / "two_pd.toml"
    f.write_text(PAIR_TWO_PD.format(kp0=4.0, kp1=6.0, kv0=3.0, kv1=7.0,
                                    xm=orb.xm))
    loop = load_model(f).automaton.loop
    assert loop.state_names == ("x1", "x1_dot", "x2", "x2_dot", "pc", "ps")
    assert main(["orbit", "--model", str(f), "--set", "controller.*.kv", "10", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["exists"]
    np.testing.assert_allclose(d["spectral_radius"], orb.spectral_radius, rtol=1e-8, atol=0)

    from _regions import model_region_map

    from hybridpd.sweeps.regions import load_region_map

    rm = model_region_map(f, ("controller.*.kp", 5.0, 6.0, 2),
                          ("controller.0.kv,controller.1.kv", 10.0, 11.0, 2), progress=False)
    assert (rm.x_name, rm.y_name) == ("controller.*.kp", "controller.0.kv,controller.1.kv")
    assert rm.exists[0, 0, 0]
    np.testing.assert_allclose(rm.spectral_radius[0, 0, 0], orb.spectral_radius, rtol=1e-8,
                               atol=0)
    out = tmp_path / "map.nc"
    rm.save(out)
    ds = load_region_map(out).to_dataset()
    assert "controller.*.kp" in ds.coords and "controller.0.kv,controller.1.kv" in ds.coords
    with pytest.raises(ValueError, match="must set different entries"):
        model_region_map(f, ("controller.*.kp", 5.0, 6.0, 2),
                         ("controller.1.kp", 5.0, 6.0, 2), progress=False)


# ---------------------------------------------------------------------------------------------
# the shipped three-joint arm

def test_arm_with_three_sampled_pd_loads_and_simulates():
    m = load_model(MODELS / "arm3.toml")
    loop = m.automaton.loop
    names = loop.state_names
    assert len(set(names)) == len(names) and len(loop.channels) == 3
    assert loop.clocks == tuple((names.index(f"k{i}.s"), 0.001) for i in range(3))
    assert loop.reference_period == pytest.approx(1.0, rel=1e-12)
    assert all(r.omegas == (2 * math.pi,) for r in loop.references)
    assert m.system.B is None
    t_end = 12.0
    tr = m.simulate(t_end)
    assert tr.termination == "end_time"
    # it settles into a periodic motion (period 1 s) with impacts on every backlash
    counts = [np.bincount(tr.contacts[(tr.impact_times >= k) & (tr.impact_times < k + 1)],
                          minlength=3) for k in (10, 11)]
    assert np.all(counts[0] > 0)
    np.testing.assert_array_equal(counts[0], counts[1])
    np.testing.assert_allclose(tr.mechanical(11.5), tr.mechanical(10.5), rtol=0, atol=1e-7)
    # the held torque of each joint after each sample is its PD law at the sample, from the
    # file's numbers: u = ff xd'' + kp (xd - q_motor) + kv (xd' - v_motor)
    law = [(1.41, 40.0, 10.0, 0.5), (1.01, 30.0, 8.0, 0.4), (0.56, 20.0, 5.0, 0.3)]
    jt = tr.hybrid.jumps
    for i, (ff, kp, kv, amp) in enumerate(law):
        rows = [j for j in range(len(jt.t)) if jt.guard[j] == f"sample{i}"]
        assert len(rows) == round(t_end / 1e-3)
        t = np.array([jt.t[j] for j in rows])
        z = np.array([jt.post[j] for j in rows])
        w = 2 * math.pi
        xd, vd, ad = amp * np.cos(w * t), -amp * w * np.sin(w * t), -amp * w * w * np.cos(w * t)
        q, v = z[:, 6 * i], z[:, 6 * i + 1]
        u = ff * ad + kp * (xd - q) + kv * (vd - v)
        np.testing.assert_allclose(z[:, names.index(f"k{i}.h0")], u, rtol=1e-9, atol=1e-9)
