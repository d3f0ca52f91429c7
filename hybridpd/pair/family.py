"""The impact pair's parameter families: :meth:`ImpactMap.family
<hybridpd.pair.impactmap.ImpactMap.family>` returns a :class:`PairFamily`, whose hooks give
:func:`~hybridpd.analysis.continuation.continue_orbit` the pair's rules of continuation
(domains of its parameters, the design path, step sizes, the scale without the phase, ``dF/dp``
at the current point, points with flight margins and approach speeds, grazing events and the
end of a branch at grazing), and the pair's branch points and :class:`Branch` (the one branch
type with the pair's variables), which its closed-form symmetric family shares."""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from hybridpd.analysis.bifevents import fold_test
from hybridpd.analysis.branch import BifurcationEvent, Branch
from hybridpd.analysis.family import ParameterFamily, PathRun, sequence_change
from hybridpd.analysis.floquet import stability
from hybridpd.analysis.periodic import find_orbit
from hybridpd.model import (
    Case,
    ImpactPair,
    PDGains,
    Reference,
    check_array,
    check_int,
    check_positive,
)
from hybridpd.pair.orbits import symmetric_orbits

if TYPE_CHECKING:
    from hybridpd.pair.impactmap import ImpactMap

__all__ = ["DESIGN_PARAMETERS", "EVENT_KINDS", "PARAMETERS", "SYMMETRIC_PARAMETERS", "PairFamily",
           "design_xm", "pair_family"]

#: Parameters :func:`continue_orbit` can follow (all others fixed).
PARAMETERS = ("kp", "kv", "e", "mu", "xm", "omega", "L", "m2")
#: Parameters :func:`continue_orbit` can follow along the design path (``x10`` given: the
#: reference amplitude ``xm`` follows the symmetric-orbit design, as in
#: :func:`continue_symmetric`).
DESIGN_PARAMETERS = ("kp", "kv", "e", "mu", "omega", "L", "m2", "gamma", "x10")


def _min(values):
    return float(min(values)) if values else np.nan


def _check_parameter(name, allowed):
    if not isinstance(name, str) or name not in allowed:
        raise ValueError(f"parameter must be one of {allowed}, got {name!r}")
    return name


@dataclass(frozen=True)
class _Design:
    """The design path: ``xm`` is the amplitude that puts the primary mass on the order-``n``
    triangle wave of amplitude ``x10`` (paper (20)), recomputed at every parameter value."""

    x10: float
    n: int = 1


def design_xm(pair: ImpactPair, gains: PDGains, omega: float, x10: float, n: int = 1,
              case="collocated") -> float:
    """Reference amplitude ``xm`` of the order-``n`` symmetric orbit realising ``x10``.

    The closed-form solution of (13)-(14) and (20) (the *formal* orbit: its viability is not
    required); NaN where the conditions are singular or give ``xm <= 0``.
    """
    r = symmetric_orbits(gains.kp, gains.kv, mu=pair.mu, e=pair.e, L=pair.L, omega=omega,
                         m2=pair.m2, x10=x10, n=n, case=case, margin=False, jacobian=False)
    xm = float(np.asarray(r.xm).reshape(-1)[0])
    return xm if np.isfinite(xm) and xm > 0 else np.nan


def _map_with(P: ImpactMap, name: str, value: float, design: _Design | None = None):
    """A copy of ``P`` with one parameter changed (the others and the tolerances kept).

    With a ``design``, ``xm`` follows the design at the new value (``gamma`` moves
    ``L = gamma * x10``; ``x10`` moves the design itself); None where the design has no
    amplitude.
    """
    pair, g, ref = P.pair, P.gains, P.reference
    if name in ("kp", "kv"):
        g = PDGains(**{"kp": g.kp, "kv": g.kv, name: value})
    elif name in ("e", "mu", "L", "m2", "gamma"):
        if name == "gamma":
            name, value = "L", value * design.x10
        pair = ImpactPair(**{"mu": pair.mu, "e": pair.e, "L": pair.L, "m2": pair.m2,
                             name: value})
    elif name in ("xm", "omega"):
        ref = Reference(**{"xm": ref.xm, "omega": ref.omega, name: value})
    if design is not None:
        if name == "x10":
            design = _Design(value, design.n)
        xm = design_xm(pair, g, ref.omega, design.x10, design.n, P.case)
        if not np.isfinite(xm):
            return None
        ref = Reference(xm, ref.omega)
    return type(P)(pair, g, ref, P.case, tol=P.tol, max_impacts=P.max_impacts)


