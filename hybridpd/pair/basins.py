"""What the impact pair adds to the general basin mapper (paper Figs 6-7): its slice, its
criterion and its compiled labelling.

The pair's :class:`~hybridpd.pair.impactmap.ImpactMap` returns a :class:`PairLabeller` from
its :meth:`~hybridpd.analysis.maps.PoincareMap.labeller` hook, so the one mapper
(:func:`hybridpd.analysis.mappers.mapper`; for a symmetric orbit with its conventions
:func:`hybridpd.reproduce.basins.orbit_mapper`) and the one basin
(:func:`hybridpd.sweeps.basins.basin_of_attraction`) take it like any map::

    basin_of_attraction(mapper(P, fixed_point), x1, y1, grow=Growth())

Labels (:data:`~hybridpd.analysis.labels.LABELS`): ``converged`` (the paper's criterion holds
after ``n_iter`` iterations of ``P``), ``not_converged``, ``diverged`` (left the bounded
region, non-finite, or no further impact), ``zeno_sticking`` (impacts accumulated and the
masses stay stuck on a wall for 50 periods), ``unresolved`` (an iteration bound inside one
flight was hit), ``off_section`` (the grid point is not a pre-impact state: ``z4 = y1 - y2 <=
0``).

The paper's criterion: converged if ``(x1*-x1)^2 + (y1*-y1)^2 + (y2*-y2)^2 + (phi*-phi)^2 <
0.001`` after 1500 iterations of ``P`` (3000 impacts); phase differences are taken modulo
``T`` (nearest representative), which the paper leaves implicit (:func:`paper_distance2`,
:class:`PaperMetric`, the metric of its attractor catalogue too).

**Early exits.** The certified contraction ball (:func:`hybridpd.analysis.certify.certify_ball`
in the criterion's coordinates, 400 sampled directions): a trajectory entering it is labelled
``converged`` at once. Once an iterate repeats one of the previous 32 to within ``1e-12``
(relative), the trajectory sits on a periodic cycle of ``P`` and iterate ``n_iter`` is known;
it is used only when that iterate's criterion value is not within ``1e-6`` (relative) of the
threshold. ``early_exit=False`` runs every trajectory to the end.

**The slice** ``(x1, y1)`` holds ``phi = phi*`` and ``y2 = y2*`` (:func:`section_grid`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hybridpd.analysis.basins import Slice
from hybridpd.analysis.certify import certify_ball
from hybridpd.analysis.labels import OFF_SECTION
from hybridpd.analysis.mappers import Labeller, MapMapper, Metric
from hybridpd.analysis.periodic import LabelSpec
from hybridpd.model import check_axis, wrap_phase
from hybridpd.pair.batch import impact_map, map_labels

__all__ = ["PairLabeller", "PaperMetric", "paper_distance2", "section_grid", "slice_points"]

# (dx1, dy1, dy2, dphi) = C (dphi, dz1, dz2, dz4): the paper's criterion coordinates
_C = np.array([[0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 1, 0], [1, 0, 0, 0]], float)

_UNITS = {"x1": {"units": "length", "long_name": "primary-mass position at the impact x1"},
          "y1": {"units": "length/time", "long_name": "primary-mass velocity at the impact y1"}}


def section_grid(fixed_point, L, x1, y1) -> np.ndarray:
    """Section points of the paper's basin slice: ``(x1, y1)`` with ``y2 = y2*``, ``phi = phi*``.

    On the section ``x1 = z1 + L``, ``y1 = z2 + z4``, ``y2 = z2``, so a grid point maps to
    ``(phi*, x1 - L, z2*, y1 - z2*)``. Returns shape ``(len(y1), len(x1), 4)``.

    Examples
    --------
    >>> section_grid([0.1, 0.2, 1.0, 2.0], 0.75, [1.0], [3.0, 4.0])[:, 0].tolist()
    [[0.1, 0.25, 1.0, 2.0], [0.1, 0.25, 1.0, 3.0]]
    """
    fp = np.asarray(fixed_point, float)
    X1, Y1 = np.meshgrid(np.asarray(x1, float), np.asarray(y1, float))
    return np.stack([np.full_like(X1, fp[0]), X1 - L, np.full_like(X1, fp[2]), Y1 - fp[2]],
                    axis=-1)


def paper_distance2(a, b, T: float) -> np.ndarray:
    """Squared distance of the paper's criterion between section points ``a`` and ``b``.

    ``(x1 - x1')^2 + (y1 - y1')^2 + (y2 - y2')^2 + (phi - phi')^2`` with ``x1 = z1 + L``,
    ``y1 = z2 + z4``, ``y2 = z2`` and the phase difference taken modulo ``T`` (nearest
    representative). ``a`` and ``b`` broadcast over leading axes, last axis 4.

    Examples
    --------
    >>> float(paper_distance2([0.0, 1.0, 0.0, 0.0], [6.0, 0.0, 0.0, 0.0], 6.0))
    1.0
    """
    d = np.asarray(a, float) - np.asarray(b, float)
    d[..., 0] = wrap_phase(d[..., 0], T)
    cd = d @ _C.T
    return np.einsum("...i,...i->...", cd, cd)


class PaperMetric(Metric):
    """The paper's criterion as the metric of the pair's attractor catalogue: squared
    distance :func:`paper_distance2`, differences with the phase wrapped, the scale of a tail
    without the phase."""

    def distance2(self, a, b) -> np.ndarray:
        return paper_distance2(a, b, self.T)


def slice_points(attractor, L: float) -> np.ndarray:
    """An attractor's cycle points in the basin slice's coordinates ``(x1, y1) = (z1 + L,
    z2 + z4)``, shape ``(period, 2)``.

    The slice fixes ``phi`` and ``y2``; the cycle's points have their own, so these are
    projections.

    Examples
    --------
    >>> from hybridpd.analysis.basins import Attractor
    >>> slice_points(Attractor(0, "orbit", 1, np.array([[0.1, 0.2, 1.0, 2.0]])), 0.75)
    array([[0.95, 3.  ]])
    """
    p = np.asarray(attractor.points, float).reshape(-1, 4)
    return np.stack([p[:, 1] + L, p[:, 2] + p[:, 3]], axis=-1)


class PairLabeller(Labeller):
    """The impact pair's labelling (module docstring): the compiled
    :func:`~hybridpd.pair.batch.map_labels` with both early exits, the slice ``(x1, y1)``,
    the paper's metric and the parameters for a basin's metadata."""

    orbit_name = "symmetric orbit (period 1)"
    converged_name = "converged to the symmetric orbit"
    orbit_kind = "symmetric"

    def criterion_matrix(self) -> np.ndarray:
        return _C

    def certify(self, m: MapMapper, fp) -> tuple:
        """Largest sampled-invariant Q-ball inside the criterion ball (r^2 = 0: none)."""
        P = self.map
        try:
            DP = np.asarray(P.blocks(fp).DP, float).reshape(4, 4)
        except (ValueError, RuntimeError):
            return np.eye(4), 0.0

        def images(pts):
            if np.any(pts[:, 3] <= 0):
                return pts, np.zeros(len(pts), bool)
            res = P.apply_batch(pts)
            return res.s, res.ok

        return certify_ball(DP, fp, m.criterion, images, P.wrap, C=_C, n_dirs=400)

    def run(self, S, spec: LabelSpec) -> tuple:
        return _PairSpec.of(self.map, spec).labels(S)

    def spec(self, m: MapMapper) -> _PairSpec:
        return _PairSpec.of(self.map, m.spec_of())

    def label_tails(self, m: MapMapper, S, tail: int) -> dict:
        return self.spec(m).label_tails(S, tail)

    def slice(self, m: MapMapper, x, y, axes) -> Slice:
        """The paper's slice ``(x1, y1)`` (``phi = phi*``, ``y2 = y2*``)."""
        if axes not in (None, ("x1", "y1"), ["x1", "y1"]):
            raise ValueError(f"axes: the pair's basin slice is ('x1', 'y1'), got {axes!r}")
        xs, ys = check_axis("x1", x), check_axis("y1", y)
        fp, L = m.fixed_point, self.map.pair.L
        S = section_grid(fp, L, xs, ys).reshape(-1, 4)
        return Slice(xs, ys, S, ("x1", "y1"), {n: dict(_UNITS[n]) for n in ("x1", "y1")},
                     fp.copy(), (fp[1] + L, fp[2] + fp[3]))

    def metric(self) -> PaperMetric:
        return PaperMetric(self.map)

    def metadata(self, m: MapMapper) -> dict:
        P = self.map
        return {"case": P.case.value, "kp": P.gains.kp, "kv": P.gains.kv, "mu": P.pair.mu,
                "e": P.pair.e, "L": P.pair.L, "m2": P.pair.m2, "omega": P.reference.omega,
                "xm": P.reference.xm, "certified_radius": m.certified_radius}


