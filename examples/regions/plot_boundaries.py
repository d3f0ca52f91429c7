"""Figs 4-5 with traced region boundaries and codimension-2 points
===============================================================

The paper's existence/stability regions of the symmetric orbit (mu = 0.1, gamma = 0.75,
n = 1, omega = 5; e = 0.1, 0.5, 0.9) in the gain plane (kp, kv), collocated (Fig. 4) and
non-collocated (Fig. 5, with a zoom on small gains). The shading is a coarse grid of
"exists and stable" (only the background); the boundaries are *traced* curves
(pseudo-arclength continuation of closed-form test functions), exact at any zoom: grazing
(the orbit stops existing, paper (19)), fold/branch points (a multiplier at +1),
Neimark-Sacker (a complex pair on the unit circle). Black markers are codimension-2 points
(where a boundary ends or two meet; 1:1 / 1:2 resonances on Neimark-Sacker curves).
Colour: the restitution coefficient; line style: the kind of boundary.

Run: ``python examples/regions/plot_boundaries.py [--out DIR]`` (writes ``boundaries.png``, ~30 s).
"""
import argparse
import time
from pathlib import Path

from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

PAPER = dict(mu=0.1, gamma=0.75, omega=5.0, n=1)
ES = (0.1, 0.5, 0.9)
COLORS = ("#0072B2", "#E69F00", "#009E73")   # Okabe-Ito: blue, orange, green
PANELS = [("collocated", (0.1, 50.0), (0.1, 50.0), "Fig. 4: collocated"),
          ("noncollocated", (0.1, 50.0), (0.1, 50.0), "Fig. 5: non-collocated"),
          ("noncollocated", (0.1, 20.0), (0.1, 6.0), "Fig. 5, zoom")]


def panel(ax, case, xr, yr, title):
    from hybridpd import region_map
    from hybridpd.pair.boundaries import boundary_curves
    from hybridpd.pair.regions import SymmetricFamily
    from hybridpd.plotting.boundaries import draw_boundaries

    fam = SymmetricFamily(case, e=ES, mu=PAPER["mu"], omega=PAPER["omega"],
                          gamma=PAPER["gamma"], n=PAPER["n"])
    rm = region_map(fam, x=("kp", *xr, 120), y=("kv", *yr, 120))
    for k, e in enumerate(ES):
        if rm.stable[k].any():
            ax.contourf(rm.x, rm.y, rm.stable[k].astype(float), levels=[0.5, 1.5],
                        colors=[COLORS[k]], alpha=0.18)
    kinds_seen, codim_seen = set(), set()
    for k, e in enumerate(ES):
        t0 = time.perf_counter()
        res = boundary_curves(case, x=("kp", *xr), y=("kv", *yr), e=e, **PAPER)
        print(f"{title}, e = {e}: {len(res.curves)} curves, {res.n_points()} points, "
              f"{len(res.codim2)} codim-2 points in {time.perf_counter() - t0:.2f} s")
        for c in res.curves:
            print(f"    {c.kind:15s} {len(c):4d} pts  ends {c.ends}  max |test| {c.max_test:.1e}")
        for q in res.codim2:
            print(f"    codim-2 {q.kind:24s} kp = {q.x:.6f}, kv = {q.y:.6f}")
        draw_boundaries(ax, res, color=COLORS[k], legend=False)
        kinds_seen |= {c.kind for c in res.curves}
        codim_seen |= {q.kind for q in res.codim2}
    ax.set_title(title, fontsize=10)
    return kinds_seen, codim_seen


def main():
    ap = argparse.ArgumentParser(description=(__doc__ or "").strip().split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="boundaries-out",
                    help="output directory (created), default ./boundaries-out")
    ap.add_argument("--quick", action="store_true",
                    help="accepted for uniformity with the other examples (this one is fast)")
    args = ap.parse_args()
    from hybridpd.plotting.boundaries import CODIM2_STYLES, KIND_STYLES

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    fig = Figure(figsize=(17, 6.2), layout="constrained")
    axes = fig.subplots(1, 3)
    kinds, codim = set(), set()
    for ax, (case, xr, yr, title) in zip(axes, PANELS):
        k, c = panel(ax, case, xr, yr, title)
        kinds |= k
        codim |= c
    handles = [Patch(facecolor=c, alpha=0.35, label=f"e = {e:g}: exists and stable (shaded)")
               for e, c in zip(ES, COLORS)]
    handles += [Line2D([], [], color="0.3", linestyle=KIND_STYLES[k]["linestyle"],
                       label=KIND_STYLES[k]["label"]) for k in KIND_STYLES if k in kinds]
    handles += [Line2D([], [], color="black", marker=st["marker"], linestyle="none",
                       label=st["label"]) for k, st in CODIM2_STYLES.items() if k in codim]
    fig.legend(handles=handles, loc="outside lower center", ncol=4, fontsize=8)
    fig.suptitle("Symmetric orbit, mu = 0.1, gamma = 0.75, n = 1, omega = 5: traced region "
                 "boundaries", fontsize=11)
    path = out / "boundaries.png"
    fig.savefig(path, dpi=110)
    print(f"figure written to {path}")


if __name__ == "__main__":
    main()
