"""Boundary curves of the symmetric-orbit regions in any parameter plane, and codim-2 points.

The existence and stability regions of the simple symmetric orbit (paper Figs 4-5) are
bounded by curves of five kinds (:data:`~hybridpd.pair.testfunctions.KINDS`):
``existence``, ``grazing`` (paper (19)), ``fold`` (a multiplier at +1), ``period_doubling``
(a multiplier at -1) and ``neimark_sacker`` (a complex pair on the unit circle). Each is the
zero set of a scalar test function of the two swept parameters (the orbit is closed form, so
the defining system "orbit conditions + test function = 0" reduces to it; see
:mod:`hybridpd.pair.testfunctions`), and :func:`boundary_curves` *traces* it by
pseudo-arclength continuation (:class:`~hybridpd.pair.testcurve.TestCurve` on
:func:`~hybridpd.analysis.pathfollow.follow_path`) instead of reading it off a
grid: every point of a curve satisfies its test function to ``tol`` (1e-11 by default).

Completeness: a coarse ``seed_grid x seed_grid`` map of every test function seeds the
curves. Each sign change between neighbouring coarse points (an *edge*) must end up on a
traced curve: the edges a traced curve crosses are marked, and tracing restarts from every
edge not yet covered, so closed curves and curves that leave and re-enter the box are found.
(A component that crosses no coarse edge, i.e. fits inside one coarse cell, can be missed:
raise ``seed_grid`` to resolve smaller features.)

Curves are restricted to where they bound a region: multiplier curves (fold,
period_doubling, neimark_sacker) to where the orbit exists, the grazing curve to where the
impact is admissible, the existence curve to where the flight is viable. A curve ends at the
box edge (``"box_edge"``), closes on itself (``"closed"``), or ends at a codimension-2 point
(``"codim2:<kind>"``, e.g. ``"codim2:grazing+neimark_sacker"`` where the orbit stops existing
on a Neimark-Sacker curve, ``"codim2:resonance_1_1"`` where the complex pair reaches +1 and
the curve continues as a neutral saddle, which bounds nothing). ``"stalled"`` (the corrector
failed at the smallest step) and ``"max_steps"`` report the rare failures honestly.
Codimension-2 points where two boundaries cross, and the 1:2 resonances met along
Neimark-Sacker curves, are located on the curves and listed in
:attr:`BoundaryResult.codim2`.
"""
from __future__ import annotations

import itertools
import time
from dataclasses import dataclass, field

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.analysis.pathfollow import illinois_many
from hybridpd.model import check_positive
from hybridpd.pair.testcurve import Codim2Point, TestCurve, _pair
from hybridpd.pair.testfunctions import KINDS, PARAMETERS, Plane, TestValues, make_plane

__all__ = ["CODIM2_KINDS", "ENDS", "KINDS", "PARAMETERS", "BoundaryCurve", "BoundaryResult",
           "Codim2Point", "boundary_curves"]

#: How a curve can end (``"codim2:<kind>"`` with a kind of :data:`CODIM2_KINDS`).
ENDS = ("box_edge", "closed", "codim2", "stalled", "max_steps")
#: Kinds of :class:`Codim2Point`.
CODIM2_KINDS = ("existence+grazing", "existence+fold", "existence+period_doubling",
                "existence+neimark_sacker", "grazing+fold", "grazing+period_doubling",
                "grazing+neimark_sacker", "fold+period_doubling", "fold+neimark_sacker",
                "period_doubling+neimark_sacker", "grazing+grazing", "resonance_1_1",
                "resonance_1_2")

_MULT = ("fold", "period_doubling", "neimark_sacker")
_MAX_CODIM_SEEDS = 200     # bound on the codim-2 points tried as extra seeds