@dataclass(frozen=True)
class _PairSpec:
    """Picklable description of the pair's labelling (no compiled objects; worker processes
    run it on their chunks)."""

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
    def of(cls, P, spec: LabelSpec) -> _PairSpec:
        return cls(tuple(P.params.tolist()), P.case.value, tuple(spec.FP[0].tolist()),
                   int(spec.n_iter), float(spec.criterion), float(spec.escape),
                   tuple(np.asarray(spec.QS[0]).ravel().tolist()), float(spec.R2[0]),
                   float(spec.cycle_tol), P.tol, P.max_impacts)

    def _run(self, S):
        S = np.asarray(S, float).reshape(-1, 4)
        lab = np.full(S.shape[0], OFF_SECTION, dtype=np.int64)
        its = np.zeros(S.shape[0], dtype=np.int64)
        final = np.full(S.shape, np.nan)
        valid = np.isfinite(S).all(axis=1) & (S[:, 3] > 0)
        if np.any(valid):
            lv, iv, fv = map_labels(np.array(self.params), self._c, np.ascontiguousarray(S[valid]),
                                    self.label_spec(), self.tol, self.max_impacts, True)
            lab[valid], its[valid], final[valid] = lv, iv, fv
        return lab, its, final

    def label_spec(self) -> LabelSpec:
        """The options by name, as the kernel takes them."""
        return LabelSpec(_C, 0.0, np.array(self.fixed_point, float)[None], 1, int(self.n_iter),
                         float(self.criterion), np.array(self.cert_Q, float).reshape(1, 4, 4),
                         np.array([self.cert_r2], float), float(self.escape),
                         float(self.cycle_tol))

    @property
    def _c(self) -> int:
        return 0 if self.case == "collocated" else 1

    def labels(self, S) -> tuple:
        """Labels, iterations and last iterates of section points ``S`` (``z4 <= 0``:
        ``off_section``)."""
        return self._run(S)

    def label_tails(self, S, tail: int = 0) -> dict:
        """Labels, iterations and (``tail > 0``) iterates ``n_iter .. n_iter + tail`` of the
        points that did not converge."""
        lab, its, final = self._run(S)
        out = {"label": lab, "iterations": its}
        if tail > 0:
            # only the trajectories that did not meet the criterion need their tail
            out["tail"] = self._tails(final, lab == 1, int(tail))
        return out

    def _tails(self, final, which, n) -> np.ndarray:
        """Iterates ``0..n`` of ``P`` from ``final[which]`` (NaN elsewhere and after a
        failure)."""
        params = np.array(self.params)
        tails = np.full((final.shape[0], n + 1, 4), np.nan)
        idx = np.flatnonzero(which)
        tails[idx, 0] = final[idx]
        cur = final[idx]
        for j in range(1, n + 1):   # bounded: n iterates
            if idx.size == 0:
                break
            out, status, _ = impact_map(params, self._c, np.ascontiguousarray(cur), self.tol,
                                        self.max_impacts)
            ok = (status == 0) & (out[:, 3] > 0)
            idx, cur = idx[ok], out[ok]
            tails[idx, j] = cur
        return tails
