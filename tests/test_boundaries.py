"""Traced boundary curves: independent re-evaluation, completeness against a fine mask,
agreement with one-parameter continuation, codim-2 points, validation and the CLI."""
import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hybridpd import ImpactPair, PDGains
from hybridpd.cli import main
from hybridpd.pair import symbolic
from hybridpd.pair.boundaries import BoundaryResult, boundary_curves
from hybridpd.pair.boundarymask import compare_with_mask, region_status, side_status
from hybridpd.pair.continuation import continue_symmetric
from hybridpd.pair.orbits import symmetric_orbit
from hybridpd.pair.testfunctions import make_plane

PAPER = dict(mu=0.1, gamma=0.75, omega=5.0)
BOXES = {
    "col_e01": ("collocated", dict(x=("kp", 0.1, 50.0), y=("kv", 0.1, 50.0), e=0.1)),
    "non_e05_zoom": ("noncollocated", dict(x=("kp", 0.1, 20.0), y=("kv", 0.1, 6.0), e=0.5)),
    "non_e01": ("noncollocated", dict(x=("kp", 0.1, 50.0), y=("kv", 0.1, 50.0), e=0.1)),
    "col_gamma_omega": ("collocated", dict(x=("gamma", 0.1, 0.95), y=("omega", 1.0, 10.0),
                                           e=0.1, kp=10.0, kv=2.0)),
}
SLOW_BOXES = {
    "non_e09": ("noncollocated", dict(x=("kp", 0.1, 50.0), y=("kv", 0.1, 50.0), e=0.9)),
    "col_e09": ("collocated", dict(x=("kp", 0.1, 50.0), y=("kv", 0.1, 50.0), e=0.9)),
    "non_gamma_omega": ("noncollocated", dict(x=("gamma", 0.1, 0.95), y=("omega", 1.0, 10.0),
                                              e=0.5, kp=10.0, kv=2.0)),
    "non_mu_m2": ("noncollocated", dict(x=("mu", 0.01, 2.0), y=("m2", 0.2, 5.0), e=0.5,
                                        kp=10.0, kv=2.0)),
    "non_e_kv": ("noncollocated", dict(x=("e", 0.05, 1.0), y=("kv", 0.1, 50.0), kp=10.0)),
}
_CACHE = {}


def traced(name) -> BoundaryResult:
    if name not in _CACHE:
        case, kw = {**BOXES, **SLOW_BOXES}[name]
        kw = {**PAPER, **kw}
        _CACHE[name] = boundary_curves(case, **kw)
    return _CACHE[name]


def _orbit_at(res, x, y):
    p = {k: float(np.ravel(v)[0]) for k, v in res.plane.params(np.array([x]), np.array([y])).items()}
    pair = ImpactPair(p["mu"], p["e"], p["gamma"] * p["x10"], p["m2"])
    return symmetric_orbit(pair, PDGains(p["kp"], p["kv"]), p["omega"], x10=p["x10"],
                           n=res.plane.n, case=res.plane.case)


def _condition(kind, orb):
    """Distance from the boundary condition, recomputed from the orbit alone."""
    if kind == "grazing":
        return abs(orb.viability_margin)
    lam = np.linalg.eigvals(orb.DP)
    if kind == "fold":
        return float(np.min(np.abs(lam - 1.0)))
    if kind == "neimark_sacker":
        cplx = lam[np.abs(lam.imag) > 1e-6]
        return float(np.min(np.abs(np.abs(cplx) - 1.0)))
    raise AssertionError(kind)


def _check_points(res, every=1):
    assert res.curves
    for c in res.curves:
        assert c.max_test <= 1e-9, (c.kind, c.max_test)
        for i in range(1, len(c) - 1, every):
            orb = _orbit_at(res, c.x[i], c.y[i])
            assert _condition(c.kind, orb) <= 1e-8, (c.kind, c.x[i], c.y[i])
            if c.kind != "grazing":
                # multiplier curves bound regions only where the orbit exists
                assert orb.viability_margin > -1e-9


@pytest.mark.parametrize("name", ["col_e01", "non_e05_zoom", "col_gamma_omega"])
def test_curve_points_satisfy_the_boundary_condition_independently(name):
    _check_points(traced(name), every=3)


