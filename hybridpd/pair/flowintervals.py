"""The entire functions of the damped flow on intervals, and the kernels' backends.

Enclosures, on the outward-rounded :class:`~hybridpd.pair.intervals.Interval` of
:mod:`hybridpd.pair.intervals`, of the functions the closed forms of the pair's flow are
written with. The entire functions
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

from hybridpd.pair.intervals import (
    _EPS,
    _LIBM,
    Interval,
    _as_interval,
    _f,
    _whole_where_nan,
    cos,
    sin,
    sqrt,
    widen_down,
    widen_up,
)

__all__ = ["FLOAT_OPS", "arb_ops", "cu", "emq", "emq1", "emq2", "su", "su1", "su2"]


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
    with np.errstate(invalid="ignore"):
        return _whole_where_nan(widen_down(ya - ea), widen_up(yb + eb), x)


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
    return _whole_where_nan(lo, hi, x)


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
    return _whole_where_nan(widen_down(acc.lo - t), widen_up(acc.hi + t), x)


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
    # a NaN argument meets no part: the whole line, never the empty [inf, -inf]
    return _whole_where_nan(lo, hi, x)


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
    with np.errstate(invalid="ignore"):
        if m % 2:   # increasing
            return _whole_where_nan(widen_down(ya - ea), widen_up(yb + eb), x)
        return _whole_where_nan(widen_down(yb - eb), widen_up(ya + ea), x)


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
