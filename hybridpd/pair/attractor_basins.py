"""Attractor-labelled basins of the impact pair: which attractor each point of the paper's
slice reaches, measured.

:func:`attractor_basin` labels each point with the attractor it reaches: ``0`` the symmetric
orbit (the paper's criterion, :class:`~hybridpd.pair.basins.ImpactMapper`), ``1, 2, ...``
other periodic orbits of ``P`` found in the iterates ``n_iter .. n_iter + max_period + 2`` of
the unconverged points and refined by Newton on ``P^k``
(:class:`hybridpd.pair.attractors.CycleCatalog`), negative codes for sticking,
divergence, no convergence within the iterations, unresolved flights and points off the
section. The result is the one basin result, :class:`~hybridpd.analysis.basins.BasinResult`
(coordinates ``x1``, ``y1``; the paper's labels as ``criterion_labels``), which lists the
attractors (section points, period, multipliers, stability) and measures each basin (grid
count, share of the on-section grid, area). While the symmetric orbit's basin touches the
window's edge the window is extended (a bounded number of times); the result says whether it
still does.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from hybridpd._deprecated import moved_names
from hybridpd.analysis import basins as _basins
from hybridpd.model import check_axis
from hybridpd.pair.basins import ImpactMapper

__all__ = ["attractor_basin"]


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
                    max_workers=None) -> _basins.BasinResult:
    """Label the slice ``(x1, y1)`` by the attractor each point reaches, and measure the basins.

    One :func:`hybridpd.analysis.basins.basin_of_attraction` with the mapper as its criterion
    per window: each grid point first gets the paper's label (:class:`ImpactMapper`);
    converged points are the symmetric orbit's basin (label 0). For the others the iterates ``n_iter .. n_iter +
    max_period + 2`` are examined by a :class:`~hybridpd.pair.attractors.CycleCatalog`:
    a repeating tail is refined by Newton on ``P^k`` into a periodic orbit (label ``>= 1``),
    else the point did not converge. Failed flights keep their outcome (sticking, diverged,
    unresolved).

    With ``extend``, while a point of the symmetric orbit's basin lies on the window's edge,
    the touching sides are pushed out to twice their distance from the fixed point ``(x1*,
    y1*)`` (at least half the span) and the grid is relabelled, at most ``max_extensions``
    times, with the same number of points (so the cells grow) unless ``max_points`` allows
    more. The result says whether the basin still reaches the final window's edge
    (:attr:`~hybridpd.analysis.basins.BasinResult.reaches_edge`).

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
        As in :meth:`~hybridpd.pair.basins.ImpactMapper.label_tails`.

    Returns
    -------
    BasinResult
        Attractor labels, the paper's labels as ``criterion_labels``, the windows tried and
        the edges the symmetric orbit's basin touches.

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
    cat = mapper.catalogue(max_period)
    fp = mapper.fixed_point
    centre = (fp[1] + mapper.map.pair.L, fp[2] + fp[3])
    windows = []
    while True:   # bounded: at most max_extensions + 1 windows
        windows.append((float(xs[0]), float(xs[-1]), float(ys[0]), float(ys[-1])))
        b = _basins.basin_of_attraction(
            mapper.map, (xs[0], xs[-1], len(xs)), (ys[0], ys[-1], len(ys)), criterion=mapper,
            catalogue=cat, max_period=max_period, executor=executor, chunk_size=chunk_size,
            progress=progress, max_workers=max_workers)
        edges = _edges(b.labels)
        if not (extend and edges) or len(windows) > max_extensions:
            break
        w = _grow(windows[-1], centre, edges)
        nx = min(max(nx0, round((w[1] - w[0]) / cell[0]) + 1), cap[0])
        ny = min(max(ny0, round((w[3] - w[2]) / cell[1]) + 1), cap[1])
        xs = np.linspace(w[0], w[1], nx)
        ys = np.linspace(w[2], w[3], ny)
    meta = dict(b.metadata, extend=bool(extend), max_extensions=int(max_extensions),
                max_points=None if max_points is None else int(max_points))
    return replace(b, x=xs, y=ys, windows=tuple(windows), edges=edges, metadata=meta)


__getattr__ = moved_names(__name__, {
    "AttractorBasin": "hybridpd.analysis.basins:BasinResult",
    "BasinMeasure": "hybridpd.analysis.basins",
    "load_attractor_basin": "hybridpd.analysis.basins:load_basin",
    "format_percent": "hybridpd._format"})
