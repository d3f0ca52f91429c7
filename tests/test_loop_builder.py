"""One loop builder, one Reference, one controller normalisation for the pair and every
mechanical model: the directly written matrices against python-control's interconnection."""
import control as ct
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hybridpd as hp
from hybridpd.loop import Controller, as_controller, closed_loop
from hybridpd.mechanics import MechanicalSystem, mechanical_loop
from hybridpd.mechanics import Reference as MechReference
from hybridpd.model import ImpactPair, PDGains, Reference, sine_reference

TOL = dict(rtol=1e-12, atol=1e-12)   # two constructions of the same matrices


def random_controller(rng, n_inputs, k, dt=0.0):
    A = rng.normal(size=(k, k)) - 2 * np.eye(k)
    if dt:
        A = 0.5 * A / max(1.0, np.abs(np.linalg.eigvals(A)).max())
    return ct.ss(A, rng.normal(size=(k, n_inputs)), rng.normal(size=(1, k)),
                 rng.normal(size=(1, n_inputs)), dt)


def random_system(rng, n):
    L = rng.normal(size=(n, n))
    M = L @ L.T + n * np.eye(n)
    K = np.diag(rng.uniform(0, 5, n))
    C = np.diag(rng.uniform(0, 0.5, n))
    return MechanicalSystem([f"q{i}" for i in range(n)], M=M, K=K, C=C, B=rng.normal(size=n))


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 4), k=st.integers(0, 3),
       n_inputs=st.sampled_from([1, 2]), n_sines=st.integers(0, 3),
       offset=st.sampled_from([0.0, 0.4]))
def test_mechanical_loop_written_out_equals_interconnect(seed, n, k, n_inputs, n_sines, offset):
    rng = np.random.default_rng(seed)
    sysm = random_system(rng, n)
    ref = Reference(tuple(rng.uniform(0, 2, n_sines)), tuple(rng.uniform(0.5, 8, n_sines)),
                    offset, feedforward=float(rng.uniform(0, 2)))
    ctrl = random_controller(rng, n_inputs, k) if k or n_inputs == 1 else \
        (float(rng.normal()), float(rng.normal()))
    c, cv = rng.normal(size=n), rng.normal(size=n)
    a = mechanical_loop(sysm, ctrl, ref, c, measure_velocity=cv)
    b = mechanical_loop(sysm, ctrl, ref, c, measure_velocity=cv, method="interconnect")
    np.testing.assert_allclose(a.A, b.A, **TOL)
    np.testing.assert_allclose(a.force, b.force, **TOL)
    assert a.state_names == b.state_names
    np.testing.assert_allclose(np.asarray(a.sys.A), a.A, **TOL)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), k=st.integers(0, 3), n_inputs=st.sampled_from([1, 2]),
       case=st.sampled_from(["collocated", "noncollocated"]))
def test_pair_loop_written_out_equals_interconnect_for_lti_controllers(seed, k, n_inputs, case):
    rng = np.random.default_rng(seed)
    if k == 0 and n_inputs == 2:
        ctrl = PDGains(*rng.uniform(0.1, 50, 2))
    else:
        ctrl = random_controller(rng, n_inputs, k)
    pair, ref = ImpactPair(0.1, 0.5, 0.75, float(rng.uniform(0.5, 3))), Reference(1.0, 5.0)
    a = closed_loop(pair, ctrl, ref, case)
    b = closed_loop(pair, ctrl, ref, case, method="interconnect")
    np.testing.assert_allclose(a.A, b.A, **TOL)
    np.testing.assert_allclose(a.force, b.force, **TOL)
    assert a.state_names == b.state_names


def test_pair_as_mechanical_model_has_the_same_loop():
    """The pair's loop and the general builder on the pair written as a mechanical model."""
    pair, ref = ImpactPair(0.1, 0.5, 0.75, 2.0), Reference(1.0, 5.0)
    sysm = MechanicalSystem(["x1", "x2"], M=[[0.2, 0.0], [0.0, 2.0]], B=[0.0, 1.0])
    for case, dof in (("collocated", "x2"), ("noncollocated", "x1")):
        for ctrl in ((10.0, 20.0), ct.tf([20, 10], [1e-3, 1])):
            a = closed_loop(pair, ctrl, ref, case)
            b = mechanical_loop(sysm, ctrl, Reference(1.0, 5.0, feedforward=2.0), dof)
            np.testing.assert_allclose(a.A, b.A, **TOL)
            np.testing.assert_allclose(a.force, b.force, **TOL)


