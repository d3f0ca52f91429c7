"""The one basin of attraction: a mapper (or any map) over a 2-D slice, on any executor.

:func:`basin_of_attraction` labels every point of a slice by the attractor it reaches. Given
a mapper (:class:`~hybridpd.analysis.mappers.Mapper`, e.g. :func:`hybridpd.analysis.mappers.
mapper` of any map), the points are first labelled against its orbit (label 0: its criterion
holds after its iterations; the others its outcomes,
:func:`~hybridpd.analysis.basins.from_criterion`), serially or in chunks on an executor
(:func:`~hybridpd.sweeps.sweep.run_sweep` with :func:`_label_chunk`, the mapper travelling
as its picklable :meth:`~hybridpd.analysis.mappers.Mapper.spec`); the points that did not
converge are examined for other periodic attractors by the mapper's
:class:`~hybridpd.analysis.mappers.Catalogue`. Given a map, every point is iterated and its
tail labelled by the catalogue alone. With ``grow`` (:class:`~hybridpd.analysis.mappers.
Growth`) the window grows while the basin of label 0 touches its edge.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from hybridpd.analysis.basins import (
    DIVERGED,
    NO_CONVERGENCE,
    OFF_SECTION_LABEL,
    OUTCOMES,
    STICKING,
    UNRESOLVED,
    Attractor,
    BasinResult,
    from_criterion,
    grid_slice,
    outcome,
)
from hybridpd.analysis.labels import INADMISSIBLE
from hybridpd.analysis.mappers import Catalogue, Growth, Mapper
from hybridpd.analysis.maps import PoincareMap, check_returns
from hybridpd.sweeps.sweep import run_sweep

__all__ = ["basin_of_attraction"]


def _label_chunk(chunk, spec, tail: int = 0) -> dict:
    """Labels (and tails) of one chunk of section points by a mapper's picklable spec."""
    S = np.stack([chunk[f"s{i}"] for i in range(len(chunk))], axis=1)
    return spec.label_tails(S, int(tail))


def _label_tails(m: Mapper, S, tail, run) -> dict:
    """The mapper's labels, iterations and tails of the admissible points of ``S``; the
    others ``inadmissible``, never iterated."""
    ok = np.asarray(m.admissible(S), bool)
    out = {"label": np.full(len(S), INADMISSIBLE, np.int64),
           "iterations": np.zeros(len(S), np.int64)}
    if tail:
        out["tail"] = np.full((len(S), tail + 1, S.shape[1]), np.nan)
    todo = S[ok]
    if len(todo):
        if run["executor"] == "serial" and run["store"] is None and not run["progress"]:
            got = m.label_tails(todo, tail)
        else:
            got = run_sweep(_label_chunk, {f"s{i}": todo[:, i] for i in range(S.shape[1])},
                            func_kwargs={"spec": m.spec(), "tail": int(tail)},
                            metadata={"kind": "basin"}, label="basin", **run).outputs
        for k, v in out.items():
            v[ok] = got[k]
    return out, int((~ok).sum())


def _mapper_basin(m: Mapper, x, y, axes, max_period, tol, cat, run) -> BasinResult:
    """One window of :func:`basin_of_attraction` with a mapper."""
    sl = m.slice(x, y, axes)
    if cat is None and max_period:
        cat = m.catalogue(max_period, tol)
    tail = cat.tail_length if max_period else 0
    out, bad = _label_tails(m, np.asarray(sl.S, float), tail, run)
    shape = (len(sl.y), len(sl.x))
    crit_lab = np.asarray(out["label"], np.int64).reshape(shape)
    lab = from_criterion(crit_lab)
    if tail:
        nc = crit_lab == 1
        lab[nc] = cat.assign(np.asarray(out["tail"]).reshape(shape + (tail + 1, -1))[nc])
    present = set(np.unique(lab).tolist())
    if cat is not None:
        entries = [a for a in cat.attractors if a.label == 0 or a.label in present]
    elif m.orbit is not None:
        entries = [m.orbit]
    else:   # no search: the mapper's orbit as the mapper names it
        entries = [Attractor(0, m.converged_name, m.period,
                             np.asarray(m.fixed_point, float).reshape(1, -1), kind=m.orbit_kind)]
    entries += [outcome(c, m.n_iter) for c in sorted(OUTCOMES, reverse=True) if c in present]
    meta = {"n_iter": int(m.n_iter), "criterion": float(m.criterion), "max_period": max_period,
            **m.metadata()}
    if bad or "inadmissible" in meta:   # a map with an admissible set counts its refusals
        meta["inadmissible"] = bad
    return BasinResult(sl.x, sl.y, lab, tuple(entries),
                       np.asarray(out["iterations"]).reshape(shape), sl.names[0], sl.names[1],
                       np.asarray(m.fixed_point, float).copy(), tuple(m.map.names), crit_lab,
                       metadata=meta, axis_attrs=sl.units), cat


