"""Vectorised interval arithmetic with outward rounding, and the arithmetic backends.

An :class:`Interval` holds NumPy arrays of lower and upper bounds; every operation returns an
enclosure of the exact result for every choice of the operands in their intervals. This is
the fast layer of the certified classification (:mod:`hybridpd.pair.certified`): one NumPy
call per bound and operation for thousands of boxes at once. python-flint's ``arb`` balls
(rigorous by construction) are the reference it is tested against, and serve the point
certificates.

Rounding (why the enclosures are rigorous)
------------------------------------------
NumPy's ``+ - * /`` and ``sqrt`` on float64 are IEEE 754 operations rounded to nearest: the
exact result ``x`` of an operation returning ``r`` satisfies ``|x - r| <= 2^-53 |r| +
2^-1075``. After every operation the lower bound is moved to ``r - (2^-50 |r| + 2^-1022)``
and the upper bound to ``r + (2^-50 |r| + 2^-1022)``, both computed in float64; the widening
(at least four units in the last place) exceeds the rounding error of the operation plus
that of the widening itself, so the new bounds enclose ``x`` (:func:`widen_down`,
:func:`widen_up`). Overflow gives infinite or NaN bounds, and every decision of the
certified classification is phrased as ``lo > 0`` or ``hi < 0``, which is false for NaN:
an overflow can only leave a question undecided.

**Assumed of the platform's libm** (NumPy's ``exp``, ``expm1``, ``cosh``, ``sinh``, ``sin``,
``cos``): results within 256 units in the last place of the exact value, i.e. relative error
at most ``2^-44`` for ``exp``, ``expm1``, ``cosh``, ``sinh`` and absolute error at most
``2^-44`` for ``sin`` and ``cos`` (whose values lie in ``[-1, 1]``). Quality libms (glibc, NumPy's SIMD
routines) are within 4 units. The results of these functions are widened by those bounds
(and the propagated rounding of their arguments) before the outward step; the tests check
every function against ``arb`` on random boxes.

Functions
---------
Monotone functions are evaluated at the endpoints; ``sin`` and ``cos`` add ``+-1`` when the
interval may contain an extremum (decided with slack, so never missed). The entire functions
of the collocated flow, ``cu(u) = cosh(sqrt(u))`` and ``su(u) = sinh(sqrt(u))/sqrt(u)``
(``cos``, ``sin`` continued for ``u < 0``; ``su(0) = 1``), are increasing on ``u >= -9.5``
and ``u >= -20`` (their first turning points are ``-pi^2`` and ``-4.4934^2``); below, they
are evaluated through ``cos``/``sin`` of the interval ``sqrt(-u)``. ``su1 = su'`` and ``su2 = su''``
(needed by the centred forms of :mod:`hybridpd.pair.centred`) are enclosed by their power
series with a bounded tail for ``|u| <= 32`` and by their closed forms beyond. ``emq(x) =
(1 - exp(-x))/x = int_0^1 exp(-x s) ds`` and its derivatives are monotone on the whole line
(completely monotone), so they are evaluated at the endpoints (a power series for
``|x| <= 2``, closed forms beyond, with a stated error bound of ``2^-40`` relative).

Backends
--------
The generated kernels of :mod:`hybridpd.pair.interval_kernels` take a namespace of
operations: :data:`FLOAT_OPS` (plain floats, for checks),
:data:`hybridpd.pair.centred.INTERVAL_OPS` (intervals and centred forms) and :func:`arb_ops` (python-flint balls).
"""
from __future__ import annotations

import math
import types

import numpy as np

from hybridpd.pair import _ikernels

__all__ = ["FLOAT_OPS", "Interval", "arb_ops", "cos", "cu", "emq", "emq1", "emq2", "exp",
           "ipow",
           "sin", "sqrt", "su", "su1", "su2", "widen_down", "widen_up"]

_REL = 2.0**-50
_TINY = 2.0**-1022
_LIBM = 2.0**-44        # the assumed libm error bound (relative for exp/cosh/sinh, absolute for sin/cos)
_EPS = 2.0**-52


def widen_down(x):
    """``x - (2^-50 |x| + 2^-1022)``: a float64 result of one rounded operation, moved down.

    If ``x`` is the round-to-nearest value of an exact ``y``, the returned value is ``<= y``.
    """
    return x - (np.abs(x) * _REL + _TINY)


def widen_up(x):
    """``x + (2^-50 |x| + 2^-1022)`` (see :func:`widen_down`); ``>= y``."""
    return x + (np.abs(x) * _REL + _TINY)


