"""Fixed points of ``P^k`` by Newton's method: :func:`find_periodic_orbit` and
:class:`PeriodicOrbit`."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.analysis.floquet import stability
from hybridpd.analysis.maps import minimal_period
from hybridpd.analysis.periodic import PeriodicOrbit as _Orbit
from hybridpd.pair.continuation._common import (
    _f,
    _fixed_parameters,
    _positive_float,
    _positive_int,
    _scale,
    _section_point,
)
from hybridpd.pair.continuation.newton import _newton, _residual, map_power_jacobian
from hybridpd.pair.continuation.trace import trace_map
from hybridpd.pair.impactmap import ImpactMap


@dataclass(frozen=True, eq=False)
class PeriodicOrbit(_Orbit):
    """A fixed point of ``P^k`` of the impact pair found by Newton's method.

    The package's :class:`~hybridpd.analysis.periodic.PeriodicOrbit` (``s``, ``period``,
    ``converged``, ``reason``, ``iterations``, ``residual``, ``t_period``, ``signature``,
    ``DP``, ``multipliers``, ``spectral_radius``, ``stable``, ``hyperbolic``, ``grazing``,
    ``z``, ``names``) with the pair's contact pattern and diagnostics. Here ``s`` is
    ``(phi, z1, z2, z4)`` (``phi`` in ``[0, T)``) or the last iterate, ``DP``,
    ``multipliers``, ``stable`` and ``hyperbolic`` may be None (no Jacobian), and
    ``grazing`` is ``margin < graze_tol``, an approach speed below ``graze_tol`` times the
    largest one, or a grazing touch in the pattern.

    Attributes
    ----------
    orbit : ndarray, shape (k, 4)
        ``s, P(s), ..., P^{k-1}(s)`` (phases in ``[0, T)``).
    minimal_period : int
        Smallest ``d`` dividing ``k`` with ``P^d(s) = s`` (to ``1e-7`` relative); e.g. 1 when a
        period-2 search landed on a fixed point of ``P``.
    residual_history : ndarray
        Residual norm at every Newton iterate.
    jacobian_method : str
        ``"symbolic"`` (chain of symbolic blocks) or ``"fd"`` (finite differences).
    pattern : tuple of tuple of ImpactStep
        The contacts of each of the ``k`` applications of ``P`` (walls, flight times, speeds).
    walls : tuple of tuple of int
        ``pattern`` reduced to the walls, e.g. ``((-1, 1),)`` for a simple period-1 orbit.
    n_impacts : int
        Contacts per period ``k T``-orbit (including grazing touches and sticking).
    margin : float
        Smallest interior wall distance of a flight over the period, over ``L``
        (see :class:`MapTrace`).
    min_impact_speed : float
        Smallest approach speed over the period (length/time).
    sticking : bool
        A sticking phase occurs on the orbit.
    parameters : dict
        The map's parameters (``kp, kv, e, mu, L, m2, xm, omega, case``).
    """

    orbit: np.ndarray = field(default=None, repr=False)
    minimal_period: int = 1
    residual_history: np.ndarray = field(default=None, repr=False)
    jacobian_method: str | None = None
    pattern: tuple = field(default=(), repr=False)
    walls: tuple = ()
    n_impacts: int = 0
    margin: float = np.nan
    min_impact_speed: float = np.nan
    sticking: bool = False
    parameters: dict = field(default_factory=dict)
    __repr__ = compact_repr

    def to_dict(self) -> dict:
        """JSON-ready summary."""
        mult = None if self.multipliers is None else [[float(z.real), float(z.imag)]
                                                      for z in self.multipliers]
        return {
            "converged": self.converged, "reason": self.reason,
            "s": [float(v) for v in self.s], "orbit": self.orbit.tolist(),
            "period": self.period, "minimal_period": self.minimal_period,
            "residual": _f(self.residual), "iterations": self.iterations,
            "jacobian_method": self.jacobian_method, "multipliers": mult,
            "spectral_radius": _f(self.spectral_radius), "stable": self.stable,
            "hyperbolic": self.hyperbolic,
            "walls": [list(w) for w in self.walls],
            "flight_times": [[st.tau for st in it] for it in self.pattern],
            "n_impacts": self.n_impacts, "margin": _f(self.margin),
            "min_impact_speed": _f(self.min_impact_speed), "grazing": self.grazing,
            "sticking": self.sticking, "parameters": dict(self.parameters)}


def _orbit_diagnostics(P: ImpactMap, s: np.ndarray, k: int, jacobian: str, fd_step: float,
                       margin_samples: int, graze_tol: float):
    """Traces with margins, DP, stability and grazing flags at a (converged) point."""
    traces = []
    cur = s
    for _ in range(k):
        tr = trace_map(P, cur, margin=True, margin_samples=margin_samples)
        traces.append(tr)
        if not tr.ok:
            break
        cur = tr.s
    ok = all(tr.ok for tr in traces)
    DP = method = None
    if ok:
        try:
            DP, method, _ = map_power_jacobian(P, s, k, method=jacobian, fd_step=fd_step)
        except (RuntimeError, ValueError):
            DP = method = None
    margin = min((tr.margin for tr in traces), default=np.nan)
    speeds = [st.speed for tr in traces for st in tr.steps if st.kind != "stick"]
    vmax = max(speeds, default=0.0)
    vmin = min(speeds, default=np.nan)
    touch = any(st.kind == "graze" for tr in traces for st in tr.steps)
    grazing = bool(touch or (np.isfinite(margin) and margin < graze_tol)
                   or (vmax > 0 and vmin < graze_tol * vmax))
    sticking = any(st.kind == "stick" for tr in traces for st in tr.steps)
    return traces, DP, method, margin, vmin, grazing, sticking


def find_periodic_orbit(impact_map_: ImpactMap, s0, period: int = 1, *, tol: float = 1e-12,
                        max_iter: int = 50, jacobian: str = "auto", fd_step: float = 1e-6,
                        graze_tol: float = 1e-6, margin_samples: int = 256) -> PeriodicOrbit:
    """Solve ``P^k(s) = s`` by damped Newton's method.

    Parameters
    ----------
    impact_map_ : ImpactMap
        The impact map ``P`` (parameters, reference and feedback case fixed).
    s0 : array_like, shape (4,)
        Start ``(phi, z1, z2, z4)`` on the section (``z4 > 0``), e.g. a late iterate of ``P``.
    period : int
        ``k >= 1``.
    tol : float
        Convergence tolerance on ``||P^k(s) - s||_inf`` relative to ``max(1, |z|_inf)`` (or
        on the Newton step, when rounding keeps the residual above it).
    max_iter : int
        Bound on Newton iterations.
    jacobian : {"auto", "symbolic", "fd"}
        See :func:`map_power_jacobian`.
    fd_step : float
        Relative finite-difference step.
    graze_tol : float
        Thresholds of the grazing flag (dimensionless margin; speed relative to the largest
        approach speed on the orbit).
    margin_samples : int
        Grid of the turning-point search per flight.

    Returns
    -------
    PeriodicOrbit

    Raises
    ------
    ValueError
        Bad ``s0``, ``period``, ``tol``, ``max_iter`` or ``jacobian``.

    Examples
    --------
    The period-2 attractor of the collocated loop at ``e = 0.1`` (paper parameters):

    >>> from hybridpd import ImpactPair, PDGains, Reference
    >>> from hybridpd.pair.orbits import symmetric_orbit
    >>> pair = ImpactPair(mu=0.1, e=0.1, L=0.75)
    >>> xm = symmetric_orbit(pair, PDGains(10, 20), 5.0).xm
    >>> P = ImpactMap(pair, PDGains(10, 20), Reference(xm, 5.0))
    >>> s0 = P.iterate([0.3, -2.1, -2.3, 0.5], 200)[-1]
    >>> orb = find_periodic_orbit(P, s0, period=2)
    >>> orb.converged, orb.minimal_period, orb.walls
    (True, 2, ((-1, -1, 1), (1,)))
    >>> bool(orb.stable)
    True
    """
    if not isinstance(impact_map_, ImpactMap):
        raise ValueError(f"impact_map_ must be an ImpactMap, got {type(impact_map_).__name__}")
    P = impact_map_
    s0 = _section_point(s0, "s0")
    k = _positive_int("period", period)
    tol = _positive_float("tol", tol)
    max_iter = _positive_int("max_iter", max_iter)
    if jacobian not in ("auto", "symbolic", "fd"):
        raise ValueError(f"jacobian must be 'auto', 'symbolic' or 'fd', got {jacobian!r}")
    fd_step = _positive_float("fd_step", fd_step)
    graze_tol = _positive_float("graze_tol", graze_tol)
    margin_samples = _positive_int("margin_samples", margin_samples)

    res = _newton(lambda x: _residual(P, x, k),
                  lambda x: map_power_jacobian(P, x, k, method=jacobian, fd_step=fd_step)[0]
                  - np.eye(4),
                  s0, tol=tol, max_iter=max_iter, scale=_scale)
    return _make_orbit(P, res, k, jacobian, fd_step, margin_samples, graze_tol)


def _make_orbit(P, res, k, jacobian, fd_step, margin_samples, graze_tol) -> PeriodicOrbit:
    T = P.period
    s = res.x.copy()
    s[0] = s[0] % T
    r = _residual(P, s, k)
    resid = float(np.max(np.abs(r))) if r is not None else np.nan
    traces, DP, method, margin, vmin, grazing, sticking = _orbit_diagnostics(
        P, s, k, jacobian, fd_step, margin_samples, graze_tol)
    orbit = np.array([s] + [tr.s for tr in traces[:-1]])
    mult, rho, stable, hyper = None, np.nan, None, None
    if DP is not None and np.all(np.isfinite(DP)):
        stab = stability(DP)
        mult, rho, stable, hyper = stab.multipliers, stab.spectral_radius, stab.stable, \
            stab.hyperbolic
    minimal = minimal_period(P, s, k) if res.converged else k
    pattern = tuple(tr.steps for tr in traces)
    sig = P.apply(s, k).signature if res.converged else ()
    return PeriodicOrbit(
        t_period=float(sum(st.tau + st.stick_time for p in pattern for st in p)),
        signature=sig, names=P.names, z=P.state(s, s[0]),
        converged=bool(res.converged), reason=res.reason, s=s, orbit=orbit, period=k,
        minimal_period=minimal, residual=resid, residual_history=np.asarray(res.history),
        iterations=res.iterations, DP=DP, jacobian_method=method, multipliers=mult,
        spectral_radius=rho, stable=stable, hyperbolic=hyper,
        pattern=pattern, walls=tuple(tuple(st.wall for st in p) for p in pattern),
        n_impacts=sum(len(p) for p in pattern), margin=margin, min_impact_speed=vmin,
        grazing=grazing, sticking=sticking, parameters=_fixed_parameters(P))
