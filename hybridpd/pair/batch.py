"""Batch engine: many impact-pair trajectories at once, closed-form flows, compiled with numba.

This is the fast path for the PD impact pair (both feedback cases). It never steps an ODE:
between impacts it evaluates the closed-form flight and locates the next wall contact with a
*guaranteed safe-step* root finder. At flight time ``tau`` it evaluates the gaps
``g+ = L - z3`` and ``g- = z3 + L`` with their derivatives, and a rigorous bound ``M`` of
``|z3''|`` over ``[tau, tau + Delta]``; since ``g(tau + s) >= g + g' s - M s^2 / 2`` there, no
contact can happen before the positive root of that quadratic, which is the next step. The
iteration converges quadratically to a transversal crossing (it is a damped Newton method
from the left) and geometrically to a tangential touch (grazing), and cannot jump over a
pair of crossings however close. Right after an impact the state sits on the wall with
``g = 0, g' >= 0``; the same bound (or its cubic version when ``g' = 0``) gives a step that
provably stays off the wall, so an impact never re-triggers itself, while a genuine
re-impact is found.

Closed forms (``m2 = 1`` not assumed; ``alpha = kv / (2 m2)``, ``D = alpha^2 - kp / m2``):

* collocated: ``x2 = xd + f`` with the tracking error
  ``f(t) = exp(-alpha t) (f0 Ch(D, t) + (f0' + alpha f0) Sh(D, t))``, where
  ``Ch = cosh(sqrt(D) t)`` and ``Sh = sinh(sqrt(D) t) / sqrt(D)`` are entire in ``D``
  (evaluated by cos/sin, cosh/sinh or a series), so nothing changes branch at critical
  damping ``kv^2 = 4 kp m2``;
* non-collocated: ``x2'' = (kp/m2 - w^2) pc - (kv w / m2) ps - (kv/m2) y1 - (kp/m2) x1`` with
  ``x1`` affine in ``t``: sinusoids plus a cubic.

State on the Poincare section (paper (21)): pre-impact at ``z3 = +L``, ``z4 > 0``, coordinates
``s = (phi, z1, z2, z4)`` with ``phi = t mod T``, ``z1 = x2``, ``z2 = y2``, ``z4 = y1 - y2``.

The parameters travel as one float64 array ``params`` (:meth:`PairParams.packed
<hybridpd.pair.params.PairParams.packed>`, or :func:`pack_params` for the kernels that need
only some of them), read by the named index constants of :mod:`hybridpd.pair.params`
(``params[P.KP]``, ...); ``case`` is 0 (collocated) or 1 (non-collocated).

Zeno and sticking: when the rebound speed of a wall contact falls below the velocity
tolerance (impacts accumulating geometrically, or a plastic contact) while the force presses
the masses together, the masses move together in closed form, ``(m1 + m2) x'' = U``, until
the contact force changes sign (located like a contact), then fly apart again.

Labels returned by the mapper (:data:`LABELS`): 0 converged, 1 not converged, 2 diverged
(left a bounded region or non-finite), 3 Zeno/sticking (still stuck on a wall after 50
periods), 4 unresolved (an iteration bound was hit inside one flight).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from hybridpd._jit import njit
from hybridpd._phase import wrap_phase_kernel
from hybridpd.pair import params as P

__all__ = [
    "KIND_GRAZING",
    "KIND_IMPACT",
    "KIND_STICKING",
    "LABELS",
    "N_REC",
    "REC_KIND",
    "REC_SPEED",
    "REC_STICK_TIME",
    "REC_T",
    "REC_TAU",
    "REC_WALL",
    "REC_X1",
    "REC_X2",
    "REC_Y1",
    "REC_Y2",
    "STATUS_IMPACT",
    "STATUS_NONFINITE",
    "STATUS_STICK",
    "STATUS_TIMEOUT",
    "STATUS_UNRESOLVED",
    "Flight",
    "Flights",
    "impact_map",
    "iterate_map",
    "map_labels",
    "next_impact",
    "pack_params",
    "trace_once",
]

LABELS = ("converged", "not_converged", "diverged", "zeno_sticking", "unresolved")

STATUS_IMPACT = 0       # a wall contact was located
STATUS_TIMEOUT = 1      # no contact before the time horizon
STATUS_STICK = 2        # zero relative velocity with the force pressing into the wall
STATUS_UNRESOLVED = 3   # iteration bound hit (pathological tangency)
STATUS_NONFINITE = 4

_MAX_SAFE_STEPS = 20000

# Columns of the record of one application of P (:func:`trace_once`), one row per contact.
REC_WALL = 0        # wall hit (+1 or -1); NaN for a flight that ended without a contact
REC_TAU = 1         # flight time up to the contact
REC_SPEED = 2       # approach speed
REC_KIND = 3        # KIND_IMPACT, KIND_GRAZING or KIND_STICKING
REC_STICK_TIME = 4  # time spent sticking after the contact
REC_T = 5           # start of the flight: time, then the state x1, y1, x2, y2
REC_X1 = 6
REC_Y1 = 7
REC_X2 = 8
REC_Y2 = 9
#: Columns of a record.
N_REC = 10
KIND_IMPACT = 0     # kinds of contact in the column REC_KIND
KIND_GRAZING = 1
KIND_STICKING = 2


class Flight(NamedTuple):
    """Where a flight starts, read by name in the kernels: the time ``t0`` (the reference
    phase there is ``w t0``) and the mechanical state ``x1, y1, x2, y2`` (lengths, speeds)
    with ``|x1 - x2| <= L``."""

    t0: float
    x1: float
    y1: float
    x2: float
    y2: float


class Flights(NamedTuple):
    """Many flights (arrays of shape ``(N,)``): the fields of :class:`Flight` and each
    flight's duration ``tau`` (time)."""

    t0: np.ndarray
    x1: np.ndarray
    y1: np.ndarray
    x2: np.ndarray
    y2: np.ndarray
    tau: np.ndarray


