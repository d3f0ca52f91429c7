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
:func:`widen_up`). Operands are converted exactly: floats are exact points, and an integer
that float64 cannot hold (beyond ``2^53``) becomes the two floats around it.

**One rule for NaN**: an operand with a NaN bound, or an operation whose result would have
one (``inf - inf``, ``0 * inf``, ``sqrt`` of an interval reaching below 0, overflow), gives
the whole line ``[-inf, inf]``, never NaN bounds, ``[-1, 1]`` or an empty interval. Every
decision of the certified classification is phrased as ``lo > 0`` or ``hi < 0``, which the
whole line never satisfies: such a failure can only leave a question undecided. Two
enclosures of one quantity always meet; :meth:`Interval.intersect` raises
:class:`EmptyIntersectionError` when they do not (one of them is wrong), and the certifier
(:func:`hybridpd.pair.proofs.classify`) leaves the boxes concerned undecided.

**Assumed of the platform's libm** (NumPy's ``exp``, ``expm1``, ``cosh``, ``sinh``, ``sin``,
``cos``): results within 256 units in the last place of the exact value, i.e. relative error
at most ``2^-44`` for ``exp``, ``expm1``, ``cosh``, ``sinh`` and absolute error at most
``2^-44`` for ``sin`` and ``cos`` (whose values lie in ``[-1, 1]``), and ``sqrt`` correctly
rounded. NumPy does not document an error bound (its SIMD routines differ between versions
and CPUs), so the assumption is checked, once per process when certification first needs it,
against ``arb`` on hard arguments (:mod:`hybridpd.pair.selftest`); certification refuses to
run where it fails. The results of these functions are widened by those bounds (and the
propagated rounding of their arguments) before the outward step; the tests check every
function against ``arb`` on random boxes.

