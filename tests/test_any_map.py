"""Every analysis on a map a user writes in ten lines, against closed forms.

Two maps with known answers:

* the Hénon map ``x' = 1 - a x^2 + y``, ``y' = b x`` (no phase coordinate): fixed points
  ``x* = (-(1 - b) + sqrt((1 - b)^2 + 4 a)) / (2 a)``, ``y* = b x*``; multipliers the roots of
  ``l^2 + 2 a x* l - b = 0``; the fixed point loses stability at ``a = 3 (1 - b)^2 / 4``
  (a multiplier through -1); the 2-cycle ``x = ((1 - b) +- sqrt(4 a - 3 (1 - b)^2)) / (2 a)``
  doubles at ``a = (1 - b)^2 + (1 + b)^2 / 4``;
* a dissipative standard map with a phase ``phi' = phi + y' (mod 2 pi)``,
  ``y' = b y + k sin(phi)``: the fixed point ``(pi, 0)`` has ``DP = [[1 - k, b], [-k, b]]``,
  trace ``1 + b - k`` and determinant ``b``: it doubles at ``k = 2 (1 + b)``.
"""
import math

import numpy as np
import pytest

import hybridpd as hp

B = 0.3
A_PD1 = 3 * (1 - B) ** 2 / 4                      # 0.3675
A_PD2 = (1 - B) ** 2 + (1 + B) ** 2 / 4           # 0.9125


class Henon(hp.PoincareMap):
    names = ("x", "y")
    period = None                       # no phase coordinate

    def __init__(self, a, b=B):
        self.a, self.b = a, b

    def apply(self, s, k=1, jacobian=False):
        x, y = s
        J = np.eye(2)
        for _ in range(k):
            J = np.array([[-2 * self.a * x, 1.0], [self.b, 0.0]]) @ J
            x, y = 1 - self.a * x * x + y, self.b * x
        return hp.MapResult(np.array([x, y]), DP=J if jacobian else None)


class StandardMap(hp.PoincareMap):
    """A dissipative standard map, its first coordinate a phase of period 2 pi; no DP given
    (the analyses take finite differences)."""

    names = ("phi", "y")
    period = 2 * math.pi

    def __init__(self, k, b=0.5):
        self.k, self.b = k, b

    def apply(self, s, k=1, jacobian=False):
        phi, y = s
        for _ in range(k):
            y = self.b * y + self.k * math.sin(phi)
            phi = (phi + y) % (2 * math.pi)
        return hp.MapResult(np.array([phi, y]))


def _henon_fixed(a, b=B):
    x = (-(1 - b) + math.sqrt((1 - b) ** 2 + 4 * a)) / (2 * a)
    return np.array([x, b * x])


def _henon_multipliers(a, b=B):
    x = _henon_fixed(a, b)[0]
    return np.sort(np.abs(np.roots([1.0, 2 * a * x, -b])))


def test_the_protocol_derives_dim_and_defaults_the_result():
    P = Henon(0.2)
    assert P.dim == 2
    r = P.apply([0.1, 0.2])
    assert r.ok and r.status == "returned" and r.DP is None
    np.testing.assert_allclose(P([0.1, 0.2]), [1 - 0.2 * 0.01 + 0.2, 0.3 * 0.1], rtol=1e-15)
    np.testing.assert_allclose(P.jacobian([0.1, 0.2]), [[-0.04, 1.0], [0.3, 0.0]], rtol=1e-15)
    np.testing.assert_allclose(StandardMap(1.0).jacobian([1.0, 0.5]),
                               [[1 + math.cos(1.0), 0.5],
                                [math.cos(1.0), 0.5]], rtol=1e-6)


