"""The impact map ``P`` (paper (21)-(23)), its Jacobian ``DP`` (24)-(26) and stability (27).

Section ``Sigma = {z3 = +L, z4 > 0}`` (pre-impact states at the right wall), coordinates
``s = (phi, z1, z2, z4)`` with ``phi = t mod T``, ``z1 = x2``, ``z2 = y2``, ``z4 = y1 - y2``.
``P(s)`` applies the impact at ``+L`` and simulates until the next pre-impact state at the
right wall, whatever happens in between (on a simple orbit: one impact on the left wall). It
is computed by the simulator (the compiled closed-form engine of :mod:`hybridpd.pair.batch`), so
it is usable from any state, not only near an orbit.

``DP`` comes from the symbolic blocks ``DP43 DP32 DP21 DP10`` (:mod:`hybridpd.pair.symbolic`)
whenever the return has the simple pattern (+L, -L, +L); :meth:`ImpactMap.jacobian_fd` gives
central finite differences of the simulated map as an independent check.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hybridpd._repr import compact_repr
from hybridpd.analysis.floquet import Stability, stability
from hybridpd.model import (
    Case,
    ImpactPair,
    Reference,
    as_gains,
    check_array,
    check_int,
    check_positive,
)
from hybridpd.pair import symbolic
from hybridpd.pair.batch import (
    STATUS_IMPACT,
    _impact_velocities,
    impact_map,
    iterate_map,
    next_impact,
    pack_params,
)

__all__ = ["ImpactMap", "MapResult", "Stability", "stability"]

@dataclass(frozen=True)
class MapResult:
    """Result of applying ``P`` to points.

    Attributes
    ----------
    s : ndarray, shape (N, 4)
        Images ``P(s)`` (``phi`` in ``[0, T)``); meaningless where ``ok`` is False.
    ok : ndarray of bool, shape (N,)
        The trajectory returned to the section.
    status : ndarray of int, shape (N,)
        0 when ``ok``; else ``10 + batch.STATUS_*`` of the flight that failed.
    n_impacts : ndarray of int, shape (N,)
        Impacts taken to return (2 on a simple orbit).
    """

    __repr__ = compact_repr

    s: np.ndarray
    ok: np.ndarray
    status: np.ndarray
    n_impacts: np.ndarray


class ImpactMap:
    """The impact map of the PD-controlled impact pair.

    Parameters
    ----------
    pair : ImpactPair
    gains : PDGains or (kp, kv)
    reference : Reference
    case : {"collocated", "noncollocated"}
    tol : float
        Gap tolerance (length) of the contact location.
    max_impacts : int
        Bound on the impacts taken by one application of ``P``.

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains, Reference
    >>> from hybridpd.analysis.orbits import symmetric_orbit
    >>> orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    >>> P = ImpactMap(orb.pair, orb.gains, orb.reference())
    >>> bool(np.allclose(P(orb.fixed_point), orb.fixed_point, atol=1e-12))
    True
    """

    def __init__(self, pair: ImpactPair, gains, reference: Reference, case="collocated", *,
                 tol: float = 1e-13, max_impacts: int = 1000):
        gains = as_gains(gains)
        if not isinstance(pair, ImpactPair):
            raise ValueError(f"pair must be an ImpactPair, got {type(pair).__name__}")
        if not isinstance(reference, Reference):
            raise ValueError(f"reference must be a Reference, got {type(reference).__name__}")
        self.pair, self.gains, self.reference = pair, gains, reference
        self.case = Case.parse(case)
        self.tol = check_positive("tol", tol)
        self.max_impacts = check_int("max_impacts", max_impacts, 1)
        self.params = pack_params(gains.kp, gains.kv, pair.m2, pair.mu, pair.e, pair.L,
                                  reference.omega, reference.xm)
        self._c = 0 if self.case is Case.COLLOCATED else 1

    @property
    def period(self) -> float:
        """``T = 2 pi / omega``."""
        return self.reference.period

    def _points(self, s) -> np.ndarray:
        s = check_array("s", s, trailing=(4,))
        if np.any(s[..., 3] <= 0):
            raise ValueError("s[..., 3] = z4 must be > 0 (approaching the +L wall)")
        return np.ascontiguousarray(s.reshape(-1, 4))

    def apply(self, s) -> MapResult:
        """Apply ``P`` to points ``s`` of shape ``(4,)`` or ``(N, 4)``."""
        pts = self._points(s)
        out, status, nimp = impact_map(self.params, self._c, pts, self.tol, self.max_impacts)
        return MapResult(out, status == 0, status, nimp)

    def __call__(self, s) -> np.ndarray:
        """``P(s)``; raises ``RuntimeError`` if a trajectory does not return to the section."""
        s_arr = check_array("s", s, trailing=(4,))
        r = self.apply(s_arr)
        if not np.all(r.ok):
            raise RuntimeError(f"P undefined at {int((~r.ok).sum())} point(s): status "
                               f"{np.unique(r.status[~r.ok]).tolist()}")
        return r.s.reshape(s_arr.shape)

    def iterate(self, s0, n: int) -> np.ndarray:
        """Orbit ``s0, P(s0), ..., P^n(s0)`` of shape ``(n + 1, 4)`` (NaN rows after a failure)."""
        orbit, _done, _st = iterate_map(self.params, self._c, self._points(s0)[0], int(n),
                                      self.tol, self.max_impacts)
        return orbit

    def flight_times(self, s):
        """Walls and flight times of one application of ``P`` from the section point ``s``.

        Returns a list of ``(wall, tau)`` for the impacts after the initial one.
        """
        s = self._points(s)[0]
        L, mu, e = self.pair.L, self.pair.mu, self.pair.e
        T = self.period
        x2, y2 = s[1], s[2]
        x1, y1 = x2 + L, y2 + s[3]
        y1, y2 = _impact_velocities(mu, e, y1, y2)
        t = s[0]
        seq = []
        for _ in range(self.max_impacts):
            st, tau, wall, x1, y1, x2, y2, graze = next_impact(
                self.params, self._c, t, x1, y1, x2, y2, 50.0 * T, self.tol)
            if st != STATUS_IMPACT:
                raise RuntimeError(f"flight from t = {t:g} ended with status {st}")
            seq.append((int(wall), float(tau)))
            t += tau
            x1 = x2 + wall * L
            if wall == 1:
                return seq
            if not graze:
                y1, y2 = _impact_velocities(mu, e, y1, y2)
        raise RuntimeError("no return to the section within max_impacts")

    def jacobian(self, s) -> symbolic.JacobianResult:
        """``DP`` at ``s`` from the symbolic blocks (the return must be +L, -L, +L)."""
        seq = self.flight_times(s)
        if [w for w, _ in seq] != [-1, 1]:
            raise ValueError(
                f"the symbolic DP needs the impact pattern (+L, -L, +L); got walls "
                f"{[w for w, _ in seq]} (use jacobian_fd)")
        g, p = self.gains, self.pair
        return symbolic.map_jacobian(np.asarray(s, float), seq[0][1], seq[1][1],
                                     xm=self.reference.xm, kp=g.kp, kv=g.kv, m2=p.m2, mu=p.mu,
                                     e=p.e, L=p.L, w=self.reference.omega, case=self.case.value)

    def jacobian_fd(self, s, h: float | None = None) -> np.ndarray:
        """Central finite differences of the simulated map, with the phase unwrapped.

        ``h`` defaults to ``1e-6`` times the coordinate scale.
        """
        s = self._points(s)[0]
        T = self.period
        J = np.empty((4, 4))
        for j in range(4):
            hj = (1e-6 * max(1.0, abs(s[j]))) if h is None else h
            d = np.zeros(4)
            d[j] = hj
            a, b = self(s + d), self(s - d)
            diff = a - b
            # phi is taken mod T: unwrap across the cut
            diff[0] = (diff[0] + 0.5 * T) % T - 0.5 * T
            J[:, j] = diff / (2 * hj)
        return J

    def stability(self, s) -> Stability:
        """Stability of the fixed point ``s`` from the symbolic ``DP``."""
        return stability(np.asarray(self.jacobian(s).DP).reshape(4, 4))

