"""Region maps of a model file: one process, a process pool, a two-worker Dask cluster, and
the cost per grid point against a naive ``scipy.optimize.root`` on a ``solve_ivp`` return map.

Run ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_model_regions.py [--n 100]``. Prints

* the wall time of an ``n x n`` region map of ``examples/models/drivetrain.toml`` over
  ``(controller.kp, controller.kv)`` (section on the backlash's sticking releases, the orbits
  of one reference period) serially, on a process pool of 2 and on a cluster of a real
  ``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1 (started and stopped here),
  with the speed-up against the serial run and the time per grid point; the three maps must be
  identical;
* the cost per grid point of a naive loop, ``scipy.optimize.root`` (hybr) on a return map
  computed with ``solve_ivp`` (DOP853, rtol 1e-10, terminal impact events), against this
  package's per-point cost on the same grid of the impact pair written as a model file (the
  naive return map has no sticking, which the drivetrain's orbits need), and the largest
  difference of the fixed points found.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np


def _model_region_map():
    """A model file's region map as ``f(model, x, y, event=..., ...)``, on this version (the
    one region map over a model's search) and on earlier ones (for comparison)."""
    try:
        from hybridpd.sweeps.model_regions import ModelSearch
        from hybridpd.sweeps.regions import region_map
    except ImportError:
        from hybridpd.sweeps.model_regions import model_region_map

        return model_region_map
    names = set(ModelSearch.__dataclass_fields__)

    def model_region_map(model, x, y, **kw):
        fam = ModelSearch(model, **{k: kw.pop(k) for k in list(kw) if k in names})
        return region_map(fam, x, y, **kw)

    return model_region_map

ROOT = Path(__file__).resolve().parents[1]
DRIVETRAIN = ROOT / "examples" / "models" / "drivetrain.toml"
PAIR = {
    "system": {"dofs": ["x1", "x2"], "masses": [0.1, 1.0], "input": [0.0, 1.0]},
    "contact": [{"between": ["x1", "x2"], "lo": -0.75, "hi": 0.75, "restitution": 0.5}],
    "controller": {"type": "pd", "kp": 10.0, "kv": 20.0, "measure": "x2"},
    "reference": {"type": "sine", "amplitude": 0.4, "omega": 5.0, "feedforward_mass": 1.0},
    "initial": {"q": [0.3, 0.0], "v": [0.5, 0.0]}}