@njit(cache=True)
def flight_at(f, i):
    """Flight ``i`` of the :class:`Flights` ``f``."""
    return Flight(f.t0[i], f.x1[i], f.y1[i], f.x2[i], f.y2[i])


def pack_params(kp, kv, m2, mu, e, L, w, xm) -> np.ndarray:
    """The ``params`` array the kernels take, laid out by the index constants of
    :mod:`hybridpd.pair.params`, without validation (kernels that read only some entries
    get placeholders for the others; :meth:`PairParams.packed
    <hybridpd.pair.params.PairParams.packed>` packs validated parameters).

    The arguments broadcast: arrays of shape ``S`` give one row per point, shape
    ``S + (N_PACKED,)``; ``w`` is the reference frequency ``omega``.

    Examples
    --------
    >>> from hybridpd.pair import params as P
    >>> a = pack_params(kp=10, kv=20, m2=1, mu=0.1, e=0.5, L=0.75, w=5, xm=1.2)
    >>> float(a[P.KV]), float(a[P.OMEGA])
    (20.0, 5.0)
    >>> pack_params(kp=[1, 2, 3], kv=20, m2=1, mu=0.1, e=0.5, L=0.75, w=5, xm=1.2)[:, P.KP]
    array([1., 2., 3.])
    """
    named = {P.KP: kp, P.KV: kv, P.M2: m2, P.MU: mu, P.E: e, P.L: L, P.OMEGA: w, P.XM: xm}
    cols = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in named.values()))
    out = np.empty(cols[0].shape + (P.N_PACKED,), dtype=np.float64)
    for index, col in zip(named, cols):
        out[..., index] = col
    return out


@njit(cache=True)
def _ech(alpha, D, t):
    """Return ``exp(-alpha t) Ch(D, t)`` and ``exp(-alpha t) Sh(D, t)`` without overflow."""
    u = D * t * t
    ea = math.exp(-alpha * t)
    if abs(u) < 1e-2:
        # Series in u = D t^2: Ch = sum u^k/(2k)!, Sh = t sum u^k/(2k+1)!.
        ch = 1.0
        sh = 1.0
        term_c = 1.0
        term_s = 1.0
        for k in range(1, 9):
            term_c *= u / ((2 * k - 1) * (2 * k))
            term_s *= u / ((2 * k) * (2 * k + 1))
            ch += term_c
            sh += term_s
        return ea * ch, ea * sh * t
    if u > 0.0:
        b = math.sqrt(D)
        # exp(-alpha t) cosh(b t) with b < alpha for kp > 0: combine exponents first.
        e1 = math.exp((b - alpha) * t)
        e2 = math.exp(-(b + alpha) * t)
        return 0.5 * (e1 + e2), 0.5 * (e1 - e2) / b
    b = math.sqrt(-D)
    return ea * math.cos(b * t), ea * math.sin(b * t) / b


