"""Periodic orbits of the impact map by Newton's method, and their parameter continuation.

Two complementary tools:

* the fixed points of ``P^k`` of the impact map ``P``
  (:class:`~hybridpd.pair.impactmap.ImpactMap`) are found by the package's one orbit search,
  :func:`hybridpd.analysis.periodic.find_orbit`, from any start (double impacts, grazing
  contacts, sticking phases included); the map's hook
  :meth:`~hybridpd.pair.impactmap.ImpactMap.point_quantities` adds the pair's walls, flight
  margins and contact pattern to the orbit (:func:`.trace.orbit_quantities`).
* :func:`~hybridpd.analysis.continuation.continue_orbit` of the map's family
  (``continue_orbit(P.family("kv"), 20.0, 23.0, s0)``, :meth:`ImpactMap.family
  <hybridpd.pair.impactmap.ImpactMap.family>`) follows a fixed point of ``P^k`` in one
  parameter among :data:`PARAMETERS` on the package's one engine, with the pair's rules
  (natural-parameter continuation with a secant predictor, or pseudo-arclength continuation
  which passes folds); :func:`continue_symmetric` follows the
  closed-form symmetric orbit family of :mod:`hybridpd.pair.orbits` (``x10`` fixed, ``xm``
  follows) in one of :data:`SYMMETRIC_PARAMETERS`.

Both record, at every accepted step, the parameter, the fixed point, the Floquet multipliers
and the spectral radius, and detect and locate these events between consecutive steps
(:data:`EVENT_KINDS`), by the Illinois (safeguarded regula falsi) method on a test function,
or by bisection where the test is a discrete change:

========================  ==========================================================
``fold``                  ``det(DP - I)`` changes sign: a real multiplier crosses +1
                          (a fold if the parameter turns back; otherwise a branch
                          point, e.g. the symmetry-breaking pitchfork of a symmetric
                          orbit)
``period_doubling``       ``det(DP + I)`` changes sign: a real multiplier crosses -1
``neimark_sacker``        a complex pair crosses the unit circle (test ``|lambda| - 1``
                          of the non-real multiplier nearest the circle)
``grazing``               symmetric family: the viability margin crosses 0 (paper (19));
                          map continuation: the impact pattern changes (an extra
                          contact appears with zero velocity, or one disappears)
``stability_change``      the spectral radius crosses 1
``existence``             symmetric family only: the conditions (13)-(14) stop having a
                          solution, or viability is lost otherwise than by grazing
========================  ==========================================================

Every loop is bounded (Newton iterations, continuation steps, step-size halvings, location
iterations) and every result carries the reason it stopped. Nothing here keeps global
mutable state; the compiled helper is cached on disk by numba like the rest of the package.

Coordinates: a section point is ``s = (phi, z1, z2, z4)`` (pre-impact at ``z3 = +L``,
``z4 > 0``), ``phi`` in time units in ``[0, T)``, ``T = 2 pi / omega``; positions in length
units, velocities in length/time.

Both return the package's one :class:`~hybridpd.analysis.continuation.Branch` of
:class:`~hybridpd.analysis.continuation.BifurcationEvent` (re-exported here), with the
pair's per-point variables (``viable``, ``margin``, ``min_impact_speed``, ``xm``,
``newton_iterations``) and metadata (``family``, ``case``, ``fixed``, ``n_rejected``).

Modules: :mod:`.trace` (one application of ``P`` with its impact pattern),
:mod:`.symmetric` (:func:`continue_symmetric`), :mod:`.switching`
(:func:`switch_branch`: the period-doubled branch at a flip, the crossing branch at a branch
point, the motion reached past a grazing point); branches are drawn by
:func:`hybridpd.plotting.branches.plot_branch`.
"""
from __future__ import annotations

from hybridpd.analysis.continuation import BifurcationEvent, Branch, load_branch
from hybridpd.pair.continuation.switching import BranchSwitch, branch_map, switch_branch
from hybridpd.pair.continuation.symmetric import continue_symmetric
from hybridpd.pair.continuation.trace import ImpactStep, MapTrace, trace_map
from hybridpd.pair.family import (
    DESIGN_PARAMETERS,
    EVENT_KINDS,
    PARAMETERS,
    SYMMETRIC_PARAMETERS,
    design_xm,
)

__all__ = ["DESIGN_PARAMETERS", "EVENT_KINDS", "PARAMETERS", "SYMMETRIC_PARAMETERS",
           "BifurcationEvent", "Branch", "BranchSwitch", "ImpactStep", "MapTrace",
           "branch_map", "continue_symmetric", "design_xm", "load_branch", "switch_branch",
           "trace_map"]
