"""Gain design: PD gains and reference that make a desired primary-mass motion a stable orbit.

The user states the desired motion of the primary mass — a triangle wave of amplitude ``x10``
(length) and frequency ``omega`` (rad/time) with one impact on each wall per ``n`` reference
periods (``n`` odd) — the plant (``m2``, ``mu``, ``e``, ``L``) and the feedback case. For
every gain pair ``(kp, kv)`` the conditions (13)-(14) then fix the reference amplitude ``xm``
and the impact phase ``phi0`` (:func:`hybridpd.analysis.orbits.symmetric_orbits`); the design chooses
the gains.

Objective (maximised)
---------------------
For a gain pair whose symmetric orbit exists (solvable with ``xm > 0`` and viable) and is
stable, with spectral radius ``rho`` of ``DP`` and viability margin ``nu`` (distance to
grazing, ``min (L - |z3|)/L`` over the interior turning points of ``z3``, 1 when ``z3`` is
monotone between the impacts):

* ``objective="min"`` (default): ``J = min(1 - rho, w * nu)`` — the design is as good as its
  weaker margin; ``w = viability_weight`` (default 1) trades a unit of viability margin
  against a unit of stability margin (``w > 0`` required).
* ``objective="sum"``: ``J = (1 - rho) + w * nu``; with a small ``w`` this is the
  lexicographic choice "best stability margin, then the farthest from grazing". ``w = 0``
  ignores grazing, and the optimum may then sit on the existence boundary (19): at
  ``mu = 1, e = 0.5, gamma = 0.75, omega = 5`` (collocated) it has ``nu ~ 1e-8``, while the
  default ``min`` objective balances ``1 - rho = nu = 0.285``.

Both are > 0 exactly on the feasible set (exists and stable). Outside it the search uses a
penalty ``<= 0`` that keeps the optimiser pointed back at the feasible set: ``max(1 - rho, -1)``
for an existing but unstable orbit, ``-1 + max(min(nu, 0), -1)`` when viability fails, ``-3``
when the conditions have no solution or the masses stick.

Search
------
Global, then local: the objective is evaluated (vectorised) on a ``grid`` over the gain box
(``kp_range x kv_range``, default ``[0.1, 100]^2``, log-spaced by default: the feasible
regions span decades), the best ``n_starts`` separated local maxima of the grid are refined
with bounded Nelder-Mead (:func:`scipy.optimize.minimize`, in normalised log or linear
coordinates), and the best refined point is re-evaluated with
:func:`hybridpd.analysis.orbits.symmetric_orbit`. The map and the optimiser reports are returned as
evidence. If no grid point is feasible (and no refinement finds one)
:class:`InfeasibleDesignError` is raised.

Robust design
-------------
With uncertainty boxes for ``e`` and/or ``mu`` the gains *and* the reference amplitude ``xm``
stay those designed for the nominal plant; the reference phase is free (the system settles
wherever). A plant ``(e', mu')`` then settles on the symmetric orbit with the same ``xm`` and
another primary-mass amplitude ``x10'``. Because (13)-(14) are linear in
``(C, S) = xm (cos w t0, sin w t0)`` with right-hand sides affine in ``x10`` (``L`` fixed),
``C = C0 + x10 C1``, ``S = S0 + x10 S1`` and ``xm(x10)^2 = xm_design^2`` is a quadratic in
``x10``. Of its positive roots, **the orbit is the one closest to the desired** ``x10`` (the
branch continued from the nominal plant while the two roots stay apart; the other root is
typically an unstable saddle-type orbit at small amplitude and is reported as ``x10_alt``).
A plant fails if there is no positive root, the orbit does not exist or is unstable, or
``|x10'/x10 - 1| > x10_tol``. The robust objective is the worst case of ``J`` over the plants
(an ``uncertainty_grid`` over the box, corners included, plus the nominal plant); it is
positive exactly when every plant passes. The worst case and where it happens are reported,
and the design is re-checked on a finer validation grid.

Examples
--------
>>> from hybridpd.analysis.design import design
>>> d = design("collocated", mu=0.1, e=0.5, gamma=0.75, omega=5.0, grid=(24, 24))
>>> d.orbit.exists and d.orbit.stable
True
>>> 0 < d.spectral_radius < 1
True
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage, optimize

from hybridpd._repr import compact_repr
from hybridpd.analysis.orbits import (
    REASONS,
    SymmetricOrbitResult,
    symmetric_orbit,
    symmetric_orbits,
)
from hybridpd.model import (
    Case,
    ImpactPair,
    PDGains,
    as_gains,
    check_finite,
    check_in_range,
    check_int,
    check_odd_order,
    check_positive,
)
from hybridpd.pair import symbolic

__all__ = [
    "PLANT_STATUS",
    "ComparisonRow",
    "DesignMap",
    "DesignResult",
    "InfeasibleDesignError",
    "OptimizerRun",
    "RobustReport",
    "RobustnessComparison",
    "design",
    "design_objective",
    "robustness",
    "robustness_comparison",
    "shifted_amplitude",
    "shifted_orbit",
]

#: Codes of :attr:`RobustReport.status` (per plant of the uncertainty grid).
PLANT_STATUS = {
    0: "ok: the orbit exists, is stable and x10 is within tolerance",
    1: "no symmetric orbit with the designed xm (no positive root x10)",
    2: "the shifted orbit does not exist (viability violated or no solution)",
    3: "the shifted orbit is unstable",
    4: "the shifted orbit is stable but x10 is outside the tolerance",
}

_OBJECTIVES = ("min", "sum")
_SPACINGS = ("log", "linear")
_PENALTY_NONE = -3.0


class InfeasibleDesignError(RuntimeError):
    """No gains in the searched box give an existing, stable (and, if asked, robust) orbit.

    Attributes
    ----------
    why : str
        One-line explanation.
    reason_counts : dict
        ``{reason text: number of grid points}`` over the searched gain grid (nominal plant);
        for a robust design also ``"robust: <plant status>"`` counts over the nominally
        feasible gains.
    closest : dict or None
        The closest miss: for a nominal design the grid gains with the smallest spectral
        radius among existing orbits (``kp, kv, xm, spectral_radius, viability_margin``); for
        a robust design the gains with the best worst-case objective, with its worst case.
        ``None`` when no orbit exists anywhere in the box.
    design_map : DesignMap
        The evidence: everything evaluated on the grid.
    """

    def __init__(self, why: str, *, reason_counts: dict, closest: dict | None,
                 design_map: DesignMap):
        self.why = why
        self.reason_counts = reason_counts
        self.closest = closest
        self.design_map = design_map
        msg = why
        if closest is not None:
            msg += "; closest miss: " + ", ".join(
                f"{k} = {v:.6g}" if isinstance(v, float) else f"{k} = {v}"
                for k, v in closest.items())
        counts = ", ".join(f"{v} x {k!r}" for k, v in reason_counts.items())
        if counts:
            msg += f"; grid: {counts}"
        super().__init__(msg)


# ---------------------------------------------------------------------------------------
# Objective
# ---------------------------------------------------------------------------------------


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
    >>> from hybridpd.analysis.orbits import symmetric_orbits
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


# ---------------------------------------------------------------------------------------
# Result dataclasses
# ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class DesignMap:
    """The searched gain grid (evidence). Arrays are indexed ``[kv][kp]``.

    Attributes
    ----------
    kp, kv : ndarray, shapes (nkp,), (nkv,)
        Grid axes.
    spacing : str
        ``"log"`` or ``"linear"``.
    objective : ndarray, shape (nkv, nkp)
        What the search maximised at the grid points: the nominal objective ``J`` or, for a
        robust design, the worst case over the plants (nominally infeasible gains keep their
        nominal penalty).
    nominal_objective : ndarray
        ``J`` at the nominal plant.
    exists, stable : ndarray of bool
        Nominal existence (with viability) and stability.
    reason : ndarray of int
        Codes of :data:`hybridpd.analysis.orbits.REASONS`.
    spectral_radius, viability_margin, xm, phi0 : ndarray
        Nominal orbit data (NaN where undefined); ``xm`` length, ``phi0`` time.
    robust_feasible : ndarray of bool or None
        Every plant of the uncertainty grid passes (robust design only).
    worst_spectral_radius : ndarray or None
        Largest spectral radius over the plants (robust design only; NaN where some plant has
        no orbit).
    robust_stable : ndarray of bool or None
        The shifted orbit exists and is stable at every plant, whatever its amplitude (robust
        design only): robustness of stability alone, without the ``x10_tol`` requirement.
    """

    __repr__ = compact_repr

    kp: np.ndarray
    kv: np.ndarray
    spacing: str
    objective: np.ndarray
    nominal_objective: np.ndarray
    exists: np.ndarray
    stable: np.ndarray
    reason: np.ndarray
    spectral_radius: np.ndarray
    viability_margin: np.ndarray
    xm: np.ndarray
    phi0: np.ndarray
    robust_feasible: np.ndarray | None = None
    worst_spectral_radius: np.ndarray | None = None
    robust_stable: np.ndarray | None = None

    def feasible_fraction(self, which: str = "nominal") -> float:
        """Share of the grid (in the grid's own spacing) in a region.

        ``which``: ``"nominal"`` (exists and stable at the nominal plant), ``"robust"``
        (robust-feasible, amplitude tolerance included) or ``"robust_stable"`` (exists and
        stable over the box, amplitude ignored).
        """
        if which == "nominal":
            return float(np.mean(self.exists & self.stable))
        maps = {"robust": self.robust_feasible, "robust_stable": self.robust_stable}
        if which not in maps:
            raise ValueError(f"which must be 'nominal', 'robust' or 'robust_stable', got {which!r}")
        arr = maps[which]
        if arr is None:
            raise ValueError("this map has no robust evaluation")
        return float(np.mean(arr))


@dataclass(frozen=True)
class OptimizerRun:
    """One local refinement (bounded Nelder-Mead) from a grid seed.

    Attributes
    ----------
    start_kp, start_kv, start_objective : float
        The seed and its objective.
    kp, kv, objective : float
        Where it ended and the objective there (maximised).
    nfev, nit : int
        Objective evaluations and iterations.
    success : bool
    message : str
        :class:`scipy.optimize.OptimizeResult` status text.
    """

    __repr__ = compact_repr

    start_kp: float
    start_kv: float
    start_objective: float
    kp: float
    kv: float
    objective: float
    nfev: int
    nit: int
    success: bool
    message: str

    def to_dict(self) -> dict:
        """JSON-ready form."""
        return {k: (float(v) if isinstance(v, (float, np.floating)) else v)
                for k, v in self.__dict__.items()}


@dataclass(frozen=True)
class RobustReport:
    """Behaviour of fixed gains and reference amplitude over an uncertainty box of ``(e, mu)``.

    Plant arrays are indexed ``[e][mu]`` over ``e_values x mu_values`` (the uncertainty grid,
    corners included); the nominal plant is checked as well (``nominal_ok``).

    Attributes
    ----------
    e_values, mu_values : ndarray
        Grid axes of the uncertainty box.
    x10_nominal : float
        Desired primary-mass amplitude (length).
    xm : float
        The fixed reference amplitude (length).
    x10_tol : float
        Allowed relative amplitude error.
    x10, x10_alt : ndarray
        Amplitude of the shifted orbit (the root closest to ``x10_nominal``) and the other
        root (NaN if none).
    x10_error : ndarray
        ``|x10 / x10_nominal - 1|``.
    exists, stable : ndarray of bool
    spectral_radius, viability_margin : ndarray
    objective : ndarray
        Per-plant score: ``J`` of the shifted orbit if the plant passes, else the penalty
        (<= 0), lowered further by ``min(1, (x10_error - x10_tol)/x10_tol)`` when the
        amplitude is out of tolerance.
    status : ndarray of int
        Codes of :data:`PLANT_STATUS`.
    ok : bool
        Every plant (and the nominal plant) passes.
    nominal_ok : bool
    worst_objective : float
        Minimum of ``objective`` over the plants (and the nominal plant).
    worst_case : dict
        ``{"e": ..., "mu": ...}`` where ``worst_objective`` is attained.
    worst_spectral_radius : float
        Largest spectral radius over the plants (NaN if some plant has no orbit).
    worst_spectral_radius_case : dict
        Where it is attained.
    worst_viability_margin : float
        Smallest viability margin over the plants.
    worst_x10_error : float
        Largest relative amplitude error (NaN if some plant has no orbit).
    """

    __repr__ = compact_repr

    e_values: np.ndarray
    mu_values: np.ndarray
    x10_nominal: float
    xm: float
    x10_tol: float
    x10: np.ndarray
    x10_alt: np.ndarray
    x10_error: np.ndarray
    exists: np.ndarray
    stable: np.ndarray
    spectral_radius: np.ndarray
    viability_margin: np.ndarray
    objective: np.ndarray
    status: np.ndarray
    ok: bool
    nominal_ok: bool
    worst_objective: float
    worst_case: dict
    worst_spectral_radius: float
    worst_spectral_radius_case: dict
    worst_viability_margin: float
    worst_x10_error: float

    def failures(self) -> list:
        """``[(e, mu, status text), ...]`` for every failing plant of the grid."""
        out = []
        for i, j in zip(*np.nonzero(self.status != 0)):
            out.append((float(self.e_values[i]), float(self.mu_values[j]),
                        PLANT_STATUS[int(self.status[i, j])]))
        return out

    def to_dict(self) -> dict:
        """JSON-ready summary (grid arrays as nested lists, NaN as ``None``)."""
        return {
            "e_values": self.e_values.tolist(), "mu_values": self.mu_values.tolist(),
            "x10_nominal": self.x10_nominal, "xm": self.xm, "x10_tol": self.x10_tol,
            "ok": bool(self.ok), "nominal_ok": bool(self.nominal_ok),
            "worst_objective": _f(self.worst_objective), "worst_case": self.worst_case,
            "worst_spectral_radius": _f(self.worst_spectral_radius),
            "worst_spectral_radius_case": self.worst_spectral_radius_case,
            "worst_viability_margin": _f(self.worst_viability_margin),
            "worst_x10_error": _f(self.worst_x10_error),
            "x10": _nested(self.x10), "spectral_radius": _nested(self.spectral_radius),
            "viability_margin": _nested(self.viability_margin),
            "status": self.status.tolist(),
            "status_codes": {str(k): v for k, v in PLANT_STATUS.items()},
        }


@dataclass(frozen=True)
class DesignResult:
    """A designed PD controller and reference, with the evidence.

    Attributes
    ----------
    case : Case
    gains : PDGains
        The designed ``(kp, kv)``.
    xm : float
        Reference amplitude (length): the reference is ``xd = xm cos(omega t)``.
    phi0 : float
        Phase (time, in ``[0, T)``) of the ``+L`` impact relative to the reference.
    spectral_radius : float
        ``rho`` of ``DP`` at the nominal orbit.
    stability_margin : float
        ``1 - rho``.
    viability_margin : float
        Distance to grazing (see :mod:`hybridpd.analysis.orbits`).
    objective : float
        The maximised value: nominal ``J`` or, for a robust design, the worst case over the
        uncertainty grid.
    objective_kind : str
        ``"min"`` or ``"sum"``.
    viability_weight : float
    orbit : SymmetricOrbitResult
        The nominal orbit, recomputed by :func:`hybridpd.analysis.orbits.symmetric_orbit`.
    spec : dict
        The specification: ``mu, e, L, gamma, x10, m2, omega, n`` and the gain box.
    design_map : DesignMap
        The searched grid.
    optimizer : list of OptimizerRun
        The local refinements (best first).
    robust : RobustReport or None
        Worst case over the uncertainty grid (robust design only).
    validation : RobustReport or None
        The same check on a finer grid of the box (robust design only).
    elapsed : float
        Wall time of the design (s).
    """

    __repr__ = compact_repr

    case: Case
    gains: PDGains
    xm: float
    phi0: float
    spectral_radius: float
    stability_margin: float
    viability_margin: float
    objective: float
    objective_kind: str
    viability_weight: float
    orbit: SymmetricOrbitResult = field(repr=False)
    spec: dict = field(repr=False)
    design_map: DesignMap = field(repr=False)
    optimizer: list = field(repr=False)
    robust: RobustReport | None = field(default=None, repr=False)
    validation: RobustReport | None = field(default=None, repr=False)
    elapsed: float = float("nan")

    @property
    def kp(self) -> float:
        """Designed proportional gain."""
        return self.gains.kp

    @property
    def kv(self) -> float:
        """Designed derivative gain."""
        return self.gains.kv

    def to_dict(self) -> dict:
        """The JSON object ``hybridpd design --json`` prints.

        Always: ``case, kp, kv, xm, phi0, spectral_radius, stability_margin,
        viability_margin, objective, objective_kind, viability_weight, multipliers, robust``
        and the specification (``mu, e, L, gamma, x10, m2, omega, n, kp_range, kv_range``).
        For a robust design also ``worst_spectral_radius``, ``worst_case`` (``{"e", "mu"}``
        of the worst objective), ``worst_objective``, ``worst_viability_margin``,
        ``worst_x10_error``, ``x10_tol``, ``e_range``, ``mu_range`` and ``validation``
        (the finer-grid check's worst values).
        """
        o = self.orbit
        d = {
            "case": self.case.value, "kp": float(self.kp), "kv": float(self.kv),
            "xm": float(self.xm), "phi0": float(self.phi0),
            "spectral_radius": float(self.spectral_radius),
            "stability_margin": float(self.stability_margin),
            "viability_margin": float(self.viability_margin),
            "objective": float(self.objective), "objective_kind": self.objective_kind,
            "viability_weight": float(self.viability_weight),
            "multipliers": [[float(z.real), float(z.imag)] for z in o.multipliers],
            "exists": bool(o.exists), "stable": bool(o.stable),
            "robust": self.robust is not None,
        }
        d.update({k: v for k, v in self.spec.items()})
        if self.robust is not None:
            r = self.robust
            d.update({
                "worst_spectral_radius": _f(r.worst_spectral_radius),
                "worst_case": dict(r.worst_case),
                "worst_objective": _f(r.worst_objective),
                "worst_viability_margin": _f(r.worst_viability_margin),
                "worst_x10_error": _f(r.worst_x10_error),
                "worst_spectral_radius_case": dict(r.worst_spectral_radius_case),
            })
            if self.validation is not None:
                v = self.validation
                d["validation"] = {
                    "grid": [len(v.e_values), len(v.mu_values)], "ok": bool(v.ok),
                    "worst_spectral_radius": _f(v.worst_spectral_radius),
                    "worst_case": dict(v.worst_case), "worst_objective": _f(v.worst_objective),
                    "worst_x10_error": _f(v.worst_x10_error),
                }
        d["elapsed"] = float(self.elapsed)
        return d


def _f(x):
    return None if x is None or not np.isfinite(x) else float(x)


def _nested(a):
    return [[_f(v) for v in row] for row in np.asarray(a, float)]


# ---------------------------------------------------------------------------------------
# Validation helpers
# ---------------------------------------------------------------------------------------


def _range(name, value, *, lo_bound=0.0, hi_bound=None, closed_lo=False, allow_equal=False):
    try:
        lo, hi = value
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a pair (LO, HI), got {value!r}") from None
    lo = check_finite(f"{name}[0]", lo)
    hi = check_finite(f"{name}[1]", hi)
    if (lo < lo_bound) if closed_lo else (lo <= lo_bound):
        rng = f"[{lo_bound:g}, " if closed_lo else f"({lo_bound:g}, "
        rng += "inf)" if hi_bound is None else f"{hi_bound:g}]"
        raise ValueError(f"{name} must lie in {rng}, got {value!r}")
    if hi_bound is not None and hi > hi_bound:
        raise ValueError(f"{name} must lie in [{lo_bound:g}, {hi_bound:g}], got {value!r}")
    if not (hi > lo or (allow_equal and hi == lo)):
        raise ValueError(f"{name} must be increasing (LO < HI), got {value!r}")
    return lo, hi


def _grid_shape(name, value, minimum=2):
    try:
        a, b = value
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a pair of integers, got {value!r}") from None
    if isinstance(value, (str, bytes, dict)):
        raise ValueError(f"{name} must be a pair of integers >= {minimum}, got {value!r}")
    return check_int(f"{name}[0]", a, minimum), check_int(f"{name}[1]", b, minimum)


def _axis_values(lo, hi, num, spacing):
    if spacing == "log":
        return np.geomspace(lo, hi, num)
    return np.linspace(lo, hi, num)


# ---------------------------------------------------------------------------------------
# Core evaluations
# ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Problem:
    """Validated specification (internal; immutable, so no state leaks between calls)."""

    case: Case
    mu: float
    e: float
    L: float
    x10: float
    m2: float
    omega: float
    n: int
    kp_range: tuple
    kv_range: tuple
    spacing: str
    weight: float
    kind: str
    e_grid: np.ndarray | None
    mu_grid: np.ndarray | None
    x10_tol: float

    @property
    def robust(self) -> bool:
        return self.e_grid is not None

    def to_unit(self, kp, kv):
        (a, b), (c, d) = self.kp_range, self.kv_range
        if self.spacing == "log":
            return np.array([math.log(kp / a) / math.log(b / a), math.log(kv / c) / math.log(d / c)])
        return np.array([(kp - a) / (b - a), (kv - c) / (d - c)])

    def from_unit(self, u):
        u = np.clip(np.asarray(u, float), 0.0, 1.0)
        (a, b), (c, d) = self.kp_range, self.kv_range
        if self.spacing == "log":
            return a * (b / a) ** u[0], c * (d / c) ** u[1]
        return a + u[0] * (b - a), c + u[1] * (d - c)


def _nominal(pb: _Problem, kp, kv, margin=True):
    r = symmetric_orbits(kp, kv, mu=pb.mu, e=pb.e, L=pb.L, omega=pb.omega, m2=pb.m2,
                         x10=pb.x10, n=pb.n, case=pb.case, margin=margin)
    J = design_objective(r.exists, r.stable, r.spectral_radius, r.viability_margin,
                         viability_weight=pb.weight, objective=pb.kind)
    return r, J


def _plants(e_values, mu_values, e_nom, mu_nom):
    E, M = np.meshgrid(e_values, mu_values, indexing="ij")
    pe = np.append(E.ravel(), e_nom)
    pm = np.append(M.ravel(), mu_nom)
    return pe, pm, E.shape


def _plant_eval(pb: _Problem, kp, kv, xm, pe, pm):
    """Per (gain, plant): shape (G, P) arrays for gains (G,) with reference ``xm`` (G,)."""
    kp = np.asarray(kp, float)[:, None]
    kv = np.asarray(kv, float)[:, None]
    xm = np.asarray(xm, float)[:, None]
    pe = np.asarray(pe, float)[None, :]
    pm = np.asarray(pm, float)[None, :]
    x10, alt = shifted_amplitude(kp, kv, xm, mu=pm, e=pe, L=pb.L, omega=pb.omega, m2=pb.m2,
                                 n=pb.n, case=pb.case, x10_nominal=pb.x10)
    x10 = np.broadcast_to(x10, np.broadcast_shapes(kp.shape, pe.shape))
    has = np.isfinite(x10)
    r = symmetric_orbits(kp, kv, mu=pm, e=pe, L=pb.L, omega=pb.omega, m2=pb.m2,
                         x10=np.where(has, x10, 1.0), n=pb.n, case=pb.case, margin=True)
    exists = r.exists & has
    stable = r.stable & has
    rho = np.where(has, r.spectral_radius, np.nan)
    nu = np.where(has, r.viability_margin, np.nan)
    err = np.abs(x10 / pb.x10 - 1.0)
    J = design_objective(exists, stable, rho, nu, viability_weight=pb.weight, objective=pb.kind)
    J = np.where(has, J, _PENALTY_NONE)
    within = err <= pb.x10_tol
    with np.errstate(invalid="ignore"):
        amp_pen = -np.minimum(1.0, (err - pb.x10_tol) / pb.x10_tol)
    score = np.where(has & ~within, np.minimum(np.minimum(J, 0.0), amp_pen), J)
    status = np.where(~has, 1, np.where(~exists, 2, np.where(~stable, 3,
                                                            np.where(~within, 4, 0))))
    return {"x10": x10, "x10_alt": np.broadcast_to(alt, x10.shape), "err": err,
            "exists": exists, "stable": stable, "rho": rho, "nu": nu, "score": score,
            "status": status}


def _report(pb: _Problem, xm, ev, e_values, mu_values, shape) -> RobustReport:
    """Build a RobustReport from one gain row of :func:`_plant_eval` (last plant = nominal)."""
    g = {k: np.asarray(v)[0] for k, v in ev.items()}

    def grid(a):
        return np.asarray(a[:-1]).reshape(shape)

    score = g["score"]
    iw = int(np.argmin(score))
    rho = g["rho"]
    all_orbits = bool(np.all(np.isfinite(rho)))
    ir = int(np.nanargmax(rho)) if np.any(np.isfinite(rho)) else iw
    all_e = np.append(np.repeat(e_values, len(mu_values)), pb.e)
    all_mu = np.append(np.tile(mu_values, len(e_values)), pb.mu)

    def case_of(i):
        return {"e": float(all_e[i]), "mu": float(all_mu[i])}

    return RobustReport(
        e_values=np.asarray(e_values, float), mu_values=np.asarray(mu_values, float),
        x10_nominal=pb.x10, xm=float(xm), x10_tol=pb.x10_tol,
        x10=grid(g["x10"]), x10_alt=grid(g["x10_alt"]), x10_error=grid(g["err"]),
        exists=grid(g["exists"]), stable=grid(g["stable"]), spectral_radius=grid(rho),
        viability_margin=grid(g["nu"]), objective=grid(score), status=grid(g["status"]),
        ok=bool(np.all(g["status"] == 0)), nominal_ok=bool(g["status"][-1] == 0),
        worst_objective=float(score[iw]), worst_case=case_of(iw),
        worst_spectral_radius=float(rho[ir]) if all_orbits else float("nan"),
        worst_spectral_radius_case=case_of(ir),
        worst_viability_margin=float(np.nanmin(g["nu"])) if np.any(np.isfinite(g["nu"]))
        else float("nan"),
        worst_x10_error=float(np.max(g["err"])) if all_orbits else float("nan"),
    )


def _robust_scores(pb: _Problem, kp, kv, xm, nominal_J):
    """Worst-case score over the plants for gains (G,), nominal penalty where infeasible."""
    kp = np.atleast_1d(np.asarray(kp, float))
    kv = np.atleast_1d(np.asarray(kv, float))
    xm = np.atleast_1d(np.asarray(xm, float))
    nominal_J = np.atleast_1d(np.asarray(nominal_J, float))
    out = nominal_J.copy()
    worst_rho = np.full(kp.shape, np.nan)
    all_stable = np.zeros(kp.shape, bool)
    feas = nominal_J > 0
    if np.any(feas):
        pe, pm, _ = _plants(pb.e_grid, pb.mu_grid, pb.e, pb.mu)
        idx = np.flatnonzero(feas)
        # chunks keep the (gains x plants) temporaries (DP is 16 floats a point) small
        step = max(1, 20000 // pe.size)
        for s in range(0, idx.size, step):
            sl = idx[s:s + step]
            ev = _plant_eval(pb, kp[sl], kv[sl], xm[sl], pe, pm)
            out[sl] = ev["score"].min(axis=1)
            r = ev["rho"]
            worst_rho[sl] = np.where(np.all(np.isfinite(r), axis=1), np.max(r, axis=1), np.nan)
            all_stable[sl] = np.all((ev["status"] == 0) | (ev["status"] == 4), axis=1)
    return out, worst_rho, all_stable


def _evaluate_point(pb: _Problem, kp, kv):
    """Objective at one gain pair (nominal or robust), for the optimiser."""
    r, J = _nominal(pb, kp, kv)
    J = float(J)
    if not pb.robust or J <= 0:
        return J
    s, _, _ = _robust_scores(pb, kp, kv, float(r.xm), J)
    return float(s[0])


def _seeds(obj, k, min_sep=3):
    """Up to ``k`` grid indices of separated local maxima of ``obj`` (feasible, > 0)."""
    feasible = obj > 0
    if not np.any(feasible):
        return []
    filled = np.where(np.isfinite(obj), obj, -np.inf)
    peaks = (ndimage.maximum_filter(filled, size=3, mode="nearest") == filled) & feasible
    order_p = np.flatnonzero(peaks.ravel())
    order_p = order_p[np.argsort(-filled.ravel()[order_p], kind="stable")]
    order_f = np.flatnonzero(feasible.ravel())
    order_f = order_f[np.argsort(-filled.ravel()[order_f], kind="stable")]
    chosen = []
    for flat in list(order_p) + list(order_f):
        ij = np.unravel_index(flat, obj.shape)
        if all(max(abs(ij[0] - c[0]), abs(ij[1] - c[1])) >= min_sep for c in chosen):
            chosen.append(ij)
        if len(chosen) >= k:
            break
    return chosen


def _refine(pb: _Problem, seed_kp, seed_kv, seed_J, cell, maxiter):
    u0 = pb.to_unit(seed_kp, seed_kv)
    simplex = [u0]
    for j in range(2):
        u = u0.copy()
        u[j] = u[j] + cell[j] if u[j] + cell[j] <= 1.0 else u[j] - cell[j]
        simplex.append(u)

    def fun(u):
        kp, kv = pb.from_unit(u)
        return -_evaluate_point(pb, kp, kv)

    res = optimize.minimize(fun, u0, method="Nelder-Mead", bounds=[(0.0, 1.0), (0.0, 1.0)],
                            options={"initial_simplex": np.array(simplex), "xatol": 1e-4,
                                     "fatol": 1e-7, "maxiter": maxiter,
                                     "maxfev": 2 * maxiter})
    kp, kv = pb.from_unit(res.x)
    return OptimizerRun(start_kp=float(seed_kp), start_kv=float(seed_kv),
                        start_objective=float(seed_J), kp=float(kp), kv=float(kv),
                        objective=float(-res.fun), nfev=int(res.nfev), nit=int(res.nit),
                        success=bool(res.success), message=str(res.message))


# ---------------------------------------------------------------------------------------
# Public API
# ---------------------------------------------------------------------------------------


def _problem(case, mu, e, omega, L, gamma, x10, m2, n, kp_range, kv_range, spacing,
             viability_weight, objective, e_range, mu_range, uncertainty_grid, x10_tol):
    case = Case.parse(case)
    mu = check_positive("mu", mu)
    e = check_in_range("e", e, 0.0, 1.0)
    omega = check_positive("omega", omega)
    x10 = check_positive("x10", x10)
    m2 = check_positive("m2", m2)
    n = check_odd_order(n)
    if (L is None) == (gamma is None):
        raise ValueError("give exactly one of L or gamma (L = gamma * x10)")
    L = check_positive("L", L) if L is not None else check_positive("gamma", gamma) * x10
    kp_range = _range("kp_range", kp_range)
    kv_range = _range("kv_range", kv_range)
    if spacing not in _SPACINGS:
        raise ValueError(f"spacing must be one of {_SPACINGS}, got {spacing!r}")
    w = check_finite("viability_weight", viability_weight)
    if objective not in _OBJECTIVES:
        raise ValueError(f"objective must be one of {_OBJECTIVES}, got {objective!r}")
    if w < 0 or (w == 0 and objective == "min"):
        raise ValueError(f"viability_weight must be {'> 0' if objective == 'min' else '>= 0'} "
                         f"with objective={objective!r}, got {viability_weight!r}")
    x10_tol = check_positive("x10_tol", x10_tol)
    e_grid = mu_grid = None
    if e_range is not None or mu_range is not None:
        ne, nmu = _grid_shape("uncertainty_grid", uncertainty_grid)
        if e_range is not None:
            lo, hi = _range("e_range", e_range, hi_bound=1.0, closed_lo=True, allow_equal=True)
            if not lo <= e <= hi:
                raise ValueError(f"e_range must contain the nominal e = {e:g}, got {e_range!r}")
            e_grid = np.unique(np.linspace(lo, hi, ne))
        else:
            e_grid = np.array([e])
        if mu_range is not None:
            lo, hi = _range("mu_range", mu_range, allow_equal=True)
            if not lo <= mu <= hi:
                raise ValueError(f"mu_range must contain the nominal mu = {mu:g}, "
                                 f"got {mu_range!r}")
            mu_grid = np.unique(np.linspace(lo, hi, nmu))
        else:
            mu_grid = np.array([mu])
    return _Problem(case, mu, e, L, x10, m2, omega, n, kp_range, kv_range, spacing, w,
                    objective, e_grid, mu_grid, x10_tol)


def design(case="collocated", *, mu, e, omega, L=None, gamma=None, x10=1.0, m2=1.0, n=1,
           kp_range=(0.1, 100.0), kv_range=(0.1, 100.0), grid=(48, 48), spacing="log",
           viability_weight=1.0, objective="min", e_range=None, mu_range=None,
           uncertainty_grid=(5, 5), x10_tol=0.1, validation_grid=(9, 9), n_starts=3,
           maxiter=150) -> DesignResult:
    """Design PD gains and the reference for a desired symmetric primary-mass motion.

    Parameters
    ----------
    case : {"collocated", "noncollocated"}
        Feedback of ``x2`` (collocated) or ``x1`` (non-collocated).
    mu : float
        Mass ratio ``m1/m2`` (> 0), nominal.
    e : float
        Restitution coefficient in [0, 1], nominal.
    omega : float
        Frequency of the desired motion and of the reference (rad/time, > 0).
    L, gamma : float
        Half clearance (length, > 0) or ``gamma = L / x10`` (> 0): give exactly one.
    x10 : float
        Desired primary-mass amplitude (length, > 0); default 1.
    m2 : float
        Secondary mass (> 0); default 1.
    n : int
        Odd orbit order (one impact on each wall per ``n`` reference periods); default 1.
    kp_range, kv_range : (float, float)
        The gain box, ``0 < LO < HI``; default ``(0.1, 100)`` each.
    grid : (int, int)
        Seed-grid points along ``kp`` and ``kv`` (>= 2 each); default ``(48, 48)``.
    spacing : {"log", "linear"}
        Spacing of the seed grid and the optimiser's coordinates; default ``"log"``.
    viability_weight : float
        Weight ``w`` of the viability margin in the objective (module docstring): ``> 0``
        for ``"min"``, ``>= 0`` for ``"sum"``; default 1.
    objective : {"min", "sum"}
        ``min(1 - rho, w nu)`` (default) or ``(1 - rho) + w nu``.
    e_range, mu_range : (float, float), optional
        Uncertainty boxes (must contain the nominal value; ``LO == HI`` allowed). Giving
        either makes the design robust: the worst case over the box is maximised.
    uncertainty_grid : (int, int)
        Plants along ``e`` and ``mu`` (>= 2 each; default 5 x 5, corners included; the
        nominal plant is always added).
    x10_tol : float
        Allowed relative error of the primary-mass amplitude over the box (> 0); default 0.1.
    validation_grid : (int, int) or None
        Finer grid on which the robust design is re-checked (reported, not optimised).
    n_starts : int
        Grid seeds refined by Nelder-Mead (>= 1); default 3.
    maxiter : int
        Nelder-Mead iterations per seed (>= 1).

    Returns
    -------
    DesignResult

    Raises
    ------
    ValueError
        Bad input (the message names the parameter).
    InfeasibleDesignError
        No gains in the box give an existing, stable (and, for a robust design, robust) orbit;
        carries the reason counts and the closest miss.

    Examples
    --------
    >>> d = design("collocated", mu=0.1, e=0.5, gamma=0.75, omega=5.0, grid=(24, 24))
    >>> d.orbit.stable, d.stability_margin > 0.5
    (True, True)
    >>> r = design("noncollocated", mu=0.1, e=0.5, gamma=0.75, omega=5.0, grid=(24, 24),
    ...            e_range=(0.45, 0.55), mu_range=(0.09, 0.11), uncertainty_grid=(3, 3))
    >>> r.robust.ok, sorted(r.robust.worst_case)
    (True, ['e', 'mu'])
    """
    t_start = time.perf_counter()
    pb = _problem(case, mu, e, omega, L, gamma, x10, m2, n, kp_range, kv_range, spacing,
                  viability_weight, objective, e_range, mu_range, uncertainty_grid, x10_tol)
    nkp, nkv = _grid_shape("grid", grid)
    n_starts_i = check_int("n_starts", n_starts, 1)
    maxiter_i = check_int("maxiter", maxiter, 1)
    if validation_grid is not None and pb.robust:
        validation_grid = _grid_shape("validation_grid", validation_grid)

    # global stage: the vectorised map over the gain box
    kps = _axis_values(*pb.kp_range, nkp, pb.spacing)
    kvs = _axis_values(*pb.kv_range, nkv, pb.spacing)
    r, J = _nominal(pb, kps[None, :], kvs[:, None])
    robust_feasible = worst_rho_map = robust_stable = None
    obj = J
    if pb.robust:
        KP, KV = np.meshgrid(kps, kvs)
        rs, wr, st = _robust_scores(pb, KP.ravel(), KV.ravel(), np.nan_to_num(r.xm).ravel(),
                                    J.ravel())
        obj = rs.reshape(J.shape)
        worst_rho_map = wr.reshape(J.shape)
        robust_feasible = obj > 0
        robust_stable = st.reshape(J.shape)
    dmap = DesignMap(kp=kps, kv=kvs, spacing=pb.spacing, objective=obj, nominal_objective=J,
                     exists=r.exists, stable=r.stable, reason=r.reason,
                     spectral_radius=r.spectral_radius, viability_margin=r.viability_margin,
                     xm=r.xm, phi0=r.phi0, robust_feasible=robust_feasible,
                     robust_stable=robust_stable, worst_spectral_radius=worst_rho_map)

    # local stage: bounded Nelder-Mead from the best separated seeds
    seeds = _seeds(obj, n_starts_i)
    cell = np.array([1.0 / (nkp - 1), 1.0 / (nkv - 1)])
    runs = [_refine(pb, kps[j], kvs[i], obj[i, j], cell, maxiter_i) for i, j in seeds]
    runs.sort(key=lambda run: -run.objective)
    candidates = [(run.objective, run.kp, run.kv) for run in runs]
    candidates += [(float(obj[i, j]), float(kps[j]), float(kvs[i])) for i, j in seeds]
    candidates.sort(key=lambda c: -c[0])
    for J_best, kp_best, kv_best in candidates:
        if J_best <= 0:
            break
        res = _finish(pb, kp_best, kv_best, J_best, dmap, runs, validation_grid, t_start)
        if res is not None:
            return res
    raise _infeasible(pb, dmap, r, J, obj)


def _finish(pb, kp, kv, J, dmap, runs, validation_grid, t_start):
    pair = ImpactPair(pb.mu, pb.e, pb.L, pb.m2)
    gains = PDGains(kp, kv)
    orb = symmetric_orbit(pair, gains, pb.omega, x10=pb.x10, n=pb.n, case=pb.case)
    if not (orb.exists and orb.stable):
        return None  # the scalar re-check disagrees with the search: try the next candidate
    robust = validation = None
    objective_value = float(design_objective(True, True, orb.spectral_radius,
                                             orb.viability_margin, viability_weight=pb.weight,
                                             objective=pb.kind))
    if pb.robust:
        robust = _robustness(pb, kp, kv, orb.xm, pb.e_grid, pb.mu_grid)
        if not robust.ok:
            return None
        objective_value = robust.worst_objective
        if validation_grid is not None:
            ve = np.unique(np.linspace(pb.e_grid[0], pb.e_grid[-1], validation_grid[0]))
            vm = np.unique(np.linspace(pb.mu_grid[0], pb.mu_grid[-1], validation_grid[1]))
            validation = _robustness(pb, kp, kv, orb.xm, ve, vm)
    spec = {"mu": pb.mu, "e": pb.e, "L": pb.L, "gamma": pb.L / pb.x10, "x10": pb.x10,
            "m2": pb.m2, "omega": pb.omega, "n": pb.n, "kp_range": list(pb.kp_range),
            "kv_range": list(pb.kv_range), "spacing": pb.spacing}
    if pb.robust:
        spec.update({"e_range": [float(pb.e_grid[0]), float(pb.e_grid[-1])],
                     "mu_range": [float(pb.mu_grid[0]), float(pb.mu_grid[-1])],
                     "uncertainty_grid": [len(pb.e_grid), len(pb.mu_grid)],
                     "x10_tol": pb.x10_tol})
    return DesignResult(
        case=pb.case, gains=gains, xm=float(orb.xm), phi0=float(orb.phi0),
        spectral_radius=float(orb.spectral_radius), stability_margin=1 - orb.spectral_radius,
        viability_margin=float(orb.viability_margin), objective=objective_value,
        objective_kind=pb.kind, viability_weight=pb.weight, orbit=orb, spec=spec,
        design_map=dmap, optimizer=runs, robust=robust, validation=validation,
        elapsed=time.perf_counter() - t_start)


def _robustness(pb, kp, kv, xm, e_values, mu_values) -> RobustReport:
    pe, pm, shape = _plants(e_values, mu_values, pb.e, pb.mu)
    ev = _plant_eval(pb, [kp], [kv], [xm], pe, pm)
    return _report(pb, xm, ev, e_values, mu_values, shape)


def _infeasible(pb, dmap, r, J, obj):
    counts = {}
    for code, cnt in zip(*np.unique(r.reason, return_counts=True)):
        counts[REASONS[int(code)]] = int(cnt)
    n_unstable = int(np.sum(r.exists & ~r.stable))
    if n_unstable:
        counts["exists but unstable"] = n_unstable
        counts[REASONS[0]] = counts.get(REASONS[0], 0) - n_unstable
        if counts[REASONS[0]] == 0:
            del counts[REASONS[0]]
    box = (f"kp in [{pb.kp_range[0]:g}, {pb.kp_range[1]:g}], "
           f"kv in [{pb.kv_range[0]:g}, {pb.kv_range[1]:g}]")
    nominal_feasible = bool(np.any(J > 0))
    if pb.robust and nominal_feasible:
        # the closest miss of a robust design: the best worst case, and where it fails
        i, j = np.unravel_index(int(np.argmax(obj)), obj.shape)
        kp, kv = float(dmap.kp[j]), float(dmap.kv[i])
        rep = _robustness(pb, kp, kv, float(r.xm[i, j]), pb.e_grid, pb.mu_grid)
        st = {}
        for code in rep.status.ravel():
            key = "robust: " + PLANT_STATUS[int(code)]
            st[key] = st.get(key, 0) + 1
        counts.update(st)
        closest = {"kp": kp, "kv": kv, "xm": float(r.xm[i, j]),
                   "worst_objective": rep.worst_objective,
                   "worst_case": f"e = {rep.worst_case['e']:g}, mu = {rep.worst_case['mu']:g}",
                   "worst_x10_error": rep.worst_x10_error,
                   "worst_spectral_radius": rep.worst_spectral_radius}
        why = (f"no gains in the box ({box}) keep the symmetric orbit existing, stable and "
               f"within x10_tol = {pb.x10_tol:g} over e in [{pb.e_grid[0]:g}, "
               f"{pb.e_grid[-1]:g}], mu in [{pb.mu_grid[0]:g}, {pb.mu_grid[-1]:g}] "
               f"({int(np.sum(J > 0))} nominally feasible grid points)")
    else:
        closest = None
        if np.any(r.exists):
            rho = np.where(r.exists, r.spectral_radius, np.inf)
            i, j = np.unravel_index(int(np.argmin(rho)), rho.shape)
            closest = {"kp": float(dmap.kp[j]), "kv": float(dmap.kv[i]), "xm": float(r.xm[i, j]),
                       "spectral_radius": float(rho[i, j]),
                       "viability_margin": float(r.viability_margin[i, j])}
        why = f"no existing, stable symmetric orbit for gains in the box ({box})"
    return InfeasibleDesignError(why, reason_counts=counts, closest=closest, design_map=dmap)


def robustness(case, kp, kv, xm, *, mu, e, omega, L=None, gamma=None, x10=1.0, m2=1.0, n=1,
               e_range=None, mu_range=None, uncertainty_grid=(5, 5), x10_tol=0.1,
               viability_weight=1.0, objective="min") -> RobustReport:
    """Check fixed gains and reference amplitude over an uncertainty box of ``(e, mu)``.

    Parameters
    ----------
    case : {"collocated", "noncollocated"}
    kp, kv : float
        The gains (> 0).
    xm : float
        The fixed reference amplitude (length, > 0), e.g. ``DesignResult.xm``.
    mu, e, omega, L | gamma, x10, m2, n
        Nominal plant and desired motion, as in :func:`design`.
    e_range, mu_range : (float, float), optional
        The box (at least one); must contain the nominal value.
    uncertainty_grid : (int, int)
        Plants along ``e`` and ``mu`` (corners included).
    x10_tol, viability_weight, objective
        As in :func:`design`.

    Returns
    -------
    RobustReport

    Examples
    --------
    >>> rep = robustness("collocated", 10, 20, 0.39858, mu=0.1, e=0.5, omega=5.0,
    ...                  gamma=0.75, e_range=(0.3, 0.7), uncertainty_grid=(3, 2))
    >>> rep.ok, rep.worst_case["e"]
    (False, 0.3)
    """
    if e_range is None and mu_range is None:
        raise ValueError("give e_range and/or mu_range")
    pb = _problem(case, mu, e, omega, L, gamma, x10, m2, n, (0.1, 1.0), (0.1, 1.0), "log",
                  viability_weight, objective, e_range, mu_range, uncertainty_grid, x10_tol)
    kp = check_positive("kp", kp)
    kv = check_positive("kv", kv)
    xm = check_positive("xm", xm)
    return _robustness(pb, kp, kv, xm, pb.e_grid, pb.mu_grid)


# ---------------------------------------------------------------------------------------
# Collocated vs non-collocated (the paper's closing remark, quantified)
# ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ComparisonRow:
    """One feedback case of :func:`robustness_comparison`.

    Attributes
    ----------
    case : str
    nominal_fraction : float
        Share of the (log-spaced) gain grid where the nominal orbit exists and is stable.
    robust_fraction : float
        Share where it is robust over the whole uncertainty grid (existing, stable, ``x10``
        within tolerance).
    robust_stable_fraction : float
        Share where the shifted orbit exists and is stable over the whole grid, whatever its
        amplitude (robustness of stability alone).
    nominal : DesignResult or None
        Best nominal design (``None`` if infeasible).
    nominal_gains_over_box : RobustReport or None
        The nominal design's gains and ``xm`` checked over the box (what the paper warns
        about: gains tuned for the nominal plant).
    robust : DesignResult or None
        Best robust design (``None`` if infeasible).
    robust_failure : str or None
        Why the robust design failed.
    """

    __repr__ = compact_repr

    case: str
    nominal_fraction: float
    robust_fraction: float
    robust_stable_fraction: float
    nominal: DesignResult | None
    nominal_gains_over_box: RobustReport | None
    robust: DesignResult | None
    robust_failure: str | None

    def to_dict(self) -> dict:
        """Flat JSON-ready summary."""
        d = {"case": self.case, "nominal_fraction": self.nominal_fraction,
             "robust_fraction": self.robust_fraction,
             "robust_stable_fraction": self.robust_stable_fraction}
        if self.nominal is not None:
            d.update({"nominal_kp": self.nominal.kp, "nominal_kv": self.nominal.kv,
                      "nominal_spectral_radius": self.nominal.spectral_radius})
        if self.nominal_gains_over_box is not None:
            rep = self.nominal_gains_over_box
            d.update({"nominal_gains_robust": rep.ok,
                      "nominal_gains_failing_plants": int(np.sum(rep.status != 0)),
                      "nominal_gains_worst_spectral_radius": _f(rep.worst_spectral_radius),
                      "nominal_gains_worst_x10_error": _f(rep.worst_x10_error)})
        if self.robust is not None:
            d.update({"robust_kp": self.robust.kp, "robust_kv": self.robust.kv,
                      "robust_xm": self.robust.xm,
                      "robust_worst_spectral_radius": self.robust.robust.worst_spectral_radius,
                      "robust_worst_case": self.robust.robust.worst_case,
                      "robust_worst_x10_error": self.robust.robust.worst_x10_error})
        d["robust_failure"] = self.robust_failure
        return d


@dataclass(frozen=True)
class RobustnessComparison:
    """Collocated against non-collocated robustness (rows per case) with the settings used.

    Attributes
    ----------
    rows : list of ComparisonRow
    settings : dict
        Nominal plant, boxes, tolerance and gain box.
    """

    __repr__ = compact_repr

    rows: list
    settings: dict

    def to_dict(self) -> dict:
        """JSON-ready form."""
        return {"settings": self.settings, "rows": [r.to_dict() for r in self.rows]}

    def to_text(self) -> str:
        """A small plain-text table."""
        def num(x, fmt=".3f"):
            return "-" if x is None or not np.isfinite(x) else format(x, fmt)

        s = self.settings
        head = (f"mu = {s['mu']:g}, gamma = {s['gamma']:g}, n = {s['n']}, "
                f"omega = {s['omega']:g}, e = {s['e']:g}; box e in {s['e_range']}, "
                f"mu in {s['mu_range']}, x10 tolerance {100 * s['x10_tol']:g} %; gains in "
                f"{s['kp_range']} x {s['kv_range']} (log grid)")
        cols = (f"{'case':<14}{'stable %':>9}{'rob.stab %':>11}{'robust %':>9}  "
                f"{'nominal (kp, kv) rho':<26}{'its worst rho / x10 err':<26}"
                f"{'robust (kp, kv) worst rho [e, mu]':<38}worst x10 err")
        lines = [head, cols]
        for r in self.rows:
            nom = "-" if r.nominal is None else (
                f"({r.nominal.kp:.3g}, {r.nominal.kv:.3g}) {num(r.nominal.spectral_radius)}")
            if r.nominal_gains_over_box is None:
                nb = "-"
            else:
                rep = r.nominal_gains_over_box
                nb = (f"{num(rep.worst_spectral_radius)} / {num(rep.worst_x10_error)}"
                      f"{'' if rep.ok else ' FAIL'}")
            if r.robust is None:
                rob, err = "infeasible", "-"
            else:
                rr = r.robust.robust
                rob = (f"({r.robust.kp:.3g}, {r.robust.kv:.3g}) {num(rr.worst_spectral_radius)} "
                       f"[{rr.worst_spectral_radius_case['e']:g}, "
                       f"{rr.worst_spectral_radius_case['mu']:g}]")
                err = num(rr.worst_x10_error)
            lines.append(f"{r.case:<14}{100 * r.nominal_fraction:>9.1f}"
                         f"{100 * r.robust_stable_fraction:>11.1f}"
                         f"{100 * r.robust_fraction:>9.1f}  {nom:<26}{nb:<26}{rob:<38}{err}")
        lines.append("stable %: nominal orbit exists and is stable; rob.stab %: the shifted orbit "
                     "exists and is stable over the whole box (any amplitude); robust %: also "
                     "with x10 within tolerance (shares of the log-spaced gain grid)")
        return "\n".join(lines)


def robustness_comparison(*, mu=0.1, gamma=0.75, x10=1.0, m2=1.0, n=1, omega=5.0, e=0.5,
                          e_range=(0.3, 0.7), mu_range=(0.08, 0.12), x10_tol=0.1,
                          kp_range=(0.1, 100.0), kv_range=(0.1, 100.0), grid=(48, 48),
                          uncertainty_grid=(5, 5), cases=("collocated", "noncollocated"),
                          **design_kwargs) -> RobustnessComparison:
    """Quantify the paper's closing remark: robustness of collocated vs non-collocated PD.

    For each case: the share of the gain box with an existing stable nominal orbit, the share
    that stays so over the uncertainty box (amplitude within ``x10_tol``), the best nominal
    design and how its gains fare over the box, and the best robust design with its worst
    case. Defaults are the paper's parameters with a +-40 % box on ``e`` and +-20 % on ``mu``.

    Returns
    -------
    RobustnessComparison
        ``.to_text()`` prints the table.

    Examples
    --------
    >>> cmp = robustness_comparison(grid=(16, 16), uncertainty_grid=(3, 3))
    >>> [r.case for r in cmp.rows]
    ['collocated', 'noncollocated']
    """
    common = dict(mu=mu, e=e, omega=omega, gamma=gamma, x10=x10, m2=m2, n=n, kp_range=kp_range,
                  kv_range=kv_range, grid=grid, **design_kwargs)
    rows = []
    for case in cases:
        case = Case.parse(case).value
        try:
            nom = design(case, **common)
        except InfeasibleDesignError as exc:
            nom = None
            nom_map = exc.design_map
        else:
            nom_map = nom.design_map
        nom_box = None
        if nom is not None:
            nom_box = robustness(case, nom.kp, nom.kv, nom.xm, mu=mu, e=e, omega=omega,
                                 gamma=gamma, x10=x10, m2=m2, n=n, e_range=e_range,
                                 mu_range=mu_range, uncertainty_grid=uncertainty_grid,
                                 x10_tol=x10_tol)
        try:
            rob = design(case, e_range=e_range, mu_range=mu_range,
                         uncertainty_grid=uncertainty_grid, x10_tol=x10_tol, **common)
            failure = None
            rmap = rob.design_map
        except InfeasibleDesignError as exc:
            rob, failure, rmap = None, str(exc), exc.design_map
        rows.append(ComparisonRow(case=case, nominal_fraction=nom_map.feasible_fraction(),
                                  robust_fraction=rmap.feasible_fraction("robust"),
                                  robust_stable_fraction=rmap.feasible_fraction("robust_stable"),
                                  nominal=nom,
                                  nominal_gains_over_box=nom_box, robust=rob,
                                  robust_failure=failure))
    settings = {"mu": mu, "gamma": gamma, "x10": x10, "m2": m2, "n": n, "omega": omega, "e": e,
                "e_range": list(e_range), "mu_range": list(mu_range), "x10_tol": x10_tol,
                "kp_range": list(kp_range), "kv_range": list(kv_range), "grid": list(grid),
                "uncertainty_grid": list(uncertainty_grid)}
    return RobustnessComparison(rows, settings)
