r"""The map protocol: one interface for every Poincaré (impact) map of the package.

A map acts on the points ``s`` of a section of dimension :attr:`PoincareMap.dim` with
coordinate names :attr:`PoincareMap.names`; when the first coordinate is the phase ``phi`` of a
periodic reference (:attr:`PoincareMap.period` is then its period ``T``), differences of
section points are taken with the phase wrapped to ``[-T/2, T/2)``. A map implements one
method, :meth:`PoincareMap.apply` (``P^k(s)``, optionally ``DP^k``, the return time and the
signature: the sequence of jumps met on the way, as one :class:`MapResult`); the base class
derives everything else once: ``__call__``, :meth:`~PoincareMap.jacobian`,
:meth:`~PoincareMap.jacobian_fd` and its batch :meth:`~PoincareMap.jacobians_fd`
(finite-difference ``DP`` by the package's one rule, :mod:`hybridpd.analysis.fd`) and
:meth:`~PoincareMap.iterate`.

The reference implementation is :class:`hybridpd.analysis.hybridmap.SectionMap` (any hybrid
automaton, ``DP`` from saltation matrices). The named specialisation for the impact pair
(:class:`hybridpd.pair.impactmap.ImpactMap`, the compiled closed-form engine with the
symbolic ``DP``) implements the same protocol; it states its measured speed-up over the
general path in its docstring and is compared with it in ``tests/test_specialisations.py``.
"""
from __future__ import annotations

import abc
import math
from dataclasses import dataclass, field

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.analysis.fd import difference_quotients
from hybridpd.model import wrap_phase

__all__ = ["MapResult", "PoincareMap", "check_returns", "detect_period", "minimal_period"]


