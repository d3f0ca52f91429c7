"""Periodic orbits of the impact map by Newton's method, and their parameter continuation.

Two complementary tools (SPEC section 5):

* :func:`find_periodic_orbit` solves ``P^k(s) = s`` for a fixed point of the ``k``-th iterate
  of the impact map ``P`` (:class:`~hybridpd.analysis.impactmap.ImpactMap`), from any start: symmetric
  or not, simple impact pattern or not (double impacts, grazing contacts, sticking phases).
  The phase residual is unwrapped modulo ``T``. The Jacobian of ``P^k`` is the product of the
  symbolic ``DP`` blocks of :mod:`hybridpd.pair.symbolic` when every iterate has the simple pattern
  ``(+L, -L, +L)``, otherwise central finite differences of the simulated map. Damped Newton
  with a backtracking line search.
* :func:`continue_orbit` follows a fixed point of ``P^k`` in one parameter among
  :data:`PARAMETERS` (natural-parameter continuation with a secant predictor, or
  pseudo-arclength continuation which passes folds); :func:`continue_symmetric` follows the
  closed-form symmetric orbit family of :mod:`hybridpd.analysis.orbits` (``x10`` fixed, ``xm``
  follows) in one of :data:`SYMMETRIC_PARAMETERS`.

Both record, at every accepted step, the parameter, the fixed point, the Floquet multipliers
and the spectral radius, and detect and locate these events between consecutive steps
(:data:`EVENT_KINDS`), by the Illinois (safeguarded regula falsi) method on a test function,
or by bisection where the test is a discrete change:

========================  ==========================================================
``fold``                  ``det(DP - I)`` changes sign: a real multiplier crosses +1
                          (a fold if the parameter turns back; otherwise a branch
                          point, e.g. the symmetry-breaking pitchfork of a symmetric
                          orbit)
``period_doubling``       ``det(DP + I)`` changes sign: a real multiplier crosses -1
``neimark_sacker``        a complex pair crosses the unit circle (test ``|lambda| - 1``
                          of the non-real multiplier nearest the circle)
``grazing``               symmetric family: the viability margin crosses 0 (paper (19));
                          map continuation: the impact pattern changes (an extra
                          contact appears with zero velocity, or one disappears)
``stability_change``      the spectral radius crosses 1
``existence``             symmetric family only: the conditions (13)-(14) stop having a
                          solution, or viability is lost otherwise than by grazing
========================  ==========================================================

Every loop is bounded (Newton iterations, continuation steps, step-size halvings, location
iterations) and every result carries the reason it stopped. Nothing here keeps global
mutable state; the compiled helper is cached on disk by numba like the rest of the package.

Coordinates: a section point is ``s = (phi, z1, z2, z4)`` (pre-impact at ``z3 = +L``,
``z4 > 0``), ``phi`` in time units in ``[0, T)``, ``T = 2 pi / omega``; positions in length
units, velocities in length/time.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hybridpd._jit import njit
from hybridpd.analysis.impactmap import ImpactMap, stability
from hybridpd.analysis.orbits import REASONS, symmetric_orbits
from hybridpd.model import (
    Case,
    ImpactPair,
    PDGains,
    Reference,
    as_gains,
    check_array,
    check_finite,
    check_int,
    check_odd_order,
)
from hybridpd.pair import symbolic
from hybridpd.pair.batch import (
    STATUS_IMPACT,
    STATUS_STICK,
    _eval,
    _impact_velocities,
    impact_map,
    next_impact,
    stick_release,
)

__all__ = [
    "EVENT_KINDS",
    "PARAMETERS",
    "SYMMETRIC_PARAMETERS",
    "BifurcationEvent",
    "Branch",
    "ImpactStep",
    "MapTrace",
    "PeriodicOrbit",
    "continue_orbit",
    "continue_symmetric",
    "find_periodic_orbit",
    "map_power_jacobian",
    "plot_branch",
    "trace_map",
]

#: Parameters :func:`continue_orbit` can follow (all others fixed).
PARAMETERS = ("kp", "kv", "e", "mu", "xm", "omega", "L")
#: Parameters :func:`continue_symmetric` can follow (``xm`` is an output there).
SYMMETRIC_PARAMETERS = ("kp", "kv", "e", "mu", "omega", "L", "x10")
#: Kinds of :class:`BifurcationEvent`.
EVENT_KINDS = ("fold", "period_doubling", "neimark_sacker", "grazing", "stability_change",
               "existence")

_NONREAL_TOL = 1e-9        # |Im lambda| above this (relative) counts as a complex pair
_MAX_HALVINGS = 60         # bound on step halvings in one continuation step
_END_GRAZE = 1e-4          # a branch whose corrector fails this close to grazing ends there
_JUMP_TOL = 1e-3           # a located crossing this far from the critical value is a jump
_NEAR_BRANCH = 5e-2        # a stuck continuation this close to a +1 multiplier: branch point


# ----------------------------------------------------------------------------------------
# Tracing one application of P (the impact pattern)
# ----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ImpactStep:
    """One wall contact met by an application of ``P``.

    Attributes
    ----------
    wall : int
        +1 (``z3 = +L``) or -1 (``z3 = -L``).
    tau : float
        Flight time (time units) from the previous contact (or release) to this one.
    speed : float
        Approach speed ``wall * z4`` just before the contact (length/time, >= 0).
    kind : str
        ``"impact"`` (Newton's law applied), ``"graze"`` (tangential touch: the approach speed
        is below the engine's velocity tolerance, no velocity jump) or ``"stick"`` (impacts
        accumulated; the masses then moved together for ``stick_time``).
    stick_time : float
        Duration of the sticking phase (time units), 0 unless ``kind == "stick"``.
    """

    wall: int
    tau: float
    speed: float
    kind: str
    stick_time: float = 0.0


@dataclass(frozen=True)
class MapTrace:
    """One application of ``P`` with its impact pattern and flight diagnostics.

    Attributes
    ----------
    s : ndarray, shape (4,)
        ``P(s0)`` (``phi`` in ``[0, T)``); NaN unless ``ok``.
    ok : bool
        The trajectory returned to the section.
    status : int
        0 when ``ok``, else ``10 + batch.STATUS_*`` (as :class:`~hybridpd.analysis.impactmap.MapResult`).
    steps : tuple of ImpactStep
        Contacts after the initial ``+L`` impact; the last one is the return to ``+L``.
    margin : float
        Smallest interior distance of a flight to the wall it turns towards, divided by ``L``
        (dimensionless): at every interior turning point of ``z3`` a maximum is measured to
        ``+L`` and a minimum to ``-L``; 1 if ``z3`` has no interior turning point. It tends to
        0 at grazing (paper (19)). NaN if not computed.
    min_speed : float
        Smallest approach speed over the impacts and grazing touches (length/time).
    """

    s: np.ndarray
    ok: bool
    status: int
    steps: tuple
    margin: float
    min_speed: float

    @property
    def walls(self) -> tuple:
        """Walls of the contacts, e.g. ``(-1, 1)`` for the simple pattern."""
        return tuple(st.wall for st in self.steps)

    @property
    def signature(self) -> tuple:
        """``((wall, kind), ...)``: what a pattern change (grazing) is detected on."""
        return tuple((st.wall, st.kind) for st in self.steps)

    @property
    def simple(self) -> bool:
        """The pattern ``(+L, -L, +L)`` with two genuine impacts (symbolic ``DP`` applies)."""
        return self.signature == ((-1, "impact"), (1, "impact"))


@njit(cache=True)
def _flight_margin(params, case, t0, x1, y1, x2, y2, tau, nsamp):
    """Smallest ``distance / L`` to the wall approached at interior turning points of ``z3``.

    Turning points are sign changes of ``z4`` on a uniform grid of ``nsamp`` intervals,
    refined by bisection. A maximum of ``z3`` is measured to ``+L``, a minimum to ``-L``
    (a small hop away from the wall just left is not a near-grazing).
    """
    L = params[5]
    m = 1.0
    if not tau > 0.0:
        return m
    h = tau / nsamp
    prev = 0.0
    for k in range(1, nsamp):
        s = k * h
        r = _eval(params, case, t0, x1, y1, x2, y2, s, 0.0)
        z4 = r[1] - r[3]
        if k > 1 and z4 * prev < 0.0:
            a = s - h
            b = s
            fa = prev
            for _ in range(60):
                c = 0.5 * (a + b)
                rc = _eval(params, case, t0, x1, y1, x2, y2, c, 0.0)
                fc = rc[1] - rc[3]
                if fc * fa > 0.0:
                    a = c
                    fa = fc
                else:
                    b = c
            rc = _eval(params, case, t0, x1, y1, x2, y2, 0.5 * (a + b), 0.0)
            z3 = rc[0] - rc[2]
            if prev > 0.0:
                d = (L - z3) / L       # z4: + -> -, a maximum of z3, towards +L
            else:
                d = (z3 + L) / L       # a minimum of z3, towards -L
            m = min(m, d)
        prev = z4
    return m


def trace_map(impact_map_: ImpactMap, s, *, margin: bool = True,
              margin_samples: int = 256) -> MapTrace:
    """Apply ``P`` once from ``s`` and record every contact (the impact pattern).

    This follows the compiled engine step by step (the same kernels, the same tolerances),
    so ``trace_map(P, s).s`` equals ``P(s)``; it additionally records walls, flight times,
    approach speeds, grazing touches and sticking phases, and measures how close every
    flight comes to a wall in its interior.

    Parameters
    ----------
    impact_map_ : ImpactMap
    s : array_like, shape (4,)
        Section point ``(phi, z1, z2, z4)`` with ``z4 >= 0`` (``z4 = 0``: a grazing arrival,
        as returned by ``P`` after a tangential touch).
    margin : bool
        Compute :attr:`MapTrace.margin` (``margin_samples`` flow evaluations per flight).
    margin_samples : int
        Grid size of the turning-point search in each flight.

    Returns
    -------
    MapTrace

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.analysis.orbits import symmetric_orbit
    >>> orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    >>> P = ImpactMap(orb.pair, orb.gains, orb.reference())
    >>> tr = trace_map(P, orb.fixed_point)
    >>> tr.walls, tr.simple
    ((-1, 1), True)
    """
    # z4 = 0 (the closure of the section) is accepted: P itself returns it after a
    # tangential touch of the right wall
    P = _impact_map(impact_map_)
    s = _section_point(s, "s", closure=True)
    params, case, tol = P.params, P._c, P.tol
    mu, e, L, w = params[3], params[4], params[5], params[6]
    T = 2.0 * math.pi / w
    x2, y2 = float(s[1]), float(s[2])
    x1, y1 = x2 + L, y2 + float(s[3])
    y1, y2 = _impact_velocities(mu, e, y1, y2)
    t = float(s[0])
    steps = []
    marg = 1.0 if margin else np.nan
    speeds = []
    nan4 = np.full(4, np.nan)
    for _ in range(P.max_impacts):
        st, tau, wall, _X1, Y1, X2, Y2, graze = next_impact(params, case, t, x1, y1, x2, y2,
                                                            50.0 * T, tol)
        if margin and st in (STATUS_IMPACT, STATUS_STICK):
            marg = min(marg, _flight_margin(params, case, t, x1, y1, x2, y2, tau,
                                            check_int("margin_samples", margin_samples, 2)))
        if st == STATUS_STICK:
            t += tau
            yc = (mu * Y1 + Y2) / (1.0 + mu)
            st2, ts, X2, yc = stick_release(params, case, t, X2, yc, wall, 50.0 * T, tol)
            steps.append(ImpactStep(int(wall), float(tau), float(abs(Y1 - Y2)), "stick",
                                    float(ts)))
            if st2 != STATUS_IMPACT:
                return MapTrace(nan4, False, int(STATUS_STICK if st2 == 1 else st2) + 10,
                                tuple(steps), marg, _min(speeds))
            t += ts
            x2 = X2
            x1 = x2 + wall * L
            y1 = y2 = yc
            continue
        if st != STATUS_IMPACT:
            return MapTrace(nan4, False, int(st) + 10, tuple(steps), marg, _min(speeds))
        t += tau
        speed = max(wall * (Y1 - Y2), 0.0)
        speeds.append(speed)
        steps.append(ImpactStep(int(wall), float(tau), float(speed),
                                "graze" if graze else "impact"))
        x1, y1, x2, y2 = X2 + wall * L, Y1, X2, Y2
        if wall == 1:
            out = np.array([t - T * math.floor(t / T), x2, y2, max(y1 - y2, 0.0)])
            return MapTrace(out, True, 0, tuple(steps), marg, _min(speeds))
        if not graze:
            y1, y2 = _impact_velocities(mu, e, y1, y2)
    return MapTrace(nan4, False, 13, tuple(steps), marg, _min(speeds))


def _min(values):
    return float(min(values)) if values else np.nan


# ----------------------------------------------------------------------------------------
# Small helpers: validation, phases, parameters
# ----------------------------------------------------------------------------------------


def _section_point(s, name, closure=False) -> np.ndarray:
    a = check_array(name, s, shape=(4,))  # (phi, z1, z2, z4)
    if a[3] < 0 or (a[3] == 0 and not closure):
        raise ValueError(f"{name}[3] = z4 must be > 0 (approaching the +L wall), got {a[3]!r}")
    return a


def _impact_map(P) -> ImpactMap:
    if not isinstance(P, ImpactMap):
        raise ValueError(f"impact_map_ must be an ImpactMap, got {type(P).__name__}")
    return P


def _positive_int(name, value) -> int:
    return check_int(name, value, 1)


def _positive_float(name, value) -> float:
    v = check_finite(name, value)
    if v <= 0:
        raise ValueError(f"{name} must be > 0, got {value!r}")
    return v


def _wrap_diff(d, T):
    """Nearest representative of a phase difference modulo ``T`` (in ``[-T/2, T/2)``)."""
    return (d + 0.5 * T) % T - 0.5 * T


def _domain(name):
    """``(lo, hi, lo_closed)`` of a parameter's admissible values."""
    if name == "e":
        return 0.0, 1.0, True
    if name == "xm":
        return 0.0, math.inf, True
    return 0.0, math.inf, False