def _fixed_parameters(P: ImpactMap) -> dict:
    return {"kp": P.gains.kp, "kv": P.gains.kv, "e": P.pair.e, "mu": P.pair.mu,
            "L": P.pair.L, "m2": P.pair.m2, "xm": P.reference.xm,
            "omega": P.reference.omega, "case": P.case.value}

#: Parameters :func:`continue_symmetric` can follow (``xm`` is an output there; ``gamma`` moves
#: ``L = gamma * x10`` with ``x10`` fixed; ``m2`` moves both masses, ``m1 = mu m2``).
SYMMETRIC_PARAMETERS = ("kp", "kv", "e", "mu", "omega", "L", "x10", "m2", "gamma")
#: Kinds of the pair's :class:`BifurcationEvent`.
EVENT_KINDS = ("fold", "period_doubling", "neimark_sacker", "grazing", "stability_change",
               "existence")

_END_GRAZE = 1e-4          # a branch whose corrector fails this close to grazing ends there
_NEAR_BRANCH = 5e-2        # a stuck continuation this close to a +1 multiplier: branch point


def _domain(name):
    """``(lo, hi, lo_closed)`` of a parameter's admissible values."""
    if name == "e":
        return 0.0, 1.0, True
    if name == "xm":
        return 0.0, math.inf, True
    return 0.0, math.inf, False


def _in_domain(name, v) -> bool:
    lo, hi, closed = _domain(name)
    if not math.isfinite(v):
        return False
    return (v >= lo if closed else v > lo) and v <= hi


def _map_value(P: ImpactMap, name: str, design: _Design | None = None) -> float:
    if name == "gamma":
        return P.pair.L / design.x10
    if name == "x10":
        return design.x10
    return {"kp": P.gains.kp, "kv": P.gains.kv, "e": P.pair.e, "mu": P.pair.mu,
            "L": P.pair.L, "m2": P.pair.m2, "xm": P.reference.xm,
            "omega": P.reference.omega}[name]


def _scale(x):
    """The pair's Newton scale: ``max(1, |z|)`` without the phase."""
    return max(1.0, float(np.max(np.abs(x[1:4]))))


def _path_steps(name, p0, stop, step, max_step, min_step, max_steps, defaults):
    """Validate a continuation path ``p0 -> stop`` and its step sizes.

    ``defaults = (n_steps, n_max, min_fraction)``: unset sizes become ``span / n_steps``,
    ``span / n_max`` and ``span * min_fraction``. Returns
    ``(span, step, max_step, min_step, max_steps)``.
    """
    _check_stop(name, p0, stop)
    n_steps, n_max, min_fraction = defaults
    span = abs(stop - p0)
    step = span / n_steps if step is None else check_positive("step", step)
    max_step = span / n_max if max_step is None else check_positive("max_step", max_step)
    min_step = span * min_fraction if min_step is None else check_positive("min_step", min_step)
    if min_step > step:
        raise ValueError(f"min_step = {min_step!r} must not exceed step = {step!r}")
    return span, step, max(max_step, step), min_step, check_int("max_steps", max_steps, 1)


def _check_stop(name, p0, stop):
    if not _in_domain(name, stop):
        lo, hi, _ = _domain(name)
        raise ValueError(f"stop = {stop!r} is outside the domain of {name} ({lo:g}, {hi:g})")
    if stop == p0:
        raise ValueError(f"stop must differ from the starting value {name} = {p0!r}")


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
                   "case": None if case is None else Case.parse(case).value, "fixed": fixed,
                   "n_rejected": int(n_rejected)})


def _branch_from_points(pts, evs, name, P0, k, method, termination, rejected, *,
                        omega=None, case=None, fixed=None) -> Branch:
    """The pair's branch of followed points (``P0``: the map at the start, or None with
    ``omega``, ``case`` and ``fixed`` given)."""
    if not pts:
        z = np.zeros(0)
        return _pair_branch(name, k, method, termination, parameter=z,
                            points=np.zeros((0, 4)), multipliers=np.zeros((0, 4), complex),
                            rho=z, viable=np.zeros(0, bool),
                            variables={"margin": z, "min_impact_speed": z, "xm": z,
                                       "newton_iterations": np.zeros(0, int)},
                            case=P0.case, fixed=_fixed_parameters(P0))
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


