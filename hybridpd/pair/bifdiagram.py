"""Brute-force bifurcation diagrams of the impact map.

For every value of one parameter the impact map ``P`` (:class:`~hybridpd.pair.impactmap.ImpactMap`)
is iterated ``iterations`` times from one initial condition (or, *following*, from the final
state reached at the previous value) and the last ``keep`` section points are recorded, as in
the bifurcation diagrams of the impact-oscillator literature. Each value is classified
(:data:`CLASSES`):

``periodic``
    the kept iterates repeat with a period ``k <= max_period`` (``|s_i - s_{i-k}|`` below
    ``period_tol`` relative to ``max(1, |s|)`` over the whole kept window, phase differences
    taken modulo ``T``); the smallest such ``k`` is reported, and the ``k`` section points of
    the cycle by :meth:`BifurcationDiagram.cycle`;
``chaotic``
    not periodic and the largest Lyapunov exponent exceeds ``chaos_tol``;
``quasiperiodic``
    not periodic, exponent ``<= chaos_tol`` (quasi-periodic, a period above ``max_period``,
    or a transient slower than the window);
``diverged``
    the trajectory left ``|z1|, |z2|, |z4| <= escape`` or became non-finite;
``sticking``
    the masses stay stuck on a wall for 50 periods (impacts accumulated; the engine's Zeno
    status); sticking *phases* that end are part of ordinary iterates;
``no_impact``
    no further contact within 50 periods (the motion settled inside the clearance);
``unresolved``
    an iteration bound inside one flight was hit;
``undefined``
    no map at this value (on the design path: no reference amplitude ``xm``).

The largest Lyapunov exponent of the map (per application of ``P``) is the mean of
``log |R_ii|`` along the kept iterates, with ``Q_{i+1} R_{i+1} = DP(s_i) Q_i`` (QR
re-orthonormalisation; the first quarter of the window aligns ``Q`` and is not averaged).
``DP`` is by central finite differences of the simulated map, all iterates at once in one
call of the compiled engine (:func:`hybridpd.pair.batch.impact_map`), one-sided where a side
is undefined. On a period-``k`` orbit the exponent tends to ``log rho(DP^k) / k``.

Parameter path: with ``xm`` None (default), the *design path*: at every value the reference
amplitude is the one that realises the primary-mass amplitude ``x10`` on the order-``n``
symmetric orbit (paper (20); the path of
:func:`~hybridpd.pair.continuation.continue_symmetric`); with ``xm`` given, ``xm`` is
fixed. ``gamma`` means ``L / x10`` (CONVENTIONS.md).
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

import numpy as np

from hybridpd._jit import njit
from hybridpd._results import compact_repr
from hybridpd.model import Case, ImpactPair, PDGains, Reference, check_finite
from hybridpd.pair.batch import impact_map, iterate_map
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.orbits import symmetric_orbits

__all__ = ["CLASSES", "COORDINATES", "DIAGRAM_PARAMETERS", "BifurcationDiagram",
           "bifurcation_diagram", "load_diagram", "section_coordinate"]

#: Classes of a parameter value (index = the integer code in ``BifurcationDiagram.code``).
CLASSES = ("periodic", "quasiperiodic", "chaotic", "diverged", "sticking", "no_impact",
           "unresolved", "undefined")
#: Parameters a diagram can sweep.
DIAGRAM_PARAMETERS = ("kp", "kv", "e", "mu", "gamma", "omega", "m2", "xm")
#: Section coordinates by name (``phi, z1, z2, z4`` and the physical ``x1, y1, x2, y2``).
COORDINATES = ("phi", "z1", "z2", "z4", "x1", "y1", "x2", "y2")

_STATUS_CLASS = {11: "no_impact", 12: "sticking", 13: "unresolved", 14: "diverged"}


def section_coordinate(points, name: str, L: float) -> np.ndarray:
    """A named coordinate of section points ``(..., 4) = (phi, z1, z2, z4)``.

    ``x1 = z1 + L`` (pre-impact at ``z3 = +L``), ``y1 = z2 + z4``, ``x2 = z1``, ``y2 = z2``.
    """
    P = np.asarray(points, float)
    if name not in COORDINATES:
        raise ValueError(f"coordinate must be one of {COORDINATES}, got {name!r}")
    i = {"phi": 0, "z1": 1, "z2": 2, "z4": 3, "x2": 1, "y2": 2}.get(name)
    if i is not None:
        return P[..., i]
    if name == "x1":
        return P[..., 1] + L
    return P[..., 2] + P[..., 3]


@dataclass(frozen=True)
class BifurcationDiagram:
    """A brute-force bifurcation diagram (see the module docstring).

    Attributes
    ----------
    parameter_name : str
        The swept parameter (one of :data:`DIAGRAM_PARAMETERS`).
    values : ndarray, shape (M,)
        Parameter values, in sweep order.
    points : ndarray, shape (M, keep, 4)
        The last ``keep`` section points ``(phi, z1, z2, z4)`` of each value (``phi`` in
        ``[0, T)``); NaN rows where the trajectory stopped earlier.
    code : ndarray of int, shape (M,)
        Class of each value, an index into :data:`CLASSES`.
    period : ndarray of int, shape (M,)
        Detected period ``k`` (applications of ``P``), 0 unless periodic.
    lyapunov : ndarray, shape (M,)
        Largest Lyapunov exponent per application of ``P`` (NaN where not computed).
    lyapunov_spectrum : ndarray, shape (M, 4)
        All four exponents from the same QR product, decreasing.
    xm : ndarray, shape (M,)
        Reference amplitude used at each value (length).
    L : ndarray, shape (M,)
        Half clearance at each value (length; varies when sweeping ``gamma``).
    final : ndarray, shape (M, 4)
        Last defined section point of each value (the start of the next one when following).
    status : ndarray of int, shape (M,)
        Engine status of the run (0, or ``10 + batch.STATUS_*`` of the failed flight).
    iterations, keep : int
        ``M`` iterations of ``P`` per value, of which the last ``keep`` are recorded.
    follow : bool
        Each value started from the previous value's final state.
    initial : ndarray, shape (4,)
        The initial condition (of the first value, or of every value without following).
    case : str
    fixed : dict
        The other parameters (``kp, kv, e, mu, L, m2, omega`` and ``x10, n`` on the design
        path, or ``xm`` when fixed).
    design : bool
        ``xm`` followed the design path (``x10, n`` in ``fixed``).
    settings : dict
        ``max_period, period_tol, chaos_tol, escape, fd_step``.
    """

    parameter_name: str
    values: np.ndarray
    points: np.ndarray
    code: np.ndarray
    period: np.ndarray
    lyapunov: np.ndarray
    lyapunov_spectrum: np.ndarray
    xm: np.ndarray
    L: np.ndarray
    final: np.ndarray
    status: np.ndarray
    iterations: int
    keep: int
    follow: bool
    initial: np.ndarray
    case: str
    fixed: dict
    design: bool
    settings: dict = field(default_factory=dict)
    __repr__ = compact_repr

    def __len__(self) -> int:
        return int(self.values.size)

    @property
    def classification(self) -> list:
        """Class names, one per value (list of str)."""
        return [CLASSES[c] for c in self.code]

    def cycle(self, i: int) -> np.ndarray:
        """The ``k`` section points of the cycle at value ``i`` (shape (k, 4)), sorted by
        phase; empty unless periodic."""
        k = int(self.period[i])
        if k == 0:
            return np.zeros((0, 4))
        c = self.points[i, -k:]
        return c[np.argsort(c[:, 0])]

    def coordinate(self, name: str) -> np.ndarray:
        """A named section coordinate of :attr:`points`, shape (M, keep)."""
        return section_coordinate(self.points, name, self.L[:, None])

    def counts(self) -> dict:
        """Number of values per class."""
        return {c: int(np.sum(self.code == j)) for j, c in enumerate(CLASSES)}

    def to_dict(self) -> dict:
        """JSON-ready summary (points included, NaN as None)."""
        def lst(a):
            return [None if not np.isfinite(v) else float(v) for v in np.ravel(a)]
        return {
            "parameter": self.parameter_name, "values": lst(self.values),
            "classification": [CLASSES[c] for c in self.code],
            "period": [int(p) for p in self.period], "lyapunov": lst(self.lyapunov),
            "xm": lst(self.xm), "L": lst(self.L),
            "points": [[lst(row) for row in pts] for pts in self.points],
            "status": [int(s) for s in self.status], "iterations": self.iterations,
            "keep": self.keep, "follow": self.follow, "initial": lst(self.initial),
            "case": self.case, "fixed": dict(self.fixed), "design": self.design,
            "settings": dict(self.settings), "counts": self.counts()}

    def save(self, path) -> None:
        """Write to ``.npz`` (arrays, and the metadata as JSON)."""
        meta = {"parameter_name": self.parameter_name, "iterations": self.iterations,
                "keep": self.keep, "follow": self.follow, "case": self.case,
                "fixed": self.fixed, "design": self.design, "settings": self.settings,
                "classes": list(CLASSES)}
        np.savez_compressed(
            path, values=self.values, points=self.points, code=self.code, period=self.period,
            lyapunov=self.lyapunov, lyapunov_spectrum=self.lyapunov_spectrum, xm=self.xm,
            L=self.L, final=self.final, status=self.status, initial=self.initial,
            meta=np.array(json.dumps(meta)))


def load_diagram(path) -> BifurcationDiagram:
    """Read a diagram written by :meth:`BifurcationDiagram.save`."""
    with np.load(path, allow_pickle=False) as z:
        meta = json.loads(str(z["meta"]))
        if tuple(meta.get("classes", ())) != CLASSES:
            raise ValueError(f"{path}: unknown class table {meta.get('classes')}")
        arrays = {k: z[k] for k in ("values", "points", "code", "period", "lyapunov",
                                    "lyapunov_spectrum", "xm", "L", "final", "status",
                                    "initial")}
    return BifurcationDiagram(parameter_name=meta["parameter_name"],
                              iterations=int(meta["iterations"]), keep=int(meta["keep"]),
                              follow=bool(meta["follow"]), case=meta["case"],
                              fixed=meta["fixed"], design=bool(meta["design"]),
                              settings=meta["settings"], **arrays)


# ----------------------------------------------------------------------------------------
# Computation
# ----------------------------------------------------------------------------------------


def _wrap(d, T):
    return (d + 0.5 * T) % T - 0.5 * T


def _period(X, T, max_period, tol):
    """Smallest ``k`` with ``X[i] = X[i-k]`` over the window (0 if none)."""
    n = X.shape[0]
    scale = max(1.0, float(np.max(np.abs(X[:, 1:]))))
    for k in range(1, min(max_period, n // 2) + 1):
        d = X[k:] - X[:-k]
        d[:, 0] = _wrap(d[:, 0], T)
        if float(np.max(np.abs(d))) <= tol * scale:
            return k
    return 0


def _jacobians(P: ImpactMap, X, Y, fd_step):
    """``DP`` at the rows of ``X`` (N, 4) with ``P(X) = Y``, by batched central differences."""
    N = X.shape[0]
    H = fd_step * np.maximum(1.0, np.abs(X))
    H[:, 3] = np.minimum(H[:, 3], 0.5 * X[:, 3])
    E = np.eye(4)
    S = np.concatenate([X[:, None, :] + H[:, None, :] * E, X[:, None, :] - H[:, None, :] * E],
                       axis=1).reshape(-1, 4)
    out, st, _ = impact_map(P.params, P._c, np.ascontiguousarray(S), P.tol, P.max_impacts)
    out = out.reshape(N, 2, 4, 4)
    ok = (st == 0).reshape(N, 2, 4)
    T = P.period
    plus, minus = out[:, 0], out[:, 1]
    J = np.full((N, 4, 4), np.nan)
    for j in range(4):
        h = H[:, j][:, None]
        both = ok[:, 0, j] & ok[:, 1, j]
        d = np.where(both[:, None], plus[:, j] - minus[:, j], np.nan)
        hh = np.where(both[:, None], 2 * h, np.nan)
        only_p = ok[:, 0, j] & ~ok[:, 1, j]
        only_m = ~ok[:, 0, j] & ok[:, 1, j]
        d = np.where(only_p[:, None], plus[:, j] - Y, d)
        d = np.where(only_m[:, None], Y - minus[:, j], d)
        hh = np.where((only_p | only_m)[:, None], h, hh)
        d[:, 0] = _wrap(d[:, 0], T)
        with np.errstate(invalid="ignore"):
            J[:, :, j] = d / hh         # NaN where both sides are undefined
    return J


def _lyapunov(J):
    """Exponents (decreasing) of the product of the ``J`` (N, 4, 4) by QR; the first quarter
    only aligns ``Q``."""
    if not np.all(np.isfinite(J)):
        return np.full(4, np.nan)
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


def _check_values(name, values):
    v = np.asarray(values, dtype=float).reshape(-1)
    if v.size < 2:
        raise ValueError(f"values must hold at least 2 parameter values, got {v.size}")
    if not np.all(np.isfinite(v)):
        raise ValueError("values must be finite")
    lo = 0.0
    if name == "e":
        if np.any(v < 0) or np.any(v > 1):
            raise ValueError(f"e must lie in [0, 1], got values in [{v.min():g}, {v.max():g}]")
    elif np.any(v <= lo) and name != "xm":
        raise ValueError(f"{name} must be > 0, got values down to {v.min():g}")
    elif name == "xm" and np.any(v < 0):
        raise ValueError(f"xm must be >= 0, got values down to {v.min():g}")
    return v


def _setup(pair, gains, omega, name, v, x10, n, xm, case):
    """Per value: (ImpactPair, PDGains, omega) and the reference amplitude."""
    M = v.size
    cols = {"kp": np.full(M, gains.kp), "kv": np.full(M, gains.kv), "e": np.full(M, pair.e),
            "mu": np.full(M, pair.mu), "m2": np.full(M, pair.m2), "L": np.full(M, pair.L),
            "omega": np.full(M, float(omega))}
    if name == "gamma":
        cols["L"] = v * x10
    elif name != "xm":
        cols[name] = v.copy()
    if xm is None:
        r = symmetric_orbits(cols["kp"], cols["kv"], mu=cols["mu"], e=cols["e"], L=cols["L"],
                             omega=cols["omega"], m2=cols["m2"], x10=x10, n=n, case=case,
                             margin=False, jacobian=False)
        xms = np.asarray(r.xm, float).reshape(M)
        xms = np.where(np.isfinite(xms) & (xms > 0), xms, np.nan)
    else:
        xms = v.copy() if name == "xm" else np.full(M, float(xm))
    return cols, xms


def bifurcation_diagram(pair: ImpactPair, gains, omega: float, parameter: str, values, *,
                        case="collocated", x10: float = 1.0, n: int = 1,
                        xm: float | None = None, iterations: int = 1000, keep: int = 100,
                        follow: bool = False, initial=None, max_period: int = 32,
                        period_tol: float = 1e-8, chaos_tol: float = 1e-3,
                        escape: float = 1e3, lyapunov: bool = True, fd_step: float = 1e-6,
                        tol: float = 1e-13, max_impacts: int = 1000) -> BifurcationDiagram:
    """Brute-force bifurcation diagram of the impact map in one parameter.

    Parameters
    ----------
    pair : ImpactPair
        ``mu, e, L, m2`` (the swept one is replaced by the values).
    gains : PDGains or (kp, kv)
    omega : float
        Reference frequency (rad/time).
    parameter : str
        One of :data:`DIAGRAM_PARAMETERS` (``gamma = L / x10`` with ``x10`` fixed; ``xm``
        only with a fixed ``xm``).
    values : array_like, shape (M,)
        Parameter values in sweep order (at least 2), e.g. ``np.linspace(a, b, num)``.
    case : {"collocated", "noncollocated"}
    x10, n : float, int
        Primary-mass amplitude (length) and odd order of the design orbit.
    xm : float, optional
        Fixed reference amplitude; default None: ``xm`` follows the design at every value.
    iterations, keep : int
        Iterations of ``P`` per value and how many of the last ones are recorded
        (``1 <= keep <= iterations``; at least 8 for the classification).
    follow : bool
        Start each value from the final state of the previous one (when it is defined).
    initial : array_like, shape (4,), optional
        Initial section point ``(phi, z1, z2, z4)`` (``z4 > 0``). Default: the closed-form
        symmetric fixed point at the first value, displaced by ``1e-3`` in ``z1``.
    max_period : int
        Largest period detected.
    period_tol : float
        Relative tolerance of the period test.
    chaos_tol : float
        Exponent (per iterate) above which a non-periodic value counts as chaotic.
    escape : float
        Bound on ``|z1|, |z2|, |z4|`` (diverged beyond).
    lyapunov : bool
        Estimate the Lyapunov exponents (``keep`` Jacobians per value).
    fd_step : float
        Relative finite-difference step of the Jacobians.
    tol, max_impacts : float, int
        Contact tolerance and impact bound per application of ``P`` (see ImpactMap).

    Returns
    -------
    BifurcationDiagram

    Raises
    ------
    ValueError
        Unknown parameter, bad values, ``keep > iterations``, or a bad initial point.

    Examples
    --------
    Collocated, ``e = 0.5``, ``kp = 10``: the symmetric orbit attracts for these ``kv``:

    >>> import numpy as np
    >>> from hybridpd import ImpactPair, PDGains
    >>> d = bifurcation_diagram(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0, "kv",
    ...                         np.linspace(18, 20, 3), iterations=300, keep=40)
    >>> list(d.classification), [int(k) for k in d.period]
    (['periodic', 'periodic', 'periodic'], [1, 1, 1])
    >>> bool(np.all(d.lyapunov < 0))
    True
    """
    if not isinstance(pair, ImpactPair):
        raise ValueError(f"pair must be an ImpactPair, got {type(pair).__name__}")
    if not isinstance(gains, PDGains):
        gains = PDGains(*gains)
    omega = check_finite("omega", omega)
    if omega <= 0:
        raise ValueError(f"omega must be > 0, got {omega!r}")
    case = Case.parse(case)
    if not isinstance(parameter, str) or parameter not in DIAGRAM_PARAMETERS:
        raise ValueError(f"parameter must be one of {DIAGRAM_PARAMETERS}, got {parameter!r}")
    name = parameter
    if name == "xm" and xm is None:
        raise ValueError("parameter 'xm' needs a fixed-xm diagram (give xm=...); on the "
                         "design path xm follows x10")
    v = _check_values(name, values)
    x10 = check_finite("x10", x10)
    if x10 <= 0:
        raise ValueError(f"x10 must be > 0, got {x10!r}")
    if int(n) != n or n < 1 or n % 2 == 0:
        raise ValueError(f"n must be a positive odd integer, got {n!r}")
    if xm is not None:
        xm = check_finite("xm", xm)
        if xm < 0:
            raise ValueError(f"xm must be >= 0, got {xm!r}")
    iterations, keep, max_period = _ints(iterations=iterations, keep=keep,
                                         max_period=max_period)
    if keep > iterations:
        raise ValueError(f"keep = {keep} must not exceed iterations = {iterations}")
    if keep < 8:
        raise ValueError(f"keep must be >= 8 (period and exponent estimates), got {keep}")
    for nm, val in (("period_tol", period_tol), ("escape", escape), ("fd_step", fd_step),
                    ("tol", tol)):
        if not (math.isfinite(val) and val > 0):
            raise ValueError(f"{nm} must be > 0, got {val!r}")
    chaos_tol = check_finite("chaos_tol", chaos_tol)
    cols, xms = _setup(pair, gains, omega, name, v, x10, int(n), xm, case)
    s_init = _initial(initial, cols, x10, int(n), case)
    M = v.size
    pts = np.full((M, keep, 4), np.nan)
    code = np.full(M, CLASSES.index("undefined"), dtype=np.int64)
    per = np.zeros(M, dtype=np.int64)
    lyap = np.full((M, 4), np.nan)
    final = np.full((M, 4), np.nan)
    status = np.zeros(M, dtype=np.int64)
    cur = s_init.copy()
    for i in range(M):
        if not np.isfinite(xms[i]):
            continue
        P = ImpactMap(ImpactPair(cols["mu"][i], cols["e"][i], cols["L"][i], cols["m2"][i]),
                      PDGains(cols["kp"][i], cols["kv"][i]),
                      Reference(xms[i], cols["omega"][i]), case, tol=tol,
                      max_impacts=max_impacts)
        start = cur if follow else s_init
        orbit, done, st = iterate_map(P.params, P._c, np.ascontiguousarray(start, float),
                                      iterations, tol, max_impacts)
        status[i] = st
        last = orbit[done]
        final[i] = last
        pts[i] = orbit[iterations + 1 - keep:]
        code[i], per[i], lyap[i] = _classify(P, orbit, st, keep, iterations, escape, max_period,
                                             period_tol, chaos_tol, lyapunov, fd_step)
        if follow and np.all(np.isfinite(last)) and last[3] > 0 and st == 0 \
                and CLASSES[code[i]] != "diverged":
            cur = last.copy()
    fixed = {k: float(c[0]) for k, c in cols.items() if k != name and not
             (name == "gamma" and k == "L")}
    if xm is None:
        fixed.update({"x10": float(x10), "n": int(n)})
    else:
        fixed["xm"] = float(xm)
    fixed.pop(name, None)
    return BifurcationDiagram(
        parameter_name=name, values=v, points=pts, code=code, period=per,
        lyapunov=lyap[:, 0], lyapunov_spectrum=lyap, xm=xms, L=cols["L"].copy(),
        final=final, status=status, iterations=iterations, keep=keep, follow=bool(follow),
        initial=s_init, case=case.value, fixed=fixed, design=xm is None,
        settings={"max_period": max_period, "period_tol": float(period_tol),
                  "chaos_tol": float(chaos_tol), "escape": float(escape),
                  "fd_step": float(fd_step)})


def _ints(**kw):
    out = []
    for nm, val in kw.items():
        try:
            iv = int(val)
        except (TypeError, ValueError):
            raise ValueError(f"{nm} must be a positive integer, got {val!r}") from None
        if iv != val or iv < 1:
            raise ValueError(f"{nm} must be a positive integer, got {val!r}")
        out.append(iv)
    return out


def _initial(initial, cols, x10, n, case):
    if initial is not None:
        s = np.asarray(initial, float)
        if s.shape != (4,) or not np.all(np.isfinite(s)) or s[3] <= 0:
            raise ValueError("initial must be 4 finite numbers (phi, z1, z2, z4) with z4 > 0, "
                             f"got {initial!r}")
        return s
    r = symmetric_orbits(cols["kp"][0], cols["kv"][0], mu=cols["mu"][0], e=cols["e"][0],
                         L=cols["L"][0], omega=cols["omega"][0], m2=cols["m2"][0], x10=x10,
                         n=n, case=case, margin=False, jacobian=False)
    s = np.asarray(r.fixed_point, float).reshape(4) + np.array([0.0, 1e-3, 0.0, 0.0])
    if not (np.all(np.isfinite(s)) and s[3] > 0):
        raise ValueError("no symmetric fixed point at the first value to start from: give "
                         "initial=(phi, z1, z2, z4)")
    return s


def _classify(P, orbit, st, keep, iterations, escape, max_period, period_tol, chaos_tol,
              lyapunov, fd_step):
    """(class code, period, exponents) of one run."""
    nan4 = np.full(4, np.nan)
    if st != 0:
        return CLASSES.index(_STATUS_CLASS.get(int(st), "diverged")), 0, nan4
    X = orbit[iterations + 1 - keep:]
    if not np.all(np.isfinite(X)) or np.any(np.abs(X[:, 1:]) > escape):
        return CLASSES.index("diverged"), 0, nan4
    k = _period(X, P.period, max_period, period_tol)
    ex = nan4
    if lyapunov:
        # DP at each kept iterate but the last; its image is the next kept iterate
        ex = _lyapunov(_jacobians(P, X[:-1], X[1:], fd_step))
    if k:
        return CLASSES.index("periodic"), k, ex
    if np.isfinite(ex[0]) and ex[0] > chaos_tol:
        return CLASSES.index("chaotic"), 0, ex
    return CLASSES.index("quasiperiodic"), 0, ex