def _f(x):
    return np.asarray(x, dtype=float)


class Interval:
    """Arrays of closed intervals ``[lo, hi]`` with outward-rounded arithmetic.

    Operands of ``+ - * /`` may be intervals, Python ``int`` or ``float`` (taken as exact
    points) or arrays of floats. All arrays broadcast. A division by an interval containing
    0 gives ``[-inf, inf]``.

    Parameters
    ----------
    lo, hi : array_like
        Bounds (``hi`` defaults to ``lo``: a point interval).

    Examples
    --------
    >>> from hybridpd.pair.intervals import Interval
    >>> x = Interval([1.0, -2.0], [2.0, 3.0])
    >>> y = x * x - 1 / Interval(3.0)   # encloses x^2 - 1/3 for every x of the intervals
    >>> bool(y.lo[0] <= 1 - 1 / 3 and y.hi[0] >= 4 - 1 / 3)
    True
    >>> float((x * x).lo[1]) < -6, float((x ** 2).lo[1])  # x * x: the factors vary apart
    (True, 0.0)
    """

    __slots__ = ("hi", "lo")
    __array_priority__ = 1000  # ndarray (op) Interval defers to Interval

    def __init__(self, lo, hi=None):
        self.lo = _f(lo)
        self.hi = self.lo if hi is None else _f(hi)

    # -- construction and queries ------------------------------------------------------
    @classmethod
    def hull_of(cls, *xs) -> Interval:
        """Smallest interval containing all the given intervals."""
        lo = xs[0].lo
        hi = xs[0].hi
        for x in xs[1:]:
            lo = np.minimum(lo, x.lo)
            hi = np.maximum(hi, x.hi)
        return cls(lo, hi)

    def intersect(self, other: Interval) -> Interval:
        """Intersection (both must enclose the same quantity; then it is never empty)."""
        return Interval(np.maximum(self.lo, other.lo), np.minimum(self.hi, other.hi))

    def mid(self) -> np.ndarray:
        """Midpoints (finite where both bounds are)."""
        return 0.5 * self.lo + 0.5 * self.hi

    def width(self) -> np.ndarray:
        """``hi - lo`` (rounded)."""
        return self.hi - self.lo

    def mag(self) -> np.ndarray:
        """``max(|lo|, |hi|)``."""
        return np.maximum(np.abs(self.lo), np.abs(self.hi))

    def contains(self, x) -> np.ndarray:
        """Whether ``x`` lies in each interval."""
        x = _f(x)
        return (self.lo <= x) & (x <= self.hi)

    def take(self, idx) -> Interval:
        """The intervals at the index array ``idx`` (broadcast scalars are kept)."""
        return Interval(self.lo if self.lo.ndim == 0 else self.lo[idx],
                        self.hi if self.hi.ndim == 0 else self.hi[idx])

    @property
    def shape(self):
        """Broadcast shape of the bounds."""
        return np.broadcast_shapes(self.lo.shape, self.hi.shape)

    def __repr__(self):
        if self.lo.ndim == 0:
            return f"Interval([{self.lo:.17g}, {self.hi:.17g}])"
        return f"Interval(shape={self.shape})"

    # -- arithmetic --------------------------------------------------------------------
    def __neg__(self):
        return Interval(-self.hi, -self.lo)

    def __pos__(self):
        return self

    def __add__(self, o):
        if isinstance(o, Interval):
            fast = _compiled("add", self, o)
            if fast is not None:
                return fast
            return Interval(widen_down(self.lo + o.lo), widen_up(self.hi + o.hi))
        if _is_point(o):
            o = _f(o)
            return Interval(widen_down(self.lo + o), widen_up(self.hi + o))
        return NotImplemented

    __radd__ = __add__

    def __sub__(self, o):
        if isinstance(o, Interval):
            fast = _compiled("sub", self, o)
            if fast is not None:
                return fast
            return Interval(widen_down(self.lo - o.hi), widen_up(self.hi - o.lo))
        if _is_point(o):
            o = _f(o)
            return Interval(widen_down(self.lo - o), widen_up(self.hi - o))
        return NotImplemented

    def __rsub__(self, o):
        if _is_point(o):
            return (-self) + o
        return NotImplemented

    def __mul__(self, o):
        if isinstance(o, Interval):
            fast = _compiled("mul", self, o)
            if fast is not None:
                return fast
            a, b, c, d = self.lo * o.lo, self.lo * o.hi, self.hi * o.lo, self.hi * o.hi
            lo = np.minimum(np.minimum(a, b), np.minimum(c, d))
            hi = np.maximum(np.maximum(a, b), np.maximum(c, d))
            return Interval(widen_down(lo), widen_up(hi))
        if _is_point(o):
            o = _f(o)
            a, b = self.lo * o, self.hi * o
            return Interval(widen_down(np.minimum(a, b)), widen_up(np.maximum(a, b)))
        return NotImplemented

    __rmul__ = __mul__

    def __truediv__(self, o):
        if _is_point(o):
            o = Interval(o)
        if not isinstance(o, Interval):
            return NotImplemented
        with np.errstate(divide="ignore", invalid="ignore"):
            a, b, c, d = self.lo / o.lo, self.lo / o.hi, self.hi / o.lo, self.hi / o.hi
            lo = np.minimum(np.minimum(a, b), np.minimum(c, d))
            hi = np.maximum(np.maximum(a, b), np.maximum(c, d))
        zero = (o.lo <= 0) & (o.hi >= 0)
        lo = np.where(zero, -np.inf, widen_down(lo))
        hi = np.where(zero, np.inf, widen_up(hi))
        return Interval(lo, hi)

    def __rtruediv__(self, o):
        if _is_point(o):
            return Interval(o) / self
        return NotImplemented

    def __pow__(self, k):
        return ipow(self, k)


