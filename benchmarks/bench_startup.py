"""Cold start of the command line against ``python -c "import numpy, scipy.linalg"``.

Target: a cold ``hybridpd orbit`` and a cold short ``hybridpd simulate`` (30 impacts) each
within 2.5 times the start-up of Python with NumPy and ``scipy.linalg`` on the same machine.
"Cold" is a new process with the generated closed-form code already in its cache (it is
generated once per installation and version); one extra run first fills the cache. Each
command runs ``--repeat`` times, interleaved with the baseline so that load from other
processes affects all of them alike; min/median/max and the ratios of the medians and of the
minima are printed, and the modules the commands loaded (python-control, numba, SymPy,
matplotlib, scipy.signal should be absent). Run: ``python benchmarks/bench_startup.py``
(``--repeat N``, default 7).
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

BASELINE = [sys.executable, "-c", "import numpy, scipy.linalg"]
ORBIT = [sys.executable, "-m", "hybridpd", "orbit", "--case", "collocated", "--mu", "0.1",
         "--e", "0.5", "--omega", "5", "--L", "0.75", "--kp", "10", "--kv", "20"]
SIMULATE = [sys.executable, "-m", "hybridpd", "simulate", "--case", "collocated", "--mu",
            "0.1", "--e", "0.5", "--omega", "5", "--L", "0.75", "--xm", "1", "--kp", "10",
            "--kv", "20", "--x0", "0", "0", "0", "0", "--t-end", "100", "--max-impacts", "30"]
HEAVY = ("control", "numba", "sympy", "matplotlib", "scipy.signal")


def _time(cmd, env) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t0


_PROBE = """
import runpy, sys
heavy = sys.argv[1].split(",")
sys.argv = ["hybridpd"] + sys.argv[2:]
try:
    runpy.run_module("hybridpd", run_name="__main__")
except SystemExit:
    pass
print(sorted(h for h in heavy if h in sys.modules), file=sys.stderr)
"""


def _heavy_modules(cmd, env) -> str:
    """Heavy modules loaded by the command (run under ``runpy`` in a child process)."""
    r = subprocess.run([sys.executable, "-c", _PROBE, ",".join(HEAVY), *cmd[3:]], env=env,
                       capture_output=True, text=True, check=True)
    return r.stderr.strip().splitlines()[-1]


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeat", type=int, default=7, help="runs of each command (default 7)")
    args = p.parse_args(argv)
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    for cmd in (ORBIT, SIMULATE):  # fill the generated-code cache
        subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL)
    times = {"baseline": [], "orbit": [], "simulate": []}
    for _ in range(args.repeat):
        times["baseline"].append(_time(BASELINE, env))
        times["orbit"].append(_time(ORBIT, env))
        times["simulate"].append(_time(SIMULATE, env))
    base_med = statistics.median(times["baseline"])
    base_min = min(times["baseline"])
    print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f} "
          "(other processes on the machine inflate and scatter all figures)")
    for name, ts in times.items():
        med = statistics.median(ts)
        line = (f"{name:9s}: min {min(ts):.3f} s, median {med:.3f} s, max {max(ts):.3f} s "
                f"({len(ts)} runs)")
        if name != "baseline":
            line += (f"; ratio to baseline: median {med / base_med:.2f}, "
                     f"min {min(ts) / base_min:.2f} (target <= 2.5)")
        print(line)
    print("heavy modules loaded by orbit:", _heavy_modules(ORBIT, env))
    print("heavy modules loaded by simulate:", _heavy_modules(SIMULATE, env))


if __name__ == "__main__":
    main()
