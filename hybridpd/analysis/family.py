"""A one-parameter family of maps and its continuation rules: what
:func:`~hybridpd.analysis.continuation.continue_orbit` reads of a family.

A :class:`ParameterFamily` is callable, ``p -> PoincareMap``, and declares, with the general
rules as defaults, everything in which one family's continuation differs from another's: its
domain (:meth:`ParameterFamily.at` is None outside it), default step sizes, Newton bounds and
scale, how the starting orbit is found, how ``dF/dp`` is taken (:func:`parameter_gradient`,
with the step fixed at the start or taken at the current point), what an accepted point
carries, its own events and how the followed points become a
:class:`~hybridpd.analysis.branch.Branch` (:meth:`ParameterFamily.finish`). A map names its
families through its hook :meth:`~hybridpd.analysis.maps.PoincareMap.family` (the impact pair's
``ImpactMap.family("kv")`` overrides these rules with its own); a plain builder ``p -> map`` is
wrapped in the general family.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from hybridpd.analysis.branch import EVENT_KINDS, BifurcationEvent, Branch, BranchPoint
from hybridpd.analysis.fd import difference_quotients
from hybridpd.analysis.floquet import stability
from hybridpd.analysis.maps import PoincareMap
from hybridpd.analysis.pathfollow import bisect_predicate
from hybridpd.analysis.periodic import PeriodicOrbit, find_orbit

__all__ = ["ParameterFamily", "PathRun", "map_residual", "parameter_gradient",
           "sequence_change"]


def map_residual(P: PoincareMap, s: np.ndarray, k: int):
    """``P^k(s) - s`` (phase wrapped), or None where ``P^k`` is undefined at ``s``."""
    img, ok = P.apply_many(s[None, :], k)
    if not ok[0]:
        return None
    return P.wrap(img[0] - s)


def parameter_gradient(at: Callable, P: PoincareMap, s: np.ndarray, k: int, p: float,
                       h: float) -> np.ndarray:
    """``d(P^k(s) - s)/dp`` at the map ``P`` (parameter ``p``) by the one finite-difference
    rule (:mod:`hybridpd.analysis.fd`) with step ``h``: central, one-sided where the family has
    no map (``at(q)`` is None) or ``P^k`` is undefined on one side. Shape ``(dim,)``;
    ``RuntimeError`` where it is undefined on both sides."""
    vals = []
    for q in (p + h, p - h):
        Q = at(q)
        vals.append(None if Q is None else map_residual(Q, s, k))
    ok = [v is not None for v in vals]
    # the centre only where a side is missing: it costs one more application of P^k
    r0 = None if all(ok) else map_residual(P, s, k)
    if r0 is None and not all(ok):
        raise RuntimeError("P^k undefined at the point")
    plus, minus = (v[None] if v is not None else np.full((1, P.dim), np.nan) for v in vals)
    masks = {} if all(ok) else dict(ok_plus=np.array(ok[:1]), ok_minus=np.array(ok[1:]))
    d, defined = difference_quotients(plus, minus, np.array([h]), r0, wrap=P.wrap, **masks)
    if not defined[0]:
        raise RuntimeError(f"P^k undefined on both sides of p = {p:g}")
    return d[0]


def sequence_change(pa, pb, evaluate, *, locate, tol, max_iter=60):
    """Where the jump sequence of one period changes between two branch points: the last
    point on each side (bisection on the sequence, when ``locate``) and whether it converged.
    """
    if not locate:
        return pa, pb, False
    return bisect_predicate(lambda th: evaluate(pa, pb, th),
                            lambda pt: pt.signature == pa.signature, pa, pb,
                            size=float(np.linalg.norm(pb.u - pa.u)), tol=tol,
                            max_iter=max_iter)


@dataclass(eq=False)
class PathPoint:
    """A point of the path as the engine sees it: ``u = (s, p)``, ``DP``, ``dF/dp`` and the
    family point ``fam`` (the general rule's accepted point)."""

    u: np.ndarray
    DP: np.ndarray
    Fp: np.ndarray | None
    fam: BranchPoint
    formal = True         # the multipliers mean what they say at every point

    mult = property(lambda self: self.fam.multipliers)
    rho = property(lambda self: self.fam.spectral_radius)
    signature = property(lambda self: self.fam.signature)


@dataclass(frozen=True)
class PathRun:
    """What the engine hands :meth:`ParameterFamily.finish`: the followed points and events,
    the path follower's termination (``"reached stop"``, ``"max_steps = ..."``, ``"step below
    min_step ...: <why>"``, ``"turned back: left the parameter range"``), the rejected
    attempts and, when the step fell below ``min_step``, why (``stuck``); the run's settings
    (``p0``, ``p_end``, ``period``, ``method``, ``max_steps``, ``kinds``) and the map at
    ``p0``."""

    points: list
    events: list
    termination: str
    rejected: int
    stuck: str
    p0: float
    p_end: float
    period: int
    method: str
    max_steps: int
    kinds: tuple
    map: PoincareMap

    @property
    def range(self) -> tuple:
        """``(lo, hi)`` of the parameter range."""
        return min(self.p0, self.p_end), max(self.p0, self.p_end)


@dataclass(frozen=True, eq=False)
class ParameterFamily:
    """The maps ``p -> build(p)`` of one named parameter, with the rules of its continuation.

    The defaults are the general rules of
    :func:`~hybridpd.analysis.continuation.continue_orbit`; a map's family (e.g. the impact
    pair's :meth:`~hybridpd.pair.impactmap.ImpactMap.family`) overrides those that differ.

    Attributes
    ----------
    name : str
        The parameter's name (in messages and on the branch).
    value : float
        Its value at the map the family was made from (NaN for a plain builder).
    build : callable
        ``p -> PoincareMap``.
    fd_step : float
        Relative step of ``dF/dp`` (:func:`parameter_gradient`).
    max_iter, max_steps : int
        Default Newton bound of the corrector and bound on accepted points.
    grow : float
        Step growth after an easy correction.
    range_slack : float
        Relative slack of the parameter range (beyond it the branch has turned back).
    kinds : tuple of str
        The event kinds the family detects (the default of ``events``).
    gradient_step : {"start", "point"}
        ``dF/dp`` with the step of the starting value, or of the current point's.
    dp_in_residual : bool
        The residual is defined only where ``DP`` is (keeps Newton off points where the map
        has no Jacobian, e.g. a section map at grazing); else it needs ``P^k`` alone.
    explains : bool
        Name why the map was undefined in the termination and the corrector's failures.

    Examples
    --------
    >>> import hybridpd as hp
    >>> class Logistic(hp.PoincareMap):
    ...     names = ("x",)
    ...     def __init__(self, r):
    ...         self.r = r
    ...     def apply(self, s, k=1, jacobian=False):
    ...         x, J = s[0], 1.0
    ...         for _ in range(k):
    ...             J, x = self.r * (1 - 2 * x) * J, self.r * x * (1 - x)
    ...         return hp.MapResult(np.array([x]), DP=np.array([[J]]) if jacobian else None)
    >>> fam = ParameterFamily("r", 2.5, Logistic)
    >>> fam(2.8).r, fam.steps(1.0)
    (2.8, (0.05, 0.2, 1e-05))
    """

    name: str
    value: float
    build: Callable
    fd_step: float = 1e-6
    max_iter: ClassVar[int] = 15
    max_steps: ClassVar[int] = 200
    grow: ClassVar[float] = 1.3
    range_slack: ClassVar[float] = 1e-9
    kinds: ClassVar[tuple] = EVENT_KINDS
    gradient_step: ClassVar[str] = "start"
    dp_in_residual: ClassVar[bool] = True
    explains: ClassVar[bool] = True

    def __call__(self, p) -> PoincareMap:
        """The map at ``p``; ``ValueError`` where the family has none."""
        m = self.at(p)
        if m is None:
            raise ValueError(f"{self.name} = {p:g}: the family has no map there")
        return m

    def at(self, p) -> PoincareMap | None:
        """The map at ``p``, or None outside the family's domain."""
        return self.build(p)

    def value_of(self, P: PoincareMap, p: float) -> float:
        """The parameter value of the map ``P`` built at ``p`` (``p`` itself by default)."""
        del P
        return p

    def steps(self, span: float) -> tuple:
        """Default ``(step, max_step, min_step)`` of a range of length ``span``."""
        return span / 20, span / 5, span / 1e5

    def check_range(self, p0: float, p_end: float) -> None:
        """``ValueError`` where the range leaves the family's domain (no check by default)."""

    def start(self, P: PoincareMap, s0, k: int, tol: float, max_iter: int) -> PeriodicOrbit:
        """The orbit the continuation starts from (Newton from ``s0``)."""
        del max_iter
        return find_orbit(P, s0, k, tol=tol)

    def scale(self, x: np.ndarray, dim: int) -> float:
        """The scale of the corrector's tolerance at ``x`` (``s`` or ``(s, p)``)."""
        return max(1.0, float(np.max(np.abs(x[:dim]))))

    def gradient(self, P: PoincareMap, s, k: int, p: float, *, at=None,
                 p_ref: float | None = None) -> np.ndarray:
        """``dF/dp`` at the map ``P`` built at ``p`` (:func:`parameter_gradient`), the step
        ``fd_step * max(1, |p_ref|)`` (default ``p_ref``: the map's own value); ``at``: the
        family's maps (default :meth:`at`)."""
        p = self.value_of(P, p)
        h = self.fd_step * max(1.0, abs(p if p_ref is None else p_ref))
        return parameter_gradient(self.at if at is None else at, P, s, k, p, h)

    def point(self, P: PoincareMap, u: np.ndarray, k: int, iterations: int, result,
              DP: np.ndarray, gradient: Callable):
        """The accepted point at ``u`` of ``P^k`` (``iterations``: the corrector's Newton
        steps; ``result``: the application of ``P^k`` there, ``DP`` its Jacobian,
        ``gradient()`` ``dF/dp`` or None); None refuses it."""
        del k, iterations
        s = P.canonical(u[:-1].copy())
        st = stability(DP, structural_zeros=P.structural_zeros)
        fam = BranchPoint(float(u[-1]), s, DP, st.multipliers, st.spectral_radius,
                          bool(st.stable), result.signature, result.t_hit - result.t_start)
        return PathPoint(u.copy(), DP, gradient(), fam)

    def to_event(self, kind, pt, index, detail, test_value, located) -> BifurcationEvent:
        """The event of ``kind`` at the point ``pt``."""
        return BifurcationEvent(kind, index, float(pt.u[-1]), detail, pt.fam.s.copy(),
                                pt.mult.copy(), float(test_value), bool(located))

    def extra_events(self, pa, pb, index, evaluate, *, kinds, locate, tol) -> list:
        """The family's own events between two points (``evaluate(pa, pb, theta)``: the
        corrected point between them): a change of the jump sequence by default."""
        if "sequence_change" not in kinds or pa.signature == pb.signature:
            return []
        _la, lb, ok = sequence_change(pa, pb, evaluate, locate=locate, tol=tol)
        return [self.to_event("sequence_change", lb, index,
                              f"{len(pa.signature)} -> {len(pb.signature)} jumps per period",
                              math.nan, ok)]

    def nonsmooth(self, pt) -> bool:
        """The point lies next to a nonsmooth point (no fold is read from a turn there)."""
        del pt
        return False

    def start_failed(self, P: PoincareMap, k: int, method: str, p0: float,
                     orbit: PeriodicOrbit | None) -> Branch:
        """The empty branch of a start that failed (``orbit``: Newton's failed result, or None
        when the map has no Jacobian at the orbit found)."""
        reason = "Jacobian undefined at the initial point" if orbit is None else orbit.reason
        detail = f" ({orbit.detail})" if orbit is not None and orbit.detail else ""
        return Branch.from_points([], [], f"start failed: {reason}", method, k,
                                  f"no fixed point of P^{k} at p = {p0:.10g} to start from: "
                                  f"{reason}{detail}", dim=P.dim)

    def finish(self, run: PathRun) -> Branch:
        """The branch of a followed path: short terminations, the reason in words."""
        lo, hi = run.range
        termination = run.termination
        reason = _reason(termination, run.points[-1].u[-1], run.p_end, lo, hi, run.max_steps)
        for key, short in (("reached", "reached"), ("max_steps", "max_steps"),
                           ("step below", "min_step")):
            termination = short if termination.startswith(key) else termination
        return Branch.from_points([q.fam for q in run.points], run.events, termination,
                                  run.method, run.period, reason, dim=run.map.dim)


def _reason(termination: str, p_last: float, p_end: float, lo: float, hi: float,
            max_steps: int) -> str:
    """The path follower's `termination` as a sentence that names where the branch ended."""
    if termination.startswith("reached"):
        return f"reached the end value p = {p_end:.10g}"
    if termination.startswith("max_steps"):
        return f"max_steps = {max_steps} accepted points reached at p = {p_last:.10g}"
    if termination.startswith("turned back"):
        return (f"{termination} [{lo:.10g}, {hi:.10g}] at p = {p_last:.10g} (the branch "
                "passed a fold)")
    return termination
