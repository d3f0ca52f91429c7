"""One boundary curve of the pair's symmetric-orbit regions, traced by the general path
follower.

:class:`TestCurve` is the zero set of one scalar test function of a parameter plane
(:mod:`hybridpd.pair.testfunctions`) in the plane's unit coordinates: its evaluation, its
gradient (central differences, one-sided at the box edge), the corrector onto the curve, the
location of the points where a watched test function changes sign along it, and the edge
point where it leaves the box. :meth:`TestCurve.trace` follows it with
:func:`~hybridpd.analysis.pathfollow.follow_path` and the curve stepper
(:class:`~hybridpd.analysis.pathfollow.CurveStepper`). :class:`Codim2Point` is a point where
two boundaries meet, or a resonance on a Neimark-Sacker curve.
:func:`hybridpd.pair.boundaries.boundary_curves` seeds and collects the curves.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.analysis.fd import difference_quotients
from hybridpd.analysis.pathfollow import (
    CurvePoint,
    CurveStepper,
    PathOptions,
    follow_path,
    illinois,
    newton,
    perp,
)
from hybridpd.pair.testfunctions import KINDS, Plane, TestValues

__all__ = ["Codim2Point", "TestCurve"]

_FD = 1e-6                 # finite-difference step of the gradients (unit coordinates)
_MAX_NEWTON = 12
_MAX_ILLINOIS = 60


def _pair(a, b):
    a, b = sorted((a, b), key=KINDS.index)
    return f"{a}+{b}"


@dataclass(frozen=True)
class Codim2Point:
    """A codimension-2 point of the boundaries.

    Attributes
    ----------
    kind : str
        ``"<kind>+<kind>"`` where two boundaries meet (kinds in the order of
        :data:`~hybridpd.pair.testfunctions.KINDS`, e.g. ``"grazing+neimark_sacker"``,
        ``"fold+neimark_sacker"``), ``"grazing+grazing"`` (two turning points graze at once:
        a corner of the existence region), ``"resonance_1_1"`` / ``"resonance_1_2"`` (the
        Neimark-Sacker pair reaches +1 / -1).
    x, y : float
        Parameter values (axes' units).
    u : ndarray, shape (2,)
        Unit coordinates in the box.
    multipliers : ndarray, shape (4,), complex
        Multipliers of ``DP`` there (NaN where the formal orbit is singular).
    residual : float
        Largest absolute value of the two defining test functions at the point (about
        1e-11 when located by Newton or on a curve; larger only for a ``grazing+grazing``
        point where the margins are not smooth and the last curve point is reported).
    """

    kind: str
    x: float
    y: float
    u: np.ndarray = field(repr=False)
    multipliers: np.ndarray = field(repr=False)
    residual: float = float("nan")
    __repr__ = compact_repr


def _take(tv: TestValues, i: int) -> TestValues:
    return TestValues(**{k: getattr(tv, k)[i:i + 1] for k in tv.__dataclass_fields__})


class TestCurve:
    """The zero curve ``F(u) = 0`` of one test function in the unit box of ``plane``.

    Evaluation, corrector and location on the curve of :func:`boundary_curves`; the curve
    itself is followed by :func:`~hybridpd.analysis.pathfollow.follow_path` with a
    :class:`~hybridpd.analysis.pathfollow.CurveStepper` (:meth:`trace`).

    Parameters
    ----------
    plane : Plane
    kind : str
        A kind of :data:`~hybridpd.pair.testfunctions.KINDS`.
    tol : float
        Corrector tolerance on the local test function.
    max_step, min_step : float
        Step bounds (unit coordinates).
    max_steps : int
        Bound on accepted points per direction.
    max_turn : float
        Largest accepted turn of the tangent per step (radians).
    margin_samples : int
        Samples of the turning-point search in the viability margin.
    """

    __test__ = False      # a test function's curve, not a test case

    def __init__(self, plane: Plane, kind: str, *, tol=1e-11, max_step=0.02, min_step=1e-6,
                 max_steps=4000, max_turn=0.1, margin_samples=256):
        self.plane = plane
        self.kind = kind
        self.tol = tol
        self.max_step = max_step
        self.min_step = min_step
        self.max_steps = max_steps
        self.max_turn = max_turn
        self.margin_samples = margin_samples
        self.dom = [plane.x.unit_domain(), plane.y.unit_domain()]
        self.n_evals = 0

    # -- evaluation -------------------------------------------------------------------
    def values(self, U) -> TestValues:
        U = np.atleast_2d(np.asarray(U, float))
        self.n_evals += 1
        return self.plane.evaluate(self.plane.x.from_unit(U[:, 0]),
                                   self.plane.y.from_unit(U[:, 1]), self.margin_samples)

    def local(self, tv: TestValues) -> np.ndarray:
        return tv.local_test(self.kind)

    def fgrad(self, u, extra=None):
        """``F(u)``, ``grad F(u)`` (and of ``extra``), the center's TestValues.

        The gradient in the box's unit coordinates by the one finite-difference rule
        (:mod:`hybridpd.analysis.fd`) with step ``_FD``, the box as the domain: central,
        one-sided (forward, else backward) where a central one would leave it.
        """
        pts = [u]
        ip, im = [0, 0], [0, 0]              # rows of each side's point (0: not evaluated)
        okp, okm = np.zeros(2, bool), np.zeros(2, bool)
        for a in range(2):
            lo, hi = self.dom[a]
            e = np.zeros(2)
            e[a] = _FD
            okp[a], okm[a] = u[a] + _FD <= hi, u[a] - _FD > lo
            if okp[a]:
                pts.append(u + e)
                ip[a] = len(pts) - 1
            if okm[a]:
                pts.append(u - e)
                im[a] = len(pts) - 1
        tv = self.values(np.array(pts))
        steps = np.full(2, _FD)
        out = []
        for f in [self.local] + ([extra] if extra is not None else []):
            v = np.asarray(f(tv), float)
            d, _ok = difference_quotients(v[ip, None], v[im, None], steps, v[:1], ok_plus=okp,
                                          ok_minus=okm)
            out.append((float(v[0]), d[:, 0]))
        return out, _take(tv, 0)

    # -- corrector --------------------------------------------------------------------
    def _system(self, extra=None):
        """``(run, resid, jac)`` of ``G(u) = [F(u); extra(u)]`` for :func:`newton`: one
        finite-difference stencil gives both at a point, so the latest is kept."""
        memo = {}

        def run(u):
            key = u.tobytes()
            if key not in memo:
                memo.clear()
                memo[key] = self.fgrad(u, extra)
            return memo[key]

        def resid(u):
            vals, _tv = run(u)
            G = np.array([v for v, _ in vals])
            return G if np.all(np.isfinite(G)) and all(np.all(np.isfinite(d))
                                                        for _, d in vals) else None

        return run, resid, lambda u: np.array([d for _, d in run(u)[0]])

    def correct(self, u_pred, t, max_dist):
        """Newton (:func:`~hybridpd.analysis.pathfollow.newton`) on ``[F; t . (u - u_pred)]``
        within ``max_dist`` of ``u_pred``: (ok, u, F, grad, tv, iterations)."""
        u_pred = np.array(u_pred, float)
        run, resid_f, jac_f = self._system()

        def resid(u):
            G = None if np.linalg.norm(u - u_pred) > max_dist else resid_f(u)
            return None if G is None else np.append(G, float(t @ (u - u_pred)))

        res = newton(resid, lambda u: np.vstack([jac_f(u), t]), u_pred, tol=self.tol,
                     max_iter=_MAX_NEWTON, step_test=False)
        ((F, g),), tv = run(res.x)
        return bool(res.converged), res.x, F, g, tv, res.iterations

    def correct_on_line(self, u_pred, normal, max_dist=0.5):
        """Correct onto ``F = 0`` keeping ``normal . (u - u_pred) = 0`` (returns ok, u, g, tv)."""
        n = np.asarray(normal, float)
        ok, u, _, g, tv, _ = self.correct(u_pred, n / np.linalg.norm(n), max_dist)
        return ok, u, g, tv

    # -- location on the curve -------------------------------------------------------------
    def locate(self, ua, ub, fa, fb, mfun, tva, tvb):
        """Illinois on the curve between ``ua``, ``ub`` for a sign change of ``mfun``.

        Returns ``(u, tv)`` (``None`` if a trial point could not be corrected).
        """
        chord = ub - ua
        L = float(np.linalg.norm(chord))
        failed = []

        def evaluate(th):
            ok, u, _, tv = self.correct_on_line(ua + th * chord, chord / L, max_dist=L)
            if not ok:
                failed.append(th)
            return (u, tv) if ok else None

        a, b = (ua, tva), (ub, tvb)
        best, _f, _ok = illinois(evaluate, lambda q: float(mfun(q[1])[0]), fa, fb, a, b,
                                 size=1.0, tol=1e-13, max_iter=_MAX_ILLINOIS, ftol=1e-13,
                                 bisect_every=0)
        return None if failed and (best is a or best is b) else best

    def edge_point(self, ua, ub):
        """Where the curve between ``ua`` (inside) and ``ub`` (outside) meets the box edge."""
        d = ub - ua
        s_exit, axis, val = 1.0, 0, 0.0
        for a in range(2):
            for bound in (0.0, 1.0):
                if d[a] != 0:
                    s = (bound - ua[a]) / d[a]
                    if 0.0 <= s < s_exit:
                        s_exit, axis, val = s, a, bound
        p = ua + s_exit * d
        p[axis] = val
        normal = np.zeros(2)
        normal[axis] = 1.0
        ok, u, _, tv = self.correct_on_line(p, normal, max_dist=2 * np.linalg.norm(d) + 1e-9)
        if not ok or np.any(u < -1e-12) or np.any(u > 1 + 1e-12):
            ok, u, tv = False, p, None
        return ok, np.clip(u, 0.0, 1.0), tv

    # -- one direction ------------------------------------------------------------------------
    def trace(self, u0, g0, tv0, direction, watchers):
        """Follow the curve from ``u0`` (on it) in ``direction`` (+1/-1 along ``perp(grad)``).

        ``watchers`` are ``(name, function, mode)``: mode ``"end"`` stops the curve where
        the function turns negative (the curve's domain ends: a codimension-2 point),
        ``"mark"`` records a codimension-2 point at a sign change and continues. Returns
        ``(points, end, codim2)``: unit-coordinate arrays, ``"box_edge"``, ``"closed"``,
        ``"codim2:<name>"``, ``"stalled"`` or ``"max_steps"``, and ``(name, u, tv)`` tuples.
        """
        first = CurvePoint(np.array(u0, float), g0, direction * perp(g0), tv0)
        start = first.u
        state = {"vals": {nm: float(f(tv0)[0]) for nm, f, _ in watchers}}

        def detect(cur, new, index):
            return self._events(cur, new, index, watchers, state, start)

        stepper = CurveStepper(self.correct, max_step=self.max_step, max_turn=self.max_turn)
        pts, codim, end, _rej, _why = follow_path(
            first, None, PathOptions(step=min(0.25 * self.max_step, 0.01),
                                     min_step=self.min_step, max_step=self.max_step,
                                     max_steps=self.max_steps),
            stepper=stepper, detect=detect)
        U = [p.u for p in pts]
        if end.startswith("step below"):
            end = self._stalled(U, codim, pts[-1].u, pts[-1].data)
        elif end.startswith("max_steps"):
            end = "max_steps"
        return U, end, codim

    def _events(self, cur, new, index, watchers, state, start):
        """What ends or marks the curve between two accepted points, in this order: the box
        edge (the end point solved on it), the watchers' sign changes (located on the
        curve), the return to the start. ``(codim2 list, None or (last point, end))``."""
        u, tv, u1, tv1 = cur.u, cur.data, new.u, new.data
        at_edge = bool(np.any(u1 < 0.0) or np.any(u1 > 1.0))
        if at_edge:
            eok, u1, tv1 = self.edge_point(u, u1)
            if not eok:
                return [], (None, "box_edge")
        vals = state["vals"]
        nv = {nm: float(f(tv1)[0]) for nm, f, _ in watchers}
        codim = []
        for nm, f, mode in watchers:
            a, b = vals[nm], nv[nm]
            if mode == "end":
                hit = a >= 0 and (b < 0 or not np.isfinite(b))
            else:
                hit = np.isfinite(a) and np.isfinite(b) and (a > 0) != (b > 0)
            if not hit:
                continue
            loc = self.locate(u, u1, a, b if np.isfinite(b) else -1.0, f, tv, tv1)
            if loc is None:
                if mode == "end":     # never step past the end of the domain
                    return codim, (None, "stalled")
                continue
            codim.append((nm, *loc))
            if mode == "end":
                return codim, (CurvePoint(loc[0], None, None, loc[1]), f"codim2:{nm}")
        if at_edge:
            return codim, (CurvePoint(u1, None, None, tv1), "box_edge")
        if index > 1:          # closed curve: the chord passes the start again (the first
            d = u1 - u         # chords start at the start itself)
            s = float((start - u) @ d / (d @ d))
            if 0.0 <= s <= 1.0 and np.linalg.norm(u + s * d - start) < 0.25 * np.linalg.norm(d) + 1e-9:
                return codim, (CurvePoint(np.array(start, float), None, None), "closed")
        state["vals"] = nv
        return codim, None

    def _stalled(self, pts, codim, u, tv):
        """End of a curve whose corrector failed at the smallest step: explain it if we can
        (appends to ``pts`` and ``codim``; returns the end)."""
        if np.min(np.minimum(u, 1.0 - u)) < 1e-4:
            # e.g. at e -> 0 the boundaries run into the box edge with unbounded slope
            return "box_edge"
        if self.kind == "grazing" and tv.margin2[0] < 1e-2:
            # two interior turning points graze at once (a corner of the existence region,
            # or a max/min pair born at the wall, where the margins are not smooth): Newton
            # on both margins, else the last point (its residual says how close it is)
            uc, tvc = self.newton2(u, lambda t: t.margin2)
            if uc is None:
                uc, tvc = u, tv
            else:
                pts.append(uc)
            codim.append(("grazing", uc, tvc))
            return "codim2:grazing"
        return "stalled"

    def newton2(self, u, extra, max_iter=20):
        """Newton (:func:`~hybridpd.analysis.pathfollow.newton`) on ``[F; extra] = 0`` within
        0.05 of ``u``: ``(u, tv)`` or ``(None, None)``."""
        u0 = np.array(u, float)
        run, resid_g, jac = self._system(extra)
        res = newton(lambda x: None if np.linalg.norm(x - u0) > 0.05 else resid_g(x), jac, u0,
                     tol=self.tol, max_iter=max_iter, step_test=False)
        return (res.x, run(res.x)[1]) if res.converged else (None, None)