@dataclass(frozen=True, eq=False)
class PairFamily(ParameterFamily):
    """The impact maps along one named parameter, with the pair's rules of continuation
    (:meth:`ImpactMap.family <hybridpd.pair.impactmap.ImpactMap.family>`).

    Attributes
    ----------
    base : ImpactMap
        The map the family was made from (its other parameters are kept).
    design : _Design or None
        The design path (``x10``, ``n``: ``xm`` follows the symmetric-orbit design), or None
        (fixed ``xm``).
    graze_tol : float
        Grazing threshold of the events at the end of a branch.
    margin_samples : int
        Grid of the turning-point search per flight (the points' margins).
    """

    base: ImpactMap | None = None
    design: _Design | None = None
    graze_tol: float = 1e-6
    margin_samples: int = 128
    max_iter = 12
    max_steps = 400
    grow = 1.5
    range_slack = 1e-12
    kinds = EVENT_KINDS
    gradient_step = "point"
    dp_in_residual = False
    explains = False

    def value_of(self, P, p):
        del p
        return _map_value(P, self.name, self.design)

    def steps(self, span):
        return span / 50, span / 10, span * 1e-7

    def check_range(self, p0, p_end):
        if not (_in_domain(self.name, p0) and _in_domain(self.name, p_end)):
            lo, hi, _ = _domain(self.name)
            raise ValueError(f"p0 = {p0!r}, p_end = {p_end!r}: outside the domain of "
                             f"{self.name} ({lo:g}, {hi:g})")

    def start(self, P, s0, k, tol, max_iter):
        s0 = check_array("s0", s0, shape=(4,))
        if s0[3] <= 0:
            raise ValueError(f"s0[3] = z4 must be > 0 (approaching the +L wall), got {s0[3]!r}")
        return find_orbit(P, s0, k, tol=tol, max_iter=max(max_iter, 30), jacobian="exact")

    def scale(self, x, dim):
        del dim
        return _scale(x)

    def point(self, P, u, k, iterations, result, DP, gradient):
        """The point at ``u`` with its flight margins and approach speeds (None where a
        flight penetrates a wall)."""
        del result
        s = u[:4].copy()
        traces = P.traces(s, k, self.margin_samples)
        if not all(tr.ok for tr in traces):
            return None
        st = stability(DP)
        return _Point(u=u.copy(), DP=DP, mult=st.multipliers, rho=st.spectral_radius,
                      signature=tuple(tr.signature for tr in traces),
                      margin=_min([tr.margin for tr in traces]),
                      min_speed=_min([st.speed for tr in traces for st in tr.steps
                                      if st.kind != "stick"]),
                      xm=P.reference.xm, newton_its=iterations, traces=traces, Fp=gradient())

    def _period_of(self, u) -> float:
        """The reference period at ``u`` (the phase's range)."""
        return 2 * math.pi / (u[4] if self.name == "omega" else self.base.reference.omega)

    def to_event(self, kind, pt, index, detail, test_value, located) -> BifurcationEvent:
        s = pt.u[:4].copy()
        s[0] %= self._period_of(pt.u)
        return BifurcationEvent(kind=kind, parameter=float(pt.u[4]), point=s,
                                multipliers=pt.mult.copy(), index=index, detail=detail,
                                test_value=float(test_value), located=bool(located),
                                viable=True, variables={"xm": float(pt.xm)})

    def extra_events(self, pa, pb, index, evaluate, *, kinds, locate, tol) -> list:
        """A change of the impact pattern between two points: grazing, located by bisection
        on the pattern and reported on the side where the changing contact is slow or the
        flight margin small."""
        if "grazing" not in kinds or pa.signature == pb.signature:
            return []
        la, lb, ok = sequence_change(pa, pb, evaluate, locate=locate, tol=tol)
        ga = min(la.margin, _rel_speed(la))
        gb = min(lb.margin, _rel_speed(lb))
        pt, g = (la, ga) if ga <= gb else (lb, gb)
        detail = (f"impact pattern {_sig_str(pa.signature)} -> {_sig_str(pb.signature)} "
                  f"(margin {la.margin:.3g} / {lb.margin:.3g}, smallest approach speed "
                  f"{la.min_speed:.3g} / {lb.min_speed:.3g})")
        return [self.to_event("grazing", pt, index, detail, g, ok)]

    def nonsmooth(self, pt) -> bool:
        """Within the grazing tolerance of a grazing contact."""
        if not pt.traces:
            return False
        g = min(pt.margin, _rel_speed(pt))
        return bool(np.isfinite(g) and g < _END_GRAZE)

    def start_failed(self, P, k, method, p0, orbit):
        del p0
        why = ("Jacobian undefined at the initial point" if orbit is None
               else f"initial Newton failed: {orbit.reason}")
        return _branch_from_points([], [], self.name, P, k, method, why, 0)

    def finish(self, run: PathRun) -> Branch:
        pts, evs, termination = run.points, list(run.events), run.termination
        if termination.startswith("turned back"):
            lo, hi = run.range
            termination = (f"parameter left [{lo:g}, {hi:g}] at {self.name} = "
                           f"{pts[-1].u[-1]:.10g} (the branch turned back)")
        if run.stuck:
            termination += self._stuck(pts, run.kinds, evs, run.period)
        br = _branch_from_points(pts, evs, self.name, run.map, run.period, run.method,
                                 termination, run.rejected)
        if self.design is not None:
            fixed = {kk: v for kk, v in br.fixed.items() if kk not in ("xm", self.name)}
            fixed.update({"x10": self.design.x10, "n": self.design.n})
            br = replace(br, metadata={**br.metadata, "fixed": fixed})
        return br

    def _stuck(self, pts, kinds, evs, k) -> str:
        """Why a branch whose step fell below ``min_step`` could not go on, where the pair
        knows (a branch point, or the end of the family at grazing); appends the event it
        implies."""
        cur, index = pts[-1], len(pts) - 1
        g = min(cur.margin, _rel_speed(cur))
        m1 = float(np.min(np.abs(cur.mult - 1.0)))
        out = ""
        if m1 < _NEAR_BRANCH and not (np.isfinite(g) and g < _END_GRAZE):
            # Next to a branch point another family crosses this one; the corrector lands on
            # it (rejected as a sharp turn) whatever the step. Passing needs branch switching,
            # which is not attempted: say so.
            out += (f"; stopped next to a branch point (a multiplier within {m1:.2g} of +1): "
                    "another family of fixed points crosses here")
            if "fold" in kinds:
                evs.append(self.to_event(
                    "fold", cur, index,
                    f"branch point not passed (closest |lambda - 1| = {m1:.2g}); restart from "
                    "the other family to continue", float(fold_test(cur)), False))
        if np.isfinite(g) and g < _END_GRAZE:
            # The fixed point runs into grazing and no fixed point continues it: at a grazing
            # contact P has a square-root singularity (the branch ends, as in a nonsmooth
            # fold). The last point is within the margin of the grazing point.
            out += "; the branch ends at grazing"
            if "grazing" in kinds:
                evs.append(self.to_event(
                    "grazing", cur, index,
                    f"the branch ends at grazing (margin {cur.margin:.3g}, relative approach "
                    f"speed {_rel_speed(cur):.3g}): no fixed point of P^{k} continues beyond it",
                    g, g < self.graze_tol))
        return out


