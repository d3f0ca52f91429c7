"""Detection and location of bifurcation events along the impact pair's branches (shared by
its map continuation and its closed-form symmetric family), and the pair's :class:`Branch`
(the one branch type, with the pair's variables)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hybridpd.analysis.continuation import Branch
from hybridpd.analysis.pathfollow import illinois as _illinois
from hybridpd.model import Case
from hybridpd.pair.continuation._common import (
    _END_GRAZE,
    _JUMP_TOL,
    _NONREAL_TOL,
    _fixed_parameters,
)


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


def _nonreal(m):
    return np.abs(m.imag) > _NONREAL_TOL * np.maximum(1.0, np.abs(m))


def _test_fold(pt):
    return float(np.prod(1.0 - pt.mult).real) if pt.formal else np.nan


def _test_pd(pt):
    return float(np.prod(1.0 + pt.mult).real) if pt.formal else np.nan


def _test_ns(pt):
    """``|lambda| - 1`` of the non-real multiplier nearest the unit circle (NaN if none)."""
    if not pt.formal:
        return np.nan
    m = pt.mult[_nonreal(pt.mult)]
    if m.size == 0:
        return np.nan
    d = np.abs(m) - 1.0
    return float(d[np.argmin(np.abs(d))])


def _ns_count(pt):
    return int(np.sum(_nonreal(pt.mult) & (np.abs(pt.mult) > 1.0)))


def _test_stability(pt):
    return pt.rho - 1.0 if pt.formal else np.nan


def _changes(fa, fb):
    return bool(np.isfinite(fa) and np.isfinite(fb) and (fa > 0) != (fb > 0)
                and not (fa == 0 and fb == 0))


class _Tracker:
    """Shared event detection/location along a sequence of points (internal).

    ``evaluate(pa, pb, theta)`` computes the solution between two accepted points;
    ``turn_test(pt, chord)``, when given, is the parameter component of the branch tangent
    at ``pt`` oriented along ``chord`` (its sign change is a turning point).
    """

    def __init__(self, kinds, evaluate, size, tol, max_iter, locate, to_event,
                 turn_test=None):
        self.kinds = kinds
        self.evaluate = evaluate
        self.size = size
        self.tol = tol
        self.max_iter = max_iter
        self.locate = locate
        self.to_event = to_event
        self.turn_test = turn_test

    def _root(self, kind, ftest, pa, pb, index, detail_fn, critical=None):
        """Locate a sign change of ``ftest``; ``critical(pt)`` is the distance of the critical
        multiplier(s) from the critical value: when it stays large at the located point the
        multipliers *jumped* across (a nonsmooth point such as grazing), and the event of a
        smooth bifurcation kind is dropped (returns None)."""
        fa, fb = ftest(pa), ftest(pb)
        if self.locate:
            pt, fv, ok = _illinois(lambda th: self.evaluate(pa, pb, th), ftest, fa, fb, pa, pb,
                                   size=self.size(pa, pb), tol=self.tol, max_iter=self.max_iter)
        else:
            pt, fv, ok = (pa if abs(fa) <= abs(fb) else pb), min(fa, fb, key=abs), False
        detail = detail_fn(pt)
        if not ok:
            # the bracket did not shrink (a failed corrector or no location asked for): what
            # is known is a sign change between two points, not an event at this parameter
            why = ("the corrector failed inside the bracket" if self.locate
                   else "location was not asked for")
            detail = (f"uncertain: not located ({why}); a sign change between branch points "
                      f"{index} and {index + 1}, possibly {detail}")
        if critical is not None and ok:
            c = critical(pt)
            if np.isfinite(c) and c > _JUMP_TOL:
                if kind != "stability_change":
                    return None
                detail += (f"; the multipliers jump across the unit circle here (spectral "
                           f"radius {pa.rho:.4g} -> {pb.rho:.4g} at a nonsmooth point, e.g. "
                           "grazing)")
        return self.to_event(kind, pt, index, detail, fv, ok)

    def detect(self, pa, pb, index, extra=()):
        """Events between two consecutive points."""
        out = []
        chord = pb.u - pa.u
        cross = _changes(_test_fold(pa), _test_fold(pb))
        turn = False
        if self.turn_test is not None and not (_near_grazing(pa) or _near_grazing(pb)):
            # (next to grazing the finite-difference tangent straddles the square-root
            # singularity of P and its sign means nothing; grazing has its own events)
            turn = _changes(self.turn_test(pa, chord), self.turn_test(pb, chord))
        if "fold" in self.kinds and turn:
            def detail(pt):
                m1 = float(np.min(np.abs(pt.mult - 1.0)))
                if cross:
                    return "fold: the branch turns back (a real multiplier crosses +1)"
                return ("turning point without a multiplier crossing +1 (closest "
                        f"|lambda - 1| = {m1:.2g}): the branch passes through a branch point, "
                        "e.g. a pitchfork, onto the symmetric partner of the family")
            out.append(self._root("fold", lambda pt: self.turn_test(pt, chord), pa, pb, index,
                                  detail))
        elif "fold" in self.kinds and cross:
            out.append(self._root(
                "fold", _test_fold, pa, pb, index,
                lambda pt: ("branch point: a real multiplier crosses +1 while the branch goes "
                            "on (pitchfork or transcritical; on a symmetric orbit typically the "
                            "symmetry-breaking pitchfork)"),
                critical=lambda pt: float(np.min(np.abs(pt.mult - 1.0)))))
        if "period_doubling" in self.kinds and _changes(_test_pd(pa), _test_pd(pb)):
            out.append(self._root(
                "period_doubling", _test_pd, pa, pb, index,
                lambda pt: ("real multiplier crosses -1 "
                            f"({'outwards' if _sgn_outside(pb) > _sgn_outside(pa) else 'inwards'})"),
                critical=lambda pt: float(np.min(np.abs(pt.mult + 1.0)))))
        if "neimark_sacker" in self.kinds and pa.formal and pb.formal \
                and _ns_count(pa) != _ns_count(pb):
            fa, fb = _test_ns(pa), _test_ns(pb)
            if _changes(fa, fb):
                ev = self._root(
                    "neimark_sacker", _test_ns, pa, pb, index,
                    lambda pt: ("complex pair crosses the unit circle "
                                f"({'outwards' if _ns_count(pb) > _ns_count(pa) else 'inwards'}"
                                f", angle {_ns_angle(pt):.4g} rad)"),
                    critical=lambda pt: abs(_test_ns(pt)))
                # a pair that became real inside the interval is not a Neimark-Sacker point
                if ev is not None:
                    m = ev.multipliers
                    if np.all(np.isfinite(m)):
                        crit = m[np.argmin(np.abs(np.abs(m) - 1.0))]
                        if _nonreal(np.array([crit]))[0]:
                            out.append(ev)
        if "stability_change" in self.kinds and _changes(_test_stability(pa),
                                                         _test_stability(pb)):
            def detail(pt):
                d = "stable -> unstable" if pb.rho > pa.rho else "unstable -> stable"
                m = pt.mult
                if np.all(np.isfinite(m)):
                    c = m[np.argmin(np.abs(np.abs(m) - 1.0))]
                    kind = ("complex pair" if _nonreal(np.array([c]))[0] else
                            ("real multiplier at +1" if c.real > 0 else "real multiplier at -1"))
                    d += f" ({kind})"
                return d
            out.append(self._root("stability_change", _test_stability, pa, pb, index, detail,
                                  critical=lambda pt: abs(pt.rho - 1.0)))
        out.extend(extra)
        out = [ev for ev in out if ev is not None]
        out.sort(key=lambda ev: abs(ev.parameter - pa.u[-1]))
        return out


def _near_grazing(pt):
    if not pt.traces:
        return False
    g = min(pt.margin, _rel_speed(pt))
    return bool(np.isfinite(g) and g < _END_GRAZE)


def _sgn_outside(pt):
    """1 if a real multiplier lies below -1 at ``pt`` (used for the PD direction)."""
    m = pt.mult
    return int(np.any((~_nonreal(m)) & (m.real < -1.0)))


def _ns_angle(pt):
    m = pt.mult[_nonreal(pt.mult)]
    if m.size == 0:
        return np.nan
    c = m[np.argmin(np.abs(np.abs(m) - 1.0))]
    return float(abs(np.angle(c)))


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
