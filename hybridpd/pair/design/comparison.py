"""Collocated against non-collocated robustness: the comparison behind conclusion 5."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.model import Case
from hybridpd.pair.design.objective import _f
from hybridpd.pair.design.results import DesignResult, InfeasibleDesignError, RobustReport
from hybridpd.pair.design.search import design, robustness


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
