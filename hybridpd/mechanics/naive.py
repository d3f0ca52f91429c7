"""An independent reference: a ``solve_ivp`` loop with terminal events for PD-controlled
mechanical systems with rigid contacts.

Written from the equations, not from the automaton: the right-hand side evaluates
``M q'' = -C q' - K q + B u`` with ``u = m_ff xd'' + kp (xd - c.q) + kv (xd' - c.v)`` and
``xd = a cos(w t)`` directly, each contact bound is a terminal event, and an impact solves
for the impulse ``P`` along ``w`` with ``w . (v + P M^-1 w) = -e w . v``. A compliant contact
adds its Kelvin-Voigt force while penetrated (the integration restarts where the penetration
changes sign; engagements are recorded like impacts, with ``post = pre``); a sampled PD
holds ``u`` between samples (the integration restarts at each). It has no sticking (it stops
when impacts pile up at one instant) and can miss two crossings within one step.
It exists for the tests and as the benchmarks' baseline.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from hybridpd._results import compact_repr

__all__ = ["NaiveMechanicalResult", "naive_mechanical"]


@dataclass(frozen=True)
class NaiveMechanicalResult:
    """Impacts found by :func:`naive_mechanical`.

    Attributes
    ----------
    impact_times : ndarray, shape (k,)
    contacts, walls : ndarray of int, shape (k,)
    pre, post : ndarray, shape (k, 2n)
        Mechanical states ``[q_1, v_1, ...]`` before / after each impact (or compliant
        engagement).
    t_final : float
    n_rhs : int
        Right-hand-side evaluations.
    stopped : str
        ``"end_time"``, ``"max_impacts"`` or ``"pile_up"`` (impacts at one instant).
    """

    impact_times: np.ndarray
    contacts: np.ndarray
    walls: np.ndarray
    pre: np.ndarray
    post: np.ndarray
    t_final: float
    n_rhs: int
    stopped: str
    __repr__ = compact_repr


def naive_mechanical(M, C, K, B, contacts, kp, kv, measure, amplitude, omega, feedforward,
                     x0, t_span, max_impacts=1000, rtol=1e-12, atol=1e-13,
                     method="DOP853", dt=0.0) -> NaiveMechanicalResult:
    """Simulate with ``solve_ivp`` (see the module docstring).

    Parameters
    ----------
    M, C, K : array_like, shape (n, n)
    B, measure : array_like, shape (n,)
        Input direction and measured direction ``c``.
    contacts : sequence of (normal, lo, hi, e) or (normal, lo, hi, None, k, c)
        Rigid (restitution ``e``) or Kelvin-Voigt (stiffness ``k``, damping ``c``);
        ``lo`` / ``hi`` may be None.
    kp, kv, amplitude, omega, feedforward : float
    x0 : array_like, shape (2n,)
        ``[q_1, v_1, ..., q_n, v_n]``.
    t_span : (float, float)
    max_impacts : int
    rtol, atol, method
        Passed to :func:`scipy.integrate.solve_ivp`.
    dt : float
        Sampling period of a zero-order-hold PD (0: continuous). Samples at ``t0 + k dt``,
        the first at ``t0``.
    """
    M = np.asarray(M, float)
    n = M.shape[0]
    rhs, law = _equations(M, C, K, B, contacts, kp, kv, measure, amplitude, omega,
                          feedforward)
    events, meta = _events(contacts)
    # compliant bounds are watched for engagement while free and for release while engaged
    # (a fixed direction per segment: the restart point, on the bound, is not an event)
    engaged = {i: False for i, (_, _, _, e) in enumerate(meta) if e is None}
    t0, t_end = float(t_span[0]), float(t_span[1])
    t, x = t0, np.asarray(x0, float).copy()
    rec = {"t": [], "k": [], "wall": [], "pre": [], "post": []}
    n_rhs, stopped, last, k_sample = 0, "end_time", -np.inf, 0
    held = law(t0, x) if dt > 0 else None
    while t < t_end:
        if len(rec["t"]) >= max_impacts:
            stopped = "max_impacts"
            break
        t_stop = min(t_end, t0 + (k_sample + 1) * dt) if dt > 0 else t_end
        for i, on in engaged.items():
            events[i].direction = 1 if on else -1
        sol = solve_ivp(rhs, (t, t_stop), x, method=method, rtol=rtol, atol=atol,
                        events=events, args=(held,))
        n_rhs += sol.nfev
        if sol.status != 1:
            if sol.status < 0:
                raise RuntimeError(f"solve_ivp failed: {sol.message}")
            t, x = t_stop, sol.y[:, -1].copy()
            if dt > 0 and t < t_end:
                k_sample += 1
                held = law(t, x)
            continue
        i = min((j for j in range(len(events)) if sol.t_events[j].size),
                key=lambda j: sol.t_events[j][0])
        t_ev = float(sol.t_events[i][0])
        k, wall, w, e = meta[i]
        pre = sol.y_events[i][0].copy()
        post = pre
        if e is None:                        # compliant engagement or release: just restart
            engaged[i] = not engaged[i]
            t, x = t_ev, pre
            if not engaged[i]:
                continue
        else:
            if t_ev - last < 1e-12 * max(1.0, abs(t_ev)):
                t, stopped = t_ev, "pile_up"
                break
            mw = np.linalg.solve(M, w)
            post = pre.copy()
            post[1::2] += -(1.0 + e) * (w @ pre[1::2]) / (w @ mw) * mw
            t, x, last = t_ev, post, t_ev
        for key, val in (("t", t_ev), ("k", k), ("wall", wall), ("pre", pre), ("post", post)):
            rec[key].append(val)
    return NaiveMechanicalResult(
        np.asarray(rec["t"], float), np.asarray(rec["k"], int), np.asarray(rec["wall"], int),
        np.asarray(rec["pre"], float).reshape(-1, 2 * n),
        np.asarray(rec["post"], float).reshape(-1, 2 * n), t, n_rhs, stopped)


def _equations(M, C, K, B, contacts, kp, kv, measure, amplitude, omega, feedforward):
    """``rhs(t, x, held)`` and the control law ``law(t, x)``, written from the model."""
    C, K = np.asarray(C, float), np.asarray(K, float)
    B, c = np.asarray(B, float), np.asarray(measure, float)
    n = M.shape[0]
    Minv = np.linalg.inv(M)
    soft = [(np.asarray(w, float), lo, hi, k_, c_) for w, lo, hi, e, *kc in contacts
            if e is None for k_, c_ in [kc]]

    def law(t, x):
        q, v = x[0::2], x[1::2]
        xd = amplitude * np.cos(omega * t)
        vd = -amplitude * omega * np.sin(omega * t)
        ad = -amplitude * omega ** 2 * np.cos(omega * t)
        return feedforward * ad + kp * (xd - c @ q) + kv * (vd - c @ v)

    def rhs(t, x, held):
        q, v = x[0::2], x[1::2]
        u = law(t, x) if held is None else held
        f = -C @ v - K @ q + B * u
        for w, lo, hi, k_, c_ in soft:
            s = w @ q
            if hi is not None and s > hi:
                f = f - (k_ * (s - hi) + c_ * (w @ v)) * w
            if lo is not None and s < lo:
                f = f - (k_ * (s - lo) + c_ * (w @ v)) * w
        out = np.empty(2 * n)
        out[0::2], out[1::2] = v, Minv @ f
        return out

    return rhs, law


def _events(contacts):
    """One terminal event per contact bound (positive inside the gap) and its meaning."""
    events, meta = [], []
    for k, (w, lo, hi, e, *_) in enumerate(contacts):
        w = np.asarray(w, float)
        for wall, bound in ((-1, lo), (1, hi)):
            if bound is None:
                continue

            def ev(t, x, held, w=w, wall=wall, bound=bound):
                return wall * (bound - w @ x[0::2])
            ev.terminal = True
            ev.direction = -1
            events.append(ev)
            meta.append((k, wall, w, e))
    return events, meta
