"""Continuation of the closed-form symmetric orbit family (:func:`continue_symmetric`)."""
from __future__ import annotations

import math

import numpy as np

from hybridpd.analysis.bifevents import EventTracker, changes
from hybridpd.analysis.continuation import BifurcationEvent, Branch
from hybridpd.analysis.floquet import stability
from hybridpd.analysis.pathfollow import _MAX_HALVINGS, bisect_predicate
from hybridpd.model import (
    Case,
    ImpactPair,
    PDGains,
    as_gains,
    check_finite,
    check_int,
    check_odd_order,
    check_positive,
    wrap_phase,
)
from hybridpd.pair import symbolic
from hybridpd.pair.family import (
    EVENT_KINDS,
    SYMMETRIC_PARAMETERS,
    _branch_from_points,
    _check_parameter,
    _in_domain,
    _path_steps,
    _Point,
)
from hybridpd.pair.orbits import REASONS, symmetric_orbits
from hybridpd.pair.params import PairParams

_SIMPLE_SIG = (((-1, "impact"), (1, "impact")),)


def continue_symmetric(pair: ImpactPair, gains: PDGains, omega: float, parameter: str,
                       stop: float, *, x10: float = 1.0, n: int = 1, case="collocated",
                       step: float | None = None, min_step: float | None = None,
                       max_step: float | None = None, max_steps: int = 2000,
                       max_change: float = 0.05, locate: bool = True,
                       event_tol: float = 1e-10, margin_samples: int = 256,
                       events: tuple = EVENT_KINDS) -> Branch:
    """Continue the simple symmetric orbit family (closed form) in one parameter.

    Along the family the desired primary-mass amplitude ``x10`` stays fixed (unless it is the
    parameter) and the reference amplitude ``xm`` follows from (20), as in
    :func:`hybridpd.pair.orbits.symmetric_orbit`. Every point is closed form (conditions
    (13)-(14), viability by guaranteed contact location, symbolic ``DP``), so the family is a
    graph over the parameter and no corrector is needed; the step adapts to the change of
    the fixed point, the spectral radius and the viability margin.

    Where viability fails the *formal* orbit (the solution of (13)-(14), which crosses a
    wall) is still followed: its multipliers are reported (``viable`` False), and events on
    it are flagged ``viable=False``.

    Parameters
    ----------
    pair : ImpactPair
    gains : PDGains
    omega : float
        Reference frequency (rad/time).
    parameter : str
        One of :data:`SYMMETRIC_PARAMETERS`.
    stop : float
        End value of the parameter (the start is its value in the inputs).
    x10 : float
        Primary-mass amplitude (length); ``gamma = L / x10``. With ``parameter="gamma"`` it
        stays fixed and the clearance follows, ``L = gamma * x10`` (the paper's convention,
        CONVENTIONS.md); the start is ``gamma = pair.L / x10``.
    n : int
        Odd orbit order.
    case : {"collocated", "noncollocated"}
    step, min_step, max_step : float, optional
        Parameter steps; defaults ``|stop - p0| / 100``, ``|stop - p0| * 1e-6`` and
        ``|stop - p0| / 20``.
    max_steps : int
        Bound on accepted steps.
    max_change : float
        Largest accepted change per step of ``|s|_inf / (1 + |s|_inf)``, of
        ``min(spectral radius, 2)`` and of the viability margin.
    locate : bool
        Locate the events (Illinois method on the closed-form test functions).
    event_tol : float
        Location tolerance, relative to ``max(1, |p|)``.
    margin_samples : int
        Grid of the viability-margin search.
    events : tuple of str
        Kinds to detect (subset of :data:`EVENT_KINDS`).

    Returns
    -------
    Branch
        ``family == "symmetric"``, ``method == "closed_form"``.

    Raises
    ------
    ValueError
        Unknown parameter, non-finite or out-of-domain ``stop``, zero or negative steps.

    Examples
    --------
    The collocated symmetric orbit (``e = 0.1``, paper parameters) grazes near ``kv = 21.9``:

    >>> from hybridpd import ImpactPair, PDGains
    >>> br = continue_symmetric(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0, "kv", 23.0)
    >>> ev = br.events_of("grazing")[0]
    >>> round(ev.parameter, 3)
    21.938
    """
    if not isinstance(pair, ImpactPair):
        raise ValueError(f"pair must be an ImpactPair, got {type(pair).__name__}")
    gains = as_gains(gains)
    omega = check_positive("omega", omega)
    x10 = check_positive("x10", x10)
    case = Case.parse(case)
    name = _check_parameter(parameter, SYMMETRIC_PARAMETERS)
    stop = check_finite("stop", stop)
    base = PairParams.of(pair, gains, omega, x10=x10)
    p0 = pair.L if name == "L" else getattr(base, name)
    _, step, max_step, min_step, max_steps = _path_steps(
        name, p0, stop, step, max_step, min_step, max_steps, (100, 20, 1e-6))
    max_change = check_positive("max_change", max_change)
    event_tol = check_positive("event_tol", event_tol)
    margin_samples = check_int("margin_samples", margin_samples, 1)
    bad = [kd for kd in events if kd not in EVENT_KINDS]
    if bad:
        raise ValueError(f"events must be a subset of {EVENT_KINDS}, got {bad}")
    n = check_odd_order(n)
    fam = _SymmetricFamily(pair, base, name, n, case, margin_samples, omega, events)
    tracker = EventTracker(events, fam.evaluate, fam.size, event_tol, 80, locate, fam.to_event)
    pts, evs, rejected, termination = _graph_steps(
        fam, tracker, p0, stop, step=step, min_step=min_step, max_step=max_step,
        max_steps=max_steps, max_change=max_change, locate=locate, event_tol=event_tol)
    # the clearance recorded as it was given: gamma when it is swept, else L
    given = {("L" if k == "gamma" and name != "gamma" else k):
             (pair.L if k == "gamma" and name != "gamma" else v)
             for k, v in base.as_dict().items() if k != "xm"}
    fixed = {k: v for k, v in given.items() if k != name}
    fixed.update({"n": n, "case": case.value})
    br = _branch_from_points(pts, evs, name, None, 1, "closed_form", termination, rejected,
                             omega=omega, case=case, fixed=fixed)
    return br


