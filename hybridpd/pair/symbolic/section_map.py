"""The impact map ``P = P43 o P32 o P21 o P10`` and its Jacobian blocks (paper section 4).

Impacts act on the section coordinates ``(phi, z1, z2, z4)`` linearly; flights use the
closed-form flow, with the flight time from the compiled engine's contact location
(:func:`flight_time`) and the flight blocks from implicit differentiation (generated code of
the SymPy derivation, see :mod:`hybridpd.pair.symbolic.derive`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.pair.symbolic._numeric import _as_float_arrays, _case, _stack, kernel
from hybridpd.pair.symbolic.existence import SymmetricOrbit

__all__ = [
    "ImpactMapResult",
    "JacobianResult",
    "closed_form_map",
    "flight_block",
    "flight_section_map",
    "flight_time",
    "impact_block",
    "impact_section_map",
    "map_jacobian",
    "orbit_jacobian",
]


def impact_section_map(s, *, mu, e) -> np.ndarray:
    """Impact (P10 or P32) in section coordinates: ``(phi, z1, z2 + (1+e) mu z4/(1+mu), -e z4)``.

    ``s`` has shape (..., 4) (pre-impact); the law is the same on both walls.
    """
    s, mu, e = _as_float_arrays(s=s, mu=mu, e=e)
    phi, z1, z2, z4 = np.moveaxis(s, -1, 0)
    shape = np.broadcast_shapes(phi.shape, mu.shape, e.shape)
    return _stack([phi, z1, z2 + (1 + e) * mu / (1 + mu) * z4, -e * z4], shape)


def impact_block(*, mu, e) -> np.ndarray:
    """Jacobian ``DP10 = DP32`` of the impact in section coordinates, shape (..., 4, 4).

    ``[[1,0,0,0],[0,1,0,0],[0,0,1,(1+e) mu/(1+mu)],[0,0,0,-e]]`` (independent of the state).
    """
    mu, e = _as_float_arrays(mu=mu, e=e)
    shape = np.broadcast_shapes(mu.shape, e.shape)
    B = np.zeros(shape + (4, 4))
    B[..., 0, 0] = B[..., 1, 1] = B[..., 2, 2] = 1.0
    B[..., 2, 3] = (1 + e) * mu / (1 + mu)
    B[..., 3, 3] = -e
    return B


def _flight_args(s, tau, xm, kp, kv, m2, w, L, wall):
    s, tau, xm, kp, kv, m2, w, L, wall = _as_float_arrays(
        s=s, tau=tau, xm=xm, kp=kp, kv=kv, m2=m2, w=w, L=L, wall=wall)
    if s.shape[-1:] != (4,):
        raise ValueError(f"s must have shape (..., 4) (phi, z1, z2, z4), got {s.shape}")
    if not np.all(np.abs(wall) == 1):
        raise ValueError("wall must be +1 or -1")
    shape = np.broadcast_shapes(s.shape[:-1], tau.shape, xm.shape, kp.shape, kv.shape,
                                m2.shape, w.shape, L.shape, wall.shape)
    return [*np.moveaxis(s, -1, 0), tau, xm, kp, kv, m2, w, L, wall], shape


def flight_section_map(s, tau, *, xm, kp, kv, m2=1.0, w, L, wall=1,
                       case="collocated", return_gap=False):
    """Flight from wall ``wall`` lasting ``tau``, in section coordinates (closed form).

    Parameters
    ----------
    s : array_like, shape (..., 4)
        Post-impact ``(phi, z1, z2, z4)`` on ``z3 = wall * L``.
    tau : array_like
        Flight time (the caller supplies it, e.g. from :func:`flight_time`).
    xm, kp, kv, m2, w, L : array_like
        Reference amplitude and parameters.
    wall : {+1, -1}
        Departure wall; the flight is meant to end on ``z3 = -wall * L``.
    case : {"collocated", "noncollocated"}
    return_gap : bool
        Also return ``g = z3(tau) + wall L`` (zero when ``tau`` is the flight time).

    Returns
    -------
    s_out : ndarray, shape (..., 4)
        ``(phi + tau, x2(tau), y2(tau), y1(tau) - y2(tau))`` (``phi`` not reduced mod T).
    g : ndarray, shape (...)
        Only with ``return_gap``.
    """
    case = _case(case)
    args, shape = _flight_args(s, tau, xm, kp, kv, m2, w, L, wall)
    vals = kernel("flight_out", case)(*args)
    out = _stack(vals[:4], shape)
    if return_gap:
        return out, np.broadcast_to(np.asarray(vals[4], dtype=float), shape)[()]
    return out


def flight_block(s, tau, *, xm, kp, kv, m2=1.0, w, L, wall=1, case="collocated") -> np.ndarray:
    """Jacobian of a flight block, ``DP21`` (``wall=+1``) or ``DP43`` (``wall=-1``).

    Implicit differentiation (26): ``DP = Fs - Ftau (Gs / Gtau)`` with
    ``F = (phi + tau, x2, y2, y1 - y2)(tau)``, ``G = z3(tau) + wall L``,
    ``Gtau = z4(tau)`` (the pre-impact relative velocity; must be non-zero).

    Parameters
    ----------
    s : array_like, shape (..., 4)
        The block's input: post-impact ``(phi, z1, z2, z4)`` on ``z3 = wall L``.
    tau : array_like
        The flight time to ``z3 = -wall L``.
    xm, kp, kv, m2, w, L, wall, case
        As in :func:`flight_section_map`.

    Returns
    -------
    ndarray, shape (..., 4, 4)
        ``d(phi, z1, z2, z4)_out / d(phi, z1, z2, z4)_in``.
    """
    case = _case(case)
    return _flight_block_and_map(s, tau, xm, kp, kv, m2, w, L, wall, case)[0]


def _flight_block_and_map(s, tau, xm, kp, kv, m2, w, L, wall, case):
    """(block (..., 4, 4), s_out (..., 4), gap (...)) in one lambdified call."""
    args, shape = _flight_args(s, tau, xm, kp, kv, m2, w, L, wall)
    vals = kernel("flight", case)(*args)
    block = _stack(vals[:16], shape).reshape(shape + (4, 4))
    out = _stack(vals[16:20], shape)
    g = np.broadcast_to(np.asarray(vals[20], dtype=float), shape)[()]
    return block, out, g


def flight_time(s, *, xm, kp, kv, m2=1.0, w, L, wall=1, case="collocated",
                tmax=None, return_wall=False):
    """First time a flight from wall ``wall`` hits a wall.

    Scalar (one section point). The contact is located by the compiled engine's guaranteed
    safe-step root finder on the closed-form gap (:func:`hybridpd.pair.batch.next_impact`,
    gap tolerance ``1e-13``): the package's one contact location for the pair.

    Parameters
    ----------
    s : array_like, shape (4,)
        Post-impact ``(phi, z1, z2, z4)`` on ``z3 = wall L``; ``wall * z4 < 0`` (leaving).
    xm, kp, kv, m2, w, L, wall, case
        As in :func:`flight_section_map`.
    tmax : float, optional
        Search horizon; default ``50 T``.
    return_wall : bool
        Also return the wall hit (``-wall`` normally; ``+wall`` if the masses meet the
        departure wall again first).

    Returns
    -------
    tau : float
        First impact time (``nan`` if none before ``tmax`` or if ``wall * z4 >= 0``).
    hit : int
        Only with ``return_wall``: the wall hit (0 if none).
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.batch import STATUS_IMPACT, STATUS_STICK, Flight, next_impact, pack_params

    collocated = _case(case) == "collocated"
    s = np.asarray(s, dtype=float)
    wall = int(wall)
    res = (np.nan, 0)
    if wall * s[3] < 0:
        tmax = 100 * math.pi / w if tmax is None else float(tmax)
        # next_impact reads neither mu nor e: placeholders
        params = pack_params(kp=kp, kv=kv, m2=m2, mu=0.0, e=0.0, L=L, w=w, xm=xm)
        fl = Flight(float(s[0]), float(s[1] + wall * L), float(s[2] + s[3]), float(s[1]),
                    float(s[2]))
        st, tau, hit, *_ = next_impact(params, 0 if collocated else 1, fl, tmax, 1e-13)
        if st in (STATUS_IMPACT, STATUS_STICK):
            res = (float(tau), int(hit))
    return res if return_wall else res[0]