@njit(cache=True)
def _eval(params, case, fl, tau, dmax):
    """State at ``tau`` of the flight ``fl`` (a :class:`Flight`) plus derivatives and bounds
    valid on ``[tau, tau + dmax]``.

    Returns ``(x1, y1, x2, y2, a2, a3, M2, M3)``: ``a2 = x2''(tau)``, ``a3 = x2'''(tau)``,
    ``M2 >= sup |x2''|`` and ``M3 >= sup |x2'''|`` on the interval (``x1'' = 0``, so these bound
    the gap's second and third derivatives).
    """
    kp, kv, m2, w, xm = params[P.KP], params[P.KV], params[P.M2], params[P.OMEGA], params[P.XM]
    phi0, x10, y10, x20, y20 = fl.t0, fl.x1, fl.y1, fl.x2, fl.y2
    x1 = x10 + y10 * tau
    y1 = y10
    th = w * (phi0 + tau)
    c = math.cos(th)
    s = math.sin(th)
    if case == 0:
        alpha = 0.5 * kv / m2
        D = alpha * alpha - kp / m2
        c0 = math.cos(w * phi0)
        s0 = math.sin(w * phi0)
        f0 = x20 - xm * c0
        fd0 = y20 + xm * w * s0
        ec, es = _ech(alpha, D, tau)
        a = f0
        b = fd0 + alpha * f0
        f = a * ec + b * es
        # (a, b) -> (b - alpha a, a D - alpha b) differentiates exp(-alpha t)(a Ch + b Sh).
        a1 = b - alpha * a
        b1 = a * D - alpha * b
        fd = a1 * ec + b1 * es
        a2c = b1 - alpha * a1
        b2c = a1 * D - alpha * b1
        fdd = a2c * ec + b2c * es
        fddd = -(kv * fdd + kp * fd) / m2
        fdddd = -(kv * fddd + kp * fdd) / m2
        x2 = xm * c + f
        y2 = -xm * w * s + fd
        a2 = -xm * w * w * c + fdd
        a3 = xm * w * w * w * s + fddd
        # sup over [0, dmax] of exp(-alpha s)|Ch| <= 1 and of exp(-alpha s)|Sh| <= s.
        M2 = xm * w * w + abs(fdd) + abs(fddd + alpha * fdd) * dmax
        M3 = xm * w * w * w + abs(fddd) + abs(fdddd + alpha * fddd) * dmax
        return x1, y1, x2, y2, a2, a3, M2, M3
    pc = xm * c
    ps = xm * s
    pc0 = xm * math.cos(w * phi0)
    ps0 = xm * math.sin(w * phi0)
    Ac = kp / m2 - w * w
    As = -kv * w / m2
    # particular solution of x2'' = Ac pc + As ps is -(Ac pc + As ps) / w^2
    sp = -(Ac * pc + As * ps) / (w * w)
    sp0 = -(Ac * pc0 + As * ps0) / (w * w)
    dsp = -(-Ac * ps + As * pc) / w
    dsp0 = -(-Ac * ps0 + As * pc0) / w
    kvm = kv / m2
    kpm = kp / m2
    t2 = tau * tau
    x2 = (x20 + y20 * tau + (sp - sp0 - dsp0 * tau) - 0.5 * kvm * y10 * t2
          - kpm * (0.5 * x10 * t2 + y10 * t2 * tau / 6.0))
    y2 = y20 + (dsp - dsp0) - kvm * y10 * tau - kpm * (x10 * tau + 0.5 * y10 * t2)
    a2 = Ac * pc + As * ps - kvm * y10 - kpm * x1
    a3 = w * (-Ac * ps + As * pc) - kpm * y10
    amp = xm * math.sqrt(Ac * Ac + As * As)
    x1end = x1 + y10 * dmax
    M2 = amp + kvm * abs(y10) + kpm * max(abs(x1), abs(x1end))
    M3 = amp * w + kpm * abs(y10)
    return x1, y1, x2, y2, a2, a3, M2, M3


@njit(cache=True)
def turning_margins(params, case, fl, tau, nsamp, approached=False):
    """The two smallest ``(L - |z3|)/L`` at interior turning points of ``z3`` on ``(0, tau)``.

    Turning points are sign changes of ``z4 = y1 - y2`` on a uniform grid of ``nsamp``
    intervals, refined by bisection, along the flight ``fl`` (a :class:`Flight`). Returns
    ``(m, m2)``, each 1 when there is no such turning point; where both vanish two turning
    points graze at once. With ``approached`` a maximum of ``z3`` is
    measured to ``+L`` and a minimum to ``-L`` only (a small hop away from the wall just
    left is then not a near-grazing).
    """
    L = params[P.L]
    m = 1.0
    m2 = 1.0
    h = tau / nsamp
    prev = 0.0
    for k in range(1, nsamp):
        s = k * h
        r = _eval(params, case, fl, s, 0.0)
        z4 = r[1] - r[3]
        if k > 1 and z4 * prev < 0.0:
            a = s - h
            b = s
            fa = prev
            for _ in range(64):
                c = 0.5 * (a + b)
                if c <= a or c >= b:
                    break
                rc = _eval(params, case, fl, c, 0.0)
                fc = rc[1] - rc[3]
                if fc * fa > 0.0:
                    a = c
                    fa = fc
                else:
                    b = c
            rc = _eval(params, case, fl, 0.5 * (a + b), 0.0)
            z3 = rc[0] - rc[2]
            if not approached:
                mk = (L - abs(z3)) / L
            elif prev > 0.0:
                mk = (L - z3) / L      # z4: + -> -, a maximum of z3, towards +L
            else:
                mk = (z3 + L) / L      # a minimum of z3, towards -L
            if mk < m:
                m2 = m
                m = mk
            elif mk < m2:
                m2 = mk
        prev = z4
    return m, m2

