"""Brute-force bifurcation diagrams of any family of maps in one parameter.

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
    a coordinate left ``|s_i| <= escape`` (the phase excepted) or became non-finite;
``sticking``, ``no_impact``, ``unresolved``
    the map stopped with a status its ``status_classes`` hook (a dict ``{status: class}``)
    maps to these classes (the impact pair's engine: stuck on a wall for good, no further
    contact, an iteration bound inside one flight);
``undefined``
    the map stopped for another reason (its status is kept in ``status``), or no map could
    be built at this value.

The largest Lyapunov exponent (per application of ``P^k``) is the mean of ``log |R_ii|``
along the kept iterates, ``Q_{i+1} R_{i+1} = DP(s_i) Q_i`` (QR re-orthonormalisation; the
first quarter of the window only aligns ``Q``); ``DP`` at all kept iterates comes from one
call of the map's :meth:`~hybridpd.analysis.maps.PoincareMap.jacobians` (a map may batch
them). On a period-``k`` orbit the exponent tends to ``log rho(DP^k) / k``.

A *family* is any callable ``value -> PoincareMap`` (or ``-> (PoincareMap, start point)``,
e.g. a start from a simulation of a model). It may offer hooks, each optional:
``parameter`` (its name), ``prepare(values) -> family`` (precompute over all values at once),
``variables(values) -> {name: (M,) array}`` (recorded per value; may raise ``ValueError`` for
values outside the family), ``initial(values) -> point`` (the start when ``s0`` is not given),
``metadata`` (a dict recorded with the diagram) and ``project(P, points) -> points`` (the
recorded coordinates of a map's points, when maps of different values use different charts).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hybridpd._jit import njit
from hybridpd._results import (
    Result,
    WithExtras,
    compact_repr,
    decode_attrs,
    encode_attrs,
)
from hybridpd.analysis.maps import MapResult, PoincareMap, check_returns, detect_period

__all__ = ["ANSWERS", "CLASSES", "BifurcationDiagram", "StoppedMap", "bifurcation_diagram",
           "load_diagram", "lyapunov_exponents"]

#: Classes of a parameter value (index = the integer code in ``BifurcationDiagram.code``).
CLASSES = ("periodic", "quasiperiodic", "chaotic", "diverged", "sticking", "no_impact",
           "unresolved", "undefined")
#: The classes that say what the motion does at a value (the others say that the map could not
#: tell: it diverged, stopped inside a flight or was undefined).
ANSWERS = ("periodic", "quasiperiodic", "chaotic", "sticking", "no_impact")


@dataclass(frozen=True, eq=False)
class BifurcationDiagram(WithExtras, Result):
    """A brute-force bifurcation diagram of any family of maps (module docstring).

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
    spectrum : ndarray, shape (M, dim)
        Lyapunov exponents per application of ``P^k``, decreasing (NaN where not estimated).
    final : ndarray, shape (M, dim)
        Last defined point of each value (the start of the next one when following).
    names : tuple of str
        Coordinate names.
    variables : dict of str to ndarray (M,)
        Per-value quantities of the family (the impact pair's reference amplitude ``xm`` and
        half clearance ``L``); also readable as attributes (``d.xm``).
    metadata : dict
        Settings (``iterations``, ``keep``, ``period``, ``follow``, ``initial``, ...) and the
        family's own (the pair's ``case``, ``fixed``, ``design``; a model's ``source``); also
        readable as attributes (``d.case``).

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

    kind = "bifurcation_diagram"
    parameter_name: str
    values: np.ndarray
    points: np.ndarray = field(repr=False)
    code: np.ndarray
    periods: np.ndarray
    status: tuple = field(repr=False, default=())
    spectrum: np.ndarray | None = field(repr=False, default=None)
    final: np.ndarray | None = field(repr=False, default=None)
    names: tuple = ()
    variables: dict = field(default_factory=dict, repr=False)
    metadata: dict = field(default_factory=dict, repr=False)
    __repr__ = compact_repr


    def __len__(self) -> int:
        return len(self.values)

    @property
    def lyapunov(self) -> np.ndarray:
        """Largest Lyapunov exponent of every value, shape (M,) (NaN where not estimated)."""
        if self.spectrum is None:
            return np.full(len(self.values), np.nan)
        return self.spectrum[:, 0]

    @property
    def period(self) -> np.ndarray:
        """:attr:`periods` (the name of earlier versions)."""
        return self.periods

    @property
    def classification(self) -> list:
        """Class name of every value."""
        return [CLASSES[int(c)] for c in self.code]

    def counts(self) -> dict:
        """``{class: number of values}``."""
        return {c: int(np.sum(self.code == i)) for i, c in enumerate(CLASSES)}

    def cycle(self, i: int) -> np.ndarray:
        """The ``k`` points of the cycle at value ``i`` (shape ``(k, dim)``, sorted by the
        first coordinate); empty unless periodic."""
        k = int(self.periods[i])
        if k < 1:
            return np.zeros((0, self.points.shape[-1]))
        c = self.points[i, -k:]
        return c[np.argsort(c[:, 0], kind="stable")]

    def coordinate(self, name: str) -> np.ndarray:
        """The kept points' coordinate ``name`` (one of :attr:`names`), shape (M, keep)."""
        if name not in self.names:
            raise ValueError(f"coordinate must be one of {self.names}, got {name!r}")
        return self.points[..., list(self.names).index(name)]

    def summary(self) -> str:
        """A few lines in words."""
        c = ", ".join(f"{n} {k}" for k, n in self.counts().items() if n)
        per = {int(p): int(np.sum(self.periods == p)) for p in np.unique(self.periods) if p}
        src = self.metadata.get("source")
        out = (f"{Path(src).name + ': ' if src else ''}diagram in {self.parameter_name} "
               f"[{self.values[0]:g}, {self.values[-1]:g}] ({len(self.values)} values): {c}")
        if per:
            out += "\n  periods: " + ", ".join(f"{p}: {n} values" for p, n in per.items())
        return out

    def to_dict(self) -> dict:
        """JSON-ready form (classes by name, ``counts``)."""
        d = super().to_dict()
        d.update(classification=self.classification, counts=self.counts(),
                 parameter=self.parameter_name)
        return d

    def to_dataset(self):
        """Dimensions ``(value, iterate, coordinate)``; ``code`` a CF flag variable, each of
        :attr:`variables` a variable along ``value``."""
        # deferred import: loaded only when this runs, for start-up time
        import xarray as xr

        M, _keep, dim = self.points.shape
        nan = np.full((M, dim), np.nan)
        data = {"points": (("value", "iterate", "coordinate"), self.points),
                "code": ("value", np.asarray(self.code, np.int64), {
                    "flag_values": list(range(len(CLASSES))),
                    "flag_meanings": " ".join(CLASSES)}),
                "periods": ("value", np.asarray(self.periods, np.int64)),
                "spectrum": (("value", "coordinate"),
                             nan if self.spectrum is None else self.spectrum),
                "final": (("value", "coordinate"), nan if self.final is None else self.final)}
        for k, a in self.variables.items():
            data["var_" + k] = ("value", np.asarray(a, float))
        coords = {"value": ("value", np.asarray(self.values, float),
                            {"long_name": self.parameter_name}),
                  "coordinate": ("coordinate", [str(n) for n in self.names]
                                 if len(self.names) == dim else list(range(dim)))}
        attrs = {"kind": self.kind, "parameter_name": self.parameter_name,
                 **encode_attrs({"status": list(self.status), "metadata": self.metadata,
                                 "names": list(self.names)})}
        return xr.Dataset(data, coords=coords, attrs=attrs)

    @classmethod
    def from_dataset(cls, ds) -> BifurcationDiagram:
        """Inverse of :meth:`to_dataset`."""
        a = decode_attrs(ds.attrs)
        if a.get("kind") != cls.kind:
            raise ValueError(f"the dataset holds a {a.get('kind')!r}, not a {cls.kind!r}")
        meanings = str(ds["code"].attrs.get("flag_meanings", " ".join(CLASSES))).split()
        code = np.array([CLASSES.index(meanings[int(c)]) for c in ds["code"].values], np.int64)
        var = {k[4:]: ds[k].values for k in ds.data_vars if k.startswith("var_")}
        return cls(a["parameter_name"], ds["value"].values,
                   ds["points"].transpose("value", "iterate", "coordinate").values, code,
                   ds["periods"].values.astype(np.int64), tuple(a.get("status") or ()),
                   ds["spectrum"].transpose("value", "coordinate").values,
                   ds["final"].transpose("value", "coordinate").values,
                   tuple(a.get("names") or ()), var, dict(a.get("metadata") or {}))