def test_one_reference_class():
    assert hp.Reference is Reference is MechReference
    r = Reference.sine(1.0, 5.0, 1.0)
    assert r == Reference(1.0, 5.0, 0.0, 1.0) and r.is_sine
    assert Reference.sum_of_sines([1.0], [5.0]) == Reference(1.0, 5.0)
    s = Reference((1.0, 0.5), (2.0, 7.0), offset=0.3)
    assert s.exo_names == ("pc1", "ps1", "pc2", "ps2", "r") and not s.is_sine
    t = np.linspace(0.0, 2.0, 7)
    xd, vd, ad = s(t)
    np.testing.assert_allclose(xd, 0.3 + np.cos(2 * t) + 0.5 * np.cos(7 * t), **TOL)
    np.testing.assert_allclose(vd, -2 * np.sin(2 * t) - 3.5 * np.sin(7 * t), **TOL)
    np.testing.assert_allclose(ad, -4 * np.cos(2 * t) - 24.5 * np.cos(7 * t), **TOL)
    # the exosystem generates the signals: d/dt of the state equals A times the state
    A, _ = s.exo_matrices()
    h = 1e-6
    fd = (s.exo_state(0.7 + h) - s.exo_state(0.7 - h)) / (2 * h)
    np.testing.assert_allclose(fd, A @ s.exo_state(0.7), rtol=1e-8, atol=1e-8)


def test_reference_validation_names_the_parameter():
    with pytest.raises(ValueError, match="xm"):
        Reference(-1.0, 5.0)
    with pytest.raises(ValueError, match="omega"):
        Reference((1.0, 2.0), (5.0, 0.0))
    with pytest.raises(ValueError, match="same length"):
        Reference((1.0, 2.0), (5.0,))
    with pytest.raises(ValueError, match="feedforward"):
        Reference(1.0, 5.0, feedforward=-1.0)
    with pytest.raises(ValueError, match="omega"):
        _ = Reference((1.0, 2.0), (5.0, 6.0)).period
    pair = ImpactPair(0.1, 0.5, 0.75)
    with pytest.raises(ValueError, match="one sine"):
        closed_loop(pair, (10, 20), Reference(1.0, 5.0, offset=0.2))
    with pytest.raises(ValueError, match="feedforward"):
        closed_loop(pair, (10, 20), Reference(1.0, 5.0, feedforward=0.5))
    assert sine_reference(Reference(1.0, 5.0, feedforward=1.0), m2=1.0).is_sine


def test_one_controller_normalisation():
    pd = as_controller({"kp": 3.0, "kv": 0.0})      # a P controller is a valid loop...
    assert pd.gains == (3.0, 0.0) and pd.n_inputs == 2 and pd.n_states == 0
    with pytest.raises(ValueError, match="kv must be > 0"):
        closed_loop(ImpactPair(0.1, 0.5, 0.75), (3.0, 0.0), Reference(1.0, 5.0))  # ...not PD gains
    d = as_controller(ct.tf([1.0], [1.0, -0.5], dt=0.01))
    assert d.dt == 0.01 and d.n_inputs == 1 and d.gains is None
    assert as_controller(d) is d
    with pytest.raises(ValueError, match="continuous"):
        as_controller(d, sampled=False)
    for bad, msg in (((1.0, 2.0, 3.0), "pair"), ({"kp": 1}, "exactly the keys"),
                     ("pd", "controller must be"), ((1.0, float("nan")), "kv"),
                     (ct.ss([[0.0]], [[1.0, 0.0]], [[1.0], [1.0]], [[0, 0], [0, 0]]), "1 output")):
        with pytest.raises(ValueError, match=msg):
            as_controller(bad)
    c = Controller(np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)), np.array([[1.0, 2.0]]))
    np.testing.assert_allclose(np.asarray(c.to_ss().D), [[1.0, 2.0]], **TOL)


@pytest.mark.parametrize("k,m", [(1, 1), (2, 2), (3, 1)])
def test_zero_order_hold_equals_python_control(k, m):
    rng = np.random.default_rng(k * 10 + m)
    sysc = random_controller(rng, m, k)
    a = as_controller(sysc).sample(0.01)
    b = as_controller(sysc.sample(0.01, method="zoh"))
    for x, y in ((a.A, b.A), (a.B, b.B), (a.C, b.C), (a.D, b.D)):
        np.testing.assert_allclose(x, y, rtol=1e-12, atol=1e-14)
    assert a.dt == b.dt == 0.01
    with pytest.raises(ValueError, match="shapes"):
        Controller(np.eye(2), np.ones((3, m)), np.ones((1, 2)), np.ones((1, m)))


def test_loading_model_files_imports_no_python_control():
    """Building a model (PD or sampled PID) writes the loop out: python-control stays unloaded."""
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1] / "examples" / "models"
    code = ("import sys, hybridpd as hp\n"
            f"for f in ({str(root / 'drivetrain.toml')!r}, {str(root / 'robot_joint.toml')!r}):\n"
            "    hp.load_model(f)\n"
            "print(sorted(m for m in ('control', 'sympy', 'matplotlib') if m in sys.modules))\n")
    out = subprocess.run([sys.executable, "-c", code], check=False, capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]", out.stdout