@njit(cache=True)
def _safe_step(g, gd, gdd, M2, M3, dmax, ztol):
    """Largest step ``<= dmax`` on which ``g`` provably stays positive (0 if none is proven).

    ``g, gd, gdd`` are the gap and its first two derivatives, ``M2`` and ``M3`` bounds of the
    gap's second and third derivatives ahead, ``ztol`` the velocity tolerance below which a
    start on the wall counts as tangential.
    """
    best = 0.0
    if g > 0.0 or gd > 0.0:
        # quadratic lower bound g + gd s - M2 s^2 / 2
        if M2 > 0.0:
            disc = gd * gd + 2.0 * M2 * max(g, 0.0)
            best = (gd + math.sqrt(disc)) / M2
            if g <= 0.0:
                # leaving the wall: stop at the bound's maximum, where it is gd^2 / (2 M2) > 0,
                # so the next point is provably off the wall by more than the tolerance.
                best = gd / M2
        elif gd < 0.0:
            best = -g / gd
        else:
            best = dmax
    if gdd > 0.0 and gd >= -ztol and M3 > 0.0:
        # tangential departure: g + gd s + gdd s^2/2 - M3 s^3/6 >= gdd s^2/4 > 0 for
        # s <= 3 gdd / (2 M3) (|g| and |gd| are at rounding level there)
        best = max(best, 1.5 * gdd / M3)
    return min(best, dmax)


@njit(cache=True)
def _contact(g, rel, gdd, tau, tol, ztol):
    """Classify a wall whose gap ``g <= tol``: 0 no event, 1 impact, 2 grazing, 3 sticking.

    ``rel`` is the approach speed (``-g'``), ``gdd = g''``. At ``tau = 0`` (start on the wall)
    an approach faster than ``ztol`` is an immediate impact; a tangential start with the force
    pressing into the wall is sticking; otherwise the mass is leaving and nothing fires. Later
    on, the safe steps guarantee the wall was not reached before, so reaching the tolerance is
    a contact: an impact, or grazing when the approach speed is below ``ztol`` (a rebound that
    could not rise above the gap tolerance).
    """
    if tau == 0.0:
        if rel > ztol:
            return 1
        if rel >= -ztol and gdd <= 0.0:
            return 3
        return 0
    if rel > ztol:
        return 1
    return 2


@njit(cache=True)
def next_impact(params, case, fl, t_max, tol):
    """Locate the first wall contact of the flight ``fl``.

    Parameters
    ----------
    params : float64[8]
        ``[kp, kv, m2, mu, e, L, w, xm]``.
    case : int
        0 collocated, 1 non-collocated.
    fl : Flight
        Start time ``t0`` (any real; the reference phase is ``w * t0``) and the post-impact
        (or initial) mechanical state ``x1, y1, x2, y2``, ``|x1 - x2| <= L``.
    t_max : float
        Horizon: give up (status ``STATUS_TIMEOUT``) beyond this flight time.
    tol : float
        Gap tolerance (length) below which a contact is declared. The matching velocity
        tolerance is ``ztol = sqrt(2 tol M2)``, ``M2`` the local bound of ``|z3''|``.

    Returns
    -------
    status, tau, wall, x1, y1, x2, y2, grazing
        ``STATUS_*``, the flight time, the wall (+1/-1), the state at the contact and whether
        the contact is tangential (relative speed below ``ztol``; no velocity jump then).
    """
    L = params[P.L]
    w = params[P.OMEGA]
    dmax = 0.5 * math.pi / w
    tau = 0.0
    for _ in range(_MAX_SAFE_STEPS):
        X1, Y1, X2, Y2, a2, _a3, M2, M3 = _eval(params, case, fl, tau, dmax)
        z3 = X1 - X2
        z4 = Y1 - Y2
        if not (math.isfinite(z3) and math.isfinite(z4) and math.isfinite(M2)):
            return STATUS_NONFINITE, tau, 0, X1, Y1, X2, Y2, False
        ztol = math.sqrt(2.0 * tol * M2)
        gp = L - z3          # right wall: g' = -z4, g'' = x2'' = a2
        gm = z3 + L          # left wall:  g' = z4,  g'' = -a2
        for wall in (1, -1):
            g = gp if wall == 1 else gm
            if g <= tol:
                kind = _contact(g, wall * z4, wall * a2, tau, tol, ztol)
                if kind == 3:
                    return STATUS_STICK, tau, wall, X1, Y1, X2, Y2, True
                if kind > 0:
                    return STATUS_IMPACT, tau, wall, X1, Y1, X2, Y2, kind == 2
        step = min(_safe_step(gp, -z4, a2, M2, M3, dmax, ztol),
                   _safe_step(gm, z4, -a2, M2, M3, dmax, ztol))
        if not step > 0.0:
            return STATUS_UNRESOLVED, tau, 0, X1, Y1, X2, Y2, False
        tau += step
        if tau > t_max:
            return STATUS_TIMEOUT, t_max, 0, X1, Y1, X2, Y2, False
    return STATUS_UNRESOLVED, tau, 0, X1, Y1, X2, Y2, False