@dataclass(frozen=True)
class BoundaryCurve:
    """One traced boundary curve.

    Attributes
    ----------
    kind : str
        One of :data:`~hybridpd.pair.testfunctions.KINDS`.
    x, y : ndarray, shape (N,)
        The two swept parameters along the curve (axes' units), in order.
    ends : tuple of str
        How the curve ends at ``(x[0], y[0])`` and at ``(x[-1], y[-1])``: ``"box_edge"``,
        ``"closed"`` (both ends; the last point repeats the first), ``"codim2:<kind>"``
        (see :data:`CODIM2_KINDS`), ``"stalled"`` or ``"max_steps"``.
    x_name, y_name : str
    max_test : float
        Largest ``|local test function|`` over the points, recomputed after tracing.
    u : ndarray, shape (N, 2)
        Unit coordinates in the box.
    """

    kind: str
    x: np.ndarray
    y: np.ndarray
    ends: tuple
    x_name: str
    y_name: str
    max_test: float
    u: np.ndarray = field(repr=False)
    __repr__ = compact_repr

    def __len__(self) -> int:
        return len(self.x)

    def to_dict(self) -> dict:
        """``{"kind", <x_name>: [...], <y_name>: [...], "ends": [...]}`` (JSON-ready)."""
        return {"kind": self.kind, self.x_name: [float(v) for v in self.x],
                self.y_name: [float(v) for v in self.y], "ends": list(self.ends),
                "max_test": float(self.max_test)}


@dataclass(frozen=True)
class BoundaryResult:
    """All boundary curves and codimension-2 points of a parameter box.

    Attributes
    ----------
    plane : Plane
        Axes, case, order and fixed parameters.
    curves : list of BoundaryCurve
    codim2 : list of Codim2Point
    n_seeds : int
        Coarse edges with a sign change of a test function (inside the curves' domains).
    unresolved : int
        Seed edges whose sign change is not a zero of the test function (a discontinuity)
        or could not be corrected; 0 in a clean run.
    uncovered : int
        Seed edges not crossed by any traced curve after all restarts (0 in a clean run).
    seconds : float
        Wall time.
    n_evals : int
        Vectorised evaluations of the closed forms.
    """

    plane: Plane
    curves: list
    codim2: list
    n_seeds: int
    unresolved: int
    uncovered: int
    seconds: float
    n_evals: int
    __repr__ = compact_repr

    @property
    def x_name(self) -> str:
        return self.plane.x.name

    @property
    def y_name(self) -> str:
        return self.plane.y.name

    def of_kind(self, kind: str) -> list:
        """The curves of one kind."""
        return [c for c in self.curves if c.kind == kind]

    def n_points(self) -> int:
        """Total number of curve points."""
        return int(sum(len(c) for c in self.curves))

    def to_dict(self) -> dict:
        """The CLI's JSON object: ``{"x", "y", "curves", "codim2", ...}``."""
        xn, yn = self.x_name, self.y_name
        return {"x": xn, "y": yn, "case": self.plane.case.value, "n": self.plane.n,
                "range": {xn: [self.plane.x.lo, self.plane.x.hi],
                          yn: [self.plane.y.lo, self.plane.y.hi]},
                "fixed": dict(self.plane.fixed),
                "curves": [c.to_dict() for c in self.curves],
                "codim2": [{"kind": p.kind, xn: float(p.x), yn: float(p.y),
                            "residual": p.residual} for p in self.codim2],
                "seeds": self.n_seeds, "unresolved": self.unresolved,
                "uncovered": self.uncovered}


# ---------------------------------------------------------------------------------------
# seeding and coverage
# ---------------------------------------------------------------------------------------


def _domain_mask(tv: TestValues, kind, grid=False):
    with np.errstate(invalid="ignore"):
        if kind == "neimark_sacker" and not grid:
            return tv.exists & tv.critical_pair()[0]
        if kind in _MULT:
            return tv.exists
        if kind == "grazing":
            return tv.formal & (tv.admissible > 0)
        return tv.formal & (tv.margin > 0)


def _seed_edges(S, D):
    """Coarse edges ``(o, iy, ix)`` (``o = 0`` horizontal, ``1`` vertical) with a sign change."""
    out = []
    with np.errstate(invalid="ignore"):
        pos = S > 0
        fin = np.isfinite(S)
        h = fin[:, :-1] & fin[:, 1:] & (pos[:, :-1] != pos[:, 1:]) & (D[:, :-1] | D[:, 1:])
        v = fin[:-1, :] & fin[1:, :] & (pos[:-1, :] != pos[1:, :]) & (D[:-1, :] | D[1:, :])
    out += [(0, int(i), int(j)) for i, j in zip(*np.nonzero(h))]
    out += [(1, int(i), int(j)) for i, j in zip(*np.nonzero(v))]
    return out