def _compiled(kind, a: Interval, b: Interval):
    """The compiled loop of ``a kind b`` for 1-D operands (or a scalar one), else ``None``."""
    k = _ikernels
    alo, ahi, blo, bhi = a.lo, a.hi, b.lo, b.hi
    if alo.ndim != 1 or ahi.shape != alo.shape:
        if kind != "sub" and blo.ndim == 1 and bhi.shape == blo.shape and \
                alo.ndim == 0 and ahi.ndim == 0:
            return _compiled(kind, b, a)
        return None
    if blo.shape == alo.shape and bhi.shape == alo.shape:
        lo, hi = np.empty_like(alo), np.empty_like(alo)
        getattr(k, kind)(alo, ahi, blo, bhi, lo, hi)
        return Interval(lo, hi)
    if blo.ndim == 0 and bhi.ndim == 0:
        lo, hi = np.empty_like(alo), np.empty_like(alo)
        getattr(k, kind + "_s")(alo, ahi, float(blo), float(bhi), lo, hi)
        return Interval(lo, hi)
    return None


def _is_point(o) -> bool:
    return isinstance(o, (int, float, np.ndarray, np.floating, np.integer)) and not \
        isinstance(o, bool)


def _as_interval(x) -> Interval:
    return x if isinstance(x, Interval) else Interval(x)


def ipow(x, k: int) -> Interval:
    """``x ** k`` for an integer ``k >= 1`` (even powers are non-negative)."""
    x = _as_interval(x)
    k = int(k)
    if k < 1:
        raise ValueError(f"k must be an integer >= 1, got {k}")
    if k == 1:
        return x
    # |x|^k of the endpoints by repeated, outward-rounded products of non-negative numbers
    alo, ahi = np.abs(x.lo), np.abs(x.hi)
    plo, phi = alo, ahi
    dlo, dhi = alo, ahi
    for _ in range(k - 1):
        plo = widen_up(plo * alo)
        phi = widen_up(phi * ahi)
        dlo = np.maximum(widen_down(dlo * alo), 0.0)
        dhi = np.maximum(widen_down(dhi * ahi), 0.0)
    if k % 2:
        # odd: monotone increasing
        lo = np.where(x.lo >= 0, dlo, -plo)
        hi = np.where(x.hi >= 0, phi, -dhi)
        return Interval(lo, hi)
    straddle = (x.lo < 0) & (x.hi > 0)
    lo = np.where(straddle, 0.0, np.where(x.lo >= 0, dlo, dhi))
    hi = np.where(x.lo >= 0, phi, np.where(x.hi <= 0, plo, np.maximum(plo, phi)))
    return Interval(lo, hi)


def exp(x) -> Interval:
    """``exp`` of an interval (libm error bound as in the module docstring)."""
    x = _as_interval(x)
    with np.errstate(over="ignore"):
        lo = np.exp(x.lo)
        hi = np.exp(x.hi)
    return Interval(np.maximum(widen_down(lo * (1 - _LIBM)), 0.0), widen_up(hi * (1 + _LIBM)))


