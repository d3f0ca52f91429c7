"""Cross-checks of traced boundary curves against an independent region mask.

The region mask comes from :func:`hybridpd.pair.orbits.symmetric_orbits` (viability by the
guaranteed contact location of the batch engine, multipliers as eigenvalues of the symbolic
``DP``), not from the test functions the curves were traced with. The *status* of a point
is ``-1`` where the orbit does not exist and otherwise the number of multipliers outside the
unit circle; every boundary kind changes it (grazing/existence: exists or not; fold: one
multiplier crosses; Neimark-Sacker: two).

* :func:`region_status` - the status on a grid of the plane;
* :func:`compare_with_mask` - distances between the curves and the mask's boundaries, both
  ways (how far is the farthest mask boundary from a curve, and the farthest curve point from
  a mask boundary);
* :func:`side_status` - the status just on either side of every curve segment;
* :func:`stable_region_edges` - the parts of the curves that bound the exists-and-stable
  region (what the region figures draw).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.pair.orbits import symmetric_orbits

__all__ = ["MaskComparison", "compare_with_mask", "region_status", "side_status",
           "stable_region_edges"]


def _status(plane, xv, yv):
    p = plane.params(np.asarray(xv, float), np.asarray(yv, float))
    r = symmetric_orbits(p["kp"], p["kv"], mu=p["mu"], e=p["e"], L=p["gamma"] * p["x10"],
                         omega=p["omega"], m2=p["m2"], x10=p["x10"], n=plane.n,
                         case=plane.case)
    nun = np.sum(np.abs(r.multipliers) > 1.0, axis=-1)
    return np.where(r.exists, nun, -1)


def region_status(plane, xs, ys, chunk_rows: int = 50) -> np.ndarray:
    """Status (``-1`` no orbit, else the number of unstable multipliers) on ``ys x xs``.

    Parameters
    ----------
    plane : Plane
        E.g. :attr:`BoundaryResult.plane <hybridpd.pair.boundaries.BoundaryResult>`.
    xs, ys : array_like
        Grid axes in the parameters' units.
    chunk_rows : int
        Rows evaluated at once (bounds the memory of the vectorised evaluation).

    Returns
    -------
    ndarray of int, shape (len(ys), len(xs))
    """
    xs = np.asarray(xs, float)
    ys = np.asarray(ys, float)
    out = np.empty((ys.size, xs.size), dtype=np.int64)
    for i in range(0, ys.size, chunk_rows):
        Y, X = np.meshgrid(ys[i:i + chunk_rows], xs, indexing="ij")
        out[i:i + chunk_rows] = _status(plane, X.ravel(), Y.ravel()).reshape(X.shape)
    return out


def _dense(curves, spacing):
    pts = []
    for c in curves:
        U = c.u
        for a, b in itertools.pairwise(U):
            k = max(1, int(np.ceil(np.linalg.norm(b - a) / spacing)))
            s = np.arange(k)[:, None] / k
            pts.append(a + s * (b - a))
        pts.append(U[-1:])
    return np.concatenate(pts) if pts else np.empty((0, 2))


def _mask_edges(status, xs_u, ys_u):
    """Midpoints (unit coordinates) of grid edges whose two ends differ in status."""
    h = status[:, :-1] != status[:, 1:]
    v = status[:-1, :] != status[1:, :]
    iy, ix = np.nonzero(h)
    m1 = np.column_stack([0.5 * (xs_u[ix] + xs_u[ix + 1]), ys_u[iy]])
    iy, ix = np.nonzero(v)
    m2 = np.column_stack([xs_u[ix], 0.5 * (ys_u[iy] + ys_u[iy + 1])])
    return np.concatenate([m1, m2])


@dataclass(frozen=True)
class MaskComparison:
    """Distances between traced curves and the boundaries of a status mask.

    All distances are in unit coordinates of the box (1 = the box side) and, in
    ``*_cells``, in mask cells (the larger of the two cell sides).

    Attributes
    ----------
    mask_to_curves : float
        Largest distance from a mask boundary (midpoint of an edge between two grid points of
        different status) to the nearest curve.
    curves_to_mask : float
        Largest distance from a curve point to the nearest mask boundary (only points with a
        status change within reach of the mask, i.e. not at the box edge).
    mask_to_curves_cells, curves_to_mask_cells : float
    n_mask_edges : int
        Number of grid edges with a status change.
    cell : float
        Mask cell size in unit coordinates.
    """

    mask_to_curves: float
    curves_to_mask: float
    mask_to_curves_cells: float
    curves_to_mask_cells: float
    n_mask_edges: int
    cell: float
    __repr__ = compact_repr


def compare_with_mask(result, status, xs, ys) -> MaskComparison:
    """Compare the curves of a :class:`~hybridpd.pair.boundaries.BoundaryResult` with a
    status mask on ``ys x xs`` (from :func:`region_status`)."""
    from scipy.spatial import cKDTree

    plane = result.plane
    xs_u = plane.x.to_unit(xs)
    ys_u = plane.y.to_unit(ys)
    cell = float(max(np.max(np.diff(xs_u)), np.max(np.diff(ys_u))))
    mids = _mask_edges(np.asarray(status), xs_u, ys_u)
    dense = _dense(result.curves, 0.25 * cell)
    if len(mids) == 0 or len(dense) == 0:
        inf = np.inf if (len(mids) or len(dense)) else 0.0
        return MaskComparison(inf, inf, inf, inf, len(mids), cell)
    d1 = cKDTree(dense).query(mids)[0]
    pts = np.concatenate([c.u for c in result.curves])
    inside = np.all((pts > cell) & (pts < 1 - cell), axis=1)
    d2 = cKDTree(mids).query(pts[inside])[0] if inside.any() else np.zeros(1)
    return MaskComparison(float(d1.max()), float(d2.max()), float(d1.max() / cell),
                          float(d2.max() / cell), len(mids), cell)


def side_status(result, delta: float = 1e-4, skip: float = 1e-3):
    """Status on both sides of every curve, ``delta`` (unit coordinates) off its points.

    The interior points of each curve (which lie on the boundary to the corrector's
    tolerance, unlike the chords between them) are moved by ``+-delta`` along the normal
    (from the neighbouring points). Points within ``skip`` of a curve end or a
    codimension-2 point are left out (the sides are only meaningful away from where curves
    meet).

    Returns
    -------
    list of (kind, left, right)
        Per curve, the status arrays on the two sides.
    """
    plane = result.plane
    marks = [c.u[[0, -1]] for c in result.curves] + [p.u[None] for p in result.codim2]
    marks = np.concatenate(marks) if marks else np.empty((0, 2))
    out = []
    for c in result.curves:
        U = c.u
        mid = U[1:-1]
        d = U[2:] - U[:-2]
        nrm = np.column_stack([-d[:, 1], d[:, 0]]) / np.linalg.norm(d, axis=1)[:, None]
        far = np.all(np.linalg.norm(mid[:, None, :] - marks[None], axis=2) > skip, axis=1) \
            if len(marks) else np.ones(len(mid), bool)
        mid, nrm = mid[far], nrm[far]
        sides = []
        for sgn in (1.0, -1.0):
            P = np.clip(mid + sgn * delta * nrm, 0.0, 1.0)
            sides.append(_status(plane, plane.x.from_unit(P[:, 0]), plane.y.from_unit(P[:, 1])))
        out.append((c.kind, sides[0], sides[1]))
    return out


def stable_region_edges(result, delta: float = 1e-4) -> list:
    """The parts of the traced curves that bound the exists-and-stable region (grazing and
    existence curves: the parts that bound the existence region).

    A boundary curve of one test function need not bound the region where the orbit exists
    *and* is stable: a Neimark-Sacker curve inside the unstable region, say, only changes the
    number of unstable multipliers from 2 to 0... or from 3 to 1. Each curve point is kept
    where the status (:func:`region_status`) is 0 (exists, stable) on exactly one side,
    ``delta`` (unit coordinates) off the curve along its normal; elsewhere ``x`` and ``y`` are
    NaN, so a plotted line breaks there. Curves with no such point are dropped.

    Returns
    -------
    list of BoundaryCurve
        Copies of ``result.curves`` with the non-bounding points set to NaN.
    """
    import dataclasses

    plane = result.plane
    out = []
    for c in result.curves:
        U = np.asarray(c.u, float)
        if len(U) < 2:
            continue
        d = np.gradient(U, axis=0)
        n = np.linalg.norm(d, axis=1)
        n[n == 0] = 1.0
        nrm = np.column_stack([-d[:, 1], d[:, 0]]) / n[:, None]
        # existence-type curves bound the existence region (the figures mark its side too)
        level = -1 if c.kind in ("grazing", "existence") else 0
        side = []
        for sgn in (1.0, -1.0):
            P = np.clip(U + sgn * delta * nrm, 0.0, 1.0)
            st = _status(plane, plane.x.from_unit(P[:, 0]), plane.y.from_unit(P[:, 1]))
            side.append(st == 0 if level == 0 else st == -1)
        keep = side[0] != side[1]
        if not keep.any():
            continue
        x = np.where(keep, np.asarray(c.x, float), np.nan)
        y = np.where(keep, np.asarray(c.y, float), np.nan)
        out.append(dataclasses.replace(c, x=x, y=y))
    return out