def _crossed_edges(U, nx, ny):
    """Coarse edges crossed by the polyline ``U`` (unit coordinates)."""
    G = np.column_stack([U[:, 0] * (nx - 1), U[:, 1] * (ny - 1)])
    out = set()
    for a, b in itertools.pairwise(G):
        for ax_, o in ((1, 0), (0, 1)):   # horizontal lines y = i -> horizontal edges
            lo, hi = sorted((a[ax_], b[ax_]))
            if hi - lo == 0:
                continue
            for k in range(int(np.ceil(lo)), int(np.floor(hi)) + 1):
                s = (k - a[ax_]) / (b[ax_] - a[ax_])
                w = a[1 - ax_] + s * (b[1 - ax_] - a[1 - ax_])
                j = int(np.floor(w))
                for jj in (j, j - 1) if w == j else (j,):
                    out.add((o, k, jj) if o == 0 else (o, jj, k))
    return out


def _dist_to_polyline(p, U):
    if len(U) == 1:
        return float(np.linalg.norm(U[0] - p))
    a, b = U[:-1], U[1:]
    d = b - a
    L2 = np.maximum(np.sum(d * d, axis=1), 1e-300)
    s = np.clip(np.sum((p - a) * d, axis=1) / L2, 0.0, 1.0)
    return float(np.min(np.linalg.norm(a + s[:, None] * d - p, axis=1)))


def _edge_roots(tr: TestCurve, kind, UA, UB, FA, FB, iters=60):
    """Zeros of the sign test of ``kind`` on coarse edges ``UA[k]``-``UB[k]`` (the Illinois
    method on all edges at once, :func:`~hybridpd.analysis.pathfollow.illinois_many`); NaN
    rows where the sign test is not finite along the way."""
    def test(th, act):
        return tr.values(UA[act] + th[act, None] * (UB[act] - UA[act])).sign_test(kind)

    th, bad = illinois_many(test, FA, FB, tol=1e-9, max_iter=iters)
    R = UA + th[:, None] * (UB - UA)
    R[bad] = np.nan
    return R


# ---------------------------------------------------------------------------------------
# watchers: the domain of each kind and the codim-2 events met along its curves
# ---------------------------------------------------------------------------------------


def _sign(kind):
    return lambda tv: tv.sign_test(kind)


def _watchers(kind, kinds):
    w = []
    if kind in _MULT or kind == "existence":
        w.append(("grazing", _sign("grazing"), "end"))
    if kind in _MULT or kind == "grazing":
        w.append(("existence", _sign("existence"), "end"))
    for other in _MULT:
        if other != kind and other in kinds:
            w.append((other, _sign(other), "mark"))
    if kind == "neimark_sacker":
        # the pair leaves the unit circle through +1 and the curve continues as a neutral
        # saddle (a real pair with product 1), which bounds nothing: the curve ends. With
        # DP = M^2 the pair cannot leave through -1 (a real negative multiplier is double):
        # it passes -1 while M's pair passes +-i, marked as a 1:2 resonance
        w.append(("resonance_1_1", lambda tv: 2.0 - tv.critical_pair()[1], "end"))
        w.append(("resonance_1_2", lambda tv: tv.critical_pair()[2], "mark"))
    return w


def _codim_name(kind, name):
    return name if name.startswith("resonance") else _pair(kind, name)


# ---------------------------------------------------------------------------------------
# one kind
# ---------------------------------------------------------------------------------------


def _trace_seed(tr: TestCurve, u_seed, normal, watchers):
    """Trace the curve through a seed both ways: (points, ends, codim2 list)."""
    ok, u0, g0, tv0 = tr.correct_on_line(u_seed, normal, max_dist=0.1)
    if not ok:
        return None
    one = tr.trace(u0, g0, tv0, +1, watchers)
    if one[1] == "closed":
        return one[0], ("closed", "closed"), one[2]
    two = tr.trace(u0, g0, tv0, -1, watchers)
    return two[0][::-1] + one[0][1:], (two[1], one[1]), two[2] + one[2]


