"""The verdict rules of the reproduction, one function per rule (CONVENTIONS.md, "Verdict rules").

A verdict is one of four words (:data:`VERDICTS`):

* ``"agrees"`` / ``"contradicted"`` — the measurement decides the paper's statement;
* ``"depends"`` — decided, but differently between conventions or along ``m2``;
* ``"unresolved"`` — the measurement cannot decide (window- or grid-limited).

The rules are applied literally; the conclusion-specific thresholds live in
:mod:`hybridpd.reproduce.conclusions`.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["AGREES", "CONTRADICTED", "DEPENDS", "TREND_TOLERANCE_CELLS", "UNRESOLVED",
           "VERDICTS", "basin_comparison", "combine", "resolution", "share", "trend"]

AGREES, CONTRADICTED, DEPENDS, UNRESOLVED = "agrees", "contradicted", "depends", "unresolved"
#: The only verdicts.
VERDICTS = (AGREES, CONTRADICTED, DEPENDS, UNRESOLVED)
#: A trend may go the wrong way by at most this many grid cells of the box.
TREND_TOLERANCE_CELLS = 2


def _check_verdict(v):
    if v not in VERDICTS:
        raise ValueError(f"verdict must be one of {VERDICTS}, got {v!r}")
    return v


def share(fraction, grid) -> dict:
    """A share of a grid with its cell count: ``{"share", "cells", "of", "grid"}``.

    Parameters
    ----------
    fraction : float
        Share of the grid's cells, in ``[0, 1]``.
    grid : (int, int)
        Cells per axis.

    Examples
    --------
    >>> from hybridpd.reproduce.rules import share
    >>> share(0.25, (4, 2))
    {'share': 0.25, 'cells': 2, 'of': 8, 'grid': [4, 2]}
    """
    nx, ny = (int(v) for v in grid)
    if nx < 1 or ny < 1:
        raise ValueError(f"grid must have at least one cell per axis, got {grid!r}")
    f = float(fraction)
    if not 0.0 <= f <= 1.0:
        raise ValueError(f"fraction must lie in [0, 1], got {fraction!r}")
    return {"share": f, "cells": round(f * nx * ny), "of": nx * ny, "grid": [nx, ny]}


def combine(verdicts) -> str:
    """Verdict of a statement measured several times (conventions, values of ``m2``, cases).

    ``"depends"`` if the decided verdicts differ (or one of them already depends), else
    ``"unresolved"`` if any measurement is unresolved (or there is none), else the common
    decided verdict.

    Examples
    --------
    >>> from hybridpd.reproduce.rules import combine
    >>> combine(["agrees", "agrees"]), combine(["agrees", "contradicted"])
    ('agrees', 'depends')
    >>> combine(["agrees", "unresolved"])
    'unresolved'
    """
    vs = [_check_verdict(v) for v in verdicts]
    decided = {v for v in vs if v in (AGREES, CONTRADICTED)}
    if DEPENDS in vs or len(decided) == 2:
        return DEPENDS
    if not vs or UNRESOLVED in vs:
        return UNRESOLVED
    return decided.pop()


def resolution(at_run_grid: str, at_check_grid: str) -> str:
    """The verdict at the run's grid if the second grid gives the same, else ``"unresolved"``.

    Examples
    --------
    >>> from hybridpd.reproduce.rules import resolution
    >>> resolution("agrees", "agrees"), resolution("agrees", "contradicted")
    ('agrees', 'unresolved')
    """
    a, b = _check_verdict(at_run_grid), _check_verdict(at_check_grid)
    return a if a == b else UNRESOLVED


def trend(values, shares, cells, *, direction="decreasing",
          tolerance_cells=TREND_TOLERANCE_CELLS) -> dict:
    """A trend statement ("the share decreases with the parameter") over the whole range.

    It agrees only if the share is monotone in ``direction`` over the whole studied range
    within ``tolerance_cells`` cells: no later value exceeds (``"decreasing"``) or falls below
    (``"increasing"``) an earlier one by more than the tolerance. Otherwise it is contradicted
    and the evidence names the interval ``[values[i], values[j]]`` with the largest violation.

    Parameters
    ----------
    values : array_like, shape (N,)
        The parameter, increasing.
    shares : array_like, shape (N,)
        Shares of a grid of ``cells`` cells.
    cells : int
        Cells of the grid behind each share.
    direction : {"decreasing", "increasing"}
    tolerance_cells : int

    Returns
    -------
    dict
        ``verdict``, ``violation_cells`` (largest violation, in cells; 0 when none),
        ``interval`` (``[values[i], values[j]]`` of the largest violation, or None).

    Examples
    --------
    >>> from hybridpd.reproduce.rules import trend
    >>> trend([1, 2, 3], [0.5, 0.4, 0.6], 100)["interval"]
    [2.0, 3.0]
    >>> trend([1, 2, 3], [0.5, 0.51, 0.4], 100)["verdict"]
    'agrees'
    """
    if direction not in ("decreasing", "increasing"):
        raise ValueError(f"direction must be 'decreasing' or 'increasing', got {direction!r}")
    x = np.asarray(values, float).ravel()
    s = np.asarray(shares, float).ravel()
    if x.size != s.size or x.size < 2:
        raise ValueError(f"values and shares must have the same length >= 2, got {x.size} "
                         f"and {s.size}")
    if not (int(cells) == cells and cells >= 1):
        raise ValueError(f"cells must be an integer >= 1, got {cells!r}")
    # shares of a grid are whole cells: count them exactly (no rounding error at the
    # tolerance)
    c = np.round(s * int(cells), 6) * (1.0 if direction == "decreasing" else -1.0)
    # the largest rise of a later value over the running minimum of the earlier ones
    best, where = 0.0, None
    k_min = 0
    for j in range(1, c.size):
        if c[j - 1] < c[k_min]:
            k_min = j - 1
        rise = c[j] - c[k_min]
        if rise > best:
            best, where = float(rise), (k_min, j)
    ok = best <= tolerance_cells
    return {"verdict": AGREES if ok else CONTRADICTED, "violation_cells": best,
            "interval": None if where is None else [float(x[where[0]]), float(x[where[1]])],
            "direction": direction, "tolerance_cells": int(tolerance_cells)}


def basin_comparison(collocated, noncollocated, touches_edge, similar=(0.5, 2.0)) -> dict:
    """"Basins of similar size" from one window shared by every panel and both cases.

    A basin that touches the window's edge has only a lower bound on its area. For each ``e``
    the ratio ``noncollocated / collocated`` is bracketed from those bounds: inside
    ``similar`` for every value of the bracket is similar, outside for every value is not,
    otherwise undecided. The verdict: contradicted if some ``e`` is not similar (an empty
    basin beside a non-empty one included), agrees if every ``e`` is similar, unresolved
    otherwise (e.g. both basins fill the window, or neither case has a basin).

    Parameters
    ----------
    collocated, noncollocated : sequence of float or None
        Basin areas per ``e`` (None or 0: no stable orbit, an empty basin).
    touches_edge : {"collocated": [bool], "noncollocated": [bool]}
        Whether each basin touches the window's edge.
    similar : (lo, hi)

    Returns
    -------
    dict
        ``verdict``, ``ratio_bounds`` per ``e`` (``[lo, hi]``, ``hi`` None for unbounded),
        ``per_e`` verdicts.

    Examples
    --------
    >>> from hybridpd.reproduce.rules import basin_comparison
    >>> t = {"collocated": [True], "noncollocated": [True]}
    >>> basin_comparison([3.0], [3.0], t)["verdict"]
    'unresolved'
    """
    col = [0.0 if v is None else float(v) for v in collocated]
    non = [0.0 if v is None else float(v) for v in noncollocated]
    tc, tn = list(touches_edge["collocated"]), list(touches_edge["noncollocated"])
    if not len(col) == len(non) == len(tc) == len(tn):
        raise ValueError("collocated, noncollocated and touches_edge must have one entry per e")
    lo_s, hi_s = similar
    per_e, bounds = [], []
    for c, n, ec, en in zip(col, non, tc, tn):
        if c <= 0 and n <= 0:
            per_e.append(UNRESOLVED)
            bounds.append(None)
            continue
        if c <= 0 or n <= 0:
            # an empty basin beside a non-empty one: no window makes them similar
            per_e.append(CONTRADICTED)
            bounds.append([0.0, None] if c > 0 else [math.inf, None])
            continue
        # a basin touching the edge may be larger: its side of the ratio is a lower bound
        if ec and not en:
            r_lo, r_hi = 0.0, n / c
        elif en and not ec:
            r_lo, r_hi = n / c, math.inf
        elif ec and en:
            r_lo, r_hi = 0.0, math.inf
        else:
            r_lo = r_hi = n / c
        bounds.append([r_lo, None if math.isinf(r_hi) else r_hi])
        if lo_s < r_lo and r_hi < hi_s:
            per_e.append(AGREES)
        elif r_hi <= lo_s or r_lo >= hi_s:
            per_e.append(CONTRADICTED)
        else:
            per_e.append(UNRESOLVED)
    if CONTRADICTED in per_e:
        v = CONTRADICTED
    elif per_e and all(p == AGREES for p in per_e):
        v = AGREES
    else:
        v = UNRESOLVED
    return {"verdict": v, "per_e": per_e, "ratio_bounds": bounds}
