"""Local Taylor polynomials of guard values along an exact LTI flow (numba kernels).

Evaluation with derivatives, rigorous absolute bounds, the first root of a polynomial with a
remainder bound, and the classification of tangencies (crossing or grazing). The event
locator in :mod:`hybridpd.hybrid.events` is built on these; the constants are shared.
"""
from __future__ import annotations

import numpy as np

from hybridpd._jit import njit

EV_NONE = 0
EV_CROSSING = 1
EV_GRAZING = 2
EV_START = 3
EV_NONFINITE = -1
EV_STEP_LIMIT = -2

K_DEFAULT = 20
THETA_DEFAULT = 1.0

_EPS = 2.220446049250313e-16
_MAX_INTERVALS = 4000    # bisection budget per guard and step (a transversal crossing needs ~10)
_STACK = 200             # left-first bisection never holds more than ~2 x depth intervals
_NSAMP = 128             # samples of the local polynomial when classifying a tangency
_OVERSHOOT = 0.5         # the series stays exact slightly beyond u = 1 (tail ~ 1.5^21 / 21!)


@njit(cache=True)
def _pval(p, m, u):
    v = p[m - 1]
    for k in range(m - 2, -1, -1):
        v = v * u + p[k]
    return v


@njit(cache=True)
def _pval_der(p, m, u):
    v = p[m - 1]
    d = 0.0
    for k in range(m - 2, -1, -1):
        d = d * u + v
        v = v * u + p[k]
    return v, d


@njit(cache=True)
def _abs_bounds(p, e, m, b):
    """``(E(b), sum k|p_k| b^(k-1), sum k(k-1)|p_k| b^(k-2))`` for ``b >= 0``."""
    E = 0.0
    D1 = 0.0
    M2 = 0.0
    bk = 1.0
    bk1 = 0.0
    bk2 = 0.0
    for k in range(m):
        ak = abs(p[k])
        E += e[k] * bk
        if k >= 1:
            D1 += k * ak * bk1
        if k >= 2:
            M2 += k * (k - 1) * ak * bk2
        bk2 = bk1
        bk1 = bk
        bk *= b
    return E, D1, M2


@njit(cache=True)
def _root_bracket(p, m, lo, hi):
    """First floating-point ``u`` in ``(lo, hi]`` with ``P(u) <= 0``; ``P(lo) > 0 >= P(hi)``.

    Safeguarded Newton (falls back to bisection whenever Newton leaves the bracket or stops
    halving it); the bracket always shrinks, so it ends at adjacent floating-point numbers.
    """
    x = lo + 0.5 * (hi - lo)
    dxold = hi - lo
    for _ in range(200):
        v, dv = _pval_der(p, m, x)
        if v > 0.0:
            lo = x
        else:
            hi = x
        if hi - lo <= 2.0 * _EPS * abs(hi):
            break
        xn = x
        if dv < 0.0 and v != 0.0:
            xn = x - v / dv
        if lo < xn < hi and abs(xn - x) < 0.5 * dxold:
            dxold = abs(xn - x)
            x = xn
        else:
            dxold = hi - lo
            x = lo + 0.5 * (hi - lo)
            if x <= lo or x >= hi:
                break
    return hi


@njit(cache=True)
def _first_root(p, e, m, u_hi, dmin, tail, sa, sb):
    """Left-first exclusion search for the first point of ``[0, u_hi]`` with ``f <= 0``.

    Returns ``(status, u)``: 0 nothing (``f > 0`` certified on ``[0, u_hi]``), 1 crossing at
    ``u`` (certified sign change on a monotone interval), 2 undecided minimal interval
    starting at ``u`` (to be classified).
    """
    cd = 4.0 * m * _EPS
    sa[0] = 0.0
    sb[0] = u_hi
    top = 1
    count = 0
    nstack = sa.shape[0]
    while top > 0:
        top -= 1
        a = sa[top]
        b = sb[top]
        count += 1
        Pa, dPa = _pval_der(p, m, a)
        E, D1, M2 = _abs_bounds(p, e, m, b)
        E += tail
        d = b - a
        M2 *= 1.0 + 1e-12
        lo = min(Pa, Pa + dPa * d - 0.5 * M2 * d * d) - E - cd * D1 * d
        if lo > 0.0:
            continue
        if Pa <= 0.0:
            return 1, a
        if dPa + M2 * d + cd * D1 < 0.0:
            Pb = _pval(p, m, b)
            if Pb <= 0.0:
                return 1, _root_bracket(p, m, a, b)
        if d <= dmin or count >= _MAX_INTERVALS or top + 2 > nstack:
            return 2, a
        mid = a + 0.5 * d
        if mid <= a or mid >= b:
            return 2, a
        sa[top] = mid
        sb[top] = b
        top += 1
        sa[top] = a
        sb[top] = mid
        top += 1
    return 0, u_hi


