"""The shared damped Newton (plain and with Broyden updates) and find_orbit on top of it."""
import math

import numpy as np
import pytest

from hybridpd.analysis.hybridmap import Section, SectionMap
from hybridpd.analysis.pathfollow import newton
from hybridpd.analysis.periodic import find_orbit
from hybridpd.hybrid.samples import impact_oscillator, oscillator_initial_state


def _circle_line(x):
    """``x0^2 + x1^2 = 4`` and ``x0 = x1``: the root ``(sqrt 2, sqrt 2)`` from the right."""
    return np.array([x[0] ** 2 + x[1] ** 2 - 4.0, x[0] - x[1]])


def _counted(f):
    def g(x):
        g.calls += 1
        return f(x)
    g.calls = 0
    return g


@pytest.mark.parametrize("broyden", [False, True])
def test_newton_finds_a_known_root(broyden):
    jac = _counted(lambda x: np.array([[2 * x[0], 2 * x[1]], [1.0, -1.0]]))
    res = newton(_circle_line, jac, [3.0, 0.5], tol=1e-13, max_iter=50, broyden=broyden)
    assert res.converged and res.status == "converged", res.reason
    np.testing.assert_allclose(res.x, [math.sqrt(2.0)] * 2, rtol=1e-12,
                               err_msg="the root of the circle and the diagonal")
    np.testing.assert_allclose(res.residual, _circle_line(res.x), rtol=0, atol=1e-15,
                               err_msg="the residual reported is the one at x")
    assert len(res.history) == res.iterations + 1
    if broyden:
        # the Jacobian only at the start and where an updated one fails: far fewer calls
        assert jac.calls < res.iterations, (jac.calls, res.iterations)
    else:
        assert jac.calls == res.iterations


def test_broyden_retries_with_the_true_jacobian_where_the_update_fails():
    # exp(x0) = 2, x1^3 + x0 = 1: from (3, 2) a step along the updated Jacobian fails on
    # the way (the exponential's curvature); Newton must then ask for the true one again
    jac = _counted(lambda x: np.array([[math.exp(x[0]), 0.0], [1.0, 3 * x[1] ** 2]]))
    res = newton(lambda x: np.array([math.exp(x[0]) - 2.0, x[1] ** 3 + x[0] - 1.0]), jac,
                 [3.0, 2.0], tol=1e-13, max_iter=60, broyden=True)
    assert res.converged, res.reason
    assert jac.calls >= 2, "the update never failed: the retry is not exercised"
    np.testing.assert_allclose(res.x, [math.log(2.0), np.cbrt(1.0 - math.log(2.0))],
                               rtol=1e-12, err_msg="x0 = ln 2, x1 = (1 - ln 2)^(1/3)")


def test_newton_on_a_circle_keeps_canonical_iterates_and_rejects_undefined_points():
    # F(theta) = sin(theta) - 1/2 on [0, 2 pi); undefined (None) below theta = 0.3 in the
    # canonical representative: the root pi/6 ~ 0.52 is reached from 2 pi + 1.2 only
    # through canonical iterates, and never by a trial point in the undefined region
    two_pi = 2 * math.pi
    seen = []

    def resid(x):
        seen.append(float(x[0]) % two_pi)
        return None if (x[0] % two_pi) < 0.3 else np.array([math.sin(x[0]) - 0.5])

    def canonical(x):
        x[0] %= two_pi
        return x

    res = newton(resid, lambda x: np.array([[math.cos(x[0])]]), [two_pi + 1.2], tol=1e-14,
                 max_iter=30, broyden=True, canonical=canonical,
                 difference=lambda a, b: (a - b + math.pi) % two_pi - math.pi)
    assert res.converged, res.reason
    np.testing.assert_allclose(res.x[0], math.pi / 6, rtol=1e-13, err_msg="sin = 1/2")
    assert 0 <= res.x[0] < two_pi
    assert min(seen) < 0.3, "the undefined region was never tried: the test is void"


def test_newton_reports_why_it_stopped():
    res = newton(lambda x: None, lambda x: np.eye(1), [1.0], tol=1e-12, max_iter=5)
    assert not res.converged and res.status == "undefined" and res.iterations == 0
    res = newton(lambda x: np.array([x[0] ** 2 + 1.0]), lambda x: np.array([[2 * x[0]]]),
                 [0.5], tol=1e-12, max_iter=3, step_test=False)
    assert not res.converged and res.status in ("line_search", "max_iter"), res.reason
    res = newton(lambda x: x - 1.0, lambda x: np.zeros((1, 1)), [3.0], tol=1e-12, max_iter=5)
    assert not res.converged and res.status == "singular", res.reason

    def bad(x):
        raise RuntimeError("no Jacobian here")
    res = newton(lambda x: x - 1.0, bad, [3.0], tol=1e-12, max_iter=5)
    assert res.status == "jacobian" and "no Jacobian here" in res.reason


# ---- find_orbit on the shared Newton ----------------------------------------------------
def _oscillator():
    ha = impact_oscillator(omega0=1.0, zeta=0.1, omega=0.8, stop=1.0, e=0.8)
    return SectionMap(Section(ha, "free", "impact",
                              reference=(oscillator_initial_state(0, 0, omega=0.8), 0.0)))


@pytest.mark.parametrize("guess", [[7.7, 1.66], [7.9, 1.4], [0.2, 1.9]])
def test_find_orbit_is_a_fixed_point_with_the_multipliers_of_finite_differences(guess):
    P = _oscillator()
    po = find_orbit(P, guess)
    assert po.converged, (po.reason, po.detail)
    # independent checks: the map applied once more returns to s (phase wrapped), and the
    # multipliers are those of a central-difference Jacobian of the simulated map
    back = P.section.wrap(P(po.s) - po.s)
    np.testing.assert_allclose(back, 0.0, atol=1e-10, err_msg="P(s) = s")
    fd = np.linalg.eigvals(P.jacobian_fd(po.s, h=1e-7))
    np.testing.assert_allclose(np.sort_complex(po.multipliers), np.sort_complex(fd),
                               atol=1e-6, err_msg="multipliers vs finite differences")
    # Newton with the finite-difference Jacobian (and its Broyden updates) lands on the
    # same orbit
    po_fd = find_orbit(P, guess, jacobian="fd")
    assert po_fd.converged, po_fd.reason
    np.testing.assert_allclose(P.section.wrap(po_fd.s - po.s), 0.0, atol=1e-9,
                               err_msg="exact and finite-difference Newton agree")
    assert 1 <= po.iterations <= 50


def test_find_orbit_counts_tests_of_the_residual():
    P = _oscillator()
    po = find_orbit(P, [7.7, 1.66])
    # started on the orbit: one test of the residual, no step
    again = find_orbit(P, po.s)
    assert again.converged and again.iterations == 1
    # one step allowed from afar: not converged, "max_iter" after that one iteration
    one = find_orbit(P, [7.9, 1.4], max_iter=1)
    assert not one.converged and one.reason == "max_iter" and one.iterations == 1
    assert np.isfinite(one.residual) and one.residual > 0