def _map(n, executor, workers=None):
    model_region_map = _model_region_map()

    t0 = time.perf_counter()
    rm = model_region_map(DRIVETRAIN, ("controller.kp", 5.0, 80.0, n),
                          ("controller.kv", 1.0, 25.0, n), event="release",
                          executor=executor, max_workers=workers, progress=False)
    return time.perf_counter() - t0, rm


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _cluster(n_workers=2):
    dask = shutil.which("dask", path=os.path.dirname(sys.executable)) or shutil.which("dask")
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1")
    port = _free_port()
    addr = f"tcp://127.0.0.1:{port}"
    procs = [subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", str(port),
                               "--dashboard-address", ":0"], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    for k in range(n_workers):
        procs.append(subprocess.Popen([dask, "worker", addr, "--nthreads", "1", "--no-nanny",
                                       "--host", "127.0.0.1", "--name", f"b{k}",
                                       "--dashboard-address", ":0"], env=env,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
    from distributed import Client

    with Client(addr, timeout="60s", set_as_default=False) as c:
        c.wait_for_workers(n_workers, timeout=60)
    return addr, procs


def _stop(procs):
    for p in reversed(procs):
        if p.poll() is None:
            p.terminate()
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait(timeout=10)


def _same(a, b):
    return (np.array_equal(a.status, b.status)
            and np.array_equal(a.spectral_radius, b.spectral_radius, equal_nan=True)
            and np.array_equal(a.section_point, b.section_point, equal_nan=True))


def _naive_point(kp, kv, s0, T):
    """Fixed point of the pair's return map by scipy root on a solve_ivp map."""
    from scipy.optimize import root

    from hybridpd.mechanics.naive import naive_mechanical

    M = np.diag([0.1, 1.0])
    w = np.array([1.0, -1.0])
    mw = np.linalg.solve(M, w)

    def P(s):     # s = (phi, x1_dot, x2, x2_dot) pre-impact on the wall x1 - x2 = 0.75
        phi, y1, x2, y2 = s
        x = np.array([x2 + 0.75, y1, x2, y2])
        x[1::2] += -1.5 * (w @ x[1::2]) / (w @ mw) * mw
        r = naive_mechanical(M, np.zeros((2, 2)), np.zeros((2, 2)), [0.0, 1.0],
                             [(w, -0.75, 0.75, 0.5)], kp, kv, [0, 1], 0.4, 5.0, 1.0, x,
                             (phi, phi + 3 * T), max_impacts=20, rtol=1e-10, atol=1e-12)
        hit = [i for i in range(len(r.impact_times)) if r.walls[i] == 1]
        if not hit:
            return np.full(4, 1e3)
        i = hit[0]
        t, pre = r.impact_times[i], r.pre[i]
        d = np.array([t - phi - T, pre[1] - y1, pre[2] - x2, pre[3] - y2])
        return d

    t0 = time.perf_counter()
    sol = root(P, s0, method="hybr", options={"xtol": 1e-10})
    return time.perf_counter() - t0, sol


def naive_comparison(n_side=10, n_naive=6):
    model_region_map = _model_region_map()

    t0 = time.perf_counter()
    rm = model_region_map(PAIR, ("controller.kp", 6.0, 14.0, n_side),
                          ("controller.kv", 15.0, 25.0, n_side), progress=False)
    ours = (time.perf_counter() - t0) / rm.status.size
    T = 2 * np.pi / 5.0
    rng = np.random.default_rng(0)
    # one layer (this version's region maps are indexed [layer, iy, ix]; earlier ones [iy, ix])
    exists = rm.exists[0] if rm.exists.ndim == 3 else rm.exists
    points = rm.section_point[0] if rm.section_point.ndim == 4 else rm.section_point
    cells = [tuple(c) for c in np.argwhere(exists)]
    pick = [cells[i] for i in rng.choice(len(cells), size=min(n_naive, len(cells)),
                                          replace=False)]
    times, err = [], 0.0
    for iy, ix in pick:
        s = points[iy, ix]
        guess = s + np.array([0.01, 0.02, -0.01, 0.02])     # a neighbour's distance
        dt, sol = _naive_point(rm.x[ix], rm.y[iy], guess, T)
        times.append(dt)
        if sol.success:
            err = max(err, float(np.max(np.abs(sol.x - s))))
    return ours, float(np.mean(times)), err, len(pick)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100, help="grid points per axis")
    ap.add_argument("--skip", nargs="*", default=[], choices=["serial", "pool", "cluster",
                                                               "naive"])
    args = ap.parse_args(argv)
    out = {"n": args.n, "cores": os.cpu_count()}
    _map(4, "serial")                       # numba's cache, imports: not timed
    ref = None
    if "serial" not in args.skip:
        t, ref = _map(args.n, "serial")
        out["serial_s"] = t
        print(f"serial: {t:.1f} s, {1e3 * t / args.n ** 2:.1f} ms per grid point; "
              f"{ref.summary()}", flush=True)
    if "pool" not in args.skip:
        t, rm = _map(args.n, "processes", 2)
        out["pool_s"] = t
        out["pool_identical"] = None if ref is None else _same(ref, rm)
        print(f"process pool (2): {t:.1f} s, {1e3 * t / args.n ** 2:.1f} ms per grid point"
              + (f", speed-up {out['serial_s'] / t:.2f}, identical {out['pool_identical']}"
                 if ref is not None else ""), flush=True)
    if "cluster" not in args.skip:
        addr, procs = _cluster(2)
        try:
            t, rm = _map(args.n, addr)
        finally:
            _stop(procs)
        out["cluster_s"] = t
        out["cluster_identical"] = None if ref is None else _same(ref, rm)
        print(f"dask cluster (2 workers): {t:.1f} s, {1e3 * t / args.n ** 2:.1f} ms per grid "
              "point" + (f", speed-up {out['serial_s'] / t:.2f}, identical "
                         f"{out['cluster_identical']}" if ref is not None else ""), flush=True)
    if "naive" not in args.skip:
        ours, naive, err, k = naive_comparison()
        out.update(pair_ours_ms=1e3 * ours, pair_naive_ms=1e3 * naive, naive_error=err)
        print(f"impact pair as a model file: {1e3 * ours:.1f} ms per grid point (map with "
              f"continuation); naive root + solve_ivp: {1e3 * naive:.1f} ms per point "
              f"({k} points, from a neighbour's distance), ratio {naive / ours:.1f}; largest "
              f"difference of the fixed points {err:.2e}", flush=True)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
