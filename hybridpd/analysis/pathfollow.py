"""Path following of fixed points of ``P^k`` in one parameter: the package's one engine.

Unknowns ``u = (s, p)``: a section point and the parameter; :func:`follow_path` continues a
solution of ``F(u) = P^k(s; p) - s = 0`` by natural or pseudo-arclength steps (passing
folds). Its caller (:func:`hybridpd.analysis.continuation.continue_orbit`, for any map's
family: the rules in which families differ are the family's hooks) gives the map
through ``F``, ``Fs``, ``Fp`` and ``make_point`` and their events through ``detect``; other
paths bring their step rules as a :class:`Stepper` (:class:`CurveStepper`: a zero curve in a
plane, :func:`hybridpd.pair.boundaries.boundary_curves`).
:func:`newton` (damped; with Broyden updates for
:func:`~hybridpd.analysis.periodic.find_orbit`) is the Newton method of the correctors and of
the orbit searches; :func:`illinois` the bracketing root step of event location.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

__all__ = ["CurvePoint", "CurveStepper", "NewtonResult", "PathOptions", "Stepper",
           "bisect_predicate", "corrector", "follow_path", "illinois", "newton", "perp"]

_MAX_HALVINGS = 60         # bound on step halvings in one continuation step


@dataclass
class NewtonResult:
    """Outcome of :func:`newton`.

    Attributes
    ----------
    x : ndarray
        The last iterate.
    converged : bool
    reason, status : str
        Why it stopped, in words and as one of ``"converged"``, ``"undefined"`` (at the
        start), ``"jacobian"`` (``jac`` raised), ``"singular"``, ``"line_search"``,
        ``"max_iter"``.
    history : list of float
        The residual norm at the start and after every accepted step.
    iterations : int
        Accepted steps (plus the failed one where the line search failed).
    step : float
        ``|dx|_inf`` of the last full Newton step.
    residual : ndarray or None
        The residual at ``x``.
    """

    x: np.ndarray
    converged: bool
    reason: str
    history: list
    iterations: int
    step: float
    residual: np.ndarray | None = None
    status: str = ""


def _max_abs(_x, r):
    return float(np.max(np.abs(r)))


def newton(resid, jac, x0, *, tol, max_iter, scale=lambda _x: 1.0, norm=_max_abs,
           broyden=False, difference=np.subtract, canonical=None, min_lambda=2.0 ** -12,
           step_test=True):
    """Damped Newton with backtracking on the residual norm; optionally Broyden updates.

    Converged when ``norm(x, F) <= tol * scale(x)``, or (``step_test``) when a full Newton
    step is itself below ``tol * scale(x)`` (the residual then sits at its rounding floor,
    which exceeds ``tol`` for strongly unstable orbits whose multipliers amplify rounding).

    Parameters
    ----------
    resid, jac : callable
        ``resid(x)``: the residual, ndarray ``(d,)``, or None where undefined (such trial
        points are rejected); ``jac(x)``: its Jacobian ``(d, d)`` (may raise RuntimeError,
        ValueError or LinAlgError).
    x0 : array_like, shape (d,)
    tol, max_iter : float, int
        Tolerance on ``norm`` (times ``scale``); bound on Newton steps.
    scale, norm : callable, optional
        ``scale(x)`` multiplies ``tol`` (default 1); ``norm(x, F)`` (default ``|F|_inf``).
    broyden : bool
        Rank-one (Broyden) updates of the Jacobian after each step; ``jac`` is evaluated at
        the start and again only where a step along the updated Jacobian fails (much cheaper
        where one ``jac`` costs many evaluations of ``resid``; still superlinear).
    difference, canonical : callable, optional
        ``difference(a, b)``: the step ``a - b`` of the Broyden secant (e.g. with a phase
        wrapped); ``canonical(x)``: the representative of every accepted iterate (e.g. a
        phase reduced to ``[0, T)``).
    min_lambda : float
        Smallest damping factor of the line search (the factors are ``1, 1/2, ...``).
    step_test : bool
        Accept a full Newton step below ``tol * scale(x)`` as convergence.

    Returns
    -------
    NewtonResult

    Examples
    --------
    >>> from hybridpd.analysis.pathfollow import newton
    >>> res = newton(lambda x: x ** 2 - 2.0, lambda x: np.diag(2 * x), [1.0], tol=1e-14,
    ...              max_iter=20)
    >>> res.converged, round(float(res.x[0]), 12)
    (True, 1.414213562373)
    """
    x = np.array(x0, dtype=float)
    r = resid(x)
    if r is None:
        return NewtonResult(x, False, "map undefined at the initial point", [], 0, np.nan,
                            None, "undefined")
    nr = norm(x, r)
    hist = [nr]
    last = np.nan
    J = None

    def out(ok, reason, its, status):
        return NewtonResult(x, ok, reason, hist, its, last, r, status)

    for it in range(1, max_iter + 1):
        if nr <= tol * scale(x):
            return out(True, "residual below tol", it - 1, "converged")
        retry = False
        while True:
            fresh = J is None
            try:
                J = jac(x) if fresh else J
            except (np.linalg.LinAlgError, RuntimeError, ValueError) as exc:
                return out(False, f"Jacobian failed: {exc}", it - 1, "jacobian")
            if retry:
                # ``x`` may have been made canonical since ``r`` was evaluated: the residual
                # of the point the new Jacobian belongs to
                rx = resid(x)
                r = r if rx is None else rx
            try:
                dx = np.linalg.solve(J, -r)
                failed = None if np.all(np.isfinite(dx)) else ("singular Jacobian", it - 1)
            except np.linalg.LinAlgError as exc:
                failed = (f"Jacobian failed: {exc}", it - 1)
            if failed is None:
                last = float(np.max(np.abs(dx)))
                trial = _line_search(resid, norm, x, dx, nr, min_lambda)
                if trial is None:
                    failed = ("line search failed (no decrease of the residual)", it)
            if failed is None or fresh:
                break
            J, retry = None, True      # the updated Jacobian failed: the true one, again
        if failed is not None:
            if failed[1] == it and step_test and last <= tol * scale(x):
                return out(True, "Newton step below tol (residual at rounding floor)", it,
                           "converged")
            return out(False, *failed, "line_search" if failed[1] == it else "singular")
        xn, rn, nr, lam = trial
        if broyden:
            d = difference(xn, x)
            dd = float(d @ d)
            if dd > 0:
                J = J + np.outer((rn - r) - J @ d, d) / dd
        else:
            J = None
        x = xn if canonical is None else canonical(xn)
        r = rn
        hist.append(nr)
        if step_test and lam == 1.0 and last <= tol * scale(x):
            return out(True, "Newton step below tol", it, "converged")
    if nr <= tol * scale(x):
        return out(True, "residual below tol", max_iter, "converged")
    return out(False, f"max_iter = {max_iter} reached", max_iter, "max_iter")


def _line_search(resid, norm, x, dx, nr, min_lambda):
    """``(x_new, F_new, norm_new, lambda)`` of the first damped step that decreases the
    norm enough (Armijo), or None."""
    lam = 1.0
    while lam >= min_lambda:
        xn = x + lam * dx
        rn = resid(xn)
        if rn is not None:
            nrn = norm(xn, rn)
            if nrn <= (1.0 - 1e-4 * lam) * nr:
                return xn, rn, nrn, lam
        lam *= 0.5
    return None


def corrector(F, Fs, Fp, *, tol, max_iter, scale, explain=None):
    """``correct(u_pred, normal)``: Newton on ``[F(u); normal . (u - u_pred)] = 0``.

    ``normal=None`` keeps ``p = u_pred[-1]`` fixed (Newton on ``s`` alone). ``scale(x)``
    scales the tolerance (:func:`newton`). ``explain()``, if given, returns why ``F`` was
    undefined at a point tried since its previous call (``""`` if it never was, e.g.
    ``"map undefined: grazing"``); a failed correction's reason then leads with it, since
    Newton itself only sees the undefined points as a failed line search. Returns
    ``(u, NewtonResult)``.
    """
    def correct(u_pred, normal):
        if explain is not None:
            explain()             # forget the failures of earlier corrections
        u, res = _correct(u_pred, normal)
        if not res.converged and explain is not None:
            why = explain()
            if why:
                res.reason = f"{why} (Newton: {res.reason})"
        return u, res

    def _correct(u_pred, normal):
        if normal is None:
            p = u_pred[-1]
            res = newton(lambda x: F(np.append(x, p)), lambda x: Fs(np.append(x, p)),
                         u_pred[:-1], tol=tol, max_iter=max_iter, scale=scale)
            return np.append(res.x, p), res

        def G(u):
            r = F(u)
            return None if r is None else np.append(r, normal @ (u - u_pred))

        def JG(u):
            return np.vstack([np.column_stack([Fs(u), Fp(u)]), normal])

        res = newton(G, JG, u_pred, tol=tol, max_iter=max_iter, scale=scale)
        return res.x, res
    return correct


def _tangent(DP, fp):
    """Unit null vector of ``[DP - I, dF/dp]`` (the branch tangent, unoriented)."""
    return np.linalg.svd(np.column_stack([DP - np.eye(DP.shape[0]), fp]))[2][-1]


@dataclass(frozen=True)
class PathOptions:
    """The step rules of one path: what :func:`follow_path`,
    :func:`~hybridpd.analysis.continuation.follow_branch` and
    :func:`~hybridpd.analysis.continuation.continue_orbit` pass down as one record.

    Attributes
    ----------
    step, min_step, max_step : float
        Initial, smallest and largest step (``p`` units for ``natural``, arclength in ``u``).
    max_steps : int
        Bound on accepted steps.
    method : {"arclength", "natural"}
    tol : float
        Corrector tolerance.
    max_iter : int
        Corrector (Newton) iterations per point.
    grow : float
        Step growth factor after an easy correction (at most 3 Newton iterations).
    name : str
        Parameter name in messages.
    locate : bool
        Locate events (else report the bracketing points).
    event_tol : float
        Location tolerance of events.

    Examples
    --------
    >>> PathOptions(step=0.1, min_step=1e-6, max_step=0.5, max_steps=100).method
    'arclength'
    """

    step: float
    min_step: float
    max_step: float
    max_steps: int
    method: str = "arclength"
    tol: float = 1e-10
    max_iter: int = 15
    grow: float = 1.5
    name: str = "p"
    locate: bool = True
    event_tol: float = 1e-9


def follow_path(first, stop, options: PathOptions, *, F=None, Fs=None, Fp=None,
                make_point=None, correct=None, k=1, lower_period=None, unwrap=None,
                detect=None, out_of_range=None, explain=None, stepper=None):
    """Continue from the accepted point ``first`` (its ``u``) towards ``p = stop``.

    ``method="natural"``: ``p`` steps by ``h`` (secant predictor through the last two
    points), Newton on ``s`` at fixed ``p``. ``method="arclength"``: predictor along the
    tangent (the kernel of ``[F_s, F_p]`` at the start, then the secant), Newton on
    ``[F(u); t . (u - u_pred)] = 0``; a corrected point whose secant turns by more than 37
    degrees is rejected (most likely another branch), and next to a fold the exact tangent is
    tried once before the step is halved. Steps halve on a failed correction (down to
    ``min_step``) and grow after easy ones; an overshoot of ``stop`` lands on it by a
    fixed-parameter correction.

    Parameters
    ----------
    first : point
        An object with ``u`` (ndarray ``(d + 1,)``), ``DP`` (``(d, d)``, of ``P^k``) and
        ``Fp`` (``dF/dp`` at ``u`` or None); ``make_point(u, newton_iterations)`` returns
        such objects (None: the point is not usable).
    stop : float
        End value of the parameter.
    F, Fs, Fp : callable
        ``F(u)`` (residual, None where undefined), its Jacobians in ``s`` and ``p``.
    options : PathOptions
        Steps, their bound, method, corrector tolerance, growth and the parameter's name.
    correct : callable
        ``correct(u_pred, normal)`` (:func:`corrector`).
    k : int
        Period (returns to the section).
    lower_period : callable, optional
        ``lower_period(u)``: True when ``u`` is a fixed point of a lower power of ``P`` (the
        corrector slid onto a parent branch); checked for ``k > 1``.
    unwrap : callable, optional
        ``unwrap(cur, new)``: make the phase of ``new.u`` continuous with ``cur.u`` (in place).
    detect : callable, optional
        ``detect(a, b, index)``: events between accepted points.
    out_of_range : callable, optional
        ``out_of_range(p)``: None inside the range, else the termination message (the
        arclength branch has turned back out of it).
    explain : callable, optional
        ``explain()``: why the map was undefined at a point tried since the previous call
        (``""`` if it was not); names the cause when a corrected point has no Jacobian.
    stepper : Stepper, optional
        Step rules of another kind of path (e.g. :class:`CurveStepper`, a zero curve in a
        plane). Then ``stepper`` predicts and corrects, and ``F``, ``Fs``, ``Fp``,
        ``make_point``, ``correct``, ``stop``, the keywords after ``k`` but ``detect`` and the
        options after ``max_steps`` are not used; ``detect(cur, new, index)`` returns
        ``(events, end)``
        with ``end`` None (go on) or ``(last, termination)``: the path stops there, with
        ``last`` (a point or None) appended. None: today's arclength or natural rules.

    Returns
    -------
    points : list
    events : list
    termination : str
        ``"reached stop"``, ``"max_steps = N reached at <name> = ..."``, ``"step below
        min_step = ... at <name> = ...: <why>"`` (``why``: the corrector's failure at the
        smallest step, e.g. ``"corrector failed: map undefined: grazing (Newton: ...)"``, or
        why its answer was rejected) or the message of ``out_of_range``.
    rejected : int
        Rejected corrector attempts.
    stuck : str
        Why the last step failed (``""`` unless the step fell below ``min_step``).
    """
    if stepper is not None:
        return _follow_stepper(first, stepper, options, detect)
    method, step, min_step, max_step = (options.method, options.step, options.min_step,
                                        options.max_step)
    max_steps, tol, name, grow = options.max_steps, options.tol, options.name, options.grow
    pts = [first]
    evs = []
    rejected = 0
    direction = 1.0 if stop > first.u[-1] else -1.0
    h = min(step, max_step)
    d = first.u.size - 1
    tangent = None
    if method == "arclength":
        try:
            tangent = _tangent(first.DP, Fp(first.u))
        except (RuntimeError, np.linalg.LinAlgError):
            tangent = np.append(np.zeros(d), 1.0)
        if tangent[-1] * direction < 0:
            tangent = -tangent
        if abs(tangent[-1]) < 1e-12:
            tangent = np.append(np.zeros(d), direction)
    prev_u = None
    why = ""
    for _ in range(max_steps):
        cur = pts[-1]
        accepted, res, why = _step(cur, prev_u, h, tangent, stop, direction, method, correct,
                                   make_point, k, lower_period, tol, min_step, explain)
        rejected += accepted[1]
        accepted, h, tangent = accepted[0], accepted[2], accepted[3]
        if accepted is None:
            termination = (f"step below min_step = {min_step:g} at {name} = "
                           f"{cur.u[-1]:.10g}: {why}")
            break
        new = accepted
        its = res.iterations
        if unwrap is not None:
            unwrap(cur, new)
        p_new = new.u[-1]
        done = False
        if method == "natural" and p_new == stop:
            done = True
        elif method == "arclength" and (p_new - stop) * direction >= 0:
            # overshot: land exactly on stop by a fixed-parameter correction
            w = (stop - cur.u[-1]) / (p_new - cur.u[-1])
            u_pred = cur.u + w * (new.u - cur.u)
            u_pred[-1] = stop
            u, res2 = correct(u_pred, None)
            if res2.converged:
                pt = make_point(u, res2.iterations)
                if pt is not None:
                    if unwrap is not None:
                        unwrap(cur, pt)
                    new = pt
            done = True
        if detect is not None:
            evs.extend(detect(cur, new, len(pts) - 1))
        prev_u = cur.u.copy()
        pts.append(new)
        if done:
            termination = "reached stop"
            break
        if method == "arclength":
            sec = new.u - cur.u
            tangent = sec / np.linalg.norm(sec)       # secant predictor
            left = None if out_of_range is None else out_of_range(p_new)
            if left is not None:
                termination = left
                break
        # step control: easy corrections lengthen the step, hard ones shorten it
        if its <= 3:
            h = min(grow * h, max_step)
        elif its >= 7:
            h = max(0.6 * h, min_step)
    else:
        termination = f"max_steps = {max_steps} reached at {name} = {pts[-1].u[-1]:.10g}"
    return pts, evs, termination, rejected, why if termination.startswith("step below") else ""


def _step(cur, prev_u, h, tangent, stop, direction, method, correct, make_point, k,
          lower_period, tol, min_step, explain=None):
    """One accepted step from ``cur`` (halving ``h`` on failure): ``((point or None,
    rejected, h, tangent), NewtonResult, why)``."""
    rejected = 0
    exact = False
    why = ""
    res = None
    d = cur.u.size - 1
    for _h in range(_MAX_HALVINGS):
        if method == "natural":
            p_new = cur.u[-1] + direction * h
            if (p_new - stop) * direction > 0:
                p_new = stop
            if prev_u is not None:
                # secant predictor through the last two points
                dp_prev = cur.u[-1] - prev_u[-1]
                u_pred = cur.u + (cur.u - prev_u) * ((p_new - cur.u[-1]) / dp_prev)
            else:
                u_pred = cur.u.copy()
            u_pred[-1] = p_new
            u, res = correct(u_pred, None)
        else:
            u_pred = cur.u + h * tangent
            if (u_pred[-1] - stop) * direction > 0 and tangent[-1] * direction > 0:
                # the predictor passes stop (maybe beyond the parameter's domain): correct at
                # stop itself, along the tangent
                u_pred = cur.u + ((stop - cur.u[-1]) / tangent[-1]) * tangent
                u_pred[-1] = stop
                u, res = correct(u_pred, None)
            else:
                u, res = correct(u_pred, tangent)
        pt = None
        if not res.converged:
            why = f"corrector failed: {res.reason}"
        else:
            sec = u - cur.u
            ns = float(np.linalg.norm(sec))
            if method == "arclength" and not (ns > 0 and (sec @ tangent) / ns > 0.8):
                # the corrected point lies far off the predicted direction: most likely
                # another branch
                why = "the step turned by more than 37 degrees"
            elif method == "natural" and not (
                    np.linalg.norm(u[:d] - u_pred[:d]) <= 0.5 * max(ns, h) + 10 * tol):
                why = "the corrector moved far from the predictor"
            elif k > 1 and lower_period is not None and lower_period(u):
                # the corrector slid onto an orbit of lower period (e.g. the parent of a
                # period-doubled branch, a fixed point of P^k too): another branch
                why = "the corrector landed on an orbit of lower period"
            else:
                pt = make_point(u, res.iterations)
                if pt is None:
                    cause = explain() if explain is not None else ""
                    why = "Jacobian undefined at the corrected point" + (
                        f": {cause}" if cause else "")
        if pt is not None:
            return (pt, rejected, h, tangent), res, why
        rejected += 1
        if method == "arclength" and not exact and why.startswith("the step turned") \
                and cur.Fp is not None:
            # Next to a fold the secant of the last (long) step is a poor tangent and the
            # branch turns away from it whatever the step: retry with the exact tangent.
            v = _tangent(cur.DP, cur.Fp)
            tangent = v if v @ tangent >= 0 else -v
            exact = True
            continue
        h *= 0.5
        if h < min_step:
            break
    return (None, rejected, h, tangent), res, why


class Stepper(Protocol):
    """The step rules of :func:`follow_path` for a path other than a branch of orbits.

    ``predict(cur, h)``: the corrected point a step ``h`` ahead of ``cur`` (predictor and
    corrector), or None where the correction failed; ``accept(cur, new, h)``: whether that
    point is the path's next one (else ``h`` is halved); ``next_step(h, cur, new)``: the step
    after an accepted one.
    """

    def predict(self, cur, h): ...

    def accept(self, cur, new, h) -> bool: ...

    def next_step(self, h, cur, new) -> float: ...


@dataclass
class CurvePoint:
    """A point of a zero curve ``F(u) = 0`` in a plane (:class:`CurveStepper`).

    ``u``: the point; ``g``: ``grad F`` there; ``t``: the unit tangent the path moves along
    (``perp(g)``, oriented); ``data``: the caller's values at ``u``; ``iterations``, ``turn``:
    the corrector's Newton steps and the tangent's turn (radians) from the previous point.
    """

    u: np.ndarray
    g: np.ndarray
    t: np.ndarray
    data: object = None
    iterations: int = 0
    turn: float = 0.0


def perp(g):
    """The unit vector ``(-g[1], g[0]) / |g|`` (NaN where ``g = 0``): a zero curve's tangent."""
    n = math.hypot(g[0], g[1])
    return np.array([-g[1], g[0]]) / n if n > 0 else np.array([np.nan, np.nan])