@dataclass(frozen=True, eq=False)
class MapResult:
    """One application of ``P^k`` (see :meth:`PoincareMap.apply`).

    Only ``s`` is required: ``MapResult(s)`` or ``MapResult(s, DP=J)`` is a complete answer of
    a map without times or jumps; the other fields default to "returned, no timing".

    Attributes
    ----------
    s : ndarray, shape (dim,)
        The image (NaN unless ``ok``; ``phi`` in ``[0, T)``).
    ok : bool
        The run returned to the section (default True).
    status : str
        ``"returned"`` when ``ok``; otherwise why the run stopped (the values depend on the
        map, e.g. :data:`hybridpd.analysis.hybridmap.MAP_STATUS`).
    t_start, t_hit : float
        Start time (``phi``, or 0) and time of the return (time units; NaN for a map
        without time).
    z_hit : ndarray, shape (n,) or None
        Full pre-jump state at the return (or where the run stopped).
    mode_final : str
        Mode where the run stopped (empty for a map without modes).
    jumps : tuple of (float, str, str, str, str)
        ``(t, source mode, guard, target mode, kind)`` of every jump before the return, the
        initial one included; ``kind`` is ``"crossing"``, ``"grazing"`` or ``"zeno"``.
    grazing : bool
        A grazing jump occurred, or the return is tangential.
    DP : ndarray, shape (dim, dim) or None
        Jacobian, when requested and ``ok`` (phase unwrapped).
    structural_zeros : int or None
        Multipliers of ``DP`` that vanish by construction on this run (directions its jumps
        remove: a held input overwritten at a sample, a contact's gap and normal velocity
        projected at the start of a sticking phase); None: the map's own
        :attr:`PoincareMap.structural_zeros`.

    Examples
    --------
    >>> r = MapResult(np.array([0.5, 0.2]), DP=np.eye(2))
    >>> r.ok, r.status, r.signature
    (True, 'returned', ())
    """

    s: np.ndarray
    ok: bool = True
    status: str = "returned"
    t_start: float = math.nan
    t_hit: float = math.nan
    z_hit: np.ndarray | None = field(default=None, repr=False)
    mode_final: str = ""
    jumps: tuple = ()
    grazing: bool = False
    DP: np.ndarray | None = field(default=None, repr=False)
    structural_zeros: int | None = None
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

    For developers
    --------------
    A map gives :attr:`names` (a tuple of coordinate names; :attr:`dim` follows), its
    :attr:`period` (``T`` when ``s[0]`` is a phase of period ``T``, else None; a class
    attribute is enough) and :meth:`apply`, returning a :class:`MapResult` (with ``DP``
    when ``jacobian`` is asked and the map knows it; without one the analyses take
    :meth:`jacobian_fd`). Everything else is derived once here: ``__call__``,
    :meth:`jacobian`, :meth:`jacobian_fd`, :meth:`jacobians_fd`, :meth:`iterate`,
    :meth:`apply_many`, :meth:`wrap`. A specialisation overrides only what it speeds up (a
    compiled :meth:`apply_many` or :meth:`iterate`; the finite differences evaluate through
    :meth:`apply_many`). Maps that know more about their orbits answer
    the hooks :meth:`refuse` and :meth:`validate` (a hybrid section map checks that a
    fixed point returns after whole reference periods and that an independent simulation
    returns to it), :attr:`structural_zeros`, :meth:`state` and :attr:`mode`. A map with
    quantities of its own at a fixed point (the impact pair's walls, flight margins and
    contact pattern) returns them from :meth:`point_quantities`: orbit searches keep them in
    :attr:`~hybridpd.analysis.periodic.PeriodicOrbit.quantities` (a quantity named
    ``grazing`` also raises the orbit's grazing flag). A map with named parameters gives
    :meth:`family`, a builder of the map at other values of one of them, for the one
    continuation engine (:func:`hybridpd.analysis.continuation.continue_orbit`). No analysis
    asks which class it has.

    Examples
    --------
    A linear contraction, written in a few lines:

    >>> class Linear(PoincareMap):
    ...     names = ("x", "y")
    ...     def apply(self, s, k=1, jacobian=False):
    ...         A = np.linalg.matrix_power(np.array([[0.5, 1.0], [0.0, -0.25]]), k)
    ...         return MapResult(A @ np.asarray(s, float), DP=A if jacobian else None)
    >>> P = Linear()
    >>> P.dim, P.period, P([1.0, 2.0]).tolist()
    (2, None, [2.5, -0.5])
    """

    #: Names of the section coordinates (``"phi"`` first when there is a phase).
    names: tuple = ()
    #: Period ``T`` of the phase coordinate ``s[0]``, or None without a phase.
    period: float | None = None
    #: The mode of the section (maps of hybrid automata; empty otherwise).
    mode: str = ""
    #: Multipliers of ``DP`` that vanish by construction of the coordinates and are not
    #: multipliers of the motion (see :func:`hybridpd.analysis.floquet.stability`).
    structural_zeros: int = 0

    @property
    def dim(self) -> int:
        """Number of section coordinates (``len(names)``)."""
        return len(self.names)

    @abc.abstractmethod
    def apply(self, s, k: int = 1, jacobian: bool = False) -> MapResult:
        """Apply ``P^k`` to the section point ``s`` (optionally with ``DP^k``)."""

    def check_point(self, s) -> np.ndarray:
        """``s`` as a float array of shape ``(dim,)``; ``ValueError`` naming ``s`` otherwise."""
        s = np.asarray(s, float)
        if s.shape != (self.dim,) or not np.all(np.isfinite(s)):
            raise ValueError(f"s must be {self.dim} finite numbers {self.names}, got shape "
                             f"{s.shape}")
        return s

    def state(self, s) -> np.ndarray:
        """The full state at the section point ``s`` (default: ``s`` itself)."""
        return np.array(s, float)

    def refuse(self, s0, k: int, **options):
        """Why no orbit of ``P^k`` can start from ``s0`` before Newton runs: ``(reason,
        detail)``, or None (the default)."""
        del s0, k, options

    def accept(self, result: MapResult, **options) -> bool:
        """Whether Newton may take the trial point whose application gave `result` (True by
        default; a section map refuses returns within one burst of impacts)."""
        return True

    def validate(self, s, k: int, result: MapResult, **options) -> tuple:
        """Whether a zero of ``P^k(s) - s`` is an orbit: ``(reason, n_periods, detail,
        return_error)`` with reason ``"converged"`` when it is (the default)."""
        return "converged", 1, "", math.nan

    def point_quantities(self, s, k: int, result: MapResult, **options) -> dict:
        """Quantities of the map's own at the point ``s`` of ``P^k`` whose application gave
        `result`: a dict by name (empty by default; the impact pair gives its walls and
        flight margins). `options` are those of the analysis (e.g. :func:`~hybridpd.analysis.periodic.find_orbit`'s
        checks); a hook ignores the ones it does not know."""
        del s, k, result, options
        return {}

    def family(self, parameter: str, **options):
        """This map's family in its parameter named `parameter`: a
        :class:`~hybridpd.analysis.family.ParameterFamily` (callable, ``p -> PoincareMap``: this
        map with that parameter set to ``p``, the others kept) with the map's rules of
        continuation, for :func:`~hybridpd.analysis.continuation.continue_orbit`. The default
        map has no named parameters (``ValueError``)."""
        del options
        raise ValueError(f"parameter: this map ({type(self).__name__}) names no parameters, "
                         f"got {parameter!r}; give continue_orbit a builder p -> map")

    def labeller(self):
        """The map's own basin labeller (a :class:`hybridpd.analysis.mappers.Labeller`: a
        compiled labelling and what only the map has, e.g. its slice and metric), or None:
        :func:`hybridpd.analysis.mappers.mapper` then labels by the general rules."""

    def canonical(self, s) -> np.ndarray:
        """The representative of a section point (the phase reduced to ``[0, T)``)."""
        if self.period is not None:
            s[0] %= self.period
        return s

    def _fd_steps(self, S, H):
        """Finite-difference steps at the points ``S`` (shape ``(..., dim)``, as ``H``; a hook:
        keep ``S +- H`` on the section)."""
        return H

    def wrap(self, ds) -> np.ndarray:
        """Differences of section points with the phase taken to ``[-T/2, T/2)``."""
        ds = np.array(ds, float, copy=True)
        T = self.period
        if T is not None:
            ds[..., 0] = wrap_phase(ds[..., 0], T)
        return ds

    def __call__(self, s, k: int = 1) -> np.ndarray:
        """``P^k(s)``; ``RuntimeError`` (with the status) if the run does not return."""
        r = self.apply(s, k)
        if not r.ok:
            raise RuntimeError(f"P^{k} undefined at s = {np.asarray(s).tolist()}: {r.status}")
        return r.s

    def jacobian(self, s, k: int = 1) -> np.ndarray:
        """``DP^k(s)`` (shape ``(dim, dim)``) from :meth:`apply`, or by :meth:`jacobian_fd`
        where the map gives none."""
        r = self.apply(s, k, jacobian=True)
        if not r.ok:
            raise RuntimeError(f"P^{k} undefined at s = {np.asarray(s).tolist()}: {r.status}")
        return self.jacobian_fd(s, k) if r.DP is None else r.DP

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
        """Finite differences of ``P^k`` by the one rule (:mod:`hybridpd.analysis.fd`; phase
        differences wrapped), ``(dim, dim)``: the single-point form of :meth:`jacobians_fd`.

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
            one-sided difference on the other (``RuntimeError`` if both are undefined, or
            the map does not return from ``s``); otherwise central differences only.

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
            J, ok = self._fd_jacobians(s[None, :], k, (hrel * sc)[None, :], one_sided)
            if not ok.all():
                j = int(np.flatnonzero(~ok[0])[0])
                raise RuntimeError(f"P^{k} undefined around s in direction {j}")
            return J[0]

        if richardson:
            return (4.0 * central(hr / 2) - central(hr)) / 3.0
        return central(hr)

    def iterate(self, s0, n: int, k: int = 1) -> np.ndarray:
        """``s0, P^k(s0), ..., P^{nk}(s0)``, shape ``(n + 1, dim)``; NaN rows after a failure."""
        return self.iterate_status(s0, n, k)[0]

    def iterate_status(self, s0, n: int, k: int = 1) -> tuple:
        """:meth:`iterate` and why it stopped early: ``(points, status)`` with ``status``
        ``""`` when all ``n`` iterations ran, else the map's status (``"nonfinite"`` for an
        image that is not finite, ``"off_section"`` where the image left the map's domain)."""
        out = np.full((int(n) + 1, self.dim), np.nan)
        out[0] = s0
        for i in range(int(n)):
            try:
                r = self.apply(out[i], k)
            except ValueError:
                if i == 0:              # a bad start
                    raise
                return out, "off_section"   # the image left the section's domain
            if not r.ok:
                return out, r.status
            if not np.all(np.isfinite(r.s)):
                return out, "nonfinite"
            out[i + 1] = r.s
        return out, ""

    def iterate_many(self, S, n: int, k: int = 1, tail: int = 1) -> tuple:
        """Iterate every row of ``S`` (shape ``(N, dim)``) ``n`` times by ``P^k``:
        ``(tails (N, tail, dim), status (N,), iterations (N,))`` with the last ``tail``
        points of each run and why it stopped (``""`` when it ran to the end; see
        :meth:`iterate_status`). A map may compile this loop (basins run it on whole grids)."""
        S = np.atleast_2d(np.asarray(S, float))
        tails = np.full((len(S), int(tail), self.dim), np.nan)
        status = []
        its = np.zeros(len(S), np.int64)
        for i, s in enumerate(S):
            try:
                pts, why = self.iterate_status(s, n, k)
            except ValueError:
                status.append("off_section")
                continue
            done = int(np.sum(np.all(np.isfinite(pts), axis=1))) - 1
            its[i] = done
            tails[i] = pts[max(done + 1 - int(tail), 0):done + 1][-int(tail):] \
                if done + 1 >= int(tail) else np.nan
            status.append(why)
        return tails, status, its

    def jacobians_fd(self, S, k: int = 1, h: float = 1e-6) -> np.ndarray:
        """Finite differences of ``P^k`` at every row of ``S`` (shape ``(N, dim)``), all
        points in one call of :meth:`apply_many`: the one rule of
        :mod:`hybridpd.analysis.fd` (central, one-sided where one side does not return, NaN
        where neither does or ``P^k`` is undefined at the row), coordinate ``j`` moving by
        ``h max(1, |s_j|)`` (within the map's steps, :meth:`_fd_steps`). Shape
        ``(N, dim, dim)``."""
        X = np.atleast_2d(np.asarray(S, float))
        return self._fd_jacobians(X, k, h * np.maximum(1.0, np.abs(X)), True)[0]

    def _fd_jacobians(self, X, k, H, centre: bool) -> tuple:
        """``(J (N, dim, dim), defined (N, dim))`` at the rows of ``X`` with the steps
        ``H`` (shape ``(N, dim)``) by :func:`~hybridpd.analysis.fd.difference_quotients`
        (without ``centre``, the centre is neither evaluated nor one-sided differences taken).
        """
        k = check_returns(k)
        N, m = X.shape
        H = self._fd_steps(X, H)
        D = H[:, None, :] * np.eye(m)           # row j of point i: its step along j
        c = N if centre else 0
        img, ok = self.apply_many(np.concatenate(
            ([X] if centre else []) + [(X[:, None, :] + D).reshape(-1, m),
                                       (X[:, None, :] - D).reshape(-1, m)]), k)
        vals = img[c:].reshape(2, N, m, m)
        # all returned (the common case): no masks to combine
        masks = {} if ok.all() else dict(ok_plus=ok[c:c + N * m].reshape(N, m),
                                         ok_minus=ok[c + N * m:].reshape(N, m),
                                         ok_centre=ok[:N] if centre else None)
        q, defined = difference_quotients(vals[0], vals[1], H, img[:N] if centre else None,
                                          wrap=self.wrap, **masks)
        return q.swapaxes(-1, -2), defined

    def jacobians(self, S, k: int = 1) -> np.ndarray:
        """``DP^k`` at every row of ``S`` (shape ``(N, dim)``), shape ``(N, dim, dim)``
        (a map may compute them all at once); ``RuntimeError`` where undefined."""
        return np.array([self.jacobian(s, k) for s in np.atleast_2d(S)])


