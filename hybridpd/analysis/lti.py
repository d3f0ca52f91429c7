r"""Any python-control LTI controller between impacts: symmetric orbits, impact map, stability.

The PD law of the paper is the special case of a linear controller from the tracking error to
the force. This module analyses the impact pair under **any proper, continuous-time
python-control LTI controller** (``StateSpace`` or ``TransferFunction``): a PD with a
derivative filter, a PID with a filter, a lead-lag, ... in both feedback cases. The closed loop
between impacts is still linear (:func:`hybridpd.loop.closed_loop`), now with the ``k``
controller states appended: ``z = [x1, y1, x2, y2, pc, ps, c1..ck]`` (``n = 6 + k`` states).
Orbits, the impact map and its Jacobian are computed **numerically** from the exact flow
``expm(A t)``; the symbolic path (:mod:`hybridpd.analysis.orbits`) remains the fast path for a pure PD.

Signal conventions (those of :mod:`hybridpd.loop`)
--------------------------------------------------
* Tracking error ``err = xd - x`` (``x = x2`` collocated, ``x = x1`` non-collocated), and for a
  2-input controller also ``err_dot = xd' - y``. The controller output ``u_fb`` is added to the
  feed-forward ``m2 xd''``: ``U = m2 xd'' + u_fb``. The PD (3) is
  ``u_fb = kp err + kv err_dot`` (:func:`hybridpd.loop.pd_controller`, 2 inputs, no states).
* A 1-input controller sees only ``err``; a PD is then improper and must be filtered, e.g.
  :func:`filtered_pd` ``kp + kv s / (tf s + 1)``, which tends to the PD as ``tf -> 0``.
* Controller states ``c`` are continuous across impacts (positions do not jump, so neither does
  ``err``; a 2-input controller sees the jump of ``err_dot`` only through its dynamics).

Symmetric orbits of odd order ``n``
-----------------------------------
As for the PD (paper (9)-(12)), the desired primary-mass motion fixes the impact states on the
``+L`` wall: ``v = 2 x10 w / (n pi)`` (9), ``y2- = v (e - 2 mu - 1)/(1 + e)`` (10),
``y2+ = R y2-`` (11)-(12), ``x1 = x10``, ``x20 = x10 - L``, ``y1+ = -v``. With the unknowns
``C = xm cos(w t0)``, ``S = xm sin(w t0)`` (exosystem state at the impact time ``t0``) and
the controller state ``c0`` at the impact, the post-impact state is affine in
``u = (C, S, c0)``; symmetry after the flight ``tau = n T / 2`` requires
``x2 -> -x20``, ``y2 -> -y2-`` and ``c -> -c0`` (``x1 -> -x10``, ``y1 = -v`` and
``(pc, ps) -> -(C, S)`` hold automatically because ``v tau = 2 x10`` and ``n`` is odd). These
``2 + k`` conditions are **linear** in ``u`` through ``Phi = expm(A tau)``; they are solved by
an SVD (singular when ``sigma_min <= rcond sigma_max``), then ``xm = hypot(C, S)``,
``phi0 = atan2(S, C)/w mod T``. For ``k = 0`` this is exactly (13)-(16).

**Existence** needs ``xm > 0`` and viability (18): no contact on the open interval
``(t0, t0 + tau)``. It is decided by the guaranteed first-crossing location of
:mod:`hybridpd.hybrid.events` on the two wall guards (an extra contact is never missed, however close
to grazing); a violation is reported with its time, wall and ``x1``.

Impact map on the extended section
----------------------------------
Section ``z3 = x1 - x2 = +L``, ``z4 = y1 - y2 > 0`` (pre-impact), coordinates
``s = (phi, z1, z2, z4, c1..ck)`` with ``phi = t mod T``, ``z1 = x2``, ``z2 = y2``. On a wall
``sigma = +-1`` the full state is ``z = (z1 + sigma L, z2 + z4, z1, z2, xm cos(w phi),
xm sin(w phi), c)``. ``P`` applies Newton's law (2), flies exactly until the next contact
(guaranteed event location), repeats on the ``-L`` wall, and stops at the next ``+L`` contact.

Jacobian by implicit differentiation. Work with ``(t, z)``. An impact is ``z -> E z``. A flight
``z -> z' = Phi(tau) z`` ends where ``g = cg . Phi(tau) z -/+ L = 0`` with ``cg . z = z3``, so

.. math:: \frac{d\tau}{dz} = -\frac{g_z}{g_\tau} = -\frac{c_g \Phi(\tau)}{c_g A z'},\qquad
          \frac{dz'}{dz} = \Phi(\tau) + A z' \frac{d\tau}{dz},\qquad
          t' = t + \tau .

Each block is mapped back to the reduced coordinates of its wall (``phi_out = phi_in + tau``),
giving ``DP = DP43 DP32 DP21 DP10`` (24) for the simple pattern, or the product over any
pattern of transversal impacts. :meth:`LTIImpactMap.jacobian_fd` gives central differences of
the simulated map as the independent check. Stability: :func:`hybridpd.analysis.impactmap.stability`.

Examples
--------
>>> from hybridpd import ImpactPair
>>> orb = lti_symmetric_orbit(ImpactPair(mu=0.1, e=0.5, L=0.75), filtered_pd(10, 20, 0.01),
...                           omega=5.0)
>>> orb.exists, orb.stable, orb.fixed_point.shape
(True, True, (5,))
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.linalg import expm

from hybridpd._repr import compact_repr
from hybridpd.analysis.impactmap import Stability, stability
from hybridpd.analysis.orbits import _END_RTOL, _HYPERBOLIC_TOL, REASONS
from hybridpd.hybrid.events import (
    EV_CROSSING,
    EV_GRAZING,
    EV_NONE,
    EV_NONFINITE,
    EV_START,
    EV_STEP_LIMIT,
    advance,
    lti_flow,
    prepare_lti_mode,
)
from hybridpd.loop import ClosedLoop, closed_loop
from hybridpd.model import (
    Case,
    ImpactPair,
    Reference,
    check_int,
    check_odd_order,
    check_positive,
)

__all__ = [
    "LTI_REASONS",
    "LTIImpactMap",
    "LTIJacobian",
    "LTIMapResult",
    "LTIOrbitResult",
    "filtered_pd",
    "filtered_pid",
    "lead_lag",
    "lti_symmetric_orbit",
]

#: Reason codes of :attr:`LTIOrbitResult.code`: the same as for the PD fast path.
LTI_REASONS = REASONS

_WALL_PLUS, _WALL_MINUS = 0, 1   # guard indices in the free-flight mode


# ----------------------------------------------------------------------------------------
# Common controllers as python-control objects
# ----------------------------------------------------------------------------------------
def filtered_pd(kp: float, kv: float, tf: float, name: str = "filtered_pd"):
    """PD with a first-order derivative filter, ``C(s) = kp + kv s / (tf s + 1)``.

    Parameters
    ----------
    kp : float
        Proportional gain (force/length), ``> 0``.
    kv : float
        Derivative gain (force time/length), ``> 0``.
    tf : float
        Filter time constant (time), ``> 0``. As ``tf -> 0`` the loop tends to the PD (3) with
        an ``O(tf)`` error.
    name : str
        python-control system name.

    Returns
    -------
    control.TransferFunction
        1 input ``err = xd - x``, 1 output ``u_fb``, one state once realised.

    Examples
    --------
    >>> C = filtered_pd(10, 20, 0.01)
    >>> bool(abs(C(0) - 10) < 1e-12), bool(abs(C(1e9) - (10 + 20 / 0.01)) < 1e-3)
    (True, True)
    """
    import control as ct

    kp = check_positive("kp", kp)
    kv = check_positive("kv", kv)
    tf = check_positive("tf", tf)
    return ct.tf([kp * tf + kv, kp], [tf, 1.0], inputs="err", outputs="u_fb", name=name)


def filtered_pid(kp: float, ki: float, kv: float, tf: float, name: str = "filtered_pid"):
    """PID with a filtered derivative, ``C(s) = kp + ki / s + kv s / (tf s + 1)``.

    Parameters
    ----------
    kp : float
        Proportional gain (force/length), ``> 0``.
    ki : float
        Integral gain (force/(length time)), ``> 0`` (use :func:`filtered_pd` for ``ki = 0``;
        a zero ``ki`` would leave a cancelled pole at ``s = 0`` in the realisation).
    kv : float
        Derivative gain (force time/length), ``> 0``.
    tf : float
        Derivative filter time constant (time), ``> 0``.
    name : str

    Returns
    -------
    control.TransferFunction
        1 input ``err``, 1 output ``u_fb``, two states once realised (integrator and filter).

    Examples
    --------
    >>> C = filtered_pid(10, 2, 20, 0.01)
    >>> bool(abs(C(1j) - (10 + 2 / 1j + 20j / (0.01j + 1))) < 1e-12)
    True
    """
    import control as ct

    kp = check_positive("kp", kp)
    ki = check_positive("ki", ki)
    kv = check_positive("kv", kv)
    tf = check_positive("tf", tf)
    # kp + ki/s + kv s/(tf s + 1) over the common denominator s (tf s + 1)
    num = [kp * tf + kv, kp + ki * tf, ki]
    return ct.tf(num, [tf, 1.0, 0.0], inputs="err", outputs="u_fb", name=name)


def lead_lag(k: float, t_lead_zero: float, t_lead_pole: float, t_lag_zero: float | None = None,
             t_lag_pole: float | None = None, name: str = "lead_lag"):
    """Lead (optionally lead-lag) compensator with DC gain ``k``.

    ``C(s) = k (t_lead_zero s + 1)/(t_lead_pole s + 1) * (t_lag_zero s + 1)/(t_lag_pole s + 1)``

    Parameters
    ----------
    k : float
        DC gain (force/length), ``> 0``: the stiffness the controller shows at low frequency.
    t_lead_zero, t_lead_pole : float
        Lead time constants (time), ``t_lead_zero > t_lead_pole > 0`` (phase lead; the PD
        ``kp + kv s`` is the limit ``t_lead_zero = kv/kp``, ``t_lead_pole -> 0``).
    t_lag_zero, t_lag_pole : float, optional
        Lag time constants (time), ``t_lag_pole > t_lag_zero > 0``; both or neither.
    name : str

    Returns
    -------
    control.TransferFunction
        1 input ``err``, 1 output ``u_fb`` (1 or 2 states).

    Examples
    --------
    The filtered PD is a lead with ``t_lead_zero = kv/kp + tf``, ``t_lead_pole = tf``:

    >>> C1, C2 = lead_lag(10, 2.01, 0.01), filtered_pd(10, 20, 0.01)
    >>> bool(abs(C1(3j) - C2(3j)) < 1e-12)
    True
    """
    import control as ct

    k = check_positive("k", k)
    tz = check_positive("t_lead_zero", t_lead_zero)
    tp = check_positive("t_lead_pole", t_lead_pole)
    if not tz > tp:
        raise ValueError(f"a lead needs t_lead_zero > t_lead_pole, got {tz:g} <= {tp:g}")
    num, den = [k * tz, k], [tp, 1.0]
    if (t_lag_zero is None) != (t_lag_pole is None):
        raise ValueError("t_lag_zero and t_lag_pole must be given together")
    if t_lag_zero is not None:
        gz = check_positive("t_lag_zero", t_lag_zero)
        gp = check_positive("t_lag_pole", t_lag_pole)
        if not gp > gz:
            raise ValueError(f"a lag needs t_lag_pole > t_lag_zero, got {gp:g} <= {gz:g}")
        num = np.polymul(num, [gz, 1.0])
        den = np.polymul(den, [gp, 1.0])
    return ct.tf(num, den, inputs="err", outputs="u_fb", name=name)


# ----------------------------------------------------------------------------------------
# Exact free flight with guaranteed contact location
# ----------------------------------------------------------------------------------------
class _FreeFlight:
    """The closed loop's free flight with the two wall guards of :mod:`hybridpd.pair.impactpair`.

    Guard 0 (``wall+``): ``g = L - z3``, fires when the gap closes on ``+L``; guard 1
    (``wall-``): ``g = z3 + L``. Both fire when ``g`` reaches ``<= 0``.
    """

    def __init__(self, loop: ClosedLoop, max_steps: int):
        n = loop.n_states
        L = loop.pair.L
        gap = np.zeros(n)
        gap[0], gap[2] = 1.0, -1.0
        self.n = n
        self.gap = gap
        self.max_steps = int(max_steps)
        self.md = prepare_lti_mode(loop.A, None, [(-gap, L, -1), (gap, L, -1)])

    def next_contact(self, z, t_max, hot=-1, hot_tol=0.0):
        """First contact of the flow from ``z`` within ``(0, t_max]``.

        Returns ``(code, tau, wall, z_event, err)``; ``code`` is an ``events.EV_*`` constant,
        ``wall`` is ``+1``/``-1`` (0 if none), ``z_event`` the pre-reset state.
        """
        md = self.md
        w0 = np.append(np.asarray(z, float), 1.0)
        w_out = np.empty(self.n + 1)
        code, t, g, _, err = advance(w0, 0.0, float(t_max), md.h, md.Phi, md.Ah, md.dinv,
                                     md.trunc, md.G, md.gabs, md.gsum, md.cnorm, md.prio, 2,
                                     int(hot), float(hot_tol), self.max_steps, w_out)
        wall = 1 if g == _WALL_PLUS else (-1 if g == _WALL_MINUS else 0)
        return int(code), float(t), wall, w_out[:self.n].copy(), float(err)


# ----------------------------------------------------------------------------------------
# Section coordinates and Jacobian blocks
# ----------------------------------------------------------------------------------------
def _full_state(s, wall, L, xm, w):
    """Full state on wall ``wall`` from reduced ``s = (phi, z1, z2, z4, c)``."""
    phi, z1, z2, z4 = s[0], s[1], s[2], s[3]
    return np.concatenate([[z1 + wall * L, z2 + z4, z1, z2, xm * math.cos(w * phi),
                            xm * math.sin(w * phi)], s[4:]])


def _reduced(z, t):
    """Reduced coordinates ``(t, z1, z2, z4, c)`` of a full state on a wall (phase not wrapped)."""
    return np.concatenate([[t, z[2], z[3], z[1] - z[3]], z[6:]])


def _J_in(z, w):
    """``d(t, z)/ds`` at the full state ``z``: shape ``(n + 1, m)``, ``m = n - 2``."""
    n = z.size
    m = n - 2
    J = np.zeros((n + 1, m))
    J[0, 0] = 1.0                              # t = phi
    J[1, 1] = 1.0                              # x1 = z1 +- L
    J[2, 2] = J[2, 3] = 1.0                    # y1 = z2 + z4
    J[3, 1] = 1.0                              # x2 = z1
    J[4, 2] = 1.0                              # y2 = z2
    J[5, 0] = -w * z[5]                        # pc = xm cos(w phi)
    J[6, 0] = w * z[4]                         # ps = xm sin(w phi)
    J[7:, 4:] = np.eye(m - 4)                  # controller states
    return J


def _J_out(n):
    """``ds/d(t, z)``: shape ``(m, n + 1)`` (reads ``t, x2, y2, y1 - y2, c``)."""
    m = n - 2
    J = np.zeros((m, n + 1))
    J[0, 0] = 1.0
    J[1, 3] = 1.0
    J[2, 4] = 1.0
    J[3, 2], J[3, 4] = 1.0, -1.0
    J[4:, 7:] = np.eye(m - 4)
    return J


def _impact_full(pair, n):
    """Newton's law (2) on the full state: ``E`` of shape ``(n, n)``."""
    E = np.eye(n)
    E[np.ix_([1, 3], [1, 3])] = pair.velocity_jump_matrix()
    return E


