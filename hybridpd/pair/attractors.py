"""Attractors of the impact map ``P``: cycles read off late iterates and refined by Newton.

A trajectory of ``P`` that has settled on a stable periodic orbit of period ``k`` repeats itself
every ``k`` iterations. :class:`CycleCatalog` takes the last iterates of many trajectories
("tails": iterate ``n``, ``n + 1``, ..., ``n + K`` of each), finds the smallest ``k <=
max_period`` for which a tail repeats to ``detect_tol``, refines that cycle with Newton's method
on ``P^k`` (:func:`hybridpd.analysis.periodic.find_orbit`), removes duplicates (the
same cycle entered at another of its points, i.e. up to a cyclic shift), and gives every
distinct cycle an integer label ``>= 0``. A tail belongs to a cycle when each of its iterates
lies within the paper's criterion ball of a point of the cycle: squared distance in ``(x1, y1,
y2, phi)`` below ``criterion`` (the basin convention of CONVENTIONS.md, phase differences modulo ``T``),
i.e. the same test the paper applies to the symmetric orbit, applied to every iterate of the
tail.

Label ``0`` is reserved for the symmetric orbit (the fixed point the basin is computed for);
other cycles get ``1, 2, ...`` in the order they are found. Outcomes that are not periodic
orbits have negative codes (:data:`OUTCOMES`): no convergence within the iterations,
divergence, sticking, an unresolved flight, and points off the section.

Phases are taken modulo ``T``: a cycle's points are stored with ``phi`` in ``[0, T)``, starting
at the point of smallest phase.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from hybridpd.analysis import basins as _basins
from hybridpd.analysis.periodic import find_orbit
from hybridpd.model import wrap_phase
from hybridpd.pair.impactmap import ImpactMap

__all__ = ["CycleCatalog", "paper_distance2", "slice_points"]

_NC = _basins.NO_CONVERGENCE

# (dx1, dy1, dy2, dphi) = C (dphi, dz1, dz2, dz4): the paper's criterion coordinates
_C = np.array([[0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 1, 0], [1, 0, 0, 0]], float)


def paper_distance2(a, b, T: float) -> np.ndarray:
    """Squared distance of the paper's criterion between section points ``a`` and ``b``.

    ``(x1 - x1')^2 + (y1 - y1')^2 + (y2 - y2')^2 + (phi - phi')^2`` with ``x1 = z1 + L``,
    ``y1 = z2 + z4``, ``y2 = z2`` and the phase difference taken modulo ``T`` (nearest
    representative). ``a`` and ``b`` broadcast over leading axes, last axis 4.
    """
    d = np.asarray(a, float) - np.asarray(b, float)
    d[..., 0] = wrap_phase(d[..., 0], T)
    cd = d @ _C.T
    return np.einsum("...i,...i->...", cd, cd)


def _canonical(orbit: np.ndarray, T: float) -> np.ndarray:
    pts = np.array(orbit, float, copy=True)
    pts[:, 0] %= T
    return np.roll(pts, -int(np.argmin(pts[:, 0])), axis=0)


class CycleCatalog:
    """Periodic attractors of ``P`` found in tails of trajectories, with integer labels.

    Parameters
    ----------
    impact_map : ImpactMap
    fixed_point : array_like, shape (4,)
        The symmetric orbit's fixed point (label 0).
    criterion : float
        Squared distance (paper's metric) within which a tail iterate counts as on a cycle.
    max_period : int
        Largest period searched (``>= 1``).
    detect_tol : float
        A tail repeats with period ``k`` when ``|s_{j+k} - s_j|_inf <= detect_tol *
        max(1, |s|_inf)`` along the tail (phase modulo ``T``); it is only the trigger for
        Newton's method, which decides.
    max_newton : int
        Bound on the Newton solves per call of :meth:`assign` (each new cycle costs one).

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.pair.orbits import symmetric_orbit
    >>> orb = symmetric_orbit(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0)
    >>> P = ImpactMap(orb.pair, orb.gains, orb.reference())
    >>> cat = CycleCatalog(P, orb.fixed_point)
    >>> tail = P.iterate([0.3, -2.1, -2.3, 0.5], 1510)[1500:]
    >>> cat.assign(tail[None]).tolist(), cat.attractors[1].name, cat.attractors[1].period
    ([1], 'period-2 orbit', 2)
    """

    def __init__(self, impact_map: ImpactMap, fixed_point, *, criterion: float = 1e-3,
                 max_period: int = 8, detect_tol: float = 1e-4, max_newton: int = 12):
        if not isinstance(impact_map, ImpactMap):
            raise ValueError(f"impact_map must be an ImpactMap, got {type(impact_map).__name__}")
        if not (int(max_period) == max_period and 1 <= max_period <= 64):
            raise ValueError(f"max_period must be an integer in [1, 64], got {max_period!r}")
        if not (criterion > 0 and np.isfinite(criterion)):
            raise ValueError(f"criterion must be > 0, got {criterion!r}")
        if not (detect_tol > 0 and np.isfinite(detect_tol)):
            raise ValueError(f"detect_tol must be > 0, got {detect_tol!r}")
        self.map = impact_map
        self.T = impact_map.period
        self.criterion = float(criterion)
        self.max_period = int(max_period)
        self.detect_tol = float(detect_tol)
        self.max_newton = int(max_newton)
        self.attractors: list = [self._refine(np.asarray(fixed_point, float), 1, 0)
                                            or self._bare_symmetric(fixed_point)]

    @property
    def tail_length(self) -> int:
        """Iterates per tail needed to see ``max_period`` repeat twice: ``max_period + 2``."""
        return self.max_period + 2

    def _bare_symmetric(self, fp) -> _basins.Attractor:
        return _basins.Attractor(0, "symmetric orbit (period 1)", 1,
                         np.asarray(fp, float).reshape(1, 4), kind="symmetric")

    def _name(self, k: int, label: int) -> str:
        if label == 0:
            return "symmetric orbit (period 1)"
        same = [a for a in self.attractors if a.period == k and a.label > 0]
        return f"period-{k} orbit" + (f" {chr(ord('A') + len(same))}" if same else "")

    def _refine(self, s0: np.ndarray, k: int, label: int) -> _basins.Attractor | None:
        try:
            orb = find_orbit(self.map, s0, period=k, tol=1e-12)
        except (ValueError, RuntimeError, np.linalg.LinAlgError):
            return None
        if not orb.converged:
            return None
        kmin = int(orb.minimal_period)
        if label == 0 and kmin != 1:
            return None
        pts = _canonical(orb.orbit[:kmin], self.T)
        if kmin != k:   # landed on a cycle of smaller period: its own multipliers
            return self._refine(pts[0], kmin, label)
        walls = orb.walls
        shift = int(np.argmin(np.asarray(orb.orbit)[:, 0] % self.T))
        walls = tuple(walls[shift:]) + tuple(walls[:shift])
        return _basins.Attractor(label, self._name(k, label), k, pts, orb.multipliers,
                         float(orb.spectral_radius), orb.stable,
                         "symmetric" if label == 0 else "periodic", walls, float(orb.residual))

    def _add(self, att: _basins.Attractor) -> None:
        same = [i for i, a in enumerate(self.attractors) if a.label > 0 and a.period == att.period]
        if len(same) == 1:   # a second cycle of this period: the first becomes "A"
            first = self.attractors[same[0]]
            self.attractors[same[0]] = replace(first, name=f"{first.name} A")
        self.attractors.append(att)

    def _known(self, att: _basins.Attractor) -> _basins.Attractor | None:
        """An attractor already catalogued with the same cycle (up to a cyclic shift)."""
        for a in self.attractors:
            if a.period != att.period:
                continue
            d2 = paper_distance2(a.points[:, None, :], att.points[None, :, :], self.T)
            if d2.min() <= 1e-12 * (1.0 + float(np.abs(att.points).max()) ** 2):
                return a
        return None

    def _match(self, tails: np.ndarray, att: _basins.Attractor) -> np.ndarray:
        # the first iterate rules most tails out; the whole tail only for the rest
        d0 = paper_distance2(tails[:, 0, None, :], att.points[None, :, :], self.T)
        ok = d0.min(axis=1) < self.criterion
        idx = np.flatnonzero(ok)
        d2 = paper_distance2(tails[idx, :, None, :], att.points[None, None, :, :], self.T)
        ok[idx] = np.all(d2.min(axis=2) < self.criterion, axis=1)
        return ok

    def _period(self, tails: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Smallest repeating period of each tail (0: none) and its repeat error."""
        M, K1 = tails.shape[:2]
        per = np.zeros(M, dtype=np.int64)
        err = np.full(M, np.inf)
        scale = np.maximum(1.0, np.nanmax(np.abs(tails[:, :, 1:]), axis=(1, 2)))
        for k in range(min(self.max_period, K1 - 2), 0, -1):
            d = tails[:, k:] - tails[:, :-k]
            d[..., 0] = wrap_phase(d[..., 0], self.T)
            e = np.max(np.abs(d), axis=(1, 2)) / scale
            hit = e <= self.detect_tol
            # descending k: a smaller period overwrites a multiple of it
            per[hit] = k
            err[hit] = e[hit]
        return per, err

    def assign(self, tails) -> np.ndarray:
        """Label tails of trajectories by the cycle they sit on.

        Parameters
        ----------
        tails : array_like, shape (M, K + 1, 4)
            Iterates ``n, ..., n + K`` of ``M`` trajectories (rows with NaN: not on a cycle).

        Returns
        -------
        labels : ndarray of int, shape (M,)
            Attractor labels (``>= 0``) or :data:`NO_CONVERGENCE`. New cycles are added to
            :attr:`attractors`.
        """
        tails = np.asarray(tails, float)
        if tails.ndim != 3 or tails.shape[2] != 4:
            raise ValueError(f"tails must have shape (M, K + 1, 4), got {tails.shape}")
        lab = np.full(tails.shape[0], _NC, dtype=np.int64)
        finite = np.all(np.isfinite(tails), axis=(1, 2))
        for a in self.attractors:
            free = finite & (lab == _NC)
            lab[free] = np.where(self._match(tails[free], a), a.label, _NC)
        free = np.flatnonzero(finite & (lab == _NC))
        if free.size == 0:
            return lab
        per, err = self._period(tails[free])
        order = np.argsort(err, kind="stable")
        tried = 0
        for j in order:
            i = free[j]
            if per[j] == 0 or tried >= self.max_newton:
                break
            if lab[i] != _NC:
                continue
            tried += 1
            att = self._refine(tails[i, -1], int(per[j]), len(self.attractors))
            # keep a new cycle only if the tail that led to it lies on it
            if (att is None or self._known(att) is not None
                    or not self._match(tails[i:i + 1], att)[0]):
                continue
            self._add(att)
            rest = free[lab[free] == _NC]
            lab[rest] = np.where(self._match(tails[rest], att), att.label, _NC)
        return lab


def slice_points(attractor: _basins.Attractor, L: float) -> np.ndarray:
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