def _trace_from(tr, kind, u, normal, max_dist, watchers, curves, codim):
    """Correct ``u`` onto the curve along ``normal`` and trace it (appends to the lists)."""
    ok, u0, _, tv0 = tr.correct_on_line(u, normal, max_dist=max_dist)
    if not ok or not _domain_mask(tv0, kind)[0]:
        return "unresolved" if not ok else "domain"
    res = _trace_seed(tr, u0, normal, watchers)
    if res is None:
        return "unresolved"
    pts, ends, cod = res
    for name, uc, tvc in cod:
        if name in _MULT and not all(_domain_mask(tvc, k)[0] for k in (kind, name)):
            continue          # the other curve does not bound a region there
        codim.append((_codim_name(kind, name), uc, tvc))
    curves.append((kind, np.array(pts), tuple(
        e if not e.startswith("codim2:") else "codim2:" + _codim_name(kind, e[7:])
        for e in ends)))
    return "traced"


def _seed_from_codim2(plane, kinds, curves, codim, opts):
    """Trace curves met at a codim-2 crossing that no coarse edge revealed (thin features)."""
    n_evals = 0
    done = 0
    while done < len(codim) and done < _MAX_CODIM_SEEDS:
        name, uc, _ = codim[done]
        done += 1
        for kind in name.split("+") if "+" in name else ():
            if kind not in kinds or kind == "existence":
                continue
            if any(k == kind and _dist_to_polyline(uc, U) < 1e-3 for k, U, _ in curves):
                continue
            tr = TestCurve(plane, kind, **opts)
            ((_, g),), _ = tr.fgrad(uc)
            if np.all(np.isfinite(g)) and np.any(g != 0):
                _trace_from(tr, kind, uc, np.array([-g[1], g[0]]), 1e-3,
                            _watchers(kind, kinds), curves, codim)
            n_evals += tr.n_evals
    return n_evals


def _trace_kind(tr: TestCurve, kind, tvg, grid, kinds, curves, codim):
    ny, nx = grid
    S = tvg.sign_test(kind).reshape(ny, nx)
    D = _domain_mask(tvg, kind, grid=True).reshape(ny, nx)
    seeds = _seed_edges(S, D)
    state = {}           # seed edge -> "crossed" | "near" | "domain" | "unresolved"
    traced = []          # unit polylines of this kind
    crossed = set()
    watchers = _watchers(kind, kinds)
    cell = 1.0 / (max(nx, ny) - 1)
    if not seeds:
        return 0, 0, 0
    node = lambda iy, ix: np.array([ix / (nx - 1), iy / (ny - 1)])
    UA = np.array([node(iy, ix) for o, iy, ix in seeds])
    UB = np.array([node(iy, ix + 1) if o == 0 else node(iy + 1, ix) for o, iy, ix in seeds])
    FA = np.array([S[iy, ix] for o, iy, ix in seeds])
    FB = np.array([S[iy, ix + 1] if o == 0 else S[iy + 1, ix] for o, iy, ix in seeds])
    roots = _edge_roots(tr, kind, UA, UB, FA, FB)
    good = np.all(np.isfinite(roots), axis=1)
    indom = np.zeros(len(seeds), bool)
    if good.any():
        indom[good] = _domain_mask(tr.values(roots[good]), kind)
    for k, edge in enumerate(seeds):
        if edge in crossed:
            state[edge] = "crossed"
            continue
        if not good[k]:
            state[edge] = "unresolved"
            continue
        if not indom[k]:
            state[edge] = "domain"    # this zero lies where the curve bounds nothing
            continue
        root = roots[k]
        if any(_dist_to_polyline(root, P) < 0.3 * cell for P in traced):
            state[edge] = "near"
            continue
        why = _trace_from(tr, kind, root, UB[k] - UA[k], 1.5 * cell, watchers, curves, codim)
        if why == "traced":
            U = curves[-1][1]
            traced.append(U)
            crossed |= _crossed_edges(U, nx, ny)
            why = "crossed" if edge in crossed else "near"
        state[edge] = why
    unresolved = sum(1 for v in state.values() if v == "unresolved")
    uncovered = sum(1 for s in seeds if state.get(s) not in ("crossed", "near", "domain"))
    return len(seeds), unresolved, uncovered