@pytest.mark.parametrize("a", [0.1, 0.2, 0.3])
def test_find_orbit_on_a_map_without_phase(a):
    orb = hp.find_orbit(Henon(a), [0.5, 0.15])
    assert orb.converged and orb.stable
    np.testing.assert_allclose(orb.s, _henon_fixed(a), rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(np.sort(np.abs(orb.multipliers)), _henon_multipliers(a),
                               rtol=1e-9, atol=1e-12)


def test_find_orbit_of_period_two():
    a = 0.6
    orb = hp.find_orbit(Henon(a), [1.2, -0.1], period=2)
    root = math.sqrt(4 * a - 3 * (1 - B) ** 2)
    xs = np.sort([((1 - B) + root) / (2 * a), ((1 - B) - root) / (2 * a)])
    assert orb.converged and orb.period == 2
    assert min(abs(orb.s[0] - x) for x in xs) < 1e-10
    # the 2-cycle's multipliers: det(DP^2) = b^2, trace = 4 (1-b)^2 - 4 a + 2 b
    np.testing.assert_allclose(np.prod(orb.multipliers).real, B ** 2, rtol=1e-9)
    np.testing.assert_allclose(np.sum(orb.multipliers).real,
                               4 * (1 - B) ** 2 - 4 * a + 2 * B, rtol=1e-9)


def test_find_orbit_on_a_map_with_a_phase_and_no_jacobian():
    orb = hp.find_orbit(StandardMap(1.0), [3.0, 0.2])
    assert orb.converged and orb.stable
    np.testing.assert_allclose(orb.s, [math.pi, 0.0], rtol=0, atol=1e-10)
    tr, det = 1 + 0.5 - 1.0, 0.5
    np.testing.assert_allclose(np.sum(orb.multipliers).real, tr, rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(np.prod(orb.multipliers).real, det, rtol=1e-6)


def test_continue_orbit_finds_the_period_doubling():
    orb = hp.find_orbit(Henon(0.2), [0.5, 0.15])
    branch = hp.continue_orbit(Henon, 0.2, 0.6, orb)
    pd = [e for e in branch.events if e.kind == "period_doubling"]
    assert len(pd) == 1, [(e.kind, e.parameter) for e in branch.events]
    np.testing.assert_allclose(pd[0].parameter, A_PD1, rtol=1e-6)
    # every point of the branch is the closed-form fixed point
    for p, s in zip(branch.parameter, branch.points):
        np.testing.assert_allclose(s, _henon_fixed(p), rtol=1e-8, atol=1e-10)
    assert branch.parameter[-1] == pytest.approx(0.6)


def test_continue_orbit_with_a_phase():
    orb = hp.find_orbit(StandardMap(1.0), [3.0, 0.2])
    branch = hp.continue_orbit(StandardMap, 1.0, 3.5, orb)
    pd = [e for e in branch.events if e.kind == "period_doubling"]
    assert len(pd) == 1
    np.testing.assert_allclose(pd[0].parameter, 2 * (1 + 0.5), rtol=1e-5)


class Fold(hp.PoincareMap):
    """``x' = x + (p - x^2) / 2``: fixed points ``x = +-sqrt(p)`` with multiplier ``1 - x``,
    so the branch turns back at ``p = 0`` (a fold, where it also loses stability); a return
    whose image exceeds 1/2 counts one jump, so the jump sequence of the fixed point changes
    at ``x = 1/2``, ``p = 1/4``."""

    names = ("x",)

    def __init__(self, p):
        self.p = p

    def apply(self, s, k=1, jacobian=False):
        x, J, jumps = s[0], 1.0, ()
        for _ in range(k):
            J *= 1 - x
            x = x + 0.5 * (self.p - x * x)
            jumps += ((0, 0.0, "wall", 0, "impact"),) if x > 0.5 else ()
        return hp.MapResult(np.array([x]), jumps=jumps,
                            DP=np.array([[J]]) if jacobian else None)


@pytest.mark.parametrize("method", ["arclength", "natural"])
def test_continue_orbit_locates_a_turning_point_and_a_sequence_change(method):
    branch = hp.continue_orbit(Fold, 1.0, -1.0, [1.0], method=method)
    for p, s in zip(branch.parameter, branch.points):     # on the closed-form branch
        assert abs(s[0] ** 2 - p) < 1e-9
    seq = branch.events_of("sequence_change")
    assert len(seq) == 1 and seq[0].located
    assert abs(seq[0].parameter - 0.25) < 1e-8 and abs(seq[0].point[0] - 0.5) < 1e-8
    if method == "natural":
        # natural steps in p cannot pass the fold: the corrector fails at p < 0
        assert branch.termination == "min_step" and not branch.events_of("fold")
        assert branch.parameter[-1] < 1e-3
        return
    stab = branch.events_of("stability_change")
    assert len(stab) == 1 and abs(stab[0].parameter) < 1e-7 and stab[0].located
    fold = branch.events_of("fold")
    assert len(fold) == 1 and fold[0].located and "turns back" in fold[0].detail
    assert abs(fold[0].parameter) < 1e-8 and abs(fold[0].point[0]) < 1e-4
    np.testing.assert_allclose(fold[0].multipliers, [1.0], atol=1e-4)
    assert branch.termination.startswith("turned back") and branch.points[-1][0] < 0
    assert not branch.stable[-1] and branch.stable[0]
    # without location the same events are reported between their points, uncertain
    rough = hp.continue_orbit(Fold, 1.0, -1.0, [1.0], locate=False)
    assert [e.kind for e in rough.events] == [e.kind for e in branch.events]
    assert all(not e.located and e.detail.startswith("uncertain") for e in rough.events
               if e.kind != "sequence_change")


def test_continue_orbit_event_options():
    only = hp.continue_orbit(Fold, 1.0, -1.0, [1.0], events=("fold",))
    assert [e.kind for e in only.events] == ["fold"]
    for bad, match in ((dict(events=("grazing",)), "events"), (dict(event_tol=0.0), "event_tol")):
        with pytest.raises(ValueError, match=match):
            hp.continue_orbit(Fold, 1.0, -1.0, [1.0], **bad)


def test_bifurcation_diagram_periods():
    values = np.linspace(0.2, 1.0, 81)
    d = hp.bifurcation_diagram(Henon, values, s0=[0.1, 0.1])
    expect = np.where(values < A_PD1, 1, np.where(values < A_PD2, 2, 4))
    # away from the bifurcations (slow convergence there) the periods are the closed forms'
    far = (np.abs(values - A_PD1) > 0.02) & (np.abs(values - A_PD2) > 0.02)
    np.testing.assert_array_equal(d.periods[far], expect[far])
    i = int(np.argmin(np.abs(values - 0.3)))
    np.testing.assert_allclose(d.points[i][-1], _henon_fixed(0.3), rtol=1e-8, atol=1e-10)


def test_basin_of_attraction_labels_the_fixed_point_and_divergence():
    P = Henon(0.2)
    basin = hp.basin_of_attraction(P, x=(-2, 2, 41), y=(-1, 1, 21))
    assert basin.labels.shape == (21, 41)
    fp = _henon_fixed(0.2)
    att = [a for a in basin.attractors if a.periodic]
    assert len(att) == 1
    np.testing.assert_allclose(att[0].points[0], fp, rtol=1e-8, atol=1e-10)
    ix = int(np.argmin(np.abs(basin.x - fp[0])))
    iy = int(np.argmin(np.abs(basin.y - fp[1])))
    assert basin.labels[iy, ix] == att[0].label
    # an independent iteration of every grid point agrees with the labels
    X, Y = np.meshgrid(basin.x, basin.y)
    x, y = X.copy(), Y.copy()
    with np.errstate(over="ignore", invalid="ignore"):
        for _ in range(500):
            x, y = 1 - 0.2 * x * x + y, B * x
    conv = np.hypot(x - fp[0], y - fp[1]) < 1e-6
    np.testing.assert_array_equal(basin.labels == att[0].label, conv)
