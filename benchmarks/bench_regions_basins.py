"""Benchmark: region maps and basins, with the naive per-impact baseline.

Targets on this 2-core machine: a 200 x 200 (kp, kv) map for 3 values of e in <= 6 s per
feedback case; a 200 x 200 basin with 1500 iterations in <= 30 s (aim 10 s). The naive
approach (solve_ivp event loop) runs on a small sample in the same run and the per-impact
ratio is printed. Run: ``python benchmarks/bench_regions_basins.py [--quick]``.
"""
import sys
import time

import numpy as np
from _common import naive_per_impact, pair_region_map


def main(quick=False):
    from hybridpd import ImpactPair, PDGains
    from hybridpd.analysis.mappers import mapper as make_mapper
    from hybridpd.pair.batch import iterate_map, pack_params
    from hybridpd.pair.impactmap import ImpactMap
    from hybridpd.pair.orbits import symmetric_orbit
    from hybridpd.sweeps.basins import basin_of_attraction
    region_map = pair_region_map()

    num = 60 if quick else 200
    common = dict(e=(0.1, 0.5, 0.9), mu=0.1, omega=5.0, gamma=0.75)
    region_map("collocated", x=("kp", 0.1, 50, 3), y=("kv", 0.1, 50, 3), **common)
    region_map("noncollocated", x=("kp", 0.1, 50, 3), y=("kv", 0.1, 50, 3), **common)
    for case in ("collocated", "noncollocated"):
        t0 = time.perf_counter()
        rm = region_map(case, x=("kp", 0.1, 50, num), y=("kv", 0.1, 50, num), **common)
        el = time.perf_counter() - t0
        print(f"regions {case}: {num} x {num} x 3 in {el:.2f} s (target <= 6 s); stable "
              f"fractions {np.round(rm.fraction(), 4).tolist()}")

    # basins: the paper's collocated case, e = 0.5 and the slower e = 0.1
    nb = 50 if quick else 200
    for e in (0.5, 0.1):
        orb = symmetric_orbit(ImpactPair(0.1, e, 0.75), PDGains(10, 20), 5.0)
        mapper = make_mapper(ImpactMap(orb.pair, orb.gains, orb.reference()), orb.fixed_point)
        for executor in ("processes",):
            t0 = time.perf_counter()
            b = basin_of_attraction(mapper, (-3, 5, nb), (-2, 10, nb), max_period=0,
                                    executor=executor, progress=True)
            el = time.perf_counter() - t0
            print(f"basin collocated e = {e}: {nb} x {nb}, 1500 iterations, {executor}: "
                  f"{el:.2f} s (target <= 30 s, aim 10 s); converged "
                  f"{100 * b.converged_fraction:.1f}%, mean iterations "
                  f"{b.iterations.mean():.0f}")

    # per-impact cost of the batch engine against the naive loop, same trajectory
    orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    p = pack_params(10, 20, 1, 0.1, 0.5, 0.75, 5.0, orb.xm)
    s0 = orb.fixed_point + np.array([0.05, 0.3, -0.2, 0.4])
    iterate_map(p, 0, s0, 2)
    t0 = time.perf_counter()
    iterate_map(p, 0, s0, 1500)
    el = (time.perf_counter() - t0) / 3000
    naive, _ = naive_per_impact(xm=orb.xm, n_impacts=100 if quick else 300)
    print(f"per impact: batch engine {el * 1e6:.2f} us, naive solve_ivp loop "
          f"{naive * 1e6:.0f} us -> {naive / el:.0f}x faster")


if __name__ == "__main__":
    main(quick="--quick" in sys.argv)
