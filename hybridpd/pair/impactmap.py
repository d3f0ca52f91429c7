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

import warnings
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.analysis.floquet import Stability, stability
from hybridpd.analysis.maps import MapResult, PoincareMap, check_returns
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
from hybridpd.pair.batch import impact_map, iterate_map, pack_params, trace_once

__all__ = ["BatchMapResult", "ImpactMap", "MapResult", "Stability", "stability"]

#: :attr:`MapResult.status` of the engine's codes ``10 + batch.STATUS_*``.
STATUS_NAMES = {0: "returned", 11: "end_time", 12: "sticking", 13: "unresolved",
                14: "nonfinite"}
_KINDS = ("crossing", "grazing", "zeno")


@dataclass(frozen=True)
class BatchMapResult:
    """Result of applying ``P`` to many points at once (:meth:`ImpactMap.apply_batch`).

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


class ImpactMap(PoincareMap):
    """The impact map of the PD-controlled impact pair: the compiled closed-form engine.

    A named specialisation of the map protocol (:class:`~hybridpd.analysis.maps.PoincareMap`)
    for the PD impact pair: closed-form flights between impacts (:mod:`hybridpd.pair.batch`),
    ``DP`` from the symbolic blocks ``DP43 DP32 DP21 DP10`` on the simple pattern
    ``(+L, -L, +L)`` (finite differences otherwise). It equals the general
    :class:`~hybridpd.analysis.hybridmap.SectionMap` on :func:`~hybridpd.analysis.sections.
    impact_pair_section` to about ``1e-12`` (``tests/test_specialisations.py``). Measured
    (``benchmarks/bench_specialisations.py``, README parameters, loaded 2-core machine): ``P``
    5 times faster per call and 57-130 times faster in batch (:meth:`apply_batch`) than the
    general path; the symbolic ``DP`` per point is 0.3-0.6 times as fast as the general
    saltation ``DP`` (it is kept for its named blocks and the vectorised orbit grids of
    :mod:`hybridpd.pair.symbolic`, not for speed). Limits: PD controllers only (any LTI
    controller: :class:`~hybridpd.pair.lti.LTIImpactMap`); a sticking phase is one
    ``"zeno"`` jump and its release, not the accumulating impacts the general path resolves
    one by one.

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
    >>> from hybridpd.pair.orbits import symmetric_orbit
    >>> orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    >>> P = ImpactMap(orb.pair, orb.gains, orb.reference())
    >>> bool(np.allclose(P(orb.fixed_point), orb.fixed_point, atol=1e-12))
    True
    >>> P.apply(orb.fixed_point).signature
    (('wall+', 'crossing'), ('wall-', 'crossing'))
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

    @property
    def dim(self) -> int:
        return 4

    @property
    def names(self) -> tuple:
        return ("phi", "z1", "z2", "z4")

    def _points(self, s) -> np.ndarray:
        s = check_array("s", s, trailing=(4,))
        if np.any(s[..., 3] <= 0):
            raise ValueError("s[..., 3] = z4 must be > 0 (approaching the +L wall)")
        return np.ascontiguousarray(s.reshape(-1, 4))

    def _fd_steps(self, s, H):
        H = H.copy()
        H[3] = min(H[3], 0.5 * s[3])          # stay on the section side z4 > 0
        return H

    def apply(self, s, k: int = 1, jacobian: bool = False) -> MapResult:
        """Apply ``P^k`` to the section point ``s`` (shape ``(4,)``), optionally with ``DP^k``.

        ``DP^k`` is the chain of symbolic blocks when every return has the simple pattern,
        else central differences of the engine's ``P^k``.
        """
        if np.ndim(s) == 2:             # the former batch call
            warnings.warn("ImpactMap.apply of an (N, 4) array is deprecated: use apply_batch",
                          DeprecationWarning, stacklevel=2)
            return self.apply_batch(s)
        k = check_returns(k)
        cur = self._points(check_array("s", s, shape=(4,)))[0]
        T = self.period
        jumps = [(float(cur[0]), "free", "wall+", "free", "crossing")]
        s0, blocks = cur, []
        t_abs = float(cur[0])
        st = 0
        for i in range(k):
            out, st, _n, rec = trace_once(self.params, self._c, cur, self.tol, self.max_impacts)
            off = t_abs - cur[0]        # engine time (from phi) -> time since t = 0
            for q, r in enumerate(rec):
                t = float(r[5] + r[1] + off)
                g = "wall+" if r[0] > 0 else "wall-"
                if st == 0 and q == len(rec) - 1:
                    t_abs = t
                    if i < k - 1:
                        jumps.append((t, "free", g, "free", _KINDS[int(r[3])]))
                elif r[3] == 2:
                    sm = "stick" + g[-1]
                    jumps += [(t, "free", g, sm, "zeno"),
                              (t + float(r[4]), sm, "release" + g[-1], "free", "crossing")]
                else:
                    jumps.append((t, "free", g, "free", _KINDS[int(r[3])]))
            if st != 0:
                return MapResult(np.full(4, np.nan), False, STATUS_NAMES.get(int(st),
                                 str(int(st))), float(jumps[0][0]), float(out[0]),
                                 self.state(out, out[0]), "free", tuple(jumps),
                                 any(j[4] == "grazing" for j in jumps))
            blocks.append((cur, rec))
            cur = out
        z = self.state(cur, t_abs)
        grazing = any(j[4] == "grazing" for j in jumps) or cur[3] <= 1e-12 * max(1.0, T)
        DP = self._power_dp(s0, k, blocks) if jacobian else None
        return MapResult(cur.copy(), True, "returned", float(jumps[0][0]), t_abs, z, "free",
                         tuple(jumps), bool(grazing), DP)

    def state(self, s, t) -> np.ndarray:
        """Full state ``[x1, y1, x2, y2, pc, ps]`` of the pre-impact section point ``s`` at time
        ``t``."""
        return np.array([s[1] + self.pair.L, s[2] + s[3], s[1], s[2],
                         *self.reference.exo_state(t)])

    def _power_dp(self, s, k, blocks) -> np.ndarray:
        """``DP^k``: the chain of symbolic blocks when every return is simple, else FD."""
        simple = all(len(rec) == 2 and rec[0, 0] < 0 and rec[1, 0] > 0
                     and not np.any(rec[:, 3]) for _s, rec in blocks)
        if not simple:
            return self.jacobian_fd(s, k=k, one_sided=True)
        DP = np.eye(4)
        for si, rec in blocks:
            DP = self._symbolic(si, rec[0, 1], rec[1, 1]).DP.reshape(4, 4) @ DP
        return DP

    def _symbolic(self, s, tau1, tau2) -> symbolic.JacobianResult:
        g, p = self.gains, self.pair
        return symbolic.map_jacobian(np.asarray(s, float), tau1, tau2, xm=self.reference.xm,
                                     kp=g.kp, kv=g.kv, m2=p.m2, mu=p.mu, e=p.e, L=p.L,
                                     w=self.reference.omega, case=self.case.value)

    def apply_batch(self, s) -> BatchMapResult:
        """Apply ``P`` to points ``s`` of shape ``(4,)`` or ``(N, 4)`` in the compiled loop."""
        pts = self._points(s)
        out, status, nimp = impact_map(self.params, self._c, pts, self.tol, self.max_impacts)
        return BatchMapResult(out, status == 0, status, nimp)

    def apply_many(self, S, k: int = 1) -> tuple:
        S = np.ascontiguousarray(np.atleast_2d(np.asarray(S, float)))
        img = S.copy()
        ok = np.all(np.isfinite(S), axis=1) & (S[:, 3] > 0)
        for _ in range(check_returns(k)):
            idx = np.flatnonzero(ok)
            if idx.size == 0:
                break
            out, status, _n = impact_map(self.params, self._c, np.ascontiguousarray(img[idx]),
                                         self.tol, self.max_impacts)
            img[idx] = out
            ok[idx] = status == 0
        img[~ok] = np.nan
        return img, ok

    def __call__(self, s, k: int = 1) -> np.ndarray:
        """``P^k(s)`` of points ``(4,)`` or ``(N, 4)``; ``RuntimeError`` where undefined."""
        s_arr = check_array("s", s, trailing=(4,))
        img, ok = self.apply_many(self._points(s_arr), k)
        if not np.all(ok):
            raise RuntimeError(f"P undefined at {int((~ok).sum())} point(s)")
        return img.reshape(s_arr.shape)

    def iterate(self, s0, n: int, k: int = 1) -> np.ndarray:
        """Orbit ``s0, P^k(s0), ..., P^{nk}(s0)``, shape ``(n + 1, 4)`` (NaN rows after a failure)."""
        if k != 1:
            return super().iterate(s0, n, k)
        orbit, _done, _st = iterate_map(self.params, self._c, self._points(s0)[0], int(n),
                                        self.tol, self.max_impacts)
        return orbit

    #: Diagram classes of the engine's statuses (:mod:`hybridpd.analysis.diagrams`).
    status_classes: ClassVar[dict] = {"end_time": "no_impact", "sticking": "sticking",
                                      "unresolved": "unresolved", "nonfinite": "diverged"}

    def iterate_status(self, s0, n: int, k: int = 1) -> tuple:
        """:meth:`iterate` and why it stopped (``""``, or a name of ``STATUS_NAMES``), in the
        compiled loop."""
        if k != 1:
            return super().iterate_status(s0, n, k)
        orbit, _done, st = iterate_map(self.params, self._c, self._points(s0)[0], int(n),
                                       self.tol, self.max_impacts)
        return orbit, "" if st == 0 else STATUS_NAMES.get(int(st), str(int(st)))

    def jacobians(self, S, k: int = 1, h: float = 1e-6) -> np.ndarray:
        """``DP`` at every row of ``S`` (shape ``(N, 4)``) by central differences with steps
        ``h max(1, |s_j|)``, all in one call of the engine; one-sided where one side does not
        return, NaN where neither does. Shape ``(N, 4, 4)``."""
        if k != 1:
            return super().jacobians(S, k)
        X = np.ascontiguousarray(np.atleast_2d(np.asarray(S, float)))
        N = X.shape[0]
        H = h * np.maximum(1.0, np.abs(X))
        H[:, 3] = np.minimum(H[:, 3], 0.5 * X[:, 3])   # stay on the section side z4 > 0
        E = np.eye(4)
        pts = np.concatenate([X, (X[:, None, :] + H[:, None, :] * E).reshape(-1, 4),
                              (X[:, None, :] - H[:, None, :] * E).reshape(-1, 4)])
        out, st, _ = impact_map(self.params, self._c, np.ascontiguousarray(pts), self.tol,
                                self.max_impacts)
        Y, ok0 = out[:N], st[:N] == 0
        plus, minus = out[N:5 * N].reshape(N, 4, 4), out[5 * N:].reshape(N, 4, 4)
        okp = (st[N:5 * N] == 0).reshape(N, 4) & ok0[:, None]
        okm = (st[5 * N:] == 0).reshape(N, 4) & ok0[:, None]
        J = np.full((N, 4, 4), np.nan)
        for j in range(4):
            both, hj = okp[:, j] & okm[:, j], H[:, j][:, None]
            d = np.where(both[:, None], plus[:, j] - minus[:, j], np.nan)
            step = np.where(both[:, None], 2 * hj, np.nan)
            only_p, only_m = okp[:, j] & ~okm[:, j], ~okp[:, j] & okm[:, j]
            d = np.where(only_p[:, None], plus[:, j] - Y, d)
            d = np.where(only_m[:, None], Y - minus[:, j], d)
            step = np.where((only_p | only_m)[:, None], hj, step)
            with np.errstate(invalid="ignore"):
                J[:, :, j] = self.wrap(d) / step     # NaN where neither side returns
        return J

    def flight_times(self, s):
        """Walls and flight times of one application of ``P`` from the section point ``s``.

        Returns a list of ``(wall, tau)`` for the impacts after the initial one.
        """
        _out, st, _n, rec = trace_once(self.params, self._c, self._points(s)[0], self.tol,
                                       self.max_impacts)
        if st != 0 or np.any(rec[:, 3] == 2):
            raise RuntimeError(f"no return to the section without sticking: status {st}")
        return [(int(r[0]), float(r[1])) for r in rec]

    def jacobian(self, s) -> symbolic.JacobianResult:
        """``DP`` at ``s`` from the symbolic blocks (the return must be +L, -L, +L)."""
        seq = self.flight_times(s)
        if [w for w, _ in seq] != [-1, 1]:
            raise ValueError(
                f"the symbolic DP needs the impact pattern (+L, -L, +L); got walls "
                f"{[w for w, _ in seq]} (use jacobian_fd)")
        return self._symbolic(s, seq[0][1], seq[1][1])

    def jacobian_fd(self, s, h: float | None = None, *, k: int = 1, scale=None,
                    richardson: bool = False, one_sided: bool = False) -> np.ndarray:
        """Central finite differences of the simulated map (:meth:`PoincareMap.jacobian_fd`)."""
        return super().jacobian_fd(self._points(s)[0], k, h=h, scale=scale,
                                   richardson=richardson, one_sided=one_sided)

    def stability(self, s) -> Stability:
        """Stability of the fixed point ``s`` from the symbolic ``DP``."""
        return stability(np.asarray(self.jacobian(s).DP).reshape(4, 4))