class CurveStepper:
    """Step rules of a zero curve ``F(u) = 0`` of a function of two unknowns.

    The predictor steps ``h`` along the tangent ``t = perp(grad F)`` of the current point; the
    corrector ``correct(u_pred, t, max_dist)`` (Newton on ``[F; t . (u - u_pred)] = 0`` within
    ``max_dist = h`` of the predictor) returns ``(ok, u, F, g, data, iterations)``. A corrected
    point is accepted when the tangent turned by at most ``max_turn`` and the step's length
    lies in ``(0.2 h, 1.6 h)``; the step grows by 1.5 (to ``max_step``) after an easy one (at
    most 3 Newton steps, a turn below ``max_turn / 3``).

    Examples
    --------
    The unit circle, one quarter of it from ``(1, 0)``: the turn per step is the step itself,
    above ``max_turn / 3``, so the steps stay 0.05 and a quarter (length 1.571) takes 32:

    >>> def correct(u_pred, t, max_dist):
    ...     u = np.array(u_pred, float)
    ...     for it in range(1, 20):
    ...         F, g = u @ u - 1.0, 2 * u
    ...         u = u - np.linalg.solve(np.vstack([g, t]), [F, 0.0])
    ...         if abs(u @ u - 1.0) < 1e-14:
    ...             return True, u, 0.0, 2 * u, None, it
    ...     return False, u, F, g, None, it
    >>> st = CurveStepper(correct, max_step=0.1)
    >>> first = CurvePoint(np.array([1.0, 0.0]), np.array([2.0, 0.0]), np.array([0.0, 1.0]))
    >>> pts, _, end, _, _ = follow_path(
    ...     first, None, PathOptions(step=0.05, min_step=1e-6, max_step=0.1, max_steps=100),
    ...     stepper=st, detect=lambda a, b, i: ([], None if b.u[0] > 0 else (None, "quarter")))
    >>> end, bool(np.allclose([p.u @ p.u for p in pts], 1.0)), len(pts)
    ('quarter', True, 32)
    """

    def __init__(self, correct, *, max_step, max_turn=0.1):
        self.correct = correct
        self.max_step = max_step
        self.max_turn = max_turn

    def predict(self, cur, h):
        t = cur.t
        ok, u1, _, g1, data, its = self.correct(cur.u + h * t, t, h)
        if not ok:
            return None
        t1 = perp(g1)
        if t1 @ t < 0:
            t1 = -t1
        turn = math.acos(min(1.0, max(-1.0, float(t1 @ t))))
        return CurvePoint(u1, g1, t1, data, its, turn)

    def accept(self, cur, new, h) -> bool:
        step = float(np.linalg.norm(new.u - cur.u))
        return new.turn <= self.max_turn and 0.2 * h < step < 1.6 * h

    def next_step(self, h, cur, new) -> float:
        if new.iterations <= 3 and new.turn < self.max_turn / 3:
            return min(1.5 * h, self.max_step)
        return h