def _change(a, b):
    """Size of the change between two closed-form points (for the step control)."""
    if a.formal != b.formal or a.viable != b.viable:
        return math.inf
    sa, sb = a.u[:4], b.u[:4]
    if not (np.all(np.isfinite(sa)) and np.all(np.isfinite(sb))):
        return 0.0
    ch = float(np.max(np.abs(sb[1:] - sa[1:]))) / (1.0 + float(np.max(np.abs(sa[1:]))))
    # the phase lives on a circle of length T: a wrap from T to 0 is no change
    ch = max(ch, abs(wrap_phase(sb[0] - sa[0], a.T)) / (1.0 + abs(sa[0])))
    if np.isfinite(a.rho) and np.isfinite(b.rho):
        # only the neighbourhood of the unit circle matters for the step: far outside it the
        # radius may grow by orders of magnitude without any event
        ch = max(ch, abs(min(b.rho, 2.0) - min(a.rho, 2.0)))
    if np.isfinite(a.margin) and np.isfinite(b.margin):
        ch = max(ch, abs(b.margin - a.margin))
    return ch


class _SymmetricFamily:
    """The closed-form symmetric orbits along one named parameter: their points, the point
    between two, their events (internal)."""

    def __init__(self, pair, base, name, n, case, margin_samples, omega, events):
        self.pair, self.base, self.name, self.n, self.case = pair, base, name, n, case
        self.margin_samples, self.omega, self.events = margin_samples, omega, events

    def point(self, p) -> _Point:
        """The family's point at parameter value ``p`` (closed form, symbolic ``DP``)."""
        name = self.name
        # gamma = L / x10: x10 moves at a fixed clearance, gamma moves the clearance
        v = self.base.replace(**{name: float(p)}, **({"L": self.pair.L} if name == "x10"
                                                     else {}))
        # the clearance exactly as swept or fixed (gamma x10 may round it)
        L = {"L": float(p), "x10": self.pair.L}.get(name, v.L)
        r = symmetric_orbits(v.kp, v.kv, mu=v.mu, e=v.e, L=L,
                             omega=v.omega, m2=v.m2, x10=v.x10, n=self.n, case=self.case,
                             margin=True, jacobian=False, margin_samples=self.margin_samples)
        code = int(r.reason)
        formal = code not in (1, 2)
        s = np.asarray(r.fixed_point, float).reshape(4)
        mult = np.full(4, np.nan + 0j)
        rho = np.nan
        DP = None
        if formal:
            DP = np.asarray(symbolic.orbit_jacobian(r.candidate).DP, float).reshape(4, 4)
            if np.all(np.isfinite(DP)):
                st = stability(DP)
                mult, rho = st.multipliers, st.spectral_radius
            else:
                formal = False
        viable = bool(r.exists)
        return _Point(u=np.append(s, p), DP=DP, mult=mult, rho=rho,
                      signature=_SIMPLE_SIG if viable else (), margin=float(r.viability_margin),
                      min_speed=float(s[3]), viable=viable, formal=formal, xm=float(r.xm),
                      reason=code, T=v.period)

    def evaluate(self, pa, pb, theta) -> _Point:
        return self.point(pa.u[-1] + theta * (pb.u[-1] - pa.u[-1]))

    def to_event(self, kind, pt, index, detail, fv, ok) -> BifurcationEvent:
        T = 2 * math.pi / (pt.u[-1] if self.name == "omega" else self.omega)
        s = pt.u[:4].copy()
        s[0] %= T
        if not pt.viable and kind not in ("grazing", "existence"):
            detail += " [formal orbit, not viable]"
        return BifurcationEvent(kind=kind, parameter=float(pt.u[-1]), point=s,
                                multipliers=pt.mult.copy(), index=index, detail=detail,
                                test_value=float(fv), located=bool(ok), viable=pt.viable,
                                variables={"xm": float(pt.xm)})

    @staticmethod
    def size(pa, pb) -> float:
        return abs(pb.u[-1] - pa.u[-1]) / max(1.0, abs(pa.u[-1]))

    def extra_events(self, pa, pb, index, tracker, locate, event_tol) -> list:
        """Grazing (the viability margin crosses 0) and changes of existence."""
        out = []
        ma, mb = pa.margin, pb.margin
        grazed = changes(ma, mb)
        if "grazing" in self.events and grazed:
            out.append(tracker.root(
                "grazing", lambda pt: pt.margin, pa, pb, index,
                lambda pt: ("viability margin crosses 0: the orbit "
                            f"{'stops' if mb < ma else 'starts'} existing by grazing (19)")))
        if "existence" in self.events and (pa.formal != pb.formal
                                           or (pa.viable != pb.viable and not grazed)):
            def same(pt):
                return (pt.formal, pt.viable) == (pa.formal, pa.viable)
            if locate:
                la, lb, ok = bisect_predicate(lambda th: self.evaluate(pa, pb, th), same,
                                              pa, pb, size=self.size(pa, pb), tol=event_tol,
                                              max_iter=80)
            else:
                la, lb, ok = pa, pb, False
            pt = la if la.formal else lb
            out.append(self.to_event("existence", pt, index,
                                     f"{REASONS[pa.reason]} -> {REASONS[pb.reason]}", np.nan,
                                     ok))
        return out


