r"""The map protocol: one interface for every Poincaré (impact) map of the package.

A map acts on the points ``s`` of a section of dimension :attr:`PoincareMap.dim` with
coordinate names :attr:`PoincareMap.names`; when the first coordinate is the phase ``phi`` of a
periodic reference (:attr:`PoincareMap.period` is then its period ``T``), differences of
section points are taken with the phase wrapped to ``[-T/2, T/2)``. A map implements one
method, :meth:`PoincareMap.apply` (``P^k(s)``, optionally ``DP^k``, the return time and the
signature: the sequence of jumps met on the way, as one :class:`MapResult`); the base class
derives everything else once: ``__call__``, :meth:`~PoincareMap.jacobian`,
:meth:`~PoincareMap.jacobian_fd` (the package's one finite-difference ``DP``) and
:meth:`~PoincareMap.iterate`.

The reference implementation is :class:`hybridpd.analysis.hybridmap.SectionMap` (any hybrid
automaton, ``DP`` from saltation matrices). The named specialisations for the impact pair
(:class:`hybridpd.analysis.impactmap.ImpactMap`, the compiled closed-form engine with the
symbolic ``DP``; :class:`hybridpd.analysis.lti.LTIImpactMap`, exact flights under any LTI
controller) implement the same protocol; each states its measured speed-up over the general
path in its docstring and is compared with it in ``tests/test_specialisations.py``.
"""
from __future__ import annotations

import abc
from dataclasses import dataclass, field

import numpy as np

from hybridpd._repr import compact_repr

__all__ = ["MapResult", "PoincareMap", "check_returns", "minimal_period"]


@dataclass(frozen=True, eq=False)
class MapResult:
    """One application of ``P^k`` (see :meth:`PoincareMap.apply`).

    Attributes
    ----------
    s : ndarray, shape (dim,)
        The image (NaN unless ``ok``; ``phi`` in ``[0, T)``).
    ok : bool
        The run returned to the section.
    status : str
        ``"returned"`` when ``ok``; otherwise why the run stopped (the values depend on the
        map, e.g. :data:`hybridpd.analysis.hybridmap.MAP_STATUS`).
    t_start, t_hit : float
        Start time (``phi``, or 0) and time of the return (time units).
    z_hit : ndarray, shape (n,)
        Full pre-jump state at the return (or where the run stopped).
    mode_final : str
        Mode where the run stopped.
    jumps : tuple of (float, str, str, str, str)
        ``(t, source mode, guard, target mode, kind)`` of every jump before the return, the
        initial one included; ``kind`` is ``"crossing"``, ``"grazing"`` or ``"zeno"``.
    grazing : bool
        A grazing jump occurred, or the return is tangential.
    DP : ndarray, shape (dim, dim) or None
        Jacobian, when requested and ``ok`` (phase unwrapped).
    """

    s: np.ndarray
    ok: bool
    status: str
    t_start: float
    t_hit: float
    z_hit: np.ndarray
    mode_final: str
    jumps: tuple
    grazing: bool
    DP: np.ndarray | None = field(default=None, repr=False)
    __repr__ = compact_repr

    @property
    def signature(self) -> tuple:
        """``(guard, kind)`` of the jumps: the impact sequence of this return."""
        return tuple((j[2], j[4]) for j in self.jumps)


def check_returns(k) -> int:
    """``k`` (number of returns) as an int ``>= 1`` (``ValueError`` otherwise)."""
    if isinstance(k, bool) or int(k) != k or k < 1:
        raise ValueError(f"k (the number of returns) must be an int >= 1, got {k!r}")
    return int(k)


