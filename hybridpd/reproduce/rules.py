"""The verdict rules of the reproduction, one function per rule (CONVENTIONS.md, "Verdict rules").

A verdict is one of four words (:data:`VERDICTS`):

* ``"agrees"`` / ``"contradicted"`` — the measurement decides the paper's statement;
* ``"unresolved"`` — it cannot: the certified intervals overlap (no change within the
  certified resolution), or a window or a grid limits the measurement;
* ``"split"`` — two readings of the paper's words that are both reasonable (two robustness
  criteria) give opposite decided verdicts; both are reported.

Shares that decide verdicts are **certified intervals** ``(lo, hi)``: the true share of the
box lies inside (:mod:`hybridpd.reproduce.certified`). A rule says *agrees* or
*contradicted* only when the intervals separate, so two enclosures of the same boxes (a
coarse and a fine certification) can never give opposite decided verdicts; where they
overlap the rule says *unresolved*. Sampled shares (basins, the robustness comparison) are
checked on two grids instead (:func:`resolution`).

The conclusion-specific thresholds live in :mod:`hybridpd.reproduce.conclusions`.
"""
from __future__ import annotations

import itertools
import math

import numpy as np

__all__ = ["AGREES", "CONTRADICTED", "NO_CHANGE", "SPLIT", "UNRESOLVED", "VERDICTS", "all_of",
           "at_least", "basin_comparison", "criteria", "m2_readings", "ratio_below",
           "resolution", "separation", "share", "trend"]

AGREES, CONTRADICTED, UNRESOLVED, SPLIT = "agrees", "contradicted", "unresolved", "split"
#: The only verdicts.
VERDICTS = (AGREES, CONTRADICTED, UNRESOLVED, SPLIT)
#: What overlapping certified intervals mean.
NO_CHANGE = "no change within the certified resolution"


def _check_verdict(v):
    if v not in VERDICTS:
        raise ValueError(f"verdict must be one of {VERDICTS}, got {v!r}")
    return v


def _interval(name, iv) -> tuple:
    try:
        lo, hi = (float(v) for v in iv)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a (lo, hi) pair, got {iv!r}") from None
    if not 0.0 <= lo <= hi <= 1.0:
        raise ValueError(f"{name} must satisfy 0 <= lo <= hi <= 1, got {iv!r}")
    return lo, hi