@pytest.mark.slow
@pytest.mark.parametrize("name", [*BOXES, *SLOW_BOXES])
def test_curve_points_satisfy_the_boundary_condition_all(name):
    _check_points(traced(name))


def _completeness(res, num):
    xs = np.linspace(res.plane.x.lo, res.plane.x.hi, num)
    ys = np.linspace(res.plane.y.lo, res.plane.y.hi, num)
    status = region_status(res.plane, xs, ys)
    cmp = compare_with_mask(res, status, xs, ys)
    # every status change between grid neighbours lies within one cell of a traced curve
    assert cmp.mask_to_curves_cells <= 1.0, cmp
    # and every curve point is within one cell of a status change of the mask
    assert cmp.curves_to_mask_cells <= 1.0, cmp
    # every traced curve separates points of different status
    for kind, left, right in side_status(res):
        assert left.size and np.all(left != right), kind
    assert res.uncovered == 0 and res.unresolved == 0


@pytest.mark.parametrize("name", ["col_e01", "non_e05_zoom"])
def test_completeness_against_a_fine_mask(name):
    _completeness(traced(name), 121)


@pytest.mark.slow
@pytest.mark.parametrize("name", [*BOXES, *SLOW_BOXES])
def test_completeness_against_a_fine_mask_all(name):
    _completeness(traced(name), 301)


def _crossings(res, kind, name, value):
    """The other parameter where the traced curves of ``kind`` cross ``name = value``,
    corrected onto the curve (exact, not the chord)."""
    from hybridpd.pair.testcurve import TestCurve

    axis = 0 if name == res.x_name else 1
    ax = (res.plane.x, res.plane.y)
    v = ax[axis].to_unit(value)
    tr = TestCurve(res.plane, kind)
    out = []
    for c in res.of_kind(kind):
        w = c.u[:, axis] - v
        for i in np.nonzero(np.sign(w[:-1]) != np.sign(w[1:]))[0]:
            s = w[i] / (w[i] - w[i + 1])
            p = c.u[i] + s * (c.u[i + 1] - c.u[i])
            normal = np.eye(2)[axis]
            ok, u, _, _ = tr.correct_on_line(p, normal, max_dist=0.05)
            assert ok
            out.append(float(ax[1 - axis].from_unit(u[1 - axis])))
    return out


def _near(values, target, tol):
    return bool(values) and min(abs(v - target) for v in values) < tol


@pytest.mark.stored_data
def test_one_parameter_events_lie_on_the_traced_curves():
    # grazing of the collocated orbit, e = 0.1, kp = 10, at kv = 21.938
    br = continue_symmetric(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0, "kv", 23.0)
    ev = br.events_of("grazing")[0]
    assert abs(ev.parameter - 21.938) < 1e-3
    res = traced("col_e01")
    assert _near(_crossings(res, "grazing", "kp", 10.0), ev.parameter, 1e-6)
    # Neimark-Sacker of the non-collocated orbit, e = 0.5, kp = 10, near kv = 2.32
    br = continue_symmetric(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 0.5), 5.0, "kv", 6.0,
                            case="noncollocated")
    res = traced("non_e05_zoom")
    ns = br.events_of("neimark_sacker")
    assert ns
    for ev in ns:
        assert _near(_crossings(res, "neimark_sacker", "kp", 10.0), ev.parameter, 1e-6)
    # the fold (a multiplier at +1: here the symmetry-breaking pitchfork) along kp, kv = 1
    br = continue_symmetric(ImpactPair(0.1, 0.5, 0.75), PDGains(5, 1.0), 5.0, "kp", 20.0,
                            case="noncollocated")
    folds = br.events_of("fold")
    assert folds
    for ev in folds:
        assert _near(_crossings(res, "fold", "kv", 1.0), ev.parameter, 1e-6)


