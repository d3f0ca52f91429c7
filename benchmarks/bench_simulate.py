"""Benchmark: 3000 impacts of the collocated impact pair, hybridpd vs the naive loop.

Case: mu 0.1, e 0.5, L 0.75, omega 5, kp 10, kv 20, xm 1, x0 = (0.3, 0.5, 0, 0). The naive
loop is solve_ivp (DOP853, rtol 1e-10, atol 1e-12) with terminal events, restarted after each
impact. Both run here; the script prints wall times, the per-impact ratio (target >= 100x),
and two accuracy figures:

* the largest impact-time difference over the whole run. This trajectory is a chaotic
  transient, so two correct solvers separate exponentially (about x10 every 5 impacts) and
  the global figure only measures where they part;
* the largest per-flight error: each flight restarted from hybridpd's post-impact state (local
  accuracy, which is what "equal or better accuracy" means here) for both hybridpd and the
  naive solver, against the closed-form flight of :mod:`hybridpd.pair.batch` located to a gap
  tolerance of 1e-15 (an independent method, exact up to rounding).

Run: ``python benchmarks/bench_simulate.py``.
"""
import time

import numpy as np
from scipy.integrate import solve_ivp

from hybridpd import ImpactPair, PDGains, Reference
from hybridpd.pair.impactpair import ControlledImpactPair
from hybridpd.pair.naive import naive_simulate

N = 3000


def flight(cl, z0, rtol, atol):
    L = cl.pair.L

    def right(t, z):
        return L - (z[0] - z[2])

    def left(t, z):
        return z[0] - z[2] + L

    for ev in (right, left):
        ev.terminal, ev.direction = True, -1
    sol = solve_ivp(lambda t, z: cl.A @ z, (0, 50.0), z0, method="DOP853", rtol=rtol, atol=atol,
                    events=(right, left))
    k = 0 if sol.t_events[0].size else 1
    return float(sol.t_events[k][0])


def main():
    sysm = ControlledImpactPair(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), Reference(1.0, 5.0),
                                "collocated")
    x0 = [0.3, 0.5, 0.0, 0.0]
    # The first long run loads numba and the cached kernels (short runs are interpreted and
    # would not): timed separately, the ratio is per impact in the steady state.
    t0 = time.perf_counter()
    sysm.simulate(x0, (0.0, 1e6), max_impacts=N)
    t_first = time.perf_counter() - t0
    t0 = time.perf_counter()
    traj = sysm.simulate(x0, (0.0, 1e6), max_impacts=N)
    t_h = time.perf_counter() - t0
    print(f"first run in this process (numba and kernel cache load included): {t_first:.3f} s")
    n = traj.n_impacts
    t0 = time.perf_counter()
    ref = naive_simulate(sysm.loop, sysm.initial_state(x0), (0.0, 1e6), max_impacts=N,
                         rtol=1e-10, atol=1e-12)
    t_n = time.perf_counter() - t0
    m = min(n, len(ref.impact_times))
    diff = np.abs(traj.impact_times[:m] - ref.impact_times[:m])
    part = int(np.argmax(diff > 1e-6)) if np.any(diff > 1e-6) else m
    print(f"hybridpd (automaton): {n} impacts in {t_h:.3f} s = {t_h / n * 1e6:.1f} us/impact")
    print(f"naive solve_ivp loop: {len(ref.impact_times)} impacts in {t_n:.2f} s = "
          f"{t_n / len(ref.impact_times) * 1e6:.0f} us/impact")
    print(f"ratio per impact: {t_n / len(ref.impact_times) / (t_h / n):.0f}x (target >= 100x)")
    print(f"largest impact-time difference over the run: {diff.max():.3g} (the runs agree to "
          f"1e-6 up to impact {part}: chaotic transient)")
    # local accuracy, flight by flight from hybridpd's post-impact states
    from hybridpd.pair.batch import Flight, next_impact, pack_params

    cl = sysm.loop
    p = pack_params(10, 20, 1, 0.1, 0.5, 0.75, 5.0, 1.0)
    idx = np.linspace(0, n - 2, 100).astype(int)
    err_h, err_n = [], []
    for k in idx:
        t_k = traj.impact_times[k]
        exact = next_impact(p, 0, Flight(t_k, *traj.post[k]), 50.0, 1e-15)[1]
        z0 = cl.initial_state(traj.post[k], t_k)
        err_h.append(abs(traj.impact_times[k + 1] - t_k - exact))
        err_n.append(abs(flight(cl, z0, 1e-10, 1e-12) - exact))
    print(f"per-flight impact-time error vs the closed form (100 flights): hybridpd "
          f"{max(err_h):.2g}, naive solve_ivp (rtol 1e-10) {max(err_n):.2g}")


if __name__ == "__main__":
    main()
