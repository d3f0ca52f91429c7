"""Choose controller gains for a desired periodic motion of a named DOF, on any automaton.

:func:`design_gains` searches gains ``g`` (any parameters of a model builder
``builder(g) -> SectionMap | Section | automaton``, as in
:mod:`hybridpd.analysis.continuation`) that

* keep a periodic orbit of the impact map (found by Newton on ``P^k``, continued from the
  previous evaluation's fixed point),
* give the named state (a DOF position, e.g. ``"load"``) the desired amplitude
  ``(max - min) / 2`` over one period (maximum and minimum over a dense sampling of the exact
  flow and over every jump's pre- and post-state),
* and, among those, maximise the stability margin ``1 - spectral radius``.

The search is SLSQP (:func:`scipy.optimize.minimize`) on ``minimize rho(g)`` subject to
``amplitude(g) = target`` and the bounds, with finite-difference gradients; every objective
evaluation is bounded (Newton iterations, map bounds) and the total number of model
evaluations is capped. The result always says whether the constraint holds and why the search
stopped.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.analysis.continuation import _map_factory
from hybridpd.analysis.periodic import PeriodicOrbit, find_orbit

__all__ = ["GainDesign", "design_gains", "orbit_amplitude"]


@dataclass(frozen=True, eq=False)
class GainDesign:
    """Result of :func:`design_gains`.

    Attributes
    ----------
    gains : ndarray
        The gains found (in the builder's order).
    success : bool
        An orbit exists at ``gains`` and the amplitude matches the target to ``rtol``.
    message : str
        Why the search stopped (the optimiser's message, or the failure).
    amplitude : float
        Amplitude of the named state on the orbit at ``gains``.
    spectral_radius : float
    orbit : PeriodicOrbit or None
    evaluations : int
        Model evaluations (each: build, Newton, amplitude).
    initial_spectral_radius, initial_amplitude : float
        The same at the starting gains.
    """

    gains: np.ndarray
    success: bool
    message: str
    amplitude: float
    spectral_radius: float
    orbit: PeriodicOrbit | None = field(repr=False)
    evaluations: int
    initial_spectral_radius: float
    initial_amplitude: float
    __repr__ = compact_repr


def orbit_amplitude(P, orbit: PeriodicOrbit, state, samples: int = 4000) -> float:
    """Amplitude ``(max - min) / 2`` of a state over one period of ``orbit`` (map ``P``).

    ``state`` is a state name or index of the automaton. The extremes are taken over
    ``samples`` points of the exact flow and over every jump's pre- and post-state.
    """
    ha = P.section.automaton
    i = ha.state_names.index(state) if isinstance(state, str) else int(state)
    if not 0 <= i < ha.n_states:
        raise ValueError(f"state must name one of {ha.state_names}, got {state!r}")
    tr = ha.simulate(orbit.z, P.section.mode, (0.0, orbit.t_period), max_jumps=P.max_jumps)
    x = tr(np.linspace(0.0, tr.t_final, int(samples)))[:, i]
    J = tr.jumps
    vals = np.concatenate([x, J.pre[:, i], J.post[:, i]]) if len(J) else x
    return 0.5 * float(vals.max() - vals.min())


def design_gains(builder, gains0, s0, *, state, amplitude: float, bounds, period: int = 1,
                 section=None, rtol: float = 1e-6, max_evaluations: int = 300,
                 map_options: dict | None = None) -> GainDesign:
    """Gains giving ``state`` the periodic amplitude ``amplitude`` with the most stable orbit.

    Parameters
    ----------
    builder : callable
        ``gains (ndarray) -> SectionMap | Section | automaton`` (see
        :mod:`hybridpd.analysis.continuation`; ``section`` for automata).
    gains0 : array_like
        Starting gains (inside ``bounds``).
    s0 : array_like
        Guess of the orbit's section point at ``gains0``.
    state : str or int
        The state whose amplitude is prescribed (e.g. a DOF name).
    amplitude : float
        Desired amplitude (> 0, units of the state).
    bounds : sequence of (lo, hi)
        One pair per gain.
    period : int
        ``k`` of ``P^k``.
    rtol : float
        Relative tolerance on the amplitude for ``success``.
    max_evaluations : int
        Bound on model evaluations.

    Returns
    -------
    GainDesign
    """
    from scipy.optimize import minimize

    g0 = np.asarray(gains0, float).ravel()
    bnd = [(float(a), float(b)) for a, b in bounds]
    if len(bnd) != g0.size or any(not lo < hi for lo, hi in bnd):
        raise ValueError(f"bounds must be {g0.size} pairs (lo, hi) with lo < hi")
    if not all(lo <= v <= hi for v, (lo, hi) in zip(g0, bnd)):
        raise ValueError("gains0 must lie inside bounds")
    if not (amplitude > 0 and math.isfinite(amplitude)):
        raise ValueError(f"amplitude must be finite and > 0, got {amplitude!r}")
    make = _map_factory(lambda g: builder(np.array(g)), section, dict(map_options or {}))
    cache = {}
    last = {"s": np.asarray(s0, float)}
    count = [0]

    def evaluate(g):
        key = tuple(np.round(np.asarray(g, float), 15))
        if key in cache:
            return cache[key]
        if count[0] >= max_evaluations:
            raise _Budget
        count[0] += 1
        P = make(key)
        orb = find_orbit(P, last["s"], period, max_iter=20)
        if orb.converged and np.isfinite(orb.spectral_radius):
            last["s"] = orb.s
            out = (orb.spectral_radius, orbit_amplitude(P, orb, state), orb)
        else:
            out = (math.nan, math.nan, None)
        cache[key] = out
        return out

    rho0, amp0, orb0 = evaluate(g0)
    if orb0 is None:
        return GainDesign(g0, False, "no periodic orbit at gains0 from s0", math.nan, math.nan,
                          None, count[0], math.nan, math.nan)

    def fobj(g):
        rho, _amp, orb = evaluate(g)
        return rho if orb is not None else 10.0 + float(np.sum((g - g0) ** 2))

    def fcon(g):
        _rho, amp, orb = evaluate(g)
        return (amp - amplitude) / amplitude if orb is not None else -10.0

    message = ""
    best = g0
    try:
        res = minimize(fobj, g0, method="SLSQP", bounds=bnd,
                       constraints=[{"type": "eq", "fun": fcon}],
                       options={"maxiter": 100, "ftol": 1e-10})
        best, message = res.x, str(res.message)
    except _Budget:
        feas = [(v[0], k) for k, v in cache.items() if v[2] is not None
                and abs(v[1] - amplitude) <= rtol * amplitude]
        best = np.array(min(feas)[1]) if feas else g0
        message = f"evaluation budget ({max_evaluations}) exhausted"
    count_before = count[0]
    count[0] = min(count[0], max_evaluations - 1)     # the final check is always allowed
    rho, amp, orb = evaluate(best)
    count[0] = max(count[0], count_before)
    ok = orb is not None and abs(amp - amplitude) <= rtol * amplitude
    if orb is None:
        message += "; no orbit at the final gains"
    return GainDesign(np.asarray(best, float), bool(ok), message, amp, rho, orb, count[0],
                      rho0, amp0)


class _Budget(Exception):
    """The evaluation budget is exhausted."""
