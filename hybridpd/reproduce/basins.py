"""Basins of Figs 6-7 on one window shared by every panel and both cases.

Conclusion 4 compares basin sizes, so every basin of a convention is labelled on the same
window: it starts at the settings' window and, while the symmetric orbit's basin of some panel
touches its edge, the touching sides are pushed out (to twice their distance from that
panel's fixed point, at least half the span) and every panel is relabelled, at most
``Settings.basin_extensions`` times (the cap). The grid keeps its number of points, so the
cells grow with the window.

:func:`boundary_distance` is a measure no window saturates: the distance from the fixed point
to the nearest labelled point that is not in its basin, in the scaled coordinates
``(x1 / x10, y1 / (omega x10))``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hybridpd._results import compact_repr

__all__ = ["SharedWindowBasins", "boundary_distance", "orbit_mapper", "shared_window_basins"]


def orbit_mapper(orbit, **options):
    """The basin mapper of a :class:`~hybridpd.pair.orbits.SymmetricOrbitResult`'s fixed
    point: :func:`hybridpd.analysis.mappers.mapper` of its impact map (the paper's criterion,
    slice and early exits, :class:`hybridpd.pair.basins.PairLabeller`).

    ``options`` go to the mapper (``n_iter``, ``criterion``, ``early_exit``, ``escape``);
    the orbit's ``n``, ``x10`` and ``gamma = L / x10`` reach the basin's metadata.

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.pair.orbits import symmetric_orbit
    >>> m = orbit_mapper(symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0))
    >>> m.label_name(m(m.fixed_point + [0, 0.01, 0, 0])), m.metadata()["gamma"]
    ('converged', 0.75)
    """
    if not orbit.exists:
        raise ValueError(f"orbit must be an existing symmetric orbit, got {orbit.reason!r}")
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.analysis.mappers import mapper
    from hybridpd.pair.impactmap import ImpactMap

    conventions = {"n": int(orbit.n), "x10": float(orbit.x10),
                   "gamma": float(orbit.pair.L / orbit.x10)}
    return mapper(ImpactMap(orbit.pair, orbit.gains, orbit.reference(), orbit.case),
                  orbit.fixed_point, metadata=conventions, **options)


@dataclass
class SharedWindowBasins:
    """Basins of several orbits on one window.

    Attributes
    ----------
    basins : dict
        ``{key: BasinResult or None}`` (None: the orbit does not exist or is unstable).
    window : (x1_min, x1_max, y1_min, y1_max)
        The final window (physical units).
    windows : list of tuple
        Every window tried, the last one is :attr:`window`.
    touches_edge : dict
        ``{key: bool}``: the symmetric orbit's basin touches the final window's edge.
    capped : bool
        Some basin still touches the edge after the last allowed growth.
    """

    basins: dict
    window: tuple
    windows: list
    touches_edge: dict
    capped: bool
    __repr__ = compact_repr


def _label_all(mappers, window, grid, **kw):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.analysis.mappers import Growth
    from hybridpd.sweeps.basins import basin_of_attraction

    x0, x1, y0, y1 = window
    nx, ny = grid
    # Growth(0): one window, its edges reported (the shared window grows here, not per orbit)
    return {k: None if m is None else basin_of_attraction(m, (x0, x1, nx), (y0, y1, ny),
                                                          grow=Growth(0), **kw)
            for k, m in mappers.items()}


def shared_window_basins(orbits: dict, window, grid, *, n_iter=1500, max_growths=1,
                         executor="serial", max_workers=None, progress=False,
                         log=None) -> SharedWindowBasins:
    """Label every orbit's basin on one window, grown until no symmetric basin touches it.

    Parameters
    ----------
    orbits : dict
        ``{key: SymmetricOrbitResult}``.
    window : (x1_min, x1_max, y1_min, y1_max)
        First window (physical units).
    grid : (nx, ny)
        Points per axis.
    n_iter : int
        Iterations of ``P`` of the basin criterion.
    max_growths : int
        The cap: times the window may grow.
    executor, max_workers, progress
        As in :func:`hybridpd.sweeps.basins.basin_of_attraction`.
    log : callable, optional
        Receives a line per growth.

    Returns
    -------
    SharedWindowBasins
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.sweeps.basins import grow_window

    if not (int(max_growths) == max_growths and max_growths >= 0):
        raise ValueError(f"max_growths must be an integer >= 0, got {max_growths!r}")
    mappers = {k: orbit_mapper(o, n_iter=n_iter) if o.exists and o.stable else None
               for k, o in orbits.items()}
    w = tuple(float(v) for v in window)
    windows = []
    kw = dict(executor=executor, max_workers=max_workers, progress=progress)
    while True:   # bounded: at most max_growths + 1 windows
        windows.append(w)
        basins = _label_all(mappers, w, grid, **kw)
        touching = {k: b for k, b in basins.items() if b is not None and b.reaches_edge}
        if not touching or len(windows) > max_growths:
            break
        grown = [grow_window(w, _centre(b), b.edges, b.axes) for b in touching.values()]
        w = (min(g[0] for g in grown), max(g[1] for g in grown),
             min(g[2] for g in grown), max(g[3] for g in grown))
        if log is not None:
            log(f"basin window grown to x1 in [{w[0]:.3g}, {w[1]:.3g}], "
                f"y1 in [{w[2]:.3g}, {w[3]:.3g}]")
    touches = {k: bool(b is not None and b.reaches_edge) for k, b in basins.items()}
    return SharedWindowBasins(basins, w, windows, touches, any(touches.values()))


