"""Bifurcation diagram in the velocity gain kv with the continued branches overlaid
================================================================================

The paper's other parameters: collocated feedback, e = 0.1, mu = 0.1, gamma = L / x10 = 0.75
(x10 = 1), omega = 5, kp = 10, m2 = 1; the reference amplitude xm follows the design (the
symmetric orbit realises x10 = 1 at every kv). The figure shows

* the brute-force diagram: the last iterates of the impact map P at every kv, swept upwards
  from the symmetric orbit and downwards from the period-2 motion, each value started from
  the previous one's final state ("following": the two sweeps differ where two attractors
  coexist);
* the branches found by continuation, not by iteration: the symmetric period-1 family
  (closed form), which ends at grazing; the switch at that grazing point onto the motion
  the system jumps to, a period-2 orbit with a double impact, continued in both directions
  (a fold where it meets its unstable partner, and its own grazing end);
* the largest Lyapunov exponent of the map along both sweeps.

At kv = 20 (the paper's basin gains) the period-2 orbit coexists with the symmetric orbit:
it is the double-impact motion that takes most of the basin slice there.

Run: ``python examples/orbits/plot_bifurcation_diagram.py --out DIR`` (about half a minute).
"""
from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from hybridpd import ImpactPair, PDGains, bifurcation_diagram, continue_orbit
from hybridpd.pair.bifdiagram import PAIR_SETTINGS, ImpactMapFamily
from hybridpd.pair.continuation import branch_map, continue_symmetric, switch_branch
from hybridpd.plotting.bifurcation import bifurcation_legend, plot_bifurcation

MU, E, GAMMA, X10, OMEGA, KP = 0.1, 0.1, 0.75, 1.0, 5.0, 10.0


def parse():
    p = argparse.ArgumentParser(
        description="Bifurcation diagram in kv (collocated, e = 0.1, kp = 10) with the "
        "symmetric and period-2 branches found by continuation and branch switching.")
    p.add_argument("--out", type=Path, default=None,
                   help="output directory (default: a new temporary directory)")
    p.add_argument("--kv", type=float, nargs=2, default=(10.0, 35.0), metavar=("MIN", "MAX"),
                   help="kv range (default 10 35)")
    p.add_argument("--num", type=int, default=250, help="kv values per sweep (default 250)")
    p.add_argument("--iterations", type=int, default=600,
                   help="iterations of P per value (default 600)")
    p.add_argument("--keep", type=int, default=60,
                   help="last iterates drawn per value (default 60)")
    p.add_argument("--coordinate", default="phi",
                   choices=["phi", "z1", "z2", "z4", "x1", "y1", "x2", "y2"],
                   help="section coordinate on the y axis (default phi)")
    p.add_argument("--quick", action="store_true",
                   help="a few values and iterations: a smoke test, not the figure")
    args = p.parse_args()
    if args.quick:
        args.num, args.iterations, args.keep = 12, 80, 10
    return args


def report(title, br):
    print(f"{title}: {len(br)} points, kv {br.parameter.min():.4f} .. {br.parameter.max():.4f};"
          f" {br.termination}")
    for ev in br.events:
        if ev.viable and ev.kind != "stability_change":
            print(f"    {ev.kind:15s} kv = {ev.parameter:.6f}  {ev.detail[:70]}")