# ---------------------------------------------------------------------------------------
# public entry point
# ---------------------------------------------------------------------------------------


def _residual(name, tv):
    """Largest |defining test function| of a codim-2 point."""
    with np.errstate(invalid="ignore"):
        if name == "grazing+grazing":
            vals = [tv.margin[0], tv.margin2[0]]
        elif name == "resonance_1_1":
            vals = [tv.local_test("neimark_sacker")[0], 2.0 - tv.critical_pair()[1][0]]
        elif name == "resonance_1_2":
            vals = [tv.local_test("neimark_sacker")[0], tv.critical_pair()[2][0]]
        else:
            vals = [tv.local_test(k)[0] for k in name.split("+")]
    return float(np.max(np.abs(vals)))


def _codim2_points(plane, raw, tol=1e-6):
    out = []
    for name, u, tv in raw:
        if any(p.kind == name and np.linalg.norm(p.u - u) < tol for p in out):
            continue
        if name.startswith("fold+neimark") and any(
                p.kind == "resonance_1_1" and np.linalg.norm(p.u - u) < tol for p in out):
            continue
        out.append(Codim2Point(kind=name, x=float(plane.x.from_unit(u[0])),
                               y=float(plane.y.from_unit(u[1])), u=np.array(u, float),
                               multipliers=np.asarray(tv.lam[0]).copy(),
                               residual=_residual(name, tv)))
    # an unlocated corner approached from both sides is one point: keep the better one
    approx = sorted((p for p in out if not p.residual <= 1e-8), key=lambda p: p.residual)
    for i, p in enumerate(approx):
        if any(q.kind == p.kind and np.linalg.norm(q.u - p.u) < 1e-3 for q in approx[:i]):
            out = [q for q in out if q is not p]
    # a 1:1 resonance found after the fold crossing at the same point replaces it
    res = [p for p in out if p.kind == "resonance_1_1"]
    return [p for p in out if not (p.kind == "fold+neimark_sacker" and any(
        np.linalg.norm(p.u - r.u) < tol for r in res))]


