"""Basins of attraction of any map, labelled by the attractor each point reaches.

A basin is a thin layer over one question asked of every point of a 2-D slice: where does
iterating the map take it? (Attractors.jl's "initial condition -> label" mapper.) Every grid
point is iterated ``n_iter`` times (:meth:`~hybridpd.analysis.maps.PoincareMap.iterate_many`,
which a map may compile); its tail is then either periodic, of period ``k <= max_period``
(:func:`~hybridpd.analysis.maps.detect_period`), and its cycle is matched against the
attractors found so far (a new one is refined by Newton on ``P^k``,
:func:`~hybridpd.analysis.periodic.find_orbit`, and named by its period and stability), or
one of the outcomes :data:`OUTCOMES`: no convergence within the iterations, divergence
(non-finite, or beyond ``escape``), sticking, the map stopped for another reason
(``unresolved``, its status kept), a start off the map's domain, or (slices of a section with
an admissible set) an inadmissible start. Labels ``0, 1, ...`` are the attractors in the order
found; outcomes are negative.

:class:`BasinResult` is the one basin result: of any map, of the impact pair's slice
``(x1, y1)`` and of a model file's section alike, with the grid's coordinate names, the
attractors (:class:`Attractor`), optionally the labels of a mapper's criterion against one
orbit (:data:`~hybridpd.analysis.labels.LABELS`, ``criterion_labels``) and the windows tried.
It is a :class:`hybridpd._results.Result` (``.nc``/``.zarr`` files, ``to_dict``); files of
earlier versions (``basin``, ``attractor_basin`` and ``model_basin`` datasets, ``.npz``) read
back as one.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from hybridpd._format import format_percent
from hybridpd._results import Result, check_suffix, compact_repr, decode_attrs, jsonable
from hybridpd.analysis import _basin_files
from hybridpd.analysis.labels import LABELS
from hybridpd.analysis.maps import PoincareMap, check_returns, detect_period
from hybridpd.analysis.periodic import find_orbit
from hybridpd.model import check_axis

__all__ = ["DIVERGED", "INADMISSIBLE_LABEL", "NO_CONVERGENCE", "OFF_SECTION_LABEL", "OUTCOMES",
           "STICKING", "UNRESOLVED", "Attractor", "BasinMeasure", "BasinResult",
           "basin_of_attraction", "from_criterion", "load_basin", "outcome"]

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
class Attractor:
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

    def to_dict(self) -> dict:
        """JSON-ready description (complex multipliers as ``[re, im]``)."""
        return {f.name: jsonable(getattr(self, f.name)) for f in fields(self)}

    @classmethod
    def from_dict(cls, d: dict) -> Attractor:
        """Inverse of :meth:`to_dict` (also reads the dictionaries of earlier versions)."""
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
        """Inverse of :meth:`to_dataset`; datasets of earlier versions (kinds ``basin``,
        ``attractor_basin``, ``model_basin``) read too."""
        a = decode_attrs(ds.attrs)
        kind = a.get("kind")
        if kind == "basin" and "attractors" in a:
            return super().from_dataset(ds)
        if kind not in ("basin", "attractor_basin", "model_basin"):
            raise ValueError(f"the dataset does not hold a basin (it holds a {kind!r}: "
                             "attribute kind)")
        return _from_old(kind, a, {k: ds[k].values for k in ds.variables})

    def save(self, path) -> Path:
        """Write to ``.nc`` or ``.zarr`` (:meth:`to_dataset`), or ``.npz``, by suffix."""
        if check_suffix(path) != ".npz":
            return super().save(path)
        return _basin_files.write_basin_npz(self, Path(path))

    @classmethod
    def load(cls, path) -> BasinResult:
        """Read a basin written by :meth:`save` (or by earlier versions)."""
        if check_suffix(path) != ".npz":
            return super().load(path)
        kind, meta, arrays = _basin_files.read_basin_npz(Path(path))
        new = kind == "basin" and "attractors" in meta
        return cls(**arrays, **meta) if new else _from_old(kind, meta, arrays)


_PAIR_COORDS = ("phi", "z1", "z2", "z4")


def _from_old(kind: str, a: dict, v: dict) -> BasinResult:
    """A basin of an earlier version's file: attributes (or ``.npz`` metadata) ``a`` and
    arrays ``v``."""
    if kind == "model_basin":
        xn, yn = a["x_name"], a["y_name"]
        return BasinResult(v[xn], v[yn], v["attractor"], a["attractors"], v["iterations"],
                           xn, yn, a["fixed_point"], a["section_coordinates"],
                           v["criterion_label"], metadata=dict(a.get("metadata") or {},
                                                               model=a["model"]))
    x, y = v.get("x1"), v.get("y1")
    fp = a.get("fixed_point", v.get("fixed_point"))
    if kind == "basin":
        crit = np.asarray(v["labels"], np.int64)
        lab = from_criterion(crit)
        drop = ("fixed_point", "converged_fraction", "fixed_point_coordinates", "label_names")
        meta = {k: w for k, w in a.items() if k not in drop}
        sym = Attractor(0, "converged to the symmetric orbit", 1,
                        np.asarray(fp, float).reshape(1, -1), kind="symmetric")
        atts = (sym,) + tuple(outcome(k, meta.get("n_iter")) for k in sorted(OUTCOMES)[::-1]
                              if np.any(lab == k))
        return BasinResult(x, y, lab, atts, v["iterations"], "x1", "y1", fp, _PAIR_COORDS,
                           crit, metadata=meta)
    crit = v["criterion_label"] if "criterion_label" in v else v["criterion_labels"]
    lab = v["attractor"] if "attractor" in v else v["labels"]
    skip = ("attractors", "windows", "edges", "fixed_point", "converged_fraction",
            "basin_metadata", "metadata", "kind")
    meta = dict(a.get("basin_metadata") or {}, **(a.get("metadata") or {}),
                **{k: w for k, w in a.items() if k not in skip})
    return BasinResult(x, y, lab, a["attractors"], v["iterations"], "x1", "y1", fp,
                       _PAIR_COORDS, crit, a.get("windows", ()), a.get("edges", ()), meta)


def load_basin(path) -> BasinResult:
    """Read a :class:`BasinResult` written by :meth:`BasinResult.save`.

    Parameters
    ----------
    path : str or path
        A ``.nc``, ``.zarr`` or ``.npz`` file; files of earlier versions (the pair's basins,
        attractor basins and model basins) read too.

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
# the catalogue of cycles and the generic basin
# ----------------------------------------------------------------------------------------
class Catalogue:
    """The periodic attractors found in the tails of trajectories, with integer labels.

    The one catalogue interface of basins: :attr:`attractors`, :attr:`tail_length` and
    :meth:`assign`. A tail (the last iterates of one trajectory) is periodic of period ``p <=
    max_period`` (:func:`~hybridpd.analysis.maps.detect_period`); its cycle is matched against
    the attractors found so far (to ``1e3 tol`` relative), else refined by Newton on ``P^p``
    (:func:`~hybridpd.analysis.periodic.find_orbit`) and added. A map with its own metric
    (the impact pair's criterion: :class:`hybridpd.pair.attractors.CycleCatalog`) supplies its
    own catalogue with this interface.

    Parameters
    ----------
    P : PoincareMap
    period : int
        ``k``: the tails are iterates of ``P^k``.
    max_period : int
        Largest period searched (in applications of ``P^k``).
    tol : float
        Relative tolerance of the period test.
    orbit : array_like, shape (dim,), optional
        A point of a known orbit, label 0 (a criterion's fixed point).

    Examples
    --------
    >>> import hybridpd as hp
    >>> class Logistic(hp.PoincareMap):
    ...     names = ("x",)
    ...     def apply(self, s, k=1, jacobian=False):
    ...         x = np.asarray(s, float)
    ...         for _ in range(k):
    ...             x = 3.2 * x * (1 - x)
    ...         return hp.MapResult(x)
    >>> P = Logistic()
    >>> cat = Catalogue(P, max_period=4)
    >>> cat.assign(P.iterate([0.3], 300)[None, -cat.tail_length:]).tolist()
    [0]
    >>> cat.attractors[0].name, cat.attractors[0].period
    ('period-2 orbit (stable)', 2)
    """

    def __init__(self, P: PoincareMap, *, period: int = 1, max_period: int = 8,
                 tol: float = 1e-6, orbit=None):
        self.P, self.k = P, check_returns(period)
        self.max_period, self.tol = int(max_period), float(tol)
        self.attractors: list = []
        if orbit is not None:
            s = P.check_point(orbit)
            self.attractors.append(Attractor(0, f"period-{self.k} orbit", 1, s.reshape(1, -1)))

    @property
    def tail_length(self) -> int:
        """Iterates per tail that show ``max_period`` twice: ``2 max_period + 1``."""
        return 2 * self.max_period + 1

    def assign(self, tails) -> np.ndarray:
        """Labels of tails of shape ``(M, K, dim)``: an attractor's, or ``NO_CONVERGENCE``
        (new cycles are added to :attr:`attractors`)."""
        tails = np.asarray(tails, float)
        lab = np.full(len(tails), NO_CONVERGENCE, np.int64)
        for i, tail in enumerate(tails):
            if np.all(np.isfinite(tail)):
                lab[i] = self._label(tail)
        return lab

    def _label(self, tail) -> int:
        p = detect_period(tail, self.P.wrap, self.max_period, self.tol)
        if not p:
            return NO_CONVERGENCE
        cycle = tail[-p:]
        for a in self.attractors:
            if a.period == p and self._on(cycle[-1], a.points):
                return a.label
        return self._add(cycle, p)

    def _on(self, s, points) -> bool:
        d = np.max(np.abs(self.P.wrap(points - s)), axis=1)
        return bool(np.min(d) <= 1e3 * self.tol * max(1.0, float(np.max(np.abs(s)))))

    def _add(self, cycle, p) -> int:
        po = find_orbit(self.P, cycle[-1], p * self.k, max_iter=30)
        pts = cycle if not po.converged else self.P.iterate(po.s, p - 1, self.k)
        pts = pts[np.argsort(pts[:, 0])]
        label = len(self.attractors)
        stab = "stable" if po.converged and po.stable else "unstable"
        name = f"period-{p} orbit ({stab})" if po.converged else f"period-{p} cycle"
        self.attractors.append(Attractor(label, name, p, pts, po.multipliers,
                                         po.spectral_radius, bool(po.converged and po.stable)))
        return label


