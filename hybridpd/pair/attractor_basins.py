"""Attractor-labelled basins: which attractor each point of a section slice reaches, measured.

:func:`attractor_basin` labels each point with the attractor it reaches: ``0`` the symmetric
orbit (the paper's criterion, :class:`~hybridpd.pair.basins.ImpactMapper`), ``1, 2, ...``
other periodic orbits of ``P`` found in the iterates ``n_iter .. n_iter + max_period + 2`` of
the unconverged points and refined by Newton on ``P^k``
(:class:`hybridpd.pair.attractors.CycleCatalog`), negative codes for sticking,
divergence, no convergence within the iterations, unresolved flights and points off the
section. The result (:class:`AttractorBasin`) lists the attractors (section points, period,
multipliers, stability) and measures each basin (grid count, share of the on-section grid,
area). While the symmetric orbit's basin touches the window's edge the window is extended (a
bounded number of times); the result says whether it still does. :func:`format_percent`
never rounds a share to ``100 %`` or ``0 %`` when some points differ. Results are written as
``.nc``, ``.zarr`` (an :class:`xarray.Dataset`, :meth:`AttractorBasin.to_dataset`) or
``.npz``, by suffix.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hybridpd._format import format_percent
from hybridpd._results import compact_repr
from hybridpd.model import check_axis
from hybridpd.pair.attractors import (
    DIVERGED,
    NO_CONVERGENCE,
    OFF_SECTION_LABEL,
    OUTCOMES,
    STICKING,
    UNRESOLVED,
    Attractor,
    CycleCatalog,
    outcome,
)
from hybridpd.pair.basins import (
    LABELS,
    OFF_SECTION,
    BasinResult,
    ImpactMapper,
    _basin_result,
    _label_grid,
)
from hybridpd.sweeps.labelled import (
    axis_attrs,
    decode_attrs,
    encode_attrs,
    load_result,
    save_result,
)

__all__ = ["AttractorBasin", "BasinMeasure", "attractor_basin", "format_percent",
           "load_attractor_basin"]


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
        ``count`` over the on-section grid points (``off_section``: over all points).
    area : float
        ``count`` times the grid cell area (``x1``-``y1`` units).
    percent : str
        ``fraction`` formatted by :func:`format_percent`.
    """

    label: int
    name: str
    count: int
    fraction: float
    area: float
    percent: str