def _in_domain(name, v) -> bool:
    lo, hi, closed = _domain(name)
    if not math.isfinite(v):
        return False
    return (v >= lo if closed else v > lo) and v <= hi


def _check_parameter(name, allowed):
    if not isinstance(name, str) or name not in allowed:
        raise ValueError(f"parameter must be one of {allowed}, got {name!r}")
    return name


def _map_value(P: ImpactMap, name: str) -> float:
    return {"kp": P.gains.kp, "kv": P.gains.kv, "e": P.pair.e, "mu": P.pair.mu,
            "L": P.pair.L, "xm": P.reference.xm, "omega": P.reference.omega}[name]


def _map_with(P: ImpactMap, name: str, value: float) -> ImpactMap:
    """A copy of ``P`` with one parameter changed (the others and the tolerances kept)."""
    pair, g, ref = P.pair, P.gains, P.reference
    if name in ("kp", "kv"):
        g = PDGains(**{"kp": g.kp, "kv": g.kv, name: value})
    elif name in ("e", "mu", "L"):
        pair = ImpactPair(**{"mu": pair.mu, "e": pair.e, "L": pair.L, "m2": pair.m2,
                             name: value})
    else:
        ref = Reference(**{"xm": ref.xm, "omega": ref.omega, name: value})
    return ImpactMap(pair, g, ref, P.case, tol=P.tol, max_impacts=P.max_impacts)


def _fixed_parameters(P: ImpactMap) -> dict:
    return {"kp": P.gains.kp, "kv": P.gains.kv, "e": P.pair.e, "mu": P.pair.mu,
            "L": P.pair.L, "m2": P.pair.m2, "xm": P.reference.xm,
            "omega": P.reference.omega, "case": P.case.value}


# ----------------------------------------------------------------------------------------
# P^k, its residual and Jacobian
# ----------------------------------------------------------------------------------------


def _power_many(P: ImpactMap, S: np.ndarray, k: int):
    """``P^k`` of the rows of ``S`` (N, 4); returns ``(images, ok)``."""
    cur = np.array(S, dtype=float, copy=True)
    ok = np.all(np.isfinite(cur), axis=1) & (cur[:, 3] > 0)
    for _ in range(k):
        idx = np.flatnonzero(ok)
        if idx.size == 0:
            break
        out, status, _ = impact_map(P.params, P._c, np.ascontiguousarray(cur[idx]), P.tol,
                                    P.max_impacts)
        cur[idx] = out
        ok[idx] = status == 0
    cur[~ok] = np.nan
    return cur, ok


def _residual(P: ImpactMap, s: np.ndarray, k: int):
    """``P^k(s) - s`` with the phase difference unwrapped, or None where undefined."""
    if not (np.all(np.isfinite(s)) and s[3] > 0):
        return None
    img, ok = _power_many(P, s[None, :], k)
    if not ok[0]:
        return None
    r = img[0] - s
    r[0] = _wrap_diff(r[0], P.period)
    return r


def map_power_jacobian(impact_map_: ImpactMap, s, period: int = 1, *, method: str = "auto",
                       fd_step: float = 1e-6):
    """Jacobian of ``P^k`` at ``s`` (4x4), and how it was obtained.

    Parameters
    ----------
    impact_map_ : ImpactMap
    s : array_like, shape (4,)
        Section point.
    period : int
        ``k``, the number of applications of ``P``.
    method : {"auto", "symbolic", "fd"}
        ``"symbolic"``: chain rule ``DP(s_{k-1}) ... DP(s_0)`` of the symbolic Jacobians
        (every iterate must have the simple pattern ``(+L, -L, +L)``); ``"fd"``: central
        differences of the simulated ``P^k`` (phase unwrapped) with steps
        ``fd_step * max(1, |s_j|)``; ``"auto"``: symbolic when possible.
    fd_step : float
        Relative finite-difference step.

    Returns
    -------
    DP : ndarray, shape (4, 4)
    method : str
        ``"symbolic"`` or ``"fd"``.
    traces : list of MapTrace
        The ``k`` applications of ``P`` along the orbit segment (without margins).

    Raises
    ------
    ValueError
        Unknown method, or ``"symbolic"`` requested on a non-simple pattern.
    RuntimeError
        ``P^k`` undefined at ``s`` or at every finite-difference point of a column.
    """
    if method not in ("auto", "symbolic", "fd"):
        raise ValueError(f"method must be 'auto', 'symbolic' or 'fd', got {method!r}")
    k = _positive_int("period", period)
    fd_step = _positive_float("fd_step", fd_step)
    P = _impact_map(impact_map_)
    s = _section_point(s, "s")
    pts = [s]
    traces = []
    for _ in range(k):
        tr = trace_map(P, pts[-1], margin=False)
        if not tr.ok:
            raise RuntimeError(f"P undefined along the orbit (status {tr.status})")
        traces.append(tr)
        pts.append(tr.s)
    simple = all(tr.simple for tr in traces)
    if method == "symbolic" and not simple:
        raise ValueError("method='symbolic' needs the simple pattern (+L, -L, +L) on every "
                         f"iterate; got {[tr.walls for tr in traces]}")
    if simple and method != "fd":
        g, p, ref = P.gains, P.pair, P.reference
        J = np.eye(4)
        for i, tr in enumerate(traces):
            jac = symbolic.map_jacobian(pts[i], tr.steps[0].tau, tr.steps[1].tau, xm=ref.xm,
                                        kp=g.kp, kv=g.kv, m2=p.m2, mu=p.mu, e=p.e, L=p.L,
                                        w=ref.omega, case=P.case.value)
            J = np.asarray(jac.DP, float).reshape(4, 4) @ J
        return J, "symbolic", traces
    return _fd_jacobian(P, s, k, fd_step), "fd", traces


def _fd_jacobian(P: ImpactMap, s: np.ndarray, k: int, fd_step: float) -> np.ndarray:
    """Central differences of ``P^k`` (one-sided where a side is undefined)."""
    T = P.period
    H = fd_step * np.maximum(1.0, np.abs(s))
    H[3] = min(H[3], 0.5 * s[3])          # stay on the section side z4 > 0
    S = np.concatenate([s + np.diag(H), s - np.diag(H), s[None, :]])
    img, ok = _power_many(P, S, k)
    J = np.empty((4, 4))
    for j in range(4):
        if ok[j] and ok[4 + j]:
            d, h = img[j] - img[4 + j], 2 * H[j]
        elif ok[j] and ok[8]:
            d, h = img[j] - img[8], H[j]
        elif ok[4 + j] and ok[8]:
            d, h = img[8] - img[4 + j], H[j]
        else:
            raise RuntimeError(f"P^{k} undefined around s in direction {j}")
        d[0] = _wrap_diff(d[0], T)
        J[:, j] = d / h
    return J


def _param_derivative(P: ImpactMap, name: str, s: np.ndarray, k: int, fd_step: float):
    """``d(P^k(s) - s)/dp`` by central (or one-sided at a domain edge) differences."""
    p = _map_value(P, name)
    h = fd_step * max(1.0, abs(p))
    vals = []
    for q in (p + h, p - h):
        if _in_domain(name, q):
            r = _residual(_map_with(P, name, q), s, k)
            vals.append(r)
        else:
            vals.append(None)
    if vals[0] is not None and vals[1] is not None:
        d, hh = vals[0] - vals[1], 2 * h
    else:
        r0 = _residual(P, s, k)
        if r0 is None:
            raise RuntimeError("P^k undefined at the point")
        if vals[0] is not None:
            d, hh = vals[0] - r0, h
        elif vals[1] is not None:
            d, hh = r0 - vals[1], h
        else:
            raise RuntimeError(f"P^k undefined on both sides of {name} = {p:g}")
    d[0] = _wrap_diff(d[0], P.period)
    return d / hh