@dataclass(frozen=True)
class ImpactMapResult:
    """One application of the impact map ``P`` (numerical: closed-form flows + root finding).

    Attributes
    ----------
    s0, s1, s2, s3, s4 : ndarray, shape (4,)
        Pre-impact at ``+L``, post-impact, pre-impact at ``-L``, post-impact, pre-impact at
        ``+L`` (``phi`` accumulates: ``s4[0] = s0[0] + tau1 + tau2``, not reduced mod T).
    tau1, tau2 : float
        Flight times ``+L -> -L`` and ``-L -> +L``.
    ok : bool
        Both flights ended on the opposite wall (otherwise later entries are ``nan``).
    """

    __repr__ = compact_repr

    s0: np.ndarray
    s1: np.ndarray
    s2: np.ndarray
    s3: np.ndarray
    s4: np.ndarray
    tau1: float
    tau2: float
    ok: bool


def closed_form_map(s0, *, xm, kp, kv, m2=1.0, mu, e, L, w, case="collocated",
               tmax=None) -> ImpactMapResult:
    """Apply ``P = P43 o P32 o P21 o P10`` to one pre-impact section point (scalar).

    Parameters
    ----------
    s0 : array_like, shape (4,)
        ``(phi, z1, z2, z4)`` on ``z3 = +L`` with ``z4 > 0``.
    xm, kp, kv, m2, mu, e, L, w : float
        Reference amplitude and parameters.
    case : {"collocated", "noncollocated"}
    tmax : float, optional
        Horizon of each flight-time search (default ``50 T``).

    Returns
    -------
    ImpactMapResult
    """
    case = _case(case)
    kw = dict(xm=xm, kp=kp, kv=kv, m2=m2, w=w, L=L, case=case)
    s0 = np.asarray(s0, dtype=float)
    nan4 = np.full(4, np.nan)
    s1 = impact_section_map(s0, mu=mu, e=e)
    tau1, hit1 = flight_time(s1, wall=1, tmax=tmax, return_wall=True, **kw)
    if hit1 != -1:
        return ImpactMapResult(s0, s1, nan4, nan4, nan4, tau1, np.nan, False)
    s2 = flight_section_map(s1, tau1, wall=1, **kw)
    s3 = impact_section_map(s2, mu=mu, e=e)
    tau2, hit2 = flight_time(s3, wall=-1, tmax=tmax, return_wall=True, **kw)
    if hit2 != 1:
        return ImpactMapResult(s0, s1, s2, s3, nan4, tau1, tau2, False)
    s4 = flight_section_map(s3, tau2, wall=-1, **kw)
    return ImpactMapResult(s0, s1, s2, s3, s4, tau1, tau2, True)


