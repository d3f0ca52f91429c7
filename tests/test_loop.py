"""The python-control closed loop against the paper's equations (3)-(8)."""
import control as ct
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import expm

from hybridpd.loop import closed_loop, pd_controller
from hybridpd.model import ImpactPair, PDGains, Reference


def force_by_hand(state, kp, kv, m2, w, case):
    x1, y1, x2, y2, pc, ps = state
    x, y = (x2, y2) if case == "collocated" else (x1, y1)
    xd, vd, ad = pc, -w * ps, -w * w * pc
    return m2 * ad - kv * (y - vd) - kp * (x - xd)


@settings(max_examples=50, deadline=None)
@given(kp=st.floats(0.1, 100), kv=st.floats(0.1, 100), m2=st.floats(0.1, 10), w=st.floats(0.1, 20),
       case=st.sampled_from(["collocated", "noncollocated"]),
       state=st.lists(st.floats(-5, 5), min_size=6, max_size=6))
def test_force_and_flow_match_eq3_eq8(kp, kv, m2, w, case, state):
    cl = closed_loop(ImpactPair(0.1, 0.5, 0.75, m2), PDGains(kp, kv), Reference(1.0, w), case)
    s = np.array(state)
    U = force_by_hand(s, kp, kv, m2, w, case)
    assert cl.force @ s == pytest.approx(U, rel=1e-12, abs=1e-10)
    ds = cl.A @ s
    _x1, y1, _x2, y2, pc, ps = s
    assert np.allclose(ds, [y1, 0, y2, U / m2, -w * ps, w * pc], rtol=1e-12, atol=1e-9)


def test_exosystem_generates_reference():
    cl = closed_loop(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), Reference(0.7, 5.0))
    t = 0.37
    s = expm(cl.A * t) @ cl.initial_state([0, 0, 0, 0], 0.0)
    assert s[4:6] == pytest.approx(cl.reference.exo_state(t), rel=1e-12)


def test_collocated_tracking_error_is_homogeneous():
    """With x2 = xd at t0 the collocated loop tracks exactly (particular solution = xd)."""
    cl = closed_loop(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), Reference(1.0, 5.0))
    s0 = cl.initial_state([0.2, 0.1, 1.0, 0.0], 0.0)   # x2 = xd(0) = 1, y2 = xd'(0) = 0
    for t in (0.3, 1.1, 2.9):
        s = expm(cl.A * t) @ s0
        assert s[2] == pytest.approx(np.cos(5 * t), abs=1e-12)


def test_general_controller_and_pd_as_system_agree():
    pair, ref = ImpactPair(0.1, 0.5, 0.75), Reference(1.0, 5.0)
    a = closed_loop(pair, PDGains(10, 20), ref)
    b = closed_loop(pair, pd_controller(10, 20), ref)
    np.testing.assert_allclose(a.A, b.A)
    filt = closed_loop(pair, ct.tf([20, 10], [1e-3, 1]), ref, "noncollocated")
    assert filt.n_states == 7 and filt.gains is None
    st_ = filt.sticking_A()
    assert np.allclose(st_[1], st_[3]) and np.allclose(st_[1], filt.force / 1.1)


def test_controller_validation():
    pair, ref = ImpactPair(0.1, 0.5, 0.75), Reference(1.0, 5.0)
    with pytest.raises(ValueError, match="proper"):
        closed_loop(pair, ct.tf([20, 10], [1]), ref)
    with pytest.raises(ValueError, match="controller"):
        closed_loop(pair, "pd", ref)
    with pytest.raises(ValueError, match="continuous"):
        closed_loop(pair, ct.tf([1], [1, 1], dt=0.1), ref)
    with pytest.raises(ValueError, match="x0"):
        closed_loop(pair, PDGains(1, 1), ref).initial_state([0, 0, 0])
