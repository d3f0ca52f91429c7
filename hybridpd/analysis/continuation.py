"""The one continuation engine: one-parameter families of periodic orbits of any map.

A *model builder* ``builder(p)`` returns, for a parameter value ``p``, the model: a
:class:`~hybridpd.analysis.hybridmap.SectionMap`, a
:class:`~hybridpd.hybrid.section.Section`, or a
:class:`~hybridpd.hybrid.automaton.HybridAutomaton` (or any object with an ``automaton``
attribute, e.g. a mechanical automaton) together with ``section=dict(mode=..., guard=...,
...)`` (keyword arguments of :class:`Section`). Any parameter of any model can therefore be
followed: a gain, a clearance, a restitution coefficient, a sampling period, a forcing
amplitude. The section dimension must not change along the family.

:func:`continue_orbit` follows a fixed point of ``P^k`` from ``(s0, p0)`` on the package's
path-following engine (:func:`hybridpd.analysis.pathfollow.follow_path`): ``method="natural"``
(``p`` steps, secant predictor on ``s``) or ``"arclength"`` (pseudo-arclength in ``(s, p)``,
``dF/dp`` by central differences of the map in ``p``; passes folds). Step sizes halve on a
failed correction (bounded number of halvings) and grow after easy
ones. At every accepted point the Floquet multipliers (eigenvalues of ``DP^k``), spectral
radius and impact sequence are recorded; between consecutive points the one detector of
:mod:`hybridpd.analysis.bifevents` finds folds (turning points, or branch points where a
real multiplier crosses +1 while the branch goes on), period doublings, Neimark-Sacker
points and stability changes by sign changes of test functions, and locates them by Illinois
(safeguarded regula falsi) iterations along the branch (points on hyperplanes normal to the
chord, corrected like arclength steps); a ``sequence_change`` (the jump sequence of one
period changes: grazing, sticking, ...) is located by bisection on the sequence.

A map knows its named parameters through its hook ``family``, which returns a
:class:`~hybridpd.analysis.family.ParameterFamily`: the maps along the parameter and the
rules in which its continuation differs from the general one (domain, step sizes, Newton
scale, ``dF/dp``, what a point carries, its own events, its branch's variables). The impact
pair's ``ImpactMap.family("kv")`` carries the pair's rules (grazing events, flight margins,
the design path), so ``continue_orbit(P.family("kv"), 20.0, 23.0, s0)`` follows the pair's
orbits on this engine; a plain builder ``p -> map`` gets the general rules.

The result is the package's one :class:`Branch` (per-point arrays; ``branch[i]`` is a
:class:`BranchPoint`) with :class:`BifurcationEvent` (``kind``, ``index``, ``parameter``,
``detail``): the impact pair's continuations return the same class, with their own
quantities in ``variables`` and ``metadata``. Branches are saved as ``.nc`` or ``.zarr``
(:meth:`Branch.save`, :func:`load_branch`).
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from hybridpd.analysis.bifevents import EventTracker, turn_test
from hybridpd.analysis.branch import (
    EVENT_KINDS,
    BifurcationEvent,
    Branch,
    BranchPoint,
    load_branch,
)
from hybridpd.analysis.family import ParameterFamily, PathRun, map_residual
from hybridpd.analysis.hybridmap import Section, SectionMap
from hybridpd.analysis.maps import PoincareMap, minimal_period
from hybridpd.analysis.pathfollow import PathOptions, corrector, follow_path

__all__ = ["EVENT_KINDS", "BifurcationEvent", "Branch", "BranchPoint", "continue_orbit",
           "load_branch"]

#: What a :data:`~hybridpd.analysis.hybridmap.MAP_STATUS` means where the map is undefined.
_UNDEFINED = {
    "bad_start": "the flow does not cross the section at the trial point",
    "jump_limit": "more than max_jumps jumps before the return",
    "end_time": "no return to the section within t_max",
    "zeno": "an accumulation of jumps on the way",
    "nonfinite": "the state overflowed on the way",
    "step_limit": "more than max_steps flow steps before the return",
    "simultaneous": "a joint impact of several contacts on the way"}


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

    def _build(p) -> PoincareMap:
        m = builder(p)
        if isinstance(m, PoincareMap):
            return m
        if not isinstance(m, Section):
            ha = getattr(m, "automaton", m)
            if section is None:
                raise ValueError("builder returned an automaton: give section=dict(mode=..., "
                                 "guard=..., ...)")
            m = Section(ha, **section)
        return SectionMap(m, **map_options)
    return make




def follow_branch(path, first, p_end, options: PathOptions, *, scale, to_event,
                  kinds=EVENT_KINDS, extra_events=None, nonsmooth=None, out_of_range=None,
                  k=1):
    """The one continuation engine: follow a branch from ``first`` towards ``p = p_end`` and
    detect its events.

    ``path`` gives ``F(u)`` (``P^k(s) - s``, phase wrapped; None where undefined), ``Fs``,
    ``Fp``, ``point(u, iterations)`` (an accepted point with ``u``, ``DP``, ``Fp``, ``mult``,
    ``rho``, ``formal``, ``signature``; None to refuse it), ``unwrap(cur, new)``,
    ``lower_period(u)`` and ``explain()`` (None-able). The path follower is
    :func:`~hybridpd.analysis.pathfollow.follow_path`, the detector
    :class:`~hybridpd.analysis.bifevents.EventTracker` (with turning points); a family's own
    events come from ``extra_events(pa, pb, index, evaluate)`` (``evaluate(pa, pb, theta)``
    the corrected point between two points). ``options`` (a
    :class:`~hybridpd.analysis.pathfollow.PathOptions`) holds the steps, the corrector's
    tolerance and iterations and the events' location rules. Returns ``follow_path``'s
    ``(points, events, termination, rejected, why)``.
    """
    correct = corrector(path.F, path.Fs, path.Fp, tol=options.tol, max_iter=options.max_iter,
                        scale=scale, explain=path.explain)

    def evaluate(pa, pb, theta):
        chord = pb.u - pa.u
        u, res = correct(pa.u + theta * chord, chord / np.linalg.norm(chord))
        return path.point(u, res.iterations) if res.converged else None

    tracker = EventTracker(kinds, evaluate, lambda a, b: float(np.linalg.norm(b.u - a.u)),
                           options.event_tol, 60, options.locate, to_event,
                           turn_test=turn_test, nonsmooth=nonsmooth)

    def detect(a, b, i):
        return tracker.detect(a, b, i, () if extra_events is None
                              else extra_events(a, b, i, evaluate))

    return follow_path(first, p_end, options, F=path.F, Fs=path.Fs, Fp=path.Fp,
                       make_point=path.point, correct=correct, k=k,
                       lower_period=path.lower_period, unwrap=path.unwrap, detect=detect,
                       out_of_range=out_of_range, explain=path.explain)




def continue_orbit(builder, p0: float, p_end: float, s0, *, period: int | None = None,
                   section=None, method: str = "arclength", step: float | None = None,
                   max_step: float | None = None, min_step: float | None = None,
                   max_steps: int | None = None, tol: float = 1e-10,
                   max_iter: int | None = None, fd_step: float | None = None,
                   locate: bool = True, event_tol: float = 1e-9, events: tuple | None = None,
                   map_options: dict | None = None) -> Branch:
    """Follow a periodic orbit (a fixed point of ``P^k``) in a parameter, on any map.

    Parameters
    ----------
    builder : ParameterFamily or callable
        A map's family of one named parameter (``P.family("kv")``: its rules of
        continuation, :class:`~hybridpd.analysis.family.ParameterFamily`), or ``p ->
        PoincareMap`` (any map: a user's, a specialisation, a
        :class:`~hybridpd.analysis.hybridmap.SectionMap`), or ``p -> Section | automaton``
        with ``section`` (module docstring). A map class whose constructor takes the
        parameter first is a builder.
    p0, p_end : float
        Start and end of the parameter range.
    s0 : array_like, shape (dim,), or PeriodicOrbit
        Guess of the fixed point at ``p0`` (corrected first), or an orbit found there (its
        section point and period).
    period : int, optional
        ``k`` (default: the orbit's, or 1).
    section : dict, optional
        Keyword arguments of :class:`Section` when ``builder`` returns an automaton.
    method : {"arclength", "natural"}
    step, max_step, min_step : float, optional
        Initial, largest and smallest step (in ``p`` for natural continuation, in arclength of
        ``(s, p)`` otherwise); defaults the family's (:meth:`ParameterFamily.steps
        <hybridpd.analysis.family.ParameterFamily.steps>`; a builder's ``|p_end - p0| / 20``,
        ``/ 5`` and ``/ 1e5``), widened to include ``step``.
    max_steps : int, optional
        Bound on accepted points (default the family's: 200 for a builder).
    tol : float
        Newton tolerance (residual relative to the family's scale: ``max(1, |s|)`` for a
        builder).
    max_iter : int, optional
        Newton bound of the corrector (default the family's: 15 for a builder).
    fd_step : float, optional
        Relative step of the parameter derivative (default the family's: ``1e-6``).
    locate : bool
        Locate the events (Illinois iterations on the test function along the branch,
        bisection on the jump sequence); otherwise each is reported at the nearer bracketing
        point, ``located=False``.
    event_tol : float
        Location tolerance: length of the final bracket in ``(s, p)``.
    events : tuple of str
        Kinds to detect (default: all the family's kinds, :data:`EVENT_KINDS` for a builder).
    map_options : dict, optional
        Keyword arguments of :class:`SectionMap` (``t_max``, ``max_jumps``, ...).

    Returns
    -------
    Branch

    Raises
    ------
    ValueError
        If a parameter is out of range (or ``p_end`` out of the family's domain), ``section`` is missing for an automaton builder, or
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
    >>> br = hp.continue_orbit(build, 0.8, 0.82, [7.7, 1.66], section=sec, step=0.01)
    >>> br.termination, round(br[-1].p, 6), bool(br[-1].stable)
    ('reached', 0.82, True)
    >>> br.reason
    'reached the end value p = 0.82'

    The impact pair's orbit followed in its damping gain with the pair's rules (``kv`` from
    20 to 23: the branch ends at grazing):

    >>> from hybridpd.pair.orbits import symmetric_orbit
    >>> orb = symmetric_orbit(hp.ImpactPair(0.1, 0.1, 0.75), hp.PDGains(10, 20), 5.0)
    >>> P = hp.ImpactMap(orb.pair, orb.gains, orb.reference())
    >>> br = hp.continue_orbit(P.family("kv"), 20.0, 23.0, orb.fixed_point, step=0.5)
    >>> [ev.kind for ev in br.events][:1]
    ['grazing']
    """
    if not callable(builder):
        raise ValueError(f"builder must be a callable p -> PoincareMap (e.g. a map class), got "
                         f"{type(builder).__name__}")
    if method not in ("arclength", "natural"):
        raise ValueError(f"method must be 'arclength' or 'natural', got {method!r}")
    fam = builder if isinstance(builder, ParameterFamily) else ParameterFamily(
        "p", math.nan, _map_factory(builder, section, dict(map_options or {})))
    if fd_step is not None:
        fam = replace(fam, fd_step=_positive("fd_step", fd_step))
    p0, p_end = float(p0), float(p_end)
    if not (math.isfinite(p0) and math.isfinite(p_end)) or p0 == p_end:
        raise ValueError(f"p0 and p_end must be finite and differ, got {p0!r}, {p_end!r}")
    fam.check_range(p0, p_end)
    span = abs(p_end - p0)
    d_step, d_max, d_min = fam.steps(span)
    step = d_step if step is None else float(step)
    max_step = max(d_max, step) if max_step is None else float(max_step)
    min_step = min(d_min, step) if min_step is None else float(min_step)
    if not (0 < min_step <= step <= max_step):
        raise ValueError("steps must satisfy 0 < min_step <= step <= max_step")
    max_steps = fam.max_steps if max_steps is None else int(max_steps)
    if max_steps < 1:
        raise ValueError(f"max_steps must be >= 1, got {max_steps!r}")
    max_iter = fam.max_iter if max_iter is None else int(max_iter)
    if max_iter < 1:
        raise ValueError(f"max_iter must be >= 1, got {max_iter!r}")
    tol = _positive("tol", tol)
    event_tol = _positive("event_tol", event_tol)
    events = fam.kinds if events is None else tuple(events)
    bad = [kind for kind in events if kind not in fam.kinds]
    if bad:
        raise ValueError(f"events must be a subset of {fam.kinds}, got {bad}")
    if period is None:
        period = getattr(s0, "period", 1)
    s0 = getattr(s0, "s", s0)
    k = int(period)
    if k < 1:
        raise ValueError(f"period must be >= 1, got {period!r}")
    P = fam.at(p0)
    if P is None:
        raise ValueError(f"p0: the family has no map at {fam.name} = {p0:g}")
    orbit = fam.start(P, s0, k, tol, max_iter)
    if not orbit.converged:
        return fam.start_failed(P, k, method, p0, orbit)
    path = _Path(fam, k, p0, P)
    first = path.point(np.append(orbit.s, p0), orbit.iterations)
    if first is None:
        return fam.start_failed(P, k, method, p0, None)
    lo, hi = sorted((p0, p_end))
    slack = fam.range_slack * span
    options = PathOptions(step=step, min_step=min_step, max_step=max_step,
                          max_steps=max_steps - 1, method=method, tol=tol, max_iter=max_iter,
                          grow=fam.grow, name=fam.name, locate=locate, event_tol=event_tol)
    pts, evs, termination, rejected, why = follow_branch(
        path, first, p_end, options, scale=lambda x: fam.scale(x, P.dim),
        to_event=fam.to_event, kinds=events,
        extra_events=lambda pa, pb, i, evaluate: fam.extra_events(
            pa, pb, i, evaluate, kinds=events, locate=locate, tol=event_tol),
        nonsmooth=fam.nonsmooth, k=k,
        out_of_range=lambda p: None if lo - slack <= p <= hi + slack
        else "turned back: left the parameter range")
    return fam.finish(PathRun(pts, evs, termination, rejected, why, p0, p_end, k, method,
                              max_steps, events, P))


def _positive(name, value) -> float:
    v = float(value)
    if not v > 0 or not math.isfinite(v):
        raise ValueError(f"{name} must be > 0 and finite, got {value!r}")
    return v


class _Path:
    """``F(u) = P^k(s; p) - s`` (phase wrapped) of a family's maps, its Jacobians and points,
    for the engine; the family's hooks give the rules in which families differ."""

    def __init__(self, family, k, p0, P0):
        self.family, self.k, self.p0 = family, k, p0
        self._maps = {float(p0): P0}
        self._last = (None, None)
        self._why = ""        # why the map was last undefined (see explain)

    def map_at(self, p):
        """The family's map at ``p`` (None outside its domain)."""
        # the corrector and dF/dp revisit the same few parameter values
        key = float(p)
        if key not in self._maps:
            if len(self._maps) > 64:
                self._maps.clear()
            self._maps[key] = self.family.at(key)
        return self._maps[key]

    def explain(self) -> str:
        """Why the map was undefined at a point evaluated since the previous call (``""`` if
        it never was); forgets it."""
        why, self._why = self._why, ""
        return why

    def _undefined(self, u, r) -> None:
        if not self.family.explains:
            return
        if r is None:
            what = "outside the family's domain"
        elif r.ok:
            what = ("grazing (a tangential contact: no saltation matrix)" if r.grazing
                    else "its Jacobian DP is not finite")
        else:
            what = r.status + (f" ({_UNDEFINED[r.status]})" if r.status in _UNDEFINED else "")
            what += " after a grazing contact" if r.grazing else ""
        self._why = f"map undefined: {what} at p = {u[-1]:.10g}"

    def _run(self, u):
        key = u.tobytes()
        if self._last[0] != key:      # F and Fs ask for the same point in turn
            P = self.map_at(u[-1])
            if P is None:
                raise RuntimeError(f"no map at p = {u[-1]:.10g}")
            r = P.apply(u[:-1], self.k, jacobian=True)
            DP = r.DP
            if r.ok and DP is None:   # the map gives no DP: its finite differences
                try:
                    DP = P.jacobian_fd(u[:-1], self.k)
                except RuntimeError:
                    DP = np.full((P.dim, P.dim), np.nan)
            self._last = (key, (P, r, DP))
        return self._last[1]

    def F(self, u):
        if not self.family.dp_in_residual:
            P = self.map_at(u[-1])
            return None if P is None else map_residual(P, u[:-1], self.k)
        try:
            P, r, DP = self._run(u)
        except ValueError as exc:     # not a section point
            if self.family.explains:
                self._why = f"not a section point at p = {u[-1]:.10g}: {exc}"
            return None
        except RuntimeError:
            self._undefined(u, None)
            return None
        if r.ok and np.all(np.isfinite(DP)):
            return P.wrap(r.s - u[:-1])
        self._undefined(u, r)
        return None

    def Fs(self, u):
        P, r, DP = self._run(u)
        if not r.ok:
            raise RuntimeError(f"P^k undefined: {r.status}")
        return DP - np.eye(P.dim)

    def Fp(self, u):
        P = self.map_at(u[-1])
        if P is None:
            raise RuntimeError(f"no map at p = {u[-1]:.10g}")
        p_ref = self.p0 if self.family.gradient_step == "start" else None
        return self.family.gradient(P, u[:-1], self.k, u[-1], at=self.map_at, p_ref=p_ref)

    def point(self, u, its=0):
        try:
            P, r, DP = self._run(u)
        except (RuntimeError, ValueError):
            self._undefined(u, None)
            return None
        if not r.ok or not np.all(np.isfinite(DP)):
            self._undefined(u, r)
            return None

        def gradient():
            try:
                return self.Fp(u)
            except RuntimeError:
                return None
        return self.family.point(P, u, self.k, its, r, DP, gradient)

    def lower_period(self, u) -> bool:
        """The point is a fixed point of a lower power of the map (another branch)."""
        return minimal_period(self.map_at(u[-1]), u[:-1], self.k) < self.k

    def unwrap(self, cur, new):
        P = self.map_at(new.u[-1])
        if P is not None and P.period is not None:
            new.u[0] = cur.u[0] + P.wrap(new.u[:-1] - cur.u[:-1])[0]
