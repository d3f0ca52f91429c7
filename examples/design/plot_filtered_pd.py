"""PD versus filtered PD (and a lead-lag) on the paper's impact pair
=================================================================

A pure PD ``kp + kv s`` needs the velocity error; in practice the derivative is filtered,
``C(s) = kp + kv s / (tf s + 1)``. This example computes, for the paper's parameters
(mu = 0.1, gamma = L/x10 = 0.75, n = 1, w = 5, e = 0.5, kp = 10, kv = 20, collocated):

1. the symmetric orbit and its Floquet multipliers with the pure PD (symbolic fast path,
   :func:`hybridpd.pair.orbits.symmetric_orbit`) and with the PD given as a python-control system
   through the general numerical path (:func:`hybridpd.pair.lti.lti_symmetric_orbit`);
2. the same with filtered PDs, ``tf`` in (0.1, 0.03, 0.01, 0.001): the required reference
   amplitude ``xm`` and the spectral radius converge to the PD values at the rate ``O(tf)``;
   the filter adds one controller state, hence a fifth multiplier;
3. a lead-lag compensator, in both feedback cases.

Run::

    python examples/design/plot_filtered_pd.py [--out DIR]

The figure (matplotlib ``Figure``, no GUI) goes to ``DIR/filtered_pd.png``, by default
``examples/out/filtered_pd.png``.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from hybridpd import ImpactPair, PDGains
from hybridpd.loop import pd_controller
from hybridpd.pair.lti import filtered_pd, lead_lag, lti_symmetric_orbit
from hybridpd.pair.orbits import symmetric_orbit

# sphinx_gallery_start_ignore
sys.path.insert(0, str(Path(sys.argv[0]).resolve().parents[1]))  # examples/_out.py
# sphinx_gallery_end_ignore
from _out import example_args

# The paper's parameters (Figs. 4-7), with x10 = 1 so that gamma = L / x10 = 0.75.
MU, E, GAMMA, N, OMEGA = 0.1, 0.5, 0.75, 1, 5.0
KP, KV = 10.0, 20.0
X10 = 1.0
TFS = (0.1, 0.03, 0.01, 0.001)
# Lead-lag: DC stiffness kp; lead zero at 1 s with its pole at 0.1 s (phase lead around the
# reference frequency, bounded high-frequency gain 100 instead of the PD's unbounded kv s) and
# a lag section (zero 1 s, pole 5 s) that halves the stiffness between 0.2 and 1 rad/s.
LEAD_LAG = {"k": KP, "t_lead_zero": 1.0, "t_lead_pole": 0.1, "t_lag_zero": 1.0,
            "t_lag_pole": 5.0}


def fmt_mults(m) -> str:
    return ", ".join(f"{abs(z):.4f}" + (f"∠{np.degrees(np.angle(z)):+.0f}°" if abs(z.imag) > 1e-12
                                        else "") for z in m)


def main(out: Path) -> None:
    pair = ImpactPair(mu=MU, e=E, L=GAMMA * X10)
    pd_sym = symmetric_orbit(pair, PDGains(KP, KV), OMEGA, x10=X10, n=N)
    pd_num = lti_symmetric_orbit(pair, pd_controller(KP, KV), OMEGA, x10=X10, n=N,
                                 fd_check=True)
    print(f"Impact pair mu = {MU:.2f}, e = {E:.2f}, gamma = {GAMMA:.2f}, n = {N}, w = {OMEGA:g}; "
          f"kp = {KP:g}, kv = {KV:g}, collocated")
    print(f"  PD symbolic : xm = {pd_sym.xm:.10f}  phi0 = {pd_sym.phi0:.10f}  "
          f"rho = {pd_sym.spectral_radius:.10f}  stable = {pd_sym.stable}")
    print(f"  PD numerical: xm = {pd_num.xm:.10f}  phi0 = {pd_num.phi0:.10f}  "
          f"rho = {pd_num.spectral_radius:.10f}  (|dDP| = "
          f"{np.abs(pd_num.DP - pd_sym.DP).max():.1e}, DP vs FD {pd_num.DP_fd_error:.1e})")
    print(f"  multipliers : {fmt_mults(pd_sym.multipliers)}")
    print()
    print(f"  {'tf':>7} {'exists':>6} {'xm':>12} {'xm-xm_PD':>10} {'rho':>9} {'rho-rho_PD':>11}"
          f" {'stable':>6}  multipliers (modulus∠angle)")
    filt = []
    for tf in TFS:
        o = lti_symmetric_orbit(pair, filtered_pd(KP, KV, tf), OMEGA, x10=X10, n=N,
                                fd_check=True)
        filt.append(o)
        print(f"  {tf:7.3g} {o.exists!s:>6} {o.xm:12.8f} {o.xm - pd_sym.xm:10.2e} "
              f"{o.spectral_radius:9.6f} {o.spectral_radius - pd_sym.spectral_radius:11.2e} "
              f"{o.stable!s:>6}  {fmt_mults(o.multipliers)}")
    # the O(tf) rate, from the two smallest filters
    slope = np.log(abs((filt[-2].xm - pd_sym.xm) / (filt[-1].xm - pd_sym.xm))) / np.log(
        TFS[-2] / TFS[-1])
    print(f"  observed order of xm -> xm_PD as tf -> 0: {slope:.3f} (expected 1)")
    print()

    ll = {case: lti_symmetric_orbit(pair, lead_lag(**LEAD_LAG), OMEGA, x10=X10, n=N, case=case,
                                    fd_check=True)
          for case in ("collocated", "noncollocated")}
    pd_nc = symmetric_orbit(pair, PDGains(KP, KV), OMEGA, x10=X10, n=N, case="noncollocated")
    print("  lead-lag C(s) = {k:g} ({t_lead_zero:g}s+1)/({t_lead_pole:g}s+1) * "
          "({t_lag_zero:g}s+1)/({t_lag_pole:g}s+1)".format(**LEAD_LAG))
    for case, o in ll.items():
        ref = pd_sym if case == "collocated" else pd_nc
        print(f"    {case:>13}: exists = {o.exists}, xm = {o.xm:.6f}, rho = "
              f"{o.spectral_radius:.4g} (PD: {ref.spectral_radius:.4g}), stable = {o.stable}, "
              f"DP vs FD {o.DP_fd_error:.1e}")
        print(f"    {'':>13}  multipliers {fmt_mults(o.multipliers)}")

    # ---------------------------------------------------------------- figure
    fig = Figure(figsize=(12, 8.5), layout="constrained")
    ax = fig.subplots(2, 2)
    colors = ["tab:blue", "tab:orange", "tab:green", "tab:red"]

    # (a) one period of the secondary mass for PD / filtered PD, primary mass for reference
    a = ax[0, 0]
    T = pd_sym.T
    t = np.linspace(0.0, N * T, 600)
    s_pd = full_period(pd_num, t)
    a.plot(t, s_pd[:, 0], color="k", lw=2.5, alpha=0.35, label="$x_1$ (desired triangle)")
    a.plot(t, s_pd[:, 2], color="k", lw=1.5, label="$x_2$, PD")
    for o, tf, c in zip(filt, TFS, colors):
        a.plot(t, full_period(o, t)[:, 2], color=c, lw=1, ls="--", label=f"$x_2$, tf = {tf:g}")
    a.plot(t, full_period(ll["collocated"], t)[:, 2], color="tab:purple", lw=1, ls=":",
           label="$x_2$, lead-lag")
    a.set(xlabel="time since the +L impact", ylabel="position",
          title="(a) one period of the symmetric orbit (collocated)")
    a.legend(fontsize=8, loc="lower left")

    # (b) multipliers in the complex plane
    b = ax[0, 1]
    th = np.linspace(0, 2 * np.pi, 400)
    b.plot(np.cos(th), np.sin(th), color="0.6", lw=1)
    b.plot(pd_sym.multipliers.real, pd_sym.multipliers.imag, "ko", ms=9, mfc="none",
           label="PD (symbolic)")
    for o, tf, c in zip(filt, TFS, colors):
        b.plot(o.multipliers.real, o.multipliers.imag, "x", color=c, ms=7, label=f"tf = {tf:g}")
    m = ll["collocated"].multipliers
    b.plot(m.real, m.imag, "+", color="tab:purple", ms=9, label="lead-lag")
    m = ll["noncollocated"].multipliers
    b.plot(m.real, m.imag, "d", color="tab:brown", ms=6, mfc="none",
           label="lead-lag, non-collocated")
    b.set(xlabel="Re", ylabel="Im", title="(b) Floquet multipliers (unit circle)",
          aspect="equal", xlim=(-1.1, 1.1), ylim=(-1.1, 1.1))
    b.legend(fontsize=8, loc="lower left")

    # (c) convergence of xm and rho as tf -> 0 (log-log): slope 1
    cax = ax[1, 0]
    tf_grid = np.geomspace(1e-4, 0.3, 12)
    sweep = [lti_symmetric_orbit(pair, filtered_pd(KP, KV, tf), OMEGA, x10=X10, n=N,
                                 margin=False) for tf in tf_grid]
    exm = np.array([abs(o.xm - pd_sym.xm) for o in sweep])
    erho = np.array([abs(o.spectral_radius - pd_sym.spectral_radius) if o.exists else np.nan
                     for o in sweep])
    cax.loglog(tf_grid, exm, "o-", label=r"$|x_m - x_m^{PD}|$")
    cax.loglog(tf_grid, erho, "s-", label=r"$|\rho - \rho^{PD}|$")
    ref = exm[0] * tf_grid / tf_grid[0]
    cax.loglog(tf_grid, ref, "k:", label="slope 1")
    cax.set(xlabel="filter time constant tf", ylabel="difference to the PD",
            title="(c) filtered PD -> PD at rate O(tf)")
    cax.legend(fontsize=8)

    # (d) relative gap z3 = x1 - x2 over one flight: viability (|z3| < L inside)
    d = ax[1, 1]
    L = pair.L
    tt = np.linspace(pd_num.t0, pd_num.t0 + pd_num.tau, 400)
    for o, lab, c in ((pd_num, "PD", "k"), (filt[0], f"tf = {TFS[0]:g}", colors[0]),
                      (ll["collocated"], "lead-lag, collocated", "tab:purple"),
                      (ll["noncollocated"], "lead-lag, non-collocated", "tab:brown")):
        tt = np.linspace(o.t0, o.t0 + o.tau, 400)
        z = o.flight(tt)
        d.plot(tt - o.t0, (z[:, 0] - z[:, 2]) / L, color=c, label=lab)
    d.axhline(1, color="0.5", lw=0.8)
    d.axhline(-1, color="0.5", lw=0.8)
    d.set(xlabel="time since the +L impact", ylabel="$z_3 / L$",
          title="(d) gap during the flight +L -> -L (viability)")
    d.legend(fontsize=8)

    fig.suptitle("Impact pair, mu = 0.1, e = 0.5, gamma = 0.75, w = 5: PD vs filtered PD "
                 "and lead-lag")
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    print(f"\nfigure saved to {out}")


def full_period(o, t) -> np.ndarray:
    """Mechanical states over one period ``[t0, t0 + 2 tau)``; the second half is the mirror."""
    t = np.asarray(t, float)
    first = t < o.tau
    out = np.empty((t.size, o.loop.n_states))
    out[first] = o.flight(o.t0 + t[first])
    out[~first] = -o.flight(o.t0 + t[~first] - o.tau)
    return out


if __name__ == "__main__":
    main(example_args(__doc__).out / "filtered_pd.png")