def _follow_stepper(first, stepper, options, detect):
    """:func:`follow_path` with a :class:`Stepper`: the same returns."""
    step, min_step, max_step, max_steps = (options.step, options.min_step, options.max_step,
                                           options.max_steps)
    pts = [first]
    evs = []
    rejected = 0
    h = min(step, max_step)
    for _ in range(max_steps):
        cur = pts[-1]
        new = None
        while h >= min_step:      # halvings: bounded by min_step
            cand = stepper.predict(cur, h)
            if cand is not None and stepper.accept(cur, cand, h):
                new = cand
                break
            rejected += 1
            h *= 0.5
        if new is None:
            why = "no accepted point at the smallest step"
            return pts, evs, f"step below min_step = {min_step:g}: {why}", rejected, why
        if detect is not None:
            found, end = detect(cur, new, len(pts) - 1)
            evs.extend(found)
            if end is not None:
                if end[0] is not None:
                    pts.append(end[0])
                return pts, evs, end[1], rejected, ""
        pts.append(new)
        h = stepper.next_step(h, cur, new)
    return pts, evs, f"max_steps = {max_steps} reached", rejected, ""


def illinois(evaluate, ftest, fa, fb, pa, pb, *, size, tol, max_iter, ftol=0.0,
             bisect_every=3):
    """Root of ``ftest(evaluate(theta))`` on ``[0, 1]`` with ``f(0) = fa``, ``f(1) = fb``:
    the package's one bracketing root step (Illinois, a safeguarded regula falsi).

    ``evaluate(theta)`` returns a point or None (then the bracket is bisected instead).
    ``size`` converts a ``theta`` interval to a length (stop below ``tol``); a point with
    ``|f| < ftol`` is also a root. Every ``bisect_every``-th step bisects (0: never), which
    keeps the bracket shrinking where the test function is not smooth; a smooth one (a
    boundary tracer's) converges in fewer evaluations without. Returns ``(point, f,
    located)`` with the best bracket end; ``pa``, ``pb`` are the end points.
    """
    a, b = 0.0, 1.0
    side = 0
    best = (pa, fa) if abs(fa) <= abs(fb) else (pb, fb)
    for it in range(max_iter):
        if (b - a) * size <= tol:
            return best[0], best[1], True
        theta = b - fb * (b - a) / (fb - fa) if fb != fa else 0.5 * (a + b)
        # keep the regula-falsi point inside the bracket and bisect every third iteration so
        # that the bracket shrinks geometrically even when the test function is not smooth
        if not (a < theta < b) or (bisect_every and it % bisect_every == bisect_every - 1):
            theta = 0.5 * (a + b)
        pt = evaluate(theta)
        fc = ftest(pt) if pt is not None else np.nan
        if not np.isfinite(fc):
            theta = 0.5 * (a + b)
            pt = evaluate(theta)
            fc = ftest(pt) if pt is not None else np.nan
            if not np.isfinite(fc):
                return best[0], best[1], False
        if abs(fc) < abs(best[1]):
            best = (pt, fc)
        if fc == 0.0 or abs(fc) < ftol:
            return pt, fc, True
        a, b, fa, fb, side = (float(v) for v in _illinois_update(a, b, fa, fb, side, theta, fc))
    return best[0], best[1], (b - a) * size <= tol