def test_closed_curve_and_codim2_points():
    res = traced("non_e01")
    closed = [c for c in res.curves if c.ends == ("closed", "closed")]
    assert closed and closed[0].kind == "fold"
    assert np.allclose(closed[0].u[0], closed[0].u[-1])
    res = traced("non_e05_zoom")
    kinds = {q.kind for q in res.codim2}
    assert {"resonance_1_1", "fold+neimark_sacker", "resonance_1_2"} <= kinds
    ns_ends = [e for c in res.of_kind("neimark_sacker") for e in c.ends]
    assert "codim2:resonance_1_1" in ns_ends
    for q in res.codim2:
        lam = np.linalg.eigvals(_orbit_at(res, q.x, q.y).DP)
        if q.kind == "resonance_1_1":       # the pair meets at +1 (a double multiplier)
            assert np.sort(np.abs(lam - 1))[1] < 1e-4
        elif q.kind == "resonance_1_2":     # the pair passes -1
            assert np.sort(np.abs(lam + 1))[1] < 1e-4
        elif q.kind == "fold+neimark_sacker":
            assert np.min(np.abs(lam - 1)) < 1e-8
            cplx = lam[np.abs(lam.imag) > 1e-6]
            assert np.min(np.abs(np.abs(cplx) - 1)) < 1e-8


def test_curves_end_where_the_orbit_stops_existing():
    res = traced("col_gamma_omega")
    ends = [(c.kind, e) for c in res.curves for e in c.ends]
    assert ("fold", "codim2:grazing+fold") in ends
    for q in res.codim2:
        if q.kind.startswith("grazing+"):
            assert abs(_orbit_at(res, q.x, q.y).viability_margin) < 1e-9


@settings(max_examples=25, deadline=None)
@given(kp=st.floats(0.1, 50), kv=st.floats(0.1, 50), e=st.floats(0.0, 1.0),
       mu=st.floats(0.05, 2.0), case=st.sampled_from(["collocated", "noncollocated"]))
def test_symmetry_dp_is_a_square_so_no_period_doubling_curves(kp, kv, e, mu, case):
    # DP = M^2 with M = S DP21 DP10: hence det(I + DP) = |det(M - iI)|^2 >= 0
    c = symbolic.solve_symmetric_orbit(kp=kp, kv=kv, mu=mu, e=e, L=0.75, w=5.0, x10=1.0, case=case)
    jac = symbolic.orbit_jacobian(c)
    S = np.diag([1.0, -1, -1, -1])
    M = S @ jac.DP21 @ jac.DP10
    scale = 1 + np.abs(jac.DP).max()
    assert np.abs(jac.DP - M @ M).max() <= 1e-9 * scale
    assert np.linalg.det(np.eye(4) + jac.DP) >= -1e-9 * scale ** 4


def test_validation():
    kw = dict(e=0.5, **PAPER)
    with pytest.raises(ValueError, match="axis name"):
        boundary_curves("collocated", x=("foo", 1, 2), y=("kv", 1, 2), kp=1, **kw)
    with pytest.raises(ValueError, match="MIN must be < MAX"):
        boundary_curves("collocated", x=("kp", 2, 1), y=("kv", 1, 2), **kw)
    with pytest.raises(ValueError, match="different parameters"):
        boundary_curves("collocated", x=("kp", 1, 2), y=("kp", 3, 4), kv=1, **kw)
    with pytest.raises(ValueError, match="also fixed"):
        boundary_curves("collocated", x=("kp", 1, 2), y=("kv", 1, 2), kp=10, **kw)
    with pytest.raises(ValueError, match=r"must lie in \[0, 1\]"):
        boundary_curves("collocated", x=("kp", 1, 2), y=("e", 0.5, 1.5), mu=0.1, gamma=0.75,
                        omega=5)
    with pytest.raises(ValueError, match="kv must be given"):
        boundary_curves("collocated", x=("kp", 1, 2), y=("e", 0.1, 0.5), mu=0.1, gamma=0.75,
                        omega=5)
    with pytest.raises(ValueError, match="seed_grid"):
        boundary_curves("collocated", x=("kp", 1, 2), y=("kv", 1, 2), seed_grid=2, **kw)
    with pytest.raises(ValueError, match="kinds"):
        boundary_curves("collocated", x=("kp", 1, 2), y=("kv", 1, 2), kinds=("flip",), **kw)
    # a fixed value of a swept name inside its range is ignored
    pl = make_plane("collocated", ("kp", 1, 20), ("kv", 1, 2), kp=10, **kw)
    assert "kp" not in pl.fixed and pl.fixed["gamma"] == 0.75


