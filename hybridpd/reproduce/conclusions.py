"""The paper's five conclusions (section 5) as computed tests.

Each ``check_*`` function takes computed numbers and returns a dict with a ``"verdict"``
(``"agrees"`` or ``"contradicted"``) and the numbers it rests on. The thresholds that turn a
qualitative statement into a test are module constants, so that a reader can see and change
them. Region statements are tested on three quantities: existence alone, stability alone (of
the orbit candidate, viability ignored) and both (the paper's shaded regions); the verdict of
a conclusion is that of "both", the others are evidence.
"""
from __future__ import annotations

import numpy as np

__all__ = ["LARGE", "MUCH_SMALLER", "QUANTITIES", "SATURATED", "SIMILAR", "STATEMENTS",
           "check_1", "check_2", "check_3", "check_4", "check_5", "combine"]

STATEMENTS = {
    1: "The existence and stability regions are much smaller for the non-collocated case "
       "than for the collocated one.",
    2: "For the non-collocated case the region of existence and stability decreases with "
       "increasing e; it is the inverse for the collocated case.",
    3: "The range of admissible gains is large for the collocated case.",
    4: "The basins of attraction have a similar size in both cases.",
    5: "Uncertainties on the physical parameters will be an obstacle to the non-collocated "
       "control, due to the smallness of its admissible gain regions.",
}

#: "Much smaller": non-collocated / collocated share of the same gain box below this, every e.
MUCH_SMALLER = 0.2
#: "Large": the collocated region covers at least this share of the gain box, every e.
LARGE = 0.3
#: "Similar size": basin-measure ratio non-collocated / collocated inside this range, every e.
SIMILAR = (0.5, 2.0)
#: A region covering more than this share of the box cannot show growth ("saturated").
SATURATED = 0.99
#: The region quantities of conclusions 1-3.
QUANTITIES = ("exists", "stability", "both")

AGREES, CONTRADICTED, DEPENDS, NOT_MEASURED = "agrees", "contradicted", "depends", "not measured"


def _v(ok) -> str:
    return AGREES if ok else CONTRADICTED


def combine(verdicts) -> str:
    """``"agrees"``/``"contradicted"`` if all measured verdicts say so, else ``"depends"``."""
    vs = {v for v in verdicts if v in (AGREES, CONTRADICTED)}
    if not vs:
        return DEPENDS
    return vs.pop() if len(vs) == 1 else DEPENDS


def _lst(a):
    return [float(x) for x in np.asarray(a, float)]


def check_1(col: dict, non: dict) -> dict:
    """Conclusion 1 from box shares ``{quantity: (len(e),)}`` of both cases (same box)."""
    out = {}
    for q in QUANTITIES:
        c, n = np.asarray(col[q], float), np.asarray(non[q], float)
        with np.errstate(all="ignore"):
            ratio = np.where(c > 0, n / c, np.where(n > 0, np.inf, np.nan))
        ok = bool(np.all(np.isfinite(ratio) & (ratio < MUCH_SMALLER)))
        out[q] = {"collocated": _lst(c), "noncollocated": _lst(n),
                  "ratio": [None if not np.isfinite(r) else float(r) for r in ratio],
                  "verdict": _v(ok)}
    return {"verdict": out["both"]["verdict"], "by_quantity": out}


def _trend(a, sign):
    a = np.asarray(a, float)
    d = np.diff(a)
    sat = (a[:-1] > SATURATED) & (a[1:] > SATURATED)
    strict = bool(np.all(sign * d > 0))
    allowed = bool(np.all((sign * d > 0) | sat))
    return strict, allowed, [bool(s) for s in sat]


def check_2(col: dict, non: dict) -> dict:
    """Conclusion 2: non-collocated shares strictly decrease along ``e``; collocated ones
    increase (steps between two saturated shares are not counted against it)."""
    out = {}
    for q in QUANTITIES:
        dec, _, _ = _trend(non[q], -1)
        inc, inc_allowed, sat = _trend(col[q], +1)
        out[q] = {"noncollocated": _lst(non[q]), "collocated": _lst(col[q]),
                  "noncollocated_decreases": dec, "collocated_increases": inc,
                  "collocated_saturated_steps": sat,
                  "verdict": _v(dec and inc_allowed)}
    return {"verdict": out["both"]["verdict"], "by_quantity": out}


def check_3(col: dict) -> dict:
    """Conclusion 3: the collocated shares are at least :data:`LARGE` for every ``e``."""
    out = {q: {"collocated": _lst(col[q]), "verdict": _v(bool(np.min(col[q]) >= LARGE))}
           for q in QUANTITIES}
    return {"verdict": out["both"]["verdict"], "by_quantity": out}


def check_4(col: list, non: list) -> dict:
    """Conclusion 4 from per-``e`` basin measures (areas in the ``(x1, y1)`` slice; None: no
    stable orbit).

    Similar means both non-empty and the ratio inside :data:`SIMILAR`, for every ``e``.
    """
    ratios, ok = [], True
    for c, n in zip(col, non):
        c, n = (0.0 if c is None else float(c)), (0.0 if n is None else float(n))
        r = n / c if c > 0 else (float("inf") if n > 0 else float("nan"))
        ratios.append(None if not np.isfinite(r) else r)
        ok &= bool(c > 0 and n > 0 and SIMILAR[0] < r < SIMILAR[1])
    return {"verdict": _v(ok), "collocated": col, "noncollocated": non, "ratio": ratios}


def check_4_necessary(col_stable: list, non_stable: list) -> str:
    """Conclusion 4 without basins: a missing or unstable orbit on one side only has an
    empty basin while the other side's is not (contradicted); otherwise not measured."""
    if any(bool(c) != bool(n) for c, n in zip(col_stable, non_stable)):
        return CONTRADICTED
    return NOT_MEASURED


def check_5(comparison) -> dict:
    """Conclusion 5 from a :class:`~hybridpd.analysis.design.RobustnessComparison`: the share
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
