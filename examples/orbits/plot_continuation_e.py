"""Continuation of the symmetric orbit in the velocity gain, with bifurcation events
=================================================================================

Paper parameters (mu = 0.1, gamma = L / x10 = 0.75, n = 1, omega = 5, kp = 10): the
symmetric period-1 orbit that puts the primary mass on a triangle wave of amplitude
x10 = 1 is followed in kv (x10 fixed, the reference amplitude xm follows), for

* the collocated loop at e = 0.1, and
* the non-collocated loop at e = 0.5.

Along each branch the spectral radius of DP (stability, paper (27)) and the viability
margin (existence, paper (18)-(19)) are plotted with the detected events marked: grazing
(the margin crosses 0: the orbit stops existing), Neimark-Sacker points (a complex pair of
multipliers crosses the unit circle), folds/branch points, period doublings, stability
changes. Then the map continuation (Newton on P at fixed xm) follows the period-2 attractor
that coexists with the collocated orbit at kv = 20 down to its fold.

Run: ``python examples/orbits/plot_continuation_e.py [--out DIR]`` (writes ``continuation_e.png``).
"""
import sys
import time
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from hybridpd import ImpactPair, PDGains, Reference, continue_orbit
from hybridpd.analysis.periodic import find_orbit
from hybridpd.pair.continuation import continue_symmetric
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.orbits import symmetric_orbit
from hybridpd.plotting.branches import plot_branch

# sphinx_gallery_start_ignore
sys.path.insert(0, str(Path(sys.argv[0]).resolve().parents[1]))  # examples/_out.py
# sphinx_gallery_end_ignore
from _out import example_args

ARGS = example_args(__doc__)

MU, L, OMEGA, KP = 0.1, 0.75, 5.0, 10.0
RUNS = [("collocated", 0.1), ("noncollocated", 0.5)]


def report(title, br):
    print(f"\n{title}: {len(br)} points, {br.n_rejected} rejected steps; {br.termination}")
    for ev in br.events:
        mods = ", ".join(f"{abs(z):.4f}" for z in ev.multipliers[:2])
        print(f"  {ev.kind:17s} kv = {ev.parameter:10.6f}  xm = {ev.xm:.6f}  "
              f"|lambda_1,2| = {mods}  {'' if ev.viable else '[not viable] '}{ev.detail}")


t0 = time.perf_counter()
fig = Figure(figsize=(11, 7.5), layout="constrained")
axes = fig.subplots(2, 2)
for j, (case, e) in enumerate(RUNS):
    br = continue_symmetric(ImpactPair(MU, e, L), PDGains(KP, 0.5), OMEGA, "kv", 40.0,
                            case=case)
    report(f"{case}, e = {e}", br)
    o = symmetric_orbit(ImpactPair(MU, e, L), PDGains(KP, 20.0), OMEGA, case=case)
    print(f"  the paper's gains kv = 20: exists {o.exists}, spectral radius "
          f"{o.spectral_radius:.4g}, viability margin {o.viability_margin:.4g}")
    plot_branch(br, axes[0, j], "spectral_radius", label=f"{case}, e = {e}")
    axes[0, j].set_title(f"{case}, e = {e}: spectral radius of DP", fontsize=9)
    plot_branch(br, axes[1, j], "margin", label=f"{case}, e = {e}")
    axes[1, j].set_ylim(-0.2, 1.1)
    axes[1, j].set_title("viability margin (< 0: an extra contact, no orbit)", fontsize=9)

# The period-2 attractor coexisting with the collocated orbit at kv = 20 (e = 0.1): Newton
# on P^2 from a late iterate, then continuation in kv at fixed xm down to its fold.
pair = ImpactPair(MU, 0.1, L)
xm = symmetric_orbit(pair, PDGains(KP, 20.0), OMEGA).xm
P = ImpactMap(pair, PDGains(KP, 20.0), Reference(xm, OMEGA))
cyc = find_orbit(P, P.iterate(np.array([0.3, -2.1, -2.3, 0.5]), 200)[-1], period=2)
print(f"\nperiod-2 cycle at kv = 20 (xm = {xm:.6f}): converged {cyc.converged}, walls "
      f"{cyc.walls}, multipliers {np.round(np.abs(cyc.multipliers), 6)}")
for s in cyc.orbit:
    print("  ", np.round(s, 6))
br2 = continue_orbit(P.family("kv"), 20.0, 5.0, cyc, period=2)
report("period-2 cycle continued in kv (xm fixed)", br2)

print(f"\ntotal {time.perf_counter() - t0:.1f} s")
path = ARGS.out / "continuation_e.png"
fig.savefig(path, dpi=110)
print(f"wrote {path}")