def _edges(b: BasinResult) -> tuple:
    hit = b.labels == 0
    names = (f"{b.x_name} min", f"{b.x_name} max", f"{b.y_name} min", f"{b.y_name} max")
    return tuple(n for n, h in zip(names, (hit[:, 0].any(), hit[:, -1].any(),
                                           hit[0, :].any(), hit[-1, :].any())) if h)


def grow_window(window, centre, edges, names=("x", "y")) -> tuple:
    """Push each side in ``edges`` (``"<x> min"``, ``"<x> max"``, ``"<y> min"``, ``"<y>
    max"`` with the coordinate ``names``) out to twice its distance from ``centre`` (at least
    half the window's span).

    Examples
    --------
    >>> grow_window((0.0, 1.0, 0.0, 1.0), (0.5, 0.5), ("x min",))
    (-0.5, 1.0, 0.0, 1.0)
    """
    x0, x1, y0, y1 = window
    cx, cy = centre
    sx, sy = x1 - x0, y1 - y0
    xn, yn = names
    if f"{xn} min" in edges:
        x0 -= max(cx - x0, 0.5 * sx)
    if f"{xn} max" in edges:
        x1 += max(x1 - cx, 0.5 * sx)
    if f"{yn} min" in edges:
        y0 -= max(cy - y0, 0.5 * sy)
    if f"{yn} max" in edges:
        y1 += max(y1 - cy, 0.5 * sy)
    return (x0, x1, y0, y1)


def _grown(m: Mapper, x, y, axes, max_period, tol, grow: Growth, cat, run) -> BasinResult:
    """:func:`basin_of_attraction` over growing windows (:class:`Growth`)."""
    first = m.slice(x, y, axes)
    xs, ys, centre = first.x, first.y, first.centre
    nx0, ny0 = len(xs), len(ys)
    cap = grow.max_points
    if cap is not None and not (int(cap) == cap and cap >= max(nx0, ny0)):
        raise ValueError(f"max_points must be an integer >= the first window's points per "
                         f"axis ({max(nx0, ny0)}), got {cap!r}")
    cap = (nx0, ny0) if cap is None else (int(cap), int(cap))
    cell = (float(xs[-1] - xs[0]) / max(nx0 - 1, 1), float(ys[-1] - ys[0]) / max(ny0 - 1, 1))
    if cat is None and max_period:
        cat = m.catalogue(max_period, tol)
    windows = []
    while True:   # bounded: at most max_extensions + 1 windows
        windows.append((float(xs[0]), float(xs[-1]), float(ys[0]), float(ys[-1])))
        b, cat = _mapper_basin(m, (xs[0], xs[-1], len(xs)), (ys[0], ys[-1], len(ys)), axes,
                               max_period, tol, cat, run)
        edges = _edges(b)
        if not edges or len(windows) > grow.max_extensions:
            break
        w = grow_window(windows[-1], centre, edges, b.axes)
        nx = min(max(nx0, round((w[1] - w[0]) / cell[0]) + 1), cap[0])
        ny = min(max(ny0, round((w[3] - w[2]) / cell[1]) + 1), cap[1])
        xs = np.linspace(w[0], w[1], nx)
        ys = np.linspace(w[2], w[3], ny)
    meta = dict(b.metadata, max_extensions=grow.max_extensions, max_points=grow.max_points)
    return replace(b, x=xs, y=ys, windows=tuple(windows), edges=edges, metadata=meta)


