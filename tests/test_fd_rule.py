"""The one finite-difference rule (hybridpd.analysis.fd) on maps with known Jacobians: central
where both sides return, one-sided from the centre where one does not, NaN (batch) or an error
(one point) where neither does; the single-point and batch forms and dF/dp agree with it."""
import numpy as np
import pytest

from hybridpd.analysis.family import parameter_gradient
from hybridpd.analysis.fd import difference_quotients
from hybridpd.analysis.maps import MapResult, PoincareMap

A = np.array([[0.5, 1.0], [0.0, -0.25]])
B = np.array([[2.0, 1.0], [1.0, -1.0]])


class Linear(PoincareMap):
    names = ("x", "y")

    def apply(self, s, k=1, jacobian=False):
        return MapResult(np.linalg.matrix_power(A, k) @ np.asarray(s, float))


class HalfLinear(PoincareMap):
    """``B s`` where ``lo <= x <= hi``; does not return elsewhere."""

    names = ("x", "y")

    def __init__(self, lo=0.0, hi=np.inf, p=1.0):
        self.lo, self.hi, self.p = lo, hi, p

    def apply(self, s, k=1, jacobian=False):
        s = np.asarray(s, float)
        if not self.lo <= s[0] <= self.hi:
            return MapResult(np.full(2, np.nan), ok=False, status="no_return")
        return MapResult(self.p * (B @ s))


def test_the_rule_selects_central_one_sided_and_undefined():
    plus = np.array([[[3.0], [9.0], [5.0], [1.0]]])
    minus = np.array([[[1.0], [0.0], [4.0], [1.0]]])
    q, ok = difference_quotients(plus, minus, [[1.0, 1.0, 0.5, 1.0]], [[2.0]],
                                 ok_plus=[[True, True, False, False]],
                                 ok_minus=[[True, False, True, False]])
    assert ok.tolist() == [[True, True, True, False]]
    assert q[0, :3, 0].tolist() == [1.0, 7.0, -4.0] and np.isnan(q[0, 3, 0])
    q, ok = difference_quotients(plus, minus, [[1.0] * 4], [[2.0]], ok_centre=[False])
    assert not ok.any() and np.all(np.isnan(q))


def test_single_point_and_batch_central_on_a_linear_map():
    P = Linear()
    s = np.array([0.3, -2.0])
    np.testing.assert_allclose(P.jacobian_fd(s), A, atol=1e-8)
    np.testing.assert_allclose(P.jacobian_fd(s, 2), A @ A, atol=1e-8)
    S = np.array([s, [4.0, 1.0], [-7.0, 0.0]])
    J = P.jacobians_fd(S)
    np.testing.assert_allclose(J, np.broadcast_to(A, (3, 2, 2)), atol=1e-8)
    # the batch's row is the single point's with the same steps, bit for bit
    assert np.array_equal(J[1], P.jacobian_fd(S[1], h=1e-6, scale=np.maximum(1.0, abs(S[1]))))
    # the central quotient in its one order of operations
    h = 1e-6 * np.maximum(1.0, np.abs(s))
    col = (P(s + [h[0], 0.0]) - P(s - [h[0], 0.0])) / (2 * h[0])
    assert np.array_equal(J[0][:, 0], col)


def test_one_sided_where_one_side_does_not_return():
    P = HalfLinear()
    edge = np.array([0.0, 0.7])
    with pytest.raises(RuntimeError, match="direction 0"):
        P.jacobian_fd(edge)
    np.testing.assert_allclose(P.jacobian_fd(edge, one_sided=True), B, atol=1e-8)
    narrow = HalfLinear(0.0, 1e-7)
    S = np.array([[2.0, 0.7], edge, [-1.0, 0.0], [5e-8, 0.3]])
    J = np.concatenate([P.jacobians_fd(S[:3]), narrow.jacobians_fd(S[3:])])
    np.testing.assert_allclose(J[0], B, atol=1e-8)           # central
    np.testing.assert_allclose(J[1], B, atol=1e-8)           # forward in x
    assert np.all(np.isnan(J[2]))                            # the centre does not return
    assert np.all(np.isnan(J[3][:, 0]))                      # neither side in x
    np.testing.assert_allclose(J[3][:, 1], B[:, 1], atol=1e-8)


def test_parameter_gradient_by_the_same_rule():
    s = np.array([0.5, 0.25])

    def at(p):
        return HalfLinear(p=p) if p >= 1.0 else None

    dF = B @ s       # d(p B s - s)/dp
    np.testing.assert_allclose(parameter_gradient(at, at(2.0), s, 1, 2.0, 1e-6), dF, atol=1e-8)
    np.testing.assert_allclose(parameter_gradient(at, at(1.0), s, 1, 1.0, 1e-6), dF, atol=1e-8)
    with pytest.raises(RuntimeError, match="both sides"):
        parameter_gradient(lambda p: None, at(1.0), s, 1, 1.0, 1e-6)
