"""The paper's five conclusions (section 5) and its two remarks on ``mu`` as computed tests.

Each ``check_*`` function takes measured numbers and returns a dict with a ``"verdict"`` (one
of :data:`~hybridpd.reproduce.rules.VERDICTS`, by the rules of
:mod:`hybridpd.reproduce.rules`) and the numbers it rests on. Region statements (1-3 and the
remarks) are decided by **certified shares** ``(lo, hi)`` of the scaled gain box
(:mod:`hybridpd.reproduce.certified`) where the orbit exists and is stable (the paper's shaded
regions); existence alone is evidence. The thresholds that turn a qualitative statement into
a test are module constants, so that a reader can see and change them.
"""
from __future__ import annotations

from hybridpd.reproduce import rules as R
from hybridpd.reproduce.rules import AGREES, CONTRADICTED, SPLIT, UNRESOLVED

__all__ = ["AGREES", "CONTRADICTED", "CRITERIA_5", "LARGE", "MUCH_SMALLER", "REMARKS", "SHORT",
           "SIMILAR", "SPLIT", "STATEMENTS", "UNRESOLVED", "check_1", "check_2", "check_3",
           "check_4", "check_4_necessary", "check_5", "check_mu_existence", "check_mu_small"]

STATEMENTS = {
    1: "The existence and stability regions are much smaller for the non-collocated case "
       "than for the collocated one.",
    2: "For the non-collocated case the region of existence and stability decreases with "
       "increasing e; it is the inverse for the collocated case.",
    3: "The range of admissible gains is large for the collocated case.",
    4: "The basins of attraction have a similar size in both cases.",
    5: "Uncertainties on the physical parameters will be an obstacle to the non-collocated "
       "control, due to the smallness of its admissible gain regions."}
#: The paper's remarks on ``mu`` (section 5).
REMARKS = {"mu-existence": "The existence region tends to decrease with increasing mu.",
           "mu-small": "As mu tends to zero control becomes easier."}
#: The statements in a few words, for the summary's table.
SHORT = {1: "non-collocated regions much smaller than collocated ones",
         2: "as e grows the non-collocated region shrinks, the collocated one grows",
         3: "collocated admissible gain range large",
         4: "basins of similar size in both cases",
         5: "uncertainty an obstacle for non-collocated PD",
         "mu-existence": "existence region tends to shrink as mu grows",
         "mu-small": "control easier as mu -> 0"}

#: "Much smaller": non-collocated / collocated share of the same gain box below this, every e.
MUCH_SMALLER = 0.2
#: "Large": the collocated region covers at least this share of the gain box, every e.
LARGE = 0.3
#: "Similar size": basin-measure ratio non-collocated / collocated inside this range, every e.
SIMILAR = (0.5, 2.0)
#: The two readings of "an obstacle" (conclusion 5): what must survive the uncertainty.
CRITERIA_5 = ("robust stability", "robust stability and amplitude within 10 %")


def _ivs(x):
    return [list(map(float, iv)) for iv in x]


def check_1(col, non, e, *, col_exists=None, non_exists=None) -> dict:
    """Conclusion 1 from certified shares per ``e`` (``[(lo, hi)]``) of the region where the
    orbit exists and is stable: non-collocated / collocated below :data:`MUCH_SMALLER` for
    every ``e`` (:func:`~hybridpd.reproduce.rules.ratio_below`). The same test on existence
    alone (``*_exists``) is evidence."""
    r = R.ratio_below(non, col, MUCH_SMALLER)
    out = {"verdict": r["verdict"], "per_e": r["per_item"], "ratio": r["ratio"],
           "threshold": MUCH_SMALLER, "e": [float(v) for v in e],
           "collocated": _ivs(col), "noncollocated": _ivs(non)}
    if col_exists is not None and non_exists is not None:
        x = R.ratio_below(non_exists, col_exists, MUCH_SMALLER)
        out["existence_alone"] = {"verdict": x["verdict"], "per_e": x["per_item"],
                                  "ratio": x["ratio"], "collocated": _ivs(col_exists),
                                  "noncollocated": _ivs(non_exists)}
    return out


def check_2(col, non, e) -> dict:
    """Conclusion 2 by the trend rule (:func:`~hybridpd.reproduce.rules.trend`) along ``e``:
    the non-collocated share falls from the smallest to the largest ``e`` and the
    collocated one rises."""
    tn = R.trend(e, non, direction="decreasing")
    tc = R.trend(e, col, direction="increasing")
    return {"verdict": R.all_of([tn["verdict"], tc["verdict"]]), "e": [float(v) for v in e],
            "noncollocated": _ivs(non), "collocated": _ivs(col), "noncollocated_trend": tn,
            "collocated_trend": tc}


def check_3(col, e) -> dict:
    """Conclusion 3: the collocated share is at least :data:`LARGE` for every ``e``
    (:func:`~hybridpd.reproduce.rules.at_least`)."""
    r = R.at_least(col, LARGE)
    return {"verdict": r["verdict"], "per_e": r["per_item"], "threshold": LARGE,
            "e": [float(v) for v in e], "collocated": _ivs(col)}


