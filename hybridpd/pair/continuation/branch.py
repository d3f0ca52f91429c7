"""Continuation of fixed points of ``P^k`` in one parameter (:func:`continue_pair_orbit`)."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from hybridpd.analysis.continuation import BifurcationEvent, Branch
from hybridpd.analysis.floquet import stability
from hybridpd.analysis.maps import minimal_period
from hybridpd.analysis.pathfollow import bisect_predicate, corrector, follow_path
from hybridpd.analysis.periodic import PeriodicOrbit, find_orbit
from hybridpd.model import check_finite
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
    _wrap_diff,
)
from hybridpd.pair.continuation.events import (
    _branch_from_points,
    _empty_branch,
    _Point,
    _rel_speed,
    _sig_str,
    _test_fold,
    _Tracker,
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

    cache = {}

    def map_at(p):
        # the corrector evaluates the same few parameter values repeatedly
        key = float(p)
        if key not in cache:
            if len(cache) > 64:
                cache.clear()
            cache[key] = _map_with(P0, name, key, design)
        return cache[key]

    def F(u):
        p = u[4]
        if not _in_domain(name, p) or map_at(p) is None:
            return None
        return _residual(map_at(p), u[:4], k)

    def Fs(u):
        if map_at(u[4]) is None:
            raise RuntimeError(f"no design amplitude at {name} = {u[4]:g}")
        return map_power_jacobian(map_at(u[4]), u[:4], k, method=jacobian,
                                  fd_step=fd_step)[0] - np.eye(4)

    def Fp(u):
        if map_at(u[4]) is None:
            raise RuntimeError(f"no design amplitude at {name} = {u[4]:g}")
        return _param_derivative(map_at(u[4]), name, u[:4], k, fd_step, design)

    correct = corrector(F, Fs, Fp, tol=tol, max_iter=max_newton, scale=_scale)

    def make_point(u, its):
        P = map_at(u[4])
        if P is None:
            return None
        s = u[:4].copy()
        traces = trace_orbit(P, s, k, margin_samples)
        if not all(tr.ok for tr in traces):
            return None
        try:
            DP = map_power_jacobian(P, s, k, method=jacobian, fd_step=fd_step)[0]
        except (RuntimeError, ValueError):
            return None
        if not np.all(np.isfinite(DP)):
            return None
        margin = _min([tr.margin for tr in traces])
        vmin = _min([st.speed for tr in traces for st in tr.steps if st.kind != "stick"])
        st = stability(DP)
        sig = tuple(tr.signature for tr in traces)
        try:
            fp = Fp(u)
        except RuntimeError:
            fp = None
        return _Point(u=u.copy(), DP=DP, mult=st.multipliers, rho=st.spectral_radius,
                      signature=sig, margin=margin, min_speed=vmin,
                      xm=P.reference.xm, newton_its=its, traces=traces, Fp=fp)

    def turn_test(pt, chord):
        # parameter component of the unit tangent (kernel of [DP^k - I, dF/dp]) oriented
        # along the chord: it changes sign at a turning point of the branch
        if pt.Fp is None:
            return np.nan
        v = np.linalg.svd(np.column_stack([pt.DP - np.eye(4), pt.Fp]))[2][-1]
        return float(v[4] if v @ chord >= 0 else -v[4])

    def evaluate_between(pa, pb, theta):
        chord = pb.u - pa.u
        nrm = np.linalg.norm(chord)
        u, res = correct(pa.u + theta * chord, chord / nrm)
        if not res.converged:
            return None
        return make_point(u, res.iterations)

    def to_event(kind, pt, index, detail, fv, ok):
        T = 2 * math.pi / (pt.u[4] if name == "omega" else P0.reference.omega)
        s = pt.u[:4].copy()
        s[0] %= T
        return BifurcationEvent(kind=kind, parameter=float(pt.u[4]), point=s,
                                multipliers=pt.mult.copy(), index=index, detail=detail,
                                test_value=float(fv), located=bool(ok), viable=True,
                                variables={"xm": float(pt.xm)})

    tracker = _Tracker(events, evaluate_between, lambda a, b: float(np.linalg.norm(b.u - a.u)),
                       event_tol, 60, locate, to_event, turn_test=turn_test)

    def grazing_events(pa, pb, index):
        if "grazing" not in events or pa.signature == pb.signature:
            return []
        if locate:
            la, lb, ok = bisect_predicate(lambda th: evaluate_between(pa, pb, th),
                                           lambda pt: pt.signature == pa.signature, pa, pb,
                                           size=float(np.linalg.norm(pb.u - pa.u)),
                                           tol=event_tol, max_iter=60)
        else:
            la, lb, ok = pa, pb, False
        # report the side where the changing contact is slow / the margin is small
        ga = min(la.margin, _rel_speed(la))
        gb = min(lb.margin, _rel_speed(lb))
        pt, g = (la, ga) if ga <= gb else (lb, gb)
        detail = (f"impact pattern {_sig_str(pa.signature)} -> {_sig_str(pb.signature)} "
                  f"(margin {la.margin:.3g} / {lb.margin:.3g}, smallest approach speed "
                  f"{la.min_speed:.3g} / {lb.min_speed:.3g})")
        return [to_event("grazing", pt, index, detail, g, ok)]

    # ---- initial point
    start = find_orbit(P0, s0, k, tol=tol, max_iter=max(max_newton, 30),
                       jacobian="fd" if jacobian == "fd" else "exact")
    if not start.converged:
        return _empty_branch(name, P0, k, method,
                             f"initial Newton failed: {start.reason}")
    u0 = np.append(start.s, p0)
    first = make_point(u0, start.iterations)
    if first is None:
        return _empty_branch(name, P0, k, method, "Jacobian undefined at the initial point")
    def unwrap(cur, new):
        # keep the phase continuous along the branch
        T = 2 * math.pi / (cur.u[4] if name == "omega" else P0.reference.omega)
        new.u[0] = cur.u[0] + _wrap_diff(new.u[0] - cur.u[0], T)

    def out_of_range(p):
        if lo_p - 1e-12 * span <= p <= hi_p + 1e-12 * span:
            return None
        return f"parameter left [{lo_p:g}, {hi_p:g}] at {name} = {p:.10g} (the branch turned back)"

    pts, evs, termination, rejected, why = follow_path(
        first, stop, F=F, Fs=Fs, Fp=Fp, make_point=make_point, correct=correct, method=method,
        step=step, min_step=min_step, max_step=max_step, max_steps=max_steps, k=k,
        lower_period=lambda u: minimal_period(map_at(u[4]), u[:4], k) < k, unwrap=unwrap,
        detect=lambda a, b, i: tracker.detect(a, b, i, grazing_events(a, b, i)),
        out_of_range=out_of_range, tol=tol, name=name)
    if why:
        cur = pts[-1]
        g = min(cur.margin, _rel_speed(cur))
        m1 = float(np.min(np.abs(cur.mult - 1.0)))
        if m1 < _NEAR_BRANCH and not (np.isfinite(g) and g < _END_GRAZE):
            # Next to a branch point another family crosses this one; the corrector lands on
            # it (rejected as a sharp turn) whatever the step. Passing needs branch
            # switching, which is not attempted: say so.
            termination += (f"; stopped next to a branch point (a multiplier within "
                            f"{m1:.2g} of +1): another family of fixed points crosses here")
            if "fold" in events:
                evs.append(to_event(
                    "fold", cur, len(pts) - 1,
                    f"branch point not passed (closest |lambda - 1| = {m1:.2g}); restart "
                    "from the other family to continue", float(_test_fold(cur)), False))
        if np.isfinite(g) and g < _END_GRAZE:
            # The fixed point runs into grazing and no fixed point continues it: at a grazing
            # contact P has a square-root singularity (the branch ends, as in a nonsmooth
            # fold). The last point is within the margin of the grazing point.
            termination += "; the branch ends at grazing"
            if "grazing" in events:
                evs.append(to_event(
                    "grazing", cur, len(pts) - 1,
                    f"the branch ends at grazing (margin {cur.margin:.3g}, relative approach "
                    f"speed {_rel_speed(cur):.3g}): no fixed point of P^{k} continues beyond it",
                    g, g < graze_tol))
    br = _branch_from_points(pts, evs, name, P0, k, method, termination, rejected)
    if design is not None:
        fixed = {kk: v for kk, v in br.fixed.items() if kk not in ("xm", name)}
        fixed.update({"x10": design.x10, "n": design.n})
        br = replace(br, metadata={**br.metadata, "fixed": fixed})
    return br