def _impact_block(E, z_pre, w):
    """Reduced-coordinate Jacobian of an impact (the paper's ``DP10``/``DP32``)."""
    n = z_pre.size
    Eaug = np.eye(n + 1)
    Eaug[1:, 1:] = E
    return _J_out(n) @ Eaug @ _J_in(z_pre, w)


def _flight_block(A, gap, z_post, tau, w):
    """Reduced-coordinate Jacobian of a flight (``DP21``/``DP43``) by implicit differentiation.

    Returns ``(block, z_end)``. ``g(tau, z) = gap . expm(A tau) z -/+ L``;
    ``dtau/dz = -g_z / g_tau`` and ``dz'/dz = Phi + (A z') dtau/dz``; ``t' = t + tau``.
    """
    n = z_post.size
    Phi = expm(A * tau)
    z_end = Phi @ z_post
    f_tau = A @ z_end                          # d z'/d tau
    g_tau = gap @ f_tau                        # = z4 at the contact (transversality)
    if g_tau == 0.0 or not np.isfinite(g_tau):
        raise ValueError("the flight ends tangentially (z4 = 0 at the contact): DP is undefined")
    dtau = -(gap @ Phi) / g_tau                # dtau/dz, shape (n,)
    F = np.zeros((n + 1, n + 1))
    F[0, 0] = 1.0                              # t' = t + tau(z) (the flow is autonomous)
    F[0, 1:] = dtau
    F[1:, 1:] = Phi + np.outer(f_tau, dtau)
    return _J_out(n) @ F @ _J_in(z_post, w), z_end