# ----------------------------------------------------------------------------------------
# Damped Newton
# ----------------------------------------------------------------------------------------


@dataclass
class _NewtonOut:
    x: np.ndarray
    converged: bool
    reason: str
    history: list
    iterations: int
    step: float


def _newton(resid, jac, x0, *, tol, max_iter, scale, min_lambda=2.0 ** -12):
    """Damped Newton with backtracking on ``||F||_inf``.

    ``resid(x)`` returns the residual or None where undefined; ``jac(x)`` the Jacobian (may
    raise). Converged when ``||F|| <= tol * scale(x)``, or when a full Newton step is itself
    below ``tol * scale(x)`` (the residual then sits at its rounding floor, which exceeds
    ``tol`` for strongly unstable orbits whose multipliers amplify rounding).
    """
    x = np.array(x0, dtype=float)
    r = resid(x)
    if r is None:
        return _NewtonOut(x, False, "map undefined at the initial point", [], 0, np.nan)
    nr = float(np.max(np.abs(r)))
    hist = [nr]
    last = np.nan
    for it in range(1, max_iter + 1):
        if nr <= tol * scale(x):
            return _NewtonOut(x, True, "residual below tol", hist, it - 1, last)
        try:
            J = jac(x)
            dx = np.linalg.solve(J, -r)
        except (np.linalg.LinAlgError, RuntimeError, ValueError) as exc:
            return _NewtonOut(x, False, f"Jacobian failed: {exc}", hist, it - 1, last)
        if not np.all(np.isfinite(dx)):
            return _NewtonOut(x, False, "singular Jacobian", hist, it - 1, last)
        last = float(np.max(np.abs(dx)))
        lam = 1.0
        accepted = False
        while lam >= min_lambda:
            xn = x + lam * dx
            rn = resid(xn)
            if rn is not None:
                nrn = float(np.max(np.abs(rn)))
                if nrn <= (1.0 - 1e-4 * lam) * nr:
                    accepted = True
                    break
            lam *= 0.5
        if not accepted:
            if last <= tol * scale(x):
                return _NewtonOut(x, True, "Newton step below tol (residual at rounding floor)",
                                  hist, it, last)
            return _NewtonOut(x, False, "line search failed (no decrease of the residual)",
                              hist, it, last)
        x, r, nr = xn, rn, nrn
        hist.append(nr)
        if lam == 1.0 and last <= tol * scale(x):
            return _NewtonOut(x, True, "Newton step below tol", hist, it, last)
    if nr <= tol * scale(x):
        return _NewtonOut(x, True, "residual below tol", hist, max_iter, last)
    return _NewtonOut(x, False, f"max_iter = {max_iter} reached", hist, max_iter, last)


def _scale(x):
    return max(1.0, float(np.max(np.abs(x[1:4]))))


# ----------------------------------------------------------------------------------------
# Periodic orbits
# ----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class PeriodicOrbit:
    """A fixed point of ``P^k`` found by Newton's method.

    Attributes
    ----------
    converged : bool
    reason : str
        Why Newton stopped.
    s : ndarray, shape (4,)
        The fixed point ``(phi, z1, z2, z4)`` (``phi`` in ``[0, T)``), or the last iterate.
    orbit : ndarray, shape (k, 4)
        ``s, P(s), ..., P^{k-1}(s)`` (phases in ``[0, T)``).
    period : int
        ``k`` (number of applications of ``P`` per period).
    minimal_period : int
        Smallest ``d`` dividing ``k`` with ``P^d(s) = s`` (to ``1e-7`` relative); e.g. 1 when a
        period-2 search landed on a fixed point of ``P``.
    residual : float
        ``||P^k(s) - s||_inf`` at ``s`` (phase unwrapped).
    residual_history : ndarray
        Residual norm at every Newton iterate.
    iterations : int
    DP : ndarray, shape (4, 4)
        Jacobian of ``P^k`` at ``s``.
    jacobian_method : str
        ``"symbolic"`` (chain of symbolic blocks) or ``"fd"`` (finite differences).
    multipliers : ndarray, shape (4,), complex
        Eigenvalues of ``DP`` by decreasing modulus (Floquet multipliers of ``P^k``).
    spectral_radius : float
    stable, hyperbolic : bool
    pattern : tuple of tuple of ImpactStep
        The contacts of each of the ``k`` applications of ``P`` (walls, flight times, speeds).
    walls : tuple of tuple of int
        ``pattern`` reduced to the walls, e.g. ``((-1, 1),)`` for a simple period-1 orbit.
    n_impacts : int
        Contacts per period ``k T``-orbit (including grazing touches and sticking).
    margin : float
        Smallest interior wall distance of a flight over the period, over ``L``
        (see :class:`MapTrace`).
    min_impact_speed : float
        Smallest approach speed over the period (length/time).
    grazing : bool
        ``margin < graze_tol``, or an approach speed below ``graze_tol`` times the largest one,
        or a grazing touch in the pattern.
    sticking : bool
        A sticking phase occurs on the orbit.
    parameters : dict
        The map's parameters (``kp, kv, e, mu, L, m2, xm, omega, case``).
    """

    converged: bool
    reason: str
    s: np.ndarray
    orbit: np.ndarray
    period: int
    minimal_period: int
    residual: float
    residual_history: np.ndarray
    iterations: int
    DP: np.ndarray | None
    jacobian_method: str | None
    multipliers: np.ndarray | None
    spectral_radius: float
    stable: bool | None
    hyperbolic: bool | None
    pattern: tuple
    walls: tuple
    n_impacts: int
    margin: float
    min_impact_speed: float
    grazing: bool
    sticking: bool
    parameters: dict

    def to_dict(self) -> dict:
        """JSON-ready summary."""
        mult = None if self.multipliers is None else [[float(z.real), float(z.imag)]
                                                      for z in self.multipliers]
        return {
            "converged": self.converged, "reason": self.reason,
            "s": [float(v) for v in self.s], "orbit": self.orbit.tolist(),
            "period": self.period, "minimal_period": self.minimal_period,
            "residual": _f(self.residual), "iterations": self.iterations,
            "jacobian_method": self.jacobian_method, "multipliers": mult,
            "spectral_radius": _f(self.spectral_radius), "stable": self.stable,
            "hyperbolic": self.hyperbolic,
            "walls": [list(w) for w in self.walls],
            "flight_times": [[st.tau for st in it] for it in self.pattern],
            "n_impacts": self.n_impacts, "margin": _f(self.margin),
            "min_impact_speed": _f(self.min_impact_speed), "grazing": self.grazing,
            "sticking": self.sticking, "parameters": dict(self.parameters),
        }


def _f(x):
    return None if x is None or not np.isfinite(x) else float(x)


@dataclass
class _Point:
    """Everything the continuation keeps about one solution (internal)."""

    u: np.ndarray                 # (s with continuous phase, p)
    DP: np.ndarray | None
    mult: np.ndarray
    rho: float
    signature: tuple
    margin: float
    min_speed: float
    viable: bool = True
    formal: bool = True
    xm: float = np.nan
    reason: int = 0
    newton_its: int = 0
    T: float = np.nan             # period of the reference at this point
    Fp: np.ndarray | None = None  # d(P^k(s) - s)/dp (map continuation: turning points)
    traces: list = field(default_factory=list, repr=False)


def _orbit_diagnostics(P: ImpactMap, s: np.ndarray, k: int, jacobian: str, fd_step: float,
                       margin_samples: int, graze_tol: float):
    """Traces with margins, DP, stability and grazing flags at a (converged) point."""
    traces = []
    cur = s
    for _ in range(k):
        tr = trace_map(P, cur, margin=True, margin_samples=margin_samples)
        traces.append(tr)
        if not tr.ok:
            break
        cur = tr.s
    ok = all(tr.ok for tr in traces)
    DP = method = None
    if ok:
        try:
            DP, method, _ = map_power_jacobian(P, s, k, method=jacobian, fd_step=fd_step)
        except (RuntimeError, ValueError):
            DP = method = None
    margin = min((tr.margin for tr in traces), default=np.nan)
    speeds = [st.speed for tr in traces for st in tr.steps if st.kind != "stick"]
    vmax = max(speeds, default=0.0)
    vmin = min(speeds, default=np.nan)
    touch = any(st.kind == "graze" for tr in traces for st in tr.steps)
    grazing = bool(touch or (np.isfinite(margin) and margin < graze_tol)
                   or (vmax > 0 and vmin < graze_tol * vmax))
    sticking = any(st.kind == "stick" for tr in traces for st in tr.steps)
    return traces, DP, method, margin, vmin, grazing, sticking


def _minimal_period(P, s, k):
    T = P.period
    for d in range(1, k):
        if k % d:
            continue
        img, ok = _power_many(P, s[None, :], d)
        if ok[0]:
            r = img[0] - s
            r[0] = _wrap_diff(r[0], T)
            if np.max(np.abs(r)) <= 1e-7 * _scale(s):
                return d
    return k