def load_diagram(path) -> BifurcationDiagram:
    """Read a diagram written by :meth:`BifurcationDiagram.save` (``.nc``, ``.zarr`` or
    ``.npz``)."""
    return BifurcationDiagram.load(path)


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


class StoppedMap(PoincareMap):
    """The map `P` at a value where no run can start (e.g. the simulation that would give
    its start diverged): its coordinates and section are `P`'s, and its first application
    stops with `status` (``"diverged"``: the value is classed ``diverged``), so that the
    value has its row and class in a diagram like any other.

    Examples
    --------
    >>> class Id(PoincareMap):
    ...     names = ("x",)
    ...     def apply(self, s, k=1, jacobian=False):
    ...         return MapResult(np.asarray(s, float))
    >>> StoppedMap(Id(), "diverged").iterate_status(np.full(1, np.nan), 3)[1]
    'diverged'
    """

    def __init__(self, P: PoincareMap, status: str):
        self.map, self.status = P, str(status)
        self.names, self.period, self.mode = tuple(P.names), P.period, P.mode
        self.section = getattr(P, "section", None)

    def apply(self, s, k: int = 1, jacobian: bool = False) -> MapResult:
        return MapResult(np.full(self.dim, np.nan), False, self.status)


def _status_class(P, why: str) -> int:
    """The class of a map that stopped with status ``why`` (module docstring)."""
    named = getattr(P, "status_classes", {}).get(why)
    if named is None:
        named = "diverged" if why in ("nonfinite", "diverged") else "undefined"
    return CLASSES.index(named)


