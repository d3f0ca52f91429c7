"""The impact pair's branch points and their nonsmooth quantities (viability margin, approach
speeds: what its grazing events read), and the pair's :class:`Branch` (the one branch type,
with the pair's variables). Its events are detected by the one detector,
:class:`~hybridpd.analysis.bifevents.EventTracker`."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hybridpd.analysis.continuation import Branch
from hybridpd.model import Case
from hybridpd.pair.continuation._common import _END_GRAZE, _fixed_parameters


@dataclass
class _Point:
    """Everything the continuation keeps about one solution (internal)."""

    u: np.ndarray                 # (s with continuous phase, p)
    DP: np.ndarray | None
    mult: np.ndarray
    rho: float
    signature: tuple
    margin: float
    min_speed: float
    viable: bool = True
    formal: bool = True
    xm: float = np.nan
    reason: int = 0
    newton_its: int = 0
    T: float = np.nan             # period of the reference at this point
    Fp: np.ndarray | None = None  # d(P^k(s) - s)/dp (map continuation: turning points)
    traces: list = field(default_factory=list, repr=False)


def _near_grazing(pt):
    """Within the grazing tolerance of a grazing contact (nonsmooth for the detector)."""
    if not pt.traces:
        return False
    g = min(pt.margin, _rel_speed(pt))
    return bool(np.isfinite(g) and g < _END_GRAZE)


def _rel_speed(pt):
    speeds = [st.speed for tr in pt.traces for st in tr.steps if st.kind != "stick"]
    vmax = max(speeds, default=0.0)
    return min(speeds) / vmax if vmax > 0 else np.nan


def _sig_str(sig):
    return " | ".join(",".join(f"{w:+d}{'' if kd == 'impact' else kd[0]}" for w, kd in it)
                      for it in sig)


def _pair_branch(name, k, method, termination, *, parameter, points, multipliers, rho,
                 viable, patterns=(), events=(), variables=None, case=None, fixed=None,
                 n_rejected=0) -> Branch:
    """The pair's branch: the one :class:`Branch` with its variables and metadata."""
    return Branch(name, parameter, points, multipliers, rho, viable & (rho < 1.0), k,
                  list(events), termination, method, "", tuple(patterns),
                  {"viable": viable, **(variables or {})},
                  {"family": "periodic" if method != "closed_form" else "symmetric",
                   "case": None if case is None else Case.parse(case).value, "fixed": fixed, "n_rejected": int(n_rejected)})


def _empty_branch(name, P, k, method, reason) -> Branch:
    z = np.zeros(0)
    return _pair_branch(name, k, method, reason, parameter=z, points=np.zeros((0, 4)),
                        multipliers=np.zeros((0, 4), complex), rho=z,
                        viable=np.zeros(0, bool),
                        variables={"margin": z, "min_impact_speed": z, "xm": z,
                                   "newton_iterations": np.zeros(0, int)},
                        case=P.case, fixed=_fixed_parameters(P))


def _branch_from_points(pts, evs, name, P0, k, method, termination, rejected, *,
                        omega=None, case=None, fixed=None) -> Branch:
    p = np.array([pt.u[-1] for pt in pts])
    S = np.array([pt.u[:4] for pt in pts])
    if P0 is not None:
        omega, case, fixed = P0.reference.omega, P0.case, _fixed_parameters(P0)
    w = p if name == "omega" else omega
    S[:, 0] = np.mod(S[:, 0], 2 * np.pi / w)
    col = lambda attr: np.array([getattr(pt, attr) for pt in pts])
    return _pair_branch(
        name, k, method, termination, parameter=p, points=S, multipliers=col("mult"),
        rho=col("rho"), viable=col("viable").astype(bool), events=evs,
        patterns=tuple(pt.signature for pt in pts),
        variables={"margin": col("margin"), "min_impact_speed": col("min_speed"),
                   "xm": col("xm"), "newton_iterations": col("newton_its")},
        case=case, fixed=fixed, n_rejected=rejected)