def _centre(b):
    fp = b.fixed_point
    return float(fp[1] + b.metadata["L"]), float(fp[2] + fp[3])


def relabel(orbits: dict, window, grid, *, n_iter=1500, **kw) -> dict:
    """Every orbit's basin on ``window`` with ``grid`` points (no growth): the resolution
    check of a :class:`SharedWindowBasins`."""
    mappers = {k: orbit_mapper(o, n_iter=n_iter) if o.exists and o.stable else None
               for k, o in orbits.items()}
    return _label_all(mappers, window, grid, **kw)


def boundary_distance(basin, *, x10, omega) -> dict:
    """Distance from the fixed point to the nearest point not in the symmetric orbit's basin.

    Measured on the basin's grid, in the scaled coordinates ``(x1 / x10, y1 / (omega x10))``
    of the section slice. Points off the section (``y1 <= y2*``) are not in the domain of
    ``P`` and are not counted. When no labelled point outside the basin lies in the window,
    the distance to the window's nearest edge is returned as a lower bound.

    Parameters
    ----------
    basin : BasinResult
    x10 : float
        Amplitude of the primary mass (length unit).
    omega : float
        Forcing frequency (rad per time unit).

    Returns
    -------
    dict
        ``distance`` (scaled), ``lower_bound`` (bool), ``cell`` (the grid's cell diagonal in
        the same units: the resolution of the distance), ``nearest`` (``[x1, y1]`` physical,
        or None).

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.pair.orbits import symmetric_orbit
    >>> from hybridpd import basin_of_attraction
    >>> orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    >>> b = basin_of_attraction(orbit_mapper(orb, n_iter=200), (-3, 5, 9), (-2, 10, 9))
    >>> d = boundary_distance(b, x10=1.0, omega=5.0)
    >>> d["distance"] > 0
    True
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.analysis.basins import OFF_SECTION_LABEL

    from_x = lambda v: np.asarray(v, float) / x10
    from_y = lambda v: np.asarray(v, float) / (omega * x10)
    fx, fy = _centre(basin)
    X, Y = np.meshgrid(basin.x1, basin.y1)
    other = (basin.labels != 0) & (basin.labels != OFF_SECTION_LABEL)
    dx = (basin.x1[-1] - basin.x1[0]) / max(len(basin.x1) - 1, 1)
    dy = (basin.y1[-1] - basin.y1[0]) / max(len(basin.y1) - 1, 1)
    cell = float(math.hypot(from_x(dx), from_y(dy)))
    if other.any():
        d = np.hypot(from_x(X[other] - fx), from_y(Y[other] - fy))
        k = int(np.argmin(d))
        return {"distance": float(d[k]), "lower_bound": False, "cell": cell,
                "nearest": [float(X[other][k]), float(Y[other][k])]}
    x0, x1, y0, y1 = basin.window
    edge = min(from_x(fx - x0), from_x(x1 - fx), from_y(fy - y0), from_y(y1 - fy))
    return {"distance": float(edge), "lower_bound": True, "cell": cell, "nearest": None}
