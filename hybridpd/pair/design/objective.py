"""The design objective, the shifted orbit of a perturbed plant and the plant status codes."""
from __future__ import annotations

import numpy as np

from hybridpd.model import Case, ImpactPair, as_gains, check_odd_order, check_positive
from hybridpd.pair import symbolic
from hybridpd.pair.orbits import SymmetricOrbitResult, symmetric_orbit

#: Codes of :attr:`RobustReport.status` (per plant of the uncertainty grid).
PLANT_STATUS = {
    0: "ok: the orbit exists, is stable and x10 is within tolerance",
    1: "no symmetric orbit with the designed xm (no positive root x10)",
    2: "the shifted orbit does not exist (viability violated or no solution)",
    3: "the shifted orbit is unstable",
    4: "the shifted orbit is stable but x10 is outside the tolerance"}

_OBJECTIVES = ("min", "sum")
_SPACINGS = ("log", "linear")
_PENALTY_NONE = -3.0


def _f(x):
    return None if x is None or not np.isfinite(x) else float(x)


def _nested(a):
    return [[_f(v) for v in row] for row in np.asarray(a, float)]


def design_objective(exists, stable, spectral_radius, viability_margin, *,
                     viability_weight: float = 1.0, objective: str = "min") -> np.ndarray:
    """The scalar design objective (maximised), vectorised; see the module docstring.

    Parameters
    ----------
    exists, stable : array_like of bool
        Existence (with viability) and stability of the orbit.
    spectral_radius : array_like
        ``rho = max |multiplier|`` (NaN where the orbit does not exist).
    viability_margin : array_like
        Distance to grazing ``nu`` (negative when viability fails, NaN when undefined).
    viability_weight : float
        ``w >= 0``.
    objective : {"min", "sum"}
        ``min(1 - rho, w nu)`` or ``(1 - rho) + w nu``.

    Returns
    -------
    ndarray
        ``J``, > 0 exactly where the orbit exists and is stable; the penalty (<= 0) elsewhere.

    Examples
    --------
    >>> float(design_objective(True, True, 0.3, 0.9))
    0.7
    >>> float(design_objective(True, False, 1.5, 1.0))
    -0.5
    """
    exists = np.asarray(exists, bool)
    stable = np.asarray(stable, bool)
    rho = np.asarray(spectral_radius, float)
    nu = np.asarray(viability_margin, float)
    with np.errstate(invalid="ignore"):
        nu_ok = np.where(np.isfinite(nu), np.maximum(nu, 0.0), 0.0)
        stab = 1.0 - rho
        if objective == "min":
            J = np.minimum(stab, viability_weight * nu_ok)
        elif objective == "sum":
            J = stab + viability_weight * nu_ok
        else:
            raise ValueError(f"objective must be one of {_OBJECTIVES}, got {objective!r}")
        unstable = np.maximum(np.where(np.isfinite(rho), stab, -1.0), -1.0)
        nonviable = -1.0 + np.maximum(np.where(np.isfinite(nu), np.minimum(nu, 0.0), -1.0), -1.0)
    feasible = exists & stable & (J > 0)
    out = np.where(feasible, J, np.where(exists, np.minimum(unstable, 0.0),
                                         np.where(np.isfinite(nu), nonviable, _PENALTY_NONE)))
    return out[()] if out.ndim == 0 else out


# ---------------------------------------------------------------------------------------
# Shifted orbit (robustness)
# ---------------------------------------------------------------------------------------


