"""Brute-force bifurcation diagrams of any map in one parameter.

For every value of a parameter the map ``P`` built for it is iterated from one initial point
(or, *following*, from the final point reached at the previous value) and the last ``keep``
points are recorded, as in the bifurcation diagrams of the impact-oscillator literature. Each
value is classified (:data:`CLASSES`):

``periodic``
    the kept iterates repeat with a period ``k <= max_period`` (:func:`detect_period`); the
    smallest such ``k`` is reported;
``chaotic``
    not periodic, and the largest Lyapunov exponent exceeds ``chaos_tol``;
``quasiperiodic``
    not periodic and not chaotic (quasi-periodic, a period above ``max_period``, or a
    transient slower than the window; without exponents every non-periodic value);
``diverged``
    a coordinate left ``|s_i| <= escape`` or became non-finite;
``undefined``
    the map stopped (its status is kept in ``status``: e.g. a hybrid map's ``end_time``, the
    pair's ``sticking``), or no map could be built at this value.

The largest Lyapunov exponent (per application of ``P^k``) is the mean of ``log |R_ii|``
along the kept iterates, ``Q_{i+1} R_{i+1} = DP(s_i) Q_i`` (QR re-orthonormalisation; the
first quarter of the window only aligns ``Q``). ``DP`` is the map's own where it gives one,
else central differences; a map may compute all of them at once
(:meth:`~hybridpd.analysis.maps.PoincareMap.jacobians`). On a period-``k`` orbit the
exponent tends to ``log rho(DP^k) / k``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hybridpd._jit import njit
from hybridpd._results import compact_repr
from hybridpd.analysis.maps import PoincareMap, check_returns, detect_period

__all__ = ["CLASSES", "BifurcationDiagram", "bifurcation_diagram", "lyapunov_exponents"]

#: Classes of a parameter value (index = the integer code in ``BifurcationDiagram.code``).
CLASSES = ("periodic", "quasiperiodic", "chaotic", "diverged", "undefined")


@dataclass(frozen=True, eq=False)
class BifurcationDiagram:
    """A brute-force bifurcation diagram (module docstring).

    Attributes
    ----------
    parameter_name : str
        The swept parameter.
    values : ndarray, shape (M,)
        Parameter values, in sweep order.
    points : ndarray, shape (M, keep, dim)
        The last ``keep`` points of each value (NaN where the map stopped).
    code : ndarray of int, shape (M,)
        Index into :data:`CLASSES`.
    periods : ndarray of int, shape (M,)
        The detected period (applications of ``P^k``), 0 unless periodic.
    status : tuple of str
        Why the map stopped at each value (``""`` where it did not).
    lyapunov : ndarray, shape (M,)
        Largest Lyapunov exponent per application of ``P^k`` (NaN where not estimated).
    names : tuple of str
        Coordinate names.
    metadata : dict
        Settings (``iterations``, ``keep``, ``period``, ``follow``, ...).

    Examples
    --------
    The logistic map ``x -> r x (1 - x)`` doubles its period at ``r = 3``:

    >>> import hybridpd as hp
    >>> class Logistic(hp.PoincareMap):
    ...     names = ("x",)
    ...     def __init__(self, r):
    ...         self.r = r
    ...     def apply(self, s, k=1, jacobian=False):
    ...         x = s[0]
    ...         for _ in range(k):
    ...             x = self.r * x * (1 - x)
    ...         return hp.MapResult(np.array([x]))
    >>> d = hp.bifurcation_diagram(Logistic, [2.8, 3.2, 3.5], s0=[0.3])
    >>> d.periods.tolist(), d.classification
    ([1, 2, 4], ['periodic', 'periodic', 'periodic'])
    """

    parameter_name: str
    values: np.ndarray
    points: np.ndarray = field(repr=False)
    code: np.ndarray
    periods: np.ndarray
    status: tuple = field(repr=False, default=())
    lyapunov: np.ndarray | None = field(repr=False, default=None)
    names: tuple = ()
    metadata: dict = field(default_factory=dict, repr=False)
    __repr__ = compact_repr

    def __len__(self) -> int:
        return len(self.values)

    @property
    def classification(self) -> list:
        """Class name of every value."""
        return [CLASSES[int(c)] for c in self.code]

    def counts(self) -> dict:
        """``{class: number of values}``."""
        return {c: int(np.sum(self.code == i)) for i, c in enumerate(CLASSES)}

    def cycle(self, i: int) -> np.ndarray:
        """The ``k`` points of the cycle of periodic value ``i`` (shape ``(k, dim)``)."""
        k = int(self.periods[i])
        if k < 1:
            raise ValueError(f"value {i} is not periodic ({self.classification[i]})")
        return self.points[i, -k:]


def lyapunov_exponents(J) -> np.ndarray:
    """Exponents (decreasing) of the product of the Jacobians ``J`` (shape ``(N, d, d)``) by QR
    re-orthonormalisation; the first quarter only aligns ``Q`` (NaN if any ``J`` is not
    finite).

    Examples
    --------
    >>> lyapunov_exponents(np.tile(np.diag([2.0, 0.5]), (40, 1, 1))).round(12)
    array([ 0.69314718, -0.69314718])
    """
    J = np.asarray(J, float)
    if not np.all(np.isfinite(J)):
        return np.full(J.shape[-1], np.nan)
    return np.sort(_qr_exponents(np.ascontiguousarray(J), J.shape[0] // 4))[::-1]


@njit(cache=True)
def _qr_exponents(J, warm):
    """Mean ``log |R_aa|`` of ``Q_{i+1} R_{i+1} = J_i Q_i`` over ``i >= warm`` (modified
    Gram-Schmidt; a column that vanishes, e.g. from a zero multiplier, is replaced by a unit
    vector orthogonal to the previous ones and contributes ``log 1e-300``)."""
    N, n = J.shape[0], J.shape[1]
    Q = np.eye(n)
    acc = np.zeros(n)
    Z = np.empty((n, n))
    Qn = np.empty((n, n))
    v = np.empty(n)
    for i in range(N):
        for r in range(n):
            for c in range(n):
                s = 0.0
                for m in range(n):
                    s += J[i, r, m] * Q[m, c]
                Z[r, c] = s
        for a in range(n):
            for attempt in range(2):
                for r in range(n):
                    v[r] = Z[r, a] if attempt == 0 else (1.0 if r == a else 0.0)
                for b in range(a):
                    d = 0.0
                    for r in range(n):
                        d += Qn[r, b] * v[r]
                    for r in range(n):
                        v[r] -= d * Qn[r, b]
                nv = 0.0
                for r in range(n):
                    nv += v[r] * v[r]
                nv = math.sqrt(nv)
                if attempt == 0 and i >= warm:
                    acc[a] += math.log(max(nv, 1e-300))
                if nv > 1e-300:
                    break
            for r in range(n):
                Qn[r, a] = v[r] / nv
        for r in range(n):
            for c in range(n):
                Q[r, c] = Qn[r, c]
    return acc / max(N - warm, 1)


def _start(s0, P, value):
    """The initial point at ``value``: ``s0(P, value)`` if callable, else ``s0``."""
    return np.asarray(s0(P, value) if callable(s0) else s0, float)


def _classify(P, tail, period, max_period, period_tol, chaos_tol, escape, lyapunov):
    """``(code, period, exponent)`` of a finite window of iterates."""
    if np.any(np.abs(tail[:, 1:] if P.period is not None else tail) > escape):
        return CLASSES.index("diverged"), 0, math.nan
    k = detect_period(tail, P.wrap, max_period, period_tol)
    if k:
        return CLASSES.index("periodic"), k, math.nan
    if not lyapunov:
        return CLASSES.index("quasiperiodic"), 0, math.nan
    try:
        lam = float(lyapunov_exponents(P.jacobians(tail[:-1], period))[0])
    except RuntimeError:
        lam = math.nan
    chaotic = np.isfinite(lam) and lam > chaos_tol
    return CLASSES.index("chaotic" if chaotic else "quasiperiodic"), 0, lam


def bifurcation_diagram(builder, values, *, s0, period: int = 1, iterations: int = 1000,
                        keep: int = 64, follow: bool = True, max_period: int = 16,
                        period_tol: float = 1e-6, chaos_tol: float = 1e-3,
                        escape: float = 1e6, lyapunov: bool = False,
                        parameter: str = "p") -> BifurcationDiagram:
    """Brute-force bifurcation diagram of a family of maps (module docstring).

    Parameters
    ----------
    builder : callable
        ``value -> PoincareMap`` (a map class whose constructor takes the parameter first is
        one).
    values : array_like, shape (M,)
        Parameter values in sweep order (at least 2).
    s0 : array_like, shape (dim,), or callable
        Initial point, or ``s0(P, value) -> point`` (e.g. from a simulation of a model).
    period : int
        ``k``: the diagram iterates ``P^k``.
    iterations, keep : int
        Iterations per value and how many of the last ones are recorded
        (``8 <= keep <= iterations``).
    follow : bool
        Start each value from the final point of the previous one (when it is finite).
    max_period : int
        Largest period detected (``<= keep // 2``).
    period_tol : float
        Relative tolerance of the period test.
    chaos_tol : float
        Exponent (per iterate) above which a non-periodic value counts as chaotic.
    escape : float
        Bound on the coordinates (the phase excepted); diverged beyond.
    lyapunov : bool
        Estimate the largest Lyapunov exponent of the non-periodic values.
    parameter : str
        Name of the parameter (for the result).

    Returns
    -------
    BifurcationDiagram

    Raises
    ------
    ValueError
        Bad values or settings, or a builder that does not return a map.

    Examples
    --------
    The Hénon map's fixed point doubles at ``a = 3 (1 - b)^2 / 4 = 0.3675`` (``b = 0.3``):

    >>> import hybridpd as hp
    >>> class Henon(hp.PoincareMap):
    ...     names = ("x", "y")
    ...     def __init__(self, a):
    ...         self.a = a
    ...     def apply(self, s, k=1, jacobian=False):
    ...         x, y = s
    ...         for _ in range(k):
    ...             x, y = 1 - self.a * x * x + y, 0.3 * x
    ...         return hp.MapResult(np.array([x, y]))
    >>> d = hp.bifurcation_diagram(Henon, [0.3, 0.5, 0.95], s0=[0.1, 0.1], parameter="a")
    >>> d.periods.tolist()
    [1, 2, 4]
    """
    v = np.asarray(values, float).reshape(-1)
    if v.size < 2 or not np.all(np.isfinite(v)):
        raise ValueError(f"values must be at least 2 finite numbers, got {values!r}")
    if not callable(builder):
        raise ValueError(f"builder must be a callable value -> PoincareMap, got "
                         f"{type(builder).__name__}")
    k = check_returns(period)
    iterations, keep, max_period = int(iterations), int(keep), int(max_period)
    if not 8 <= keep <= iterations:
        raise ValueError(f"keep must be in [8, iterations = {iterations}], got {keep}")
    if not 1 <= max_period <= keep // 2:
        raise ValueError(f"max_period must be in [1, keep // 2 = {keep // 2}], got "
                         f"{max_period}")
    pts = code = per = lam = None
    status, last, names = [], None, ()
    for i, value in enumerate(v):
        try:
            P = builder(float(value))
        except ValueError as exc:            # no map at this value
            status.append(f"no map: {exc}")
            continue
        if not isinstance(P, PoincareMap):
            raise ValueError(f"builder must return a PoincareMap, got {type(P).__name__}")
        if pts is None:
            names = P.names
            pts = np.full((v.size, keep, P.dim), np.nan)
            code = np.full(v.size, CLASSES.index("undefined"), np.int64)
            per, lam = np.zeros(v.size, np.int64), np.full(v.size, np.nan)
            code[:i] = CLASSES.index("undefined")
        start = last if follow and last is not None else _start(s0, P, value)
        it, why = P.iterate_status(start, iterations, k)
        pts[i] = it[-keep:]
        status.append(why)
        tail = it[-keep:]
        if why:
            code[i] = CLASSES.index("diverged" if why in ("nonfinite", "diverged")
                                    else "undefined")
            last = None
            continue
        last = tail[-1].copy()
        code[i], per[i], lam[i] = _classify(P, tail, k, max_period, period_tol, chaos_tol,
                                            escape, lyapunov)
        if code[i] == CLASSES.index("diverged"):
            last = None
    if pts is None:
        raise ValueError("the builder built no map at any value: " + "; ".join(status))
    meta = {"iterations": iterations, "keep": keep, "period": k, "follow": bool(follow),
            "max_period": max_period, "period_tol": float(period_tol)}
    return BifurcationDiagram(str(parameter), v, pts, code, per, tuple(status), lam, names,
                              meta)