def find_periodic_orbit(impact_map_: ImpactMap, s0, period: int = 1, *, tol: float = 1e-12,
                        max_iter: int = 50, jacobian: str = "auto", fd_step: float = 1e-6,
                        graze_tol: float = 1e-6, margin_samples: int = 256) -> PeriodicOrbit:
    """Solve ``P^k(s) = s`` by damped Newton's method.

    Parameters
    ----------
    impact_map_ : ImpactMap
        The impact map ``P`` (parameters, reference and feedback case fixed).
    s0 : array_like, shape (4,)
        Start ``(phi, z1, z2, z4)`` on the section (``z4 > 0``), e.g. a late iterate of ``P``.
    period : int
        ``k >= 1``.
    tol : float
        Convergence tolerance on ``||P^k(s) - s||_inf`` relative to ``max(1, |z|_inf)`` (or
        on the Newton step, when rounding keeps the residual above it).
    max_iter : int
        Bound on Newton iterations.
    jacobian : {"auto", "symbolic", "fd"}
        See :func:`map_power_jacobian`.
    fd_step : float
        Relative finite-difference step.
    graze_tol : float
        Thresholds of the grazing flag (dimensionless margin; speed relative to the largest
        approach speed on the orbit).
    margin_samples : int
        Grid of the turning-point search per flight.

    Returns
    -------
    PeriodicOrbit

    Raises
    ------
    ValueError
        Bad ``s0``, ``period``, ``tol``, ``max_iter`` or ``jacobian``.

    Examples
    --------
    The period-2 attractor of the collocated loop at ``e = 0.1`` (paper parameters):

    >>> from hybridpd import ImpactPair, PDGains, Reference
    >>> from hybridpd.analysis.orbits import symmetric_orbit
    >>> pair = ImpactPair(mu=0.1, e=0.1, L=0.75)
    >>> xm = symmetric_orbit(pair, PDGains(10, 20), 5.0).xm
    >>> P = ImpactMap(pair, PDGains(10, 20), Reference(xm, 5.0))
    >>> s0 = P.iterate([0.3, -2.1, -2.3, 0.5], 200)[-1]
    >>> orb = find_periodic_orbit(P, s0, period=2)
    >>> orb.converged, orb.minimal_period, orb.walls
    (True, 2, ((-1, -1, 1), (1,)))
    >>> bool(orb.stable)
    True
    """
    if not isinstance(impact_map_, ImpactMap):
        raise ValueError(f"impact_map_ must be an ImpactMap, got {type(impact_map_).__name__}")
    P = impact_map_
    s0 = _section_point(s0, "s0")
    k = _positive_int("period", period)
    tol = _positive_float("tol", tol)
    max_iter = _positive_int("max_iter", max_iter)
    if jacobian not in ("auto", "symbolic", "fd"):
        raise ValueError(f"jacobian must be 'auto', 'symbolic' or 'fd', got {jacobian!r}")
    fd_step = _positive_float("fd_step", fd_step)
    graze_tol = _positive_float("graze_tol", graze_tol)
    margin_samples = _positive_int("margin_samples", margin_samples)

    res = _newton(lambda x: _residual(P, x, k),
                  lambda x: map_power_jacobian(P, x, k, method=jacobian, fd_step=fd_step)[0]
                  - np.eye(4),
                  s0, tol=tol, max_iter=max_iter, scale=_scale)
    return _make_orbit(P, res, k, jacobian, fd_step, margin_samples, graze_tol)


def _make_orbit(P, res, k, jacobian, fd_step, margin_samples, graze_tol) -> PeriodicOrbit:
    T = P.period
    s = res.x.copy()
    s[0] = s[0] % T
    r = _residual(P, s, k)
    resid = float(np.max(np.abs(r))) if r is not None else np.nan
    traces, DP, method, margin, vmin, grazing, sticking = _orbit_diagnostics(
        P, s, k, jacobian, fd_step, margin_samples, graze_tol)
    orbit = np.array([s] + [tr.s for tr in traces[:-1]])
    mult, rho, stable, hyper = None, np.nan, None, None
    if DP is not None and np.all(np.isfinite(DP)):
        stab = stability(DP)
        mult, rho, stable, hyper = stab.multipliers, stab.spectral_radius, stab.stable, \
            stab.hyperbolic
    minimal = _minimal_period(P, s, k) if res.converged else k
    pattern = tuple(tr.steps for tr in traces)
    return PeriodicOrbit(
        converged=bool(res.converged), reason=res.reason, s=s, orbit=orbit, period=k,
        minimal_period=minimal, residual=resid, residual_history=np.asarray(res.history),
        iterations=res.iterations, DP=DP, jacobian_method=method, multipliers=mult,
        spectral_radius=rho, stable=stable, hyperbolic=hyper,
        pattern=pattern, walls=tuple(tuple(st.wall for st in p) for p in pattern),
        n_impacts=sum(len(p) for p in pattern), margin=margin, min_impact_speed=vmin,
        grazing=grazing, sticking=sticking, parameters=_fixed_parameters(P),
    )


# ----------------------------------------------------------------------------------------
# Branches and events
# ----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BifurcationEvent:
    """A detected (and, where possible, located) event on a branch.

    Attributes
    ----------
    kind : str
        One of :data:`EVENT_KINDS`.
    parameter : float
        Parameter value at the located event (or the midpoint of the bracketing steps when
        location failed).
    point : ndarray, shape (4,)
        Fixed point at the event (``phi`` in ``[0, T)``).
    multipliers : ndarray, shape (4,), complex
        Multipliers at the event (by decreasing modulus); NaN where undefined.
    index : int
        The event lies between branch points ``index`` and ``index + 1``.
    detail : str
        Human-readable description (direction of the crossing, fold vs branch point, ...).
    test_value : float
        Test function at the reported point (0 at an exact event; for grazing the margin or
        the smallest approach speed).
    located : bool
        The location converged (bracket below the tolerance).
    viable : bool
        The orbit at the event is a genuine orbit (symmetric family: viability holds; a
        stability change of a non-viable, "virtual" orbit is reported with ``False``).
    xm : float
        Reference amplitude at the event.
    """

    kind: str
    parameter: float
    point: np.ndarray
    multipliers: np.ndarray
    index: int
    detail: str = ""
    test_value: float = np.nan
    located: bool = False
    viable: bool = True
    xm: float = np.nan

    def to_dict(self) -> dict:
        """JSON-ready summary."""
        return {"kind": self.kind, "parameter": float(self.parameter),
                "point": [_f(v) for v in self.point],
                "multipliers": [[_f(z.real), _f(z.imag)] for z in self.multipliers],
                "index": int(self.index), "detail": self.detail,
                "test_value": _f(self.test_value), "located": bool(self.located),
                "viable": bool(self.viable), "xm": _f(self.xm)}


@dataclass(frozen=True)
class Branch:
    """A continued family of periodic orbits (one row per accepted step).

    Attributes
    ----------
    parameter_name : str
    parameter : ndarray, shape (N,)
    points : ndarray, shape (N, 4)
        Fixed points ``(phi, z1, z2, z4)`` (``phi`` in ``[0, T)``).
    multipliers : ndarray, shape (N, 4), complex
        By decreasing modulus (NaN where undefined).
    spectral_radius : ndarray, shape (N,)
    stable : ndarray of bool, shape (N,)
        Viable and spectral radius < 1.
    viable : ndarray of bool, shape (N,)
        The orbit exists as such (symmetric family: paper's existence incl. viability; map
        continuation: always True, the orbits are simulated).
    margin : ndarray, shape (N,)
        Viability margin (symmetric family, signed: negative when violated) or the smallest
        interior wall distance over ``L`` of the flights (map continuation).
    min_impact_speed : ndarray, shape (N,)
        Smallest approach speed at an impact on the orbit (length/time).
    xm : ndarray, shape (N,)
        Reference amplitude (varies on the symmetric family, or when it is the parameter).
    period : int
        ``k`` of ``P^k`` (1 on the symmetric family).
    patterns : tuple
        Per point, the impact signature ``(((wall, kind), ...) per iteration)``.
    events : list of BifurcationEvent
        In branch order.
    termination : str
        Why the continuation stopped.
    family : str
        ``"periodic"`` (Newton on ``P^k``) or ``"symmetric"`` (closed form).
    method : str
        ``"natural"``, ``"arclength"`` or ``"closed_form"``.
    case : Case
    fixed : dict
        The other parameters.
    n_rejected : int
        Rejected (halved) steps.
    newton_iterations : ndarray of int, shape (N,)
        Corrector iterations per point (0 on the closed-form family).
    """

    parameter_name: str
    parameter: np.ndarray
    points: np.ndarray
    multipliers: np.ndarray
    spectral_radius: np.ndarray
    stable: np.ndarray
    viable: np.ndarray
    margin: np.ndarray
    min_impact_speed: np.ndarray
    xm: np.ndarray
    period: int
    patterns: tuple
    events: list
    termination: str
    family: str
    method: str
    case: Case
    fixed: dict
    n_rejected: int = 0
    newton_iterations: np.ndarray = field(default_factory=lambda: np.zeros(0, int))

    def __len__(self) -> int:
        return int(self.parameter.size)

    def events_of(self, kind: str) -> list:
        """The events of one kind."""
        return [ev for ev in self.events if ev.kind == kind]

    def to_dict(self) -> dict:
        """JSON-ready summary (arrays as lists, complex numbers as ``[re, im]``)."""
        return {
            "parameter_name": self.parameter_name, "family": self.family,
            "method": self.method, "case": self.case.value, "period": self.period,
            "fixed": {k: (v if isinstance(v, str) else float(v)) for k, v in self.fixed.items()},
            "parameter": [float(v) for v in self.parameter],
            "points": [[_f(v) for v in row] for row in self.points],
            "multipliers": [[[_f(z.real), _f(z.imag)] for z in row] for row in self.multipliers],
            "spectral_radius": [_f(v) for v in self.spectral_radius],
            "stable": [bool(v) for v in self.stable], "viable": [bool(v) for v in self.viable],
            "margin": [_f(v) for v in self.margin],
            "min_impact_speed": [_f(v) for v in self.min_impact_speed],
            "xm": [_f(v) for v in self.xm],
            "events": [ev.to_dict() for ev in self.events],
            "termination": self.termination, "n_rejected": int(self.n_rejected),
        }


def _nonreal(m):
    return np.abs(m.imag) > _NONREAL_TOL * np.maximum(1.0, np.abs(m))


def _test_fold(pt):
    return float(np.prod(1.0 - pt.mult).real) if pt.formal else np.nan


def _test_pd(pt):
    return float(np.prod(1.0 + pt.mult).real) if pt.formal else np.nan


def _test_ns(pt):
    """``|lambda| - 1`` of the non-real multiplier nearest the unit circle (NaN if none)."""
    if not pt.formal:
        return np.nan
    m = pt.mult[_nonreal(pt.mult)]
    if m.size == 0:
        return np.nan
    d = np.abs(m) - 1.0
    return float(d[np.argmin(np.abs(d))])


def _ns_count(pt):
    return int(np.sum(_nonreal(pt.mult) & (np.abs(pt.mult) > 1.0)))


def _test_stability(pt):
    return pt.rho - 1.0 if pt.formal else np.nan


def _changes(fa, fb):
    return bool(np.isfinite(fa) and np.isfinite(fb) and (fa > 0) != (fb > 0)
                and not (fa == 0 and fb == 0))