# ----------------------------------------------------------------------------------------
# The impact map
# ----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class LTIMapResult:
    """One application of the impact map :class:`LTIImpactMap`.

    Attributes
    ----------
    s : ndarray, shape (m,)
        Image ``P(s)`` = ``(phi, z1, z2, z4, c1..ck)`` with ``phi`` in ``[0, T)``; NaN unless
        ``ok``.
    ok : bool
        The trajectory returned to the section ``z3 = +L``.
    status : str
        ``"ok"``, ``"sticking"`` (a contact fires at once after an impact: zero rebound with
        the force pressing the masses together), ``"no contact"`` (no contact within the
        flight horizon), ``"max impacts"`` (no return within ``max_impacts`` contacts),
        ``"nonfinite"`` or ``"step limit"``.
    walls : tuple of int
        Walls (``+1``/``-1``) of the contacts after the initial impact (``(-1, +1)`` on a
        simple orbit).
    taus : ndarray, shape (j,)
        Flight times (time) between consecutive contacts.
    pre : ndarray, shape (j, n)
        Full pre-impact states at those contacts.
    grazing : tuple of bool
        Contacts located as tangential touches.
    phase_unwrapped : float
        ``phi_in + sum(taus)`` (time): the output phase before reduction mod ``T``.
    """

    __repr__ = compact_repr

    s: np.ndarray
    ok: bool
    status: str
    walls: tuple
    taus: np.ndarray
    pre: np.ndarray
    grazing: tuple
    phase_unwrapped: float


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


