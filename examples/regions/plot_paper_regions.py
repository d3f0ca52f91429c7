"""Figs 4-5 of the paper with the API: existence and stability regions in the (kp, kv) plane
=========================================================================================

mu = 0.1, gamma = 0.75, n = 1, omega = 5, e = 0.1, 0.5, 0.9, collocated and non-collocated.
A grid point is shaded when the symmetric orbit exists (conditions (13)-(14) with xm > 0 and
viability (18)) and is stable (all multipliers of DP inside the unit circle).

Run: ``python examples/regions/plot_paper_regions.py [--out DIR] [--quick]`` (about 5 s).
"""
import sys
from pathlib import Path

from matplotlib.figure import Figure

from hybridpd import region_map
from hybridpd.pair.regions import SymmetricFamily
from hybridpd.plotting import plot_regions

# sphinx_gallery_start_ignore
sys.path.insert(0, str(Path(sys.argv[0]).resolve().parents[1]))  # examples/_out.py
# sphinx_gallery_end_ignore
from _out import example_args

ARGS = example_args(__doc__)
NUM = 30 if ARGS.quick else 150
common = dict(e=(0.1, 0.5, 0.9), mu=0.1, omega=5.0, gamma=0.75, x10=1.0, n=1)
col_fam = SymmetricFamily("collocated", **common)
non_fam = SymmetricFamily("noncollocated", **common)
col = region_map(col_fam, x=("kp", 0.1, 50, 150), y=("kv", 0.1, 50, NUM))
non = region_map(non_fam, x=("kp", 0.1, 50, NUM), y=("kv", 0.1, 50, NUM))
zoom = region_map(non_fam, x=("kp", 0.1, 20, NUM), y=("kv", 0.1, 6, NUM))

for name, rm in (("collocated", col), ("non-collocated", non), ("non-collocated zoom", zoom)):
    print(name, "exists & stable:",
          ", ".join(f"e={e:g}: {a:.4g} ({100 * f:.2f}%)"
                    for e, a, f in zip(rm.e, rm.area("stable"), rm.fraction("stable"))))

fig = Figure(figsize=(17, 5))
for i, (rm, title) in enumerate(((col, "Fig. 4: collocated"), (non, "Fig. 5: non-collocated"),
                                 (zoom, "Fig. 5, zoom"))):
    plot_regions(rm, ax=fig.add_subplot(1, 3, i + 1), title=title)
fig.tight_layout()
out = ARGS.out
fig.savefig(out / "paper_regions.png", dpi=110)
print(f"figure written to {out / 'paper_regions.png'}")
