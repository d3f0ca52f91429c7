"""Import time of the flat namespace, against ``python -c "import numpy"``.

Targets: ``import hybridpd`` under 0.1 s and loading none of numba, SymPy, python-control,
matplotlib, xarray; the general names (``hp.find_orbit``, ``hp.SectionMap``,
``hp.continue_orbit``, ``hp.load_model``, ``hp.simulate``) load no module of the impact pair.
Each probe is a new interpreter that times its own imports with ``time.perf_counter`` (so the
interpreter's start-up is not counted) and reports the modules loaded; probes run
``--repeat`` times, interleaved with the baseline so that other load on the machine affects
them alike, and min/median/max are printed with the ratio of medians to the baseline.
Run: ``python benchmarks/bench_import.py`` (``--repeat N``, default 7).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys

HEAVY = ("numba", "sympy", "control", "matplotlib", "xarray", "scipy", "dask", "zarr")

_PROBE = """
import json, sys, time
t0 = time.perf_counter()
{stmt}
dt = time.perf_counter() - t0
print(json.dumps({{"seconds": dt,
    "heavy": sorted({{m.split('.')[0] for m in sys.modules}} & set({heavy!r})),
    "pair": sorted(m for m in sys.modules if m.startswith('hybridpd.pair'))}}))
"""

PROBES = {
    "import numpy (baseline)": "import numpy",
    "import hybridpd": "import hybridpd",
    **{f"hp.{n}": f"import hybridpd as hp; hp.{n}" for n in
       ("find_orbit", "SectionMap", "continue_orbit", "load_model", "simulate",
        "symmetric_orbit")},
}


def _run(stmt: str) -> dict:
    code = _PROBE.format(stmt=stmt, heavy=HEAVY)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       check=True, env=dict(os.environ, OPENBLAS_NUM_THREADS="1"))
    return json.loads(r.stdout.strip().splitlines()[-1])


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeat", type=int, default=7, help="runs of each probe (default 7)")
    args = p.parse_args(argv)
    times = {k: [] for k in PROBES}
    last = {}
    for _ in range(args.repeat):
        for name, stmt in PROBES.items():
            last[name] = _run(stmt)
            times[name].append(last[name]["seconds"])
    base = statistics.median(times["import numpy (baseline)"])
    print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}")
    for name, ts in times.items():
        med = statistics.median(ts)
        print(f"{name:25s} min {min(ts) * 1e3:7.1f} ms, median {med * 1e3:7.1f} ms, "
              f"max {max(ts) * 1e3:7.1f} ms; ratio to import numpy {med / base:5.2f}; "
              f"heavy {last[name]['heavy']}; pair modules {len(last[name]['pair'])}")


if __name__ == "__main__":
    main()
