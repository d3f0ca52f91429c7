"""The result of a continuation: a family of periodic orbits (:class:`Branch`, one row per
point, ``branch[i]`` a :class:`BranchPoint`) and its events (:class:`BifurcationEvent`), saved
as ``.nc`` or ``.zarr`` (:meth:`Branch.save`, :func:`load_branch`). The engine that computes
them is :mod:`hybridpd.analysis.continuation`; a map's family of its own
(:mod:`hybridpd.analysis.family`) fills its variables and metadata."""
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

__all__ = ["EVENT_KINDS", "BifurcationEvent", "Branch", "BranchPoint", "load_branch"]

#: Kinds of :class:`BifurcationEvent`.
EVENT_KINDS = ("fold", "period_doubling", "neimark_sacker", "stability_change",
                 "sequence_change")

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