@dataclass(frozen=True)
class AttractorBasin:
    """Attractor-labelled basin slice ``(x1, y1)`` (``phi = phi*``, ``y2 = y2*``).

    Attributes
    ----------
    x1, y1 : ndarray
        Grid axes of the final window.
    labels : ndarray of int, shape (len(y1), len(x1))
        Attractor labels: ``0`` the symmetric orbit (the paper's criterion), ``1, 2, ...`` other
        periodic orbits of ``P`` (see :attr:`attractors`), negative codes the outcomes of
        :data:`hybridpd.pair.attractors.OUTCOMES`.
    attractors : tuple of Attractor
        The symmetric orbit, every periodic attractor found, and the outcomes present.
    basin : BasinResult
        The paper's labels (:data:`LABELS`) on the same grid.
    windows : tuple of (x1min, x1max, y1min, y1max)
        Every window labelled, the last one is the grid's.
    edges : tuple of str
        Sides (``"x1 min"``, ``"x1 max"``, ``"y1 min"``, ``"y1 max"``) of the final window on
        which a point of the symmetric orbit's basin lies.
    metadata : dict
    """

    x1: np.ndarray
    y1: np.ndarray
    labels: np.ndarray
    attractors: tuple
    basin: BasinResult
    windows: tuple
    edges: tuple
    metadata: dict = field(default_factory=dict)
    __repr__ = compact_repr

    @property
    def reaches_edge(self) -> bool:
        """The symmetric orbit's basin touches the final window's edge: its measure is a lower
        bound on a larger window."""
        return bool(self.edges)

    @property
    def window(self) -> tuple:
        return self.windows[-1]

    @property
    def fixed_point(self) -> np.ndarray:
        return self.basin.fixed_point

    def attractor(self, label: int):
        """The :class:`Attractor` with ``label``."""
        for a in self.attractors:
            if a.label == label:
                return a
        raise ValueError(f"label must be one of {[a.label for a in self.attractors]}, "
                         f"got {label!r}")

    def _cell(self) -> float:
        dx = (self.x1[-1] - self.x1[0]) / max(len(self.x1) - 1, 1)
        dy = (self.y1[-1] - self.y1[0]) / max(len(self.y1) - 1, 1)
        return float(dx * dy)

    def measure(self, label: int) -> BasinMeasure:
        """Count, fraction, area and formatted percentage of the basin of ``label``."""
        a = self.attractor(label)
        n = int((self.labels == label).sum())
        whole = self.labels.size if label == OFF_SECTION_LABEL else int(
            (self.labels != OFF_SECTION_LABEL).sum())
        frac = n / whole if whole else 0.0
        pct = format_percent(n, whole) if whole else "0 %"
        return BasinMeasure(label, a.name, n, frac, n * self._cell(), pct)

    def measures(self) -> list:
        """:meth:`measure` of every entry of :attr:`attractors`."""
        return [self.measure(a.label) for a in self.attractors]

    def summary(self) -> list:
        """Lines in words: window, edge flag, then one line per attractor."""
        x0, x1, y0, y1 = self.window
        lines = [(f"window x1 in [{x0:g}, {x1:g}], y1 in [{y0:g}, {y1:g}] "
                 f"({len(self.x1)} x {len(self.y1)} points, {len(self.windows)} window(s) tried)")]
        if self.reaches_edge:
            lines.append("the symmetric orbit's basin reaches the window edge ("
                         + ", ".join(self.edges) + "): its measure is a lower bound")
        for a, m in zip(self.attractors, self.measures()):
            extra = ""
            if a.periodic:
                rho = a.spectral_radius
                stab = "stable" if a.stable else ("unstable" if a.stable is False else "?")
                extra = f"; {stab}, spectral radius {rho:.4g}"
            where = "window" if a.label == OFF_SECTION_LABEL else "on-section grid"
            lines.append(f"{m.name}: {m.percent} of the {where}, area {m.area:.4g}{extra}")
        return lines

    def to_dict(self) -> dict:
        """JSON-ready description (without the label array)."""
        return {"window": list(self.window), "windows": [list(w) for w in self.windows],
                "edges": list(self.edges), "reaches_edge": self.reaches_edge,
                "shape": list(self.labels.shape),
                "attractors": [dict(a.to_dict(), count=m.count, fraction=m.fraction,
                                    area=m.area, percent=m.percent)
                               for a, m in zip(self.attractors, self.measures())],
                "metadata": dict(self.metadata)}

    def to_dataset(self):
        """The basin as an :class:`xarray.Dataset` with dimensions ``(y1, x1)``.

        ``attractor`` holds the attractor labels (CF ``flag_values``/``flag_meanings`` name
        them), ``criterion_label`` the paper's labels and ``iterations`` the iterations run;
        the attractors, windows, edges, fixed point and parameters are attributes. E.g.
        ``(ab.to_dataset().attractor == 0).plot()`` draws the symmetric orbit's basin.
        """
        # deferred import: loaded only when this runs, for start-up time
        import xarray as xr

        dims = ("y1", "x1")
        b = self.basin
        labels = [a.label for a in self.attractors]
        names = [a.name.replace(" ", "_") for a in self.attractors]
        data = {
            "attractor": (dims, self.labels, {"long_name": "attractor reached",
                                              "flag_values": labels,
                                              "flag_meanings": " ".join(names)}),
            "criterion_label": (dims, b.labels, {
                "long_name": "the paper's label", "flag_values": list(range(len(LABELS))),
                "flag_meanings": " ".join(LABELS)}),
            "iterations": (dims, b.iterations,
                           {"long_name": "iterations of the impact map actually run"})}
        coords = {n: (n, np.asarray(getattr(self, n)), axis_attrs(n)) for n in dims}
        attrs = {"kind": "attractor_basin", **encode_attrs({
            "attractors": [a.to_dict() for a in self.attractors],
            "windows": [list(w) for w in self.windows], "edges": list(self.edges),
            "fixed_point": [float(v) for v in b.fixed_point],
            "converged_fraction": b.converged_fraction, "basin_metadata": b.metadata,
            "metadata": dict(self.metadata)})}
        return xr.Dataset(data, coords=coords, attrs=attrs)

    @classmethod
    def from_dataset(cls, ds) -> AttractorBasin:
        """Inverse of :meth:`to_dataset`."""
        a = decode_attrs(ds.attrs)
        if a.get("kind") != "attractor_basin":
            raise ValueError("the dataset does not hold an attractor basin (attribute kind)")
        ds = ds.transpose("y1", "x1")
        x1, y1 = ds["x1"].values, ds["y1"].values
        b = BasinResult(x1, y1, ds["criterion_label"].values.astype(np.int64),
                        ds["iterations"].values.astype(np.int64),
                        np.asarray(a["fixed_point"], float), float(a["converged_fraction"]),
                        dict(a.get("basin_metadata") or {}))
        return cls(x1, y1, ds["attractor"].values.astype(np.int64),
                   tuple(Attractor.from_dict(d) for d in a["attractors"]), b,
                   tuple(tuple(w) for w in a["windows"]), tuple(a["edges"]),
                   dict(a.get("metadata") or {}))

    def save(self, path):
        """Write to ``.nc`` (netCDF) or ``.zarr`` (:meth:`to_dataset`), or ``.npz``, by suffix
        (see :func:`load_attractor_basin`)."""
        b = self.basin
        return save_result(self, path, lambda: (
            {"x1": self.x1, "y1": self.y1, "labels": self.labels, "criterion_labels": b.labels,
             "iterations": b.iterations, "fixed_point": b.fixed_point},
            {"kind": "attractor_basin", "attractors": [a.to_dict() for a in self.attractors],
             "windows": [list(w) for w in self.windows], "edges": list(self.edges),
             "basin_metadata": b.metadata, "converged_fraction": b.converged_fraction,
             **self.metadata}))


