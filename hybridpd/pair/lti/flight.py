"""Exact free flight of the closed loop, contact location and the impact/flight Jacobian blocks.

The flight between impacts is the exact LTI flow ``expm(A t)`` of the closed loop
(:func:`hybridpd.loop.closed_loop`) with the two wall guards ``z3 = +-L``, located by the
guaranteed first-crossing search of :mod:`hybridpd.hybrid.events`. Also here: the reduced
section coordinates ``s = (phi, z1, z2, z4, c1..ck)`` and the per-impact and per-flight
Jacobian blocks in those coordinates (conventions: :mod:`hybridpd.pair.lti`).
"""
from __future__ import annotations

import math

import numpy as np
from scipy.linalg import expm

from hybridpd.hybrid.events import advance, prepare_lti_mode
from hybridpd.loop import ClosedLoop

_WALL_PLUS, _WALL_MINUS = 0, 1   # guard indices in the free-flight mode


class _FreeFlight:
    """The closed loop's free flight with the two wall guards of :mod:`hybridpd.pair.impactpair`.

    Guard 0 (``wall+``): ``g = L - z3``, fires when the gap closes on ``+L``; guard 1
    (``wall-``): ``g = z3 + L``. Both fire when ``g`` reaches ``<= 0``.
    """

    def __init__(self, loop: ClosedLoop, max_steps: int):
        n = loop.n_states
        L = loop.pair.L
        gap = np.zeros(n)
        gap[0], gap[2] = 1.0, -1.0
        self.n = n
        self.gap = gap
        self.max_steps = int(max_steps)
        self.tables = prepare_lti_mode(loop.A, None, [(-gap, L, -1), (gap, L, -1)]).flow_tables()

    def next_contact(self, z, t_max, hot=-1, hot_tol=0.0):
        """First contact of the flow from ``z`` within ``(0, t_max]``.

        Returns ``(code, tau, wall, z_event, err)``; ``code`` is an ``events.EV_*`` constant,
        ``wall`` is ``+1``/``-1`` (0 if none), ``z_event`` the pre-reset state.
        """
        w0 = np.append(np.asarray(z, float), 1.0)
        w_out = np.empty(self.n + 1)
        code, t, g, _, err = advance(w0, 0.0, float(t_max), self.tables, int(hot),
                                     float(hot_tol), self.max_steps, w_out)
        wall = 1 if g == _WALL_PLUS else (-1 if g == _WALL_MINUS else 0)
        return int(code), float(t), wall, w_out[:self.n].copy(), float(err)


# ----------------------------------------------------------------------------------------
# Section coordinates and Jacobian blocks
# ----------------------------------------------------------------------------------------
def _full_state(s, wall, L, xm, w):
    """Full state on wall ``wall`` from reduced ``s = (phi, z1, z2, z4, c)``."""
    phi, z1, z2, z4 = s[0], s[1], s[2], s[3]
    return np.concatenate([[z1 + wall * L, z2 + z4, z1, z2, xm * math.cos(w * phi),
                            xm * math.sin(w * phi)], s[4:]])


def _reduced(z, t):
    """Reduced coordinates ``(t, z1, z2, z4, c)`` of a full state on a wall (phase not wrapped)."""
    return np.concatenate([[t, z[2], z[3], z[1] - z[3]], z[6:]])


def _J_in(z, w):
    """``d(t, z)/ds`` at the full state ``z``: shape ``(n + 1, m)``, ``m = n - 2``."""
    n = z.size
    m = n - 2
    J = np.zeros((n + 1, m))
    J[0, 0] = 1.0                              # t = phi
    J[1, 1] = 1.0                              # x1 = z1 +- L
    J[2, 2] = J[2, 3] = 1.0                    # y1 = z2 + z4
    J[3, 1] = 1.0                              # x2 = z1
    J[4, 2] = 1.0                              # y2 = z2
    J[5, 0] = -w * z[5]                        # pc = xm cos(w phi)
    J[6, 0] = w * z[4]                         # ps = xm sin(w phi)
    J[7:, 4:] = np.eye(m - 4)                  # controller states
    return J


def _J_out(n):
    """``ds/d(t, z)``: shape ``(m, n + 1)`` (reads ``t, x2, y2, y1 - y2, c``)."""
    m = n - 2
    J = np.zeros((m, n + 1))
    J[0, 0] = 1.0
    J[1, 3] = 1.0
    J[2, 4] = 1.0
    J[3, 2], J[3, 4] = 1.0, -1.0
    J[4:, 7:] = np.eye(m - 4)
    return J


def _impact_full(pair, n):
    """Newton's law (2) on the full state: ``E`` of shape ``(n, n)``."""
    E = np.eye(n)
    E[np.ix_([1, 3], [1, 3])] = pair.velocity_jump_matrix()
    return E


def _impact_block(E, z_pre, w):
    """Reduced-coordinate Jacobian of an impact (the paper's ``DP10``/``DP32``)."""
    n = z_pre.size
    Eaug = np.eye(n + 1)
    Eaug[1:, 1:] = E
    return _J_out(n) @ Eaug @ _J_in(z_pre, w)


def _flight_block(A, gap, z_post, tau, w):
    """Reduced-coordinate Jacobian of a flight (``DP21``/``DP43``) by implicit differentiation.

    Returns ``(block, z_end)``. ``g(tau, z) = gap . expm(A tau) z -/+ L``;
    ``dtau/dz = -g_z / g_tau`` and ``dz'/dz = Phi + (A z') dtau/dz``; ``t' = t + tau``.
    """
    n = z_post.size
    Phi = expm(A * tau)
    z_end = Phi @ z_post
    f_tau = A @ z_end                          # d z'/d tau
    g_tau = gap @ f_tau                        # = z4 at the contact (transversality)
    if g_tau == 0.0 or not np.isfinite(g_tau):
        raise ValueError("the flight ends tangentially (z4 = 0 at the contact): DP is undefined")
    dtau = -(gap @ Phi) / g_tau                # dtau/dz, shape (n,)
    F = np.zeros((n + 1, n + 1))
    F[0, 0] = 1.0                              # t' = t + tau(z) (the flow is autonomous)
    F[0, 1:] = dtau
    F[1:, 1:] = Phi + np.outer(f_tau, dtau)
    return _J_out(n) @ F @ _J_in(z_post, w), z_end