def sqrt(x) -> Interval:
    """``sqrt`` of an interval (``NaN`` bounds if it reaches below 0)."""
    x = _as_interval(x)
    with np.errstate(invalid="ignore"):
        lo = np.sqrt(x.lo)
        hi = np.sqrt(x.hi)
    return Interval(np.maximum(widen_down(lo), 0.0), widen_up(hi))


def _extrema(x: Interval, shift: float):
    """Whether ``[lo, hi]`` may contain ``(k + shift) pi`` with ``k`` even / ``k`` odd."""
    with np.errstate(invalid="ignore"):
        a = x.lo / math.pi - shift
        b = x.hi / math.pi - shift
        slack = 2.0**-40 * (1 + np.maximum(np.abs(a), np.abs(b)))
        ka = np.ceil(a - slack)
        kb = np.floor(b + slack)
    many = (kb - ka >= 1) | ~np.isfinite(ka) | ~np.isfinite(kb)
    one = kb == ka
    even = np.mod(ka, 2) == 0
    return many | (one & even), many | (one & ~even)


def _trig(x, fn, shift) -> Interval:
    x = _as_interval(x)
    with np.errstate(invalid="ignore"):
        ya, yb = fn(x.lo), fn(x.hi)
    lo = widen_down(np.minimum(ya, yb) - _LIBM)
    hi = widen_up(np.maximum(ya, yb) + _LIBM)
    has_max, has_min = _extrema(x, shift)
    lo = np.where(has_min, -1.0, lo)
    hi = np.where(has_max, 1.0, hi)
    return Interval(np.maximum(lo, -1.0), np.minimum(hi, 1.0))


def cos(x) -> Interval:
    """``cos`` of an interval (extrema at ``k pi``)."""
    return _trig(x, np.cos, 0.0)


def sin(x) -> Interval:
    """``sin`` of an interval (extrema at ``(k + 1/2) pi``)."""
    return _trig(x, np.sin, 0.5)


# ----------------------------------------------------------------------------------------
# The entire functions cu, su of the collocated flow
# ----------------------------------------------------------------------------------------

_NSER = 14
_CU_COEF = tuple(1.0 / math.factorial(2 * k) for k in range(_NSER))
_SU_COEF = tuple(1.0 / math.factorial(2 * k + 1) for k in range(_NSER))
_CU_MONO = -9.5     # cu is increasing on [-pi^2, inf)
_SU_MONO = -20.0    # su is increasing on [-4.4934^2, inf)


def _horner_f(u, coef):
    acc = np.full_like(u, coef[-1])
    for c in coef[-2::-1]:
        acc = acc * u + c
    return acc


def _cu_point(u):
    """``cu(u)`` in float64 and a bound of its error."""
    u = _f(u)
    with np.errstate(all="ignore"):
        r = np.sqrt(np.abs(u))
        small = np.abs(u) <= 1.0
        y = np.where(small, _horner_f(np.where(small, u, 0.0), _CU_COEF),
                     np.where(u > 0, np.cosh(r), np.cos(r)))
    # libm (2^-44 relative or absolute) plus the rounding of sqrt propagated (|d/dr| <= |y| + 1)
    err = (np.abs(y) + 1.0) * (_LIBM + (r + 1.0) * 4 * _EPS)
    return y, err


def _su_point(u):
    """``su(u)`` in float64 and a bound of its error."""
    u = _f(u)
    with np.errstate(all="ignore"):
        r = np.sqrt(np.abs(u))
        small = np.abs(u) <= 1.0
        rr = np.where(small, 1.0, r)
        y = np.where(small, _horner_f(np.where(small, u, 0.0), _SU_COEF),
                     np.where(u > 0, np.sinh(rr), np.sin(rr)) / rr)
    # sin, sinh absolute/relative 2^-44 divided by r >= 1; sqrt's rounding propagated
    err = (np.abs(y) + 1.0) * (_LIBM + (r + 1.0) * 4 * _EPS)
    return y, err


def _monotone(x: Interval, point, start) -> Interval:
    """Enclosure of an increasing function on ``x ∩ [start, inf)``."""
    a = np.maximum(x.lo, start)
    ya, ea = point(a)
    yb, eb = point(x.hi)
    return Interval(widen_down(ya - ea), widen_up(yb + eb))


def _below(x: Interval, start, fn) -> Interval:
    """Enclosure of ``fn(b)`` with ``b = sqrt(-u)`` for ``u`` in ``x ∩ (-inf, start]``."""
    ulo = x.lo
    uhi = np.minimum(x.hi, start)
    b = sqrt(Interval(-uhi, -ulo))
    return fn(b)


