"""The convention study: how the paper's findings depend on the secondary mass ``m2``.

The closed loop between impacts is ``y2' = xd'' + (kp/m2) err + (kv/m2) err'`` and the impact
law involves ``mu`` only, so at fixed ``mu`` every result depends on ``(kp, kv, m2)`` through
``kp/m2`` and ``kv/m2``. The paper gives no ``m2``. This module measures what that leaves open:

* :func:`stable_intervals` — for fixed gains, the intervals of ``m2`` on which the symmetric
  orbit exists and is stable. Their end points are bifurcation points of the orbit (a
  multiplier crossing the unit circle, or a grazing that ends viability); each is bracketed on
  a fine log grid of the vectorised closed form
  (:func:`hybridpd.pair.orbits.symmetric_orbits`) and then located by Brent's method on the
  exact test function (``spectral radius - 1`` or the viability margin), and verified by
  recomputing that test function at the located point.
* :func:`choose_m2` — the documented rule for the second convention of a reproduction: the
  smallest value of the 1-2-5 series at or above every threshold at which all six orbits of
  Figs 6-7 exist and are stable.
* :func:`box_fractions` — shares of a gain box where the orbit exists (alone), where its
  candidate is stable (alone, viability ignored), and where both hold.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from hybridpd._results import Fields, compact_repr
from hybridpd.model import Case, check_positive
from hybridpd.pair.orbits import REASONS, symmetric_orbits

__all__ = ["EndPoint", "StableInterval", "box_fractions", "choose_m2", "series_125",
           "stable_intervals"]

_VERIFY_TOL = 1e-6


@dataclass(frozen=True)
class EndPoint(Fields):
    """One end of an ``m2`` interval.

    Attributes
    ----------
    m2 : float
        Location.
    kind : str
        ``"stability"`` (a multiplier on the unit circle: spectral radius = 1),
        ``"viability"`` (grazing: viability margin = 0), ``"existence"`` (another loss of
        existence, located by bisection on the existence flag; see ``reason``) or ``"window"``
        (the end of the studied range, not a bifurcation).
    residual : float
        The test function recomputed at ``m2`` (``rho - 1`` or the margin); NaN for
        ``"existence"`` and ``"window"``.
    verified : bool
        ``|residual| <= 1e-6`` (``"window"``: True; ``"existence"``: the bracket is below
        ``1e-6`` relative).
    reason : str
        For ``"existence"`` ends: why the orbit is lost beyond.
    """

    m2: float
    kind: str
    residual: float
    verified: bool
    reason: str = ""


@dataclass(frozen=True)
class StableInterval(Fields):
    """An interval ``[lo.m2, hi.m2]`` of ``m2`` on which the orbit exists and is stable."""

    lo: EndPoint
    hi: EndPoint
    __repr__ = compact_repr

    def bounds(self) -> list:
        return [self.lo.m2, self.hi.m2]


def _orbit_fn(case, kp, kv, params):
    def at(m2, margin=False):
        return symmetric_orbits(kp, kv, m2=m2, case=case, margin=margin, **params)
    return at


def _locate(at, a, b):
    """End point between grid points ``a`` (stable side) and ``b`` (other side)."""
    rb = at(b, margin=True)
    ra = at(a, margin=True)
    u = lambda m2: math.log(m2)
    if bool(rb.exists):
        f = lambda s: float(at(math.exp(s)).spectral_radius) - 1.0
        kind = "stability"
    elif int(rb.reason) == 3 and float(ra.viability_margin) > 0 > float(rb.viability_margin):
        f = lambda s: float(at(math.exp(s), margin=True).viability_margin)
        kind = "viability"
    else:
        return _bisect_existence(at, a, b, REASONS[int(rb.reason)])
    s = brentq(f, u(a), u(b), xtol=1e-14, rtol=4 * np.finfo(float).eps, maxiter=200)
    m2 = math.exp(s)
    res = f(s)
    if not math.isfinite(res):
        return _bisect_existence(at, a, b, REASONS[int(rb.reason)])
    return EndPoint(m2, kind, res, abs(res) <= _VERIFY_TOL)


def _bisect_existence(at, a, b, reason):
    # the existence flag is all we have here: bisect it (bounded: 80 halvings in log m2)
    ua, ub = math.log(a), math.log(b)
    for _ in range(80):
        if abs(ub - ua) < 1e-12:
            break
        um = 0.5 * (ua + ub)
        if bool(at(math.exp(um)).stable):
            ua = um
        else:
            ub = um
    return EndPoint(math.exp(0.5 * (ua + ub)), "existence", float("nan"),
                    abs(ub - ua) < 1e-6, reason)


def stable_intervals(case, e, *, kp, kv, mu, L, omega, x10=1.0, n=1, m2_range=(0.1, 1000.0),
                     num=2001) -> list:
    """Intervals of ``m2`` where the symmetric orbit exists and is stable, end points located.

    Parameters
    ----------
    case : {"collocated", "noncollocated"}
    e, kp, kv, mu, L, omega, x10, n
        Fixed parameters of the orbit.
    m2_range : (lo, hi)
        Studied range (log axis).
    num : int
        Points of the bracketing grid ``logspace(lo, hi, num)``.

    Returns
    -------
    list of StableInterval
        In increasing order; ends at the range limits have kind ``"window"``.

    Examples
    --------
    >>> iv = stable_intervals("noncollocated", 0.5, kp=10, kv=20, mu=0.1, L=0.75, omega=5.0)
    >>> [(round(i.lo.m2, 2), i.lo.kind) for i in iv]
    [(8.77, 'stability')]
    """
    case = Case.parse(case).value
    lo, hi = (check_positive("m2_range", v) for v in m2_range)
    if not lo < hi:
        raise ValueError(f"m2_range must satisfy lo < hi, got {m2_range!r}")
    if int(num) < 3:
        raise ValueError(f"num must be >= 3, got {num!r}")
    params = dict(mu=mu, e=e, L=L, omega=omega, x10=x10, n=n)
    at = _orbit_fn(case, kp, kv, params)
    m2 = np.logspace(math.log10(lo), math.log10(hi), int(num))
    m2[0], m2[-1] = lo, hi
    ok = at(m2).stable
    out = []
    k = 0
    while k < len(m2):
        if not ok[k]:
            k += 1
            continue
        j = k
        while j + 1 < len(m2) and ok[j + 1]:
            j += 1
        start = (EndPoint(lo, "window", float("nan"), True) if k == 0
                 else _locate(at, m2[k], m2[k - 1]))
        stop = (EndPoint(hi, "window", float("nan"), True) if j == len(m2) - 1
                else _locate(at, m2[j], m2[j + 1]))
        out.append(StableInterval(start, stop))
        k = j + 1
    return out


def intersect(interval_lists) -> list:
    """Common part of several lists of ``[lo, hi]`` intervals (as ``[lo, hi]`` pairs)."""
    common = None
    for ivs in interval_lists:
        cur = [list(i.bounds()) if isinstance(i, StableInterval) else list(i) for i in ivs]
        if common is None:
            common = cur
            continue
        common = [[max(a[0], b[0]), min(a[1], b[1])] for a in common for b in cur
                  if max(a[0], b[0]) < min(a[1], b[1])]
    return common or []


def series_125(lo: float, hi: float) -> list:
    """The values of the 1-2-5 series (..., 0.1, 0.2, 0.5, 1, 2, 5, 10, ...) in ``[lo, hi]``.

    Examples
    --------
    >>> from hybridpd.reproduce.study import series_125
    >>> series_125(3.7, 60)
    [5.0, 10.0, 20.0, 50.0]
    """
    lo, hi = check_positive("lo", lo), check_positive("hi", hi)
    out = []
    for dec in range(math.floor(math.log10(lo)) - 1, math.ceil(math.log10(hi)) + 1):
        for m in (1, 2, 5):
            v = float(f"{m}e{dec}")
            if lo * (1 - 1e-12) <= v <= hi * (1 + 1e-12):
                out.append(v)
    return out


def choose_m2(intervals: dict, m2_range=None) -> float | None:
    """The second convention's ``m2``, by a rule that needs no study edge.

    ``intervals`` maps each orbit (e.g. ``(case, e)``) to its :func:`stable_intervals`. The
    common interval of all of them that reaches the top of the studied range (the orbits stay
    stable for every larger ``m2``) starts at the largest threshold; the rule takes the
    smallest value of the 1-2-5 series at or above it. When no common interval reaches the
    top, the smallest 1-2-5 value inside the widest common interval (in log) is taken.
    Returns None when the orbits have no common interval or it holds no 1-2-5 value.

    Parameters
    ----------
    intervals : dict
        ``{key: [StableInterval]}``.
    m2_range : (lo, hi), optional
        The studied range (default: the largest upper end of the intervals).

    Examples
    --------
    >>> from hybridpd.reproduce.study import EndPoint, StableInterval, choose_m2
    >>> end = lambda m2, kind="stability": EndPoint(m2, kind, 0.0, True)
    >>> choose_m2({1: [StableInterval(end(3.7), end(1000.0, "window"))],
    ...            2: [StableInterval(end(53.8), end(1000.0, "window"))]})
    100.0
    """
    common = intersect(intervals.values())
    if not common:
        return None
    top = m2_range[1] if m2_range is not None else max(iv[1] for iv in common)
    open_top = [iv for iv in common if iv[1] >= top * (1 - 1e-12)]
    lo, hi = open_top[0] if open_top else max(common, key=lambda iv: math.log(iv[1] / iv[0]))
    if open_top:   # stable for every larger m2: the first value at or above the threshold
        return series_125(lo, 10 * lo)[0]
    values = [v for v in series_125(lo, hi) if lo < v < hi]
    return values[0] if values else None


def candidate_stability(case, kp, kv, *, mu, e, L, omega, m2, x10=1.0, n=1):
    """Spectral radius of ``DP`` of the orbit candidate, viability ignored (NaN: no candidate).

    "Stability alone": the multipliers of the solution of (13)-(14) with ``xm > 0``, whether
    or not the flight between the impacts is viable.
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair import symbolic

    cand = symbolic.solve_symmetric_orbit(kp=kp, kv=kv, m2=m2, mu=mu, e=e, L=L, w=omega, x10=x10,
                                    n=n, case=Case.parse(case).value)
    ok = ~np.asarray(cand.singular, bool) & (np.nan_to_num(cand.xm) > 0)
    with np.errstate(all="ignore"):
        DP = np.asarray(symbolic.orbit_jacobian(cand).DP)
        good = ok & np.all(np.isfinite(DP), axis=(-2, -1))
        rho = np.full(good.shape, np.nan)
        if good.any():
            rho[good] = np.max(np.abs(np.linalg.eigvals(DP[good])), axis=-1)
    return rho


def box_fractions(case, kp_axis, kv_axis, *, e, mu, L, omega, m2, x10=1.0, n=1) -> dict:
    """Shares of a ``(kp, kv)`` grid in each region, one value per ``e``.

    Returns
    -------
    dict
        ``{"exists": (len(e),), "stability": (len(e),), "both": (len(e),)}``: existence
        alone (solvable and viable), stability alone (the candidate's spectral radius < 1,
        viability ignored) and both (the paper's shaded region).
    """
    es = np.atleast_1d(np.asarray(e, float))
    E, KV, KP = np.meshgrid(es, np.asarray(kv_axis, float), np.asarray(kp_axis, float),
                            indexing="ij")
    r = symmetric_orbits(KP, KV, mu=mu, e=E, L=L, omega=omega, m2=m2, x10=x10, n=n, case=case)
    rho = candidate_stability(case, KP, KV, mu=mu, e=E, L=L, omega=omega, m2=m2, x10=x10, n=n)
    with np.errstate(invalid="ignore"):
        st = np.nan_to_num(rho, nan=np.inf) < 1.0
    mean = lambda a: a.mean(axis=(1, 2))
    return {"exists": mean(r.exists), "stability": mean(st), "both": mean(r.stable)}