def _map_in_domain(base, name, design, p):
    """The map at ``p`` on the family of ``base`` (None out of the parameter's domain or
    where the design has no amplitude)."""
    if not _in_domain(name, p):
        return None
    return _map_with(base, name, float(p), design)


def pair_family(P: ImpactMap, parameter: str, *, x10=None, n=1, fd_step=1e-6,
                graze_tol=1e-6, margin_samples=128) -> PairFamily:
    """The :class:`PairFamily` of ``P`` in ``parameter`` (:meth:`ImpactMap.family`)."""
    design = None
    if x10 is not None:
        design = _Design(check_positive("x10", x10), check_int("n", n, 1))
    name = _check_parameter(parameter, PARAMETERS if design is None else DESIGN_PARAMETERS)
    value = _map_value(P, name, design)
    base = P
    if design is not None:
        base = _map_with(P, name, value, design)
        if base is None:
            raise ValueError(f"the design path has no reference amplitude at {name} = "
                             f"{value:g} (x10 = {design.x10:g}, n = {design.n})")
    build = functools.partial(_map_in_domain, base, name, design)
    return PairFamily(name, value, build, check_positive("fd_step", fd_step), base=base,
                      design=design, graze_tol=check_positive("graze_tol", graze_tol),
                      margin_samples=check_int("margin_samples", margin_samples, 1))