@dataclass(frozen=True)
class JacobianResult:
    """Jacobian of the impact map and its four blocks (24)-(25), vectorised.

    Attributes
    ----------
    DP : ndarray, shape (..., 4, 4)
        ``DP43 @ DP32 @ DP21 @ DP10`` in coordinates ``(phi, z1, z2, z4)``.
    DP10, DP21, DP32, DP43 : ndarray, shape (..., 4, 4)
        Impact at ``+L``, flight ``+L -> -L``, impact at ``-L``, flight ``-L -> +L``.
    s0, s1, s2, s3, s4 : ndarray, shape (..., 4)
        Section points along the map (``s2``, ``s4`` from the closed-form flow with the given
        flight times; ``phi`` not reduced mod T).
    tau1, tau2 : ndarray
        The flight times used.
    gap2, gap4 : ndarray
        Residuals ``z3 + L`` at ``s2`` and ``z3 - L`` at ``s4`` (zero if the flight times are
        the true ones).
    """

    __repr__ = compact_repr

    DP: np.ndarray
    DP10: np.ndarray
    DP21: np.ndarray
    DP32: np.ndarray
    DP43: np.ndarray
    s0: np.ndarray
    s1: np.ndarray
    s2: np.ndarray
    s3: np.ndarray
    s4: np.ndarray
    tau1: np.ndarray
    tau2: np.ndarray
    gap2: np.ndarray
    gap4: np.ndarray

    def eigenvalues(self) -> np.ndarray:
        """Eigenvalues of ``DP`` (Floquet multipliers), shape (..., 4), complex."""
        return np.linalg.eigvals(self.DP)

    def spectral_radius(self) -> np.ndarray:
        """Largest eigenvalue modulus of ``DP``, shape (...)."""
        return np.max(np.abs(self.eigenvalues()), axis=-1)


