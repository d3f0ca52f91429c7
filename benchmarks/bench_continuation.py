"""Benchmark of Newton on P^k and of the continuations (paper parameters).

Reports the wall time of: Newton for the symmetric fixed point (symbolic DP) and for the
period-2 cycle (finite-difference DP of P^2); the closed-form continuation of the symmetric
family in kv with event location; map continuations (pseudo-arclength) of the period-2
cycle to its fold and of a non-symmetric orbit through a Neimark-Sacker pair and a period
doubling. Run: ``python benchmarks/bench_continuation.py``.
"""
import numpy as np
from _common import best_of

from hybridpd import ImpactPair, PDGains
from hybridpd.analysis.continuation import continue_orbit
from hybridpd.analysis.periodic import find_orbit
from hybridpd.pair.continuation import continue_symmetric
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.orbits import symmetric_orbit


def main():
    pair = ImpactPair(0.1, 0.1, 0.75)
    orb = symmetric_orbit(pair, PDGains(10, 20), 5.0)
    P = ImpactMap(pair, orb.gains, orb.reference())
    start = orb.fixed_point + np.array([0.01, 0.02, -0.05, 0.05])
    find_orbit(P, start)                                  # warm-up (numba, SymPy)
    t, r = best_of(lambda: find_orbit(P, start))
    print(f"Newton, symmetric fixed point (symbolic DP): {t * 1e3:.1f} ms, "
          f"{r.iterations} iterations, residual {r.residual:.1e}")
    s2 = P.iterate(np.array([0.3, -2.1, -2.3, 0.5]), 200)[-1] + 0.01
    t, c = best_of(lambda: find_orbit(P, s2, period=2))
    print(f"Newton, period-2 cycle (finite-difference DP): {t * 1e3:.1f} ms, "
          f"{c.iterations} iterations")

    for case, e in (("collocated", 0.1), ("noncollocated", 0.5)):
        t, br = best_of(lambda e=e, case=case: continue_symmetric(
            ImpactPair(0.1, e, 0.75), PDGains(10, 0.5), 5.0, "kv", 40.0, case=case), repeat=2)
        print(f"symmetric family in kv, {case} e = {e}: {t:.2f} s, {len(br)} points "
              f"({t / len(br) * 1e3:.1f} ms/point incl. location), events "
              f"{[(ev.kind, round(ev.parameter, 4)) for ev in br.events]}")

    t, br = best_of(lambda: continue_orbit(P.family("kv"), 20.0, 5.0, c, period=2), repeat=2)
    print(f"period-2 cycle in kv to its fold: {t:.2f} s, {len(br)} points, events "
          f"{[(ev.kind, round(ev.parameter, 4)) for ev in br.events]}")

    pa = ImpactPair(0.1, 0.5, 0.75)
    o = symmetric_orbit(pa, PDGains(60, 0.5), 5.0)
    Q = ImpactMap(pa, o.gains, o.reference())
    a = find_orbit(Q, Q.iterate(o.fixed_point + 1e-3, 3000)[-1])
    t, br = best_of(lambda: continue_orbit(Q.family("kp"), 60.0, 99.3, a), repeat=2)
    print(f"non-symmetric orbit in kp 60 -> 99.3: {t:.2f} s, {len(br)} points "
          f"({t / len(br) * 1e3:.1f} ms/point incl. location), events "
          f"{[(ev.kind, round(ev.parameter, 4)) for ev in br.events]}")


if __name__ == "__main__":
    main()