def load_attractor_basin(path) -> AttractorBasin:
    """Read an :class:`AttractorBasin` written by :meth:`AttractorBasin.save`.

    Parameters
    ----------
    path : str or path
        A ``.nc``, ``.zarr`` or (earlier versions) ``.npz`` file.

    Returns
    -------
    AttractorBasin

    Raises
    ------
    ValueError
        If the suffix is unknown or the file holds something else.

    Examples
    --------
    >>> import tempfile, os
    >>> import hybridpd as hp
    >>> orb = hp.symmetric_orbit(hp.ImpactPair(0.1, 0.5, 0.75), hp.PDGains(10, 20), 5.0)
    >>> ab = hp.attractor_basin(hp.ImpactMapper.from_orbit(orb, n_iter=100), (-1, 3, 4),
    ...                         (-1, 5, 3), extend=False)
    >>> back = hp.load_attractor_basin(ab.save(os.path.join(tempfile.mkdtemp(), "ab.nc")))
    >>> back.labels.shape, len(back.attractors)
    ((3, 4), 1)
    """

    def from_npz(a, meta):
        if meta.pop("kind", None) != "attractor_basin":
            raise ValueError(f"{path} does not hold an attractor basin")
        atts = tuple(Attractor.from_dict(d) for d in meta.pop("attractors"))
        windows = tuple(tuple(w) for w in meta.pop("windows"))
        edges = tuple(meta.pop("edges"))
        b = BasinResult(a["x1"], a["y1"], a["criterion_labels"], a["iterations"],
                        a["fixed_point"], float(meta.pop("converged_fraction")),
                        meta.pop("basin_metadata"))
        return AttractorBasin(a["x1"], a["y1"], a["labels"], atts, b, windows, edges, meta)

    return load_result(AttractorBasin, path, from_npz)


_EDGE_NAMES = ("x1 min", "x1 max", "y1 min", "y1 max")


def _edges(lab: np.ndarray) -> tuple:
    hit = lab == 0
    return tuple(n for n, h in zip(_EDGE_NAMES, (hit[:, 0].any(), hit[:, -1].any(),
                                                 hit[0, :].any(), hit[-1, :].any())) if h)


def _grow(window, centre, edges) -> tuple:
    """Push each side in ``edges`` out to twice its distance from ``centre`` (at least half
    the window's span)."""
    x0, x1, y0, y1 = window
    cx, cy = centre
    sx, sy = x1 - x0, y1 - y0
    if "x1 min" in edges:
        x0 -= max(cx - x0, 0.5 * sx)
    if "x1 max" in edges:
        x1 += max(x1 - cx, 0.5 * sx)
    if "y1 min" in edges:
        y0 -= max(cy - y0, 0.5 * sy)
    if "y1 max" in edges:
        y1 += max(y1 - cy, 0.5 * sy)
    return (x0, x1, y0, y1)