def map_jacobian(s0, tau1, tau2, *, xm, kp, kv, m2=1.0, mu, e, L, w,
                 case="collocated") -> JacobianResult:
    """``DP`` and its blocks at a general pre-impact section point, given the flight times.

    Parameters
    ----------
    s0 : array_like, shape (..., 4)
        Pre-impact ``(phi, z1, z2, z4)`` on ``z3 = +L`` (``z4 > 0``).
    tau1, tau2 : array_like
        Flight times ``+L -> -L`` and ``-L -> +L`` (e.g. from :func:`closed_form_map`).
    xm, kp, kv, m2, mu, e, L, w : array_like
        Reference amplitude and parameters; everything broadcasts.
    case : {"collocated", "noncollocated"}

    Returns
    -------
    JacobianResult
    """
    case = _case(case)
    s1 = impact_section_map(s0, mu=mu, e=e)
    F21, s2, g2 = _flight_block_and_map(s1, tau1, xm, kp, kv, m2, w, L, 1.0, case)
    s3 = impact_section_map(s2, mu=mu, e=e)
    F43, s4, g4 = _flight_block_and_map(s3, tau2, xm, kp, kv, m2, w, L, -1.0, case)
    B = impact_block(mu=mu, e=e)
    shape = F21.shape[:-2]
    B = np.broadcast_to(B, shape + (4, 4))
    DP = F43 @ B @ F21 @ B
    s0 = np.broadcast_to(np.asarray(s0, dtype=float), shape + (4,))
    return JacobianResult(DP=DP, DP10=B, DP21=F21, DP32=B, DP43=F43, s0=s0, s1=s1, s2=s2,
                          s3=s3, s4=s4, tau1=np.broadcast_to(np.asarray(tau1, float), shape),
                          tau2=np.broadcast_to(np.asarray(tau2, float), shape), gap2=g2,
                          gap4=g4)


def orbit_jacobian(orbit: SymmetricOrbit) -> JacobianResult:
    """``DP`` and its blocks at the fixed point of a :class:`SymmetricOrbit` (vectorised).

    Both flights last ``tau = n T/2``; the section point is ``orbit.section_point``.
    """
    return map_jacobian(orbit.section_point, orbit.tau, orbit.tau, xm=orbit.xm, kp=orbit.kp,
                        kv=orbit.kv, m2=orbit.m2, mu=orbit.mu, e=orbit.e, L=orbit.L, w=orbit.w,
                        case=orbit.case)


# the name of 0.2.0 (hybridpd.pair.batch.impact_map is the compiled map of a batch)