def branches(pair, kv_lo, kv_hi):
    """The symmetric family and the period-2 family reached from its grazing point."""
    sym = continue_symmetric(pair, PDGains(KP, kv_lo), OMEGA, "kv", kv_hi, x10=X10)
    report("symmetric period-1 family (closed form)", sym)
    graze = sym.events_of("grazing")[0]
    sw = switch_branch(sym, graze, kv_hi)
    print(f"switch at grazing kv = {graze.parameter:.6f}: {sw.reason}; start kv = "
          f"{sw.start_parameters[0]:.6f}, walls {sw.starts[0].walls}")
    up = sw.branches[0]
    report("  period-2 branch, upwards", up)
    # downwards: through the fold onto the unstable partner, then along it
    fam = branch_map(sym, sw.start_parameters[0]).family("kv", x10=X10)
    down = continue_orbit(fam, fam.value, kv_lo, sw.starts[0], period=2)
    report("  period-2 branch, downwards", down)
    out = [(sym, "symmetric period-1"), (up, "period-2 (double impact)"),
           (down, "period-2 (double impact)")]
    if "turned back" in down.termination:
        fam = branch_map(down, down.parameter[-1]).family("kv", x10=X10)
        partner = continue_orbit(fam, fam.value, kv_hi, down.points[-1], period=2)
        report("  unstable partner after the fold", partner)
        out.append((partner, "period-2 (double impact)"))
    at20 = [b for b, _ in out[1:] if b.stable.any()]
    for b in at20:
        i = np.flatnonzero(b.stable)
        j = i[np.argmin(np.abs(b.parameter[i] - 20.0))]
        if abs(b.parameter[j] - 20.0) < 0.5:
            print(f"  stable 2-cycle near kv = {b.parameter[j]:.4f}: s = "
                  f"{np.round(b.points[j], 6)}, spectral radius {b.spectral_radius[j]:.4f}")
            break
    return out


def main():
    args = parse()
    out = args.out or Path(tempfile.mkdtemp(prefix="hybridpd-bifurcation-"))
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    pair = ImpactPair(MU, E, GAMMA * X10)
    kv_lo, kv_hi = args.kv
    brs = branches(pair, kv_lo, kv_hi)
    t1 = time.perf_counter()
    kv = np.linspace(kv_lo, kv_hi, args.num)
    fam = ImpactMapFamily(pair, PDGains(KP, kv_lo), OMEGA, "kv", x10=X10)
    common = dict(PAIR_SETTINGS, iterations=args.iterations, keep=args.keep, follow=True)
    d_up = bifurcation_diagram(fam, kv, **common)
    d_down = bifurcation_diagram(fam, kv[::-1], s0=[0.3, -2.1, -2.3, 0.5], **common)
    t2 = time.perf_counter()
    for name, d in (("upwards", d_up), ("downwards", d_down)):
        counts = {c: n for c, n in d.counts().items() if n}
        per = {int(k): int(np.sum(d.periods == k)) for k in np.unique(d.periods) if k}
        print(f"diagram {name}: {counts}; periods {per}")
    print(f"continuation {t1 - t0:.1f} s, diagrams {t2 - t1:.1f} s "
          f"({2 * args.num * args.iterations} iterates)")

    fig = Figure(figsize=(9, 8), layout="constrained")
    ax, ax2 = fig.subplots(2, 1, sharex=True, height_ratios=(3, 1.3))
    plot_bifurcation(d_up, ax, args.coordinate, color="k", markersize=1.0,
                     label="iterates of $P$, $k_v$ increasing", legend=False, note=False)
    plot_bifurcation(d_down, ax, args.coordinate, brs, color="tab:red", markersize=1.0,
                     label="iterates of $P$, $k_v$ decreasing", legend=False, note=False,
                     title="Collocated PD, $e = 0.1$, $\\mu = 0.1$, $\\gamma = 0.75$ "
                     "($x_{10} = 1$, $x_m$ from the design), $\\omega = 5$, $k_p = 10$\n"
                     f"last {args.keep} of {args.iterations} iterates per $k_v$, each "
                     "started from the previous state")
    bifurcation_legend(ax, loc="upper right", ncols=2)
    ax.set_xlabel("")
    ax.axvline(20.0, color="gray", lw=0.6, ls=":")
    ax2.plot(d_up.values, d_up.lyapunov, ".", ms=2, color="k", label="$k_v$ increasing")
    ax2.plot(d_down.values, d_down.lyapunov, ".", ms=2, color="tab:red",
             label="$k_v$ decreasing")
    ax2.axhline(0.0, color="gray", lw=0.8)
    ax2.axvline(20.0, color="gray", lw=0.6, ls=":")
    ax2.set_xlabel("$k_v$")
    ax2.set_ylabel("largest Lyapunov\nexponent of $P$")
    ax2.legend(fontsize=7, loc="lower left")
    path = out / "bifurcation_diagram.png"
    fig.savefig(path, dpi=130)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
