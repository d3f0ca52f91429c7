"""An independent stroboscopic period map of the two-mass drivetrain with a rubber stop and a
hard stop under a sampled PD (``examples/models/drivetrain_stops.toml``).

Written here from the equations with numpy and scipy only, nothing of the package. The plant:
``M q'' + C q' + K q = [u, 0] - [load > hi] (k (load - hi) + c load')`` (the rubber stop, a
Kelvin-Voigt spring-damper while compressed), and at ``load = lo`` the rigid stop's impact
``load'+ = -e load'-`` (the mass matrix is diagonal, so the impulse moves the load alone). The
controller samples at ``t_k = k dt`` and holds ``u_k = m_ff xd''(t_k) + kp (xd(t_k) -
motor) + kv (xd'(t_k) - motor')``, ``xd = A cos(w t)``. Each sampling interval is one
``solve_ivp`` integration (DOP853, rtol 1e-11, atol 1e-13) with the rubber stop's entry and
exit and the hard stop's impacts located as terminal events.
"""
import math

import numpy as np
from scipy.integrate import solve_ivp

__all__ = ["naive_period_map"]


def naive_period_map(data, kp, kv):
    """``period_map(s, phi0)``: the state one reference period after ``s = (motor,
    motor', load, load', held torque)`` at time ``phi0`` (``data``: the model file's
    tables; ``kp``, ``kv`` the gains)."""
    Mi = np.linalg.inv(np.diag(data["system"]["masses"]))
    Cd, K = np.array(data["system"]["damping"]), np.array(data["system"]["stiffness"])
    soft, hard = data["contact"]
    ref, dt = data["reference"], data["controller"]["dt"]
    A, w, mff = ref["amplitude"], ref["omega"], ref["feedforward_mass"]
    T = 2 * math.pi / w

    def rhs(t, y, engaged, u):
        q, v = y[:2], y[2:]
        f = np.array([u, 0.0]) - Cd @ v - K @ q
        if engaged:
            f[1] -= soft["stiffness"] * (q[1] - soft["hi"]) + soft["damping"] * v[1]
        return np.concatenate([v, Mi @ f])

    def soft_edge(t, y, engaged, u):
        return y[1] - soft["hi"]

    def hard_edge(t, y, engaged, u):
        return y[1] - hard["lo"]

    soft_edge.terminal = hard_edge.terminal = True
    hard_edge.direction = -1.0

    def held(t, y):
        xd, vd = A * math.cos(w * t), -A * w * math.sin(w * t)
        return -mff * A * w * w * math.cos(w * t) + kp * (xd - y[0]) + kv * (vd - y[2])

    def period_map(s, phi0):
        y = np.array([s[0], s[2], s[1], s[3]], float)      # (q_m, q_l, v_m, v_l)
        u, engaged, t = float(s[4]), y[1] > soft["hi"], phi0
        k = math.floor(phi0 / dt) + 1
        for _ in range(100 * round(T / dt)):       # bounded: each stretch ends at an event,
            t1 = min(k * dt, phi0 + T)             # a sample or the end of the period
            soft_edge.direction = -1.0 if engaged else 1.0
            sol = solve_ivp(rhs, (t, t1), y, method="DOP853", rtol=1e-11, atol=1e-13,
                            events=(soft_edge, hard_edge), args=(engaged, u))
            t, y = sol.t[-1], sol.y[:, -1].copy()
            if sol.status == 1 and sol.t_events[0].size:
                engaged = not engaged
            elif sol.status == 1:                  # Newton's law at the rigid stop
                y[3] = -hard["restitution"] * y[3]
            elif t >= phi0 + T:
                return np.array([y[0], y[2], y[1], y[3], u])
            else:                                  # a sample instant
                u, k = held(t, y), k + 1
        raise RuntimeError("the naive period map did not reach the end of the period")

    return period_map
