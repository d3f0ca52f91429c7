"""The impact map on the extended section and its Jacobian by implicit differentiation.

:class:`LTIImpactMap` applies Newton's law, flies exactly to the next contact, and stops at
the next ``+L`` contact; :class:`LTIJacobian` is the product of the impact and flight blocks
of :mod:`hybridpd.pair.lti.flight` along the contact sequence (section coordinates and
derivation: :mod:`hybridpd.pair.lti`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.analysis.floquet import Stability, stability
from hybridpd.analysis.maps import MapResult, PoincareMap, check_returns
from hybridpd.hybrid.events import EV_GRAZING, EV_NONE, EV_NONFINITE, EV_START, EV_STEP_LIMIT
from hybridpd.loop import ClosedLoop, closed_loop
from hybridpd.model import Case, ImpactPair, Reference, check_positive
from hybridpd.pair.lti.flight import (
    _WALL_MINUS,
    _WALL_PLUS,
    _flight_block,
    _FreeFlight,
    _full_state,
    _impact_block,
    _impact_full,
    _reduced,
)
from hybridpd.pair.orbits import _HYPERBOLIC_TOL

__all__ = ["LTIImpactMap", "LTIJacobian", "LTIMapResult"]


@dataclass(frozen=True, eq=False)
class LTIMapResult(MapResult):
    """One application of :class:`LTIImpactMap`: a :class:`~hybridpd.analysis.maps.MapResult`
    with the pair's contact sequence.

    Attributes
    ----------
    walls : tuple of int
        Walls (``+1``/``-1``) of the contacts after the initial impact (``(-1, +1)`` on a
        simple orbit, repeated ``k`` times for ``P^k``).
    taus : ndarray, shape (j,)
        Flight times (time) between consecutive contacts.
    pre : ndarray, shape (j, n)
        Full pre-impact states at those contacts.
    contact_grazing : tuple of bool
        Contacts located as tangential touches.
    phase_unwrapped : float
        ``phi_in + sum(taus)`` (time): the output phase before reduction mod ``T``.

    ``status`` is ``"returned"``, ``"sticking"`` (a contact fires at once after an impact:
    zero rebound with the force pressing the masses together), ``"no contact"`` (none within
    the flight horizon), ``"max impacts"``, ``"nonfinite"`` or ``"step limit"``.
    """

    walls: tuple = ()
    taus: np.ndarray | None = None
    pre: np.ndarray | None = None
    contact_grazing: tuple = ()
    phase_unwrapped: float = math.nan


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


class LTIImpactMap(PoincareMap):
    """Impact map of the impact pair under any LTI controller, on the extended section.

    A named specialisation of the map protocol (:class:`~hybridpd.analysis.maps.PoincareMap`):
    exact flights of the closed loop between contacts, ``DP`` as the product of the impact
    and flight blocks (implicit differentiation, the orbit's named blocks ``DP10 .. DP43``).
    It equals the general :class:`~hybridpd.analysis.hybridmap.SectionMap` on
    :func:`~hybridpd.analysis.sections.impact_pair_section` to about ``1e-14``
    (``tests/test_specialisations.py``). Measured on a filtered PD (README parameters,
    ``benchmarks/bench_specialisations.py``, loaded 2-core machine): ``P`` 1.3-2.5 times
    faster per call than the general path, ``DP`` 0.5-1.3 times as fast (it gives the named
    blocks). Limits: the pair's rigid walls without sticking (a sticking contact ends the map
    with status ``"sticking"``).

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
    >>> from hybridpd.pair.lti import filtered_pd, lti_symmetric_orbit
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

    @property
    def names(self) -> tuple:
        return ("phi", "z1", "z2", "z4") + tuple(self.loop.state_names[6:])

    def _once(self, s):
        """One application from ``s``: ``(status, walls, taus, pre, grazing, z, t)``."""
        z = self.section_state(s, +1)
        t = 0.0
        walls, taus, pres, graz = [], [], [], []
        hot, hot_tol = _WALL_PLUS, 0.0
        status = "max impacts"
        stops = {EV_START: "sticking", EV_NONE: "no contact", EV_NONFINITE: "nonfinite",
                 EV_STEP_LIMIT: "step limit"}
        for _ in range(self.max_impacts):
            z = self._E @ z
            code, tau, wall, zpre, err = self._flight.next_contact(z, self.max_flight, hot,
                                                                   hot_tol)
            if code in stops:
                status = stops[code]
                break
            t += tau
            walls.append(wall)
            taus.append(tau)
            pres.append(zpre)
            graz.append(code == EV_GRAZING)
            z = zpre
            if wall == 1:
                status = "returned"
                break
            hot, hot_tol = (_WALL_PLUS if wall == 1 else _WALL_MINUS), err
        return status, walls, taus, pres, graz, z, t

    def apply(self, s, k: int = 1, jacobian: bool = False) -> LTIMapResult:
        """Apply ``P^k`` to the section point ``s`` of shape ``(m,)`` (optionally ``DP^k``)."""
        k = check_returns(k)
        s = self._point(s)
        T = self.period
        cur, phase = s, float(s[0])
        walls, taus, pres, graz, DP = [], [], [], [], np.eye(self.dim)
        jumps = [(phase, "free", "wall+", "free", "crossing")]
        z = self.section_state(s, +1)
        status = "returned"
        for i in range(k):
            status, w1, tau1, pre1, g1, z, t = self._once(cur)
            for w, tq, gq in zip(w1, np.cumsum(tau1), g1):
                jumps.append((phase + float(tq), "free", "wall+" if w == 1 else "wall-",
                              "free", "grazing" if gq else "crossing"))
            if status != "returned" or i == k - 1:
                jumps = jumps[:-1] if status == "returned" else jumps
            walls += w1
            taus += tau1
            pres += pre1
            graz += g1
            if jacobian and status == "returned" and not any(g1):
                DP = _chain_jacobian(self.loop.A, self._E, self._flight.gap,
                                     self.section_state(cur, +1), w1, tau1,
                                     self.reference.omega).DP @ DP
            phase += t
            if status != "returned":
                break
            cur = _reduced(z, phase)
            cur[0] = phase % T
            if cur[0] >= T:             # rounding of the modulo
                cur[0] = 0.0
            if i < k - 1 and not cur[3] > 0:
                status = "grazing return"
                break
        ok = status == "returned"
        return LTIMapResult(
            s=cur if ok else np.full(self.dim, np.nan), ok=ok, status=status,
            t_start=float(s[0]), t_hit=phase, z_hit=z, mode_final="free", jumps=tuple(jumps),
            grazing=bool(any(graz)), DP=DP if (jacobian and ok and not any(graz)) else None,
            walls=tuple(walls), taus=np.asarray(taus, float),
            pre=np.asarray(pres, float).reshape(-1, self.loop.n_states),
            contact_grazing=tuple(graz), phase_unwrapped=phase)

    def jacobian(self, s) -> LTIJacobian:
        """``DP`` at ``s`` by implicit differentiation of the flight blocks.

        Uses the contact sequence and flight times of :meth:`apply`; every contact must be
        transversal (``ValueError`` at a grazing contact, where ``P`` is not differentiable).
        """
        s = self._point(s)
        r = self.apply(s)
        if not r.ok:
            raise RuntimeError(f"P undefined at s = {s.tolist()}: {r.status}")
        if r.grazing:
            raise ValueError("a contact of P(s) is grazing: DP is undefined there")
        return _chain_jacobian(self.loop.A, self._E, self._flight.gap,
                               self.section_state(s, +1), r.walls, r.taus,
                               self.reference.omega)

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