class LTIImpactMap:
    """Impact map of the impact pair under any LTI controller, on the extended section.

    Parameters
    ----------
    pair : ImpactPair
    controller : PDGains, (kp, kv), control.StateSpace or control.TransferFunction
        See :mod:`hybridpd.loop` (proper, continuous-time; 1 input ``err`` or 2 inputs
        ``[err, err_dot]``; 1 output).
    reference : Reference
        ``xd = xm cos(omega t)``.
    case : {"collocated", "noncollocated"}
    max_impacts : int
        Bound on the contacts of one application of ``P``.
    max_flight : float, optional
        Horizon (time) of one flight; default ``100 T``.
    max_steps : int
        Bound on the exact flow steps of one flight.

    Attributes
    ----------
    loop : ClosedLoop
    dim : int
        ``m = 4 + k`` (section coordinates ``(phi, z1, z2, z4, c1..ck)``).

    Examples
    --------
    >>> from hybridpd import ImpactPair
    >>> orb = lti_symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), filtered_pd(10, 20, 0.05), 5.0)
    >>> P = orb.impact_map()
    >>> bool(np.abs(P(orb.fixed_point) - orb.fixed_point).max() < 1e-10)
    True
    >>> P.jacobian(orb.fixed_point).DP.shape
    (5, 5)
    """

    def __init__(self, pair: ImpactPair, controller, reference: Reference, case="collocated", *,
                 max_impacts: int = 1000, max_flight: float | None = None,
                 max_steps: int = 10_000_000):
        self.loop: ClosedLoop = closed_loop(pair, controller, reference, case)
        self.pair = pair
        self.reference = reference
        self.case: Case = self.loop.case
        self.controller = controller
        if isinstance(max_impacts, bool) or int(max_impacts) != max_impacts or max_impacts < 1:
            raise ValueError(f"max_impacts must be an int >= 1, got {max_impacts!r}")
        self.max_impacts = int(max_impacts)
        self.max_flight = (100.0 * reference.period if max_flight is None
                           else check_positive("max_flight", max_flight))
        self._flight = _FreeFlight(self.loop, max_steps)
        self._E = _impact_full(pair, self.loop.n_states)

    @property
    def dim(self) -> int:
        """Dimension ``m = 4 + k`` of the section coordinates."""
        return self.loop.n_states - 2

    @property
    def period(self) -> float:
        """``T = 2 pi / omega``."""
        return self.reference.period

    def _point(self, s) -> np.ndarray:
        s = np.asarray(s, dtype=float)
        if s.shape != (self.dim,):
            raise ValueError(f"s must have shape ({self.dim},) = (phi, z1, z2, z4, c1..c"
                             f"{self.dim - 4}), got {s.shape}")
        if not np.all(np.isfinite(s)):
            raise ValueError("s must be finite")
        if s[3] <= 0:
            raise ValueError(f"s[3] = z4 must be > 0 (approaching the +L wall), got {s[3]!r}")
        return s

    def section_state(self, s, wall: int = +1) -> np.ndarray:
        """Full closed-loop state ``(n,)`` of the section point ``s`` on wall ``wall``."""
        s = np.asarray(s, dtype=float)
        return _full_state(s, wall, self.pair.L, self.reference.xm, self.reference.omega)

    def apply(self, s) -> LTIMapResult:
        """Apply ``P`` once to the section point ``s`` of shape ``(m,)``."""
        s = self._point(s)
        T = self.period
        z = self.section_state(s, +1)
        t = 0.0
        walls, taus, pres, graz = [], [], [], []
        hot, hot_tol = _WALL_PLUS, 0.0
        status = "max impacts"
        for _ in range(self.max_impacts):
            z = self._E @ z
            code, tau, wall, zpre, err = self._flight.next_contact(z, self.max_flight, hot,
                                                                   hot_tol)
            if code == EV_START:
                status = "sticking"
                break
            if code == EV_NONE:
                status = "no contact"
                break
            if code == EV_NONFINITE:
                status = "nonfinite"
                break
            if code == EV_STEP_LIMIT:
                status = "step limit"
                break
            t += tau
            walls.append(wall)
            taus.append(tau)
            pres.append(zpre)
            graz.append(code == EV_GRAZING)
            z = zpre
            if wall == 1:
                status = "ok"
                break
            hot, hot_tol = (_WALL_PLUS if wall == 1 else _WALL_MINUS), err
        ok = status == "ok"
        phase = float(s[0] + t)
        out = _reduced(z, phase) if ok else np.full(self.dim, np.nan)
        if ok:
            out[0] = phase % T
            if out[0] >= T:             # rounding of the modulo
                out[0] = 0.0
        return LTIMapResult(s=out, ok=ok, status=status, walls=tuple(walls),
                            taus=np.asarray(taus, float), pre=np.asarray(pres, float).reshape(
                                -1, self.loop.n_states), grazing=tuple(graz),
                            phase_unwrapped=phase)

    def __call__(self, s) -> np.ndarray:
        """``P(s)``; ``RuntimeError`` if the trajectory does not return to the section."""
        r = self.apply(s)
        if not r.ok:
            raise RuntimeError(f"P undefined at s = {np.asarray(s).tolist()}: {r.status}")
        return r.s

    def iterate(self, s0, n_iter: int) -> np.ndarray:
        """``s0, P(s0), ..., P^n(s0)`` as shape ``(n_iter + 1, m)`` (NaN rows after a failure)."""
        s = self._point(s0)
        out = np.full((int(n_iter) + 1, self.dim), np.nan)
        out[0] = s
        for i in range(int(n_iter)):
            r = self.apply(s)
            if not r.ok or r.s[3] <= 0:
                break
            s = r.s
            out[i + 1] = s
        return out

    def jacobian(self, s) -> LTIJacobian:
        """``DP`` at ``s`` by implicit differentiation of the flight blocks.

        Uses the contact sequence and flight times of :meth:`apply`; every contact must be
        transversal (``ValueError`` at a grazing contact, where ``P`` is not differentiable).
        """
        s = self._point(s)
        r = self.apply(s)
        if not r.ok:
            raise RuntimeError(f"P undefined at s = {s.tolist()}: {r.status}")
        if any(r.grazing):
            raise ValueError("a contact of P(s) is grazing: DP is undefined there")
        return _chain_jacobian(self.loop.A, self._E, self._flight.gap,
                               self.section_state(s, +1), r.walls, r.taus,
                               self.reference.omega)

    def jacobian_fd(self, s, h: float | None = None, scale=None,
                    richardson: bool = False) -> np.ndarray:
        """Central finite differences of the simulated map (phase unwrapped), shape ``(m, m)``.

        Parameters
        ----------
        s : array_like, shape (m,)
            Section point.
        h : float, optional
            Relative step: coordinate ``j`` moves by ``h * scale[j]`` (default ``1e-6``).
        scale : array_like, shape (m,), optional
            Coordinate scales (default ``max(1, |s_j|)``). Controller states of a realisation
            with very small or large natural magnitudes need their own scale (e.g.
            :meth:`LTIOrbitResult.coordinate_scale`), otherwise the step is far outside the
            linear range of that coordinate.
        richardson : bool
            Combine steps ``h`` and ``h/2`` as ``(4 J(h/2) - J(h)) / 3`` (error ``O(h^4)``):
            useful for strongly expanding maps, whose second derivatives are large.
        """
        s = self._point(s)
        m = self.dim
        T = self.period
        hr = 1e-6 if h is None else check_positive("h", h)
        sc = np.maximum(1.0, np.abs(s)) if scale is None else np.asarray(scale, float)
        if sc.shape != (m,) or not np.all(np.isfinite(sc)) or np.any(sc <= 0):
            raise ValueError(f"scale must be {m} positive finite numbers, got {scale!r}")

        def central(hrel):
            J = np.empty((m, m))
            for j in range(m):
                hj = hrel * sc[j]
                d = np.zeros(m)
                d[j] = hj
                diff = self(s + d) - self(s - d)
                diff[0] = (diff[0] + 0.5 * T) % T - 0.5 * T     # phase across the cut
                J[:, j] = diff / (2 * hj)
            return J

        if richardson:
            return (4.0 * central(hr / 2) - central(hr)) / 3.0
        return central(hr)

    def stability(self, s) -> Stability:
        """Multipliers, spectral radius, stability and hyperbolicity of ``DP(s)``."""
        return stability(self.jacobian(s).DP, _HYPERBOLIC_TOL)


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