def _classify(P, tail, period, settings, lyapunov):
    """``(code, period, spectrum)`` of a finite window of iterates."""
    nan = np.full(tail.shape[1], np.nan)
    if np.any(np.abs(tail[:, 1:] if P.period is not None else tail) > settings["escape"]):
        return CLASSES.index("diverged"), 0, nan
    # a period shows when the window holds it twice: k <= K / 2
    k = detect_period(tail, P.wrap, min(settings["max_period"], len(tail) // 2),
                      settings["period_tol"])[0]
    ex = nan
    if lyapunov:
        try:
            ex = lyapunov_exponents(P.jacobians(tail[:-1], period))
        except RuntimeError:           # DP undefined somewhere along the window
            pass
    if k:
        return CLASSES.index("periodic"), k, ex
    chaotic = np.isfinite(ex[0]) and ex[0] > settings["chaos_tol"]
    return CLASSES.index("chaotic" if chaotic else "quasiperiodic"), 0, ex


def _settings(iterations, keep, max_period, period_tol, chaos_tol, escape):
    iterations, keep, max_period = int(iterations), int(keep), int(max_period)
    if iterations < 1:
        raise ValueError(f"iterations must be >= 1, got {iterations}")
    if not 8 <= keep <= iterations:
        raise ValueError(f"keep must be in [8, iterations = {iterations}], got {keep}")
    if max_period < 1:
        raise ValueError(f"max_period must be >= 1, got {max_period}")
    max_period = min(max_period, keep // 2)     # a longer period cannot repeat in the window
    for name, val in (("period_tol", period_tol), ("escape", escape)):
        if not (math.isfinite(val) and val > 0):
            raise ValueError(f"{name} must be > 0, got {val!r}")
    if not math.isfinite(chaos_tol):
        raise ValueError(f"chaos_tol must be finite, got {chaos_tol!r}")
    return {"iterations": iterations, "keep": keep, "max_period": max_period,
            "period_tol": float(period_tol), "chaos_tol": float(chaos_tol),
            "escape": float(escape)}


def _build(builder, value, s0):
    """``(P, start)`` at ``value``: the family's map and its start (``s0`` unless the family
    gives one; ``s0(P, value)`` if callable)."""
    out = builder(float(value))
    P, start = out if isinstance(out, tuple) else (out, None)
    if not isinstance(P, PoincareMap):
        return P, None
    if start is None:
        if s0 is None:
            raise ValueError("give s0 (the family has no start of its own)")
        start = s0(P, value) if callable(s0) else s0
    return P, np.asarray(start, float)


def bifurcation_diagram(builder, values, *, s0=None, period: int = 1, iterations: int = 1000,
                        keep: int = 64, follow: bool = True, max_period: int = 16,
                        period_tol: float = 1e-6, chaos_tol: float = 1e-3,
                        escape: float = 1e6, lyapunov: bool = False,
                        parameter: str | None = None) -> BifurcationDiagram:
    """Brute-force bifurcation diagram of a family of maps (module docstring).

    Parameters
    ----------
    builder : callable
        The family: ``value -> PoincareMap`` or ``value -> (PoincareMap, start)`` (a map
        class whose constructor takes the parameter first is one), with the optional hooks
        of the module docstring (the impact pair's
        :class:`~hybridpd.pair.bifdiagram.ImpactMapFamily`).
    values : array_like, shape (M,)
        Parameter values in sweep order (at least 2).
    s0 : array_like, shape (dim,), or callable, optional
        Initial point, or ``s0(P, value) -> point``; default: the family's ``initial`` hook.
    period : int
        ``k``: the diagram iterates ``P^k``.
    iterations, keep : int
        Iterations per value and how many of the last ones are recorded
        (``8 <= keep <= iterations``).
    follow : bool
        Start each value from the final point of the previous one (where that run stopped,
        or the map refuses its final point, from the last start the maps accepted).
    max_period : int
        Largest period detected (at most ``keep // 2`` is).
    period_tol : float
        Relative tolerance of the period test.
    chaos_tol : float
        Exponent (per iterate) above which a non-periodic value counts as chaotic.
    escape : float
        Bound on the coordinates (the phase excepted); diverged beyond.
    lyapunov : bool
        Estimate the Lyapunov exponents of every value that ran to the end.
    parameter : str, optional
        Name of the parameter (default: the family's ``parameter``, else ``"p"``).

    Returns
    -------
    BifurcationDiagram

    Raises
    ------
    ValueError
        Bad values or settings, values outside the family, or no map at any value.

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
    st = _settings(iterations, keep, max_period, period_tol, chaos_tol, escape)
    if hasattr(builder, "prepare"):
        builder = builder.prepare(v)
    variables = builder.variables(v) if hasattr(builder, "variables") else {}
    if s0 is None and hasattr(builder, "initial"):
        s0 = builder.initial(v)
    arrays, status, names = None, [], ()
    last = good = None
    for i, value in enumerate(v):
        try:
            P, start = _build(builder, value, s0)
        except ValueError as exc:            # no map at this value
            status.append(f"no map: {exc}")
            continue
        if not isinstance(P, PoincareMap):
            raise ValueError(f"builder must return a PoincareMap, got {type(P).__name__}")
        if arrays is None:
            names, dim = tuple(P.names), P.dim
            arrays = {"pts": np.full((v.size, st["keep"], dim), np.nan),
                      "code": np.full(v.size, CLASSES.index("undefined"), np.int64),
                      "per": np.zeros(v.size, np.int64),
                      "ex": np.full((v.size, dim), np.nan),
                      "final": np.full((v.size, dim), np.nan)}
        if follow:                     # the last start the maps accepted if the run stopped
            start = last if last is not None else good if good is not None else start
        try:
            last = _one_value(P, start, k, st, lyapunov, arrays, i, status)
            good = start
        except ValueError:
            if good is None:
                raise                  # a bad start: the caller's s0
            # the previous value's final point is off the map's domain (e.g. a grazing
            # z4 = 0 of the pair): from the last start the maps accepted instead
            last = _one_value(P, good, k, st, lyapunov, arrays, i, status)
        if hasattr(builder, "project"):
            arrays["pts"][i] = builder.project(P, arrays["pts"][i])
    if arrays is None:
        raise ValueError("the builder built no map at any value: " + "; ".join(status))
    meta = dict(getattr(builder, "metadata", {}) or {})
    meta.update(st, period=k, follow=bool(follow),
                initial=None if s0 is None or callable(s0) else np.asarray(s0, float).tolist())
    name = parameter or getattr(builder, "parameter", None) or "p"
    return BifurcationDiagram(str(name), v, arrays["pts"], arrays["code"], arrays["per"],
                              tuple(status), arrays["ex"], arrays["final"], names,
                              {k_: np.asarray(a, float) for k_, a in variables.items()}, meta)


def _one_value(P, start, k, st, lyapunov, arrays, i, status):
    """Iterate, record and classify value ``i``; the point to follow from (or None)."""
    it, why = P.iterate_status(start, st["iterations"], k)
    done = np.flatnonzero(np.all(np.isfinite(it), axis=1))
    tail = it[-st["keep"]:]
    arrays["pts"][i] = tail
    arrays["final"][i] = it[done[-1]] if done.size else np.nan
    status.append(why)
    if why:
        arrays["code"][i] = _status_class(P, why)
        return None
    arrays["code"][i], arrays["per"][i], arrays["ex"][i] = _classify(P, tail, k, st, lyapunov)
    if arrays["code"][i] == CLASSES.index("diverged"):
        return None
    return tail[-1].copy()