def share(fraction, grid) -> dict:
    """A sampled share of a grid with its cell count: ``{"share", "cells", "of", "grid"}``.

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


def separation(a, b) -> str:
    """Where certified interval ``a`` lies against ``b``: ``"below"`` (``a_hi < b_lo``),
    ``"above"`` (``a_lo > b_hi``) or ``"overlap"`` (no change within the certified
    resolution).

    Examples
    --------
    >>> from hybridpd.reproduce.rules import separation
    >>> separation((0.1, 0.2), (0.3, 0.4)), separation((0.1, 0.35), (0.3, 0.4))
    ('below', 'overlap')
    """
    (alo, ahi), (blo, bhi) = _interval("a", a), _interval("b", b)
    if ahi < blo:
        return "below"
    if alo > bhi:
        return "above"
    return "overlap"


def trend(values, intervals, *, direction="decreasing") -> dict:
    """"The share tends to decrease (increase) with the parameter": a trend over the range.

    The trend is the change from the first to the last value of the range: *agrees* when the
    last interval lies wholly below (``"decreasing"``) or above (``"increasing"``) the
    first, *contradicted* when it lies wholly on the other side, *unresolved* when they
    overlap. A proved move the other way inside the range (``lo_j > hi_i`` for a decrease,
    ``i < j``) is reported, the largest one with its interval ``[values[i], values[j]]``,
    but does not decide: "tends to" is not "at every step".

    Parameters
    ----------
    values : array_like, shape (N,)
        The parameter, increasing, ``N >= 2``.
    intervals : sequence of (lo, hi)
        Certified shares at ``values``.
    direction : {"decreasing", "increasing"}

    Returns
    -------
    dict
        ``verdict``, ``direction``, ``change`` (``[lo, hi]`` of last minus first),
        ``against`` (``{"interval": [p_i, p_j], "by": d}``, the largest proved move the
        other way, ``d`` its smallest size; or None).

    Examples
    --------
    >>> from hybridpd.reproduce.rules import trend
    >>> t = trend([1, 2, 3], [(0.5, 0.6), (0.7, 0.8), (0.1, 0.2)])
    >>> t["verdict"], t["against"]["interval"]
    ('agrees', [1.0, 2.0])
    >>> trend([1, 2], [(0.5, 0.6), (0.55, 0.65)])["verdict"]
    'unresolved'
    """
    if direction not in ("decreasing", "increasing"):
        raise ValueError(f"direction must be 'decreasing' or 'increasing', got {direction!r}")
    x = np.asarray(values, float).ravel()
    ivs = [_interval(f"intervals[{k}]", iv) for k, iv in enumerate(intervals)]
    if x.size != len(ivs) or x.size < 2:
        raise ValueError(f"values and intervals must have the same length >= 2, got {x.size} "
                         f"and {len(ivs)}")
    if not np.all(np.diff(x) > 0):
        raise ValueError("values must be increasing")
    sign = 1.0 if direction == "decreasing" else -1.0
    sep = separation(ivs[-1], ivs[0])
    wanted, opposite = ("below", "above") if sign > 0 else ("above", "below")
    verdict = AGREES if sep == wanted else CONTRADICTED if sep == opposite else UNRESOLVED
    best = None
    for i in range(len(ivs)):
        for j in range(i + 1, len(ivs)):
            # a proved move against the direction: the later share is surely on the wrong side
            d = (ivs[j][0] - ivs[i][1]) if sign > 0 else (ivs[i][0] - ivs[j][1])
            if d > 0 and (best is None or d > best[0]):
                best = (d, i, j)
    return {"verdict": verdict, "direction": direction,
            "change": [ivs[-1][0] - ivs[0][1], ivs[-1][1] - ivs[0][0]],
            "against": None if best is None else
            {"interval": [float(x[best[1]]), float(x[best[2]])], "by": float(best[0])}}


def at_least(intervals, threshold) -> dict:
    """"The share is at least ``threshold``" for every interval: *agrees* when every lower
    bound is ``>= threshold``, *contradicted* when some upper bound is below it,
    *unresolved* otherwise. ``per_item`` gives each interval's own verdict.

    Examples
    --------
    >>> from hybridpd.reproduce.rules import at_least
    >>> at_least([(0.4, 0.5), (0.9, 1.0)], 0.3)["verdict"]
    'agrees'
    >>> at_least([(0.4, 0.5), (0.1, 0.2)], 0.3)["per_item"]
    ['agrees', 'contradicted']
    """
    t = float(threshold)
    per = []
    for k, iv in enumerate(intervals):
        lo, hi = _interval(f"intervals[{k}]", iv)
        per.append(AGREES if lo >= t else CONTRADICTED if hi < t else UNRESOLVED)
    return {"verdict": all_of(per), "per_item": per, "threshold": t}


def ratio_below(num, den, threshold) -> dict:
    """"``num`` is much smaller than ``den``": the ratio ``num / den`` below ``threshold``
    for every pair of intervals.

    The ratio is bracketed by ``[num_lo / den_hi, num_hi / den_lo]`` (an upper bound of
    ``inf`` when ``den_lo = 0``): *agrees* when every upper bound is below the threshold,
    *contradicted* when some lower bound is at or above it, *unresolved* otherwise.

    Examples
    --------
    >>> from hybridpd.reproduce.rules import ratio_below
    >>> r = ratio_below([(0.01, 0.05)], [(0.4, 0.5)], 0.2)
    >>> r["verdict"], r["ratio"]
    ('agrees', [[0.02, 0.125]])
    >>> ratio_below([(0.01, 0.05)], [(0.0, 0.5)], 0.2)["verdict"]
    'unresolved'
    """
    t = float(threshold)
    nums = [_interval(f"num[{k}]", iv) for k, iv in enumerate(num)]
    dens = [_interval(f"den[{k}]", iv) for k, iv in enumerate(den)]
    if len(nums) != len(dens):
        raise ValueError("num and den must have one interval each per item")
    per, ratios = [], []
    for (nlo, nhi), (dlo, dhi) in zip(nums, dens):
        lo = nlo / dhi if dhi > 0 else (math.inf if nlo > 0 else 0.0)
        hi = nhi / dlo if dlo > 0 else math.inf   # a share that may be 0 bounds no ratio
        ratios.append([lo, None if math.isinf(hi) else hi])
        per.append(AGREES if hi < t else CONTRADICTED if lo >= t else UNRESOLVED)
    return {"verdict": all_of(per), "per_item": per, "ratio": ratios, "threshold": t}


def all_of(verdicts) -> str:
    """A statement that must hold for every item (every ``e``, both cases): *contradicted*
    if some item is, *agrees* if every item agrees, else *unresolved*.

    Examples
    --------
    >>> from hybridpd.reproduce.rules import all_of
    >>> all_of(["agrees", "unresolved"]), all_of(["agrees", "contradicted", "unresolved"])
    ('unresolved', 'contradicted')
    """
    vs = [_check_verdict(v) for v in verdicts]
    if CONTRADICTED in vs:
        return CONTRADICTED
    if vs and all(v == AGREES for v in vs):
        return AGREES
    return UNRESOLVED


def criteria(verdicts: dict) -> str:
    """One statement under several reasonable criteria (``{criterion: verdict}``): their
    common verdict, *split* when decided verdicts differ, *unresolved* when none decides.

    Examples
    --------
    >>> from hybridpd.reproduce.rules import criteria
    >>> criteria({"stability": "agrees", "stability and amplitude": "contradicted"})
    'split'
    >>> criteria({"stability": "agrees", "stability and amplitude": "unresolved"})
    'agrees'
    """
    vs = [_check_verdict(v) for v in verdicts.values()]
    if SPLIT in vs:
        return SPLIT
    decided = {v for v in vs if v in (AGREES, CONTRADICTED)}
    if len(decided) == 2:
        return SPLIT
    return decided.pop() if decided else UNRESOLVED


def resolution(at_run_grid: str, at_check_grid: str) -> str:
    """A sampled measurement on two grids: the run grid's verdict if the second grid gives
    the same, else ``"unresolved"``.

    Examples
    --------
    >>> from hybridpd.reproduce.rules import resolution
    >>> resolution("agrees", "agrees"), resolution("agrees", "contradicted")
    ('agrees', 'unresolved')
    """
    a, b = _check_verdict(at_run_grid), _check_verdict(at_check_grid)
    return a if a == b else UNRESOLVED


def m2_readings(m2, verdicts) -> list:
    """The readings of the printed gain box along ``m2`` as intervals of ``m2``.

    Consecutive computed values with the same verdict form one run ``[first, last]``; a
    change of verdict lies somewhere between the last value of one run and the first of the
    next (never drawn or stated as known there).

    Parameters
    ----------
    m2 : array_like
        The computed values of ``m2`` (increasing).
    verdicts : sequence of str
        The verdict at each.

    Returns
    -------
    list of dict
        ``{"verdict", "m2": [first, last], "computed": [values], "change_after": (last,
        next first) or None}``.

    Examples
    --------
    >>> from hybridpd.reproduce.rules import m2_readings
    >>> r = m2_readings([0.1, 1, 10, 100], ["agrees", "agrees", "contradicted",
    ...                                      "contradicted"])
    >>> [(x["verdict"], x["m2"], x["change_after"]) for x in r]
    [('agrees', [0.1, 1.0], [1.0, 10.0]), ('contradicted', [10.0, 100.0], None)]
    """
    x = [float(v) for v in m2]
    vs = [_check_verdict(v) for v in verdicts]
    if len(x) != len(vs) or not x:
        raise ValueError("m2 and verdicts must have the same non-zero length")
    if any(b <= a for a, b in itertools.pairwise(x)):
        raise ValueError("m2 must be increasing")
    runs = []
    for m, v in zip(x, vs):
        if runs and runs[-1]["verdict"] == v:
            runs[-1]["computed"].append(m)
            runs[-1]["m2"][1] = m
        else:
            if runs:
                runs[-1]["change_after"] = [runs[-1]["m2"][1], m]
            runs.append({"verdict": v, "m2": [m, m], "computed": [m], "change_after": None})
    return runs


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
    return {"verdict": all_of(per_e) if per_e else UNRESOLVED, "per_e": per_e,
            "ratio_bounds": bounds}
