"""Simple symmetric periodic orbits (paper section 3): existence, viability and stability.

An orbit of odd order ``n`` has one impact on each wall per period ``n T`` (``T = 2 pi / w``),
``n T / 2`` apart, and is symmetric about the origin. The desired primary-mass motion is a
triangle wave between ``+x10`` and ``-x10``; the required reference amplitude ``xm`` and the
impact phase ``phi0`` follow from the linear conditions (13)-(14) (derived in
:mod:`hybridpd.pair.symbolic`).

**Existence** (paper (17)-(18)) means: the conditions have a solution (``xm > 0``) *and* the
flight between the two impacts is viable — no other contact on the open interval. Viability is
decided by the guaranteed first-contact location of :mod:`hybridpd.pair.batch` (a contact located
before ``n T / 2`` is a violation, reported with its time, wall and position), not by
sampling. The **viability margin** is ``min (L - |z3|) / L`` over the interior turning points
of ``z3 = x1 - x2`` (1 when ``z3`` is monotone; it tends to 0 at the grazing boundary (19)
and is negative when violated); it is a diagnostic computed by sampling and refinement.

**Stability** (paper section 4): the eigenvalues of ``DP = DP43 DP32 DP21 DP10`` (Floquet
multipliers of the impact map) from the symbolic blocks; stable iff all have modulus < 1;
hyperbolic iff none has modulus within ``1e-9`` of 1.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hybridpd._jit import njit
from hybridpd._results import compact_repr
from hybridpd.model import (
    Case,
    ImpactPair,
    PDGains,
    Reference,
    as_gains,
    check_array,
    check_int,
    check_odd_order,
    check_positive,
)
from hybridpd.pair import symbolic
from hybridpd.pair.batch import (
    STATUS_IMPACT,
    STATUS_STICK,
    Flight,
    Flights,
    _eval,
    flight_at,
    next_impact,
    turning_margins,
)

__all__ = ["REASONS", "OrbitArrays", "SymmetricOrbitResult", "symmetric_orbit", "symmetric_orbits"]

#: Codes of :attr:`OrbitArrays.reason`.
REASONS = {
    0: "exists",
    1: "no solution: the symmetry conditions (13)-(14) are singular",
    2: "no solution: xm = 0",
    3: "viability violated: extra contact between the impacts",
    4: "viability violated: the masses stick after the impact (zero rebound, force pressing)",
    5: "viability undecided: contact location did not resolve"}

_HYPERBOLIC_TOL = 1e-9
_END_RTOL = 1e-7   # a contact this close to n T / 2 (relative) is the orbit's own impact


@njit(cache=True)
def _viability_kernel(P, case, fl, tol, margin, nsamp):
    """Per point: (code, contact time, contact wall, contact x1, margin) of the half-period
    flights ``fl`` (:class:`~hybridpd.pair.batch.Flights`)."""
    N = P.shape[0]
    code = np.zeros(N, dtype=np.int64)
    t_c = np.full(N, np.nan)
    w_c = np.zeros(N, dtype=np.int64)
    x_c = np.full(N, np.nan)
    marg = np.full(N, np.nan)
    tau = fl.tau
    for i in range(N):
        p = P[i]
        f = flight_at(fl, i)
        st, t, wall, X1, _Y1, _X2, _Y2, _graze = next_impact(
            p, case, f, tau[i] * (1 + 10 * _END_RTOL), tol)
        if st == STATUS_STICK:
            code[i] = 4
            t_c[i] = t
            w_c[i] = wall
            x_c[i] = X1
            continue
        if st != STATUS_IMPACT:
            code[i] = 5
            continue
        if t < tau[i] * (1 - _END_RTOL) or wall != -1:
            code[i] = 3
            t_c[i] = t
            w_c[i] = wall
            x_c[i] = X1
        if margin:
            marg[i] = turning_margins(p, case, f, tau[i], nsamp)[0]
    return code, t_c, w_c, x_c, marg


def _check_array(name, value, lo=None, lo_open=True, hi=None):
    return check_array(name, value, lo=lo, lo_open=lo_open, hi=hi)


@dataclass(frozen=True)
class OrbitArrays:
    """Vectorised symmetric-orbit results (all arrays share the broadcast input shape).

    Attributes
    ----------
    case : Case
    exists : ndarray of bool
        Solvable with ``xm > 0`` and viable.
    reason : ndarray of int
        Code into :data:`REASONS` (0 when the orbit exists).
    xm, phi0 : ndarray
        Required reference amplitude (length) and impact phase in ``[0, T)`` (time); NaN
        where singular.
    multipliers : ndarray, shape (..., 4), complex
        Eigenvalues of ``DP``, sorted by decreasing modulus (NaN where the orbit does not
        exist).
    spectral_radius : ndarray
        ``max |multiplier|`` (NaN where the orbit does not exist).
    stable, hyperbolic : ndarray of bool
        ``exists and spectral_radius < 1``; no multiplier within 1e-9 of the unit circle.
    viability_margin : ndarray
        See the module docstring (NaN unless requested).
    violation_time, violation_wall, violation_x1 : ndarray
        Where the extra contact happened (time after the +L impact, wall, ``x1``); NaN/0
        when viable.
    fixed_point : ndarray, shape (..., 4)
        Pre-impact section point ``(phi0, x20, y2-, v - y2-)`` (the fixed point of P).
    DP : ndarray, shape (..., 4, 4)
        Jacobian of the impact map at the fixed point.
    candidate : symbolic.SymmetricOrbit
        The raw solution of (13)-(14) (velocities, ``C``, ``S``, ``R``, ...).
    """

    __repr__ = compact_repr

    case: Case
    exists: np.ndarray
    reason: np.ndarray
    xm: np.ndarray
    phi0: np.ndarray
    multipliers: np.ndarray
    spectral_radius: np.ndarray
    stable: np.ndarray
    hyperbolic: np.ndarray
    viability_margin: np.ndarray
    violation_time: np.ndarray
    violation_wall: np.ndarray
    violation_x1: np.ndarray
    fixed_point: np.ndarray
    DP: np.ndarray = field(repr=False)
    candidate: object = field(repr=False)


def symmetric_orbits(kp, kv, *, mu, e, L, omega, m2=1.0, x10=1.0, n=1, case="collocated",
                     margin=False, jacobian=True, tol=1e-13, margin_samples=256) -> OrbitArrays:
    """Existence, viability and stability of symmetric orbits over arrays of parameters.

    Every parameter broadcasts (e.g. ``kp[None, :]``, ``kv[:, None]`` for a gain map).

    Parameters
    ----------
    kp, kv : array_like
        PD gains, > 0.
    mu, e, L, omega, m2 : array_like
        Mass ratio (> 0), restitution in [0, 1], half clearance (> 0), reference frequency
        (rad/time, > 0), secondary mass (> 0).
    x10 : array_like
        Desired primary-mass amplitude (> 0).
    n : int
        Odd orbit order.
    case : {"collocated", "noncollocated"}
    margin : bool
        Also compute the viability margin (costs ~``margin_samples`` flow evaluations/point).
    jacobian : bool
        Compute ``DP`` and the multipliers.
    tol : float
        Gap tolerance (length) of the contact location.

    Returns
    -------
    OrbitArrays
        Every field has the broadcast shape of the parameters.

    Raises
    ------
    ValueError
        If a parameter is out of its range or ``n`` is not odd.

    Examples
    --------
    >>> import numpy as np
    >>> import hybridpd as hp
    >>> oa = hp.symmetric_orbits(np.array([5.0, 10.0, 40.0]), 20.0, mu=0.1, e=0.5, L=0.75,
    ...                          omega=5.0)
    >>> oa.exists, oa.stable
    (array([ True,  True,  True]), array([ True,  True,  True]))
    >>> oa.spectral_radius.round(4)
    array([0.7272, 0.5238, 0.1334])
    """
    case = Case.parse(case)
    n = check_odd_order(n)
    kp = _check_array("kp", kp, 0.0)
    kv = _check_array("kv", kv, 0.0)
    mu = _check_array("mu", mu, 0.0)
    e = _check_array("e", e, 0.0, lo_open=False, hi=1.0)
    L = _check_array("L", L, 0.0)
    omega = _check_array("omega", omega, 0.0)
    m2 = _check_array("m2", m2, 0.0)
    x10 = _check_array("x10", x10, 0.0)
    tol = check_positive("tol", tol)
    margin_samples = check_int("margin_samples", margin_samples, 2)
    kp, kv, mu, e, L, omega, m2, x10 = np.broadcast_arrays(kp, kv, mu, e, L, omega, m2, x10)
    shape = kp.shape
    cand = symbolic.solve_symmetric_orbit(kp=kp, kv=kv, m2=m2, mu=mu, e=e, L=L, w=omega, x10=x10, n=n,
                                    case=case.value)
    xm = np.broadcast_to(cand.xm, shape).astype(float)
    singular = np.broadcast_to(np.asarray(cand.singular, bool), shape) | ~np.isfinite(xm)
    reason = np.zeros(shape, dtype=np.int64)
    reason[singular] = 1
    reason[(~singular) & (xm <= 0)] = 2
    ok = reason == 0

    flat = lambda a: np.ascontiguousarray(np.broadcast_to(a, shape), dtype=float).ravel()
    P = np.stack([flat(kp), flat(kv), flat(m2), flat(mu), flat(e), flat(L), flat(omega),
                  np.where(ok, xm, 0.0).ravel()], axis=1)
    idx = np.flatnonzero(ok.ravel())
    code = np.zeros(P.shape[0], dtype=np.int64)
    t_c = np.full(P.shape[0], np.nan)
    w_c = np.zeros(P.shape[0], dtype=np.int64)
    x_c = np.full(P.shape[0], np.nan)
    marg = np.full(P.shape[0], np.nan)
    if idx.size:
        sub = lambda a: flat(a)[idx]
        # a handful of orbits: interpreting beats loading numba (see hybridpd._jit)
        fl = Flights(sub(cand.phi0), sub(cand.x10), -sub(cand.v), sub(cand.x20),
                     sub(cand.y2_post), sub(cand.tau))
        r = _viability_kernel.call(idx.size <= 16, np.ascontiguousarray(P[idx]),
                                   0 if case is Case.COLLOCATED else 1, fl, tol, bool(margin),
                                   int(margin_samples))
        code[idx], t_c[idx], w_c[idx], x_c[idx], marg[idx] = r
    reason.ravel()[:] = np.where(reason.ravel() == 0, code, reason.ravel())
    exists = reason == 0

    fixed = np.broadcast_to(cand.section_point, shape + (4,)).astype(float)
    mult = np.full(shape + (4,), np.nan + 0j)
    DP = np.full(shape + (4, 4), np.nan)
    if jacobian and np.any(exists):
        jac = symbolic.orbit_jacobian(cand)
        DPall = np.broadcast_to(jac.DP, shape + (4, 4))
        DP[exists] = DPall[exists]
        ev = np.linalg.eigvals(DP[exists])
        order = np.argsort(-np.abs(ev), axis=-1)
        mult[exists] = np.take_along_axis(ev, order, axis=-1)
    rho = np.max(np.abs(mult), axis=-1)
    rho = np.where(exists, rho, np.nan)
    stable = exists & (rho < 1.0)
    hyper = exists & np.all(np.abs(np.abs(mult) - 1.0) > _HYPERBOLIC_TOL, axis=-1)
    return OrbitArrays(
        case=case, exists=exists, reason=reason, xm=np.where(singular, np.nan, xm),
        phi0=np.where(singular, np.nan, np.broadcast_to(cand.phi0, shape)),
        multipliers=mult, spectral_radius=rho, stable=stable, hyperbolic=hyper,
        viability_margin=marg.reshape(shape), violation_time=t_c.reshape(shape),
        violation_wall=w_c.reshape(shape), violation_x1=x_c.reshape(shape),
        fixed_point=fixed, DP=DP, candidate=cand)


@dataclass(frozen=True)
class SymmetricOrbitResult:
    """One symmetric orbit of order ``n`` with its existence, viability and stability.

    Attributes
    ----------
    exists : bool
    reason : str
        Human-readable reason (``"exists"`` or why not; a viability violation says where and
        when).
    case : Case
    pair : ImpactPair
    gains : PDGains
    omega, x10, n : float, float, int
    xm : float
        Reference amplitude realising the orbit (20).
    phi0 : float
        Phase of the ``+L`` impact in ``[0, T)``; ``t0 = phi0`` is one impact time.
    t0, T, tau : float
        Impact time, period of the reference, flight time ``n T / 2``.
    R : float
        Virtual restitution coefficient (12).
    pre_plus, post_plus, pre_minus, post_minus : ndarray, shape (4,)
        ``[x1, y1, x2, y2]`` before/after the impacts on the ``+L`` and ``-L`` walls.
    fixed_point : ndarray, shape (4,)
        Pre-impact section point ``(phi0, z1, z2, z4)``: the fixed point of ``P``.
    DP : ndarray, shape (4, 4) or None
        Jacobian of the impact map; ``blocks`` holds ``DP10, DP21, DP32, DP43``.
    multipliers : ndarray, shape (4,), complex or None
        Eigenvalues of ``DP``, by decreasing modulus.
    spectral_radius : float or None
    stable : bool or None
        ``None`` where the orbit does not exist.
    hyperbolic : bool or None
    viability_margin : float
        ``min (L - |z3|)/L`` over interior turning points of ``z3`` (1 if monotone).
    grazing : bool
        Margin below ``1e-6``: at the existence boundary (19).
    violation : dict or None
        ``{"t": time after t0, "wall": +-1, "x1": position}`` of an extra contact.
    """

    __repr__ = compact_repr

    exists: bool
    reason: str
    case: Case
    pair: ImpactPair
    gains: PDGains
    omega: float
    x10: float
    n: int
    xm: float
    phi0: float
    t0: float
    T: float
    tau: float
    R: float
    pre_plus: np.ndarray
    post_plus: np.ndarray
    pre_minus: np.ndarray
    post_minus: np.ndarray
    fixed_point: np.ndarray
    DP: np.ndarray | None
    blocks: dict | None
    multipliers: np.ndarray | None
    spectral_radius: float | None
    stable: bool | None
    hyperbolic: bool | None
    viability_margin: float
    grazing: bool
    violation: dict | None

    def reference(self) -> Reference:
        """The reference ``xd = xm cos(omega t)`` that realises the orbit."""
        return Reference(self.xm, self.omega)

    def system(self):
        """The :class:`~hybridpd.pair.impactpair.ControlledImpactPair` with this orbit's reference."""
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.pair.impactpair import ControlledImpactPair

        return ControlledImpactPair(self.pair, self.gains, self.reference(), self.case)

    def flight(self, t) -> np.ndarray:
        """``[x1, y1, x2, y2]`` at times ``t`` in ``[t0, t0 + tau]`` (the half-period flight)."""
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.pair.batch import pack_params

        p = pack_params(kp=self.gains.kp, kv=self.gains.kv, m2=self.pair.m2, mu=self.pair.mu,
                        e=self.pair.e, L=self.pair.L, w=self.omega, xm=self.xm)
        c = 0 if self.case is Case.COLLOCATED else 1
        t = np.asarray(t, float)
        fl = Flight(float(self.t0), *(float(v) for v in self.post_plus))
        out = np.array([_eval(p, c, fl, s - self.t0, 0.0)[:4] for s in t.ravel()])
        return out.reshape(t.shape + (4,))

    def to_dict(self) -> dict:
        """JSON-ready summary (the CLI's ``orbit --json`` format)."""
        def f(x):
            return None if x is None or not np.isfinite(x) else float(x)

        return {
            "case": self.case.value, "exists": bool(self.exists), "reason": self.reason,
            "xm": f(self.xm), "phi0": f(self.phi0), "t0": f(self.t0), "T": self.T,
            "tau": self.tau, "R": self.R, "n": self.n, "x10": self.x10,
            "kp": self.gains.kp, "kv": self.gains.kv, "mu": self.pair.mu, "e": self.pair.e,
            "L": self.pair.L, "m2": self.pair.m2, "omega": self.omega,
            "fixed_point": [float(v) for v in self.fixed_point],
            "pre_plus": [float(v) for v in self.pre_plus],
            "post_plus": [float(v) for v in self.post_plus],
            "multipliers": None if self.multipliers is None else
            [[float(z.real), float(z.imag)] for z in self.multipliers],
            "spectral_radius": f(self.spectral_radius),
            "stable": self.stable, "hyperbolic": self.hyperbolic,
            "viability_margin": f(self.viability_margin), "grazing": bool(self.grazing),
            "violation": self.violation}