def _graph_steps(fam, tracker, p0, stop, *, step, min_step, max_step, max_steps, max_change,
                 locate, event_tol) -> tuple:
    """Step the family as a graph over the parameter from ``p0`` to ``stop`` (no corrector:
    every point is exact), halving where a step changes the point by more than
    ``max_change`` (see :func:`_change`), and detect the events between consecutive points.
    Returns ``(points, events, rejected, termination)``."""
    direction = 1.0 if stop > p0 else -1.0
    pts = [fam.point(p0)]
    evs = []
    rejected = 0
    termination = f"max_steps = {max_steps} reached"
    h = min(step, max_step)
    for _ in range(max_steps):
        cur = pts[-1]
        pc = cur.u[-1]
        for _h in range(_MAX_HALVINGS):
            pn = pc + direction * h
            if (pn - stop) * direction > 0:
                pn = stop
            if not _in_domain(fam.name, pn):
                pn = stop
            new = fam.point(pn)
            ch = _change(cur, new)
            if ch <= max_change or h <= min_step:
                break
            rejected += 1
            h = max(0.5 * h, min_step)
        idx = len(pts) - 1
        evs.extend(tracker.detect(cur, new, idx, fam.extra_events(cur, new, idx, tracker,
                                                                  locate, event_tol)))
        pts.append(new)
        if ch <= max_change / 3:
            h = min(1.5 * h, max_step)
        if pn == stop:
            termination = "reached stop"
            break
    return pts, evs, rejected, termination