def _grid(P, x, y, axes, base):
    names = P.names
    if axes is None:
        axes = names[:2]
    if len(axes) != 2:
        raise ValueError(f"axes must name two coordinates of {names}, got {axes!r}")
    idx = []
    for a in axes:
        if isinstance(a, str):
            if a not in names:
                raise ValueError(f"axes: {a!r} is no coordinate; they are {list(names)}")
            idx.append(names.index(a))
        elif isinstance(a, (int, np.integer)) and 0 <= int(a) < P.dim:
            idx.append(int(a))
        else:
            raise ValueError(f"axes: {a!r} must be a coordinate name or index")
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
    return xs, ys, S, tuple(names[i] for i in idx), base


def basin_of_attraction(P: PoincareMap, x, y, *, axes=None, base=None, period: int = 1,
                        n_iter: int = 500, max_period: int = 8, tol: float = 1e-6,
                        escape: float = 1e6, criterion=None, catalogue=None,
                        **options) -> BasinResult:
    """Label a 2-D slice of a map's section by the attractor each point reaches.

    Without ``criterion`` every point is iterated ``n_iter`` times
    (:meth:`~hybridpd.analysis.maps.PoincareMap.iterate_many`, which a map may compile) and
    its tail is labelled by the :class:`Catalogue`. With a ``criterion`` (a basin mapper, e.g.
    :class:`~hybridpd.analysis.periodic.SectionMapper` or the impact pair's
    :class:`~hybridpd.pair.basins.ImpactMapper`: ``labels(S)``, ``fixed_point``, ``n_iter``)
    the points are first labelled against its orbit (label 0: the criterion holds after its
    iterations; the others its outcomes, :func:`from_criterion`), and only the points that did
    not converge are examined for other attractors (``max_period = 0``: not at all). The
    criterion's hooks, where it has them, supply the speed and what only its map has:
    ``slice(x, y, axes)`` (the slice's section points, coordinate names and units, e.g. the
    pair's ``(x1, y1)``), ``label_tails(S, tail, **options)`` (labels, iterations and the tails
    of the unconverged points in one compiled sweep; ``options`` are its executor, store and
    progress), ``catalogue(max_period)`` (the attractor catalogue of its metric), ``basin_metadata()``
    and ``orbit_name`` (label 0's name when no attractor is searched).

    Parameters
    ----------
    P : PoincareMap
    x, y : (min, max, num)
        The grid of the two coordinates ``axes``.
    axes : (str or int, str or int), optional
        The coordinates the grid spans (default the first two, or the criterion's slice).
    base : array_like, shape (dim,), optional
        The other coordinates (required when the map has more than two; with a criterion,
        its fixed point).
    period : int
        ``k``: iterate ``P^k`` (without a criterion).
    n_iter : int
        Iterations per point (without a criterion; a criterion has its own).
    max_period : int
        Largest period of an attractor (in applications of ``P^k``); 0: no search beyond the
        criterion's orbit.
    tol : float
        Relative tolerance of the period test.
    escape : float
        Bound on the coordinates (the phase excepted): diverged beyond.
    criterion : basin mapper, optional
        Labels the points against one orbit first (see above).
    catalogue : Catalogue, optional
        The attractors found so far (shared between calls, e.g. over growing windows).
    **options
        Passed to the criterion's ``label_tails`` hook (e.g. ``executor``, ``chunk_size``,
        ``store``, ``progress``, ``max_workers`` of :func:`hybridpd.sweeps.sweep.run_sweep`).

    Returns
    -------
    BasinResult

    Examples
    --------
    A contraction toward the origin: every point reaches it.

    >>> import hybridpd as hp
    >>> class Half(hp.PoincareMap):
    ...     names = ("x", "y")
    ...     def apply(self, s, k=1, jacobian=False):
    ...         return hp.MapResult(np.asarray(s, float) * 0.5 ** k)
    >>> b = hp.basin_of_attraction(Half(), x=(-1, 1, 5), y=(-1, 1, 3), n_iter=80)
    >>> b.labels.tolist(), b.attractors[0].name
    ([[0, 0, 0, 0, 0], [0, 0, 0, 0, 0], [0, 0, 0, 0, 0]], 'period-1 orbit (stable)')
    """
    if criterion is None and not isinstance(P, PoincareMap) and hasattr(P, "labels"):
        # the call form of earlier versions: basin_of_attraction(mapper, x1, y1)
        criterion, P = P, getattr(P, "map", None)
    if not isinstance(P, PoincareMap):
        raise ValueError(f"P must be a PoincareMap, got {type(P).__name__}")
    max_period = int(max_period)
    if criterion is not None:
        if not (callable(getattr(criterion, "labels", None)) and hasattr(criterion, "n_iter")
                and hasattr(criterion, "fixed_point")):
            raise ValueError(f"criterion must be a basin mapper (labels(S), fixed_point, "
                             f"n_iter), got {type(criterion).__name__}")
        if max_period < 0:
            raise ValueError(f"max_period must be >= 0, got {max_period}")
        return _criterion_basin(P, criterion, x, y, axes, max_period, tol, catalogue, options)
    if options:
        raise ValueError(f"{', '.join(sorted(options))}: options of a criterion's labeller; "
                         "give criterion=")
    k = check_returns(period)
    n_iter = int(n_iter)
    if n_iter < 4 * max_period or max_period < 1:
        raise ValueError(f"n_iter must be >= 4 max_period (got {n_iter}, {max_period})")
    xs, ys, S, names, base = _grid(P, x, y, axes, base)
    cat = catalogue or Catalogue(P, period=k, max_period=max_period, tol=tol)
    tails, status, its = P.iterate_many(S, n_iter, k, cat.tail_length)
    lab = np.full(len(S), NO_CONVERGENCE, np.int64)
    off = 1 if P.period is not None else 0
    for i in range(len(S)):
        st = status[i]
        if st:
            lab[i] = {"off_section": OFF_SECTION_LABEL, "nonfinite": DIVERGED,
                      "sticking": STICKING}.get(st, UNRESOLVED)
        elif np.any(np.abs(tails[i][:, off:]) > escape):
            lab[i] = DIVERGED
        else:
            lab[i] = cat.assign(tails[i][None])[0]
    stops = sorted({status[i] for i in range(len(S)) if lab[i] == UNRESOLVED})
    outcomes = tuple(Attractor(c, OUTCOMES[c][1] + (f" ({', '.join(stops)})"
                                                    if c == UNRESOLVED else ""),
                               kind=OUTCOMES[c][0])
                     for c in sorted(OUTCOMES, reverse=True) if np.any(lab == c))
    shape = (len(ys), len(xs))
    meta = {"n_iter": n_iter, "period": k, "max_period": max_period, "tol": float(tol)}
    return BasinResult(xs, ys, lab.reshape(shape), tuple(cat.attractors) + outcomes,
                       its.reshape(shape), names[0], names[1], base, tuple(P.names),
                       metadata=meta)


