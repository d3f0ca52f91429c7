"""Modes on demand at scale: a chain of N masses with m = N - 1 clearances.

System (:func:`hybridpd.mechanics.samples.mass_chain`): unit masses, neighbours joined by a
spring (20) and damper (0.1) in parallel with a rigid clearance of +-0.05 (e = 0.8), a PD
loop (kp 50, kv 5) on the first mass tracking ``cos 3 t``. With m contacts there are up to
3^m modes; only the ones a run visits are built.

Printed, for m = 1 ... 30 (``--ms`` to choose): the time to build the model, the first run
(mode builds and kernel start included) and a repeated run of 1000 impacts, the modes built,
the memory of the kernel's tables, microseconds per impact, and the same cost of the naive
``solve_ivp`` loop (:mod:`hybridpd.mechanics.naive`: DOP853, rtol 1e-10, atol 1e-12, terminal
events, restarted at every impact; it has no sticking, so it runs until impacts pile up or
``--naive-impacts`` impacts) with the ratio. Then, in a fresh process for m = 30: start-up
(imports, model, first run of 1000 impacts) wall time and peak memory (targets: model under
1 s, everything under 10 s and 1 GB); and the first simulation of a first-ever run (empty
compiled-code cache) against the next fresh process.

Run: ``python benchmarks/bench_chain.py [--ms 1,2,...] [--naive-impacts 60]``.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from hybridpd.mechanics import simulate
from hybridpd.mechanics.naive import naive_mechanical
from hybridpd.mechanics.samples import chain_matrices, mass_chain

N_IMPACTS = 1000

_COLD = """
import resource, time
t0 = time.perf_counter()
import numpy as np
from hybridpd.mechanics import simulate
from hybridpd.mechanics.samples import mass_chain
t1 = time.perf_counter()
ma = mass_chain(31)
t2 = time.perf_counter()
tr = simulate(ma, np.zeros(62), (0.0, 1e4), max_impacts=1000)
t3 = time.perf_counter()
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(f"{t1 - t0:.3f} {t2 - t1:.3f} {t3 - t2:.3f} {rss:.0f} {tr.n_impacts} {ma.automaton.n_built}")
"""


def naive_cost(m, n_impacts):
    M, C, K, B = chain_matrices(m + 1)
    eye = np.eye(m + 1)
    contacts = [(eye[i] - eye[i + 1], -0.05, 0.05, 0.8) for i in range(m)]
    t0 = time.perf_counter()
    r = naive_mechanical(M, C, K, B, contacts, 50.0, 5.0, eye[0], 1.0, 3.0, 0.0,
                         np.zeros(2 * (m + 1)), (0.0, 1e4), max_impacts=n_impacts,
                         rtol=1e-10, atol=1e-12)
    el = time.perf_counter() - t0
    return el / max(len(r.impact_times), 1), len(r.impact_times)


def row(m, naive_impacts):
    t0 = time.perf_counter()
    ma = mass_chain(m + 1)
    t_load = time.perf_counter() - t0
    x0 = np.zeros(2 * (m + 1))
    t0 = time.perf_counter()
    tr = simulate(ma, x0, (0.0, 1e4), max_impacts=N_IMPACTS)
    t_first = time.perf_counter() - t0
    t0 = time.perf_counter()
    tr = simulate(ma, x0, (0.0, 1e4), max_impacts=N_IMPACTS)
    t_run = time.perf_counter() - t0
    us = t_run / max(tr.n_impacts, 1) * 1e6
    nv, nn = naive_cost(m, naive_impacts) if naive_impacts else (np.nan, 0)
    print(f"{m:3d} {t_load:8.3f} {t_first:8.3f} {t_run:8.3f} {tr.n_impacts:6d} "
          f"{len(tr.sticking):5d} {ma.automaton.n_built:6d} "
          f"{ma.automaton.table_bytes / 1e6:8.1f} {us:8.1f} {nv * 1e6:10.0f} {nn:5d} "
          f"{nv * 1e6 / us:7.0f}x", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ms", default=",".join(str(m) for m in range(1, 31)))
    ap.add_argument("--naive-impacts", type=int, default=60)
    ap.add_argument("--no-cold", action="store_true")
    args = ap.parse_args(argv)
    ms = [int(s) for s in args.ms.split(",")]
    mass_chain(2)                      # imports python-control once, outside the table
    print(f"chain with m clearances, {N_IMPACTS} impacts (jumps) per run")
    print("  m  load[s] first[s]   run[s] jumps stick  modes table[MB] us/jump "
          "naive[us] n_nv   ratio")
    for m in ms:
        row(m, args.naive_impacts)
    if not args.no_cold:
        out = subprocess.run([sys.executable, "-c", _COLD], capture_output=True, text=True,
                             check=True).stdout.split()
        imp, model, run, rss, nimp, built = out
        print(f"fresh process, m = 30: imports {imp} s, model {model} s, first run of {nimp} "
              f"jumps {run} s ({built} modes built), peak RSS {rss} MB")
        # the compiled-code cache: a first-ever run (empty cache) against the next process
        with tempfile.TemporaryDirectory() as d:
            env = dict(os.environ, HYBRIDPD_NUMBA_CACHE_DIR=str(Path(d) / "nb"))
            for label in ("first run ever (compiles)", "next process (cache)"):
                r = subprocess.run([sys.executable, "-c", _COLD], capture_output=True,
                                   text=True, check=True, env=env)
                run = r.stdout.split()[2]
                said = "says it compiles" if "compiling" in r.stderr else "silent"
                print(f"numba cache, {label}: first simulation {run} s ({said})")


if __name__ == "__main__":
    main()
