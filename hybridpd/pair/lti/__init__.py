r"""Any python-control LTI controller between impacts: symmetric orbits, impact map, stability.

The PD law of the paper is the special case of a linear controller from the tracking error to
the force. This module analyses the impact pair under **any proper, continuous-time
python-control LTI controller** (``StateSpace`` or ``TransferFunction``): a PD with a
derivative filter, a PID with a filter, a lead-lag, ... in both feedback cases. The closed loop
between impacts is still linear (:func:`hybridpd.loop.closed_loop`), now with the ``k``
controller states appended: ``z = [x1, y1, x2, y2, pc, ps, c1..ck]`` (``n = 6 + k`` states).
Orbits, the impact map and its Jacobian are computed **numerically** from the exact flow
``expm(A t)``; the symbolic path (:mod:`hybridpd.pair.orbits`) remains the fast path for a pure PD.

Signal conventions (those of :mod:`hybridpd.loop`)
--------------------------------------------------
* Tracking error ``err = xd - x`` (``x = x2`` collocated, ``x = x1`` non-collocated), and for a
  2-input controller also ``err_dot = xd' - y``. The controller output ``u_fb`` is added to the
  feed-forward ``m2 xd''``: ``U = m2 xd'' + u_fb``. The PD (3) is
  ``u_fb = kp err + kv err_dot`` (:func:`hybridpd.loop.pd_controller`, 2 inputs, no states).
* A 1-input controller sees only ``err``; a PD is then improper and must be filtered, e.g.
  :func:`filtered_pd` ``kp + kv s / (tf s + 1)``, which tends to the PD as ``tf -> 0``.
* Controller states ``c`` are continuous across impacts (positions do not jump, so neither does
  ``err``; a 2-input controller sees the jump of ``err_dot`` only through its dynamics).

Symmetric orbits of odd order ``n``
-----------------------------------
As for the PD (paper (9)-(12)), the desired primary-mass motion fixes the impact states on the
``+L`` wall: ``v = 2 x10 w / (n pi)`` (9), ``y2- = v (e - 2 mu - 1)/(1 + e)`` (10),
``y2+ = R y2-`` (11)-(12), ``x1 = x10``, ``x20 = x10 - L``, ``y1+ = -v``. With the unknowns
``C = xm cos(w t0)``, ``S = xm sin(w t0)`` (exosystem state at the impact time ``t0``) and
the controller state ``c0`` at the impact, the post-impact state is affine in
``u = (C, S, c0)``; symmetry after the flight ``tau = n T / 2`` requires
``x2 -> -x20``, ``y2 -> -y2-`` and ``c -> -c0`` (``x1 -> -x10``, ``y1 = -v`` and
``(pc, ps) -> -(C, S)`` hold automatically because ``v tau = 2 x10`` and ``n`` is odd). These
``2 + k`` conditions are **linear** in ``u`` through ``Phi = expm(A tau)``; they are solved by
an SVD (singular when ``sigma_min <= rcond sigma_max``), then ``xm = hypot(C, S)``,
``phi0 = atan2(S, C)/w mod T``. For ``k = 0`` this is exactly (13)-(16).

**Existence** needs ``xm > 0`` and viability (18): no contact on the open interval
``(t0, t0 + tau)``. It is decided by the guaranteed first-crossing location of
:mod:`hybridpd.hybrid.events` on the two wall guards (an extra contact is never missed, however close
to grazing); a violation is reported with its time, wall and ``x1``.

Impact map on the extended section
----------------------------------
Section ``z3 = x1 - x2 = +L``, ``z4 = y1 - y2 > 0`` (pre-impact), coordinates
``s = (phi, z1, z2, z4, c1..ck)`` with ``phi = t mod T``, ``z1 = x2``, ``z2 = y2``. On a wall
``sigma = +-1`` the full state is ``z = (z1 + sigma L, z2 + z4, z1, z2, xm cos(w phi),
xm sin(w phi), c)``. ``P`` applies Newton's law (2), flies exactly until the next contact
(guaranteed event location), repeats on the ``-L`` wall, and stops at the next ``+L`` contact.

Jacobian by implicit differentiation. Work with ``(t, z)``. An impact is ``z -> E z``. A flight
``z -> z' = Phi(tau) z`` ends where ``g = cg . Phi(tau) z -/+ L = 0`` with ``cg . z = z3``, so

.. math:: \frac{d\tau}{dz} = -\frac{g_z}{g_\tau} = -\frac{c_g \Phi(\tau)}{c_g A z'},\qquad
          \frac{dz'}{dz} = \Phi(\tau) + A z' \frac{d\tau}{dz},\qquad
          t' = t + \tau .

Each block is mapped back to the reduced coordinates of its wall (``phi_out = phi_in + tau``),
giving ``DP = DP43 DP32 DP21 DP10`` (24) for the simple pattern, or the product over any
pattern of transversal impacts (:class:`LTIJacobian`, its blocks named). The map itself is the
general :class:`~hybridpd.analysis.hybridmap.SectionMap` of the controlled pair
(:meth:`LTIOrbitResult.section_map`), whose ``jacobian_fd`` gives central differences of the
simulated map as the independent check. Stability: :func:`hybridpd.analysis.floquet.stability`.

Modules, by concept
-------------------
:mod:`~hybridpd.pair.lti.controllers` (filtered PD, filtered PID, lead-lag as
python-control objects), :mod:`~hybridpd.pair.lti.flight` (exact free flight, contact
location, section coordinates, impact and flight Jacobian blocks),
:mod:`~hybridpd.pair.lti.orbit` (:func:`lti_symmetric_orbit`, :class:`LTIOrbitResult`,
:class:`LTIJacobian`).
Everything public is re-exported here.

Examples
--------
>>> from hybridpd import ImpactPair
>>> orb = lti_symmetric_orbit(ImpactPair(mu=0.1, e=0.5, L=0.75), filtered_pd(10, 20, 0.01),
...                           omega=5.0)
>>> orb.exists, orb.stable, orb.fixed_point.shape
(True, True, (5,))
"""
# The private helpers are re-exported too (noqa: F401), so that every name importable from
# ``hybridpd.pair.lti`` before it became a package still is.
from hybridpd.pair.lti.controllers import filtered_pd, filtered_pid, lead_lag
from hybridpd.pair.lti.flight import (  # noqa: F401
    _WALL_MINUS,
    _WALL_PLUS,
    _flight_block,
    _FreeFlight,
    _full_state,
    _impact_block,
    _impact_full,
    _J_in,
    _J_out,
    _reduced,
)
from hybridpd.pair.lti.orbit import (  # noqa: F401
    LTI_REASONS,
    LTIJacobian,
    LTIOrbitResult,
    _chain_jacobian,
    _viability_margin,
    lti_symmetric_orbit,
)

__all__ = ["LTI_REASONS", "LTIJacobian", "LTIOrbitResult", "filtered_pd", "filtered_pid",
           "lead_lag", "lti_symmetric_orbit"]
