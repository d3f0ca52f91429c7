"""One entry for continuing a periodic orbit in a parameter, on any map.

:func:`continue_orbit` takes either path of the package's one path-following engine
(:mod:`hybridpd.analysis.pathfollow`):

* **any hybrid automaton** (a model file, a sample, the pair written as an automaton): a
  builder ``p -> SectionMap | Section | automaton`` and the starting value of ``p``;
  :func:`~hybridpd.analysis.hybridcont.continue_family` corrects and follows the fixed point of
  ``P^k`` with saltation-matrix Jacobians and locates fold, period-doubling, Neimark-Sacker and
  stability-change events;
* **the impact pair's closed-form map** (:class:`~hybridpd.analysis.impactmap.ImpactMap`) and
  the name of one of its parameters (``kp``, ``kv``, ``e``, ``mu``, ``omega``, ...): the pair's
  continuation (:func:`hybridpd.analysis.continuation.continue_orbit`), with its symbolic
  Jacobians, viability margin and grazing as hooks.

Only the second loads the impact pair's modules, and only when it runs.
"""
from __future__ import annotations

from hybridpd.analysis.hybridcont import continue_family
from hybridpd.analysis.maps import PoincareMap

__all__ = ["continue_orbit"]


def continue_orbit(P, s0, parameter, stop, **options):
    """Continue a periodic orbit of a section map in one parameter.

    Parameters
    ----------
    P : callable or ImpactMap
        Either a builder ``p -> SectionMap | Section | automaton`` (any hybrid automaton; the
        general path), or the impact pair's :class:`~hybridpd.analysis.impactmap.ImpactMap`
        at the starting parameter values (its closed-form specialisation).
    s0 : array_like, shape (dim,), or PeriodicOrbit
        Starting guess of the fixed point of ``P^k`` (corrected by Newton first).
    parameter : float or str
        With a builder: the starting value ``p0`` of its parameter. With an ``ImpactMap``: the
        name of the parameter to vary (``kp``, ``kv``, ``e``, ``mu``, ``omega``, ...).
    stop : float
        Parameter value where the continuation ends.
    **options
        Passed on: see :func:`hybridpd.analysis.hybridcont.continue_family` (builder; e.g.
        ``period``, ``section``, ``method``, ``step``) or
        :func:`hybridpd.analysis.continuation.continue_orbit` (impact pair).

    Returns
    -------
    FamilyBranch or Branch
        The branch: points with their multipliers and stability, located events, and why the
        continuation stopped.

    Raises
    ------
    ValueError
        If ``P`` and ``parameter`` do not match one of the two forms, or an option is out of
        range.

    Examples
    --------
    Any automaton: a forced oscillator against a stop, its impacting orbit followed in the
    forcing frequency from 0.8 to 0.82 rad/s:

    >>> import hybridpd as hp
    >>> from hybridpd.hybrid.samples import impact_oscillator, oscillator_initial_state
    >>> def build(w):
    ...     return impact_oscillator(omega0=1.0, zeta=0.1, omega=w, stop=1.0, e=0.8)
    >>> sec = {"mode": "free", "guard": "impact",
    ...        "reference": (oscillator_initial_state(0, 0, omega=0.8), 0.0)}
    >>> br = hp.continue_orbit(build, [7.7, 1.66], 0.8, 0.82, section=sec, step=0.01)
    >>> br.termination, round(br.points[-1].p, 6)
    ('reached', 0.82)

    The impact pair's closed-form map, its symmetric orbit followed in ``kv``:

    >>> pair = hp.ImpactPair(mu=0.1, e=0.1, L=0.75)
    >>> orb = hp.symmetric_orbit(pair, hp.PDGains(10, 20), 5.0)
    >>> P = hp.ImpactMap(pair, hp.PDGains(10, 20), hp.Reference(orb.xm, 5.0))
    >>> br = hp.continue_orbit(P, orb.fixed_point, "kv", 23.0, step=0.5)
    >>> [ev.kind for ev in br.events][:1]
    ['grazing']
    """
    if isinstance(parameter, str):
        if not isinstance(P, PoincareMap):
            raise ValueError(f"P must be the impact pair's ImpactMap when parameter is a name "
                             f"({parameter!r}), got {type(P).__name__}; for any other model "
                             "pass a builder p -> SectionMap and the starting value of p")
        # deferred import: the pair's continuation loads only when a pair map is continued
        from hybridpd.analysis.continuation.branch import continue_orbit as continue_pair

        return continue_pair(P, s0, parameter, stop, **options)
    if isinstance(P, PoincareMap) or not callable(P):
        raise ValueError("P must be a builder p -> SectionMap | Section | automaton when "
                         f"parameter is the starting value p0 (got P of type "
                         f"{type(P).__name__}); an ImpactMap takes the parameter's name")
    return continue_family(P, s0, parameter, stop, **options)