def check_4(col: list, non: list, touches_edge=None, *, window=None, grid=None,
            distance=None) -> dict:
    """Conclusion 4 from per-``e`` basin areas in one window shared by every panel and both
    cases (None: no stable orbit), by :func:`~hybridpd.reproduce.rules.basin_comparison`.

    ``touches_edge`` (``{"collocated": [bool], "noncollocated": [bool]}``, default: none
    touches), ``window``, ``grid`` and ``distance`` (the window-free measure, see
    :func:`hybridpd.reproduce.basins.boundary_distance`) are recorded as evidence.
    """
    if touches_edge is None:
        touches_edge = {"collocated": [False] * len(col), "noncollocated": [False] * len(non)}
    cmp = R.basin_comparison(col, non, touches_edge, SIMILAR)
    ratios = []
    for c, n in zip(col, non):
        c, n = (0.0 if c is None else float(c)), (0.0 if n is None else float(n))
        ratios.append(n / c if c > 0 and n > 0 else None)
    return {"verdict": cmp["verdict"], "collocated": col, "noncollocated": non,
            "ratio": ratios, "ratio_bounds": cmp["ratio_bounds"], "per_e": cmp["per_e"],
            "touches_edge": touches_edge, "window": None if window is None else list(window),
            "grid": None if grid is None else list(grid), "distance": distance}


def check_4_necessary(col_stable: list, non_stable: list) -> str:
    """Conclusion 4 without basins: a missing or unstable orbit on one side only has an
    empty basin while the other side's is not (contradicted); otherwise the orbits alone
    cannot decide (unresolved)."""
    if any(bool(c) != bool(n) for c, n in zip(col_stable, non_stable)):
        return CONTRADICTED
    return UNRESOLVED


def _fractions(comparison) -> dict:
    rows = {r.case: r for r in comparison.rows}
    c, n = rows["collocated"], rows["noncollocated"]
    return {CRITERIA_5[0]: {"collocated": c.robust_stable_fraction,
                            "noncollocated": n.robust_stable_fraction},
            CRITERIA_5[1]: {"collocated": c.robust_fraction,
                            "noncollocated": n.robust_fraction},
            "nominal": {"collocated": c.nominal_fraction, "noncollocated": n.nominal_fraction}}


def check_5(comparison, check=None) -> dict:
    """Conclusion 5 from a :class:`~hybridpd.pair.design.RobustnessComparison` under
    both criteria of :data:`CRITERIA_5`: the share of the gain grid that survives the
    uncertainty box is smaller for the non-collocated case.

    With ``check`` (the same comparison on another grid) each criterion's verdict is
    :func:`~hybridpd.reproduce.rules.resolution` of the two; the verdict is
    :func:`~hybridpd.reproduce.rules.criteria` of the criteria (``"split"`` when they
    disagree).
    """
    f = _fractions(comparison)
    g = _fractions(check) if check is not None else None
    by = {}
    for crit in CRITERIA_5:
        v = R.AGREES if f[crit]["noncollocated"] < f[crit]["collocated"] else R.CONTRADICTED
        if g is not None:
            v2 = R.AGREES if g[crit]["noncollocated"] < g[crit]["collocated"] else \
                R.CONTRADICTED
            v = R.resolution(v, v2)
        by[crit] = v
    s = comparison.settings
    return {"verdict": R.criteria(by), "by_criterion": by, "fractions": f,
            "check_fractions": g, "grid": list(s["grid"]),
            "uncertainty_grid": list(s["uncertainty_grid"]),
            "check_grid": None if check is None else list(check.settings["grid"]),
            "box": {"e": list(s["e_range"]), "mu": list(s["mu_range"])},
            "gains": {"kp": list(s["kp_range"]), "kv": list(s["kv_range"])},
            "x10_tol": s["x10_tol"], "e": s["e"]}


def _per_case(trends) -> dict:
    per = {key: t["verdict"] for key, t in trends.items()}
    return {"verdict": R.all_of(per.values()), "per_case": per, "trends": trends}


def check_mu_existence(mu_ends, first: dict, last: dict, e, inside=None) -> dict:
    """"The existence region tends to decrease with increasing mu": per case and ``e`` the
    certified existence share at the end of the studied range of ``mu`` is below the share
    at its start (:func:`~hybridpd.reproduce.rules.trend`), for every case and ``e``; the
    certified shares ``inside`` the range (``{(case, e): [(mu, (lo, hi)), ...]}``, e.g. where
    a sampled share rises most) enter the trend's series, so the largest proved move the
    other way is reported (it does not decide). ``first``, ``last``: ``{case: [(lo, hi) per
    e]}``."""
    out, series = {}, {}
    for case in first:
        for k, ev in enumerate(e):
            pts = [(float(mu_ends[0]), first[case][k])]
            pts += [(float(m), iv) for m, iv in (inside or {}).get((case, ev), ())
                    if mu_ends[0] < m < mu_ends[1]]
            pts += [(float(mu_ends[1]), last[case][k])]
            pts.sort(key=lambda q: q[0])
            key = f"{case} e={ev:g}"
            out[key] = R.trend([m for m, _ in pts], [iv for _, iv in pts],
                               direction="decreasing")
            series[key] = [[m, list(map(float, iv))] for m, iv in pts]
    return {**_per_case(out), "mu": [float(v) for v in mu_ends], "e": [float(v) for v in e],
            "first": {c: _ivs(v) for c, v in first.items()},
            "last": {c: _ivs(v) for c, v in last.items()}, "series": series}


def check_mu_small(mu_points, limit: dict, paper: dict, e) -> dict:
    """"As mu tends to zero control becomes easier": per case and ``e`` the certified share
    where the orbit exists and is stable is larger at the limit point ``mu_points[0]``
    (1e-4) than at the paper's ``mu_points[1]`` (0.1), for every case and ``e``.
    ``limit``, ``paper``: ``{case: [(lo, hi) per e]}``."""
    out = {}
    for case in limit:
        for k, ev in enumerate(e):
            out[f"{case} e={ev:g}"] = R.trend(mu_points, [limit[case][k], paper[case][k]],
                                              direction="decreasing")
    return {**_per_case(out), "mu": [float(v) for v in mu_points], "e": [float(v) for v in e],
            "limit": {c: _ivs(v) for c, v in limit.items()},
            "paper": {c: _ivs(v) for c, v in paper.items()}}
