"""Cost per impact of the generic hybrid automaton vs a naive ``solve_ivp`` event loop.

Run ``python benchmarks/bench_automaton.py`` (after one warm-up run has filled numba's cache).
Prints microseconds of compute per impact for

* the forced oscillator against a stop (:func:`hybridpd.hybrid.samples.impact_oscillator`),
* the ball on a vibrating table (sticking and releases included),
* one raw kernel call (:func:`hybridpd.hybrid.events.advance`) from Python,
* a ``scipy.integrate.solve_ivp`` loop (DOP853, rtol = atol = 1e-12, terminal events) on the
  oscillator, and the largest difference of the impact times.
"""
from __future__ import annotations

import math
import time
import timeit

import numpy as np
from scipy.integrate import solve_ivp

from hybridpd.hybrid.events import advance, prepare_lti_mode
from hybridpd.hybrid.samples import (
    ball_initial_state,
    bouncing_ball,
    impact_oscillator,
    oscillator_initial_state,
)


def _time(fn, repeat=3):
    best = np.inf
    out = None
    for _ in range(repeat):
        # CPU time of this process: the figure is compute, robust to a busy machine
        t = time.process_time()
        out = fn()
        best = min(best, time.process_time() - t)
    return best, out


def bench_oscillator(T=20_000.0):
    w0, zeta, F, W, s, e = 1.0, 0.05, 1.0, 0.8, 0.5, 0.8
    ha = impact_oscillator(w0, zeta, F, W, s, e)
    x0 = oscillator_initial_state(0.0, 0.0, force=F, omega=W)
    ha.simulate(x0, "free", (0.0, 10.0))
    dt, tr = _time(lambda: ha.simulate(x0, "free", (0.0, T), max_jumps=10**6))
    return dt / len(tr.jumps) * 1e6, len(tr.jumps), tr.n_steps / len(tr.jumps)


def bench_ball(T=300.0):
    a, w = 0.01, 2 * math.pi * 8
    ha = bouncing_ball(e=0.5, amplitude=a, omega=w)
    x0 = ball_initial_state(0.0, 0.0, amplitude=a, omega=w, relative=True)
    ha.simulate(x0, "flight", (0.0, 1.0))
    dt, tr = _time(lambda: ha.simulate(x0, "flight", (0.0, T), max_jumps=10**6))
    return dt / len(tr.jumps) * 1e6, len(tr.jumps), tr.n_steps / len(tr.jumps)


def bench_kernel():
    md = prepare_lti_mode([[0.0, 1.0], [0.0, 0.0]], [0.0, -9.81], [([1.0, 0.0], 0.0, -1)])
    w0 = np.array([0.0, 1.0, 1.0])
    w_out = np.empty(3)
    args = (w0, 0.0, 5.0, md.flow_tables(), 0, 0.0, 10**6, w_out)
    advance(*args)
    n = 20_000
    timer = timeit.Timer(lambda: advance(*args), timer=time.process_time)
    return min(timer.repeat(3, n)) / n * 1e6


def bench_solve_ivp(T=400.0):
    w0, zeta, F, W, s, e = 1.0, 0.05, 1.0, 0.8, 0.5, 0.8

    def rhs(t, y):
        return [y[1], -w0 * w0 * y[0] - 2 * zeta * w0 * y[1] + F * math.cos(W * t)]

    def hit(t, y):
        return s - y[0]
    hit.terminal = True
    hit.direction = -1

    def run():
        t, y, times = 0.0, [0.0, 0.0], []
        while t < T:
            sol = solve_ivp(rhs, (t, T), y, method="DOP853", rtol=1e-12, atol=1e-12,
                            events=hit)
            if sol.status != 1:
                break
            t = float(sol.t_events[0][0])
            times.append(t)
            y = [s, -e * sol.y_events[0][0][1]]
        return np.array(times)

    dt, times = _time(run, repeat=1)
    ha = impact_oscillator(w0, zeta, F, W, s, e)
    tr = ha.simulate(oscillator_initial_state(0.0, 0.0, force=F, omega=W), "free", (0.0, T))
    n = min(times.size, len(tr.jumps))
    return dt / times.size * 1e6, times.size, float(np.max(np.abs(tr.jumps.t[:n] - times[:n])))


def main():
    us, n, spj = bench_oscillator()
    print(f"oscillator vs stop : {us:7.2f} us/impact  ({n} impacts, {spj:.1f} flow steps each)")
    us, n, spj = bench_ball()
    print(f"ball, vibrating    : {us:7.2f} us/jump    ({n} jumps incl. sticking/release)")
    print(f"advance() from Py  : {bench_kernel():7.2f} us/call    (one free flight, dispatch "
          f"included)")
    us, n, err = bench_solve_ivp()
    print(f"solve_ivp loop     : {us:7.1f} us/impact  ({n} impacts; max |dt_impact| vs "
          f"automaton {err:.1e})")


if __name__ == "__main__":
    main()
