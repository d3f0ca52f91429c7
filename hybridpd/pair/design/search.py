"""The design search: global map, separated seeds, bounded Nelder-Mead, robust scores."""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from scipy import ndimage, optimize

from hybridpd.model import (
    Case,
    ImpactPair,
    PDGains,
    check_finite,
    check_in_range,
    check_int,
    check_odd_order,
    check_positive,
)
from hybridpd.pair.design.objective import (
    _OBJECTIVES,
    _PENALTY_NONE,
    _SPACINGS,
    PLANT_STATUS,
    design_objective,
    shifted_amplitude,
)
from hybridpd.pair.design.results import (
    DesignMap,
    DesignResult,
    InfeasibleDesignError,
    OptimizerRun,
    RobustReport,
)
from hybridpd.pair.orbits import REASONS, symmetric_orbit, symmetric_orbits


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
        worst_x10_error=float(np.max(g["err"])) if all_orbits else float("nan"))


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
        res = _finish(pb, kp_best, kv_best, dmap, runs, validation_grid, t_start)
        if res is not None:
            return res
    raise _infeasible(pb, dmap, r, J, obj)


def _finish(pb, kp, kv, dmap, runs, validation_grid, t_start):
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
    counts = {REASONS[int(code)]: int(cnt)
              for code, cnt in zip(*np.unique(r.reason, return_counts=True))}
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