def test_gamma_sweeps_the_clearance_at_fixed_x10():
    pl = make_plane("collocated", ("gamma", 0.2, 0.9), ("kv", 1, 30), kp=10, e=0.1, mu=0.1,
                    omega=5, x10=2.0)
    p = pl.params(np.array([0.5]), np.array([3.0]))
    assert p["gamma"][0] * p["x10"][0] == pytest.approx(1.0)


def test_cli_json(capsys):
    rc = main(["boundaries", "--case", "noncollocated", "--mu", "0.1", "--e", "0.5",
               "--gamma", "0.75", "--omega", "5", "--n", "1", "--x", "kp", "0.1", "20",
               "--y", "kv", "0.1", "6", "--json", "--seed-grid", "21"])
    assert rc == 0
    out = capsys.readouterr().out
    d = json.loads(out)
    assert out.count("\n") == 1
    assert d["x"] == "kp" and d["y"] == "kv"
    assert {c["kind"] for c in d["curves"]} == {"fold", "neimark_sacker"}
    for c in d["curves"]:
        assert len(c["kp"]) == len(c["kv"]) > 1 and len(c["ends"]) == 2
    for q in d["codim2"]:
        assert set(q) >= {"kind", "kp", "kv"}


@pytest.mark.parametrize("argv, msg", [
    (["--x", "foo", "0", "1", "--y", "kv", "1", "2"], "axis name"),
    (["--x", "kp", "5", "1", "--y", "kv", "1", "2"], "MIN must be < MAX"),
    (["--x", "kp", "1", "5", "--y", "kv", "1", "2", "--kp", "10"], "also fixed"),
    (["--x", "kp", "1", "5", "--y", "kp", "1", "2"], "different"),
    (["--x", "kp", "1", "5", "--y", "e", "0", "2"], "must lie in"),
    (["--x", "kp", "1", "5", "--y", "kv", "1", "2", "--n", "2"], "odd"),
    (["--x", "kp", "1", "5"], "required"),
])
def test_cli_bad_input_exits_2(argv, msg, capsys):
    rc = main(["boundaries", "--case", "collocated", "--mu", "0.1", "--e", "0.5", "--gamma",
               "0.75", "--omega", "5", *argv, "--json"])
    assert rc == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and msg in err


def test_cli_missing_fixed_parameter_exits_2(capsys):
    rc = main(["boundaries", "--case", "collocated", "--mu", "0.1", "--gamma", "0.75",
               "--omega", "5", "--x", "kp", "1", "5", "--y", "kv", "1", "2", "--json"])
    assert rc == 2
    assert "e must be given" in capsys.readouterr().err


def test_corner_of_the_existence_region_is_a_grazing_grazing_point():
    # n = 3: two turning points of the flight graze at once where two grazing curves meet
    res = boundary_curves("collocated", x=("kp", 0.1, 50.0), y=("kv", 0.1, 50.0), e=0.1,
                          n=3, **PAPER)
    assert {c.kind for c in res.curves} == {"grazing"}
    ends = [e for c in res.curves for e in c.ends]
    assert ends.count("codim2:grazing+grazing") == 2
    (q,) = [q for q in res.codim2 if q.kind == "grazing+grazing"]
    assert q.residual < 1e-3
    _check_points(res)


@pytest.mark.slow
def test_existence_boundary_of_a_plastic_impact():
    # e = 0: the masses stick after the impact on one side of the existence curve
    res = boundary_curves("noncollocated", x=("kp", 0.1, 50.0), y=("kv", 0.1, 50.0), e=0.0,
                          **PAPER)
    (c,) = res.of_kind("existence")
    from hybridpd.pair.orbits import symmetric_orbits

    U = c.u[1:-1]
    d = c.u[2:] - c.u[:-2]
    nrm = np.column_stack([-d[:, 1], d[:, 0]]) / np.linalg.norm(d, axis=1)[:, None]
    codes = []
    for sgn in (1, -1):
        P = U + sgn * 1e-4 * nrm
        r = symmetric_orbits(res.plane.x.from_unit(P[:, 0]), res.plane.y.from_unit(P[:, 1]),
                             mu=0.1, e=0.0, L=0.75, omega=5.0, case="noncollocated")
        codes.append(r.reason)
    stuck = (codes[0] == 4) != (codes[1] == 4)
    assert np.all(stuck)