def attractor_basin(mapper: ImpactMapper, x1, y1, *, max_period: int = 8,
                    extend: bool = True, max_extensions: int = 3, max_points=None,
                    executor="serial", chunk_size=None, progress=False,
                    max_workers=None) -> AttractorBasin:
    """Label the slice ``(x1, y1)`` by the attractor each point reaches, and measure the basins.

    Each grid point first gets the paper's label (:class:`ImpactMapper`); converged points are
    the symmetric orbit's basin (label 0). For the others the iterates ``n_iter .. n_iter +
    max_period + 2`` are examined by a :class:`~hybridpd.pair.attractors.CycleCatalog`:
    a repeating tail is refined by Newton on ``P^k`` into a periodic orbit (label ``>= 1``),
    else the point did not converge. Failed flights keep their outcome (sticking, diverged,
    unresolved).

    With ``extend``, while a point of the symmetric orbit's basin lies on the window's edge,
    the touching sides are pushed out to twice their distance from the fixed point ``(x1*,
    y1*)`` (at least half the span) and the grid is relabelled, at most ``max_extensions``
    times, with the same number of points (so the cells grow) unless ``max_points`` allows
    more. The result says whether the basin still reaches the final window's edge
    (:attr:`AttractorBasin.reaches_edge`).

    Parameters
    ----------
    mapper : ImpactMapper
    x1, y1 : (min, max, num)
        The first window's grid axes.
    max_period : int
        Largest period of ``P`` searched in the tails.
    extend : bool
    max_extensions : int
        ``>= 0``.
    max_points : int, optional
        Bound on the points per axis of an extended window, which then keeps the first
        window's cell size up to that bound (default: every window has the first window's
        number of points on each axis).
    executor, chunk_size, progress, max_workers
        As in :func:`basin_of_attraction`.

    Returns
    -------
    AttractorBasin

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.pair.orbits import symmetric_orbit
    >>> orb = symmetric_orbit(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0)
    >>> ab = attractor_basin(ImpactMapper.from_orbit(orb), (-3, 5, 12), (-2, 10, 12))
    >>> [a.name for a in ab.attractors][:2]
    ['symmetric orbit (period 1)', 'period-2 orbit']
    """
    xs = check_axis("x1", x1)
    ys = check_axis("y1", y1)
    if not (int(max_extensions) == max_extensions and max_extensions >= 0):
        raise ValueError(f"max_extensions must be an integer >= 0, got {max_extensions!r}")
    nx0, ny0 = len(xs), len(ys)
    if max_points is not None and not (int(max_points) == max_points
                                       and max_points >= max(nx0, ny0)):
        raise ValueError(f"max_points must be an integer >= the first window's points per "
                         f"axis ({max(nx0, ny0)}), got {max_points!r}")
    cap = (nx0, ny0) if max_points is None else (int(max_points), int(max_points))
    cell = (float(xs[-1] - xs[0]) / max(nx0 - 1, 1), float(ys[-1] - ys[0]) / max(ny0 - 1, 1))
    cat = CycleCatalog(mapper.map, mapper.fixed_point, criterion=mapper.criterion,
                       max_period=max_period)
    fp = mapper.fixed_point
    centre = (fp[1] + mapper.map.pair.L, fp[2] + fp[3])
    windows = []
    while True:   # bounded: at most max_extensions + 1 windows
        windows.append((float(xs[0]), float(xs[-1]), float(ys[0]), float(ys[-1])))
        out = _label_grid(mapper, xs, ys, cat.tail_length, executor=executor,
                          chunk_size=chunk_size, progress=progress, max_workers=max_workers)
        lab = out["label"]
        edges = _edges(lab)
        if not (extend and edges) or len(windows) > max_extensions:
            break
        w = _grow(windows[-1], centre, edges)
        nx = min(max(nx0, round((w[1] - w[0]) / cell[0]) + 1), cap[0])
        ny = min(max(ny0, round((w[3] - w[2]) / cell[1]) + 1), cap[1])
        xs = np.linspace(w[0], w[1], nx)
        ys = np.linspace(w[2], w[3], ny)
    att = _attractor_labels(lab, out["tail"], cat)
    present = set(np.unique(att).tolist())
    entries = [a for a in cat.attractors if a.label == 0 or a.label in present]
    entries += [outcome(k, mapper.n_iter) for k in sorted(OUTCOMES, reverse=True) if k in present]
    basin = _basin_result(mapper, xs, ys, lab, out["iterations"])
    meta = dict(basin.metadata, max_period=int(max_period), extend=bool(extend),
                max_extensions=int(max_extensions),
                max_points=None if max_points is None else int(max_points))
    return AttractorBasin(xs, ys, att, tuple(entries), basin, tuple(windows), edges, meta)


def _attractor_labels(lab: np.ndarray, tails: np.ndarray, cat: CycleCatalog) -> np.ndarray:
    """Attractor labels from the paper's labels; unconverged points by their tails."""
    att = np.full(lab.shape, NO_CONVERGENCE, dtype=np.int64)
    for paper, code in ((0, 0), (2, DIVERGED), (3, STICKING), (4, UNRESOLVED),
                        (OFF_SECTION, OFF_SECTION_LABEL)):
        att[lab == paper] = code
    nc = lab == 1
    att[nc] = cat.assign(tails[nc])
    return att