def _illinois(evaluate, ftest, fa, fb, pa, pb, *, size, tol, max_iter):
    """Root of ``ftest(evaluate(theta))`` on ``[0, 1]`` with ``f(0) = fa``, ``f(1) = fb``.

    ``evaluate(theta)`` returns a point or None (then the bracket is bisected instead).
    ``size`` converts a ``theta`` interval to a length (stop below ``tol``). Returns
    ``(point, f, located)`` with the best bracket end; ``pa``, ``pb`` are the end points.
    """
    a, b = 0.0, 1.0
    side = 0
    best = (pa, fa) if abs(fa) <= abs(fb) else (pb, fb)
    for it in range(max_iter):
        if (b - a) * size <= tol:
            return best[0], best[1], True
        theta = b - fb * (b - a) / (fb - fa) if fb != fa else 0.5 * (a + b)
        # keep the regula-falsi point inside the bracket and bisect every third iteration so
        # that the bracket shrinks geometrically even when the test function is not smooth
        if not (a < theta < b) or it % 3 == 2:
            theta = 0.5 * (a + b)
        pt = evaluate(theta)
        fc = ftest(pt) if pt is not None else np.nan
        if not np.isfinite(fc):
            theta = 0.5 * (a + b)
            pt = evaluate(theta)
            fc = ftest(pt) if pt is not None else np.nan
            if not np.isfinite(fc):
                return best[0], best[1], False
        if abs(fc) < abs(best[1]):
            best = (pt, fc)
        if fc == 0.0:
            return pt, fc, True
        if (fc > 0) == (fb > 0):
            b, fb = theta, fc
            if side == 1:
                fa *= 0.5
            side = 1
        else:
            a, fa = theta, fc
            if side == -1:
                fb *= 0.5
            side = -1
    return best[0], best[1], (b - a) * size <= tol


def _bisect_predicate(evaluate, same_as_a, pa, pb, *, size, tol, max_iter):
    """Bisection on a discrete change: returns the last point on each side and ``located``."""
    a, b = 0.0, 1.0
    last_a, last_b = pa, pb
    for _ in range(max_iter):
        if (b - a) * size <= tol:
            return last_a, last_b, True
        theta = 0.5 * (a + b)
        pt = evaluate(theta)
        if pt is None:
            return last_a, last_b, False
        if same_as_a(pt):
            a, last_a = theta, pt
        else:
            b, last_b = theta, pt
    return last_a, last_b, (b - a) * size <= tol


class _Tracker:
    """Shared event detection/location along a sequence of points (internal).

    ``evaluate(pa, pb, theta)`` computes the solution between two accepted points;
    ``turn_test(pt, chord)``, when given, is the parameter component of the branch tangent
    at ``pt`` oriented along ``chord`` (its sign change is a turning point).
    """

    def __init__(self, kinds, evaluate, size, tol, max_iter, locate, to_event,
                 turn_test=None):
        self.kinds = kinds
        self.evaluate = evaluate
        self.size = size
        self.tol = tol
        self.max_iter = max_iter
        self.locate = locate
        self.to_event = to_event
        self.turn_test = turn_test

    def _root(self, kind, ftest, pa, pb, index, detail_fn, critical=None):
        """Locate a sign change of ``ftest``; ``critical(pt)`` is the distance of the critical
        multiplier(s) from the critical value: when it stays large at the located point the
        multipliers *jumped* across (a nonsmooth point such as grazing), and the event of a
        smooth bifurcation kind is dropped (returns None)."""
        fa, fb = ftest(pa), ftest(pb)
        if self.locate:
            pt, fv, ok = _illinois(lambda th: self.evaluate(pa, pb, th), ftest, fa, fb, pa, pb,
                                   size=self.size(pa, pb), tol=self.tol, max_iter=self.max_iter)
        else:
            pt, fv, ok = (pa if abs(fa) <= abs(fb) else pb), min(fa, fb, key=abs), False
        detail = detail_fn(pt)
        if critical is not None and ok:
            c = critical(pt)
            if np.isfinite(c) and c > _JUMP_TOL:
                if kind != "stability_change":
                    return None
                detail += (f"; the multipliers jump across the unit circle here (spectral "
                           f"radius {pa.rho:.4g} -> {pb.rho:.4g} at a nonsmooth point, e.g. "
                           "grazing)")
        return self.to_event(kind, pt, index, detail, fv, ok)

    def detect(self, pa, pb, index, extra=()):
        """Events between two consecutive points."""
        out = []
        chord = pb.u - pa.u
        cross = _changes(_test_fold(pa), _test_fold(pb))
        turn = False
        if self.turn_test is not None and not (_near_grazing(pa) or _near_grazing(pb)):
            # (next to grazing the finite-difference tangent straddles the square-root
            # singularity of P and its sign means nothing; grazing has its own events)
            turn = _changes(self.turn_test(pa, chord), self.turn_test(pb, chord))
        if "fold" in self.kinds and turn:
            def detail(pt):
                m1 = float(np.min(np.abs(pt.mult - 1.0)))
                if cross:
                    return "fold: the branch turns back (a real multiplier crosses +1)"
                return ("turning point without a multiplier crossing +1 (closest "
                        f"|lambda - 1| = {m1:.2g}): the branch passes through a branch point, "
                        "e.g. a pitchfork, onto the symmetric partner of the family")
            out.append(self._root("fold", lambda pt: self.turn_test(pt, chord), pa, pb, index,
                                  detail))
        elif "fold" in self.kinds and cross:
            out.append(self._root(
                "fold", _test_fold, pa, pb, index,
                lambda pt: ("branch point: a real multiplier crosses +1 while the branch goes "
                            "on (pitchfork or transcritical; on a symmetric orbit typically the "
                            "symmetry-breaking pitchfork)"),
                critical=lambda pt: float(np.min(np.abs(pt.mult - 1.0)))))
        if "period_doubling" in self.kinds and _changes(_test_pd(pa), _test_pd(pb)):
            out.append(self._root(
                "period_doubling", _test_pd, pa, pb, index,
                lambda pt: ("real multiplier crosses -1 "
                            f"({'outwards' if _sgn_outside(pb) > _sgn_outside(pa) else 'inwards'})"),
                critical=lambda pt: float(np.min(np.abs(pt.mult + 1.0)))))
        if "neimark_sacker" in self.kinds and pa.formal and pb.formal \
                and _ns_count(pa) != _ns_count(pb):
            fa, fb = _test_ns(pa), _test_ns(pb)
            if _changes(fa, fb):
                ev = self._root(
                    "neimark_sacker", _test_ns, pa, pb, index,
                    lambda pt: ("complex pair crosses the unit circle "
                                f"({'outwards' if _ns_count(pb) > _ns_count(pa) else 'inwards'}"
                                f", angle {_ns_angle(pt):.4g} rad)"),
                    critical=lambda pt: abs(_test_ns(pt)))
                # a pair that became real inside the interval is not a Neimark-Sacker point
                if ev is not None:
                    m = ev.multipliers
                    if np.all(np.isfinite(m)):
                        crit = m[np.argmin(np.abs(np.abs(m) - 1.0))]
                        if _nonreal(np.array([crit]))[0]:
                            out.append(ev)
        if "stability_change" in self.kinds and _changes(_test_stability(pa),
                                                         _test_stability(pb)):
            def detail(pt):
                d = "stable -> unstable" if pb.rho > pa.rho else "unstable -> stable"
                m = pt.mult
                if np.all(np.isfinite(m)):
                    c = m[np.argmin(np.abs(np.abs(m) - 1.0))]
                    kind = ("complex pair" if _nonreal(np.array([c]))[0] else
                            ("real multiplier at +1" if c.real > 0 else "real multiplier at -1"))
                    d += f" ({kind})"
                return d
            out.append(self._root("stability_change", _test_stability, pa, pb, index, detail,
                                  critical=lambda pt: abs(pt.rho - 1.0)))
        out.extend(extra)
        out = [ev for ev in out if ev is not None]
        out.sort(key=lambda ev: abs(ev.parameter - pa.u[-1]))
        return out


def _near_grazing(pt):
    if not pt.traces:
        return False
    g = min(pt.margin, _rel_speed(pt))
    return bool(np.isfinite(g) and g < _END_GRAZE)


def _sgn_outside(pt):
    """1 if a real multiplier lies below -1 at ``pt`` (used for the PD direction)."""
    m = pt.mult
    return int(np.any((~_nonreal(m)) & (m.real < -1.0)))


def _ns_angle(pt):
    m = pt.mult[_nonreal(pt.mult)]
    if m.size == 0:
        return np.nan
    c = m[np.argmin(np.abs(np.abs(m) - 1.0))]
    return float(abs(np.angle(c)))


# ----------------------------------------------------------------------------------------
# Continuation of fixed points of P^k
# ----------------------------------------------------------------------------------------


def _path_steps(name, p0, stop, step, max_step, min_step, max_steps, defaults):
    """Validate a continuation path ``p0 -> stop`` and its step sizes.

    ``defaults = (n_steps, n_max, min_fraction)``: unset sizes become ``span / n_steps``,
    ``span / n_max`` and ``span * min_fraction``. Returns
    ``(span, step, max_step, min_step, max_steps)``.
    """
    if not _in_domain(name, stop):
        lo, hi, _ = _domain(name)
        raise ValueError(f"stop = {stop!r} is outside the domain of {name} ({lo:g}, {hi:g})")
    if stop == p0:
        raise ValueError(f"stop must differ from the starting value {name} = {p0!r}")
    n_steps, n_max, min_fraction = defaults
    span = abs(stop - p0)
    step = span / n_steps if step is None else _positive_float("step", step)
    max_step = span / n_max if max_step is None else _positive_float("max_step", max_step)
    min_step = span * min_fraction if min_step is None else _positive_float("min_step", min_step)
    if min_step > step:
        raise ValueError(f"min_step = {min_step!r} must not exceed step = {step!r}")
    return span, step, max(max_step, step), min_step, _positive_int("max_steps", max_steps)