def shifted_amplitude(kp, kv, xm, *, mu, e, L, omega, m2=1.0, n=1, case="collocated",
                      x10_nominal=1.0):
    """Primary-mass amplitude of the symmetric orbit realised by a given reference amplitude.

    Solves ``(C0 + x C1)^2 + (S0 + x S1)^2 = xm^2`` for ``x > 0`` (``C``, ``S`` of (13)-(14)
    are affine in ``x10`` for fixed ``L``; the coefficients come from the symbolic layer
    evaluated at ``x10 = 1`` and ``2``). Vectorised: all parameters broadcast.

    Parameters
    ----------
    kp, kv : array_like
        PD gains (> 0).
    xm : array_like
        Reference amplitude (length, > 0), e.g. the nominal design's.
    mu, e, L, omega, m2 : array_like
        The (perturbed) plant and the reference frequency (rad/time).
    n : int
        Odd orbit order.
    case : {"collocated", "noncollocated"}
    x10_nominal : array_like
        The desired amplitude; the root closest to it is "the" orbit.

    Returns
    -------
    x10 : ndarray
        The chosen positive root (NaN if none).
    x10_alt : ndarray
        The other positive root (NaN if none).

    Examples
    --------
    >>> from hybridpd.pair.orbits import symmetric_orbits
    >>> xm = float(symmetric_orbits(10, 20, mu=0.1, e=0.5, L=0.75, omega=5.0).xm)
    >>> x, alt = shifted_amplitude(10, 20, xm, mu=0.1, e=0.5, L=0.75, omega=5.0)
    >>> round(float(x), 9)
    1.0
    """
    case = Case.parse(case).value
    n = check_odd_order(n)
    kw = {"kp": kp, "kv": kv, "m2": m2, "mu": mu, "e": e, "L": L, "w": omega, "n": n,
          "case": case}
    a = symbolic.symmetric_orbit(x10=1.0, **kw)
    b = symbolic.symmetric_orbit(x10=2.0, **kw)
    with np.errstate(all="ignore"):
        C1 = np.asarray(b.C) - np.asarray(a.C)
        S1 = np.asarray(b.S) - np.asarray(a.S)
        C0 = np.asarray(a.C) - C1
        S0 = np.asarray(a.S) - S1
        xm = np.asarray(xm, float)
        qa = C1 * C1 + S1 * S1
        qb = 2.0 * (C0 * C1 + S0 * S1)
        qc = C0 * C0 + S0 * S0 - xm * xm
        disc = qb * qb - 4.0 * qa * qc
        sq = np.sqrt(np.maximum(disc, 0.0))
        # the cancellation-free pair of roots
        q = -0.5 * (qb + np.where(qb >= 0, sq, -sq))
        r1 = q / qa
        r2 = qc / q
        ok = (disc >= 0) & np.isfinite(disc)
        v1 = ok & np.isfinite(r1) & (r1 > 0)
        v2 = ok & np.isfinite(r2) & (r2 > 0)
        r1 = np.where(v1, r1, np.nan)
        r2 = np.where(v2, r2, np.nan)
        x0 = np.asarray(x10_nominal, float)
        d1 = np.where(v1, np.abs(r1 - x0), np.inf)
        d2 = np.where(v2, np.abs(r2 - x0), np.inf)
        first = d1 <= d2
        x10 = np.where(first, r1, r2)
        alt = np.where(first, r2, r1)
    x10 = np.where(np.isfinite(x10), x10, np.nan)
    return (x10[()] if x10.ndim == 0 else x10), (alt[()] if alt.ndim == 0 else alt)


def shifted_orbit(pair: ImpactPair, gains, xm: float, omega: float, *, x10_nominal: float = 1.0,
                  n: int = 1, case="collocated") -> SymmetricOrbitResult | None:
    """The symmetric orbit a plant settles on when driven by a reference of amplitude ``xm``.

    Parameters
    ----------
    pair : ImpactPair
        The (perturbed) plant.
    gains : PDGains or (kp, kv)
    xm : float
        Reference amplitude (length).
    omega : float
        Reference frequency (rad/time).
    x10_nominal : float
        Desired primary-mass amplitude: the root of the amplitude quadratic closest to it is
        taken (see :func:`shifted_amplitude`).
    n : int
        Odd orbit order.
    case : {"collocated", "noncollocated"}

    Returns
    -------
    SymmetricOrbitResult or None
        The orbit with primary-mass amplitude ``x10'`` (its ``xm`` equals the given one to
        rounding; check ``exists`` and ``stable``), or ``None`` when no positive ``x10'``
        realises ``xm``.

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains
    >>> o = shifted_orbit(ImpactPair(0.1, 0.7, 0.75), PDGains(10, 20), 0.3986, 5.0)
    >>> o.exists, o.stable, round(o.x10, 3)
    (True, True, 1.078)
    """
    if not isinstance(pair, ImpactPair):
        raise ValueError(f"pair must be an ImpactPair, got {type(pair).__name__}")
    gains = as_gains(gains)
    xm = check_positive("xm", xm)
    omega = check_positive("omega", omega)
    x10_nominal = check_positive("x10_nominal", x10_nominal)
    x10, _ = shifted_amplitude(gains.kp, gains.kv, xm, mu=pair.mu, e=pair.e, L=pair.L,
                               omega=omega, m2=pair.m2, n=n, case=case,
                               x10_nominal=x10_nominal)
    if not np.isfinite(x10):
        return None
    return symmetric_orbit(pair, gains, omega, x10=float(x10), n=n, case=case)