Functions
---------
Monotone functions are evaluated at the endpoints; ``sin`` and ``cos`` add ``+-1`` when the
interval may contain an extremum (decided with slack, so never missed).
The entire functions of the damped flow (``cu``, ``su``, ``emq`` and their derivatives) and
the backends of the generated kernels are in :mod:`hybridpd.pair.flowintervals`.
"""
from __future__ import annotations

import functools
import math

import numpy as np

from hybridpd._jit import njit
from hybridpd.pair import _ikernels

__all__ = ["LIBM_BOUND", "EmptyIntersectionError", "Interval", "cos", "exp", "ipow", "sin",
           "sqrt", "widen_down", "widen_up"]

_REL = 2.0**-50
_TINY = 2.0**-1022
_LIBM = 2.0**-44        # the assumed libm error bound (relative for exp/cosh/sinh, absolute for sin/cos)
#: The error bound assumed of NumPy's elementary functions (relative for ``exp``, ``expm1``,
#: ``cosh``, ``sinh``; absolute for ``sin``, ``cos``), checked by :mod:`hybridpd.pair.selftest`.
LIBM_BOUND = _LIBM
_EPS = 2.0**-52
_EXACT_INT = 2**53      # every integer of at most this magnitude is a float64


class EmptyIntersectionError(ArithmeticError):
    """Two enclosures of one quantity do not meet: one of them is wrong.

    Raised by :meth:`Interval.intersect`; the certifier turns it into "undecided" for the
    boxes concerned, never into a proof.
    """


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


_F64 = np.dtype(np.float64)


def _scalar_bounds(v):
    """``(lo, hi)`` floats enclosing the exact number ``v`` (an int beyond 2^53 rounded out)."""
    if isinstance(v, (bool, np.bool_)):
        return float(v), float(v)
    if isinstance(v, np.integer):
        v = int(v)
    if isinstance(v, (float, np.floating)):
        return float(v), float(v)
    try:
        f = float(v)
    except OverflowError:
        big = np.finfo(float).max
        return (big, math.inf) if v > 0 else (-math.inf, -big)
    if f == v:  # Python compares int (Fraction, ...) with float exactly
        return f, f
    if f > v:
        return math.nextafter(f, -math.inf), f
    return f, math.nextafter(f, math.inf)


def _bounds(x):
    """Float64 arrays ``(lo, hi)`` enclosing the exact values of ``x``.

    Floats are exact (``lo is hi``); integers beyond ``2^53`` (Python ``int``, NumPy integer
    arrays, lists of ints) are rounded outward to the floats around them.
    """
    if type(x) is np.ndarray and x.dtype is _F64:
        return x, x
    if isinstance(x, (float, np.floating)):
        a = _f(x)
        return a, a
    if isinstance(x, (int, np.integer)) and not isinstance(x, (bool, np.bool_)):
        lo, hi = _scalar_bounds(x)
        return (_f(lo), _f(hi)) if lo != hi else (_f(lo),) * 2
    a = np.asarray(x, dtype=object) if isinstance(x, (list, tuple)) else np.asarray(x)
    if a.dtype.kind in "iu":
        f = a.astype(float)
        big = np.abs(f) >= _EXACT_INT
        if not np.any(big):
            return f, f
        return (np.where(big, np.nextafter(f, -np.inf), f),
                np.where(big, np.nextafter(f, np.inf), f))
    if a.dtype == object:
        flat = [_scalar_bounds(v) for v in a.ravel()]
        lo = np.array([p[0] for p in flat], dtype=float).reshape(a.shape)
        hi = np.array([p[1] for p in flat], dtype=float).reshape(a.shape)
        return (lo, lo) if np.array_equal(lo, hi, equal_nan=True) else (lo, hi)
    a = _f(a)
    return a, a


_LE = np.less_equal
_ALL = np.logical_and.reduce
_MAX = np.maximum.reduce     # propagates NaN
_isnan = math.isnan


def _has_nan(a) -> bool:
    """Whether the array ``a`` has a NaN element (one reduction)."""
    return a.size > 0 and _isnan(_MAX(a, axis=None))


def _whole_where_nan(lo, hi, *operands):
    """The interval ``[lo, hi]``, the whole line wherever it or an operand has a NaN bound.

    The module's one rule for NaN. The result is checked by ``lo <= hi`` (false at a NaN
    bound; one comparison, no warning on infinities), the operands (of the functions, whose
    value may hide a NaN argument) by a reduction each; the elementwise masks are formed
    only when one of them finds a NaN.
    """
    if _ALL(_LE(lo, hi), axis=None) and not any(_has_nan(x.lo) or _has_nan(x.hi)
                                                 for x in operands):
        return Interval(lo, hi)
    ok = _LE(lo, hi)
    for x in operands:
        ok = ok & ~(np.isnan(x.lo) | np.isnan(x.hi))
    return Interval(np.where(ok, lo, -np.inf), np.where(ok, hi, np.inf))


class Interval:
    """Arrays of closed intervals ``[lo, hi]`` with outward-rounded arithmetic.

    Operands of ``+ - * /`` may be intervals, Python ``int`` or ``float`` or arrays of them
    (floats are exact points; an integer beyond ``2^53`` is enclosed by the two floats
    around it). All arrays broadcast. A division by an interval containing 0 gives
    ``[-inf, inf]``, and so does any operation on or giving a NaN bound (the module's rule).

    Parameters
    ----------
    lo, hi : array_like
        Bounds (``hi`` defaults to ``lo``: a point interval). Integers that float64 cannot
        hold are rounded outward (``lo`` down, ``hi`` up).

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
        if hi is None:
            self.lo, self.hi = _bounds(lo)
            return
        # float64 arrays (every result of the arithmetic) are taken as they are
        self.lo = lo if type(lo) is np.ndarray and lo.dtype is _F64 else _bounds(lo)[0]
        self.hi = hi if type(hi) is np.ndarray and hi.dtype is _F64 else _bounds(hi)[1]

    # -- construction and queries ------------------------------------------------------
    @classmethod
    def hull_of(cls, *xs) -> Interval:
        """Smallest interval containing all the given intervals."""
        lo = xs[0].lo
        hi = xs[0].hi
        for x in xs[1:]:
            lo = np.minimum(lo, x.lo)
            hi = np.maximum(hi, x.hi)
        return _whole_where_nan(lo, hi)

    def intersect(self, other: Interval) -> Interval:
        """Intersection of two enclosures of the same quantity.

        Two enclosures of one quantity always meet; where they do not, one of them is wrong,
        and nothing computed from them may be trusted: :class:`EmptyIntersectionError` is
        raised (never an empty interval, whose ``lo > 0`` and ``hi < 0`` could both hold).
        An operand with a NaN bound gives the whole line there (the module's rule).

        Raises
        ------
        EmptyIntersectionError
            Where ``max(lo) > min(hi)`` for some element.
        """
        lo = np.maximum(self.lo, other.lo)     # propagates a NaN bound of either operand
        hi = np.minimum(self.hi, other.hi)
        ok = _LE(lo, hi)
        if _ALL(ok, axis=None):
            return Interval(lo, hi)
        nan = np.isnan(lo) | np.isnan(hi)
        empty = ~ok & ~nan
        if np.any(empty):
            bad = np.flatnonzero(empty)
            raise EmptyIntersectionError(
                f"two enclosures of one quantity do not meet at {bad.size} element(s) "
                f"(first at flat index {int(bad[0])}): one of them is wrong")
        return Interval(np.where(nan, -np.inf, lo), np.where(nan, np.inf, hi))

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
        return _whole_where_nan(-self.hi, -self.lo)

    def __pos__(self):
        return self

    def __add__(self, o):
        if not isinstance(o, Interval):
            o = _operand(o)
        if isinstance(o, Interval):
            fast = _compiled("add", self, o)
            if fast is not None:
                return fast
            return _whole_where_nan(widen_down(self.lo + o.lo), widen_up(self.hi + o.hi))
        if o is not None:
            if o.ndim == 0 and self.lo.ndim == 1 and self.hi.shape == self.lo.shape:
                return _compiled("add", self, _raw(o, o))
            return _whole_where_nan(widen_down(self.lo + o), widen_up(self.hi + o))
        return NotImplemented

    __radd__ = __add__

    def __sub__(self, o):
        if not isinstance(o, Interval):
            o = _operand(o)
        if isinstance(o, Interval):
            fast = _compiled("sub", self, o)
            if fast is not None:
                return fast
            return _whole_where_nan(widen_down(self.lo - o.hi), widen_up(self.hi - o.lo))
        if o is not None:
            if o.ndim == 0 and self.lo.ndim == 1 and self.hi.shape == self.lo.shape:
                return _compiled("sub", self, _raw(o, o))
            return _whole_where_nan(widen_down(self.lo - o), widen_up(self.hi - o))
        return NotImplemented

    def __rsub__(self, o):
        if _is_point(o):
            return (-self) + o
        return NotImplemented

    def __mul__(self, o):
        if not isinstance(o, Interval):
            o = _operand(o)
        if isinstance(o, Interval):
            fast = _compiled("mul", self, o)
            if fast is not None:
                return fast
            a, b, c, d = self.lo * o.lo, self.lo * o.hi, self.hi * o.lo, self.hi * o.hi
            lo = np.minimum(np.minimum(a, b), np.minimum(c, d))
            hi = np.maximum(np.maximum(a, b), np.maximum(c, d))
            return _whole_where_nan(widen_down(lo), widen_up(hi))
        if o is not None:
            if o.ndim == 0 and self.lo.ndim == 1 and self.hi.shape == self.lo.shape:
                return _compiled("mul", self, _raw(o, o))
            a, b = self.lo * o, self.hi * o
            return _whole_where_nan(widen_down(np.minimum(a, b)), widen_up(np.maximum(a, b)))
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
            return _whole_where_nan(lo, hi)

    def __rtruediv__(self, o):
        if _is_point(o):
            return Interval(o) / self
        return NotImplemented

    def __pow__(self, k):
        return ipow(self, k)


@njit(cache=True)
def _nan_to_whole(lo, hi):
    """The whole line wherever a bound is NaN (in place): the module's rule, in the loops."""
    for i in range(lo.size):
        if math.isnan(lo[i]) or math.isnan(hi[i]):
            lo[i] = -math.inf
            hi[i] = math.inf


# The loops of hybridpd.pair._ikernels give the whole line where a product or sum is NaN; a
# bound that becomes NaN only in the outward step (inf - inf: a lower bound that overflowed
# to +inf) is caught by _nan_to_whole in the same compiled call.
@njit(cache=True)
def _add(alo, ahi, blo, bhi, lo, hi):
    _ikernels.add(alo, ahi, blo, bhi, lo, hi)
    _nan_to_whole(lo, hi)


@njit(cache=True)
def _add_s(alo, ahi, b1, b2, lo, hi):
    _ikernels.add_s(alo, ahi, b1, b2, lo, hi)
    _nan_to_whole(lo, hi)


@njit(cache=True)
def _sub(alo, ahi, blo, bhi, lo, hi):
    _ikernels.sub(alo, ahi, blo, bhi, lo, hi)
    _nan_to_whole(lo, hi)


@njit(cache=True)
def _sub_s(alo, ahi, b1, b2, lo, hi):
    _ikernels.sub_s(alo, ahi, b1, b2, lo, hi)
    _nan_to_whole(lo, hi)


@njit(cache=True)
def _mul(alo, ahi, blo, bhi, lo, hi):
    _ikernels.mul(alo, ahi, blo, bhi, lo, hi)
    _nan_to_whole(lo, hi)


@njit(cache=True)
def _mul_s(alo, ahi, b1, b2, lo, hi):
    _ikernels.mul_s(alo, ahi, b1, b2, lo, hi)
    _nan_to_whole(lo, hi)


_LOOPS = {"add": _add, "add_s": _add_s, "sub": _sub, "sub_s": _sub_s, "mul": _mul,
          "mul_s": _mul_s}


@functools.cache
def _loop(name):
    """The numba dispatcher of the compiled loop ``name`` (compiled or loaded on first use)."""
    return _LOOPS[name].dispatcher


def _compiled(kind, a: Interval, b: Interval):
    """The compiled loop of ``a kind b`` for 1-D operands (or a scalar one), else ``None``."""
    alo, ahi, blo, bhi = a.lo, a.hi, b.lo, b.hi
    if alo.ndim != 1 or ahi.shape != alo.shape:
        if kind != "sub" and blo.ndim == 1 and bhi.shape == blo.shape and \
                alo.ndim == 0 and ahi.ndim == 0:
            return _compiled(kind, b, a)
        return None
    if blo.shape == alo.shape and bhi.shape == alo.shape:
        lo, hi = np.empty_like(alo), np.empty_like(alo)
        _loop(kind)(alo, ahi, blo, bhi, lo, hi)
        return _raw(lo, hi)
    if blo.ndim == 0 and bhi.ndim == 0:
        lo, hi = np.empty_like(alo), np.empty_like(alo)
        _loop(kind + "_s")(alo, ahi, float(blo), float(bhi), lo, hi)
        return _raw(lo, hi)
    return None


def _raw(lo, hi) -> Interval:
    """An interval of two float64 arrays, without conversion (the arithmetic's results)."""
    r = object.__new__(Interval)
    r.lo = lo
    r.hi = hi
    return r


def _is_point(o) -> bool:
    return isinstance(o, (int, float, np.ndarray, np.floating, np.integer)) and not \
        isinstance(o, bool)


def _operand(o):
    """An operand of ``+ - *``: the interval, the float array of an exact point, or ``None``.

    A point that float64 cannot hold exactly (an integer beyond ``2^53``) becomes the
    interval of the floats around it.
    """
    if isinstance(o, Interval):
        return o
    if not _is_point(o):
        return None
    lo, hi = _bounds(o)
    return lo if lo is hi else Interval(lo, hi)


def _as_interval(x) -> Interval:
    return x if isinstance(x, Interval) else Interval(x)


def _exponent(k) -> int:
    """``k`` as a Python int if it is an integral number, else ``ValueError`` naming it.

    A real exponent is refused rather than truncated (``x ** 2.5`` is not ``x ** 2``).
    """
    if isinstance(k, (int, np.integer)) and not isinstance(k, (bool, np.bool_)):
        return int(k)
    if isinstance(k, (float, np.floating)) and math.isfinite(k) and float(k).is_integer():
        return int(k)
    raise ValueError(f"the exponent k of an interval power must be an integer >= 1 (a real "
                     f"exponent is not enclosed), got {k!r}")


def ipow(x, k: int) -> Interval:
    """``x ** k`` for an integer ``k >= 1`` (even powers are non-negative).

    ``k`` may be an integral float (``2.0``); any other exponent (``2.5``) raises
    ``ValueError`` naming it.
    """
    x = _as_interval(x)
    k = _exponent(k)
    if k < 1:
        raise ValueError(f"the exponent k of an interval power must be an integer >= 1, "
                         f"got {k}")
    if k == 1:
        return _whole_where_nan(x.lo, x.hi)
    # |x|^k of the endpoints by repeated, outward-rounded products of non-negative numbers
    alo, ahi = np.abs(x.lo), np.abs(x.hi)
    plo, phi = alo, ahi
    dlo, dhi = alo, ahi
    with np.errstate(over="ignore", invalid="ignore"):
        for _ in range(k - 1):
            plo = widen_up(plo * alo)
            phi = widen_up(phi * ahi)
            # a lower bound that overflowed is at least the largest float (inf - inf is NaN)
            dlo = np.fmin(np.maximum(widen_down(dlo * alo), 0.0), _BIG)
            dhi = np.fmin(np.maximum(widen_down(dhi * ahi), 0.0), _BIG)
    if k % 2:
        # odd: monotone increasing
        lo = np.where(x.lo >= 0, dlo, -plo)
        hi = np.where(x.hi >= 0, phi, -dhi)
        return _whole_where_nan(lo, hi, x)
    straddle = (x.lo < 0) & (x.hi > 0)
    lo = np.where(straddle, 0.0, np.where(x.lo >= 0, dlo, dhi))
    hi = np.where(x.lo >= 0, phi, np.where(x.hi <= 0, plo, np.maximum(plo, phi)))
    return _whole_where_nan(lo, hi, x)


_BIG = float(np.finfo(float).max)


def exp(x) -> Interval:
    """``exp`` of an interval (libm error bound as in the module docstring)."""
    x = _as_interval(x)
    with np.errstate(over="ignore", invalid="ignore"):
        lo = np.exp(x.lo)
        hi = np.exp(x.hi)
        # an overflowed lower bound (inf - inf would be NaN): exp(lo) exceeds half the
        # largest float; a NaN argument stays NaN (np.maximum propagates it)
        lo = np.where(lo == np.inf, 0.5 * _BIG, np.maximum(widen_down(lo * (1 - _LIBM)), 0.0))
        return _whole_where_nan(lo, widen_up(hi * (1 + _LIBM)))


def sqrt(x) -> Interval:
    """``sqrt`` of an interval (the whole line if it reaches below 0: the module's NaN rule)."""
    x = _as_interval(x)
    with np.errstate(invalid="ignore"):
        lo = np.sqrt(x.lo)
        hi = np.sqrt(x.hi)
        # np.maximum keeps a NaN (sqrt of a negative bound): the result is then the whole line
        return _whole_where_nan(np.maximum(widen_down(lo), 0.0), widen_up(hi), x)


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
    # an infinite bound reaches both extrema: [-1, 1]; a NaN bound gives the whole line
    return _whole_where_nan(np.maximum(lo, -1.0), np.minimum(hi, 1.0), x)


def cos(x) -> Interval:
    """``cos`` of an interval (extrema at ``k pi``)."""
    return _trig(x, np.cos, 0.0)


def sin(x) -> Interval:
    """``sin`` of an interval (extrema at ``(k + 1/2) pi``)."""
    return _trig(x, np.sin, 0.5)
