"""Figs 6-7 of the paper with the API: basins of attraction at kp = 10, kv = 20
============================================================================

The mapper (one section point -> a label) iterates the impact map 1500 times (3000 impacts)
and applies the paper's criterion; basins are a thin layer that maps a grid of the slice
(x1, y1) with y2 = y2*, phi = phi* through it.

Run: ``python examples/regions/plot_paper_basins.py [--out DIR] [--quick]`` (about a minute on 2 cores).
"""
import sys
from pathlib import Path

from matplotlib.figure import Figure

from hybridpd import ImpactPair, PDGains, basin_of_attraction, mapper
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.orbits import symmetric_orbit
from hybridpd.plotting import plot_basin

# sphinx_gallery_start_ignore
sys.path.insert(0, str(Path(sys.argv[0]).resolve().parents[1]))  # examples/_out.py
# sphinx_gallery_end_ignore
from _out import example_args

ARGS = example_args(__doc__)
NUM, N_ITER = (12, 100) if ARGS.quick else (60, 1500)
fig = Figure(figsize=(16, 9))
for row, case in enumerate(("collocated", "noncollocated")):
    for col, e in enumerate((0.1, 0.5, 0.9)):
        ax = fig.add_subplot(2, 3, 3 * row + col + 1)
        orb = symmetric_orbit(ImpactPair(0.1, e, 0.75), PDGains(10, 20), 5.0, case=case)
        if not orb.exists:
            print(f"{case} e={e}: no orbit ({orb.reason})")
            ax.set_axis_off()
            ax.text(0.5, 0.5, f"{case}, e = {e}:\nno symmetric orbit", ha="center",
                    transform=ax.transAxes)
            continue
        m = mapper(ImpactMap(orb.pair, orb.gains, orb.reference(), case), orb.fixed_point,
                   n_iter=N_ITER)
        b = basin_of_attraction(m, (-3, 5, NUM), (-2, 10, NUM), max_period=0,
                                executor="serial" if ARGS.quick else "processes")
        print(f"{case} e={e}: spectral radius {orb.spectral_radius:.4g}, converged "
              f"{100 * b.converged_fraction:.1f}%")
        plot_basin(b, ax=ax)
fig.tight_layout()
out = ARGS.out
fig.savefig(out / "paper_basins.png", dpi=100)
print(f"figure written to {out / 'paper_basins.png'}")