def boundary_curves(case="collocated", *, x=("kp", 0.1, 50.0), y=("kv", 0.1, 50.0),
                    kp=None, kv=None, e=None, mu=None, gamma=None, omega=None, m2=None,
                    x10=1.0, n=1, kinds=KINDS, seed_grid=41, tol=1e-11, max_step=0.02,
                    max_turn=0.1, max_steps=4000, margin_samples=256) -> BoundaryResult:
    """Trace the boundary curves of the symmetric orbit's regions in a parameter box.

    Parameters
    ----------
    case : {"collocated", "noncollocated"}
    x, y : (name, MIN, MAX)
        The swept parameters, any two of :data:`PARAMETERS` (``kp, kv, e, mu, gamma,
        omega, m2``), and the box.
    kp, kv, e, mu, gamma, omega : float
        The fixed parameters (gains in force/length and force time/length, ``0 <= e <= 1``,
        ``gamma = L / x10``, ``omega`` in rad/time). Those not swept must be given; the value
        of a swept one is ignored if inside its range (ValueError otherwise).
    m2, x10 : float
        Secondary mass (default 1 unless swept) and the primary mass's amplitude (default 1;
        ``L = gamma x10``).
    n : int
        Odd orbit order.
    kinds : sequence of str
        Which kinds to trace (subset of :data:`KINDS`).
    seed_grid : int
        Points per axis of the coarse seeding map (>= 3).
    tol : float
        Corrector tolerance on the (dimensionless) local test functions.
    max_step : float
        Largest step along a curve, as a fraction of the box (unit coordinates).
    max_turn : float
        Largest turn of the tangent between two points (radians); with ``max_step`` it
        bounds the distance between the polyline's chords and the curve (about
        ``max_step * max_turn / 8``, 2.5e-4 of the box by default). The points themselves
        lie on the curve to ``tol`` whatever the step.
    max_steps : int
        Bound on the points of a curve per direction.
    margin_samples : int
        Samples of the turning-point search in the viability margin.

    Returns
    -------
    BoundaryResult

    Raises
    ------
    ValueError
        Bad axes or fixed parameters (see :func:`~hybridpd.pair.testfunctions.make_plane`),
        unknown kinds, ``seed_grid < 3``, non-positive ``tol`` or ``max_step``.

    Examples
    --------
    The collocated orbit at ``e = 0.1`` stops existing by grazing near ``kv = 21.94`` at
    ``kp = 10``; in the (kp, kv) plane that is one grazing curve across the box:

    >>> res = boundary_curves("collocated", x=("kp", 5, 15), y=("kv", 15, 30), e=0.1,
    ...                       mu=0.1, gamma=0.75, omega=5.0, seed_grid=11)
    >>> [(c.kind, c.ends) for c in res.curves]
    [('grazing', ('box_edge', 'box_edge'))]
    >>> import numpy as np
    >>> round(float(np.interp(10.0, res.curves[0].x, res.curves[0].y)), 3)
    21.938
    """
    t0 = time.perf_counter()
    plane = make_plane(case, x, y, kp=kp, kv=kv, e=e, mu=mu, gamma=gamma, omega=omega, m2=m2,
                       x10=x10, n=n)
    kinds = tuple(kinds)
    bad = [k for k in kinds if k not in KINDS]
    if bad or not kinds:
        raise ValueError(f"kinds must be a non-empty subset of {KINDS}, got {list(kinds)}")
    if int(seed_grid) != seed_grid or seed_grid < 3:
        raise ValueError(f"seed_grid must be an integer >= 3, got {seed_grid!r}")
    seed_grid = int(seed_grid)
    tol = check_positive("tol", tol)
    max_step = check_positive("max_step", max_step)
    if max_step > 0.5:
        raise ValueError(f"max_step must lie in (0, 0.5] (a fraction of the box), got {max_step}")
    max_turn = check_positive("max_turn", max_turn)
    gu = np.linspace(0.0, 1.0, seed_grid)
    UX, UY = np.meshgrid(gu, gu)
    tvg = plane.evaluate(plane.x.from_unit(UX.ravel()), plane.y.from_unit(UY.ravel()),
                         margin_samples)
    raw_curves, raw_codim = [], []
    n_seeds = unresolved = uncovered = 0
    n_evals = 1
    for kind in kinds:
        tr = TestCurve(plane, kind, tol=tol, max_step=max_step, max_steps=max_steps,
                    max_turn=max_turn, margin_samples=margin_samples)
        a, b, c = _trace_kind(tr, kind, tvg, (seed_grid, seed_grid), kinds, raw_curves,
                              raw_codim)
        n_seeds += a
        unresolved += b
        uncovered += c
        n_evals += tr.n_evals
    n_evals += _seed_from_codim2(plane, kinds, raw_curves, raw_codim,
                                 dict(tol=tol, max_step=max_step, max_steps=max_steps,
                                      max_turn=max_turn, margin_samples=margin_samples))
    curves = []
    for kind, U, ends in raw_curves:
        tv = plane.evaluate(plane.x.from_unit(U[:, 0]), plane.y.from_unit(U[:, 1]),
                            margin_samples)
        n_evals += 1
        curves.append(BoundaryCurve(
            kind=kind, x=plane.x.from_unit(U[:, 0]), y=plane.y.from_unit(U[:, 1]), ends=ends,
            x_name=plane.x.name, y_name=plane.y.name,
            max_test=float(np.nanmax(np.abs(tv.local_test(kind)))), u=U))
    return BoundaryResult(plane=plane, curves=curves, codim2=_codim2_points(plane, raw_codim),
                          n_seeds=n_seeds, unresolved=unresolved, uncovered=uncovered,
                          seconds=time.perf_counter() - t0, n_evals=n_evals)