def continue_orbit(impact_map_: ImpactMap, s0, parameter: str, stop: float, *,
                   period: int = 1, method: str = "arclength", step: float | None = None,
                   min_step: float | None = None, max_step: float | None = None,
                   max_steps: int = 400, tol: float = 1e-10, max_newton: int = 12,
                   jacobian: str = "auto", fd_step: float = 1e-6, locate: bool = True,
                   event_tol: float = 1e-9, graze_tol: float = 1e-6,
                   margin_samples: int = 128,
                   events: tuple = EVENT_KINDS) -> Branch:
    """Continue a fixed point of ``P^k`` in one parameter from its value in the map to ``stop``.

    Parameters
    ----------
    impact_map_ : ImpactMap
        Map at the starting parameter values.
    s0 : array_like, shape (4,), or PeriodicOrbit
        Starting guess (corrected by Newton first).
    parameter : str
        One of :data:`PARAMETERS`; the others stay fixed (``xm`` included: to follow the
        symmetric family with ``x10`` fixed use :func:`continue_symmetric`).
    stop : float
        Parameter value where the continuation ends.
    period : int
        ``k``.
    method : {"arclength", "natural"}
        Pseudo-arclength (unknowns ``(s, p)``, constraint ``t . (u - u_pred) = 0``; passes
        folds) or natural continuation in ``p`` with a secant predictor for ``s`` (stops at a
        fold: the corrector fails, the step shrinks below ``min_step``).
    step, min_step, max_step : float, optional
        Initial, smallest and largest step (parameter units for ``natural``, arclength in
        ``(phi, z1, z2, z4, p)`` for ``arclength``). Defaults ``|stop - p0| / 50``,
        ``|stop - p0| * 1e-7`` and ``|stop - p0| / 10``.
    max_steps : int
        Bound on accepted steps.
    tol, max_newton : float, int
        Corrector tolerance and iteration bound.
    jacobian : {"auto", "symbolic", "fd"}
        Jacobian of ``P^k`` (see :func:`map_power_jacobian`).
    fd_step : float
        Relative finite-difference step (Jacobian and parameter derivative).
    locate : bool
        Locate events (otherwise they are reported at the nearer bracketing point).
    event_tol : float
        Location tolerance (length of the bracket in ``(s, p)``).
    graze_tol : float
        Grazing thresholds (see :func:`find_periodic_orbit`).
    margin_samples : int
        Grid of the turning-point search per flight.
    events : tuple of str
        Kinds to detect (subset of :data:`EVENT_KINDS`; ``existence`` does not apply here).

    Returns
    -------
    Branch
        ``family == "periodic"``; ``termination`` tells why it stopped ("reached stop",
        "max_steps reached", "step below min_step ...", "parameter left ...").

    Raises
    ------
    ValueError
        Unknown parameter or method, non-finite ``stop``, zero or negative steps, ``stop``
        equal to the start or outside the parameter's domain.

    Examples
    --------
    Follow the symmetric orbit of the collocated loop (``e = 0.1``) at fixed ``xm`` in
    ``kv`` through its grazing:

    >>> from hybridpd import ImpactPair, PDGains, Reference
    >>> from hybridpd.analysis.orbits import symmetric_orbit
    >>> pair = ImpactPair(mu=0.1, e=0.1, L=0.75)
    >>> orb = symmetric_orbit(pair, PDGains(10, 20), 5.0)
    >>> P = ImpactMap(pair, PDGains(10, 20), Reference(orb.xm, 5.0))
    >>> br = continue_orbit(P, orb.fixed_point, "kv", 23.0, step=0.5)
    >>> [ev.kind for ev in br.events][:1]
    ['grazing']
    """
    if not isinstance(impact_map_, ImpactMap):
        raise ValueError(f"impact_map_ must be an ImpactMap, got {type(impact_map_).__name__}")
    name = _check_parameter(parameter, PARAMETERS)
    P0 = impact_map_
    if isinstance(s0, PeriodicOrbit):
        s0 = s0.s
    s0 = _section_point(s0, "s0")
    stop = check_finite("stop", stop)
    if method not in ("arclength", "natural"):
        raise ValueError(f"method must be 'arclength' or 'natural', got {method!r}")
    k = _positive_int("period", period)
    p0 = _map_value(P0, name)
    span, step, max_step, min_step, max_steps = _path_steps(
        name, p0, stop, step, max_step, min_step, max_steps, (50, 10, 1e-7))
    tol = _positive_float("tol", tol)
    max_newton = _positive_int("max_newton", max_newton)
    if jacobian not in ("auto", "symbolic", "fd"):
        raise ValueError(f"jacobian must be 'auto', 'symbolic' or 'fd', got {jacobian!r}")
    fd_step = _positive_float("fd_step", fd_step)
    event_tol = _positive_float("event_tol", event_tol)
    graze_tol = _positive_float("graze_tol", graze_tol)
    margin_samples = _positive_int("margin_samples", margin_samples)
    bad = [kd for kd in events if kd not in EVENT_KINDS]
    if bad:
        raise ValueError(f"events must be a subset of {EVENT_KINDS}, got {bad}")
    direction = 1.0 if stop > p0 else -1.0
    lo_p, hi_p = min(p0, stop), max(p0, stop)

    cache = {}

    def map_at(p):
        # the corrector evaluates the same few parameter values repeatedly
        key = float(p)
        if key not in cache:
            if len(cache) > 64:
                cache.clear()
            cache[key] = _map_with(P0, name, key)
        return cache[key]

    def F(u):
        p = u[4]
        if not _in_domain(name, p):
            return None
        return _residual(map_at(p), u[:4], k)

    def Fs(u):
        return map_power_jacobian(map_at(u[4]), u[:4], k, method=jacobian,
                                  fd_step=fd_step)[0] - np.eye(4)

    def Fp(u):
        return _param_derivative(map_at(u[4]), name, u[:4], k, fd_step)

    def correct(u_pred, normal):
        """Newton on [F(u); normal . (u - u_pred)] = 0 (normal None: fixed p)."""
        if normal is None:
            p = u_pred[4]
            res = _newton(lambda x: F(np.append(x, p)), lambda x: Fs(np.append(x, p)),
                          u_pred[:4], tol=tol, max_iter=max_newton, scale=_scale)
            return np.append(res.x, p), res

        def G(u):
            r = F(u)
            return None if r is None else np.append(r, normal @ (u - u_pred))

        def JG(u):
            return np.vstack([np.column_stack([Fs(u), Fp(u)]), normal])

        res = _newton(G, JG, u_pred, tol=tol, max_iter=max_newton, scale=_scale)
        return res.x, res

    def make_point(u, its):
        P = map_at(u[4])
        s = u[:4].copy()
        traces, DP, _, margin, vmin, _, _ = _orbit_diagnostics(
            P, s, k, jacobian, fd_step, margin_samples, graze_tol)
        if DP is None or not np.all(np.isfinite(DP)):
            return None
        st = stability(DP)
        sig = tuple(tr.signature for tr in traces)
        try:
            fp = Fp(u)
        except RuntimeError:
            fp = None
        return _Point(u=u.copy(), DP=DP, mult=st.multipliers, rho=st.spectral_radius,
                      signature=sig, margin=margin, min_speed=vmin,
                      xm=P.reference.xm, newton_its=its, traces=traces, Fp=fp)

    def turn_test(pt, chord):
        # parameter component of the unit tangent (kernel of [DP^k - I, dF/dp]) oriented
        # along the chord: it changes sign at a turning point of the branch
        if pt.Fp is None:
            return np.nan
        v = np.linalg.svd(np.column_stack([pt.DP - np.eye(4), pt.Fp]))[2][-1]
        return float(v[4] if v @ chord >= 0 else -v[4])

    def evaluate_between(pa, pb, theta):
        chord = pb.u - pa.u
        nrm = np.linalg.norm(chord)
        u, res = correct(pa.u + theta * chord, chord / nrm)
        if not res.converged:
            return None
        return make_point(u, res.iterations)

    def to_event(kind, pt, index, detail, fv, ok):
        T = 2 * math.pi / (pt.u[4] if name == "omega" else P0.reference.omega)
        s = pt.u[:4].copy()
        s[0] %= T
        return BifurcationEvent(kind=kind, parameter=float(pt.u[4]), point=s,
                                multipliers=pt.mult.copy(), index=index, detail=detail,
                                test_value=float(fv), located=bool(ok), viable=True,
                                xm=float(pt.xm))

    tracker = _Tracker(events, evaluate_between, lambda a, b: float(np.linalg.norm(b.u - a.u)),
                       event_tol, 60, locate, to_event, turn_test=turn_test)

    def grazing_events(pa, pb, index):
        if "grazing" not in events or pa.signature == pb.signature:
            return []
        if locate:
            la, lb, ok = _bisect_predicate(lambda th: evaluate_between(pa, pb, th),
                                           lambda pt: pt.signature == pa.signature, pa, pb,
                                           size=float(np.linalg.norm(pb.u - pa.u)),
                                           tol=event_tol, max_iter=60)
        else:
            la, lb, ok = pa, pb, False
        # report the side where the changing contact is slow / the margin is small
        ga = min(la.margin, _rel_speed(la))
        gb = min(lb.margin, _rel_speed(lb))
        pt, g = (la, ga) if ga <= gb else (lb, gb)
        detail = (f"impact pattern {_sig_str(pa.signature)} -> {_sig_str(pb.signature)} "
                  f"(margin {la.margin:.3g} / {lb.margin:.3g}, smallest approach speed "
                  f"{la.min_speed:.3g} / {lb.min_speed:.3g})")
        return [to_event("grazing", pt, index, detail, g, ok)]

    # ---- initial point
    start = find_periodic_orbit(P0, s0, k, tol=tol, max_iter=max(max_newton, 30),
                                jacobian=jacobian, fd_step=fd_step)
    if not start.converged:
        return _empty_branch(name, P0, k, method,
                             f"initial Newton failed: {start.reason}")
    u0 = np.append(start.s, p0)
    first = make_point(u0, start.iterations)
    if first is None:
        return _empty_branch(name, P0, k, method, "Jacobian undefined at the initial point")
    pts = [first]
    evs = []
    rejected = 0
    termination = f"max_steps = {max_steps} reached"
    h = min(step, max_step)
    # initial tangent: kernel of [F_s, F_p], oriented towards stop
    if method == "arclength":
        try:
            A = np.column_stack([Fs(u0), Fp(u0)])
            tangent = np.linalg.svd(A)[2][-1]
        except (RuntimeError, np.linalg.LinAlgError):
            tangent = np.append(np.zeros(4), 1.0)
        if tangent[4] * direction < 0:
            tangent = -tangent
        if abs(tangent[4]) < 1e-12:
            tangent = np.append(np.zeros(4), direction)
    prev_u = None
    for _ in range(max_steps):
        cur = pts[-1]
        T = 2 * math.pi / (cur.u[4] if name == "omega" else P0.reference.omega)
        accepted = None
        why = ""
        for _h in range(_MAX_HALVINGS):
            if method == "natural":
                p_new = cur.u[4] + direction * h
                if (p_new - stop) * direction > 0:
                    p_new = stop
                if prev_u is not None:
                    # secant predictor through the last two points
                    dp_prev = cur.u[4] - prev_u[4]
                    u_pred = cur.u + (cur.u - prev_u) * ((p_new - cur.u[4]) / dp_prev)
                else:
                    u_pred = cur.u.copy()
                u_pred[4] = p_new
                u, res = correct(u_pred, None)
            else:
                u_pred = cur.u + h * tangent
                if (u_pred[4] - stop) * direction > 0 and tangent[4] * direction > 0:
                    # the predictor passes stop (maybe beyond the parameter's domain, e.g.
                    # e > 1): correct at stop itself, along the tangent
                    u_pred = cur.u + ((stop - cur.u[4]) / tangent[4]) * tangent
                    u_pred[4] = stop
                    u, res = correct(u_pred, None)
                else:
                    u, res = correct(u_pred, tangent)
            pt = None
            if not res.converged:
                why = f"corrector: {res.reason}"
            else:
                sec = u - cur.u
                ns = float(np.linalg.norm(sec))
                if method == "arclength" and not (ns > 0 and (sec @ tangent) / ns > 0.8):
                    # the corrected point lies far off the predicted direction: most likely
                    # another branch
                    why = "the step turned by more than 37 degrees"
                elif method == "natural" and not (
                        np.linalg.norm(u[:4] - u_pred[:4]) <= 0.5 * max(ns, h) + 10 * tol):
                    why = "the corrector moved far from the predictor"
                else:
                    pt = make_point(u, res.iterations)
                    if pt is None:
                        why = "Jacobian undefined at the corrected point"
            if pt is not None:
                accepted = pt
                break
            rejected += 1
            h *= 0.5
            if h < min_step:
                break
        if accepted is None:
            termination = (f"step below min_step = {min_step:g} at {name} = {cur.u[4]:.10g} "
                           f"({why})")
            g = min(cur.margin, _rel_speed(cur))
            m1 = float(np.min(np.abs(cur.mult - 1.0)))
            if m1 < _NEAR_BRANCH and not (np.isfinite(g) and g < _END_GRAZE):
                # Next to a branch point another family crosses this one; the corrector
                # lands on it (rejected as a sharp turn) whatever the step. Passing needs
                # branch switching, which is not attempted: say so.
                termination += (f"; stopped next to a branch point (a multiplier within "
                                f"{m1:.2g} of +1): another family of fixed points crosses here")
                if "fold" in events:
                    evs.append(to_event(
                        "fold", cur, len(pts) - 1,
                        f"branch point not passed (closest |lambda - 1| = {m1:.2g}); restart "
                        "from the other family to continue", float(_test_fold(cur)), False))
            if np.isfinite(g) and g < _END_GRAZE:
                # The fixed point runs into grazing and no fixed point continues it: at a
                # grazing contact P has a square-root singularity (the branch ends, as in a
                # nonsmooth fold). The last point is within the margin of the grazing point.
                termination += "; the branch ends at grazing"
                if "grazing" in events:
                    evs.append(to_event(
                        "grazing", cur, len(pts) - 1,
                        f"the branch ends at grazing (margin {cur.margin:.3g}, relative "
                        f"approach speed {_rel_speed(cur):.3g}): no fixed point of P^{k} "
                        "continues beyond it", g, g < graze_tol))
            break
        new = accepted
        its = res.iterations
        # keep the phase continuous along the branch
        new.u[0] = cur.u[0] + _wrap_diff(new.u[0] - cur.u[0], T)
        p_new = new.u[4]
        done = False
        if method == "natural" and p_new == stop:
            done = True
        elif method == "arclength" and (p_new - stop) * direction >= 0:
            # overshot: land exactly on stop by a fixed-parameter correction
            w = (stop - cur.u[4]) / (p_new - cur.u[4])
            u_pred = cur.u + w * (new.u - cur.u)
            u_pred[4] = stop
            u, res2 = correct(u_pred, None)
            if res2.converged:
                pt = make_point(u, res2.iterations)
                if pt is not None:
                    pt.u[0] = cur.u[0] + _wrap_diff(pt.u[0] - cur.u[0], T)
                    new = pt
            done = True
        idx = len(pts) - 1
        evs.extend(tracker.detect(cur, new, idx, grazing_events(cur, new, idx)))
        prev_u = cur.u.copy()
        pts.append(new)
        if done:
            termination = "reached stop"
            break
        if method == "arclength":
            sec = new.u - cur.u
            tangent = sec / np.linalg.norm(sec)       # secant predictor
            if not (lo_p - 1e-12 * span <= p_new <= hi_p + 1e-12 * span):
                termination = (f"parameter left [{lo_p:g}, {hi_p:g}] at {name} = {p_new:.10g} "
                               "(the branch turned back)")
                break
        # step control: easy corrections lengthen the step, hard ones shorten it
        if its <= 3:
            h = min(1.5 * h, max_step)
        elif its >= 7:
            h = max(0.6 * h, min_step)
    return _branch_from_points(pts, evs, name, P0, k, method, termination, rejected)