@njit(cache=True)
def _stick_eval(params, case, phi0, x20, y0, wall, tau, dmax):
    """Stuck motion at ``wall`` from ``(x2, y)`` at time ``phi0``: state and release function.

    While stuck, ``(m1 + m2) x2'' = U`` with ``x1 = x2 + wall L`` and ``y1 = y2``. Writing
    ``x2 = xd + a pc + b ps + c + h`` (a particular solution of the sinusoidal forcing
    ``-m1 xd''``, the constant ``c = -wall L`` in the non-collocated loop, and a homogeneous
    ``h`` with mass ``M = m1 + m2``) gives a closed form. Returns ``(x2, y, acc, jerk, bound)``
    with the acceleration and jerk of ``x2`` and a bound on its fourth derivative over
    ``[tau, tau + dmax]``.
    """
    kp, kv, m2, mu = params[P.KP], params[P.KV], params[P.M2], params[P.MU]
    L, w, xm = params[P.L], params[P.OMEGA], params[P.XM]
    M = m2 * (1.0 + mu)
    m1 = mu * m2
    K = kp - M * w * w
    det = K * K + (kv * w) ** 2
    a = K * m1 * w * w / det
    b = kv * w * m1 * w * w / det
    coff = -wall * L if case == 1 else 0.0
    alpha = 0.5 * kv / M
    D = alpha * alpha - kp / M
    c0 = xm * math.cos(w * phi0)
    s0 = xm * math.sin(w * phi0)
    h0 = x20 - ((1.0 + a) * c0 + b * s0 + coff)
    hd0 = y0 - ((1.0 + a) * (-w * s0) + b * w * c0)
    ec, es = _ech(alpha, D, tau)
    A0 = h0
    B0 = hd0 + alpha * h0
    A1 = B0 - alpha * A0
    B1 = A0 * D - alpha * B0
    h = A0 * ec + B0 * es
    hd = A1 * ec + B1 * es
    h2 = -(kv * hd + kp * h) / M
    h3 = -(kv * h2 + kp * hd) / M
    h4 = -(kv * h3 + kp * h2) / M
    h5 = -(kv * h4 + kp * h3) / M
    th = w * (phi0 + tau)
    pc = xm * math.cos(th)
    ps = xm * math.sin(th)
    x2 = (1.0 + a) * pc + b * ps + coff + h
    y = -(1.0 + a) * w * ps + b * w * pc + hd
    acc = -w * w * ((1.0 + a) * pc + b * ps) + h2
    jerk = -w * w * (-(1.0 + a) * w * ps + b * w * pc) + h3
    amp = xm * math.sqrt((1.0 + a) ** 2 + b * b)
    bound = amp * w ** 4 + abs(h4) + abs(h5 + alpha * h4) * dmax
    return x2, y, acc, jerk, bound


