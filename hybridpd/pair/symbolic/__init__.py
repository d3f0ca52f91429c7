"""Closed-form flows, symmetric-orbit existence and impact-map Jacobians, derived with SymPy.

This package reproduces sections 2-4 of the paper symbolically and turns every result into
vectorised NumPy functions. The SymPy derivations run once per installation and version: their
generated code (``lambdify`` source) is kept in a cache directory (see
:mod:`hybridpd._codecache`; ``$HYBRIDPD_CACHE_DIR`` overrides the location) and regenerated
when missing, stale or corrupt. *Importing this package does not import SymPy*, and neither
does a computation whose generated code is cached.

Modules, by concept: :mod:`~hybridpd.pair.symbolic.damped` (the entire functions ``DCh``,
``DSh``), :mod:`~hybridpd.pair.symbolic.derive` (the SymPy derivations and the kernels they
generate), :mod:`~hybridpd.pair.symbolic.flows` (flows and section coordinates),
:mod:`~hybridpd.pair.symbolic.existence` (symmetric orbits),
:mod:`~hybridpd.pair.symbolic.section_map` (the impact map and its Jacobian). Everything
public is re-exported here.

Conventions (those of CONVENTIONS.md)
-----------------------------------------
* State order ``X = [x1, y1, x2, y2, pc, ps]``: primary mass ``m1 = mu*m2`` (position ``x1``,
  velocity ``y1``), secondary mass ``m2`` (``x2``, ``y2``), exosystem ``pc = xm cos(w t)``,
  ``ps = xm sin(w t)`` with ``pc' = -w ps``, ``ps' = w pc``. Units: any consistent system,
  e.g. positions in m, velocities in m/s, time in s, ``w`` in rad/s, ``m2`` in kg,
  ``kp`` in N/m, ``kv`` in N s/m.
* Reference ``xd = xm cos(w t) = pc``, so ``xd' = -w ps``, ``xd'' = -w^2 pc``.
* Between impacts (8): ``x1' = y1``, ``y1' = 0``, ``x2' = y2``, ``m2 y2' = U`` with
  ``U = m2 xd'' - kv (y - xd') - kp (x - xd)``; collocated ``(x, y) = (x2, y2)``,
  non-collocated ``(x, y) = (x1, y1)``. The closed loop is the autonomous LTI system
  ``X' = A X`` (6x6), whose exact flow ``X(t) = Phi(t) X(0)`` is given in closed form.
* Collocated homogeneous part: the error ``x2 - xd`` obeys ``m2 x'' + kv x' + kp x = 0``.
  With ``alpha = kv/(2 m2)`` and ``D = alpha^2 - kp/m2`` it is written with the *entire*
  functions (analytic in ``D``, valid across under-, critically and over-damped)

      ``DCh(a, D, t) = exp(-a t) cosh(sqrt(D) t)``,
      ``DSh(a, D, t) = exp(-a t) sinh(sqrt(D) t) / sqrt(D)``

  (``cos``/``sin`` for ``D < 0``, ``t exp(-a t)`` limit for ``D = 0``). See :func:`dch`,
  :func:`dsh`. Non-collocated: ``x2`` is a polynomial in ``t`` plus sinusoids (no exponentials).
* Impact law (2) at ``z3 = x1 - x2 = +L`` with ``z4 = y1 - y2 > 0`` (wall ``+1``) or at
  ``z3 = -L`` with ``z4 < 0`` (wall ``-1``): positions unchanged,
  ``y1+ = ((mu - e) y1 + (1 + e) y2)/(1 + mu)``, ``y2+ = ((1 + e) mu y1 + (1 - mu e) y2)/(1 + mu)``,
  hence ``z4+ = -e z4-``.
* Section coordinates ``s = (phi, z1, z2, z4)`` with ``z1 = x2``, ``z2 = y2``, ``z4 = y1 - y2``,
  ``phi = t mod T``, ``T = 2 pi / w``. On wall ``sigma = +-1`` the full state is
  ``X = (z1 + sigma L, z2 + z4, z1, z2, xm cos(w phi), xm sin(w phi))``.
* Symmetric orbit of odd order ``n`` (paper section 3): impacts ``tau = n T / 2`` apart,
  ``v = y10 = 2 x10 w / (n pi)``, ``x20 = x10 - L`` (may be negative), pre-impact velocity of
  ``m2`` ``y2- = v (e - 2 mu - 1)/(1 + e)`` (10), post ``y2+ = R y2-`` (11)-(12),
  ``R = (e + 2 e mu - 1)/(e - 2 mu - 1)``. With unknowns ``C = xm cos(w t0)``,
  ``S = xm sin(w t0)`` the conditions (13)-(14) are linear; ``xm = hypot(C, S)``,
  ``sn = S / xm``, ``cs = C / xm``, ``phi0 = atan2(S, C)/w mod T``.
* Impact map (paper section 4) ``P = P43 o P32 o P21 o P10`` on the pre-impact section
  ``z3 = +L, z4 > 0``; ``DP = DP43 DP32 DP21 DP10`` (24). Flight blocks by implicit
  differentiation: ``g(tau, s) = z3(tau; s) + sigma L = 0`` (target wall ``-sigma``),
  ``dtau/ds = -g_s / g_tau`` and ``DP = f_s + f_tau dtau/ds`` with ``phi_out = phi_in + tau``.

Public API
----------
Flows: :func:`transition_matrix`, :func:`flow`, :func:`gap`, :func:`gap_derivatives`,
:func:`system_matrix`, :func:`dch`, :func:`dsh`.
Section: :func:`state_from_section`, :func:`section_from_state`.
Symmetric orbit: :func:`virtual_restitution`, :func:`symmetric_velocities`,
:func:`solve_symmetric_orbit` (-> :class:`SymmetricOrbit`).
Impact map: :func:`impact_section_map`, :func:`impact_block`, :func:`flight_section_map`,
:func:`flight_block`, :func:`flight_time`, :func:`closed_form_map` (-> :class:`ImpactMapResult`),
:func:`map_jacobian`, :func:`orbit_jacobian` (-> :class:`JacobianResult`).
SymPy objects: :func:`derivation` (-> :class:`Derivation`), :func:`sympy_functions`.
"""
from hybridpd.pair.symbolic.damped import dch, dsh
from hybridpd.pair.symbolic.derive import Derivation, derivation, sympy_functions
from hybridpd.pair.symbolic.existence import (
    SymmetricOrbit,
    solve_symmetric_orbit,
    symmetric_velocities,
    virtual_restitution,
)
from hybridpd.pair.symbolic.flows import (
    flow,
    gap,
    gap_derivatives,
    section_from_state,
    state_from_section,
    system_matrix,
    transition_matrix,
)
from hybridpd.pair.symbolic.section_map import (
    ImpactMapResult,
    JacobianResult,
    closed_form_map,
    flight_block,
    flight_section_map,
    flight_time,
    impact_block,
    impact_section_map,
    map_jacobian,
    orbit_jacobian,
)

__all__ = [
    "Derivation",
    "ImpactMapResult",
    "JacobianResult",
    "SymmetricOrbit",
    "closed_form_map",
    "dch",
    "derivation",
    "dsh",
    "flight_block",
    "flight_section_map",
    "flight_time",
    "flow",
    "gap",
    "gap_derivatives",
    "impact_block",
    "impact_section_map",
    "map_jacobian",
    "orbit_jacobian",
    "section_from_state",
    "solve_symmetric_orbit",
    "state_from_section",
    "symmetric_velocities",
    "sympy_functions",
    "system_matrix",
    "transition_matrix",
    "virtual_restitution",
]

# the names of 0.2.0
