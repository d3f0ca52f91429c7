"""Benchmark: orbit + stability per gain point, first call, import time.

Targets: orbit + stability for one gain point <= 50 us after warm-up over a grid; first call
including the SymPy derivation <= 5 s; ``import hybridpd`` <= 0.5 s. Run:
``python benchmarks/bench_orbits.py``.
"""
import subprocess
import sys
import time

import numpy as np


def main():
    code = "import time; t=time.perf_counter(); import hybridpd; print(time.perf_counter()-t)"
    imp = min(float(subprocess.run([sys.executable, "-c", code], capture_output=True,
                                   text=True, check=True).stdout) for _ in range(3))
    code = ("import time; t=time.perf_counter(); from hybridpd import ImpactPair, PDGains;"
            "from hybridpd.pair.orbits import symmetric_orbit;"
            "[symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0, case=c) "
            "for c in ('collocated', 'noncollocated')]; print(time.perf_counter()-t)")
    first = float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                 check=True).stdout)

    from hybridpd.pair.orbits import symmetric_orbits

    kp = np.linspace(0.1, 50, 200)
    kv = np.linspace(0.1, 50, 200)
    print(f"import hybridpd: {imp * 1e3:.0f} ms (target <= 500 ms)")
    print(f"first call, both cases, incl. SymPy derivation + numba load: {first:.2f} s "
          f"(target <= 5 s)")
    for case in ("collocated", "noncollocated"):
        symmetric_orbits(kp[:3], kv[:3, None], e=0.5, mu=0.1, L=0.75, omega=5.0, case=case)
        t0 = time.perf_counter()
        r = symmetric_orbits(kp[None, :], kv[:, None], e=0.5, mu=0.1, L=0.75, omega=5.0,
                             case=case)
        el = time.perf_counter() - t0
        print(f"{case}: 200 x 200 grid, existence + viability + DP + eigenvalues: {el:.3f} s "
              f"= {el / r.exists.size * 1e6:.1f} us per gain point (target <= 50 us); "
              f"{100 * r.stable.mean():.1f}% stable")


if __name__ == "__main__":
    main()
