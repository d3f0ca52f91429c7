"""One-parameter continuation of periodic orbits of the impact map of any hybrid automaton.

A *model builder* ``builder(p)`` returns, for a parameter value ``p``, the model: a
:class:`~hybridpd.analysis.hybridmap.SectionMap`, a
:class:`~hybridpd.analysis.hybridmap.Section`, or a
:class:`~hybridpd.hybrid.automaton.HybridAutomaton` (or any object with an ``automaton``
attribute, e.g. a mechanical automaton) together with ``section=dict(mode=..., guard=...,
...)`` (keyword arguments of :class:`Section`). Any parameter of any model can therefore be
followed: a gain, a clearance, a restitution coefficient, a sampling period, a forcing
amplitude. The section dimension must not change along the family.

:func:`continue_family` follows a fixed point of ``P^k`` from ``(s0, p0)``:

* ``method="natural"``: ``p`` steps by ``step``; secant predictor on ``s``; Newton on ``s``
  (:func:`~hybridpd.analysis.periodic.find_orbit`);
* ``method="arclength"`` (pseudo-arclength): unknowns ``u = (s, p)``; tangent = null vector
  of ``[DP^k - I, dF/dp]`` (``dF/dp`` by central differences of the map in ``p``), Newton on
  ``F(u) = 0`` plus the arclength condition; passes folds.

Step sizes halve on a failed correction (bounded number of halvings) and grow after easy
ones. At every accepted point the Floquet multipliers (eigenvalues of ``DP^k``), spectral
radius and impact sequence are recorded; between consecutive points the events below are
detected by sign changes of test functions, and located by Illinois (safeguarded regula
falsi) iterations on the test function along the branch (points on hyperplanes normal to the
chord, corrected like arclength steps); ``locate=False`` keeps a linear interpolation:

=====================  =====================================================================
``fold``               ``det(DP - I)`` changes sign (a real multiplier crosses +1; a fold
                       when ``p`` turns back, else a branch point)
``period_doubling``    ``det(DP + I)`` changes sign (a real multiplier crosses -1)
``neimark_sacker``     the number of non-real multipliers outside the unit circle changes
``stability_change``   the spectral radius crosses 1
``sequence_change``    the impact sequence of one period changes (grazing, sticking, ...)
=====================  =====================================================================
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hybridpd._repr import compact_repr
from hybridpd.analysis.floquet import stability
from hybridpd.analysis.hybridmap import Section, SectionMap
from hybridpd.analysis.periodic import find_orbit

__all__ = ["FAMILY_EVENTS", "FamilyBranch", "FamilyEvent", "FamilyPoint", "continue_family"]

#: Kinds of :class:`FamilyEvent`.
FAMILY_EVENTS = ("fold", "period_doubling", "neimark_sacker", "stability_change",
                 "sequence_change")
_NONREAL = 1e-9


@dataclass(frozen=True, eq=False)
class FamilyPoint:
    """One accepted point of a family: parameter ``p``, fixed point ``s`` and its stability."""

    p: float
    s: np.ndarray
    DP: np.ndarray = field(repr=False)
    multipliers: np.ndarray
    spectral_radius: float
    stable: bool
    signature: tuple
    t_period: float
    __repr__ = compact_repr


@dataclass(frozen=True)
class FamilyEvent:
    """An event between points ``index`` and ``index + 1``, located at ``p`` (estimate)."""

    kind: str
    index: int
    p: float
    detail: str = ""
    __repr__ = compact_repr

    def to_dict(self) -> dict:
        return {"kind": self.kind, "index": self.index, "p": float(self.p),
                "detail": self.detail}


@dataclass(frozen=True, eq=False)
class FamilyBranch:
    """Result of :func:`continue_family`.

    Attributes
    ----------
    points : list of FamilyPoint
    events : list of FamilyEvent
    termination : str
        ``"reached"`` (the end value), ``"max_steps"``, ``"min_step"`` (the corrector failed at
        the smallest step), ``"turned back: left the parameter range"`` (after a fold), or
        ``"start failed: <reason>"``.
    method : str
    period : int
    """

    points: list
    events: list
    termination: str
    method: str
    period: int
    __repr__ = compact_repr

    @property
    def p(self) -> np.ndarray:
        return np.array([q.p for q in self.points])

    @property
    def spectral_radius(self) -> np.ndarray:
        return np.array([q.spectral_radius for q in self.points])

    def events_of(self, kind: str) -> list:
        return [e for e in self.events if e.kind == kind]

    def to_dict(self) -> dict:
        return {"p": self.p.tolist(), "spectral_radius": self.spectral_radius.tolist(),
                "stable": [bool(q.stable) for q in self.points],
                "events": [e.to_dict() for e in self.events], "termination": self.termination,
                "method": self.method, "period": self.period}


def _map_factory(builder, section, map_options):
    cache = {}   # the last few maps (corrector and parameter derivative revisit them)

    def make(p) -> SectionMap:
        p = p if isinstance(p, tuple) else float(p)     # tuples: several parameters
        if p in cache:
            return cache[p]
        if len(cache) >= 8:
            cache.pop(next(iter(cache)))
        cache[p] = _build(p)
        return cache[p]

    def _build(p) -> SectionMap:
        m = builder(p)
        if isinstance(m, SectionMap):
            return m
        if not isinstance(m, Section):
            ha = getattr(m, "automaton", m)
            if section is None:
                raise ValueError("builder returned an automaton: give section=dict(mode=..., "
                                 "guard=..., ...)")
            m = Section(ha, **section)
        return SectionMap(m, **map_options)
    return make


def _point(P: SectionMap, s, p, k) -> FamilyPoint:
    r = P.apply(s, k, jacobian=True)
    st = stability(r.DP) if np.all(np.isfinite(r.DP)) else None
    if st is None:
        nan = np.full(P.dim, np.nan + 0j)
        return FamilyPoint(float(p), s.copy(), r.DP, nan, math.nan, False, r.signature,
                           r.t_hit - r.t_start)
    return FamilyPoint(float(p), s.copy(), r.DP, st.multipliers, st.spectral_radius,
                       bool(st.stable), r.signature, r.t_hit - r.t_start)


def _tests(pt: FamilyPoint) -> dict:
    I = np.eye(pt.DP.shape[0])
    m = pt.multipliers
    nonreal_out = int(np.sum((np.abs(m.imag) > _NONREAL * np.maximum(1, np.abs(m)))
                             & (np.abs(m) > 1)))
    return {"fold": float(np.linalg.det(pt.DP - I)),
            "period_doubling": float(np.linalg.det(pt.DP + I)),
            "neimark_sacker": nonreal_out, "stability_change": pt.spectral_radius - 1.0}


def _events(a: FamilyPoint, b: FamilyPoint, index: int) -> list:
    ta, tb = _tests(a), _tests(b)
    out = []

    def lin(fa, fb):
        th = fa / (fa - fb) if fa != fb else 0.5
        return a.p + th * (b.p - a.p)

    for kind in ("fold", "period_doubling", "stability_change"):
        fa, fb = ta[kind], tb[kind]
        if np.isfinite(fa) and np.isfinite(fb) and fa * fb < 0:
            out.append(FamilyEvent(kind, index, lin(fa, fb)))
    if ta["neimark_sacker"] != tb["neimark_sacker"]:
        def ns(pt):   # |lambda| - 1 of the non-real multiplier nearest the circle
            m = pt.multipliers[np.abs(pt.multipliers.imag) > _NONREAL]
            return float(np.min(np.abs(m)) - 1.0) if m.size else math.nan
        fa, fb = ns(a), ns(b)
        pe = lin(fa, fb) if np.isfinite(fa) and np.isfinite(fb) else 0.5 * (a.p + b.p)
        out.append(FamilyEvent("neimark_sacker", index, pe,
                               f"complex multipliers outside: {ta['neimark_sacker']} -> "
                               f"{tb['neimark_sacker']}"))
    if a.signature != b.signature:
        out.append(FamilyEvent("sequence_change", index, 0.5 * (a.p + b.p),
                               f"{len(a.signature)} -> {len(b.signature)} jumps per period"))
    return out


def continue_family(builder, s0, p0: float, p_end: float, *, period: int = 1, section=None,
                    method: str = "arclength", step: float | None = None,
                    max_step: float | None = None, min_step: float | None = None,
                    max_steps: int = 200, tol: float = 1e-10, fd_step: float = 1e-6,
                    locate: bool = True, map_options: dict | None = None) -> FamilyBranch:
    """Follow a fixed point of ``P^k`` in the parameter of a model builder.

    Parameters
    ----------
    builder : callable
        ``p -> SectionMap | Section | automaton`` (module docstring).
    s0 : array_like
        Guess of the fixed point at ``p0`` (corrected first).
    p0, p_end : float
        Start and end of the parameter range.
    period : int
        ``k``.
    section : dict, optional
        Keyword arguments of :class:`Section` when ``builder`` returns an automaton.
    method : {"arclength", "natural"}
    step, max_step, min_step : float, optional
        Initial, largest and smallest step (in ``p`` for natural continuation, in arclength of
        ``(s, p)`` otherwise); defaults ``|p_end - p0| / 20``, ``/ 5`` and ``/ 1e5`` (widened to
        include ``step``).
    max_steps : int
        Bound on accepted points.
    tol : float
        Newton tolerance (residual relative to ``max(1, |s|)``).
    fd_step : float
        Relative step of the parameter derivative (arclength).
    locate : bool
        Refine fold, period-doubling, Neimark-Sacker and stability-change events by Illinois
        iterations on their test function along the branch (otherwise: linear interpolation).
    map_options : dict, optional
        Keyword arguments of :class:`SectionMap` (``t_max``, ``max_jumps``, ...).

    Returns
    -------
    FamilyBranch

    Raises
    ------
    ValueError
        If a parameter is out of range, ``section`` is missing for an automaton builder, or
        ``method`` is unknown.

    Examples
    --------
    A forced oscillator against a stop, its impacting orbit followed in the forcing
    frequency:

    >>> import hybridpd as hp
    >>> from hybridpd.hybrid.samples import impact_oscillator, oscillator_initial_state
    >>> def build(w):
    ...     return impact_oscillator(omega0=1.0, zeta=0.1, omega=w, stop=1.0, e=0.8)
    >>> sec = {"mode": "free", "guard": "impact",
    ...        "reference": (oscillator_initial_state(0, 0, omega=0.8), 0.0)}
    >>> br = hp.continue_family(build, [7.7, 1.66], 0.8, 0.82, section=sec, step=0.01)
    >>> br.termination, round(br.points[-1].p, 6), bool(br.points[-1].stable)
    ('reached', 0.82, True)
    """
    if method not in ("arclength", "natural"):
        raise ValueError(f"method must be 'arclength' or 'natural', got {method!r}")
    p0, p_end = float(p0), float(p_end)
    if not (math.isfinite(p0) and math.isfinite(p_end)) or p0 == p_end:
        raise ValueError(f"p0 and p_end must be finite and differ, got {p0!r}, {p_end!r}")
    span = abs(p_end - p0)
    step = span / 20 if step is None else float(step)
    max_step = max(span / 5, step) if max_step is None else float(max_step)
    min_step = min(span / 1e5, step) if min_step is None else float(min_step)
    if not (0 < min_step <= step <= max_step):
        raise ValueError("steps must satisfy 0 < min_step <= step <= max_step")
    if int(max_steps) < 1:
        raise ValueError(f"max_steps must be >= 1, got {max_steps!r}")
    k = int(period)
    make = _map_factory(builder, section, dict(map_options or {}))
    P = make(p0)
    first = find_orbit(P, s0, k, tol=tol)
    if not first.converged:
        return FamilyBranch([], [], f"start failed: {first.reason}", method, k)
    pts = [_point(P, first.s, p0, k)]
    sgn = 1.0 if p_end > p0 else -1.0
    run = _natural if method == "natural" else _arclength
    termination = run(make, pts, sgn, p_end, k, step, max_step, min_step, int(max_steps), tol,
                      fd_step * max(1.0, abs(p0)))
    events = []
    for i in range(len(pts) - 1):
        for ev in _events(pts[i], pts[i + 1], i):
            if locate and ev.kind in _TESTS:
                ev = _locate(make, pts[i], pts[i + 1], ev, k, tol, fd_step * max(1.0, abs(p0)))
            events.append(ev)
    return FamilyBranch(pts, events, termination, method, k)


def _ns_test(pt):
    m = pt.multipliers[np.abs(pt.multipliers.imag) > _NONREAL]
    return float(np.min(np.abs(m)) - 1.0) if m.size else math.nan


_TESTS = {"fold": lambda pt: float(np.linalg.det(pt.DP - np.eye(pt.DP.shape[0]))),
          "period_doubling": lambda pt: float(np.linalg.det(pt.DP + np.eye(pt.DP.shape[0]))),
          "stability_change": lambda pt: pt.spectral_radius - 1.0,
          "neimark_sacker": _ns_test}


def _locate(make, a, b, ev, k, tol, hp, max_iter=40) -> FamilyEvent:
    """Illinois iterations on the test function along the branch between ``a`` and ``b``.

    A point at chord fraction ``theta`` is the branch point on the hyperplane through
    ``ua + theta (ub - ua)`` normal to the chord (the arclength corrector).
    """
    f = _TESTS[ev.kind]
    ua, ub = np.append(a.s, a.p), np.append(b.s, b.p)
    chord = ub - ua
    chord[:-1] = make(a.p).section.wrap(chord[:-1])
    n = chord / np.linalg.norm(chord)
    t0, t1, f0, f1 = 0.0, 1.0, f(a), f(b)
    if not (np.isfinite(f0) and np.isfinite(f1) and f0 * f1 < 0):
        return ev
    side = 0
    best = None
    for _ in range(max_iter):
        th = t0 - f0 * (t1 - t0) / (f1 - f0)
        u, _its, ok = _correct(make, ua + th * chord, n, k, tol, hp)
        if not ok:
            break
        pt = _point(make(u[-1]), u[:-1], u[-1], k)
        fv = f(pt)
        best = pt
        if not np.isfinite(fv) or abs(t1 - t0) < 1e-12 or fv == 0.0:
            break
        if fv * f1 < 0:
            t0, f0 = t1, f1
            t1, f1 = th, fv
            side = 0
        else:
            t1, f1 = th, fv
            if side == 1:
                f0 *= 0.5
            side = 1
        if abs(fv) < 1e-13:
            break
    if best is None:
        return ev
    return FamilyEvent(ev.kind, ev.index, best.p, (ev.detail + "; " if ev.detail else "")
                       + f"located: test {f(best):.3g}")


def _natural(make, pts, sgn, p_end, k, step, max_step, min_step, max_steps, tol, _h):
    h = step
    while len(pts) < max_steps:
        a = pts[-1]
        if sgn * (p_end - a.p) <= 0:
            return "reached"
        h = min(h, abs(p_end - a.p))
        p = a.p + sgn * h
        P = make(p)
        guess = a.s.copy()
        if len(pts) > 1:   # secant predictor
            b = pts[-2]
            guess = a.s + (p - a.p) / (a.p - b.p) * P.section.wrap(a.s - b.s)
        orb = find_orbit(P, guess, k, tol=tol, max_iter=12)
        if not orb.converged or orb.signature[:1] != a.signature[:1]:
            h *= 0.5
            if h < min_step:
                return "min_step"
            continue
        pts.append(_point(P, orb.s, p, k))
        h = min(1.3 * h, max_step) if orb.iterations <= 4 else h
    return "max_steps"


def _arclength(make, pts, sgn, p_end, k, step, max_step, min_step, max_steps, tol, hp):
    d = pts[0].s.size
    tan = None
    h = step
    while len(pts) < max_steps:
        a = pts[-1]
        if sgn * (p_end - a.p) <= 0:
            return "reached"
        P = make(a.p)
        Fp = P.section.wrap(make(a.p + hp)(a.s, k) - make(a.p - hp)(a.s, k)) / (2 * hp)
        Jm = np.hstack([a.DP - np.eye(d), Fp[:, None]])
        t = np.linalg.svd(Jm)[2][-1]
        if tan is None:
            if t[-1] * sgn < 0:
                t = -t
        elif t @ tan < 0:
            t = -t
        ua = np.append(a.s, a.p)
        ok = False
        while h >= min_step:
            up = ua + h * t
            u, its, ok = _correct(make, up, t, k, tol, hp)
            if ok:
                new = _point(make(u[-1]), u[:-1], u[-1], k)
                # a changed impact sequence is accepted only at a small step (it is real)
                if new.signature == a.signature or h < 16 * min_step:
                    break
            ok = False
            h *= 0.5
        if not ok:
            return "min_step"
        if sgn * (u[-1] - p_end) > 0 and sgn * (p_end - a.p) > 0 and \
                sgn * (u[-1] - a.p) > 0:
            # overshoot the end: finish with one natural step onto p_end
            P = make(p_end)
            orb = find_orbit(P, u[:-1], k, tol=tol, max_iter=12)
            if orb.converged:
                pts.append(_point(P, orb.s, p_end, k))
                return "reached"
        pts.append(new)
        tan = t
        lo, hi = sorted((pts[0].p, p_end))
        if not lo - 1e-9 * (hi - lo) <= new.p <= hi + 1e-9 * (hi - lo):
            return "turned back: left the parameter range"   # after a fold
        h = min(1.3 * h, max_step) if its <= 4 else h
    return "max_steps"


def _correct(make, up, t, k, tol, hp):
    """Newton on ``[P^k(s; p) - s; t . (u - up)] = 0``; returns ``(u, iterations, ok)``."""
    u = up.copy()
    d = u.size - 1
    for it in range(1, 16):
        P = make(u[-1])
        r = P.apply(u[:-1], k, jacobian=True)
        if not r.ok or not np.all(np.isfinite(r.DP)):
            return u, it, False
        F = P.section.wrap(r.s - u[:-1])
        du0 = u - up
        du0[:-1] = P.section.wrap(du0[:-1])
        g = float(t @ du0)
        if np.max(np.abs(F)) <= tol * max(1.0, np.max(np.abs(u[:-1]))) and abs(g) < 1e-12:
            return u, it, True
        try:
            Fp = P.section.wrap(make(u[-1] + hp)(u[:-1], k) - make(u[-1] - hp)(u[:-1], k)) / (
                2 * hp)
        except RuntimeError:
            return u, it, False
        J = np.vstack([np.hstack([r.DP - np.eye(d), Fp[:, None]]), t[None, :]])
        try:
            du = -np.linalg.solve(J, np.append(F, g))
        except np.linalg.LinAlgError:
            return u, it, False
        u = u + du
        if P.section.has_phase:
            u[0] %= P.section.period
    return u, 16, False
