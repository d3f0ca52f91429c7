"""Which motion does each initial condition reach? Attractor-labelled basins, measured
===================================================================================

At the paper's collocated gains kp = 10, kv = 20 and e = 0.1 almost every point of the Fig. 6
slice goes to a period-2 double-impact motion, not to the symmetric orbit. The attractor
basin finds that motion (a cycle of the impact map P, refined by Newton on P^2), lists its
section points and multipliers, and measures every basin; the window grows until the
symmetric orbit's basin no longer touches its edge.

Run: ``python examples/regions/plot_basin_attractors.py [--out DIR] [--quick]`` (about 10 s).
"""

import sys
from pathlib import Path

from hybridpd import ImpactPair, PDGains, basin_of_attraction
from hybridpd.analysis.mappers import Growth
from hybridpd.pair.orbits import symmetric_orbit
from hybridpd.plotting import plot_basin
from hybridpd.reproduce.basins import orbit_mapper

# sphinx_gallery_start_ignore
sys.path.insert(0, str(Path(sys.argv[0]).resolve().parents[1]))  # examples/_out.py
# sphinx_gallery_end_ignore
from _out import example_args

ARGS = example_args(__doc__)
NUM = 12 if ARGS.quick else 60
orb = symmetric_orbit(ImpactPair(mu=0.1, e=0.1, L=0.75), PDGains(kp=10, kv=20), omega=5.0,
                      x10=1.0, n=1, case="collocated")
mapper = orbit_mapper(orb)          # the paper's criterion, 1500 iterations
ab = basin_of_attraction(mapper, (-3, 5, NUM), (-2, 10, NUM), grow=Growth(max_points=2 * NUM))
for line in ab.summary():
    print(line)
for a in ab.attractors:
    if a.periodic:
        print(f"{a.name}: period {a.period}, walls {a.walls}, |multipliers| "
              f"{[round(float(abs(z)), 6) for z in a.multipliers]}")
        for s in a.points:
            print(f"    (phi, z1, z2, z4) = ({s[0]:.6f}, {s[1]:.6f}, {s[2]:.6f}, {s[3]:.6f})")
out = ARGS.out
plot_basin(ab).savefig(out / "basin_attractors.png", dpi=120)
print(f"figure written to {out / 'basin_attractors.png'}")
