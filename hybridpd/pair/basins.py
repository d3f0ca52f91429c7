"""The impact pair's basin mapper (paper Figs 6-7): the paper's criterion and its slice.

After Attractors.jl: a **mapper** takes one initial condition on the section to a label, and
basins are the one thin layer, :func:`hybridpd.analysis.basins.basin_of_attraction`, that
applies it over a 2-D grid. :class:`ImpactMapper` is the pair's mapper with the hooks that
layer uses: the paper's slice ``(x1, y1)`` (``slice``), its compiled labelling with early exits
over any executor (``label_tails``), the attractor catalogue in the paper's metric
(``catalogue``) and the parameters for the result's metadata (``basin_metadata``)::

    basin_of_attraction(mapper.map, x1, y1, criterion=mapper, max_period=0)

Labels (:data:`LABELS`): ``converged`` (the paper's criterion holds after ``n_iter``
iterations of ``P``), ``not_converged``, ``diverged`` (left the bounded region, non-finite,
or no further impact), ``zeno_sticking`` (impacts accumulated and the masses stay stuck
on a wall for 50 periods), ``unresolved`` (an
iteration bound inside one flight was hit), ``off_section`` (the grid point is not a
pre-impact state: ``z4 = y1 - y2 <= 0``).

The paper's criterion: converged if ``(x1*-x1)^2 + (y1*-y1)^2 + (y2*-y2)^2 + (phi*-phi)^2 <
0.001`` after 1500 iterations of ``P`` (3000 impacts); phase differences are taken modulo
``T`` (nearest representative), which the paper leaves implicit.

**Early exit.** For a stable fixed point, ``Q`` solving ``DP^T Q DP - Q = -I`` defines a norm
in which ``DP`` contracts. The mapper searches the largest radius ``r`` (up to the one whose
``Q``-ball lies inside the criterion ball) for which ``P`` maps the ``Q``-ball into a strictly
smaller one, checked on sampled points of nested spheres with a safety factor. A trajectory
entering that ball stays in it, hence satisfies the criterion at iteration ``n_iter``: it is
labelled ``converged`` at once. (``Q`` solves the Lyapunov equation of ``DP / rho_t`` with
``rho_t = (1 + rho) / 2``, so ``DP`` contracts by about ``rho_t`` in the ``Q``-norm; the sampled
images must fall inside ``(1 + rho_t) / 2`` of the radius, and the ball used is 0.9 of the
largest radius that passed.) This certification is numerical (sampled), not
interval-rigorous. A second early exit reads the label off a cycle: once an iterate repeats one
of the previous 32 to within ``1e-12`` (relative), the trajectory sits on a periodic cycle of
``P`` and iterate ``n_iter`` is known; it is used only when that iterate's criterion value is
not within ``1e-6`` (relative) of the threshold. The tests compare labels with and without the
early exits on grids, and ``early_exit=False`` runs every trajectory to the end.

**Attractors**: :func:`attractor_basin` labels each point with the attractor it reaches:
``0`` the symmetric orbit (the paper's criterion above), ``1, 2, ...`` other periodic orbits of
``P`` found in the iterates ``n_iter .. n_iter + max_period + 2`` of the unconverged points and
refined by Newton on ``P^k`` (:class:`hybridpd.pair.attractors.CycleCatalog`), negative
codes for sticking, divergence, no convergence within the iterations, unresolved flights and
points off the section. The result lists the attractors (section points, period, multipliers,
stability) and measures each basin (grid count, share of all points of the slice, area). While the
symmetric orbit's basin touches the window's edge the window is extended (a bounded number of
times); the result says whether it still does. :func:`format_percent` never rounds a share to
``100 %`` or ``0 %`` when some points differ.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from hybridpd.analysis import basins as _basins
from hybridpd.analysis.certify import BasinMapper, certify_ball
from hybridpd.analysis.labels import OFF_SECTION
from hybridpd.model import check_array, check_axis
from hybridpd.pair.batch import impact_map, map_labels
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.sweeps.labelled import axis_attrs

__all__ = ["ImpactMapper", "attractor_basin", "section_grid"]


class ImpactMapper(BasinMapper):
    """Map a section point to a label by iterating the impact map (Attractors.jl's mapper).

    Parameters
    ----------
    impact_map : ImpactMap
    fixed_point : array_like, shape (4,)
        ``s* = (phi*, z1*, z2*, z4*)``, a fixed point of ``P``.
    n_iter : int
        Iterations of ``P`` (the paper: 1500, i.e. 3000 impacts).
    criterion : float
        Threshold on the squared distance in ``(x1, y1, y2, phi)`` (the paper: 0.001).
    early_exit : bool
        Use the certified contraction ball (see the module docstring).
    escape : float
        Bound on ``|z1|, |z2|, |z4|`` beyond which a trajectory is ``diverged``.

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.pair.orbits import symmetric_orbit
    >>> orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    >>> m = ImpactMapper(ImpactMap(orb.pair, orb.gains, orb.reference()), orb.fixed_point)
    >>> m.label_name(m(orb.fixed_point + [0, 0.01, 0, 0]))
    'converged'
    """

    def __init__(self, impact_map: ImpactMap, fixed_point, *, n_iter: int = 1500,
                 criterion: float = 1e-3, early_exit: bool = True, escape: float = 1e3):
        if not isinstance(impact_map, ImpactMap):
            raise ValueError(f"impact_map must be an ImpactMap, got {type(impact_map).__name__}")
        self.fixed_point = check_array("fixed_point", fixed_point, shape=(4,))
        self._limits(n_iter, criterion, escape)
        self.map = impact_map
        self.cert_Q = np.eye(4)
        self.cert_r2 = 0.0
        self.cycle_tol = 1e-12 if early_exit else 0.0
        # conventions the map does not hold (order n, x10, gamma), for metadata and titles
        self.conventions: dict = {}
        if early_exit:
            self.cert_Q, self.cert_r2 = self._certify()

    @classmethod
    def from_orbit(cls, orbit, **kw) -> ImpactMapper:
        """Mapper for the fixed point of a :class:`~hybridpd.pair.orbits.SymmetricOrbitResult`.

        Keyword arguments go to the constructor; the orbit's ``n``, ``x10`` and ``gamma = L /
        x10`` are kept in :attr:`conventions` (they reach the basin's metadata).
        """
        if not getattr(orbit, "exists", False):
            raise ValueError(f"orbit must be an existing symmetric orbit, got "
                             f"{getattr(orbit, 'reason', orbit)!r}")
        m = cls(ImpactMap(orbit.pair, orbit.gains, orbit.reference(), orbit.case),
                orbit.fixed_point, **kw)
        m.conventions = {"n": int(orbit.n), "x10": float(orbit.x10),
                         "gamma": float(orbit.pair.L / orbit.x10)}
        return m

    def _criterion_matrix(self) -> np.ndarray:
        # (dx1, dy1, dy2, dphi) = C (dphi, dz1, dz2, dz4)
        return np.array([[0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 1, 0], [1, 0, 0, 0]], float)

    def _certify(self):
        """Largest sampled-invariant Q-ball inside the criterion ball (r^2 = 0: none)."""
        P = self.map
        try:
            DP = np.asarray(P.blocks(self.fixed_point).DP, float).reshape(4, 4)
        except (ValueError, RuntimeError):
            return np.eye(4), 0.0

        def images(pts):
            if np.any(pts[:, 3] <= 0):
                return pts, np.zeros(len(pts), bool)
            res = P.apply_batch(pts)
            return res.s, res.ok

        return certify_ball(DP, self.fixed_point, self.criterion, images, P.wrap,
                            C=self._criterion_matrix(), n_dirs=400)

    def labels(self, S) -> tuple[np.ndarray, np.ndarray]:
        """Labels and iterations used for section points ``S`` of shape ``(N, 4)``.

        Points with ``z4 <= 0`` get ``off_section``.
        """
        S = np.asarray(S, float).reshape(-1, 4)
        lab = np.full(S.shape[0], OFF_SECTION, dtype=np.int64)
        its = np.zeros(S.shape[0], dtype=np.int64)
        valid = np.isfinite(S).all(axis=1) & (S[:, 3] > 0)
        if np.any(valid):
            m = self.map
            lv, iv, _ = map_labels(m.params, m._c, np.ascontiguousarray(S[valid]),
                                   self.fixed_point, self.n_iter, self.criterion, self.cert_Q,
                                   self.cert_r2, self.escape, m.tol, m.max_impacts, True,
                                   self.cycle_tol)
            lab[valid] = lv
            its[valid] = iv
        return lab, its


    # ---- hooks of hybridpd.analysis.basins.basin_of_attraction ------------------------
    def slice(self, x1, y1, axes=None) -> tuple:
        """The paper's slice ``(x1, y1)`` (``phi = phi*``, ``y2 = y2*``): ``(xs, ys, S, names,
        units)`` with the section points ``S`` of the grid (:func:`section_grid`)."""
        if axes not in (None, ("x1", "y1"), ["x1", "y1"]):
            raise ValueError(f"axes: the pair's basin slice is ('x1', 'y1'), got {axes!r}")
        xs, ys = check_axis("x1", x1), check_axis("y1", y1)
        S = section_grid(self.fixed_point, self.map.pair.L, xs, ys).reshape(-1, 4)
        return xs, ys, S, ("x1", "y1"), {n: axis_attrs(n) for n in ("x1", "y1")}

    def label_tails(self, S, tail: int = 0, *, executor="serial", chunk_size=None,
                    store=None, progress=False, max_workers=None) -> dict:
        """Labels, iterations and (``tail > 0``) the iterates ``n_iter .. n_iter + tail`` of
        the points that did not converge, in one compiled sweep over ``S`` (shape ``(N, 4)``)
        by :func:`hybridpd.sweeps.sweep.run_sweep` (``executor``, ``store``: a ``.zarr``
        directory written as it goes and resumed; the labels do not depend on them)."""
        S = np.asarray(S, float).reshape(-1, 4)
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.sweeps.sweep import run_sweep

        res = run_sweep(_label_chunk, {"phi": S[:, 0], "z1": S[:, 1], "z2": S[:, 2],
                                       "z4": S[:, 3]},
                        chunk_size=chunk_size, executor=executor, max_workers=max_workers,
                        store=store, progress=progress,
                        func_kwargs={"mapper": _MapperSpec.of(self), "tail": int(tail)},
                        metadata={"kind": "basin"},
                        label=f"basin {self.map.case.value} e={self.map.pair.e:g}")
        return res.outputs

    #: Label 0's name in a basin without attractor search.
    orbit_name = "converged to the symmetric orbit"
    orbit_kind = "symmetric"

    def catalogue(self, max_period: int):
        """The attractor catalogue in the paper's metric, label 0 the symmetric orbit
        (:class:`~hybridpd.pair.attractors.CycleCatalog`)."""
        # deferred import: the catalogue's Newton solver, loaded only when attractors are
        # searched
        from hybridpd.pair.attractors import CycleCatalog

        return CycleCatalog(self.map, self.fixed_point, criterion=self.criterion,
                            max_period=max(int(max_period), 1))

    def basin_metadata(self) -> dict:
        """Parameters, conventions and the certified radius, for a basin's metadata."""
        m = self.map
        meta = {"case": m.case.value, "kp": m.gains.kp, "kv": m.gains.kv, "mu": m.pair.mu,
                "e": m.pair.e, "L": m.pair.L, "m2": m.pair.m2, "omega": m.reference.omega,
                "xm": m.reference.xm, "certified_radius": self.certified_radius}
        meta.update(self.conventions)
        return meta


def section_grid(fixed_point, L, x1, y1) -> np.ndarray:
    """Section points of the paper's basin slice: ``(x1, y1)`` with ``y2 = y2*``, ``phi = phi*``.

    On the section ``x1 = z1 + L``, ``y1 = z2 + z4``, ``y2 = z2``, so a grid point maps to
    ``(phi*, x1 - L, z2*, y1 - z2*)``. Returns shape ``(len(y1), len(x1), 4)``.
    """
    fp = np.asarray(fixed_point, float)
    X1, Y1 = np.meshgrid(np.asarray(x1, float), np.asarray(y1, float))
    return np.stack([np.full_like(X1, fp[0]), X1 - L, np.full_like(X1, fp[2]), Y1 - fp[2]],
                    axis=-1)


@dataclass(frozen=True)
class _MapperSpec:
    """Picklable description of a mapper (rebuilt in worker processes)."""

    params: tuple
    case: str
    fixed_point: tuple
    n_iter: int
    criterion: float
    escape: float
    cert_Q: tuple
    cert_r2: float
    cycle_tol: float
    tol: float
    max_impacts: int

    @classmethod
    def of(cls, m: ImpactMapper) -> _MapperSpec:
        return cls(tuple(m.map.params.tolist()), m.map.case.value, tuple(m.fixed_point.tolist()),
                   m.n_iter, m.criterion, m.escape, tuple(m.cert_Q.ravel().tolist()),
                   m.cert_r2, m.cycle_tol, m.map.tol, m.map.max_impacts)


def _label_chunk(chunk, mapper: _MapperSpec, tail: int = 0):
    S = np.stack([chunk["phi"], chunk["z1"], chunk["z2"], chunk["z4"]], axis=1)
    lab = np.full(S.shape[0], OFF_SECTION, dtype=np.int64)
    its = np.zeros(S.shape[0], dtype=np.int64)
    final = np.full(S.shape, np.nan)
    valid = np.isfinite(S).all(axis=1) & (S[:, 3] > 0)
    params = np.array(mapper.params)
    c = 0 if mapper.case == "collocated" else 1
    if np.any(valid):
        lv, iv, fv = map_labels(params, c, np.ascontiguousarray(S[valid]),
                                np.array(mapper.fixed_point), mapper.n_iter, mapper.criterion,
                                np.array(mapper.cert_Q).reshape(4, 4), mapper.cert_r2,
                                mapper.escape, mapper.tol, mapper.max_impacts, True,
                                mapper.cycle_tol)
        lab[valid] = lv
        its[valid] = iv
        final[valid] = fv
    out = {"label": lab, "iterations": its}
    if tail > 0:
        # only the trajectories that did not meet the criterion need their tail
        out["tail"] = _tails(params, c, final, lab == 1, tail, mapper)
    return out


def _tails(params, c, final, which, n, mapper: _MapperSpec) -> np.ndarray:
    """Iterates ``0..n`` of ``P`` from ``final[which]`` (NaN elsewhere and after a failure)."""
    tails = np.full((final.shape[0], n + 1, 4), np.nan)
    idx = np.flatnonzero(which)
    tails[idx, 0] = final[idx]
    cur = final[idx]
    for j in range(1, n + 1):
        if idx.size == 0:
            break
        out, status, _ = impact_map(params, c, np.ascontiguousarray(cur), mapper.tol,
                                    mapper.max_impacts)
        ok = (status == 0) & (out[:, 3] > 0)
        idx, cur = idx[ok], out[ok]
        tails[idx, j] = cur
    return tails


# ----------------------------------------------------------------------------------------
# Attractor-labelled basins with a measure
# ----------------------------------------------------------------------------------------

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
