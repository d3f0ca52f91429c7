"""Compiled loops of the interval layer's ``+``, ``-``, ``*`` (one pass over the bounds).

The same arithmetic as the NumPy path of :class:`hybridpd.pair.intervals.Interval`: IEEE
round-to-nearest products and sums (numba compiles without fast-math, so nothing is
reassociated or contracted), each bound then moved outward by ``2^-50 |r| + 2^-1022``. A
NaN bound (``0 * inf``, ``inf - inf``) becomes the whole line ``[-inf, inf]``, which encloses
any real value. Operands are 1-D arrays of one length, or a scalar second operand.
"""
from __future__ import annotations

import math

from hybridpd._jit import njit

_REL = 2.0**-50
_TINY = 2.0**-1022


@njit(cache=True)
def _out(lo, hi, i, a, b):
    if math.isnan(a) or math.isnan(b):
        lo[i] = -math.inf
        hi[i] = math.inf
    else:
        lo[i] = a - (abs(a) * _REL + _TINY)
        hi[i] = b + (abs(b) * _REL + _TINY)


@njit(cache=True)
def _min4(p, q, r, s):
    return min(min(p, q), min(r, s))


@njit(cache=True)
def _max4(p, q, r, s):
    return max(max(p, q), max(r, s))


@njit(cache=True)
def _nan4(p, q, r, s):
    return math.isnan(p) or math.isnan(q) or math.isnan(r) or math.isnan(s)


@njit(cache=True)
def mul(alo, ahi, blo, bhi, lo, hi):
    """``[lo, hi] = [alo, ahi] * [blo, bhi]`` elementwise."""
    for i in range(lo.size):
        p = alo[i] * blo[i]
        q = alo[i] * bhi[i]
        r = ahi[i] * blo[i]
        s = ahi[i] * bhi[i]
        if _nan4(p, q, r, s):
            lo[i] = -math.inf
            hi[i] = math.inf
        else:
            _out(lo, hi, i, _min4(p, q, r, s), _max4(p, q, r, s))


@njit(cache=True)
def mul_s(alo, ahi, b1, b2, lo, hi):
    """``[lo, hi] = [alo, ahi] * [b1, b2]`` with a scalar interval ``[b1, b2]``."""
    for i in range(lo.size):
        p = alo[i] * b1
        q = alo[i] * b2
        r = ahi[i] * b1
        s = ahi[i] * b2
        if _nan4(p, q, r, s):
            lo[i] = -math.inf
            hi[i] = math.inf
        else:
            _out(lo, hi, i, _min4(p, q, r, s), _max4(p, q, r, s))


@njit(cache=True)
def add(alo, ahi, blo, bhi, lo, hi):
    """``[lo, hi] = [alo, ahi] + [blo, bhi]``."""
    for i in range(lo.size):
        _out(lo, hi, i, alo[i] + blo[i], ahi[i] + bhi[i])


@njit(cache=True)
def add_s(alo, ahi, b1, b2, lo, hi):
    """``[lo, hi] = [alo, ahi] + [b1, b2]`` (scalar second operand)."""
    for i in range(lo.size):
        _out(lo, hi, i, alo[i] + b1, ahi[i] + b2)


@njit(cache=True)
def sub(alo, ahi, blo, bhi, lo, hi):
    """``[lo, hi] = [alo, ahi] - [blo, bhi]``."""
    for i in range(lo.size):
        _out(lo, hi, i, alo[i] - bhi[i], ahi[i] - blo[i])


@njit(cache=True)
def sub_s(alo, ahi, b1, b2, lo, hi):
    """``[lo, hi] = [alo, ahi] - [b1, b2]`` (scalar second operand)."""
    for i in range(lo.size):
        _out(lo, hi, i, alo[i] - b2, ahi[i] - b1)
