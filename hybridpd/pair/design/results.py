"""Result objects of the design: the searched map, optimiser runs, robust reports."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.model import Case, PDGains
from hybridpd.pair.design.objective import PLANT_STATUS, _f, _nested
from hybridpd.pair.orbits import SymmetricOrbitResult


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
        Codes of :data:`hybridpd.pair.orbits.REASONS`.
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
        return [(float(self.e_values[i]), float(self.mu_values[j]),
                 PLANT_STATUS[int(self.status[i, j])])
                for i, j in zip(*np.nonzero(self.status != 0))]

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
            "status_codes": {str(k): v for k, v in PLANT_STATUS.items()}}


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
        Distance to grazing (see :mod:`hybridpd.pair.orbits`).
    objective : float
        The maximised value: nominal ``J`` or, for a robust design, the worst case over the
        uncertainty grid.
    objective_kind : str
        ``"min"`` or ``"sum"``.
    viability_weight : float
    orbit : SymmetricOrbitResult
        The nominal orbit, recomputed by :func:`hybridpd.pair.orbits.symmetric_orbit`.
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
            "robust": self.robust is not None}
        d.update({k: v for k, v in self.spec.items()})
        if self.robust is not None:
            r = self.robust
            d.update({
                "worst_spectral_radius": _f(r.worst_spectral_radius),
                "worst_case": dict(r.worst_case),
                "worst_objective": _f(r.worst_objective),
                "worst_viability_margin": _f(r.worst_viability_margin),
                "worst_x10_error": _f(r.worst_x10_error),
                "worst_spectral_radius_case": dict(r.worst_spectral_radius_case)})
            if self.validation is not None:
                v = self.validation
                d["validation"] = {
                    "grid": [len(v.e_values), len(v.mu_values)], "ok": bool(v.ok),
                    "worst_spectral_radius": _f(v.worst_spectral_radius),
                    "worst_case": dict(v.worst_case), "worst_objective": _f(v.worst_objective),
                    "worst_x10_error": _f(v.worst_x10_error)}
        d["elapsed"] = float(self.elapsed)
        return d

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
