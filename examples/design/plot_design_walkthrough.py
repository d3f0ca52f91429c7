"""Design walk-through: PD gains for a desired motion of the primary mass, verified and made robust
================================================================================================

Run ``python examples/design/plot_design_walkthrough.py [--out DIR]`` (default ``examples/out/``). It

1. states the desired motion (the paper's: ``x10 = 1``, ``gamma = L/x10 = 0.75``, ``n = 1``,
   ``omega = 5``) and plant (``mu = 0.1``, ``e = 0.5``, ``m2 = 1``) and designs collocated
   gains: the largest ``min(stability margin, viability margin)`` over ``[0.1, 100]^2``;
2. verifies the design by simulating the impact map from a perturbed start and compares the
   measured contraction with the spectral radius (``design_convergence.png``);
3. shows the margin map that was searched, with the seeds, the optimiser's moves and the
   chosen gains (``design_margin_map.png``);
4. designs robust gains for ``e in [0.3, 0.7]``, ``mu in [0.08, 0.12]`` (primary-mass amplitude
   within 10 %) and shows the worst case over the box (``design_robust_box.png``);
5. compares collocated with non-collocated feedback — the paper's closing remark — in a table
   and a figure of the nominal, robust-stable and robust gain regions
   (``design_collocated_vs_noncollocated.png``).

Only :class:`matplotlib.figure.Figure` objects are used (no pyplot, no GUI).
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from hybridpd import ImpactPair, Reference
from hybridpd.pair.design import robustness_comparison, shifted_orbit
from hybridpd.pair.impactmap import ImpactMap

# sphinx_gallery_start_ignore
sys.path.insert(0, str(Path(sys.argv[0]).resolve().parents[1]))  # examples/_out.py
# sphinx_gallery_end_ignore
from _out import example_args

PROBLEM = {"mu": 0.1, "e": 0.5, "gamma": 0.75, "x10": 1.0, "omega": 5.0, "n": 1}
BOX = {"e_range": (0.3, 0.7), "mu_range": (0.08, 0.12)}
L = PROBLEM["gamma"] * PROBLEM["x10"]


def phase_wrapped(d, T):
    d = np.array(d, float)
    d[..., 0] = (d[..., 0] + 0.5 * T) % T - 0.5 * T
    return d


def convergence_figure(d, path):
    """Iterate the simulated impact map from a perturbed fixed point (the designed orbit)."""
    o = d.orbit
    P = ImpactMap(o.pair, o.gains, Reference(d.xm, PROBLEM["omega"]), d.case)
    s0 = o.fixed_point + np.array([0.02, -0.05, 0.1, 0.05])
    traj = P.iterate(s0, 40)
    dist = np.linalg.norm(phase_wrapped(traj - o.fixed_point, P.period), axis=1)
    k = np.arange(len(dist))
    fig = Figure(figsize=(10, 4))
    ax1, ax2 = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    ax1.semilogy(k, np.maximum(dist, 1e-17), "o-", ms=3, label="|s_k - s*| (simulated map)")
    ax1.semilogy(k, dist[0] * d.spectral_radius ** k, "--",
                 label=f"rho^k, rho = {d.spectral_radius:.3f}")
    ax1.set_xlabel("impact-map iteration k (2 impacts each)")
    ax1.set_ylabel("distance to the designed fixed point")
    ax1.set_ylim(1e-17, 10)
    ax1.legend(fontsize=8)
    ax2.plot(k, traj[:, 1] + L, "o-", ms=3, label="x1 at the +L impact")
    ax2.axhline(PROBLEM["x10"], color="k", lw=0.8, ls="--", label="desired x10")
    ax2.set_xlabel("iteration k")
    ax2.set_ylabel("primary-mass impact position")
    ax2.legend(fontsize=8)
    fig.suptitle(f"{d.case.value}: kp = {d.kp:.4g}, kv = {d.kv:.4g}, xm = {d.xm:.4g} "
                 "— convergence from a perturbed start", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    return dist


def margin_map_figure(d, path):
    """The searched objective ``min(1 - rho, nu)`` with the seeds, moves and the choice."""
    m = d.design_map
    J = np.where(m.nominal_objective > 0, m.nominal_objective, np.nan)
    fig = Figure(figsize=(6.5, 5.2))
    ax = fig.add_subplot(1, 1, 1)
    pc = ax.pcolormesh(m.kp, m.kv, J, shading="nearest", cmap="viridis", vmin=0, vmax=1)
    fig.colorbar(pc, ax=ax, label="objective min(1 - rho, viability margin)")
    ax.contour(m.kp, m.kv, (m.exists & m.stable).astype(float), levels=[0.5], colors="w",
               linewidths=1)
    for run in d.optimizer:
        ax.annotate("", xy=(run.kp, run.kv), xytext=(run.start_kp, run.start_kv),
                    arrowprops={"arrowstyle": "->", "color": "r", "lw": 1})
        ax.plot(run.start_kp, run.start_kv, "s", mfc="none", mec="r", ms=6)
    ax.plot(d.kp, d.kv, "*", color="r", ms=14, mec="k", label="designed gains")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("kp")
    ax.set_ylabel("kv")
    ax.legend(loc="lower left", fontsize=8)
    ax.set_title(f"{d.case.value}: searched margin map (blank: no stable orbit; "
                 "squares: seeds)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def robust_box_figure(designs, path):
    """Spectral radius and amplitude of the shifted orbit over the box, per case."""
    fig = Figure(figsize=(11, 4.2 * len(designs)))
    for row, d in enumerate(designs):
        r = d.validation if d.validation is not None else d.robust
        ext = [r.mu_values[0], r.mu_values[-1], r.e_values[0], r.e_values[-1]]
        for col, (arr, label, cmap) in enumerate((
                (r.spectral_radius, "spectral radius of the shifted orbit", "magma_r"),
                (100 * (r.x10 / r.x10_nominal - 1), "x10 error [%]", "coolwarm"))):
            ax = fig.add_subplot(len(designs), 2, 2 * row + col + 1)
            kw = {"vmin": -100 * r.x10_tol, "vmax": 100 * r.x10_tol} if col else {}
            im = ax.imshow(arr, origin="lower", extent=ext, aspect="auto", cmap=cmap, **kw)
            fig.colorbar(im, ax=ax, label=label)
            wc = r.worst_spectral_radius_case if col == 0 else r.worst_case
            ax.plot(wc["mu"], wc["e"], "x", color="k" if col else "c", ms=12, mew=2,
                    clip_on=False)
            ax.plot(PROBLEM["mu"], PROBLEM["e"], "o", mfc="none", mec="k", ms=8)
            ax.set_xlabel("mu")
            ax.set_ylabel("e")
            ax.set_title(f"{d.case.value}: kp = {d.kp:.3g}, kv = {d.kv:.3g}, xm = {d.xm:.3g}"
                         + (f" — worst rho {r.worst_spectral_radius:.3f}" if col == 0 else
                            f" — worst |err| {100 * r.worst_x10_error:.1f} %"), fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def comparison_figure(cmp, path):
    """Nominal / robust-stable / robust gain regions, collocated against non-collocated."""
    fig = Figure(figsize=(11, 4.8))
    for k, row in enumerate(cmp.rows):
        ax = fig.add_subplot(1, 2, k + 1)
        m = row.robust.design_map if row.robust is not None else None
        if m is None:
            continue
        layers = (m.exists & m.stable).astype(int) + m.robust_stable.astype(int) \
            + m.robust_feasible.astype(int)
        ax.pcolormesh(m.kp, m.kv, layers, shading="nearest", vmin=0, vmax=3,
                      cmap="Blues")
        ax.plot(row.nominal.kp, row.nominal.kv, "*", color="orange", mec="k", ms=12,
                label="nominal design")
        ax.plot(row.robust.kp, row.robust.kv, "*", color="r", mec="k", ms=12,
                label="robust design")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("kp")
        ax.set_ylabel("kv")
        ax.legend(loc="lower left", fontsize=8)
        ax.set_title(f"{row.case}: stable {100 * row.nominal_fraction:.0f} %, robustly stable "
                     f"{100 * row.robust_stable_fraction:.0f} %,\nrobust incl. amplitude "
                     f"{100 * row.robust_fraction:.1f} % of the log gain box", fontsize=9)
    fig.suptitle("shades: nominal exists & stable < stable over the (e, mu) box < also "
                 "x10 within 10 %", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(out: Path):
    t0 = time.perf_counter()

    # 1-5 share the designs: the comparison runs the nominal and robust design of each case
    cmp = robustness_comparison(**{k: PROBLEM[k] for k in ("mu", "gamma", "x10", "n", "omega",
                                                        "e")}, **BOX)
    rows = {r.case: r for r in cmp.rows}
    d = rows["collocated"].nominal

    print("1. Nominal design (collocated), desired x10 = 1, omega = 5, n = 1:")
    print(f"   kp = {d.kp:.5g}, kv = {d.kv:.5g}; reference xm = {d.xm:.5g}, impact phase "
          f"phi0 = {d.phi0:.5g}")
    print(f"   spectral radius {d.spectral_radius:.4f} (stability margin "
          f"{d.stability_margin:.4f}), viability margin {d.viability_margin:.4f}")
    for run in d.optimizer:
        print(f"   seed ({run.start_kp:.3g}, {run.start_kv:.3g}) J={run.start_objective:.4f} -> "
              f"({run.kp:.4g}, {run.kv:.4g}) J={run.objective:.4f} in {run.nfev} evaluations")

    dist = convergence_figure(d, out / "design_convergence.png")
    k = int(np.argmax(dist < 1e-12))
    print(f"2. Simulated impact map from a perturbed start: |s - s*| {dist[0]:.2e} -> "
          f"{dist[k]:.2e} in {k} iterations (measured rate {(dist[k] / dist[0]) ** (1 / k):.3f}"
          f" per iteration, rho = {d.spectral_radius:.3f})")

    margin_map_figure(d, out / "design_margin_map.png")
    print(f"3. Margin map: {100 * d.design_map.feasible_fraction():.1f} % of the log-spaced "
          "gain box gives an existing, stable orbit")

    print("4. Robust designs, e in [0.3, 0.7], mu in [0.08, 0.12], x10 within 10 %:")
    robust = [rows[c].robust for c in ("collocated", "noncollocated") if rows[c].robust]
    for r in robust:
        rr = r.robust
        print(f"   {r.case.value:<13}: kp = {r.kp:.4g}, kv = {r.kv:.4g}, xm = {r.xm:.4g}; worst "
              f"rho = {rr.worst_spectral_radius:.4f} at e = {rr.worst_spectral_radius_case['e']:g},"
              f" mu = {rr.worst_spectral_radius_case['mu']:g}; worst x10 error "
              f"{100 * rr.worst_x10_error:.1f} %; 9x9 check ok: {r.validation.ok}")
        # the plant at the worst case, simulated from the nominal orbit's fixed point
        wc = rr.worst_spectral_radius_case
        pair = ImpactPair(wc["mu"], wc["e"], L)
        so = shifted_orbit(pair, r.gains, r.xm, PROBLEM["omega"], case=r.case)
        P = ImpactMap(pair, r.gains, Reference(r.xm, PROBLEM["omega"]), r.case)
        end = P.iterate(r.orbit.fixed_point, 300)[-1]
        err = np.abs(phase_wrapped(end - so.fixed_point, P.period)).max()
        print(f"     worst-case plant simulated from the nominal orbit settles on the predicted "
              f"orbit (x10 = {so.x10:.4f}) to {err:.1e}")
    if robust:
        robust_box_figure(robust, out / "design_robust_box.png")

    print("5. Collocated vs non-collocated (paper's closing remark):")
    print(cmp.to_text())
    for r in cmp.rows:
        if r.nominal_gains_over_box is not None and not r.nominal_gains_over_box.ok:
            fails = r.nominal_gains_over_box.failures()
            print(f"   {r.case}: the nominal design's gains fail at {len(fails)} of "
                  f"{r.nominal_gains_over_box.status.size} plants, e.g. e = {fails[0][0]:g}, "
                  f"mu = {fails[0][1]:g}: {fails[0][2]}")
    comparison_figure(cmp, out / "design_collocated_vs_noncollocated.png")
    print(f"figures in {out}/ ({time.perf_counter() - t0:.1f} s)")


if __name__ == "__main__":
    main(example_args(__doc__).out)
