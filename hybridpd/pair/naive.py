"""The naive reference: a ``scipy.integrate.solve_ivp`` loop with terminal events.

This is what a user would write by hand: integrate the closed loop of
:mod:`hybridpd.loop` with an adaptive Runge-Kutta method, stop at the first wall event,
apply Newton's law and restart. It has no sticking mode (it would chatter until
``max_impacts``), and it can miss two crossings inside one step. It exists as an
independent cross-check for the tests and as the baseline of the benchmarks.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from hybridpd._results import compact_repr
from hybridpd.loop import ClosedLoop

__all__ = ["NaiveResult", "naive_simulate"]


@dataclass(frozen=True)
class NaiveResult:
    """Impacts found by :func:`naive_simulate`.

    Attributes
    ----------
    impact_times : ndarray, shape (k,)
    walls : ndarray of int, shape (k,)
    pre, post : ndarray, shape (k, n)
        Full closed-loop states before/after each impact.
    state_final : ndarray, shape (n,)
    t_final : float
    n_rhs : int
        Right-hand-side evaluations (a machine-independent cost measure).
    """

    impact_times: np.ndarray
    walls: np.ndarray
    pre: np.ndarray
    post: np.ndarray
    state_final: np.ndarray
    t_final: float
    n_rhs: int
    __repr__ = compact_repr


def naive_simulate(loop: ClosedLoop, z0, t_span, max_impacts: int = 1000, *,
                   method: str = "DOP853", rtol: float = 1e-10, atol: float = 1e-12,
                   first_step=None) -> NaiveResult:
    """Simulate the free-flight/impact cycle with ``solve_ivp`` and terminal events.

    Parameters
    ----------
    loop : ClosedLoop
        Closed loop (``loop.A``) and plant (``loop.pair``).
    z0 : array_like, shape (n,)
        Full initial state (see :meth:`ClosedLoop.initial_state`).
    t_span : (float, float)
    max_impacts : int
        Stop after this many impacts.
    method, rtol, atol, first_step
        Passed to :func:`scipy.integrate.solve_ivp`.
    """
    A = np.asarray(loop.A, float)
    L = loop.pair.L
    n = A.shape[0]
    E = np.eye(n)
    E[np.ix_([1, 3], [1, 3])] = loop.pair.velocity_jump_matrix()

    def rhs(t, z):
        return A @ z

    def right(t, z):
        return L - (z[0] - z[2])

    def left(t, z):
        return (z[0] - z[2]) + L

    for ev in (right, left):
        ev.terminal = True
        ev.direction = -1

    t, t_end = float(t_span[0]), float(t_span[1])
    z = np.asarray(z0, float).copy()
    times, walls, pres, posts = [], [], [], []
    n_rhs = 0
    while t < t_end and len(times) < max_impacts:
        sol = solve_ivp(rhs, (t, t_end), z, method=method, rtol=rtol, atol=atol,
                        events=(right, left), first_step=first_step)
        n_rhs += sol.nfev
        if sol.status == 1:
            k = 0 if sol.t_events[0].size else 1
            t = float(sol.t_events[k][0])
            zpre = sol.y_events[k][0].copy()
            zpost = E @ zpre
            times.append(t)
            walls.append(+1 if k == 0 else -1)
            pres.append(zpre)
            posts.append(zpost)
            z = zpost
        elif sol.status == 0:
            t, z = t_end, sol.y[:, -1].copy()
        else:
            raise RuntimeError(f"solve_ivp failed: {sol.message}")
    return NaiveResult(np.asarray(times), np.asarray(walls, int), np.asarray(pres).reshape(-1, n),
                       np.asarray(posts).reshape(-1, n), z, t, n_rhs)
