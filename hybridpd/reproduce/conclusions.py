"""The paper's five conclusions (section 5) as computed tests.

Each ``check_*`` function takes computed numbers and returns a dict with a ``"verdict"`` (one
of :data:`~hybridpd.reproduce.rules.VERDICTS`, by the rules of
:mod:`hybridpd.reproduce.rules`) and the numbers it rests on, every share with its cell count
and grid. The thresholds that turn a qualitative statement into a test are module constants,
so that a reader can see and change them. Region statements are tested on three quantities:
existence alone, stability alone (of the orbit candidate, viability ignored) and both (the
paper's shaded regions); the verdict of a conclusion is that of "both", the others are
evidence.
"""
from __future__ import annotations

import numpy as np

from hybridpd.reproduce import rules as R
from hybridpd.reproduce.rules import AGREES, CONTRADICTED, DEPENDS, UNRESOLVED, combine

__all__ = ["LARGE", "MUCH_SMALLER", "QUANTITIES", "SIMILAR", "STATEMENTS", "check_1",
           "check_2", "check_3", "check_4", "check_4_necessary", "check_5", "combine"]

STATEMENTS = {
    1: "The existence and stability regions are much smaller for the non-collocated case "
       "than for the collocated one.",
    2: "For the non-collocated case the region of existence and stability decreases with "
       "increasing e; it is the inverse for the collocated case.",
    3: "The range of admissible gains is large for the collocated case.",
    4: "The basins of attraction have a similar size in both cases.",
    5: "Uncertainties on the physical parameters will be an obstacle to the non-collocated "
       "control, due to the smallness of its admissible gain regions."}

#: "Much smaller": non-collocated / collocated share of the same gain box below this, every e.
MUCH_SMALLER = 0.2
#: "Large": the collocated region covers at least this share of the gain box, every e.
LARGE = 0.3
#: "Similar size": basin-measure ratio non-collocated / collocated inside this range, every e.
SIMILAR = (0.5, 2.0)
#: The region quantities of conclusions 1-3.
QUANTITIES = ("exists", "stability", "both")

__all__ += ["AGREES", "CONTRADICTED", "DEPENDS", "UNRESOLVED"]


def _v(ok) -> str:
    return AGREES if ok else CONTRADICTED


def _shares(a, grid):
    return [R.share(x, grid) for x in np.asarray(a, float)]


def check_1(col: dict, non: dict, grid) -> dict:
    """Conclusion 1 from box shares ``{quantity: (len(e),)}`` of both cases on one ``grid``
    ``(nx, ny)``: the ratio non-collocated / collocated is below :data:`MUCH_SMALLER` for
    every ``e``."""
    out = {}
    for q in QUANTITIES:
        c, n = np.asarray(col[q], float), np.asarray(non[q], float)
        with np.errstate(all="ignore"):
            ratio = np.where(c > 0, n / c, np.where(n > 0, np.inf, np.nan))
        ok = bool(np.all(np.isfinite(ratio) & (ratio < MUCH_SMALLER)))
        out[q] = {"collocated": _shares(c, grid), "noncollocated": _shares(n, grid),
                  "ratio": [None if not np.isfinite(r) else float(r) for r in ratio],
                  "verdict": _v(ok)}
    return {"verdict": out["both"]["verdict"], "by_quantity": out, "grid": list(grid)}


def check_2(col: dict, non: dict, grid, e) -> dict:
    """Conclusion 2 by the trend rule (:func:`~hybridpd.reproduce.rules.trend`) along ``e``:
    the non-collocated share does not increase with ``e`` and the collocated one does not
    decrease, each within two cells of ``grid``."""
    cells = int(grid[0]) * int(grid[1])
    out = {}
    for q in QUANTITIES:
        tn = R.trend(e, non[q], cells, direction="decreasing")
        tc = R.trend(e, col[q], cells, direction="increasing")
        out[q] = {"noncollocated": _shares(non[q], grid), "collocated": _shares(col[q], grid),
                  "noncollocated_trend": tn, "collocated_trend": tc,
                  "verdict": _v(tn["verdict"] == AGREES and tc["verdict"] == AGREES)}
    return {"verdict": out["both"]["verdict"], "by_quantity": out, "grid": list(grid)}


def check_3(col: dict, grid) -> dict:
    """Conclusion 3: the collocated shares are at least :data:`LARGE` for every ``e``."""
    out = {q: {"collocated": _shares(col[q], grid),
               "verdict": _v(bool(np.min(col[q]) >= LARGE))} for q in QUANTITIES}
    return {"verdict": out["both"]["verdict"], "by_quantity": out, "grid": list(grid)}


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


def check_5(comparison) -> dict:
    """Conclusion 5 from a :class:`~hybridpd.pair.design.RobustnessComparison`: the share
    of the gain box that stays existing and stable over the uncertainty box is smaller for the
    non-collocated case (the amplitude-constrained share is evidence)."""
    rows = {r.case: r for r in comparison.rows}
    c, n = rows["collocated"], rows["noncollocated"]
    ok = n.robust_stable_fraction < c.robust_stable_fraction
    return {"verdict": _v(ok),
            "robust_stable_fraction": {"collocated": c.robust_stable_fraction,
                                       "noncollocated": n.robust_stable_fraction},
            "robust_fraction_with_amplitude": {"collocated": c.robust_fraction,
                                               "noncollocated": n.robust_fraction},
            "nominal_fraction": {"collocated": c.nominal_fraction,
                                 "noncollocated": n.nominal_fraction},
            "amplitude_verdict": _v(n.robust_fraction < c.robust_fraction)}