def _rel_speed(pt):
    speeds = [st.speed for tr in pt.traces for st in tr.steps if st.kind != "stick"]
    vmax = max(speeds, default=0.0)
    return min(speeds) / vmax if vmax > 0 else np.nan


def _sig_str(sig):
    return " | ".join(",".join(f"{w:+d}{'' if kd == 'impact' else kd[0]}" for w, kd in it)
                      for it in sig)


def _empty_branch(name, P, k, method, reason) -> Branch:
    z = np.zeros(0)
    return Branch(parameter_name=name, parameter=z, points=np.zeros((0, 4)),
                  multipliers=np.zeros((0, 4), complex), spectral_radius=z,
                  stable=np.zeros(0, bool), viable=np.zeros(0, bool), margin=z,
                  min_impact_speed=z, xm=z, period=k, patterns=(), events=[],
                  termination=reason, family="periodic", method=method, case=P.case,
                  fixed=_fixed_parameters(P), n_rejected=0,
                  newton_iterations=np.zeros(0, int))


def _branch_from_points(pts, evs, name, P0, k, method, termination, rejected, *,
                        omega=None, case=None, fixed=None) -> Branch:
    p = np.array([pt.u[-1] for pt in pts])
    S = np.array([pt.u[:4] for pt in pts])
    if P0 is not None:
        omega, case, fixed = P0.reference.omega, P0.case, _fixed_parameters(P0)
    w = p if name == "omega" else omega
    S[:, 0] = np.mod(S[:, 0], 2 * np.pi / w)
    mult = np.array([pt.mult for pt in pts])
    rho = np.array([pt.rho for pt in pts])
    viable = np.array([pt.viable for pt in pts])
    return Branch(
        parameter_name=name, parameter=p, points=S, multipliers=mult, spectral_radius=rho,
        stable=viable & (rho < 1.0), viable=viable, margin=np.array([pt.margin for pt in pts]),
        min_impact_speed=np.array([pt.min_speed for pt in pts]),
        xm=np.array([pt.xm for pt in pts]), period=k,
        patterns=tuple(pt.signature for pt in pts), events=evs, termination=termination,
        family="periodic" if method != "closed_form" else "symmetric", method=method,
        case=case, fixed=fixed, n_rejected=rejected,
        newton_iterations=np.array([pt.newton_its for pt in pts]),
    )


# ----------------------------------------------------------------------------------------
# Continuation of the symmetric family (closed form)
# ----------------------------------------------------------------------------------------


_SIMPLE_SIG = (((-1, "impact"), (1, "impact")),)


