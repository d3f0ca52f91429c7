"""Basin results of any map: the attractors and outcomes each point of a 2-D slice reaches.

A basin (:func:`hybridpd.sweeps.basins.basin_of_attraction`) asks every point of a 2-D slice
where iterating the map takes it: a mapper (:mod:`hybridpd.analysis.mappers`) labels it
against one orbit, and the points that did not converge are examined for other periodic
attractors (:class:`~hybridpd.analysis.mappers.Catalogue`). Labels ``0, 1, ...`` are the
attractors in the order found; negative labels are the outcomes :data:`OUTCOMES`: no
convergence within the iterations, divergence (non-finite, or beyond ``escape``), sticking,
the map stopped for another reason (``unresolved``), a start off the map's domain, or (slices
of a section with an admissible set) an inadmissible start.

:class:`BasinResult` is the one basin result: of any map, of the impact pair's slice
``(x1, y1)`` and of a model file's section alike, with the grid's coordinate names, the
attractors (:class:`Attractor`), optionally the labels of a mapper's criterion against one
orbit (:data:`~hybridpd.analysis.labels.LABELS`, ``criterion_labels``) and the windows tried.
It is a :class:`hybridpd._results.Result` (``.nc``/``.zarr``/``.npz`` files, ``to_dict``).
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

import numpy as np

from hybridpd._format import format_percent
from hybridpd._results import Fields, Result, compact_repr, decode_attrs
from hybridpd.analysis.labels import LABELS
from hybridpd.analysis.maps import PoincareMap
from hybridpd.model import check_axis

__all__ = ["DIVERGED", "INADMISSIBLE_LABEL", "NO_CONVERGENCE", "OFF_SECTION_LABEL", "OUTCOMES",
           "STICKING", "UNRESOLVED", "Attractor", "BasinMeasure", "BasinResult", "Slice",
           "from_criterion", "grid_slice", "load_basin", "off_section_axis", "outcome"]

NO_CONVERGENCE = -1
DIVERGED = -2
STICKING = -3
UNRESOLVED = -4
OFF_SECTION_LABEL = -5
INADMISSIBLE_LABEL = -6

#: Negative labels, what a point that reaches no periodic attractor does: ``(kind, name)``.
OUTCOMES = {
    NO_CONVERGENCE: ("no_convergence", "no convergence"),
    DIVERGED: ("diverged", "diverged"),
    STICKING: ("sticking", "sticking"),
    UNRESOLVED: ("unresolved", "unresolved flight"),
    OFF_SECTION_LABEL: ("off_section", "off the section"),
    INADMISSIBLE_LABEL: ("inadmissible", "inadmissible (a gap beyond its bounds)")}
_OUTSIDE = (OFF_SECTION_LABEL, INADMISSIBLE_LABEL)


def from_criterion(labels) -> np.ndarray:
    """Attractor codes of a mapper's labels (:data:`~hybridpd.analysis.labels.LABELS`):
    ``converged`` is ``0`` (the orbit), label ``j > 0`` the outcome ``-j``.

    Examples
    --------
    >>> from_criterion([0, 1, 5]).tolist()
    [0, -1, -5]
    """
    return -np.asarray(labels, np.int64)


@dataclass(frozen=True, eq=False)
class Attractor(Fields):
    """A periodic attractor of a basin (or an outcome, ``label < 0``).

    Attributes
    ----------
    label : int
        ``0, 1, ...`` periodic attractors (``0`` the orbit a criterion was taken against),
        negative: an outcome of :data:`OUTCOMES`.
    name : str
        In words, e.g. ``"period-2 orbit"``.
    period : int
        Applications of the map per period (0 for an outcome).
    points : ndarray, shape (period, dim)
        The cycle's points (Newton-refined where it converged).
    multipliers : ndarray or None
        Eigenvalues of the cycle's ``DP^period``.
    spectral_radius : float
        ``nan`` when unknown.
    stable : bool or None
        ``None`` when unknown.
    kind : str
        ``"periodic"``, ``"symmetric"`` (the impact pair's orbit) or an outcome's kind.
    walls : tuple
        Contacts hit in each application of the map (the impact pair's walls), if known.
    residual : float
        ``|P^period(s) - s|_inf`` at ``points[0]`` (``nan`` when unknown).

    Examples
    --------
    >>> a = Attractor(0, "period-1 orbit", 1, np.zeros((1, 2)), stable=True)
    >>> Attractor.from_dict(a.to_dict()).name, a.periodic, outcome(-2).name
    ('period-1 orbit', True, 'diverged')
    """

    label: int
    name: str
    period: int = 0
    points: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)), repr=False)
    multipliers: np.ndarray | None = field(default=None, repr=False)
    spectral_radius: float = math.nan
    stable: bool | None = None
    kind: str = "periodic"
    walls: tuple = ()
    residual: float = math.nan
    __repr__ = compact_repr

    @property
    def periodic(self) -> bool:
        """A periodic orbit (not an outcome)."""
        return self.label >= 0

    @classmethod
    def from_dict(cls, d: dict) -> Attractor:
        """Inverse of :meth:`to_dict` (optional keys left out read as unknown)."""
        mult = d.get("multipliers")
        pts = np.asarray(d.get("points") or [], float)
        stable = d.get("stable")
        return cls(int(d["label"]), str(d["name"]), int(d.get("period") or 0),
                   pts.reshape(len(pts), -1) if pts.size else np.zeros((0, 0)),
                   _multipliers(mult),
                   _float(d.get("spectral_radius")), None if stable is None else bool(stable),
                   d.get("kind") or ("periodic" if int(d["label"]) >= 0
                                     else OUTCOMES[int(d["label"])][0]),
                   tuple(tuple(w) for w in d.get("walls") or ()), _float(d.get("residual")))


def _float(v) -> float:
    return math.nan if v is None else float(v)


def _multipliers(m) -> np.ndarray | None:
    # JSON: numbers (real multipliers) or [re, im] pairs (complex); None for NaN
    if m is None or not any(isinstance(z, (list, tuple)) for z in m):
        return None if m is None else np.array([_float(z) for z in m])
    return np.array([complex(_float(z[0]), _float(z[1])) for z in m])


def outcome(label: int, n_iter: int | None = None) -> Attractor:
    """The :class:`Attractor` entry of a negative outcome label (with ``n_iter``, the
    iterations of "no convergence" are named)."""
    kind, name = OUTCOMES[int(label)]
    if label == NO_CONVERGENCE and n_iter is not None:
        name = f"no convergence in {int(n_iter)} iterations"
    return Attractor(int(label), name, kind=kind)


@dataclass(frozen=True)
class BasinMeasure:
    """Size of one attractor's basin on the grid.

    Attributes
    ----------
    label : int
    name : str
    count : int
        Grid points with this label.
    fraction : float
        ``count`` over all points of the grid (the slice), those off the section and the
        inadmissible ones included: one denominator for every label.
    area : float
        ``count`` times the grid cell area (units of ``x`` times ``y``).
    percent : str
        ``fraction`` formatted by :func:`hybridpd._format.format_percent`.
    """

    label: int
    name: str
    count: int
    fraction: float
    area: float
    percent: str


@dataclass(frozen=True, eq=False)
class BasinResult(Result):
    """Labels of a 2-D slice by attractor: the one basin result (module docstring).

    Attributes
    ----------
    x, y : ndarray
        Grid axes, values of the coordinates ``x_name`` and ``y_name``.
    labels : ndarray of int, shape (len(y), len(x))
        ``0, 1, ...`` the attractors, negative the outcomes of :data:`OUTCOMES`.
    attractors : tuple of Attractor
        The attractors and the outcomes present.
    iterations : ndarray of int, shape (len(y), len(x))
        Iterations run per point.
    x_name, y_name : str
        The coordinates the grid spans (the impact pair's slice: ``"x1"``, ``"y1"``).
    base : ndarray, shape (dim,)
        The point whose other coordinates the slice holds (a criterion's fixed point).
    names : tuple of str
        Names of the map's coordinates (``base``'s entries, :attr:`PoincareMap.names`).
    criterion_labels : ndarray of int or None
        A mapper's labels against the orbit of label 0
        (:data:`~hybridpd.analysis.labels.LABELS`), when one labelled the grid.
    windows : tuple of (xmin, xmax, ymin, ymax)
        Every window labelled (the last is the grid's); empty for a single window.
    edges : tuple of str
        Sides (``"x1 min"``, ...) of the final window on which the basin of label 0 lies.
    metadata : dict
        Parameters, iterations, criterion, model.
    axis_attrs : dict
        Attributes (``units``, ``long_name``) of the grid's coordinates in a dataset, by
        coordinate name.

    Examples
    --------
    >>> import tempfile
    >>> b = BasinResult(np.arange(3.0), np.arange(2.0), np.array([[0, 0, -2], [0, -1, -2]]),
    ...                 (Attractor(0, "period-1 orbit", 1), outcome(-1), outcome(-2)))
    >>> b.fraction(0), b.measure(-2).percent
    (0.5, '33.33 %')
    >>> back = BasinResult.load(b.save(tempfile.mkdtemp() + "/b.nc"))
    >>> back.labels.tolist(), [a.name for a in back.attractors]
    ([[0, 0, -2], [0, -1, -2]], ['period-1 orbit', 'no convergence', 'diverged'])
    """

    kind = "basin"
    x: np.ndarray = field(metadata={"coord": "@x_name"})
    y: np.ndarray = field(metadata={"coord": "@y_name"})
    labels: np.ndarray = field(metadata={"dims": ("@y_name", "@x_name"),
                                         "long_name": "attractor reached"})
    attractors: tuple = ()
    iterations: np.ndarray | None = field(
        default=None, repr=False, metadata={"dims": ("@y_name", "@x_name"),
                                            "long_name": "iterations of the map run"})
    x_name: str = "x"
    y_name: str = "y"
    base: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    names: tuple = ()
    criterion_labels: np.ndarray | None = field(
        default=None, repr=False, metadata={"dims": ("@y_name", "@x_name"),
                                            "long_name": "label against the orbit"})
    windows: tuple = ()
    edges: tuple = ()
    metadata: dict = field(default_factory=dict, repr=False)
    axis_attrs: dict = field(default_factory=dict, repr=False)
    __repr__ = compact_repr

    def __post_init__(self):
        put = lambda k, v: object.__setattr__(self, k, v)
        put("x", np.asarray(self.x, float))
        put("y", np.asarray(self.y, float))
        put("labels", np.asarray(self.labels, np.int64))
        if self.iterations is None:
            put("iterations", np.zeros(self.labels.shape, np.int64))
        put("iterations", np.asarray(self.iterations, np.int64))
        if self.criterion_labels is not None:
            put("criterion_labels", np.asarray(self.criterion_labels, np.int64))
        put("attractors", tuple(a if isinstance(a, Attractor) else Attractor.from_dict(a)
                                for a in self.attractors))
        put("base", np.asarray(self.base, float).ravel())
        put("names", tuple(str(c) for c in self.names))
        put("windows", tuple(tuple(float(v) for v in w) for w in self.windows))
        put("edges", tuple(self.edges))
        put("metadata", dict(self.metadata or {}))
        put("axis_attrs", dict(self.axis_attrs or {}))

    def __getattr__(self, name):
        # a grid axis by its coordinate's name (the pair's slice: b.x1, b.y1)
        if not name.startswith("_"):
            d = self.__dict__
            if d.get("x_name") == name:
                return d["x"]
            if d.get("y_name") == name:
                return d["y"]
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    # ---- the slice --------------------------------------------------------------------
    @property
    def axes(self) -> tuple:
        """``(x_name, y_name)``."""
        return (self.x_name, self.y_name)

    @property
    def fixed_point(self) -> np.ndarray:
        """:attr:`base`: the orbit of label 0's section point, when a criterion was used."""
        return self.base

    @property
    def window(self) -> tuple:
        """``(xmin, xmax, ymin, ymax)`` of the grid."""
        return (float(self.x[0]), float(self.x[-1]), float(self.y[0]), float(self.y[-1]))

    @property
    def reaches_edge(self) -> bool:
        """The basin of label 0 touches the final window's edge (its measure is a lower
        bound on a larger window)."""
        return bool(self.edges)

    @property
    def source(self) -> str:
        """The model file (``metadata["model"]``; empty for other maps)."""
        return str(self.metadata.get("model", ""))

    # ---- measures ---------------------------------------------------------------------
    def attractor(self, label: int) -> Attractor:
        """The attractor (or outcome) with ``label``."""
        for a in self.attractors:
            if a.label == label:
                return a
        raise ValueError(f"label must be one of {[a.label for a in self.attractors]}, "
                         f"got {label!r}")

    def _whole(self, label: int) -> int:
        # one denominator: every point of the slice (a point off the section or
        # inadmissible is its own class, never part of a basin's share)
        del label
        return int(self.labels.size)

    def fraction(self, label: int) -> float:
        """Share of all points of the grid (the slice) with ``label``: points off the
        section and inadmissible ones are counted in the denominator, in no basin."""
        whole = self._whole(int(label))
        return float((self.labels == label).sum() / whole) if whole else 0.0

    @property
    def converged_fraction(self) -> float:
        """:meth:`fraction` of label 0 (of all points of the slice)."""
        return self.fraction(0)

    @property
    def outside(self) -> int:
        """Points off the section (at the start, or whose iterates left it) or inadmissible
        (never iterated): in no basin."""
        return int(np.isin(self.labels, _OUTSIDE).sum())

    def _cell(self) -> float:
        dx = (self.x[-1] - self.x[0]) / max(len(self.x) - 1, 1)
        dy = (self.y[-1] - self.y[0]) / max(len(self.y) - 1, 1)
        return float(dx * dy)

    def area(self, label=0) -> float:
        """Area (units of ``x`` times ``y``) of the cells with ``label`` (an attractor code,
        or a name of :data:`~hybridpd.analysis.labels.LABELS`)."""
        if isinstance(label, str):
            label = -LABELS.index(label)
        return float((self.labels == label).sum() * self._cell())

    def measure(self, label: int) -> BasinMeasure:
        """Count, fraction, area and formatted percentage of the basin of ``label``."""
        a = self.attractor(label)
        n, whole = int((self.labels == label).sum()), self._whole(label)
        pct = format_percent(n, whole) if whole else "0 %"
        return BasinMeasure(label, a.name, n, n / whole if whole else 0.0, n * self._cell(), pct)

    def measures(self) -> list:
        """:meth:`measure` of every entry of :attr:`attractors`."""
        return [self.measure(a.label) for a in self.attractors]

    def summary(self) -> list:
        """Lines in words: window, edge flag, then one line per attractor."""
        x0, x1, y0, y1 = self.window
        head = f"{Path(self.source).name}: slice" if self.source else "window"
        tried = f", {len(self.windows)} window(s) tried" if self.windows else ""
        lines = [(f"{head} {self.x_name} in [{x0:g}, {x1:g}], {self.y_name} in "
                  f"[{y0:g}, {y1:g}] ({len(self.x)} x {len(self.y)} points{tried})")]
        N, out = int(self.labels.size), self.outside
        if out:
            lines.append(f"off the section or inadmissible: {out} of the {N} points "
                         f"({format_percent(out, N)}), in no basin: every share below is of "
                         f"all {N} points")
        if self.reaches_edge:
            lines.append("the basin of label 0 reaches the window edge ("
                         + ", ".join(self.edges) + "): its measure is a lower bound")
        for a, m in zip(self.attractors, self.measures()):
            extra = ""
            if a.periodic and np.isfinite(a.spectral_radius):
                stab = "stable" if a.stable else ("unstable" if a.stable is False else "?")
                extra = f"; {stab}, spectral radius {a.spectral_radius:.4g}"
            if a.label == INADMISSIBLE_LABEL:
                extra = f" ({m.count} points, not iterated)"
            lines.append(f"{m.name}: {m.percent} of the {N} points, area {m.area:.4g}{extra}")
        return lines

    # ---- files ------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """JSON-ready description: every field, each attractor with its measure."""
        d = super().to_dict()
        d["attractors"] = [dict(a.to_dict(), count=m.count, fraction=m.fraction, area=m.area,
                                percent=m.percent)
                           for a, m in zip(self.attractors, self.measures())]
        d.update(window=list(self.window), reaches_edge=self.reaches_edge,
                 converged_fraction=self.converged_fraction, points=int(self.labels.size),
                 outside=self.outside)
        return d

    def to_dataset(self):
        """An :class:`xarray.Dataset` with dimensions ``(y_name, x_name)``; ``labels`` carries
        CF ``flag_values``/``flag_meanings`` naming the attractors, e.g.
        ``(b.to_dataset().labels == 0).plot()`` draws the basin of label 0."""
        ds = super().to_dataset()
        ds.attrs["attractors"] = "json:" + json.dumps([a.to_dict() for a in self.attractors])
        ds["labels"].attrs.update(flag_values=[a.label for a in self.attractors],
                                  flag_meanings=" ".join(a.name.replace(" ", "_")
                                                         for a in self.attractors))
        for n in self.axes:
            ds[n].attrs.update(self.axis_attrs.get(n, {}))
        if self.criterion_labels is not None:
            ds["criterion_labels"].attrs.update(flag_values=list(range(len(LABELS))),
                                                flag_meanings=" ".join(LABELS))
        return ds

    @classmethod
    def from_dataset(cls, ds) -> BasinResult:
        """Inverse of :meth:`to_dataset`."""
        a = decode_attrs(ds.attrs)
        kind = a.get("kind")
        if kind != "basin" or "attractors" not in a:
            raise ValueError(f"the dataset does not hold a basin (it holds a {kind!r}: "
                             "attribute kind)")
        return super().from_dataset(ds)


def load_basin(path) -> BasinResult:
    """Read a :class:`BasinResult` written by :meth:`BasinResult.save`.

    Parameters
    ----------
    path : str or path
        A ``.nc``, ``.zarr`` or ``.npz`` file.

    Returns
    -------
    BasinResult

    Raises
    ------
    ValueError
        If the suffix is unknown or the file holds something else.

    Examples
    --------
    >>> import tempfile, os
    >>> b = BasinResult(np.arange(2.0), np.arange(2.0), np.zeros((2, 2), int),
    ...                 (Attractor(0, "period-1 orbit", 1),))
    >>> load_basin(b.save(os.path.join(tempfile.mkdtemp(), "b.npz"))).labels.tolist()
    [[0, 0], [0, 0]]
    """
    return BasinResult.load(path)


# ----------------------------------------------------------------------------------------
# the slice of a basin
# ----------------------------------------------------------------------------------------
class Slice(NamedTuple):
    """A basin's grid: axes ``x``, ``y``, section points ``S`` (shape ``(len(x) len(y),
    dim)``, row-major over ``(y, x)``), coordinate ``names``, their ``units`` (dataset
    attributes by name), the ``base`` point whose other coordinates the slice holds and its
    ``centre`` (the base in the slice's coordinates, where a growing window grows from)."""

    x: np.ndarray
    y: np.ndarray
    S: np.ndarray
    names: tuple
    units: dict
    base: np.ndarray
    centre: tuple


def off_section_axis(what: str, name: str, sec) -> str:
    """The message refusing ``name`` as a slice axis of section `sec`: a state the section
    fixes (moving it would leave the section: the constraint is named) or no state at all."""
    why = sec.fixed_by(name)
    if why:
        return (f"{what}: {name!r} is no coordinate of this section ({why}); a slice along it "
                f"would leave the section. The section's coordinates are {list(sec.names)}")
    return f"{what}: {name!r} is no section coordinate; they are {list(sec.names)}"


def _axis_index(a, P, refuse) -> int:
    names = P.names
    if isinstance(a, str):
        if a not in names:
            raise ValueError(refuse(a) if refuse is not None else
                             f"axes: {a!r} is no coordinate; they are {list(names)}")
        return names.index(a)
    if isinstance(a, (bool, np.bool_)) or not isinstance(a, (int, np.integer)) \
            or not 0 <= int(a) < P.dim:
        raise ValueError(f"axes: {a!r} must be a coordinate name or an index in "
                         f"[0, {P.dim})")
    return int(a)


def grid_slice(P: PoincareMap, x, y, axes=None, base=None, *, refuse=None) -> Slice:
    """The grid ``x`` times ``y`` over two coordinates ``axes`` of ``P`` (names or indices,
    default the first two), the other coordinates at ``base``'s values (required when the
    map has more than two); ``refuse(name)``: the message for a name that is no coordinate."""
    axes = P.names[:2] if axes is None else tuple(axes)
    if len(axes) != 2:
        raise ValueError(f"axes must name two coordinates of {P.names}, got {axes!r}")
    idx = [_axis_index(a, P, refuse) for a in axes]
    if idx[0] == idx[1]:
        raise ValueError("axes must be two different coordinates")
    if base is None:
        if P.dim > 2:
            raise ValueError(f"base: give the point whose other coordinates the slice holds "
                             f"(the map has {P.dim} coordinates)")
        base = np.zeros(P.dim)
    base = P.check_point(base).copy()
    xs, ys = check_axis("x", x), check_axis("y", y)
    X, Y = np.meshgrid(xs, ys)
    S = np.tile(base, (X.size, 1))
    S[:, idx[0]], S[:, idx[1]] = X.ravel(), Y.ravel()
    return Slice(xs, ys, S, tuple(P.names[i] for i in idx), {}, base,
                 (float(base[idx[0]]), float(base[idx[1]])))