@njit(cache=True)
def stick_release(params, case, phi0, x2, y, wall, t_max, tol):
    """Time the masses stay stuck on ``wall`` from time ``phi0``, and the state at release.

    Stuck on the right wall the slot can only push ``m1`` to the left, which holds while
    ``U <= 0``; on the left wall while ``U >= 0``. The release (``wall * x2''`` turning
    positive) is located with the same guaranteed safe steps as contacts, then the motion is
    advanced by ``1e-9 T`` (doubling if needed) past it, so that the free flight starts with
    the masses separating.

    Returns ``status, tau, x2, y`` (``STATUS_IMPACT`` on release, ``STATUS_TIMEOUT`` if still
    stuck at ``t_max``).
    """
    w = params[P.OMEGA]
    T = 2.0 * math.pi / w
    dmax = 0.25 * T
    scale = 1.0 + params[P.XM] * w * w + params[P.KP] * params[P.L] / params[P.M2]
    gtol = tol * scale
    tau = 0.0
    for _ in range(_MAX_SAFE_STEPS):
        X2, Y, acc, jerk, bound = _stick_eval(params, case, phi0, x2, y, wall, tau, dmax)
        if not (math.isfinite(X2) and math.isfinite(Y) and math.isfinite(bound)):
            return STATUS_NONFINITE, tau, X2, Y
        g = -wall * acc          # >= 0 while the contact force keeps its sign
        gd = -wall * jerk
        if g <= gtol and (tau > 0.0 or gd <= 0.0):
            nudge = 1e-9 * T
            for _k in range(60):
                X2, Y, acc, jerk, bound = _stick_eval(params, case, phi0, x2, y, wall,
                                                      tau + nudge, dmax)
                if -wall * acc < 0.0:
                    break
                nudge *= 2.0
            return STATUS_IMPACT, tau + nudge, X2, Y
        step = _safe_step(g, gd, 0.0, bound, 0.0, dmax, 0.0)
        if not step > 0.0:
            return STATUS_UNRESOLVED, tau, X2, Y
        tau += step
        if tau > t_max:
            X2, Y, acc, jerk, bound = _stick_eval(params, case, phi0, x2, y, wall, t_max, dmax)
            return STATUS_TIMEOUT, t_max, X2, Y
    return STATUS_UNRESOLVED, tau, x2, y


@njit(cache=True)
def _impact_velocities(mu, e, y1, y2):
    """Newton's law (2) on the velocities."""
    n1 = ((mu - e) * y1 + (1.0 + e) * y2) / (1.0 + mu)
    n2 = ((1.0 + e) * mu * y1 + (1.0 - mu * e) * y2) / (1.0 + mu)
    return n1, n2


@njit(cache=True)
def _record(row, st, tau, wall, rel, graze, stick):
    """Fill the record row of one flight (see :func:`_map_once`)."""
    if st == STATUS_IMPACT or (st == STATUS_STICK and stick):
        row[REC_WALL] = wall
        row[REC_TAU] = tau
        row[REC_SPEED] = abs(rel) if st == STATUS_STICK else max(wall * rel, 0.0)
        row[REC_KIND] = KIND_STICKING if st == STATUS_STICK else (
            KIND_GRAZING if graze else KIND_IMPACT)
        row[REC_STICK_TIME] = 0.0
    else:
        row[REC_WALL] = np.nan


@njit(cache=True)
def trace_once(params, case, s, tol=1e-13, max_impacts=1000, stick=True):
    """One application of P from ``s`` with its record (:func:`_map_once`).

    Returns ``(image[4], status, impacts, record[rows, N_REC])``, the record's columns
    named by the constants ``REC_WALL``, ``REC_TAU``, ... of this module.
    """
    out = np.full(4, np.nan)
    rec = np.full((max_impacts, N_REC), np.nan)
    st, k = _map_once(params, case, s, out, tol, max_impacts, stick, rec)
    n = 0
    while n < max_impacts and not np.isnan(rec[n, REC_WALL]):
        n += 1
    return out, st, k, rec[:n].copy()