def _split(x: Interval, start, point, fn) -> Interval:
    up = _monotone(x, point, start)
    low = x.lo < start
    if not np.any(low):
        return up
    down = _below(x, start, fn)
    above = x.hi >= start
    lo = np.where(low, np.where(above, np.minimum(up.lo, down.lo), down.lo), up.lo)
    hi = np.where(low, np.where(above, np.maximum(up.hi, down.hi), down.hi), up.hi)
    return Interval(lo, hi)


def cu(x) -> Interval:
    """``cu(u) = cosh(sqrt(u))`` (``cos(sqrt(-u))`` for ``u < 0``) of an interval."""
    return _split(_as_interval(x), _CU_MONO, _cu_point, cos)


def su(x) -> Interval:
    """``su(u) = sinh(sqrt(u))/sqrt(u)`` (``sin(sqrt(-u))/sqrt(-u)``, ``su(0) = 1``)."""
    return _split(_as_interval(x), _SU_MONO, _su_point, lambda b: sin(b) / b)


_SER_N = 26
_SER_CUT = 32.0
_SU1_COEF = tuple(k / math.factorial(2 * k + 1) for k in range(1, _SER_N + 1))
_SU2_COEF = tuple(k * (k - 1) / math.factorial(2 * k + 1) for k in range(2, _SER_N + 2))


def _series(x: Interval, coef, tail_term) -> Interval:
    """Horner's scheme of ``sum_j coef[j] u^j`` on ``|u| <= 32`` plus a bounded tail.

    ``tail_term`` is the first omitted term's bound at ``|u| = 32``; the omitted terms
    decrease geometrically with ratio below 1/2 there, so the tail is below twice it.
    """
    acc = Interval(widen_down(coef[-1]), widen_up(coef[-1]))
    for c in coef[-2::-1]:
        acc = acc * x + Interval(widen_down(c), widen_up(c))
    t = 2.0 * tail_term
    return Interval(widen_down(acc.lo - t), widen_up(acc.hi + t))


def _su1_tail():
    k = _SER_N + 1
    return k * _SER_CUT ** (k - 1) / math.factorial(2 * k + 1)


def _su2_tail():
    k = _SER_N + 2
    return k * (k - 1) * _SER_CUT ** (k - 2) / math.factorial(2 * k + 1)


def _series_or_formula(x: Interval, coef, tail, formula) -> Interval:
    """The series on ``x ∩ [-32, 32]``, ``formula`` on the parts beyond, hulled."""
    x = _as_interval(x)
    inner = Interval(np.clip(x.lo, -_SER_CUT, _SER_CUT), np.clip(x.hi, -_SER_CUT, _SER_CUT))
    ser = _series(inner, coef, tail)
    meets = (x.hi >= -_SER_CUT) & (x.lo <= _SER_CUT)
    lo = np.where(meets, ser.lo, np.inf)
    hi = np.where(meets, ser.hi, -np.inf)
    for part, a, b in ((x.hi > _SER_CUT, np.maximum(x.lo, _SER_CUT), x.hi),
                       (x.lo < -_SER_CUT, x.lo, np.minimum(x.hi, -_SER_CUT))):
        if not np.any(part):
            continue
        u = Interval(np.where(part, a, 2 * _SER_CUT), np.where(part, b, 2 * _SER_CUT))
        v = formula(u)
        lo = np.where(part, np.minimum(lo, v.lo), lo)
        hi = np.where(part, np.maximum(hi, v.hi), hi)
    return Interval(lo, hi)


def su1(x) -> Interval:
    """``su'(u) = (cu(u) - su(u)) / (2 u)`` (``1/6`` at 0) of an interval."""
    return _series_or_formula(x, _SU1_COEF, _su1_tail(), lambda u: (cu(u) - su(u)) / (2 * u))


def su2(x) -> Interval:
    """``su''(u) = (su(u)/2 - 3 su'(u)) / (2 u)`` (``1/60`` at 0) of an interval."""
    return _series_or_formula(x, _SU2_COEF, _su2_tail(),
                              lambda u: (su(u) * 0.5 - su1(u) * 3) / (2 * u))


_EMQ_N = 40
_EMQ_SERIES = 2.0


