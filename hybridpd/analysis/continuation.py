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
period changes: grazing, sticking, ...) is located by bisection on the sequence. The
engine (:func:`follow_branch`) is the impact pair's too: its map continuation gives it its
own map, points and grazing events as hooks.

A map knows its named parameters through its hook ``family``: e.g. the impact pair's
``ImpactMap.family("kv")`` is a builder of the map at other damping gains, so
``continue_orbit(P.family("kv"), 20.0, 23.0, s0)`` follows the pair's orbits on this engine.

The result is the package's one :class:`Branch` (per-point arrays; ``branch[i]`` is a
:class:`BranchPoint`) with :class:`BifurcationEvent` (``kind``, ``index``, ``parameter``,
``detail``): the impact pair's continuations return the same class, with their own
quantities in ``variables`` and ``metadata``. Branches are saved as ``.nc`` or ``.zarr``
(:meth:`Branch.save`, :func:`load_branch`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import numpy as np

from hybridpd._results import (
    Result,
    WithExtras,
    compact_repr,
    decode_attrs,
    encode_attrs,
    jsonable,
)
from hybridpd.analysis.bifevents import EventTracker, turn_test
from hybridpd.analysis.floquet import stability
from hybridpd.analysis.hybridmap import Section, SectionMap
from hybridpd.analysis.maps import PoincareMap, minimal_period
from hybridpd.analysis.pathfollow import bisect_predicate, corrector, follow_path
from hybridpd.analysis.periodic import find_orbit

__all__ = ["EVENT_KINDS", "BifurcationEvent", "Branch", "BranchPoint", "continue_orbit",
           "load_branch"]

#: Kinds of :class:`BifurcationEvent`.
EVENT_KINDS = ("fold", "period_doubling", "neimark_sacker", "stability_change",
                 "sequence_change")
_NONREAL = 1e-9
#: What a :data:`~hybridpd.analysis.hybridmap.MAP_STATUS` means where the map is undefined.
_UNDEFINED = {
    "bad_start": "the flow does not cross the section at the trial point",
    "jump_limit": "more than max_jumps jumps before the return",
    "end_time": "no return to the section within t_max",
    "zeno": "an accumulation of jumps on the way",
    "nonfinite": "the state overflowed on the way",
    "step_limit": "more than max_steps flow steps before the return",
    "simultaneous": "a joint impact of several contacts on the way"}


@dataclass(frozen=True, eq=False)
class BranchPoint:
    """One point of a family: parameter ``p``, fixed point ``s`` and its stability (what
    ``branch[i]`` returns; ``DP`` is kept only while the branch is followed)."""

    p: float
    s: np.ndarray
    DP: np.ndarray | None = field(repr=False)
    multipliers: np.ndarray
    spectral_radius: float
    stable: bool
    signature: tuple
    t_period: float = math.nan
    __repr__ = compact_repr


@dataclass(frozen=True, eq=False)
class BifurcationEvent(WithExtras):
    """An event between branch points ``index`` and ``index + 1``, located at ``parameter``.

    Attributes
    ----------
    kind : str
        One of :data:`EVENT_KINDS` (or an extra kind of a map's family, e.g. the impact
        pair's ``grazing`` and ``existence``).
    index : int
    parameter : float
        Parameter value of the located event (or of the nearer bracketing point when location
        failed).
    detail : str
        What changed, and how it was located; starts with ``"uncertain"`` when only a sign
        change between two points is known.
    point : ndarray, shape (dim,), optional
        Fixed point at the event (the phase in ``[0, T)``).
    multipliers : ndarray, shape (dim,), complex, optional
        Multipliers at the event.
    test_value : float
        Test function at the reported point (0 at an exact event).
    located : bool
        The location converged.
    viable : bool
        The orbit at the event is a genuine orbit (a stability change of a "virtual",
        non-viable orbit of a closed-form family is reported with ``False``).
    variables : dict
        The family's own quantities at the event (the impact pair's reference amplitude
        ``xm``); also readable as attributes (``ev.xm``).
    """

    kind: str
    index: int
    parameter: float
    detail: str = ""
    point: np.ndarray | None = field(default=None, repr=False)
    multipliers: np.ndarray | None = field(default=None, repr=False)
    test_value: float = math.nan
    located: bool = False
    viable: bool = True
    variables: dict = field(default_factory=dict, repr=False)
    __repr__ = compact_repr

    @property
    def p(self) -> float:
        """The parameter value of the event (the name of earlier versions)."""
        return self.parameter

    def to_dict(self) -> dict:
        """JSON-ready values (complex numbers as ``[re, im]``, the variables inline)."""
        out = {f.name: jsonable(getattr(self, f.name)) for f in fields(self)
               if f.name != "variables"}
        return {**out, **jsonable(self.variables)}

    @classmethod
    def from_dict(cls, d: dict) -> BifurcationEvent:
        """Inverse of :meth:`to_dict`."""
        names = {f.name for f in fields(cls)} - {"variables"}
        kw = {k: v for k, v in d.items() if k in names}
        for k in ("point", "multipliers"):
            if kw.get(k) is not None:
                kw[k] = _array(kw[k])
        for k in ("test_value", "parameter"):
            kw[k] = math.nan if kw.get(k) is None else float(kw[k])
        return cls(**kw, variables={k: (math.nan if v is None else v) for k, v in d.items()
                                    if k not in names and k != "p"})


def _array(values) -> np.ndarray:
    """A list read from JSON as an array: ``[re, im]`` pairs as complex, ``None`` as NaN."""
    nan = lambda v: math.nan if v is None else v
    if values and isinstance(values[0], list):
        return np.array([complex(nan(re), nan(im)) for re, im in values])
    return np.array([nan(v) for v in values], float)


def _tuples(obj):
    return tuple(_tuples(o) for o in obj) if isinstance(obj, list) else obj


#: Per-point fields of a branch and their dimensions in its dataset.
_COLUMNS = {"points": ("point", "coordinate"), "multipliers": ("point", "coordinate"),
            "spectral_radius": ("point",), "stable": ("point",)}


@dataclass(frozen=True, eq=False)
class Branch(WithExtras, Result):
    """A continued family of periodic orbits, one row per accepted point.

    The same class holds a family of any map (:func:`continue_orbit`) and the impact pair's
    (map continuation, or its closed-form symmetric family); what only a family has lives in
    ``variables`` and ``metadata``.

    Attributes
    ----------
    parameter_name : str
    parameter : ndarray, shape (N,)
    points : ndarray, shape (N, dim)
        Fixed points of ``P^k`` (a phase coordinate in ``[0, T)``).
    multipliers : ndarray, shape (N, dim), complex
        Floquet multipliers (NaN where undefined).
    spectral_radius : ndarray, shape (N,)
    stable : ndarray of bool, shape (N,)
        Spectral radius below 1 (and, where the family says, viable).
    period : int
        ``k`` of ``P^k``.
    events : list of BifurcationEvent
        In branch order.
    termination : str
        ``"reached"``, ``"max_steps"``, ``"min_step"``, ``"turned back: ..."`` or ``"start
        failed: <reason>"`` (the impact pair's engine says it in words).
    method : str
        ``"arclength"``, ``"natural"`` or ``"closed_form"``.
    reason : str
        Why it stopped, in words, with the parameter value.
    patterns : tuple
        Per point, the jump (impact) signature of one period.
    variables : dict of str to ndarray (N,)
        Per-point quantities of the family: ``t_period`` (time of one period of ``P^k``); the
        impact pair's ``viable``, ``margin``, ``min_impact_speed``, ``xm`` and
        ``newton_iterations``. Also readable as attributes (``br.margin``).
    metadata : dict
        The family's settings (the pair's ``family``, ``case``, ``fixed``, ``n_rejected``);
        also readable as attributes.
    """

    kind = "branch"
    parameter_name: str
    parameter: np.ndarray
    points: np.ndarray = field(repr=False)
    multipliers: np.ndarray = field(repr=False)
    spectral_radius: np.ndarray = field(repr=False)
    stable: np.ndarray = field(repr=False)
    period: int
    events: list
    termination: str
    method: str
    reason: str = ""
    patterns: tuple = field(default=(), repr=False)
    variables: dict = field(default_factory=dict, repr=False)
    metadata: dict = field(default_factory=dict, repr=False)
    __repr__ = compact_repr

    @classmethod
    def from_points(cls, points, events, termination, method, period, reason="", *,
                    parameter_name="p", dim=0, variables=None, metadata=None) -> Branch:
        """A branch from its points (:class:`BranchPoint`), in order."""
        pts = list(points)
        col = lambda name, shape, dtype=float: (np.array([getattr(q, name) for q in pts],
                                                         dtype) if pts else np.zeros(shape, dtype))
        return cls(parameter_name, col("p", 0), col("s", (0, dim)),
                   col("multipliers", (0, dim), complex), col("spectral_radius", 0),
                   col("stable", 0, bool), int(period), list(events), termination, method,
                   reason, tuple(q.signature for q in pts),
                   {"t_period": col("t_period", 0), **(variables or {})}, dict(metadata or {}))

    def __len__(self) -> int:
        return int(np.size(self.parameter))

    def __getitem__(self, i) -> BranchPoint:
        """Point ``i`` of the branch."""
        return BranchPoint(float(self.parameter[i]), self.points[i], None, self.multipliers[i],
                           float(self.spectral_radius[i]), bool(self.stable[i]),
                           self.patterns[i] if self.patterns else (),
                           float(self.variables.get("t_period", [math.nan] * len(self))[i]))

    def __iter__(self):
        return (self[i] for i in range(len(self)))

    def events_of(self, kind: str) -> list:
        """The events of one kind."""
        return [e for e in self.events if e.kind == kind]

    def to_dict(self) -> dict:
        """JSON-ready values (complex numbers as ``[re, im]``; the variables and metadata
        inline)."""
        out = {f.name: jsonable(getattr(self, f.name)) for f in fields(self)
               if f.name not in ("variables", "metadata")}
        return {**out, **jsonable(self.variables), **jsonable(self.metadata)}

    def to_dataset(self):
        """The branch as an :class:`xarray.Dataset`: per-point variables over ``point``, the
        events, patterns and metadata as JSON attributes."""
        import xarray as xr

        data = {k: (dims, np.asarray(getattr(self, k))) for k, dims in _COLUMNS.items()}
        data.update({k: ("point", np.asarray(v)) for k, v in self.variables.items()})
        attrs = {"kind": self.kind, "parameter_name": self.parameter_name,
                 "period": int(self.period), "termination": self.termination,
                 "method": self.method, "reason": self.reason,
                 "events": [e.to_dict() for e in self.events],
                 "patterns": jsonable(self.patterns), "metadata": jsonable(self.metadata),
                 "variables": list(self.variables)}
        return xr.Dataset(data, coords={"parameter": ("point", np.asarray(self.parameter))},
                          attrs=encode_attrs(attrs))

    @classmethod
    def from_dataset(cls, ds) -> Branch:
        """Inverse of :meth:`to_dataset`."""
        a = decode_attrs(ds.attrs)
        if a.get("kind") != cls.kind:
            raise ValueError(f"the dataset holds a {a.get('kind')!r}, not a branch")
        return cls(a["parameter_name"], ds["parameter"].values,
                   *(ds[k].values for k in _COLUMNS), int(a["period"]),
                   [BifurcationEvent.from_dict(d) for d in a["events"]], a["termination"],
                   a["method"], a.get("reason", ""), _tuples(a["patterns"]),
                   {k: ds[k].values for k in a["variables"]}, a["metadata"])


def load_branch(path) -> Branch:
    """Read a :class:`Branch` written by :meth:`Branch.save` (``.nc``, ``.zarr`` or ``.npz``).

    Examples
    --------
    The logistic map's fixed point ``1 - 1/r`` doubles its period at ``r = 3``:

    >>> import os, tempfile
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
    >>> br = hp.continue_orbit(Logistic, 2.5, 3.2, [0.6])
    >>> back = load_branch(br.save(os.path.join(tempfile.mkdtemp(), "b.nc")))
    >>> [(e.kind, round(e.parameter, 6)) for e in back.events]
    [('period_doubling', 3.0), ('stability_change', 3.0)]
    """
    return Branch.load(path)


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


def _point(r, DP, s, p, zeros=0) -> BranchPoint:
    """The family point of an application ``r`` of ``P^k`` with Jacobian ``DP`` at ``(s, p)``."""
    st = stability(DP, structural_zeros=zeros)
    return BranchPoint(float(p), s, DP, st.multipliers, st.spectral_radius,
                       bool(st.stable), r.signature, r.t_hit - r.t_start)


def follow_branch(path, first, p_end, *, method, step, min_step, max_step, max_steps, tol,
                  max_iter, scale, to_event, kinds=EVENT_KINDS, locate=True, event_tol=1e-9,
                  extra_events=None, nonsmooth=None, out_of_range=None, k=1, grow=1.5,
                  name="p"):
    """The one continuation engine: follow a branch from ``first`` towards ``p = p_end`` and
    detect its events.

    ``path`` gives ``F(u)`` (``P^k(s) - s``, phase wrapped; None where undefined), ``Fs``,
    ``Fp``, ``point(u, iterations)`` (an accepted point with ``u``, ``DP``, ``Fp``, ``mult``,
    ``rho``, ``formal``, ``signature``; None to refuse it), ``unwrap(cur, new)``,
    ``lower_period(u)`` and ``explain()`` (None-able). The path follower is
    :func:`~hybridpd.analysis.pathfollow.follow_path`, the detector
    :class:`~hybridpd.analysis.bifevents.EventTracker` (with turning points); a family's own
    events come from ``extra_events(pa, pb, index, evaluate)`` (``evaluate(pa, pb, theta)``
    the corrected point between two points). Returns ``follow_path``'s
    ``(points, events, termination, rejected, why)``.
    """
    correct = corrector(path.F, path.Fs, path.Fp, tol=tol, max_iter=max_iter, scale=scale,
                        explain=path.explain)

    def evaluate(pa, pb, theta):
        chord = pb.u - pa.u
        u, res = correct(pa.u + theta * chord, chord / np.linalg.norm(chord))
        return path.point(u, res.iterations) if res.converged else None

    tracker = EventTracker(kinds, evaluate, lambda a, b: float(np.linalg.norm(b.u - a.u)),
                           event_tol, 60, locate, to_event, turn_test=turn_test,
                           nonsmooth=nonsmooth)

    def detect(a, b, i):
        return tracker.detect(a, b, i, () if extra_events is None
                              else extra_events(a, b, i, evaluate))

    return follow_path(first, p_end, F=path.F, Fs=path.Fs, Fp=path.Fp,
                       make_point=path.point, correct=correct, method=method, step=step,
                       min_step=min_step, max_step=max_step, max_steps=max_steps, k=k,
                       lower_period=path.lower_period, unwrap=path.unwrap, detect=detect,
                       out_of_range=out_of_range, tol=tol, name=name, grow=grow,
                       explain=path.explain)


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


def continue_orbit(builder, p0: float, p_end: float, s0, *, period: int | None = None,
                   section=None, method: str = "arclength", step: float | None = None,
                   max_step: float | None = None, min_step: float | None = None,
                   max_steps: int = 200, tol: float = 1e-10, fd_step: float = 1e-6,
                   locate: bool = True, event_tol: float = 1e-9,
                   events: tuple = EVENT_KINDS, map_options: dict | None = None) -> Branch:
    """Follow a periodic orbit (a fixed point of ``P^k``) in a parameter, on any map.

    Parameters
    ----------
    builder : callable
        ``p -> PoincareMap`` (any map: a user's, a specialisation, a
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
        ``(s, p)`` otherwise); defaults ``|p_end - p0| / 20``, ``/ 5`` and ``/ 1e5`` (widened to
        include ``step``).
    max_steps : int
        Bound on accepted points.
    tol : float
        Newton tolerance (residual relative to ``max(1, |s|)``).
    fd_step : float
        Relative step of the parameter derivative (arclength).
    locate : bool
        Locate the events (Illinois iterations on the test function along the branch,
        bisection on the jump sequence); otherwise each is reported at the nearer bracketing
        point, ``located=False``.
    event_tol : float
        Location tolerance: length of the final bracket in ``(s, p)``.
    events : tuple of str
        Kinds to detect (a subset of :data:`EVENT_KINDS`).
    map_options : dict, optional
        Keyword arguments of :class:`SectionMap` (``t_max``, ``max_jumps``, ...).

    Returns
    -------
    Branch

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
    >>> br = hp.continue_orbit(build, 0.8, 0.82, [7.7, 1.66], section=sec, step=0.01)
    >>> br.termination, round(br[-1].p, 6), bool(br[-1].stable)
    ('reached', 0.82, True)
    >>> br.reason
    'reached the end value p = 0.82'
    """
    if not callable(builder):
        raise ValueError(f"builder must be a callable p -> PoincareMap (e.g. a map class), got "
                         f"{type(builder).__name__}")
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
    if not event_tol > 0:
        raise ValueError(f"event_tol must be > 0, got {event_tol!r}")
    bad = [kind for kind in events if kind not in EVENT_KINDS]
    if bad:
        raise ValueError(f"events must be a subset of {EVENT_KINDS}, got {bad}")
    if period is None:
        period = getattr(s0, "period", 1)
    s0 = getattr(s0, "s", s0)
    k = int(period)
    make = _map_factory(builder, section, dict(map_options or {}))
    P = make(p0)
    first = find_orbit(P, s0, k, tol=tol)
    if not first.converged:
        detail = f" ({first.detail})" if first.detail else ""
        return Branch.from_points([], [], f"start failed: {first.reason}", method, k,
                                  f"no fixed point of P^{k} at p = {p0:.10g} to start from: "
                                  f"{first.reason}{detail}", dim=P.dim)
    path = _Path(make, k, fd_step * max(1.0, abs(p0)), P.dim)
    lo, hi = sorted((p0, p_end))

    def to_event(kind, pt, index, detail, fv, ok):
        return BifurcationEvent(kind, index, float(pt.u[-1]), detail, pt.fam.s.copy(),
                                pt.mult.copy(), float(fv), bool(ok))

    def sequence_events(pa, pb, index, evaluate):
        if "sequence_change" not in events or pa.signature == pb.signature:
            return []
        _la, lb, ok = sequence_change(pa, pb, evaluate, locate=locate, tol=event_tol)
        return [to_event("sequence_change", lb, index,
                         f"{len(pa.signature)} -> {len(pb.signature)} jumps per period",
                         math.nan, ok)]

    pts, evs, termination, _rej, _why = follow_branch(
        path, path.point(np.append(first.s, p0)), p_end, method=method, step=step,
        min_step=min_step, max_step=max_step, max_steps=int(max_steps) - 1, tol=tol,
        max_iter=15, scale=lambda x: max(1.0, float(np.max(np.abs(x[:path.dim])))),
        to_event=to_event, kinds=events, locate=locate, event_tol=event_tol,
        extra_events=sequence_events, k=k, grow=1.3,
        out_of_range=lambda p: None if lo - 1e-9 * span <= p <= hi + 1e-9 * span
        else "turned back: left the parameter range")
    reason = _reason(termination, pts[-1].u[-1], p_end, lo, hi, int(max_steps))
    for key, short in (("reached", "reached"), ("max_steps", "max_steps"),
                       ("step below", "min_step")):
        termination = short if termination.startswith(key) else termination
    return Branch.from_points([q.fam for q in pts], evs, termination, method, k, reason,
                              dim=P.dim)


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


@dataclass(eq=False)
class _PathPoint:
    """A point of the path as the engine sees it: ``u = (s, p)``, ``DP``, ``dF/dp``."""

    u: np.ndarray
    DP: np.ndarray
    Fp: np.ndarray | None
    fam: BranchPoint
    formal = True         # the multipliers mean what they say at every point

    mult = property(lambda self: self.fam.multipliers)
    rho = property(lambda self: self.fam.spectral_radius)
    signature = property(lambda self: self.fam.signature)


class _Path:
    """``F(u) = P^k(s; p) - s`` (phase wrapped), its Jacobians and points, for the engine."""

    def __init__(self, make, k, hp, dim):
        self.make, self.k, self.hp, self.dim = make, k, hp, dim
        self._last = (None, None)
        self._why = ""        # why the map was last undefined (see explain)

    def explain(self) -> str:
        """Why the map was undefined at a point evaluated since the previous call (``""`` if
        it never was); forgets it."""
        why, self._why = self._why, ""
        return why

    def _undefined(self, u, r) -> None:
        if r.ok:
            what = ("grazing (a tangential contact: no saltation matrix)" if r.grazing
                    else "its Jacobian DP is not finite")
        else:
            what = r.status + (f" ({_UNDEFINED[r.status]})" if r.status in _UNDEFINED else "")
            what += " after a grazing contact" if r.grazing else ""
        self._why = f"map undefined: {what} at p = {u[-1]:.10g}"

    def _run(self, u):
        key = u.tobytes()
        if self._last[0] != key:      # F and Fs ask for the same point in turn
            P = self.make(u[-1])
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
        try:
            P, r, DP = self._run(u)
        except ValueError as exc:     # not a section point
            self._why = f"not a section point at p = {u[-1]:.10g}: {exc}"
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
        m, s, hp = self.make, u[:-1], self.hp
        return m(u[-1]).wrap(m(u[-1] + hp)(s, self.k) - m(u[-1] - hp)(s, self.k)) / (2 * hp)

    def point(self, u, _its=0):
        P, r, DP = self._run(u)
        if not r.ok or not np.all(np.isfinite(DP)):
            self._undefined(u, r)
            return None
        s = P.canonical(u[:-1].copy())
        try:
            fp = self.Fp(u)
        except RuntimeError:
            fp = None
        return _PathPoint(u.copy(), DP, fp, _point(r, DP, s, u[-1], P.structural_zeros))

    def lower_period(self, u) -> bool:
        """The point is a fixed point of a lower power of the map (another branch)."""
        return minimal_period(self.make(u[-1]), u[:-1], self.k) < self.k

    def unwrap(self, cur, new):
        P = self.make(new.u[-1])
        if P.period is not None:
            new.u[0] = cur.u[0] + P.wrap(new.u[:-1] - cur.u[:-1])[0]