@njit(cache=True)
def _map_once(params, case, s, out, tol, max_impacts, stick, rec):
    """One application of P from section point ``s`` into ``out``; returns (status, impacts).

    ``s = (phi, z1, z2, z4)``; the trajectory may hit the walls in any order; P returns the
    first pre-impact state at the right wall after the initial impact. With ``stick`` the
    trajectory continues through sticking phases (Zeno accumulation); otherwise an
    accumulation ends the map with status ``10 + STATUS_STICK``.

    Row ``k`` of ``rec`` (when it has one; shape ``(rows, 10)``) records contact ``k``:
    ``(wall, tau, approach speed, kind, stick time, t, x1, y1, x2, y2)`` with kind 0 impact,
    1 grazing touch, 2 sticking, and the state ``t, x1 .. y2`` where its flight started;
    ``wall`` is NaN for a flight that ended without a contact.
    """
    mu, e, L, w = params[P.MU], params[P.E], params[P.L], params[P.OMEGA]
    T = 2.0 * math.pi / w
    phi = s[0]
    x2 = s[1]
    y2 = s[2]
    x1 = x2 + L
    y1 = y2 + s[3]
    y1, y2 = _impact_velocities(mu, e, y1, y2)
    t = phi
    for k in range(max_impacts):
        if k < rec.shape[0]:
            rec[k, REC_T] = t
            rec[k, REC_X1] = x1
            rec[k, REC_Y1] = y1
            rec[k, REC_X2] = x2
            rec[k, REC_Y2] = y2
        st, tau, wall, x1, y1, x2, y2, graze = next_impact(
            params, case, Flight(t, x1, y1, x2, y2), 50.0 * T, tol)
        if k < rec.shape[0]:
            _record(rec[k], st, tau, wall, y1 - y2, graze, stick)
        if st == STATUS_STICK and stick:
            # impacts accumulated (or a plastic contact under a pressing force): the masses
            # move together from the momentum-conserving contact state until the contact
            # force changes sign
            t += tau
            yc = (mu * y1 + y2) / (1.0 + mu)
            st2, ts, x2, yc = stick_release(params, case, t, x2, yc, wall, 50.0 * T, tol)
            if k < rec.shape[0]:
                rec[k, REC_STICK_TIME] = ts
            if st2 != STATUS_IMPACT:
                out[0] = t
                out[1] = x2
                out[2] = yc
                out[3] = 0.0
                return (STATUS_STICK if st2 == STATUS_TIMEOUT else st2) + 10, k
            t += ts
            x1 = x2 + wall * L
            y1 = yc
            y2 = yc
            continue
        if st != STATUS_IMPACT:
            out[0] = t
            out[1] = x2
            out[2] = y2
            out[3] = y1 - y2
            return st + 10, k
        t += tau
        # snap onto the wall (the root is located to tol) so the next flight starts on it
        x1 = x2 + wall * L
        if wall == 1:
            out[0] = t - T * math.floor(t / T)
            out[1] = x2
            out[2] = y2
            # a tangential touch (grazing) lies on the closure z4 = 0 of the section
            out[3] = max(y1 - y2, 0.0)
            return STATUS_IMPACT, k + 1
        if not graze:
            y1, y2 = _impact_velocities(mu, e, y1, y2)
    return STATUS_UNRESOLVED + 10, max_impacts


@njit(cache=True)
def impact_map(params, case, S, tol=1e-13, max_impacts=1000, stick=True):
    """Apply the impact map P to many section points.

    Parameters
    ----------
    params : float64[8]
    case : int
    S : float64[N, 4]
        Section points ``(phi, z1, z2, z4)``, pre-impact at ``z3 = +L`` with ``z4 > 0``.

    Returns
    -------
    out : float64[N, 4]
        ``P(S)`` (``phi`` reduced mod T).
    status : int64[N]
        0 when P is defined; otherwise ``10 + STATUS_*`` of the flight that failed.
    n_impacts : int64[N]
        Impacts taken (2 on a simple orbit).
    """
    N = S.shape[0]
    out = np.empty((N, 4))
    status = np.empty(N, dtype=np.int64)
    nimp = np.empty(N, dtype=np.int64)
    norec = np.empty((0, N_REC))
    for i in range(N):
        st, k = _map_once(params, case, S[i], out[i], tol, max_impacts, stick, norec)
        status[i] = st
        nimp[i] = k
    return out, status, nimp


@njit(cache=True)
def iterate_map(params, case, s0, n_iter, tol=1e-13, max_impacts=1000, stick=True):
    """Iterate P ``n_iter`` times from ``s0``; returns ``(orbit[n_iter + 1, 4], n_done, status)``."""
    orbit = np.full((n_iter + 1, 4), np.nan)
    orbit[0] = s0
    cur = s0.copy()
    nxt = np.empty(4)
    norec = np.empty((0, N_REC))
    for i in range(n_iter):
        st, _k = _map_once(params, case, cur, nxt, tol, max_impacts, stick, norec)
        if st != 0:
            return orbit, i, st
        orbit[i + 1] = nxt
        cur[:] = nxt
    return orbit, n_iter, 0


@njit(cache=True)
def _criterion(cur, fixed, T):
    """The paper's squared distance in (x1, y1, y2, phi): x1 = z1 + L, y1 = z2 + z4, y2 = z2."""
    dphi = wrap_phase_kernel(cur[0] - fixed[0], T)
    dx1 = cur[1] - fixed[1]
    dy1 = (cur[2] + cur[3]) - (fixed[2] + fixed[3])
    dy2 = cur[2] - fixed[2]
    return dx1 * dx1 + dy1 * dy1 + dy2 * dy2 + dphi * dphi


_CYCLE_MAX = 32