def _emq_point(x, m):
    """``d^m/dx^m (1 - exp(-x))/x = (-1)^m int_0^1 s^m exp(-x s) ds`` in float64, error bound.

    The power series (alternating, 40 terms) for ``|x| <= 2``, the closed forms beyond.
    """
    x = _f(x)
    with np.errstate(all="ignore"):
        small = np.abs(x) <= _EMQ_SERIES
        xs = np.where(small, x, 0.0)
        ser = np.zeros_like(xs)
        term = np.ones_like(xs)  # (-x)^k / k!
        for k in range(_EMQ_N):
            ser = ser + term / (k + m + 1)
            term = term * (-xs) / (k + 1)
        xb = np.where(small, 1.0, x)
        em = np.exp(-xb)
        if m == 0:
            big = -np.expm1(-xb) / xb
        elif m == 1:
            big = (1.0 - em * (1.0 + xb)) / xb**2
        else:
            big = (2.0 - em * (xb * xb + 2.0 * xb + 2.0)) / xb**3
        y = np.where(small, ser, big) * (-1.0) ** m
    err = np.abs(y) * 2.0**-40 + 2.0**-60
    return y, err


def _emq(x, m) -> Interval:
    x = _as_interval(x)
    ya, ea = _emq_point(x.lo, m)
    yb, eb = _emq_point(x.hi, m)
    if m % 2:   # increasing
        return Interval(widen_down(ya - ea), widen_up(yb + eb))
    return Interval(widen_down(yb - eb), widen_up(ya + ea))


def emq(x) -> Interval:
    """``(1 - exp(-x))/x`` (1 at 0; entire and decreasing) of an interval."""
    return _emq(x, 0)


def emq1(x) -> Interval:
    """The derivative of :func:`emq` (increasing, ``-1/2`` at 0)."""
    return _emq(x, 1)


def emq2(x) -> Interval:
    """The second derivative of :func:`emq` (decreasing, ``1/3`` at 0)."""
    return _emq(x, 2)


# ----------------------------------------------------------------------------------------
# Backends of the generated kernels
# ----------------------------------------------------------------------------------------


def _float_cu(u):
    return math.cosh(math.sqrt(u)) if u >= 0 else math.cos(math.sqrt(-u))


def _float_su(u):
    if u == 0:
        return 1.0
    r = math.sqrt(abs(u))
    return math.sinh(r) / r if u > 0 else math.sin(r) / r


#: Plain float backend (for checks): ``math`` functions on Python floats.
FLOAT_OPS = types.SimpleNamespace(
    Q=lambda p, q: p / q, PI=math.pi, POW=lambda x, k: x**k, SQRT=math.sqrt, EXP=math.exp,
    SIN=math.sin, COS=math.cos,
    DCH=lambda a, D, t: math.exp(-a * t) * _float_cu(D * t * t),
    DSH=lambda a, D, t: t * math.exp(-a * t) * _float_su(D * t * t))


def _arb_series(u, coef_of, n_terms):
    """``sum_k coef_of(k) u^k`` for a ball ``u`` with ``|u| <= 1``, tail included."""
    from flint import arb

    acc = arb(0)
    for k in range(n_terms - 1, -1, -1):
        acc = acc * u + coef_of(k)
    tail = 2 * abs(u).upper() ** n_terms * coef_of(n_terms)
    return acc + arb(0, tail.upper()) if not tail.is_zero() else acc


def arb_ops():
    """The python-flint ``arb`` backend (balls; rigorous at the context's precision).

    Returns
    -------
    types.SimpleNamespace
        The operations the generated kernels use, on ``flint.arb`` values.
    """
    from flint import arb

    def cu_(u):
        if u > 0:
            return u.sqrt().cosh()
        if u < 0:
            return (-u).sqrt().cos()
        if abs(u) <= 1:
            return _arb_series(u, lambda k: arb(1) / arb.fac_ui(2 * k), 24)
        return arb.nan()

    def su_(u):
        if u > 0:
            r = u.sqrt()
            return r.sinh() / r
        if u < 0:
            r = (-u).sqrt()
            return r.sin() / r
        if abs(u) <= 1:
            return _arb_series(u, lambda k: arb(1) / arb.fac_ui(2 * k + 1), 24)
        return arb.nan()

    return types.SimpleNamespace(
        Q=lambda p, q: arb(p) / q, PI=arb.pi(), POW=lambda x, k: x**k,
        SQRT=lambda x: x.sqrt(), EXP=lambda x: x.exp(), SIN=lambda x: x.sin(),
        COS=lambda x: x.cos(), DCH=lambda a, D, t: (-(a * t)).exp() * cu_(D * t * t),
        DSH=lambda a, D, t: t * (-(a * t)).exp() * su_(D * t * t))