def continue_symmetric(pair: ImpactPair, gains: PDGains, omega: float, parameter: str,
                       stop: float, *, x10: float = 1.0, n: int = 1, case="collocated",
                       step: float | None = None, min_step: float | None = None,
                       max_step: float | None = None, max_steps: int = 2000,
                       max_change: float = 0.05, locate: bool = True,
                       event_tol: float = 1e-10, margin_samples: int = 256,
                       events: tuple = EVENT_KINDS) -> Branch:
    """Continue the simple symmetric orbit family (closed form) in one parameter.

    Along the family the desired primary-mass amplitude ``x10`` stays fixed (unless it is the
    parameter) and the reference amplitude ``xm`` follows from (20), as in
    :func:`hybridpd.analysis.orbits.symmetric_orbit`. Every point is closed form (conditions
    (13)-(14), viability by guaranteed contact location, symbolic ``DP``), so the family is a
    graph over the parameter and no corrector is needed; the step adapts to the change of
    the fixed point, the spectral radius and the viability margin.

    Where viability fails the *formal* orbit (the solution of (13)-(14), which crosses a
    wall) is still followed: its multipliers are reported (``viable`` False), and events on
    it are flagged ``viable=False``.

    Parameters
    ----------
    pair : ImpactPair
    gains : PDGains
    omega : float
        Reference frequency (rad/time).
    parameter : str
        One of :data:`SYMMETRIC_PARAMETERS`.
    stop : float
        End value of the parameter (the start is its value in the inputs).
    x10 : float
        Primary-mass amplitude (length); ``gamma = L / x10``.
    n : int
        Odd orbit order.
    case : {"collocated", "noncollocated"}
    step, min_step, max_step : float, optional
        Parameter steps; defaults ``|stop - p0| / 100``, ``|stop - p0| * 1e-6`` and
        ``|stop - p0| / 20``.
    max_steps : int
        Bound on accepted steps.
    max_change : float
        Largest accepted change per step of ``|s|_inf / (1 + |s|_inf)``, of
        ``min(spectral radius, 2)`` and of the viability margin.
    locate : bool
        Locate the events (Illinois method on the closed-form test functions).
    event_tol : float
        Location tolerance, relative to ``max(1, |p|)``.
    margin_samples : int
        Grid of the viability-margin search.
    events : tuple of str
        Kinds to detect (subset of :data:`EVENT_KINDS`).

    Returns
    -------
    Branch
        ``family == "symmetric"``, ``method == "closed_form"``.

    Raises
    ------
    ValueError
        Unknown parameter, non-finite or out-of-domain ``stop``, zero or negative steps.

    Examples
    --------
    The collocated symmetric orbit (``e = 0.1``, paper parameters) grazes near ``kv = 21.9``:

    >>> from hybridpd import ImpactPair, PDGains
    >>> br = continue_symmetric(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0, "kv", 23.0)
    >>> ev = br.events_of("grazing")[0]
    >>> round(ev.parameter, 3)
    21.938
    """
    if not isinstance(pair, ImpactPair):
        raise ValueError(f"pair must be an ImpactPair, got {type(pair).__name__}")
    gains = as_gains(gains)
    omega = _positive_float("omega", omega)
    x10 = _positive_float("x10", x10)
    case = Case.parse(case)
    name = _check_parameter(parameter, SYMMETRIC_PARAMETERS)
    stop = check_finite("stop", stop)
    base = {"kp": gains.kp, "kv": gains.kv, "e": pair.e, "mu": pair.mu, "L": pair.L,
            "omega": omega, "x10": x10, "m2": pair.m2}
    p0 = base[name]
    _, step, max_step, min_step, max_steps = _path_steps(
        name, p0, stop, step, max_step, min_step, max_steps, (100, 20, 1e-6))
    max_change = _positive_float("max_change", max_change)
    event_tol = _positive_float("event_tol", event_tol)
    margin_samples = _positive_int("margin_samples", margin_samples)
    bad = [kd for kd in events if kd not in EVENT_KINDS]
    if bad:
        raise ValueError(f"events must be a subset of {EVENT_KINDS}, got {bad}")
    n = check_odd_order(n)
    direction = 1.0 if stop > p0 else -1.0

    def point(p):
        v = dict(base)
        v[name] = float(p)
        r = symmetric_orbits(v["kp"], v["kv"], mu=v["mu"], e=v["e"], L=v["L"],
                             omega=v["omega"], m2=v["m2"], x10=v["x10"], n=n, case=case,
                             margin=True, jacobian=False, margin_samples=margin_samples)
        code = int(r.reason)
        formal = code not in (1, 2)
        s = np.asarray(r.fixed_point, float).reshape(4)
        mult = np.full(4, np.nan + 0j)
        rho = np.nan
        DP = None
        if formal:
            DP = np.asarray(symbolic.orbit_jacobian(r.candidate).DP, float).reshape(4, 4)
            if np.all(np.isfinite(DP)):
                st = stability(DP)
                mult, rho = st.multipliers, st.spectral_radius
            else:
                formal = False
        viable = bool(r.exists)
        return _Point(u=np.append(s, p), DP=DP, mult=mult, rho=rho,
                      signature=_SIMPLE_SIG if viable else (), margin=float(r.viability_margin),
                      min_speed=float(s[3]), viable=viable, formal=formal, xm=float(r.xm),
                      reason=code, T=2 * math.pi / v["omega"])

    def evaluate_between(pa, pb, theta):
        return point(pa.u[-1] + theta * (pb.u[-1] - pa.u[-1]))

    def to_event(kind, pt, index, detail, fv, ok):
        T = 2 * math.pi / (pt.u[-1] if name == "omega" else omega)
        s = pt.u[:4].copy()
        s[0] %= T
        if not pt.viable and kind not in ("grazing", "existence"):
            detail += " [formal orbit, not viable]"
        return BifurcationEvent(kind=kind, parameter=float(pt.u[-1]), point=s,
                                multipliers=pt.mult.copy(), index=index, detail=detail,
                                test_value=float(fv), located=bool(ok), viable=pt.viable,
                                xm=pt.xm)

    def size(pa, pb):
        return abs(pb.u[-1] - pa.u[-1]) / max(1.0, abs(pa.u[-1]))

    tracker = _Tracker(events, evaluate_between, size, event_tol, 80, locate, to_event)

    def extra_events(pa, pb, index):
        out = []
        ma, mb = pa.margin, pb.margin
        grazed = _changes(ma, mb)
        if "grazing" in events and grazed:
            out.append(tracker._root(
                "grazing", lambda pt: pt.margin, pa, pb, index,
                lambda pt: ("viability margin crosses 0: the orbit "
                            f"{'stops' if mb < ma else 'starts'} existing by grazing (19)")))
        if "existence" in events and (pa.formal != pb.formal
                                      or (pa.viable != pb.viable and not grazed)):
            def same(pt):
                return (pt.formal, pt.viable) == (pa.formal, pa.viable)
            if locate:
                la, lb, ok = _bisect_predicate(lambda th: evaluate_between(pa, pb, th), same,
                                               pa, pb, size=size(pa, pb), tol=event_tol,
                                               max_iter=80)
            else:
                la, lb, ok = pa, pb, False
            pt = la if la.formal else lb
            ev = to_event("existence", pt, index,
                          f"{REASONS[pa.reason]} -> {REASONS[pb.reason]}", np.nan, ok)
            out.append(ev)
        return out

    pts = [point(p0)]
    evs = []
    rejected = 0
    termination = f"max_steps = {max_steps} reached"
    h = min(step, max_step)
    for _ in range(max_steps):
        cur = pts[-1]
        pc = cur.u[-1]
        for _h in range(_MAX_HALVINGS):
            pn = pc + direction * h
            if (pn - stop) * direction > 0:
                pn = stop
            if not _in_domain(name, pn):
                pn = stop
            new = point(pn)
            ch = _change(cur, new)
            if ch <= max_change or h <= min_step:
                break
            rejected += 1
            h = max(0.5 * h, min_step)
        idx = len(pts) - 1
        evs.extend(tracker.detect(cur, new, idx, extra_events(cur, new, idx)))
        pts.append(new)
        if ch <= max_change / 3:
            h = min(1.5 * h, max_step)
        if pn == stop:
            termination = "reached stop"
            break
    fixed = {k: v for k, v in base.items() if k != name}
    fixed.update({"n": n, "case": case.value})
    br = _branch_from_points(pts, evs, name, None, 1, "closed_form", termination, rejected,
                             omega=omega, case=case, fixed=fixed)
    return br


def _change(a, b):
    """Size of the change between two closed-form points (for the step control)."""
    if a.formal != b.formal or a.viable != b.viable:
        return math.inf
    sa, sb = a.u[:4], b.u[:4]
    if not (np.all(np.isfinite(sa)) and np.all(np.isfinite(sb))):
        return 0.0
    ch = float(np.max(np.abs(sb[1:] - sa[1:]))) / (1.0 + float(np.max(np.abs(sa[1:]))))
    # the phase lives on a circle of length T: a wrap from T to 0 is no change
    ch = max(ch, abs(_wrap_diff(sb[0] - sa[0], a.T)) / (1.0 + abs(sa[0])))
    if np.isfinite(a.rho) and np.isfinite(b.rho):
        # only the neighbourhood of the unit circle matters for the step: far outside it the
        # radius may grow by orders of magnitude without any event
        ch = max(ch, abs(min(b.rho, 2.0) - min(a.rho, 2.0)))
    if np.isfinite(a.margin) and np.isfinite(b.margin):
        ch = max(ch, abs(b.margin - a.margin))
    return ch


# ----------------------------------------------------------------------------------------
# Plotting
# ----------------------------------------------------------------------------------------

_EVENT_STYLE = {
    "fold": ("s", "tab:red"),
    "period_doubling": ("D", "tab:purple"),
    "neimark_sacker": ("*", "tab:green"),
    "grazing": ("v", "black"),
    "stability_change": ("o", "tab:orange"),
    "existence": ("x", "tab:gray"),
}


def plot_branch(branch: Branch, ax=None, quantity="spectral_radius", *, events: bool = True,
                label: str | None = None, logy: bool | None = None):
    """Plot a branch: a quantity against the parameter, with its events marked.

    Stable parts are drawn solid, unstable parts dashed, non-viable (formal) parts dotted.

    Parameters
    ----------
    branch : Branch
    ax : matplotlib Axes, optional
        Drawn into when given; otherwise a new :class:`matplotlib.figure.Figure` (no pyplot)
        is created.
    quantity : str or int
        ``"spectral_radius"`` (with the unit level), ``"margin"`` (with 0), ``"xm"``,
        ``"min_impact_speed"``, ``"multipliers"`` (all moduli) or a coordinate index
        0-3 of the fixed point ``(phi, z1, z2, z4)``.
    events : bool
        Mark the events (one marker style per kind, labelled in the legend).
    label : str, optional
        Legend label of the curve.
    logy : bool, optional
        Logarithmic y axis; default: for ``spectral_radius``/``multipliers`` when the values
        span more than two decades.

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains
    >>> br = continue_symmetric(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0, "kv", 23.0)
    >>> fig = plot_branch(br, quantity="margin")
    >>> fig.axes[0].get_xlabel()
    'kv'
    """
    if ax is None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(6, 4))
        ax = fig.add_subplot(1, 1, 1)
    else:
        fig = ax.figure
    p = branch.parameter
    names = {0: "phi", 1: "z1", 2: "z2", 3: "z4"}
    if quantity == "multipliers":
        Y = np.abs(branch.multipliers)
        ylabel = "|multipliers|"
    elif isinstance(quantity, (int, np.integer)) and 0 <= int(quantity) <= 3:
        Y = branch.points[:, int(quantity)][:, None]
        ylabel = names[int(quantity)]
    elif quantity in ("spectral_radius", "margin", "xm", "min_impact_speed"):
        Y = np.asarray(getattr(branch, quantity), float)[:, None]
        ylabel = quantity.replace("_", " ")
    else:
        raise ValueError("quantity must be 'spectral_radius', 'margin', 'xm', "
                         f"'min_impact_speed', 'multipliers' or 0-3, got {quantity!r}")
    st = branch.stable
    un = branch.viable & ~branch.stable
    nv = ~branch.viable
    color = None
    for j in range(Y.shape[1]):
        y = Y[:, j]
        line, = ax.plot(p, np.where(st | _grow(st), y, np.nan), "-", color=color, lw=1.6,
                        label=(label or branch.parameter_name + " branch") + " (stable)"
                        if j == 0 else None)
        color = line.get_color()
        ax.plot(p, np.where(un | _grow(un), y, np.nan), "--", color=color, lw=1.2,
                label="unstable" if j == 0 and un.any() else None)
        if nv.any():
            ax.plot(p, np.where(nv | _grow(nv), y, np.nan), ":", color=color, lw=1.0,
                    label="not viable (formal)" if j == 0 else None)
    if quantity in ("spectral_radius", "multipliers"):
        ax.axhline(1.0, color="gray", lw=0.8)
        finite = Y[np.isfinite(Y) & (Y > 0)]
        if logy is None:
            logy = finite.size > 0 and finite.max() / max(finite.min(), 1e-300) > 100
    elif quantity == "margin":
        ax.axhline(0.0, color="gray", lw=0.8)
    if logy:
        ax.set_yscale("log")
    if events:
        seen = set()
        for ev in branch.events:
            mk, c = _EVENT_STYLE.get(ev.kind, ("o", "k"))
            yv = _event_y(branch, ev, quantity)
            ax.plot([ev.parameter], [yv], mk, color=c, ms=8, mfc="none" if mk != "x" else c,
                    mew=1.5, label=ev.kind.replace("_", " ") if ev.kind not in seen else None)
            seen.add(ev.kind)
    ax.set_xlabel(branch.parameter_name)
    ax.set_ylabel(ylabel)
    ax.legend(fontsize=7, loc="best")
    return fig


def _grow(mask):
    """Extend a mask by one point on each side, so that solid/dashed pieces connect."""
    m = mask.copy()
    m[1:] |= mask[:-1]
    m[:-1] |= mask[1:]
    return m


def _event_y(branch, ev, quantity):
    if quantity in ("spectral_radius", "multipliers"):
        return float(np.max(np.abs(ev.multipliers))) if np.all(np.isfinite(ev.multipliers)) \
            else 1.0
    if isinstance(quantity, (int, np.integer)):
        return float(ev.point[int(quantity)])
    if quantity == "margin" and ev.kind == "grazing":
        return 0.0
    if quantity == "xm":
        return ev.xm
    i = min(ev.index, len(branch) - 2)
    y = np.asarray(getattr(branch, quantity), float)
    pa, pb = branch.parameter[i], branch.parameter[i + 1]
    w = 0.0 if pb == pa else (ev.parameter - pa) / (pb - pa)
    return float(y[i] + w * (y[i + 1] - y[i]))