def detect_period(points, wrap, max_period: int, tol: float = 1e-6, *, scale=None):
    """Smallest ``k <= max_period`` with ``points[i] = points[i - k]`` over the whole window,
    or 0: the one period detector of sequences of iterates (basins' tails, diagrams' windows,
    fixed points of ``P^k``).

    ``points`` of shape ``(K, dim)``, or ``(M, K, dim)`` for ``M`` windows at once; ``k``
    repeats when ``max|wrap(s_{j+k} - s_j)| / scale <= tol`` (``k < K``; differences through
    ``wrap``, e.g. :meth:`PoincareMap.wrap`); ``scale`` (one per window) defaults to ``max(1,
    |points|)``. Returns ``(period, error)``: ints and floats for one window, arrays of
    shape ``(M,)`` for several (error ``inf`` where no period repeats).

    Examples
    --------
    >>> detect_period(np.array([[0.0], [1.0], [0.0], [1.0], [0.0], [1.0]]), np.asarray, 4)
    (2, 0.0)
    >>> t = np.array([[[0.0], [1.0], [0.0], [1.0]], [[0.0], [1.0], [2.0], [3.0]]])
    >>> detect_period(t, np.asarray, 2, 1e-9)[0].tolist()
    [2, 0]
    """
    X = np.asarray(points, float)
    one = X.ndim == 2
    if one:
        X = X[None]
    M, K = X.shape[:2]
    per = np.zeros(M, dtype=np.int64)
    err = np.full(M, np.inf)
    if scale is None:
        scale = np.maximum(1.0, np.max(np.abs(X), axis=(1, 2))) if X.size else np.ones(M)
    for k in range(min(int(max_period), K - 1), 0, -1):
        if one:   # wrap sees the shape of one window's differences
            e = np.max(np.abs(wrap(X[0, k:] - X[0, :-k])))[None] / scale
        else:
            e = np.max(np.abs(wrap(X[:, k:] - X[:, :-k])), axis=(1, 2)) / scale
        hit = e <= tol
        # descending k: a smaller period overwrites a multiple of it
        per[hit] = k
        err[hit] = e[hit]
    return (int(per[0]), float(err[0])) if one else (per, err)


def minimal_period(P: PoincareMap, s, k: int, rtol: float = 1e-7) -> int:
    """Smallest ``d`` dividing ``k`` with ``P^d(s) = s`` to ``rtol`` (relative to ``max(1, |s|)``).

    :func:`detect_period` on ``[s, P^d(s)]`` (e.g. 1 when a period-2 search landed on a fixed
    point of ``P``).
    """
    s = np.asarray(s, float)
    scale = np.array([max(1.0, float(np.max(np.abs(s))))])
    for d in range(1, k):   # bounded: the divisors of k
        if k % d == 0:
            img, ok = P.apply_many(s[None, :], d)
            if ok[0] and detect_period(np.stack([s, img[0]]), P.wrap, 1, rtol,
                                       scale=scale)[0] == 1:
                return d
    return k
