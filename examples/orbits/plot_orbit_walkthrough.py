"""Finding a symmetric periodic orbit and checking its stability (paper sections 3-4)
==================================================================================

1. Solve the existence conditions (13)-(14) for the paper's parameters (mu = 0.1,
   gamma = 0.75, n = 1, omega = 5, e = 0.5, kp = 10, kv = 20, collocated): the reference
   amplitude xm and the impact phase phi0 that put m1 on a triangle wave of amplitude 1.
2. Check viability (no extra contact between the impacts) and compute the Jacobian DP of the
   impact map from its four symbolic blocks; its eigenvalues decide stability.
3. Simulate from a perturbed start: the trajectory settles on the orbit, and the distance to
   the fixed point on the section shrinks at the predicted rate (the spectral radius).

Run: ``python examples/orbits/plot_orbit_walkthrough.py [--out DIR]``.
"""
import sys
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from hybridpd import ImpactPair, PDGains
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.orbits import symmetric_orbit

# sphinx_gallery_start_ignore
sys.path.insert(0, str(Path(sys.argv[0]).resolve().parents[1]))  # examples/_out.py
# sphinx_gallery_end_ignore
from _out import example_args

ARGS = example_args(__doc__)

orb = symmetric_orbit(ImpactPair(mu=0.1, e=0.5, L=0.75), PDGains(kp=10, kv=20), omega=5.0,
                      x10=1.0, n=1, case="collocated")
print(f"exists: {orb.exists} ({orb.reason}); viability margin {orb.viability_margin:.4f}")
print(f"xm = {orb.xm:.8f}, phi0 = {orb.phi0:.8f}, R = {orb.R:.6f}")
print("fixed point (phi, z1, z2, z4) =", np.round(orb.fixed_point, 8))
print("multipliers:", np.round(orb.multipliers, 6))
print(f"spectral radius {orb.spectral_radius:.6f} -> {'stable' if orb.stable else 'unstable'}")

# 3. convergence of perturbations, predicted vs simulated
P = ImpactMap(orb.pair, orb.gains, orb.reference())
s0 = orb.fixed_point + np.array([0.02, 0.05, -0.1, 0.1])
traj = P.iterate(s0, 40)
dist = np.linalg.norm(traj - orb.fixed_point, axis=1)
k = np.arange(dist.size)
pred = dist[5] * orb.spectral_radius ** (k - 5)
print(f"measured contraction per iteration (10..25): {(dist[25] / dist[10]) ** (1 / 15):.6f}")

# overlay: a long simulation started near the orbit against the orbit itself
system = orb.system()
start = orb.post_plus + np.array([0.0, 0.2, 0.05, -0.1])
sim = system.simulate(start, (orb.t0, orb.t0 + 12 * orb.T))
t_late = np.linspace(orb.t0 + 10 * orb.T, orb.t0 + 12 * orb.T, 800)
X = sim(t_late)
t_orb = np.linspace(orb.t0, orb.t0 + orb.tau, 400)
half = orb.flight(t_orb)

fig = Figure(figsize=(11, 4.5))
ax = fig.add_subplot(1, 2, 1)
ax.plot(X[:, 0], X[:, 1], lw=2, alpha=0.5, label="simulation, periods 10-12")
ax.plot(half[:, 0], half[:, 1], "k--", lw=1, label="orbit (+L -> -L flight)")
ax.plot(-half[:, 0], -half[:, 1], "k:", lw=1, label="orbit, mirrored half")
ax.set_xlabel("x1")
ax.set_ylabel("y1")
ax.legend(fontsize=8)
ax = fig.add_subplot(1, 2, 2)
ax.semilogy(k, dist, "o-", ms=3, label="|P^k(s0) - s*| (simulated)")
ax.semilogy(k, pred, "--", label=f"rho^k, rho = {orb.spectral_radius:.4f}")
ax.set_xlabel("iteration k of P")
ax.legend(fontsize=8)
fig.tight_layout()
out = ARGS.out
fig.savefig(out / "orbit_walkthrough.png", dpi=110)
print(f"figure written to {out / 'orbit_walkthrough.png'}")