@njit(cache=True)
def _classify(p, e, m, a, v_max, tail, q):
    """Classify the undecided point ``a``: ``(EV_CROSSING | EV_GRAZING, u_event)``.

    Works on ``Q(v) = P(a + v)`` over a zone whose size is where some term of ``Q`` can exceed
    the error bound: a dip to ``-E`` is a crossing (first zero), otherwise the touch is a
    grazing located at the local minimum (refined on the sign of ``Q'``).
    """
    for i in range(m):
        q[i] = p[i]
    for i in range(m - 1):
        for k in range(m - 2, i - 1, -1):
            q[k] += a * q[k + 1]
    E, _, _ = _abs_bounds(p, e, m, min(a + max(v_max, 0.0), 1.0 + _OVERSHOOT))
    E += tail
    if v_max <= 0.0:
        return EV_GRAZING, a
    vs = np.inf
    for k in range(1, m):
        if q[k] != 0.0:
            vk = (E / abs(q[k])) ** (1.0 / k)
            vs = min(vs, vk)
    V = min(32.0 * vs, v_max)
    if not (V > 0.0):
        V = v_max
    qmin = _pval(q, m, 0.0)
    imin = 0
    izero = -1
    if qmin <= 0.0:
        izero = 0
    crossing = qmin <= -E
    if not crossing:
        for i in range(1, _NSAMP + 1):
            v = V * i / _NSAMP
            Qi = _pval(q, m, v)
            if Qi <= 0.0 and izero < 0:
                izero = i
            if Qi <= -E:
                crossing = True
                break
            if Qi < qmin:
                qmin = Qi
                imin = i
            elif Qi > E and i > imin:
                break
    if crossing:
        if izero <= 0:
            return EV_CROSSING, a
        lo = V * (izero - 1) / _NSAMP
        hi = V * izero / _NSAMP
        return EV_CROSSING, a + _root_bracket(q, m, lo, hi)
    lo = V * max(imin - 1, 0) / _NSAMP
    hi = V * min(imin + 1, _NSAMP) / _NSAMP
    for _ in range(200):
        mid = lo + 0.5 * (hi - lo)
        if mid <= lo or mid >= hi:
            break
        _, dq = _pval_der(q, m, mid)
        if dq < 0.0:
            lo = mid
        else:
            hi = mid
    _, dq0 = _pval_der(q, m, lo)
    return EV_GRAZING, a + (lo if dq0 >= 0.0 else hi)


@njit(cache=True)
def _series(w, Ah, Kp1, u, out, term, tmp):
    """``out = sum_k (Ah u)^k w / k!`` (the exact flow over ``u h``)."""
    N1 = w.shape[0]
    for i in range(N1):
        out[i] = w[i]
        term[i] = w[i]
    for k in range(1, Kp1):
        f = u / k
        for i in range(N1):
            s = 0.0
            for j in range(N1):
                s += Ah[i, j] * term[j]
            tmp[i] = s * f
        for i in range(N1):
            term[i] = tmp[i]
            out[i] += tmp[i]
    out[N1 - 1] = 1.0


@njit(cache=True)
def _matvec(M, x, out):
    n = M.shape[0]
    for i in range(n):
        s = 0.0
        for j in range(M.shape[1]):
            s += M[i, j] * x[j]
        out[i] = s


@njit(cache=True)
def _scaled_norm(w, dinv):
    s = 0.0
    for i in range(w.shape[0]):
        v = abs(w[i] * dinv[i])
        if not (v <= s):  # also propagates NaN
            s = v
    return s
