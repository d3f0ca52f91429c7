"""Timings of the gain design (nominal and robust), cold and warm.

Run ``python benchmarks/bench_design.py [--repeat N]``. Prints one line per measurement and a
pass/fail against the targets (nominal design <= 2 s, robust design over a 5 x 5 uncertainty
grid <= 20 s, both warm: after the SymPy derivations and numba kernels are loaded).

*Cold* means a fresh interpreter (the import, the SymPy derivation/lambdify of the closed
forms and the loading of numba's on-disk cache are included); *warm* is the median of
``--repeat`` calls in one process after a warm-up call.
"""
from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time

PAPER = {"mu": 0.1, "e": 0.5, "gamma": 0.75, "omega": 5.0}
BOX = {"e_range": (0.3, 0.7), "mu_range": (0.08, 0.12), "uncertainty_grid": (5, 5)}
TARGETS = {"nominal": 2.0, "robust": 20.0}

_COLD = """
import time
t = time.perf_counter()
from hybridpd.pair.design import design
design({case!r}, **{spec!r})
print(time.perf_counter() - t)
"""


def cold(case: str, spec: dict) -> float:
    """Wall time of import + one design in a fresh interpreter (s)."""
    out = subprocess.run([sys.executable, "-c", _COLD.format(case=case, spec=spec)],
                         check=True, capture_output=True, text=True)
    return float(out.stdout.strip().splitlines()[-1])


def warm(case: str, spec: dict, repeat: int):
    """Median wall time over ``repeat`` designs after a warm-up (s), and the last result."""
    from hybridpd.pair.design import design

    design(case, **spec)
    times = []
    res = None
    for _ in range(repeat):
        t = time.perf_counter()
        res = design(case, **spec)
        times.append(time.perf_counter() - t)
    return statistics.median(times), min(times), res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="warm repetitions (median reported)")
    ap.add_argument("--no-cold", action="store_true", help="skip the fresh-interpreter runs")
    args = ap.parse_args(argv)

    ok = True
    print(f"{'what':<34}{'cold [s]':>10}{'warm median [s]':>17}{'warm min [s]':>14}"
          f"{'target [s]':>12}  result")
    for kind, spec in (("nominal", dict(PAPER)), ("robust", {**PAPER, **BOX})):
        for case in ("collocated", "noncollocated"):
            c = float("nan") if args.no_cold else cold(case, spec)
            med, best, res = warm(case, spec, args.repeat)
            target = TARGETS[kind]
            passed = med <= target
            ok &= passed
            extra = (f"kp={res.kp:.4g} kv={res.kv:.4g} rho={res.spectral_radius:.4f}"
                     + (f" worst rho={res.robust.worst_spectral_radius:.4f} at "
                        f"{res.robust.worst_case}" if res.robust is not None else ""))
            print(f"{kind + ' ' + case:<34}{c:>10.2f}{med:>17.2f}{best:>14.2f}{target:>12.0f}  "
                  f"{'PASS' if passed else 'FAIL'}  ({extra}; "
                  f"{sum(r.nfev for r in res.optimizer)} optimiser evaluations)")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