def symmetric_orbit(pair: ImpactPair, gains: PDGains, omega: float, *, x10: float = 1.0,
                    n: int = 1, case="collocated", tol: float = 1e-13) -> SymmetricOrbitResult:
    """Find the simple symmetric orbit of order ``n`` realising the primary-mass amplitude ``x10``.

    Parameters
    ----------
    pair : ImpactPair
    gains : PDGains
    omega : float
        Reference frequency (rad/time).
    x10 : float
        Desired amplitude of the primary mass (length); ``gamma = L / x10``.
    n : int
        Odd order (period ``n T``).
    case : {"collocated", "noncollocated"}

    Returns
    -------
    SymmetricOrbitResult

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains
    >>> orb = symmetric_orbit(ImpactPair(mu=0.1, e=0.5, L=0.75), PDGains(10, 20), omega=5)
    >>> orb.exists, orb.stable
    (True, True)
    >>> round(orb.xm, 6) > 0
    True
    """
    if not isinstance(pair, ImpactPair):
        raise ValueError(f"pair must be an ImpactPair, got {type(pair).__name__}")
    gains = as_gains(gains)
    omega = check_positive("omega", omega)
    x10 = check_positive("x10", x10)
    n = check_odd_order(n)
    case = Case.parse(case)
    r = symmetric_orbits(gains.kp, gains.kv, mu=pair.mu, e=pair.e, L=pair.L, omega=omega,
                         m2=pair.m2, x10=x10, n=n, case=case, margin=True, tol=tol)
    cand = r.candidate
    code = int(r.reason)
    exists = bool(r.exists)
    sc = lambda a: float(np.asarray(a).reshape(-1)[0])
    v, y2m, y2p = sc(cand.v), sc(cand.y2_pre), sc(cand.y2_post)
    x20 = x10 - pair.L
    pre_plus = np.array([x10, v, x20, y2m])
    post_plus = np.array([x10, -v, x20, y2p])
    violation = None
    reason = REASONS[code]
    if code in (3, 4):
        violation = {"t": float(r.violation_time), "wall": int(r.violation_wall),
                     "x1": float(r.violation_x1)}
        reason += (f" (contact on wall {int(r.violation_wall):+d} at t0 + "
                   f"{float(r.violation_time):.6g}, x1 = {float(r.violation_x1):.6g})")
    DP = blocks = mult = rho = stable = hyper = None
    if exists:
        jac = symbolic.orbit_jacobian(cand)
        DP = np.asarray(jac.DP).reshape(4, 4)
        blocks = {k: np.asarray(getattr(jac, k)).reshape(4, 4)
                  for k in ("DP10", "DP21", "DP32", "DP43")}
        mult = np.asarray(r.multipliers).reshape(4)
        rho = float(r.spectral_radius)
        stable = bool(r.stable)
        hyper = bool(r.hyperbolic)
    margin = float(r.viability_margin)
    T = 2 * math.pi / omega
    phi0 = float(r.phi0)
    return SymmetricOrbitResult(
        exists=exists, reason=reason, case=case, pair=pair, gains=gains, omega=omega, x10=x10,
        n=n, xm=float(r.xm), phi0=phi0, t0=phi0, T=T, tau=n * T / 2, R=pair.R,
        pre_plus=pre_plus, post_plus=post_plus, pre_minus=-pre_plus, post_minus=-post_plus,
        fixed_point=np.asarray(r.fixed_point, float).reshape(4), DP=DP, blocks=blocks,
        multipliers=mult, spectral_radius=rho, stable=stable, hyperbolic=hyper,
        viability_margin=margin, grazing=bool(np.isfinite(margin) and abs(margin) < 1e-6),
        violation=violation)
