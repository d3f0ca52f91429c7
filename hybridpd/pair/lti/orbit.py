"""Simple symmetric orbits of odd order under any LTI controller, with viability and stability.

:func:`lti_symmetric_orbit` solves the ``2 + k`` linear symmetry conditions through
``expm(A tau)``, decides viability (18) by guaranteed event location and computes ``DP``
by implicit differentiation (derivation and conventions: :mod:`hybridpd.pair.lti`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.linalg import expm

from hybridpd._results import compact_repr
from hybridpd.analysis.floquet import stability
from hybridpd.hybrid.events import EV_CROSSING, EV_GRAZING, EV_START, lti_flow
from hybridpd.loop import ClosedLoop, closed_loop
from hybridpd.model import Case, ImpactPair, Reference, check_int, check_odd_order, check_positive
from hybridpd.pair.lti.flight import (
    _WALL_PLUS,
    _flight_block,
    _FreeFlight,
    _impact_block,
    _impact_full,
)
from hybridpd.pair.orbits import _END_RTOL, _HYPERBOLIC_TOL, REASONS

__all__ = ["LTI_REASONS", "LTIOrbitResult", "lti_symmetric_orbit"]

#: Reason codes of :attr:`LTIOrbitResult.code`: the same as for the PD fast path.
LTI_REASONS = REASONS


@dataclass(frozen=True)
class LTIJacobian:
    """Jacobian of the impact map on the extended section, by implicit differentiation.

    Attributes
    ----------
    DP : ndarray, shape (m, m)
        ``d P / d s`` with ``s = (phi, z1, z2, z4, c1..ck)``, ``m = 4 + k``; the phase is
        unwrapped (``phi_out = phi_in + sum(taus)``).
    blocks : tuple of ndarray, each (m, m)
        Impact and flight blocks in application order (``DP10, DP21, DP32, DP43`` for the
        simple pattern); ``DP`` is their product in reverse order.
    names : tuple of str
        Names of the blocks (``"impact+"``, ``"flight->-"``, ...).
    walls : tuple of int
        Walls of the contacts after the initial impact.
    taus : ndarray
        Flight times used.
    """

    __repr__ = compact_repr

    DP: np.ndarray
    blocks: tuple
    names: tuple
    walls: tuple
    taus: np.ndarray

    def as_dict(self) -> dict:
        """``{"DP10", "DP21", "DP32", "DP43"}`` for the simple pattern (``ValueError`` otherwise)."""
        if tuple(self.walls) != (-1, 1):
            raise ValueError(f"the named blocks need the pattern (-1, +1), got {self.walls}")
        return dict(zip(("DP10", "DP21", "DP32", "DP43"), self.blocks))


@dataclass(frozen=True)
class LTIOrbitResult:
    """A simple symmetric orbit of order ``n`` under an LTI controller.

    Attributes
    ----------
    exists : bool
        Symmetry conditions solvable with ``xm > 0`` and the flight viable.
    code : int
        Key of :data:`LTI_REASONS` (0 when the orbit exists).
    reason : str
        Human-readable reason; a viability violation says where and when.
    case : Case
    pair : ImpactPair
    controller : object
        The controller as given.
    loop : ClosedLoop
        Closed loop between impacts (built with ``xm = 1``; its ``A`` does not depend on
        ``xm``).
    omega, x10 : float
        Reference frequency (rad/time) and desired primary-mass amplitude (length).
    n : int
        Odd order (period ``n T``).
    n_controller_states : int
        ``k``.
    xm : float
        Reference amplitude (length) realising the orbit (NaN when singular).
    phi0 : float
        Phase of the ``+L`` impact in ``[0, T)``; ``t0 = phi0`` is one impact time.
    t0, T, tau : float
        Impact time, period ``2 pi / omega`` and flight time ``n T / 2`` (time).
    R : float
        Virtual restitution coefficient (12).
    pre_plus, post_plus, pre_minus, post_minus : ndarray, shape (4,)
        ``[x1, y1, x2, y2]`` before/after the impacts on the ``+L`` and ``-L`` walls.
    controller_state : ndarray, shape (k,)
        ``c0``: controller state at the ``+L`` impact (``-c0`` at the ``-L`` impact).
    state_plus : ndarray, shape (n_states,)
        Full closed-loop state just before the ``+L`` impact (``-state_plus`` before ``-L``).
    fixed_point : ndarray, shape (4 + k,)
        ``(phi0, x20, y2-, v - y2-, c0)``: the fixed point of :meth:`section_map`.
    condition : float
        2-norm condition number of the ``(2 + k)`` linear symmetry conditions after row and
        column equilibration (so independent of the units of the controller states).
    residual : float
        Max abs deviation of the flown state at ``t0 + tau`` from ``-state_plus``.
    DP : ndarray, shape (4 + k, 4 + k) or None
        Jacobian of the impact map at the fixed point (implicit differentiation).
    blocks : dict or None
        ``DP10, DP21, DP32, DP43`` (``DP = DP43 DP32 DP21 DP10``).
    multipliers : ndarray, shape (4 + k,), complex, or None
        Eigenvalues of ``DP`` by decreasing modulus.
    spectral_radius : float or None
    stable, hyperbolic : bool or None
        ``None`` where the orbit does not exist.
    viability_margin : float
        ``min (L - |z3|)/L`` over interior turning points of ``z3`` (1 if monotone; sampled
        and refined, a diagnostic). NaN if not computed.
    grazing : bool
        ``|viability_margin| < 1e-6``: at the existence boundary (19).
    violation : dict or None
        ``{"t": time after t0, "wall": +-1, "x1": position}`` of the extra contact.
    DP_fd_error : float or None
        :meth:`fd_error` (only when requested with ``fd_check=True``).
    """

    __repr__ = compact_repr

    exists: bool
    code: int
    reason: str
    case: Case
    pair: ImpactPair
    controller: object = field(repr=False)
    loop: ClosedLoop = field(repr=False)
    omega: float = math.nan
    x10: float = math.nan
    n: int = 1
    n_controller_states: int = 0
    xm: float = math.nan
    phi0: float = math.nan
    t0: float = math.nan
    T: float = math.nan
    tau: float = math.nan
    R: float = math.nan
    pre_plus: np.ndarray = field(default=None, repr=False)
    post_plus: np.ndarray = field(default=None, repr=False)
    pre_minus: np.ndarray = field(default=None, repr=False)
    post_minus: np.ndarray = field(default=None, repr=False)
    controller_state: np.ndarray = field(default=None, repr=False)
    state_plus: np.ndarray = field(default=None, repr=False)
    fixed_point: np.ndarray = field(default=None, repr=False)
    condition: float = math.nan
    residual: float = math.nan
    DP: np.ndarray | None = field(default=None, repr=False)
    blocks: dict | None = field(default=None, repr=False)
    multipliers: np.ndarray | None = None
    spectral_radius: float | None = None
    stable: bool | None = None
    hyperbolic: bool | None = None
    viability_margin: float = math.nan
    grazing: bool = False
    violation: dict | None = None
    DP_fd_error: float | None = None

    def reference(self) -> Reference:
        """The reference ``xd = xm cos(omega t)`` that realises the orbit."""
        return Reference(self.xm, self.omega)

    def coordinate_scale(self, samples: int = 200) -> np.ndarray:
        """Natural scale of each section coordinate on this orbit, shape ``(4 + k,)``.

        ``1/omega`` for the phase and ``max |.|`` over the flight for ``z1, z2, z4`` and each
        controller state (1 where a coordinate vanishes identically). Used to scale finite
        difference steps and to compare Jacobians independently of the controller's
        realisation (``D^-1 DP D`` with ``D = diag(scale)``).
        """
        if self.state_plus is None or not np.isfinite(self.xm):
            raise ValueError("the orbit has no solution: no coordinate scale")
        Z = self.flight(np.linspace(self.t0, self.t0 + self.tau, int(samples)))
        sc = np.concatenate([[1.0 / self.omega], np.abs(Z[:, 2]).max(0, keepdims=True),
                             np.abs(Z[:, 3]).max(0, keepdims=True),
                             np.abs(Z[:, 1] - Z[:, 3]).max(0, keepdims=True),
                             np.abs(Z[:, 6:]).max(0)])
        sc[~(sc > 0)] = 1.0
        return sc

    def fd_error(self, h: float = 1e-5, richardson: bool = True) -> float:
        """Scaled distance between ``DP`` and finite differences of the simulated map.

        ``max |D^-1 (DP_fd - DP) D| / max |D^-1 DP D|`` with ``D = diag(coordinate_scale())``
        and ``DP_fd`` from :meth:`section_map`'s ``jacobian_fd`` (relative step ``h``, Richardson
        extrapolation by default, which the strongly expanding non-collocated maps need).
        """
        if self.DP is None:
            raise ValueError("the orbit does not exist: no DP")
        sc = self.coordinate_scale()
        J = self.section_map().jacobian_fd(self.fixed_point, h=h, scale=sc, richardson=richardson)
        Ds = self.DP * sc[None, :] / sc[:, None]
        err = (J - self.DP) * sc[None, :] / sc[:, None]
        return float(np.abs(err).max() / np.abs(Ds).max())

    def section_map(self, **options):
        """The impact map of :meth:`system` on the pre-impact section ``z3 = +L``, ``z4 > 0``.

        The general :class:`~hybridpd.analysis.hybridmap.SectionMap` of
        :func:`~hybridpd.pair.section.impact_pair_section` (``options`` passed on to it):
        coordinates ``s = (phi, z1, z2, z4, c1..ck)``, whose fixed point is
        :attr:`fixed_point`.
        """
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.analysis.hybridmap import SectionMap
        from hybridpd.pair.section import impact_pair_section

        return SectionMap(impact_pair_section(self.system()), **options)

    def system(self):
        """The :class:`~hybridpd.pair.impactpair.ControlledImpactPair` with this orbit's reference.

        Start it on the orbit with ``simulate(orb.pre_plus, (orb.t0, t1),
        controller_state=orb.controller_state)``.
        """
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.pair.impactpair import ControlledImpactPair

        return ControlledImpactPair(self.pair, self.controller, self.reference(), self.case)

    def flight(self, t) -> np.ndarray:
        """Full states ``(..., n_states)`` at times ``t`` in ``[t0, t0 + tau]``."""
        t = np.asarray(t, float)
        z0 = _impact_full(self.pair, self.loop.n_states) @ self.state_plus
        out = lti_flow(self.loop.A, z0, t.ravel() - self.t0)
        return out.reshape(t.shape + (self.loop.n_states,))

    def to_dict(self) -> dict:
        """JSON-ready summary."""
        def f(x):
            return None if x is None or not np.isfinite(x) else float(x)

        def vec(a):
            return None if a is None else [float(v) for v in np.ravel(a)]

        return {
            "case": self.case.value, "exists": bool(self.exists), "reason": self.reason,
            "code": self.code, "xm": f(self.xm), "phi0": f(self.phi0), "t0": f(self.t0),
            "T": self.T, "tau": self.tau, "R": self.R, "n": self.n, "x10": self.x10,
            "omega": self.omega, "mu": self.pair.mu, "e": self.pair.e, "L": self.pair.L,
            "m2": self.pair.m2, "n_controller_states": self.n_controller_states,
            "controller_state": vec(self.controller_state),
            "fixed_point": vec(self.fixed_point), "pre_plus": vec(self.pre_plus),
            "post_plus": vec(self.post_plus), "condition": f(self.condition),
            "residual": f(self.residual),
            "multipliers": None if self.multipliers is None else
            [[float(z.real), float(z.imag)] for z in self.multipliers],
            "spectral_radius": f(self.spectral_radius), "stable": self.stable,
            "hyperbolic": self.hyperbolic, "viability_margin": f(self.viability_margin),
            "grazing": bool(self.grazing), "violation": self.violation,
            "DP_fd_error": f(self.DP_fd_error)}


def _viability_margin(A, z0, tau, L, nsamp):
    """``min (L - |z3|)/L`` over the interior turning points of ``z3`` on ``(0, tau)``."""
    from scipy.optimize import brentq

    ts = np.linspace(0.0, tau, int(nsamp) + 1)[1:-1]
    Z = lti_flow(A, z0, ts)
    z4 = Z[:, 1] - Z[:, 3]
    row = np.zeros(z0.size)
    row[1], row[3] = 1.0, -1.0

    def rel_vel(t):
        return row @ (expm(A * t) @ z0)

    m = 1.0
    for i in np.flatnonzero(z4[:-1] * z4[1:] < 0.0):
        tc = brentq(rel_vel, ts[i], ts[i + 1], xtol=1e-15 * max(1.0, tau), rtol=1e-15)
        zc = expm(A * tc) @ z0
        m = min(m, (L - abs(zc[0] - zc[2])) / L)
    return float(m)


def lti_symmetric_orbit(pair: ImpactPair, controller, omega: float, *, x10: float = 1.0,
                        n: int = 1, case="collocated", jacobian: bool = True,
                        margin: bool = True, margin_samples: int = 256, rcond: float = 1e-12,
                        fd_check: bool = False) -> LTIOrbitResult:
    """Simple symmetric orbit of odd order ``n`` under a general LTI controller (numerical).

    Parameters
    ----------
    pair : ImpactPair
    controller : PDGains, (kp, kv), control.StateSpace or control.TransferFunction
        From the tracking error (1 input) or ``[err, err_dot]`` (2 inputs) to the force
        (1 output); proper and continuous-time (see :mod:`hybridpd.loop`).
    omega : float
        Reference frequency (rad/time), ``> 0``.
    x10 : float
        Desired primary-mass amplitude (length), ``> 0``; ``gamma = L / x10``.
    n : int
        Odd order (period ``n T``).
    case : {"collocated", "noncollocated"}
    jacobian : bool
        Compute ``DP`` and the multipliers (when the orbit exists).
    margin : bool
        Compute the viability margin (``margin_samples`` exact flow samples plus refinement).
    rcond : float
        The symmetry conditions are singular when ``sigma_min <= rcond * sigma_max``.
    fd_check : bool
        Also compare ``DP`` with central differences of the simulated map
        (:attr:`LTIOrbitResult.DP_fd_error`).

    Returns
    -------
    LTIOrbitResult

    Raises
    ------
    ValueError
        Bad parameters or controller (improper, discrete-time, wrong numbers of inputs or
        outputs), even ``n``.

    Examples
    --------
    The PD as a python-control system reproduces the symbolic fast path:

    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.loop import pd_controller
    >>> from hybridpd.pair.orbits import symmetric_orbit
    >>> pair = ImpactPair(mu=0.1, e=0.5, L=0.75)
    >>> a = lti_symmetric_orbit(pair, pd_controller(10, 20), 5.0)
    >>> b = symmetric_orbit(pair, PDGains(10, 20), 5.0)
    >>> bool(abs(a.xm - b.xm) < 1e-12), bool(abs(a.spectral_radius - b.spectral_radius) < 1e-9)
    (True, True)
    """
    if not isinstance(pair, ImpactPair):
        raise ValueError(f"pair must be an ImpactPair, got {type(pair).__name__}")
    omega = check_positive("omega", omega)
    x10 = check_positive("x10", x10)
    n = check_odd_order(n)
    case = Case.parse(case)
    rcond = check_positive("rcond", rcond)
    margin_samples = check_int("margin_samples", margin_samples, 2)
    # A does not depend on xm (it only scales the exosystem's state): build with xm = 1.
    loop = closed_loop(pair, controller, Reference(1.0, omega), case)
    A = loop.A
    N = loop.n_states
    k = N - 6
    T = 2.0 * math.pi / omega
    tau = n * T / 2.0
    R = pair.R
    x20 = x10 - pair.L
    v, y2m, pre_plus, post_plus = _impact_states(pair, omega, x10, n)

    Phi = expm(A * tau)
    u, cond = _solve_equilibrated(*_symmetry_conditions(Phi, post_plus, x20, y2m), rcond)
    base = {"case": case, "pair": pair, "controller": controller, "loop": loop,
            "omega": omega, "x10": x10, "n": n, "n_controller_states": k, "T": T, "tau": tau,
            "R": R, "pre_plus": pre_plus, "post_plus": post_plus, "pre_minus": -pre_plus,
            "post_minus": -post_plus, "condition": cond}
    if u is None:
        return LTIOrbitResult(exists=False, code=1,
                              reason=LTI_REASONS[1] + f" (condition number {cond:.3g})", **base)
    C, S = float(u[0]), float(u[1])
    c0 = u[2:].copy()
    xm = math.hypot(C, S)
    phi0 = (math.atan2(S, C) / omega) % T
    if phi0 >= T:
        phi0 = 0.0
    state_plus = np.concatenate([pre_plus, [C, S], c0])
    z0 = np.concatenate([post_plus, [C, S], c0])
    residual = float(np.abs(Phi @ z0 + state_plus).max())
    fixed = np.concatenate([[phi0, x20, y2m, v - y2m], c0])
    base.update(xm=xm, phi0=phi0, t0=phi0, controller_state=c0, state_plus=state_plus,
                fixed_point=fixed, residual=residual)
    if not xm > 1e-14 * max(1.0, x10):
        return LTIOrbitResult(exists=False, code=2, reason=LTI_REASONS[2], **base)

    flight = _FreeFlight(loop, 10_000_000)
    code, reason, violation = _check_first_contact(flight, z0, tau, x10)
    marg = _viability_margin(A, z0, tau, pair.L, margin_samples) if margin else math.nan
    base.update(viability_margin=marg,
                grazing=bool(np.isfinite(marg) and abs(marg) < 1e-6), violation=violation)
    exists = code == 0
    res = LTIOrbitResult(exists=exists, code=code, reason=reason, **base)
    if not exists or not jacobian:
        return res
    return _with_jacobian(res, flight.gap, fd_check)


def _impact_states(pair, omega, x10, n):
    """Impact states fixed by the desired motion (9)-(12): ``(v, y2-, pre_plus, post_plus)``.

    ``pre_plus``, ``post_plus`` are ``[x1, y1, x2, y2]`` before/after the ``+L`` impact.
    """
    L, mu, e = pair.L, pair.mu, pair.e
    v = 2.0 * x10 * omega / (n * math.pi)                 # (9)
    y2m = v * (e - 2.0 * mu - 1.0) / (1.0 + e)           # (10)
    y2p = pair.R * y2m                                    # (11)-(12)
    x20 = x10 - L
    return v, y2m, np.array([x10, v, x20, y2m]), np.array([x10, -v, x20, y2p])


def _with_jacobian(orb, gap, fd_check):
    """The existing orbit ``orb`` with ``DP``, its blocks, multipliers and stability."""
    E = _impact_full(orb.pair, orb.loop.n_states)
    jac = _chain_jacobian(orb.loop.A, E, gap, orb.state_plus, (-1, 1), (orb.tau, orb.tau),
                          orb.omega)
    st = stability(jac.DP, _HYPERBOLIC_TOL)
    res = replace(orb, DP=jac.DP, blocks=jac.as_dict(), multipliers=st.multipliers,
                  spectral_radius=st.spectral_radius, stable=bool(st.stable),
                  hyperbolic=bool(st.hyperbolic))
    if fd_check:
        res = replace(res, DP_fd_error=res.fd_error())
    return res


def _symmetry_conditions(Phi, post_plus, x20, y2m):
    """The ``2 + k`` symmetry conditions, linear in ``u = (C, S, c0)``: ``(M, rhs)``.

    The post-impact state is ``z0 = zk + Eu u``; after the flight ``Phi = expm(A tau)`` the
    rows ``x2, y2, c`` must reach ``-x20, -y2-, -c0``.
    """
    N = Phi.shape[0]
    k = N - 6
    zk = np.zeros(N)
    zk[:4] = post_plus
    Eu = np.zeros((N, 2 + k))
    Eu[4, 0] = Eu[5, 1] = 1.0
    Eu[6:, 2:] = np.eye(k)
    rows = [2, 3] + list(range(6, N))
    M = Phi[rows] @ Eu
    M[2:, 2:] += np.eye(k)                                # c(tau) = -c0  ->  (Phi_cc + I) c0
    rhs = np.concatenate([[-x20, -y2m], np.zeros(k)]) - Phi[rows] @ zk
    return M, rhs


def _solve_equilibrated(M, rhs, rcond):
    """Solve ``M u = rhs`` by an SVD of the equilibrated matrix: ``(u, cond)``.

    ``u`` is None when ``M`` is singular (``sigma_min <= rcond sigma_max`` or not finite);
    ``cond`` is the 2-norm condition number of the equilibrated matrix.
    """
    # Equilibrate rows and columns (powers of two, exact) before the SVD: a controller
    # realisation with tiny or huge state magnitudes (e.g. a fast derivative filter) must not
    # look singular, so the singularity test uses the scale-free condition number.
    with np.errstate(divide="ignore"):
        rs = 2.0 ** -np.round(np.log2(np.max(np.abs(M), axis=1)))
        cs = 2.0 ** -np.round(np.log2(np.max(np.abs(M * rs[:, None]), axis=0)))
    rs[~np.isfinite(rs)] = 1.0
    cs[~np.isfinite(cs)] = 1.0
    Ms = M * rs[:, None] * cs[None, :]
    U_, sv, Vt = np.linalg.svd(Ms)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else math.inf
    if not (sv[-1] > rcond * sv[0]) or not np.all(np.isfinite(sv)):
        return None, cond
    return cs * (Vt.T @ ((U_.T @ (rs * rhs)) / sv)), cond


def _check_first_contact(flight, z0, tau, x10):
    """Viability (18): ``(code, reason, violation)`` of the flight from the ``+L`` impact.

    By guaranteed event location, the first contact after the ``+L`` impact (post-impact
    state ``z0``) must be the ``-L`` impact at ``tau``.
    """
    ev, t_c, wall, z_c, _ = flight.next_contact(z0, tau * (1.0 + 10.0 * _END_RTOL),
                                                hot=_WALL_PLUS)
    code, violation = 0, None
    if ev == EV_START:
        code, violation = 4, {"t": 0.0, "wall": 1, "x1": float(x10)}
    elif ev in (EV_CROSSING, EV_GRAZING):
        if t_c < tau * (1.0 - _END_RTOL) or wall != -1:
            code, violation = 3, {"t": t_c, "wall": int(wall), "x1": float(z_c[0])}
    else:
        code = 5
    reason = LTI_REASONS[code]
    if violation is not None:
        reason += (f" (contact on wall {violation['wall']:+d} at t0 + {violation['t']:.6g}, "
                   f"x1 = {violation['x1']:.6g})")
    return code, reason, violation


def _chain_jacobian(A, E, gap, z_pre0, walls, taus, w) -> LTIJacobian:
    """Product of impact and flight blocks along a contact sequence from ``z_pre0`` (wall +L)."""
    blocks, names = [], []
    z = np.asarray(z_pre0, float)
    wall = 1
    for wall_next, tau in zip(walls, taus):
        sign = "+" if wall == 1 else "-"
        blocks.append(_impact_block(E, z, w))
        names.append(f"impact{sign}")
        F, z = _flight_block(A, gap, E @ z, float(tau), w)
        blocks.append(F)
        names.append(f"flight->{'+' if wall_next == 1 else '-'}")
        wall = wall_next
    DP = np.eye(blocks[0].shape[0])
    for B in blocks:
        DP = B @ DP
    return LTIJacobian(DP=DP, blocks=tuple(blocks), names=tuple(names), walls=tuple(walls),
                       taus=np.asarray(taus, float))