def basin_of_attraction(mapper_or_map, x, y, *, axes=None, base=None, period: int = 1,
                        n_iter: int = 500, max_period: int = 8, tol: float | None = None,
                        escape: float = 1e6, grow: Growth | None = None, catalogue=None,
                        executor="serial", chunk_size=None, store=None, progress=False,
                        max_workers=None) -> BasinResult:
    """Label a 2-D slice by the attractor each point reaches (module docstring).

    Parameters
    ----------
    mapper_or_map : Mapper or PoincareMap
        A mapper labels the points against its orbit first (its slice, iterations and
        criterion); a map's points are iterated ``n_iter`` times and labelled by their tails.
    x, y : (min, max, num)
        The grid of the two coordinates ``axes``.
    axes : (str or int, str or int), optional
        The coordinates the grid spans (default the first two, or the mapper's slice, e.g.
        the impact pair's ``(x1, y1)``).
    base : array_like, shape (dim,), optional
        A map's other coordinates (required when it has more than two; a mapper's are its
        fixed point's).
    period, n_iter, escape
        A map's ``k`` (iterate ``P^k``), iterations per point and bound on the coordinates
        (the phase excepted); a mapper has its own.
    max_period : int
        Largest period of an attractor (in applications of ``P^k``); 0: no search beyond
        the mapper's orbit.
    tol : float, optional
        Relative tolerance of the period test (default the catalogue's, ``1e-4``).
    grow : Growth, optional
        Grow the window while the basin of label 0 touches its edge (a mapper only).
    catalogue : Catalogue, optional
        The attractors found so far (shared between calls).
    executor, chunk_size, store, progress, max_workers
        Of :func:`hybridpd.sweeps.sweep.run_sweep`, which labels a mapper's points (serial
        without store or progress: one call of the mapper). The labels do not depend on them.

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
    ([[0, 0, 0, 0, 0], [0, 0, 0, 0, 0], [0, 0, 0, 0, 0]], 'period-1 orbit')
    """
    if isinstance(max_period, bool) or int(max_period) != max_period or max_period < 0:
        raise ValueError(f"max_period must be an integer >= 0, got {max_period!r}")
    max_period = int(max_period)
    if grow is not None and not isinstance(grow, Growth):
        raise ValueError(f"grow must be a Growth, got {type(grow).__name__}")
    run = {"executor": executor, "chunk_size": chunk_size, "store": store,
           "progress": progress, "max_workers": max_workers}
    if isinstance(mapper_or_map, Mapper):
        m = mapper_or_map
        if base is not None:
            raise ValueError("base: a mapper's slice holds its fixed point's coordinates")
        if grow is not None:
            return _grown(m, x, y, axes, max_period, tol, grow, catalogue, run)
        return _mapper_basin(m, x, y, axes, max_period, tol, catalogue, run)[0]
    if not isinstance(mapper_or_map, PoincareMap):
        raise ValueError(f"mapper_or_map must be a Mapper or a PoincareMap, got "
                         f"{type(mapper_or_map).__name__}")
    if grow is not None or executor != "serial" or store is not None:
        raise ValueError("grow, executor and store need a mapper: give "
                         "basin_of_attraction(mapper(P, fixed_point), ...)")
    return _map_basin(mapper_or_map, x, y, axes, base, period, n_iter, max_period, tol,
                      escape, catalogue)


def _map_basin(P, x, y, axes, base, period, n_iter, max_period, tol, escape, catalogue):
    """:func:`basin_of_attraction` of a map without mapper: tails labelled by the catalogue."""
    k = check_returns(period)
    n_iter = int(n_iter)
    if n_iter < 4 * max_period or max_period < 1:
        raise ValueError(f"n_iter must be >= 4 max_period (got {n_iter}, {max_period})")
    sl = grid_slice(P, x, y, axes, base)
    xs, ys, S, names = sl.x, sl.y, sl.S, sl.names
    opts = {} if tol is None else {"detect_tol": tol}
    cat = catalogue or Catalogue(P, period=k, max_period=max_period, **opts)
    tails, status, its = P.iterate_many(S, n_iter, k, cat.tail_length)
    lab = np.full(len(S), NO_CONVERGENCE, np.int64)
    off = 1 if P.period is not None else 0
    for i, st in enumerate(status):
        if st:
            lab[i] = {"off_section": OFF_SECTION_LABEL, "nonfinite": DIVERGED,
                      "sticking": STICKING}.get(st, UNRESOLVED)
        elif np.any(np.abs(tails[i][:, off:]) > escape):
            lab[i] = DIVERGED
    free = lab == NO_CONVERGENCE
    lab[free] = cat.assign(tails[free])
    stops = sorted({status[i] for i in range(len(S)) if lab[i] == UNRESOLVED})
    outcomes = tuple(Attractor(c, OUTCOMES[c][1] + (f" ({', '.join(stops)})"
                                                    if c == UNRESOLVED else ""),
                               kind=OUTCOMES[c][0])
                     for c in sorted(OUTCOMES, reverse=True) if np.any(lab == c))
    shape = (len(ys), len(xs))
    meta = {"n_iter": n_iter, "period": k, "max_period": max_period,
            "tol": float(cat.detect_tol)}
    return BasinResult(xs, ys, lab.reshape(shape), tuple(cat.attractors) + outcomes,
                       its.reshape(shape), names[0], names[1], sl.base, tuple(P.names),
                       metadata=meta)
