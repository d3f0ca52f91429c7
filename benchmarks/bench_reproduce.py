"""The reproduction's speed: ``hybridpd reproduce`` (quick) within 60 s wall and 90 s of CPU
on 2 idle cores, warm.

Runs the command three times, each in a fresh process on one new code cache (the compiled
numba and interval kernels): **cold** (the cache empty: every kernel compiled), **warm** (the
same cache, filled by the cold run), and the **naive** way, warm too: the same run in one
process (``--executor serial``: the certified shares, the traced boundaries and the basins
one after the other instead of in two background processes meanwhile). Prints each run's wall
time and CPU time (user + sys of the command and its worker processes: on a shared machine
the wall time mostly measures the other jobs), the ratio naive / warm, and the warm run's
per-step timings from ``summary.json``.

Run: ``python benchmarks/bench_reproduce.py [--full] [--no-naive] [OUTDIR]``.
"""
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _run(args, cache):
    """``(wall, cpu)`` of ``hybridpd reproduce ARGS`` in a fresh process on ``cache``."""
    env = dict(os.environ, HYBRIDPD_CACHE_DIR=str(cache), XDG_CACHE_HOME=str(cache))
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "hybridpd", "reproduce", *args], env=env, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return wall, cpu


def main(full=False, out=None, naive=True):
    out = Path(out or tempfile.mkdtemp(prefix="bench-reproduce-"))
    cache = Path(tempfile.mkdtemp(prefix="bench-reproduce-cache-"))
    mode = ["--full"] if full else []
    name = "full" if full else "quick"
    runs = {"cold": ["--out", str(out / "cold"), *mode],
            "warm": ["--out", str(out / "warm"), *mode]}
    if naive:
        runs["naive (serial, warm)"] = ["--out", str(out / "serial"), "--executor", "serial",
                                        *mode]
    times = {}
    for label, args in runs.items():
        times[label] = _run(args, cache)
        wall, cpu = times[label]
        print(f"reproduce --{name}, {label}: wall {wall:.1f} s, CPU {cpu:.1f} s", flush=True)
    wall, cpu = times["warm"]
    if not full:
        ok = wall <= 60.0 and cpu <= 90.0
        print(f"warm against the target (60 s wall, 90 s CPU on 2 idle cores): "
              f"{'OK' if ok else 'SLOW'} (load average {os.getloadavg()[0]:.1f})")
    if naive:
        nw, nc = times["naive (serial, warm)"]
        print(f"naive / warm: wall {nw / wall:.2f}x, CPU {nc / cpu:.2f}x")
    data = json.loads((out / "warm" / "summary.json").read_text())
    print("warm run, per step:")
    for k, v in data["timings"].items():
        print(f"  {k}: {v:.2f} s")
    for r in data["runs"]:
        for k, v in r["timings"].items():
            print(f"  m2 = {r['m2']:g}, {k}: {v:.2f} s")
    return times


if __name__ == "__main__":
    argv = sys.argv[1:]
    rest = [a for a in argv if not a.startswith("--")]
    main(full="--full" in argv, out=rest[0] if rest else None, naive="--no-naive" not in argv)