def _illinois_update(a, b, fa, fb, side, theta, fc):
    """The Illinois bracket update at ``theta`` with test value ``fc`` (scalars or arrays): the
    new point replaces the end of its sign, and the value kept at the other end is halved when
    that end was kept twice running (``side``: +1 the last point replaced ``b``, -1 ``a``)."""
    right = (fc > 0) == (fb > 0)
    fa = np.where(right & (side == 1), 0.5 * fa, fa)
    fb = np.where(~right & (side == -1), 0.5 * fb, fb)
    return (np.where(right, a, theta), np.where(right, theta, b), np.where(right, fa, fc),
            np.where(right, fc, fb), np.where(right, 1, -1))


def illinois_many(ftest, fa, fb, *, tol, max_iter):
    """:func:`illinois` on many brackets at once (the same update, no bisection steps).

    ``ftest(theta, active)`` gives the test values at ``theta[active]`` (one vectorised
    evaluation per iteration); ``fa``, ``fb`` (shape ``(K,)``) at ``theta = 0`` and 1. A bracket
    stops below width ``tol`` or where a value is not finite. Returns ``(theta, bad)``: the
    midpoints of the final brackets and where a value was not finite.

    Examples
    --------
    >>> c = np.array([0.25, 0.5])
    >>> th, bad = illinois_many(lambda th, act: th[act] ** 2 - c[act], -c, 1 - c, tol=1e-12,
    ...                         max_iter=60)
    >>> np.round(th, 10).tolist(), bad.tolist()
    ([0.5, 0.7071067812], [False, False])
    """
    fa, fb = np.array(fa, float), np.array(fb, float)
    K = len(fa)
    a, b = np.zeros(K), np.ones(K)
    side = np.zeros(K, int)
    bad = np.zeros(K, bool)
    for _ in range(max_iter):
        act = ~bad & (b - a > tol)
        if not act.any():
            break
        with np.errstate(all="ignore"):
            th = b - fb * (b - a) / (fb - fa)
        th = np.where((th > a) & (th < b), th, 0.5 * (a + b))
        fm = np.full(K, np.nan)
        fm[act] = ftest(th, act)
        bad |= act & ~np.isfinite(fm)
        act &= np.isfinite(fm)
        na, nb, nfa, nfb, nside = _illinois_update(a, b, fa, fb, side, th, fm)
        a, b = np.where(act, na, a), np.where(act, nb, b)
        fa, fb = np.where(act, nfa, fa), np.where(act, nfb, fb)
        side = np.where(act, nside, side)
    return 0.5 * (a + b), bad


def bisect_predicate(evaluate, same_as_a, pa, pb, *, size, tol, max_iter):
    """Bisection on a discrete change: returns the last point on each side and ``located``."""
    a, b = 0.0, 1.0
    last_a, last_b = pa, pb
    for _ in range(max_iter):
        if (b - a) * size <= tol:
            return last_a, last_b, True
        theta = 0.5 * (a + b)
        pt = evaluate(theta)
        if pt is None:
            return last_a, last_b, False
        if same_as_a(pt):
            a, last_a = theta, pt
        else:
            b, last_b = theta, pt
    return last_a, last_b, (b - a) * size <= tol