class PoincareMap(abc.ABC):
    """A map of section points: the protocol of every impact map (module docstring).

    Subclasses implement :attr:`dim`, :attr:`names`, :attr:`period` and :meth:`apply`; they
    may override :meth:`apply_many` with a compiled batch (used by :meth:`jacobian_fd`).
    """

    @property
    @abc.abstractmethod
    def dim(self) -> int:
        """Number of section coordinates."""

    @property
    @abc.abstractmethod
    def names(self) -> tuple:
        """Names of the section coordinates (``"phi"`` first when there is a phase)."""

    @property
    @abc.abstractmethod
    def period(self) -> float | None:
        """Period ``T`` of the phase coordinate ``s[0]``, or None without a phase."""

    @abc.abstractmethod
    def apply(self, s, k: int = 1, jacobian: bool = False) -> MapResult:
        """Apply ``P^k`` to the section point ``s`` (optionally with ``DP^k``)."""

    def _fd_steps(self, s, H):
        """Finite-difference steps at ``s`` (a hook: keep ``s +- H`` on the section)."""
        return H

    def wrap(self, ds) -> np.ndarray:
        """Differences of section points with the phase taken to ``[-T/2, T/2)``."""
        ds = np.array(ds, float, copy=True)
        T = self.period
        if T is not None and self.names[0] == "phi":
            ds[..., 0] = (ds[..., 0] + 0.5 * T) % T - 0.5 * T
        return ds

    def __call__(self, s, k: int = 1) -> np.ndarray:
        """``P^k(s)``; ``RuntimeError`` (with the status) if the run does not return."""
        r = self.apply(s, k)
        if not r.ok:
            raise RuntimeError(f"P^{k} undefined at s = {np.asarray(s).tolist()}: {r.status}")
        return r.s

    def jacobian(self, s, k: int = 1) -> np.ndarray:
        """``DP^k(s)`` (shape ``(dim, dim)``) from :meth:`apply`."""
        r = self.apply(s, k, jacobian=True)
        if not r.ok:
            raise RuntimeError(f"P^{k} undefined at s = {np.asarray(s).tolist()}: {r.status}")
        return r.DP

    def apply_many(self, S, k: int = 1) -> tuple:
        """``P^k`` of points ``S`` (shape ``(N, dim)``): images ``(N, dim)`` and ``ok`` ``(N,)``."""
        S = np.atleast_2d(np.asarray(S, float))
        img = np.full(S.shape, np.nan)
        ok = np.zeros(len(S), bool)
        for i, s in enumerate(S):
            try:
                r = self.apply(s, k)
            except ValueError:          # not a section point: undefined there
                continue
            ok[i] = r.ok
            img[i] = r.s
        return img, ok

    def jacobian_fd(self, s, k: int = 1, *, h: float | None = None, scale=None,
                    richardson: bool = False, one_sided: bool = False) -> np.ndarray:
        """Central finite differences of ``P^k`` (phase differences wrapped), ``(dim, dim)``.

        Parameters
        ----------
        s : array_like, shape (dim,)
            Section point.
        k : int
            Number of returns.
        h : float, optional
            Step: coordinate ``j`` moves by ``h * scale[j]`` (default ``1e-6``).
        scale : array_like, shape (dim,), optional
            Coordinate scales; default ``max(1, |s_j|)`` with the default ``h`` and 1 with a
            given ``h`` (an absolute step). States with very small or large natural
            magnitudes need their own scale, otherwise the step leaves the linear range of
            that coordinate.
        richardson : bool
            Combine steps ``h`` and ``h/2`` as ``(4 J(h/2) - J(h)) / 3`` (error ``O(h^4)``).
        one_sided : bool
            Where one side of a coordinate is undefined (the map does not return), use a
            one-sided difference on the other (``RuntimeError`` if both are undefined).

        Returns
        -------
        ndarray, shape (dim, dim)
        """
        s = np.asarray(s, float)
        k = check_returns(k)
        m = self.dim
        if s.shape != (m,) or not np.all(np.isfinite(s)):
            raise ValueError(f"s must be {m} finite numbers {self.names}, got shape {s.shape}")
        hr = 1e-6 if h is None else float(h)
        if not hr > 0:
            raise ValueError(f"h must be > 0, got {h!r}")
        if scale is None:
            sc = np.maximum(1.0, np.abs(s)) if h is None else np.ones(m)
        else:
            sc = np.asarray(scale, float)
        if sc.shape != (m,) or not np.all(np.isfinite(sc)) or np.any(sc <= 0):
            raise ValueError(f"scale must be {m} positive finite numbers, got {scale!r}")

        def central(hrel):
            H = self._fd_steps(s, hrel * sc)
            # the centre is needed only for a one-sided difference
            S = np.concatenate([s + np.diag(H), s - np.diag(H)] + [s[None, :]] * one_sided)
            img, ok = self.apply_many(S, k)
            if ok[:2 * m].all():
                return self.wrap(img[:m] - img[m:2 * m]).T / (2 * H)
            J = np.empty((m, m))
            for j in range(m):
                if ok[j] and ok[m + j]:
                    d, hh = img[j] - img[m + j], 2 * H[j]
                elif one_sided and ok[j] and ok[2 * m]:
                    d, hh = img[j] - img[2 * m], H[j]
                elif one_sided and ok[m + j] and ok[2 * m]:
                    d, hh = img[2 * m] - img[m + j], H[j]
                else:
                    raise RuntimeError(f"P^{k} undefined around s in direction {j}")
                J[:, j] = self.wrap(d) / hh
            return J

        if richardson:
            return (4.0 * central(hr / 2) - central(hr)) / 3.0
        return central(hr)

    def iterate(self, s0, n: int, k: int = 1) -> np.ndarray:
        """``s0, P^k(s0), ..., P^{nk}(s0)``, shape ``(n + 1, dim)``; NaN rows after a failure."""
        out = np.full((int(n) + 1, self.dim), np.nan)
        out[0] = s0
        for i in range(int(n)):
            try:
                r = self.apply(out[i], k)
            except ValueError:
                if i == 0:              # a bad start
                    raise
                break                   # the image left the section's domain
            if not r.ok:
                break
            out[i + 1] = r.s
        return out


def minimal_period(P: PoincareMap, s, k: int, rtol: float = 1e-7) -> int:
    """Smallest ``d`` dividing ``k`` with ``P^d(s) = s`` to ``rtol`` (relative to ``max(1, |s|)``).

    The one period detector of a fixed point of ``P^k`` (e.g. 1 when a period-2 search landed
    on a fixed point of ``P``).
    """
    s = np.asarray(s, float)
    for d in range(1, k):
        if k % d == 0:
            img, ok = P.apply_many(s[None, :], d)
            if ok[0] and np.max(np.abs(P.wrap(img[0] - s))) <= rtol * max(1.0, np.max(np.abs(s))):
                return d
    return k
