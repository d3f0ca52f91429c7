"""Continuation of the impact pair's fixed points of ``P^k`` in one named parameter
(:func:`continue_pair_orbit`) on the one engine,
:func:`~hybridpd.analysis.continuation.follow_branch`: the pair gives it its map along the
parameter (its exact Jacobian and design path), its points (rejected where a flight
penetrates a wall) and its grazing events."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from hybridpd.analysis.bifevents import fold_test
from hybridpd.analysis.continuation import (
    BifurcationEvent,
    Branch,
    follow_branch,
)
from hybridpd.analysis.family import sequence_change
from hybridpd.analysis.floquet import stability
from hybridpd.analysis.maps import minimal_period
from hybridpd.analysis.periodic import PeriodicOrbit, find_orbit
from hybridpd.model import check_finite, wrap_phase
from hybridpd.pair.continuation._common import (
    _END_GRAZE,
    _NEAR_BRANCH,
    DESIGN_PARAMETERS,
    EVENT_KINDS,
    PARAMETERS,
    _check_parameter,
    _Design,
    _in_domain,
    _map_value,
    _map_with,
    _min,
    _path_steps,
    _positive_float,
    _positive_int,
    _scale,
    _section_point,
)
from hybridpd.pair.continuation.events import (
    _branch_from_points,
    _empty_branch,
    _near_grazing,
    _Point,
    _rel_speed,
    _sig_str,
)
from hybridpd.pair.continuation.newton import _param_derivative, _residual, map_power_jacobian
from hybridpd.pair.continuation.trace import trace_orbit
from hybridpd.pair.impactmap import ImpactMap


def continue_pair_orbit(impact_map_: ImpactMap, s0, parameter: str, stop: float, *,
                   period: int = 1, method: str = "arclength", step: float | None = None,
                   min_step: float | None = None, max_step: float | None = None,
                   max_steps: int = 400, tol: float = 1e-10, max_newton: int = 12,
                   jacobian: str = "auto", fd_step: float = 1e-6, locate: bool = True,
                   event_tol: float = 1e-9, graze_tol: float = 1e-6,
                   margin_samples: int = 128,
                   events: tuple = EVENT_KINDS, x10: float | None = None,
                   n: int = 1) -> Branch:
    """Continue a fixed point of ``P^k`` in one parameter from its value in the map to ``stop``.

    Parameters
    ----------
    impact_map_ : ImpactMap
        Map at the starting parameter values.
    s0 : array_like, shape (4,), or PeriodicOrbit
        Starting guess (corrected by Newton first).
    parameter : str
        One of :data:`PARAMETERS`; the others stay fixed (``xm`` included), unless ``x10``
        is given: then one of :data:`DESIGN_PARAMETERS`.
    stop : float
        Parameter value where the continuation ends.
    period : int
        ``k``.
    method : {"arclength", "natural"}
        Pseudo-arclength (unknowns ``(s, p)``, constraint ``t . (u - u_pred) = 0``; passes
        folds) or natural continuation in ``p`` with a secant predictor for ``s`` (stops at a
        fold: the corrector fails, the step shrinks below ``min_step``).
    step, min_step, max_step : float, optional
        Initial, smallest and largest step (parameter units for ``natural``, arclength in
        ``(phi, z1, z2, z4, p)`` for ``arclength``). Defaults ``|stop - p0| / 50``,
        ``|stop - p0| * 1e-7`` and ``|stop - p0| / 10``.
    max_steps : int
        Bound on accepted steps.
    tol, max_newton : float, int
        Corrector tolerance and iteration bound.
    jacobian : {"auto", "symbolic", "fd"}
        Jacobian of ``P^k`` (see :func:`map_power_jacobian`).
    fd_step : float
        Relative finite-difference step (Jacobian and parameter derivative).
    locate : bool
        Locate events (otherwise they are reported at the nearer bracketing point).
    event_tol : float
        Location tolerance (length of the bracket in ``(s, p)``).
    graze_tol : float
        Grazing thresholds (see :func:`~hybridpd.pair.continuation.trace.orbit_quantities`).
    margin_samples : int
        Grid of the turning-point search per flight.
    events : tuple of str
        Kinds to detect (subset of :data:`EVENT_KINDS`; ``existence`` does not apply here).
    x10 : float, optional
        Follow the *design path* instead of a fixed ``xm``: at every parameter value the
        reference amplitude is the one that realises the primary-mass amplitude ``x10`` on
        the order-``n`` symmetric orbit (:func:`~hybridpd.pair.continuation._common.design_xm`,
        paper (20)), the path of :func:`continue_symmetric`. The map's own ``xm`` is
        replaced by the design value at the start. ``gamma`` then means ``L / x10``.
    n : int
        Odd order of the design orbit (with ``x10``).

    Returns
    -------
    Branch
        ``family == "periodic"``; ``termination`` tells why it stopped ("reached stop",
        "max_steps reached", "step below min_step ...", "parameter left ...").

    Raises
    ------
    ValueError
        Unknown parameter or method, non-finite ``stop``, zero or negative steps, ``stop``
        equal to the start or outside the parameter's domain.

    Examples
    --------
    Follow the symmetric orbit of the collocated loop (``e = 0.1``) at fixed ``xm`` in
    ``kv`` through its grazing:

    >>> from hybridpd import ImpactPair, PDGains, Reference
    >>> from hybridpd.pair.orbits import symmetric_orbit
    >>> pair = ImpactPair(mu=0.1, e=0.1, L=0.75)
    >>> orb = symmetric_orbit(pair, PDGains(10, 20), 5.0)
    >>> P = ImpactMap(pair, PDGains(10, 20), Reference(orb.xm, 5.0))
    >>> br = continue_pair_orbit(P, orb.fixed_point, "kv", 23.0, step=0.5)
    >>> [ev.kind for ev in br.events][:1]
    ['grazing']
    """
    if not isinstance(impact_map_, ImpactMap):
        raise ValueError(f"impact_map_ must be an ImpactMap, got {type(impact_map_).__name__}")
    design = None
    if x10 is not None:
        design = _Design(_positive_float("x10", x10), _positive_int("n", n))
    name = _check_parameter(parameter, PARAMETERS if design is None else DESIGN_PARAMETERS)
    P0 = impact_map_
    if isinstance(s0, PeriodicOrbit):
        s0 = s0.s
    s0 = _section_point(s0, "s0")
    stop = check_finite("stop", stop)
    if method not in ("arclength", "natural"):
        raise ValueError(f"method must be 'arclength' or 'natural', got {method!r}")
    k = _positive_int("period", period)
    p0 = _map_value(P0, name, design)
    if design is not None:
        P0 = _map_with(P0, name, p0, design)
        if P0 is None:
            raise ValueError(f"the design path has no reference amplitude at {name} = {p0:g} "
                             f"(x10 = {design.x10:g}, n = {design.n})")
    span, step, max_step, min_step, max_steps = _path_steps(
        name, p0, stop, step, max_step, min_step, max_steps, (50, 10, 1e-7))
    tol = _positive_float("tol", tol)
    max_newton = _positive_int("max_newton", max_newton)
    if jacobian not in ("auto", "symbolic", "fd"):
        raise ValueError(f"jacobian must be 'auto', 'symbolic' or 'fd', got {jacobian!r}")
    fd_step = _positive_float("fd_step", fd_step)
    event_tol = _positive_float("event_tol", event_tol)
    graze_tol = _positive_float("graze_tol", graze_tol)
    margin_samples = _positive_int("margin_samples", margin_samples)
    bad = [kd for kd in events if kd not in EVENT_KINDS]
    if bad:
        raise ValueError(f"events must be a subset of {EVENT_KINDS}, got {bad}")
    lo_p, hi_p = min(p0, stop), max(p0, stop)
    path = _PairPath(P0, name, k, design, jacobian, fd_step, margin_samples)

    # ---- initial point
    start = find_orbit(P0, s0, k, tol=tol, max_iter=max(max_newton, 30),
                       jacobian="fd" if jacobian == "fd" else "exact")
    if not start.converged:
        return _empty_branch(name, P0, k, method,
                             f"initial Newton failed: {start.reason}")
    first = path.point(np.append(start.s, p0), start.iterations)
    if first is None:
        return _empty_branch(name, P0, k, method, "Jacobian undefined at the initial point")

    def out_of_range(p):
        if lo_p - 1e-12 * span <= p <= hi_p + 1e-12 * span:
            return None
        return f"parameter left [{lo_p:g}, {hi_p:g}] at {name} = {p:.10g} (the branch turned back)"

    pts, evs, termination, rejected, why = follow_branch(
        path, first, stop, method=method, step=step, min_step=min_step, max_step=max_step,
        max_steps=max_steps, tol=tol, max_iter=max_newton, scale=_scale,
        to_event=path.to_event, kinds=events, locate=locate, event_tol=event_tol,
        extra_events=lambda pa, pb, i, evaluate: path.grazing_events(
            pa, pb, i, evaluate, events=events, locate=locate, tol=event_tol),
        nonsmooth=_near_grazing, out_of_range=out_of_range, k=k, name=name)
    if why:
        termination += _stuck(pts, len(pts) - 1, events, evs, path.to_event, graze_tol, k)
    br = _branch_from_points(pts, evs, name, P0, k, method, termination, rejected)
    if design is not None:
        fixed = {kk: v for kk, v in br.fixed.items() if kk not in ("xm", name)}
        fixed.update({"x10": design.x10, "n": design.n})
        br = replace(br, metadata={**br.metadata, "fixed": fixed})
    return br


def _stuck(pts, index, events, evs, to_event, graze_tol, k) -> str:
    """Why a branch whose step fell below ``min_step`` could not go on, where the pair knows
    (a branch point, or the end of the family at grazing); appends the event it implies."""
    cur = pts[-1]
    g = min(cur.margin, _rel_speed(cur))
    m1 = float(np.min(np.abs(cur.mult - 1.0)))
    out = ""
    if m1 < _NEAR_BRANCH and not (np.isfinite(g) and g < _END_GRAZE):
        # Next to a branch point another family crosses this one; the corrector lands on it
        # (rejected as a sharp turn) whatever the step. Passing needs branch switching, which
        # is not attempted: say so.
        out += (f"; stopped next to a branch point (a multiplier within {m1:.2g} of +1): "
                "another family of fixed points crosses here")
        if "fold" in events:
            evs.append(to_event(
                "fold", cur, index,
                f"branch point not passed (closest |lambda - 1| = {m1:.2g}); restart from the "
                "other family to continue", float(fold_test(cur)), False))
    if np.isfinite(g) and g < _END_GRAZE:
        # The fixed point runs into grazing and no fixed point continues it: at a grazing
        # contact P has a square-root singularity (the branch ends, as in a nonsmooth fold).
        # The last point is within the margin of the grazing point.
        out += "; the branch ends at grazing"
        if "grazing" in events:
            evs.append(to_event(
                "grazing", cur, index,
                f"the branch ends at grazing (margin {cur.margin:.3g}, relative approach "
                f"speed {_rel_speed(cur):.3g}): no fixed point of P^{k} continues beyond it",
                g, g < graze_tol))
    return out


class _PairPath:
    """``F(u) = P^k(s) - s`` of the pair's map along one named parameter (``u = (s, p)``),
    its Jacobians and its points (with their traces), for the one engine."""

    explain = None       # the pair's maps say nothing more than "undefined"

    def __init__(self, P0, name, k, design, jacobian, fd_step, margin_samples):
        self.P0, self.name, self.k, self.design = P0, name, k, design
        self.jacobian, self.fd_step, self.margin_samples = jacobian, fd_step, margin_samples
        self._cache = {}

    def map_at(self, p):
        """The map at parameter value ``p`` (None off the design path)."""
        # the corrector evaluates the same few parameter values repeatedly
        key = float(p)
        if key not in self._cache:
            if len(self._cache) > 64:
                self._cache.clear()
            self._cache[key] = _map_with(self.P0, self.name, key, self.design)
        return self._cache[key]

    def period(self, u) -> float:
        """The reference period at ``u`` (the phase's range)."""
        return 2 * math.pi / (u[4] if self.name == "omega" else self.P0.reference.omega)

    def to_event(self, kind, pt, index, detail, fv, ok) -> BifurcationEvent:
        """The event of ``kind`` at the point ``pt`` (its phase in ``[0, T)``)."""
        s = pt.u[:4].copy()
        s[0] %= self.period(pt.u)
        return BifurcationEvent(kind=kind, parameter=float(pt.u[4]), point=s,
                                multipliers=pt.mult.copy(), index=index, detail=detail,
                                test_value=float(fv), located=bool(ok), viable=True,
                                variables={"xm": float(pt.xm)})

    def grazing_events(self, pa, pb, index, evaluate, *, events, locate, tol) -> list:
        """A change of the impact pattern between two points: grazing, located by bisection
        on the pattern and reported on the side where the changing contact is slow or the
        flight margin small."""
        if "grazing" not in events or pa.signature == pb.signature:
            return []
        la, lb, ok = sequence_change(pa, pb, evaluate, locate=locate, tol=tol)
        ga = min(la.margin, _rel_speed(la))
        gb = min(lb.margin, _rel_speed(lb))
        pt, g = (la, ga) if ga <= gb else (lb, gb)
        detail = (f"impact pattern {_sig_str(pa.signature)} -> {_sig_str(pb.signature)} "
                  f"(margin {la.margin:.3g} / {lb.margin:.3g}, smallest approach speed "
                  f"{la.min_speed:.3g} / {lb.min_speed:.3g})")
        return [self.to_event("grazing", pt, index, detail, g, ok)]

    def _map(self, u):
        P = self.map_at(u[4])
        if P is None:
            raise RuntimeError(f"no design amplitude at {self.name} = {u[4]:g}")
        return P

    def F(self, u):
        if not _in_domain(self.name, u[4]) or self.map_at(u[4]) is None:
            return None
        return _residual(self.map_at(u[4]), u[:4], self.k)

    def Fs(self, u):
        return map_power_jacobian(self._map(u), u[:4], self.k, method=self.jacobian,
                                  fd_step=self.fd_step)[0] - np.eye(4)

    def Fp(self, u):
        return _param_derivative(self._map(u), self.name, u[:4], self.k, self.fd_step,
                                 self.design)

    def lower_period(self, u) -> bool:
        return minimal_period(self.map_at(u[4]), u[:4], self.k) < self.k

    def unwrap(self, cur, new):
        # keep the phase continuous along the branch
        T = self.period(cur.u)
        new.u[0] = cur.u[0] + wrap_phase(new.u[0] - cur.u[0], T)

    def point(self, u, its):
        """The accepted point at ``u`` (None where a flight penetrates or DP is undefined)."""
        P, k = self.map_at(u[4]), self.k
        if P is None:
            return None
        s = u[:4].copy()
        traces = trace_orbit(P, s, k, self.margin_samples)
        if not all(tr.ok for tr in traces):
            return None
        try:
            DP = map_power_jacobian(P, s, k, method=self.jacobian, fd_step=self.fd_step)[0]
        except (RuntimeError, ValueError):
            return None
        if not np.all(np.isfinite(DP)):
            return None
        st = stability(DP)
        try:
            fp = self.Fp(u)
        except RuntimeError:
            fp = None
        return _Point(u=u.copy(), DP=DP, mult=st.multipliers, rho=st.spectral_radius,
                      signature=tuple(tr.signature for tr in traces),
                      margin=_min([tr.margin for tr in traces]),
                      min_speed=_min([st.speed for tr in traces for st in tr.steps
                                      if st.kind != "stick"]),
                      xm=P.reference.xm, newton_its=its, traces=traces, Fp=fp)