# ----------------------------------------------------------------------------------------
# Symmetric orbits
# ----------------------------------------------------------------------------------------
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
        ``(phi0, x20, y2-, v - y2-, c0)``: the fixed point of :class:`LTIImpactMap`.
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
        and ``DP_fd`` from :meth:`LTIImpactMap.jacobian_fd` (relative step ``h``, Richardson
        extrapolation by default, which the strongly expanding non-collocated maps need).
        """
        if self.DP is None:
            raise ValueError("the orbit does not exist: no DP")
        sc = self.coordinate_scale()
        J = self.impact_map().jacobian_fd(self.fixed_point, h=h, scale=sc, richardson=richardson)
        Ds = self.DP * sc[None, :] / sc[:, None]
        err = (J - self.DP) * sc[None, :] / sc[:, None]
        return float(np.abs(err).max() / np.abs(Ds).max())

    def impact_map(self, **kwargs) -> LTIImpactMap:
        """The :class:`LTIImpactMap` with this orbit's reference (``kwargs`` passed on)."""
        return LTIImpactMap(self.pair, self.controller, self.reference(), self.case, **kwargs)

    def system(self):
        """The :class:`~hybridpd.pair.impactpair.ControlledImpactPair` with this orbit's reference.

        Start it on the orbit with ``simulate(orb.pre_plus, (orb.t0, t1),
        controller_state=orb.controller_state)``.
        """
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
            "DP_fd_error": f(self.DP_fd_error),
        }


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
    >>> from hybridpd.analysis.orbits import symmetric_orbit
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
    L, mu, e = pair.L, pair.mu, pair.e
    T = 2.0 * math.pi / omega
    tau = n * T / 2.0
    R = pair.R
    v = 2.0 * x10 * omega / (n * math.pi)                 # (9)
    y2m = v * (e - 2.0 * mu - 1.0) / (1.0 + e)           # (10)
    y2p = R * y2m                                         # (11)-(12)
    x20 = x10 - L
    pre_plus = np.array([x10, v, x20, y2m])
    post_plus = np.array([x10, -v, x20, y2p])

    # Post-impact state z0 = zk + Eu u with u = (C, S, c0); conditions on rows x2, y2, c.
    Phi = expm(A * tau)
    zk = np.zeros(N)
    zk[:4] = post_plus
    Eu = np.zeros((N, 2 + k))
    Eu[4, 0] = Eu[5, 1] = 1.0
    Eu[6:, 2:] = np.eye(k)
    rows = [2, 3] + list(range(6, N))
    M = Phi[rows] @ Eu
    M[2:, 2:] += np.eye(k)                                # c(tau) = -c0  ->  (Phi_cc + I) c0
    rhs = np.concatenate([[-x20, -y2m], np.zeros(k)]) - Phi[rows] @ zk
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
    base = {"case": case, "pair": pair, "controller": controller, "loop": loop,
            "omega": omega, "x10": x10, "n": n, "n_controller_states": k, "T": T, "tau": tau,
            "R": R, "pre_plus": pre_plus, "post_plus": post_plus, "pre_minus": -pre_plus,
            "post_minus": -post_plus, "condition": cond}
    if not (sv[-1] > rcond * sv[0]) or not np.all(np.isfinite(sv)):
        return LTIOrbitResult(exists=False, code=1,
                              reason=LTI_REASONS[1] + f" (condition number {cond:.3g})", **base)
    u = cs * (Vt.T @ ((U_.T @ (rs * rhs)) / sv))
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

    # Viability (18) by guaranteed event location: the first contact after the +L impact must
    # be the -L impact at tau.
    flight = _FreeFlight(loop, 10_000_000)
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
    marg = _viability_margin(A, z0, tau, L, margin_samples) if margin else math.nan
    base.update(viability_margin=marg,
                grazing=bool(np.isfinite(marg) and abs(marg) < 1e-6), violation=violation)
    exists = code == 0
    if not exists or not jacobian:
        return LTIOrbitResult(exists=exists, code=code, reason=reason, **base)

    E = _impact_full(pair, N)
    jac = _chain_jacobian(A, E, flight.gap, state_plus, (-1, 1), (tau, tau), omega)
    st = stability(jac.DP, _HYPERBOLIC_TOL)
    res = LTIOrbitResult(exists=True, code=0, reason=reason, DP=jac.DP, blocks=jac.as_dict(),
                         multipliers=st.multipliers, spectral_radius=st.spectral_radius,
                         stable=bool(st.stable), hyperbolic=bool(st.hyperbolic), **base)
    if fd_check:
        res = replace(res, DP_fd_error=res.fd_error())
    return res
