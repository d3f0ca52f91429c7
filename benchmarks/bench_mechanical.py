"""The general mechanical path: 3000 impacts of an n = 3 drivetrain, hybridpd vs a naive loop.

System (angles in rad): a motor (inertia 1) drives a gear (0.2) through a flexible shaft
(stiffness 50, damping 0.2); the gear drives a light load (0.3) through a backlash of
+-0.75 rad, restitution 0.8. PD on the motor angle (kp 10, kv 20) tracking ``cos 5 t`` with
feed-forward 1.3 xd''. The load rattles in the backlash without ever sticking, so the naive
loop (which has no sticking mode) can follow it.

Both run here, from the same state: hybridpd's automaton (exact matrix-exponential flows,
guaranteed first-crossing location) and the naive loop of :mod:`hybridpd.mechanics.naive`
(``solve_ivp`` DOP853, rtol 1e-10, atol 1e-12, terminal events, restarted after every
impact). Printed: CPU time per impact of both, their ratio (target >= 100x), and accuracy:

* the largest impact-time difference over the run (the rattle is chaotic: two correct
  solvers part after some tens of impacts, so this only says where);
* per-flight accuracy ("equal or better accuracy"): 100 flights restarted from hybridpd's
  post-impact states, the next impact time by hybridpd and by the naive solver, against an
  independent reference (``scipy.linalg.expm`` of the closed loop on a fine grid, the first
  sign change of a gap refined by ``brentq`` to 1e-15).

Run: ``python benchmarks/bench_mechanical.py``.
"""
from __future__ import annotations

import time

import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq

from hybridpd.mechanics import (
    Contact,
    MechanicalSystem,
    Reference,
    build_automaton,
    mechanical_loop,
)
from hybridpd.mechanics.naive import naive_mechanical
from hybridpd.mechanics.simulate import simulate

N_IMPACTS = 3000
KS = 50.0
M = np.diag([0.3, 0.2, 1.0])
C = np.array([[0, 0, 0], [0, 0.2, -0.2], [0, -0.2, 0.2]])
K = np.array([[0, 0, 0], [0, KS, -KS], [0, -KS, KS]])
B = np.array([0.0, 0.0, 1.0])
W = np.array([1.0, -1.0, 0.0])
L, E = 0.75, 0.8
X0 = [0.3, 0.5, 0.0, 0.0, 0.0, 0.0]


def model():
    s = MechanicalSystem(["load", "gear", "motor"], M, C, K, B)
    loop = mechanical_loop(s, (10.0, 20.0), Reference.sine(1.0, 5.0, 1.3), "motor")
    return build_automaton(loop, [Contact(W, -L, L, restitution=E)])


def cpu(fn):
    t = time.process_time()
    out = fn()
    return time.process_time() - t, out


def reference_flight(A, gap_row, z0, t_max=20.0, h=2e-3):
    """Time to the first |gap| = L from z0 (exact flow by expm, grid + brentq)."""
    step = expm(A * h)
    z, t = z0.copy(), 0.0

    def g(tau):
        s = gap_row @ (expm(A * tau) @ z0)
        return L - abs(s)

    g_prev = g(0.0)
    while t < t_max:
        z = step @ z
        g_new = L - abs(gap_row @ z)
        if g_new <= 0.0 < g_prev:
            return brentq(g, t, t + h, xtol=1e-15, rtol=8.9e-16)
        t, g_prev = t + h, g_new
    return np.nan


def naive_flight(z_mech, t0):
    r = naive_mechanical(M, C, K, B, [(W, -L, L, E)], 10.0, 20.0, [0, 0, 1], 1.0, 5.0, 1.3,
                         z_mech, (t0, t0 + 20.0), max_impacts=1, rtol=1e-10, atol=1e-12)
    return r.impact_times[0] - t0


def main():
    ma = model()
    # The first long run loads numba and the cached kernels (short runs are interpreted and
    # would not): timed separately, the ratio is per impact in the steady state.
    t_first, _ = cpu(lambda: simulate(ma, X0, (0.0, 1e6), max_impacts=N_IMPACTS))
    print(f"first run in this process (numba and kernel cache load included): {t_first:.3f} s")
    t_h, traj = cpu(lambda: simulate(ma, X0, (0.0, 1e6), max_impacts=N_IMPACTS))
    n = traj.n_impacts
    assert n == N_IMPACTS and not traj.sticking, (n, traj.sticking)
    t_n, ref = cpu(lambda: naive_mechanical(M, C, K, B, [(W, -L, L, E)], 10.0, 20.0,
                                            [0, 0, 1], 1.0, 5.0, 1.3, X0, (0.0, 1e6),
                                            max_impacts=N_IMPACTS, rtol=1e-10, atol=1e-12))
    m = min(n, len(ref.impact_times))
    diff = np.abs(traj.impact_times[:m] - ref.impact_times[:m])
    part = int(np.argmax(diff > 1e-6)) if np.any(diff > 1e-6) else m
    per_h, per_n = t_h / n, t_n / len(ref.impact_times)
    print(f"n = 3 drivetrain, {n} impacts (load rattling in the backlash, no sticking)")
    print(f"hybridpd (automaton):  {t_h:.3f} s CPU = {per_h * 1e6:.1f} us/impact")
    print(f"naive solve_ivp loop:  {t_n:.2f} s CPU = {per_n * 1e6:.0f} us/impact "
          f"({len(ref.impact_times)} impacts, {ref.n_rhs} rhs evaluations)")
    print(f"ratio per impact: {per_n / per_h:.0f}x (target >= 100x)")
    print(f"largest impact-time difference over the run: {diff.max():.3g} (the runs agree to "
          f"1e-6 up to impact {part}: chaotic rattle)")
    A = ma.loop.A
    gap_row = ma.gap_rows[0]
    idx = np.linspace(0, n - 2, 100).astype(int)
    err_h, err_n = [], []
    for k in idx:
        t_k = traj.impact_times[k]
        z0 = ma.initial_state(traj.post[k][0::2], traj.post[k][1::2], t_k)
        exact = reference_flight(A, gap_row, z0)
        err_h.append(abs(traj.impact_times[k + 1] - t_k - exact))
        err_n.append(abs(naive_flight(traj.post[k], t_k) - exact))
    print(f"per-flight impact-time error vs the expm/brentq reference (100 flights): hybridpd "
          f"{max(err_h):.2g}, naive solve_ivp (rtol 1e-10) {max(err_n):.2g}")
    gear_train()


def gear_train():
    """The shipped two-stage gear train (coupled M, both meshes held for long phases): cost
    per impact of the general path with sticking (the naive loop cannot run it)."""
    from pathlib import Path

    from hybridpd.mechanics.modelfile import load_model

    m = load_model(Path(__file__).resolve().parents[1] / "examples" / "models" /
                   "gear_train.toml")
    # warm-up with the timed run itself: a short run is interpreted, and the modes a run
    # visits are built the first time it enters them (both would be timed otherwise)
    m.simulate(1e6, max_impacts=3000)
    t, tr = cpu(lambda: m.simulate(1e6, max_impacts=3000))
    held = sum(b - a for a, b, _ in tr.sticking)
    print(f"gear train (2 clearances, coupled M): {tr.n_impacts} impacts, "
          f"{len(tr.sticking)} sticking phases (mesh-seconds held: {held:.0f} in "
          f"{tr.t_final:.0f} s; 3000 jumps in all) in {t:.3f} s CPU = "
          f"{t / max(tr.n_impacts, 1) * 1e6:.1f} us/impact")


if __name__ == "__main__":
    main()