def _criterion_basin(P, crit, x, y, axes, max_period, tol, catalogue, options):
    """:func:`basin_of_attraction` with a criterion's labels first (its docstring)."""
    hook = getattr(crit, "slice", None)
    if hook is not None:
        xs, ys, S, names, units = hook(x, y, axes)
    else:
        xs, ys, S, names, _ = _grid(P, x, y, axes, crit.fixed_point)
        units = {}
    cat = catalogue
    if cat is None and max_period:
        make = getattr(crit, "catalogue", None)
        cat = make(max_period) if make is not None else Catalogue(
            P, period=getattr(crit, "period", 1), max_period=max_period, tol=tol,
            orbit=crit.fixed_point)
    tail = cat.tail_length if max_period else 0
    hook = getattr(crit, "label_tails", None)
    out = hook(S, tail, **options) if hook is not None else _label_tails(P, crit, S, tail,
                                                                         options)
    shape = (len(ys), len(xs))
    crit_lab = np.asarray(out["label"], np.int64).reshape(shape)
    lab = from_criterion(crit_lab)
    if tail:
        nc = crit_lab == 1
        lab[nc] = cat.assign(np.asarray(out["tail"]).reshape(shape + (tail + 1, -1))[nc])
    present = set(np.unique(lab).tolist())
    if cat is not None:
        entries = [a for a in cat.attractors if a.label == 0 or a.label in present]
    else:   # no search: the criterion's orbit as the criterion names it
        k = getattr(crit, "period", 1)
        entries = [Attractor(0, getattr(crit, "orbit_name", f"period-{k} orbit"), k,
                             np.asarray(crit.fixed_point, float).reshape(1, -1),
                             kind=getattr(crit, "orbit_kind", "periodic"))]
    entries += [outcome(c, crit.n_iter) for c in sorted(OUTCOMES, reverse=True) if c in present]
    meta = {"n_iter": int(crit.n_iter), "criterion": float(crit.criterion),
            "max_period": max_period}
    meta.update(getattr(crit, "basin_metadata", dict)())
    return BasinResult(xs, ys, lab, tuple(entries), np.asarray(out["iterations"]).reshape(shape),
                       names[0], names[1], np.asarray(crit.fixed_point, float).copy(),
                       tuple(P.names), crit_lab, metadata=meta, axis_attrs=units)


def _label_tails(P, crit, S, tail, options) -> dict:
    """Labels and iterations of a criterion without hooks; the tails (iterates ``n_iter ..
    n_iter + tail``) of the points that did not converge by iterating ``P`` again."""
    if options:
        raise ValueError(f"{', '.join(sorted(options))}: this criterion has no label_tails "
                         "hook to take them")
    lab, its = crit.labels(S)
    out = {"label": lab, "iterations": its}
    if tail:
        tails = np.full((len(S), tail + 1, P.dim), np.nan)
        nc = np.flatnonzero(np.asarray(lab) == 1)
        if nc.size:
            k = getattr(crit, "period", 1)
            tails[nc] = P.iterate_many(S[nc], int(crit.n_iter) + tail, k, tail + 1)[0]
        out["tail"] = tails
    return out
