"""Attractor-labelled basins against the paper's labels alone, on the Fig. 6 slice.

For the collocated loop at kp = 10, kv = 20 (mu = 0.1, gamma = 0.75, omega = 5) and e = 0.1
(symmetric orbit and period-2 motion) and e = 0.5 (the basin fills the window), times:

* ``basin_of_attraction(max_period=0)``: the paper's labels (certified ball and cycle early
  exits);
* ``basin_of_attraction(grow=Growth(0))``: the same grid, plus the tails of unconverged
  points, cycle detection and Newton on ``P^k`` (the overhead of attractor labelling);
* ``basin_of_attraction(grow=Growth())``: with the window extension (up to 3 more grids);
* the naive alternative without early exits (every trajectory runs 1500 iterations).

Run: ``python benchmarks/bench_basins_attractors.py [--quick]`` (serial executor, one core).
"""
import sys

from _common import best_of


def main(quick=False):
    from hybridpd import ImpactPair, PDGains
    from hybridpd.analysis.mappers import Growth
    from hybridpd.pair.orbits import symmetric_orbit
    from hybridpd.reproduce.basins import orbit_mapper
    from hybridpd.sweeps.basins import basin_of_attraction

    def paper(m, x1, y1):
        return basin_of_attraction(m, x1, y1, max_period=0)

    def attractor_basin(m, x1, y1, extend=True):
        return basin_of_attraction(m, x1, y1, grow=Growth(3 if extend else 0))

    num = 40 if quick else 100
    win = ((-3, 5, num), (-2, 10, num))
    rep = 1 if quick else 2
    for e in (0.1, 0.5):
        orb = symmetric_orbit(ImpactPair(0.1, e, 0.75), PDGains(10, 20), 5.0)
        mapper = orbit_mapper(orb)
        attractor_basin(mapper, (-3, 5, 4), (-2, 10, 4))          # compile / warm caches
        t_old, b = best_of(lambda m=mapper: paper(m, *win), rep)
        t_new, ab = best_of(lambda m=mapper: attractor_basin(m, *win, extend=False), rep)
        t_ext, abx = best_of(lambda m=mapper: attractor_basin(m, *win), rep)
        print(f"collocated e = {e}: {num} x {num} grid, 1500 iterations, serial")
        print(f"  paper labels (basin_of_attraction)      {t_old:7.3f} s")
        print(f"  attractor labels, same window           {t_new:7.3f} s "
              f"(x{t_new / t_old:.2f}; mean iterations {b.iterations.mean():.0f})")
        print(f"  attractor labels, extended window       {t_ext:7.3f} s "
              f"({len(abx.windows)} window(s), reaches edge: {abx.reaches_edge})")
        for line in ab.summary()[1:]:
            print("   ", line)
        if not quick:
            slow = orbit_mapper(orb, early_exit=False)
            t_slow, _ = best_of(lambda m=slow: paper(m, (-3, 5, 30), (-2, 10, 30)), 1)
            per_pt = t_slow / 900
            print(f"  without early exits: {per_pt * 1e3:.2f} ms/point -> "
                  f"{per_pt * num * num:.1f} s for this grid "
                  f"(x{per_pt * num * num / t_new:.0f} the attractor labelling)")


if __name__ == "__main__":
    main(quick="--quick" in sys.argv)