_DOM = {"kp": (0.1, 50.0), "kv": (0.1, 30.0), "e": (0.02, 1.0), "mu": (0.02, 3.0),
        "gamma": (0.05, 0.98), "omega": (0.5, 15.0), "m2": (0.2, 5.0)}


@st.composite
def _planes(draw):
    names = draw(st.permutations(sorted(_DOM)))[:2]
    axes = []
    for nm in names:
        lo, hi = _DOM[nm]
        a = draw(st.floats(lo, hi - 0.1 * (hi - lo)))
        b = draw(st.floats(a + 0.05 * (hi - lo), hi))
        axes.append((nm, a, b))
    fixed = {k: v for k, v in dict(kp=10.0, kv=2.0, e=0.5, mu=0.1, gamma=0.75,
                                    omega=5.0).items() if k not in names}
    return axes[0], axes[1], fixed


@pytest.mark.slow
@settings(max_examples=10, deadline=None)
@given(case=st.sampled_from(["collocated", "noncollocated"]), plane=_planes(),
       n=st.sampled_from([1, 3]))
def test_random_planes_every_status_change_of_the_seed_grid_is_traced(case, plane, n):
    x, y, fixed = plane
    res = boundary_curves(case, x=x, y=y, n=n, seed_grid=21, **fixed)
    for c in res.curves:
        assert c.max_test <= 1e-9
    xs = np.linspace(x[1], x[2], 21)
    ys = np.linspace(y[1], y[2], 21)
    cmp = compare_with_mask(res, region_status(res.plane, xs, ys), xs, ys)
    if cmp.n_mask_edges:
        assert cmp.mask_to_curves_cells <= 1.0, cmp
    for kind, left, right in side_status(res):
        assert np.all(left != right), kind


def test_curve_stepper_follows_an_ellipse_once_around():
    """The curve stepper of follow_path on x^2/4 + y^2 = 1 (exact gradient, Newton corrector):
    every point on the ellipse, every step within (0.2 h, 1.6 h] of the largest step, the
    tangent's turn per step within max_turn, and the curve closed after one turn."""
    from hybridpd.analysis.pathfollow import (
        CurvePoint,
        CurveStepper,
        PathOptions,
        follow_path,
        perp,
    )

    def F(u):
        return u[0] ** 2 / 4 + u[1] ** 2 - 1.0

    def grad(u):
        return np.array([u[0] / 2, 2 * u[1]])

    def correct(u_pred, t, max_dist):
        u = np.array(u_pred, float)
        for it in range(1, 13):
            u = u - np.linalg.solve(np.vstack([grad(u), t]), [F(u), t @ (u - u_pred)])
            if np.linalg.norm(u - u_pred) > max_dist:
                break
            if abs(F(u)) < 1e-13:
                return True, u, F(u), grad(u), None, it
        return False, u, F(u), grad(u), None, it

    start = np.array([2.0, 0.0])
    first = CurvePoint(start, grad(start), perp(grad(start)))
    angle = lambda u: np.arctan2(u[1], u[0] / 2) % (2 * np.pi)

    def detect(a, b, i):      # stop on passing angle 0 again
        return [], (CurvePoint(start, None, None), "closed") if (
            i > 1 and angle(b.u) < angle(a.u)) else None

    pts, _, end, _, _ = follow_path(first, None, PathOptions(step=0.01, min_step=1e-6,
                                                             max_step=0.1, max_steps=2000),
                                    stepper=CurveStepper(correct, max_step=0.1),
                                    detect=detect)
    U = np.array([p.u for p in pts])
    assert end == "closed"
    assert np.max(np.abs(U[:, 0] ** 2 / 4 + U[:, 1] ** 2 - 1)) < 1e-12
    steps = np.linalg.norm(np.diff(U[:-1], axis=0), axis=1)
    assert np.all(steps < 1.6 * 0.1) and np.all(steps > 0)
    assert all(p.turn <= 0.1 for p in pts[1:-1])
    # one turn around: the polyline's length is the ellipse's perimeter (9.688448) to the
    # chords' shortfall
    length = float(np.sum(np.linalg.norm(np.diff(U, axis=0), axis=1)))
    assert 9.6 < length <= 9.688449