@njit(cache=True)
def map_labels(params, case, S, spec, tol=1e-13, max_impacts=1000, stick=True):
    """Label section points by where P takes them (the basin mapper's kernel).

    ``spec`` holds the labelling's options by name
    (:class:`hybridpd.analysis.periodic.LabelSpec`): the fixed point ``FP[0]``, ``n_iter``,
    the threshold ``criterion`` (``crit`` below), the certified ball ``QS[0]``, ``R2[0]``
    (``cert_Q``, ``cert_r2``), ``escape`` and ``cycle_tol`` (its ``C``, ``T`` and
    ``period`` are the pair's own here).

    Converged means the paper's criterion: after ``n_iter`` iterations,
    ``(x1*-x1)^2 + (y1*-y1)^2 + (y2*-y2)^2 + (phi*-phi)^2 < crit`` (``phi`` differences taken
    modulo T, nearest representative). Two early exits keep the label of the full run:

    * ``d^T cert_Q d < cert_r2`` for the deviation ``d`` from the fixed point: the point lies
      in a neighbourhood certified (by the caller) to be invariant, contracting and inside the
      criterion ball, so every later iterate satisfies the criterion (``cert_r2 = 0``
      disables it);
    * the iterate repeats one of the previous ``32`` to within ``cycle_tol`` (relative): the
      trajectory sits on a cycle of period ``k`` and iterate ``n_iter`` is read off the
      cycle; used only when that iterate's criterion value is farther than ``1e-6 crit``
      from the threshold (``cycle_tol = 0`` disables it).

    ``escape`` bounds ``|z1|, |z2|, |z4|``: beyond it the label is "diverged".

    Returns ``labels[N]`` (see :data:`LABELS`), ``iterations[N]`` and the final points.
    """
    fixed, n_iter, crit, escape = spec.FP[0], spec.n_iter, spec.criterion, spec.escape
    cert_Q, cert_r2, cycle_tol = spec.QS[0], spec.R2[0], spec.cycle_tol
    N = S.shape[0]
    T = 2.0 * math.pi / params[P.OMEGA]
    labels = np.empty(N, dtype=np.int64)
    iters = np.empty(N, dtype=np.int64)
    final = np.empty((N, 4))
    cur = np.empty(4)
    nxt = np.empty(4)
    d = np.empty(4)
    ring = np.empty((_CYCLE_MAX, 4))
    norec = np.empty((0, N_REC))
    for i in range(N):
        cur[:] = S[i]
        lab = -1
        it = 0
        for it in range(1, n_iter + 1):
            st, _k = _map_once(params, case, cur, nxt, tol, max_impacts, stick, norec)
            if st != 0:
                if st == STATUS_STICK + 10:
                    lab = 3
                elif st == STATUS_NONFINITE + 10 or st == STATUS_TIMEOUT + 10:
                    lab = 2
                else:
                    lab = 4
                break
            cur[:] = nxt
            if not (abs(cur[1]) < escape and abs(cur[2]) < escape and abs(cur[3]) < escape):
                lab = 2
                break
            if cert_r2 > 0.0:
                d[0] = wrap_phase_kernel(cur[0] - fixed[0], T)
                d[1] = cur[1] - fixed[1]
                d[2] = cur[2] - fixed[2]
                d[3] = cur[3] - fixed[3]
                q = 0.0
                for a in range(4):
                    for b in range(4):
                        q += d[a] * cert_Q[a, b] * d[b]
                if q < cert_r2:
                    lab = 0
                    break
            if cycle_tol > 0.0:
                period = 0
                for kk in range(1, min(it - 1, _CYCLE_MAX) + 1):
                    r = ring[(it - kk) % _CYCLE_MAX]
                    same = abs(wrap_phase_kernel(cur[0] - r[0], T)) <= cycle_tol * T
                    for a in range(1, 4):
                        same = same and abs(cur[a] - r[a]) <= cycle_tol * (1.0 + abs(cur[a]))
                    if same:
                        period = kk
                        break
                if period > 0:
                    # iterate n_iter equals iterate it - ((it - n_iter) mod period)
                    j = it - ((it - n_iter) % period)
                    pt = ring[j % _CYCLE_MAX] if j < it else cur
                    c = _criterion(pt, fixed, T)
                    if abs(c - crit) > 1e-6 * crit:
                        lab = 0 if c < crit else 1
                        cur[:] = pt
                        break
                ring[it % _CYCLE_MAX] = cur
        if lab < 0:
            lab = 0 if _criterion(cur, fixed, T) < crit else 1
        labels[i] = lab
        iters[i] = it
        final[i] = cur
    return labels, iters, final
