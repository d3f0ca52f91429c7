"""The impact map on the extended section and its Jacobian by implicit differentiation.

:class:`LTIImpactMap` applies Newton's law, flies exactly to the next contact, and stops at
the next ``+L`` contact; :class:`LTIJacobian` is the product of the impact and flight blocks
of :mod:`hybridpd.analysis.lti.flight` along the contact sequence (section coordinates and
derivation: :mod:`hybridpd.analysis.lti`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hybridpd._repr import compact_repr
from hybridpd.analysis.floquet import Stability, stability
from hybridpd.analysis.lti.flight import (
    _WALL_MINUS,
    _WALL_PLUS,
    _flight_block,
    _FreeFlight,
    _full_state,
    _impact_block,
    _impact_full,
    _reduced,
)
from hybridpd.analysis.orbits import _HYPERBOLIC_TOL
from hybridpd.hybrid.events import (
    EV_GRAZING,
    EV_NONE,
    EV_NONFINITE,
    EV_START,
    EV_STEP_LIMIT,
)
from hybridpd.loop import ClosedLoop, closed_loop
from hybridpd.model import Case, ImpactPair, Reference, check_positive

__all__ = ["LTIImpactMap", "LTIJacobian", "LTIMapResult"]


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
    >>> from hybridpd.analysis.lti import filtered_pd, lti_symmetric_orbit
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
