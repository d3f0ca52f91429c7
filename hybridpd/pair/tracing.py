"""Pseudo-arclength tracing of the zero curve of one test function in a parameter plane.

The engine behind :func:`hybridpd.pair.boundaries.boundary_curves`. It works in unit
coordinates ``u = (p - lo) / (hi - lo)`` of the box (so both axes weigh the same) and follows
``F(u) = 0`` for one boundary kind of :mod:`hybridpd.pair.testfunctions`:

* predictor ``u + h t`` along the unit tangent ``t`` (perpendicular to ``grad F``),
* corrector: Newton on ``[F(u); t . (u - u_pred)] = 0`` with central finite-difference
  gradients (one vectorised evaluation of the closed forms per iteration, one-sided at the
  edge of a parameter's domain), until ``|F| <= tol``,
* step control by the corrector's iteration count and the turn of the tangent.

Between two accepted points the engine watches for the events that end or mark a curve: the
box edge (the end point is solved on the edge), the curve's domain ending (the orbit stops
existing: a codimension-2 point, located on the curve), the return to the start (a closed
curve), and sign changes of other test functions along the curve (codimension-2 points where
two boundaries cross, and the 1:1 / 1:2 resonances of a Neimark-Sacker curve), located by the
Illinois method on the curve (each trial point corrected back onto ``F = 0``). Every loop is
bounded and a curve that cannot be continued says why (``"stalled"`` or ``"max_steps"``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.analysis.pathfollow import illinois, newton
from hybridpd.pair.testfunctions import Plane, TestValues

__all__ = ["Codim2Point", "Tracer"]

_FD = 1e-6            # finite-difference step (unit coordinates)
_MAX_NEWTON = 12
_MAX_ILLINOIS = 60


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


def _perp(g):
    n = math.hypot(g[0], g[1])
    return np.array([-g[1], g[0]]) / n if n > 0 else np.array([np.nan, np.nan])


def _take(tv: TestValues, i: int) -> TestValues:
    return TestValues(**{k: getattr(tv, k)[i:i + 1] for k in tv.__dataclass_fields__})


class Tracer:
    """Trace zero curves of ``funcs[kind]`` in the unit box of ``plane`` (internal).

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
    """

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
        """``F(u)``, ``grad F(u)`` (and of ``extra``), the center's TestValues."""
        pts = [u]
        scheme = []
        for a in range(2):
            lo, hi = self.dom[a]
            e = np.zeros(2)
            e[a] = _FD
            up, dn = u[a] + _FD <= hi, u[a] - _FD > lo
            if up and dn:
                pts += [u + e, u - e]
                scheme.append((len(pts) - 2, len(pts) - 1, 2 * _FD))
            elif up:
                pts.append(u + e)
                scheme.append((len(pts) - 1, 0, _FD))
            else:
                pts.append(u - e)
                scheme.append((0, len(pts) - 1, _FD))
        tv = self.values(np.array(pts))
        out = []
        for f in [self.local] + ([extra] if extra is not None else []):
            v = f(tv)
            out.append((float(v[0]), np.array([(v[i] - v[j]) / d for i, j, d in scheme])))
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
    def trace(self, u0, g0, tv0, direction, watchers, start=None):
        """Follow the curve from ``u0`` (on it) in ``direction`` (+1/-1 along ``perp(grad)``).

        ``watchers`` are ``(name, function, mode)``: mode ``"end"`` stops the curve where
        the function turns negative (the curve's domain ends: a codimension-2 point),
        ``"mark"`` records a codimension-2 point at a sign change and continues. Returns a
        dict with ``points`` (list of unit-coordinate arrays), ``end`` (``"box_edge"``,
        ``"closed"``, ``"codim2:<name>"``, ``"stalled"``, ``"max_steps"``) and ``codim2``
        (list of ``(name, u, tv)``).
        """
        pts = [np.array(u0, float)]
        codim = []
        t = direction * _perp(g0)
        u, tv = pts[0], tv0
        h = min(0.25 * self.max_step, 0.01)
        start = pts[0] if start is None else start
        vals = {nm: float(f(tv)[0]) for nm, f, _ in watchers}
        for _ in range(self.max_steps):
            ok = False
            while h >= self.min_step:
                ok, u1, _, g1, tv1, its = self.correct(u + h * t, t, max_dist=h)
                if ok:
                    t1 = _perp(g1)
                    if t1 @ t < 0:
                        t1 = -t1
                    turn = math.acos(min(1.0, max(-1.0, float(t1 @ t))))
                    step = float(np.linalg.norm(u1 - u))
                    if turn <= self.max_turn and 0.2 * h < step < 1.6 * h:
                        break
                    ok = False
                h *= 0.5
            if not ok:
                return self._stalled(pts, codim, u, tv)
            # box edge: the end point is solved on the edge (then checked like any point)
            at_edge = bool(np.any(u1 < 0.0) or np.any(u1 > 1.0))
            if at_edge:
                eok, u1, tv1 = self.edge_point(u, u1)
                if not eok:
                    return self._done(pts, codim, "box_edge")
            new = {nm: float(f(tv1)[0]) for nm, f, _ in watchers}
            ended = None
            for nm, f, mode in watchers:
                a, b = vals[nm], new[nm]
                if mode == "end":
                    hit = a >= 0 and (b < 0 or not np.isfinite(b))
                elif mode == "mark":
                    hit = np.isfinite(a) and np.isfinite(b) and (a > 0) != (b > 0)
                else:
                    continue
                if not hit:
                    continue
                loc = self.locate(u, u1, a, b if np.isfinite(b) else -1.0, f, tv, tv1)
                if loc is None:
                    if mode == "end":     # never step past the end of the domain
                        return self._done(pts, codim, "stalled")
                    continue
                uc, tvc = loc
                codim.append((nm, uc, tvc))
                if mode == "end":
                    ended = (nm, uc)
                    break
            if ended is not None:
                pts.append(ended[1])
                return self._done(pts, codim, f"codim2:{ended[0]}")
            if at_edge:
                pts.append(u1)
                return self._done(pts, codim, "box_edge")
            # closed curve: the chord passes the start again
            if len(pts) > 2:        # (the first chords start at the start itself)
                d = u1 - u
                s = float((start - u) @ d / (d @ d))
                if 0.0 <= s <= 1.0 and np.linalg.norm(u + s * d - start) < 0.25 * np.linalg.norm(d) + 1e-9:
                    pts.append(np.array(start, float))
                    return self._done(pts, codim, "closed")
            pts.append(u1)
            u, tv, t, vals = u1, tv1, t1, new
            if its <= 3 and turn < self.max_turn / 3:
                h = min(1.5 * h, self.max_step)
        return self._done(pts, codim, "max_steps")

    def _stalled(self, pts, codim, u, tv):
        """End of a curve whose corrector failed at the smallest step: explain it if we can."""
        if np.min(np.minimum(u, 1.0 - u)) < 1e-4:
            # e.g. at e -> 0 the boundaries run into the box edge with unbounded slope
            return self._done(pts, codim, "box_edge")
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
            return self._done(pts, codim, "codim2:grazing")
        return self._done(pts, codim, "stalled")

    def newton2(self, u, extra, max_iter=20):
        """Newton (:func:`~hybridpd.analysis.pathfollow.newton`) on ``[F; extra] = 0`` within
        0.05 of ``u``: ``(u, tv)`` or ``(None, None)``."""
        u0 = np.array(u, float)
        run, resid_g, jac = self._system(extra)
        res = newton(lambda x: None if np.linalg.norm(x - u0) > 0.05 else resid_g(x), jac, u0,
                     tol=self.tol, max_iter=max_iter, step_test=False)
        return (res.x, run(res.x)[1]) if res.converged else (None, None)

    @staticmethod
    def _done(pts, codim, end):
        return {"points": pts, "end": end, "codim2": codim}
