"""A rigid contact against compliant contacts of growing stiffness: convergence
============================================================================

The impact pair of the paper (m1 = 0.1, m2 = 1, half clearance 0.75, PD on x1) with its
clearance modelled as a Kelvin-Voigt contact: a spring k and damper c act while the gap is
closed (piecewise-linear modes, the reference [8] of the paper). With the damping ratio
``zeta = c / (2 sqrt(k m*))`` fixed (``m* = m1 m2 / (m1 + m2)``), an isolated contact returns
the relative velocity times ``e = exp(-zeta pi / sqrt(1 - zeta^2))``. As k grows the contact
lasts ``~ pi sqrt(m* / k)`` and the compliant motion converges to the rigid one with that
``e``: the impact times and the apparent restitution both converge like ``k^-1/2``.

Run: ``python examples/mechanical/plot_compliant_contact.py [--out DIR]``.
"""
from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from hybridpd.mechanics import (
    Contact,
    MechanicalSystem,
    Reference,
    build_automaton,
    mechanical_loop,
)
from hybridpd.mechanics.simulate import simulate

PAIR = MechanicalSystem(["x1", "x2"], M=[[0.1, 0.0], [0.0, 1.0]], B=[0.0, 1.0])
MSTAR = 0.1 / 1.1
X0 = [0.3, 0.5, 0.0, 0.0]
N_IMPACTS = 4


def parse(argv=None):
    p = argparse.ArgumentParser(description=(__doc__ or "").strip().split("\n")[0])
    p.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "hybridpd-examples",
                   help="directory for the figure (default: %(default)s)")
    p.add_argument("--zeta", type=float, default=0.2, help="contact damping ratio in (0, 1)")
    p.add_argument("--quick", action="store_true",
                   help="a shorter run: a smoke test of the example, not its figure")
    args = p.parse_args(argv)
    return args


def run(contact, t_end=0.6):
    loop = mechanical_loop(PAIR, (10.0, 20.0), Reference.sine(1.0, 5.0, 1.0), "x1")
    model = build_automaton(loop, [contact])
    return model, simulate(model, X0, (0.0, t_end))


def engagements(model, traj):
    """(entry time, entry gap speed, exit gap speed) of each compliant engagement."""
    out, entry = [], None
    jt = traj.hybrid.jumps
    for t, src, g, pre in zip(jt.t, jt.source, jt.guard, jt.pre):
        kind = model.guards[(src, g)].kind
        if kind == "enter":
            entry = (t, pre[1] - pre[3])
        elif kind == "leave" and entry is not None:
            out.append((entry[0], entry[1], pre[1] - pre[3]))
            entry = None
    return out


def main(argv=None):
    args = parse(argv)
    if not 0.0 < args.zeta < 1.0:
        raise SystemExit("--zeta must be in (0, 1)")
    args.out.mkdir(parents=True, exist_ok=True)
    zeta = args.zeta
    e_eq = math.exp(-zeta * math.pi / math.sqrt(1.0 - zeta ** 2))
    _, rigid = run(Contact([1.0, -1.0], -0.75, 0.75, restitution=e_eq))
    print(f"zeta = {zeta:g}: equivalent restitution e = {e_eq:.4f}; rigid contact: impacts at "
          + ", ".join(f"{t:.5f}" for t in rigid.impact_times[:N_IMPACTS]))
    ts = np.linspace(0.0, 0.6, 4001)
    fig = Figure(figsize=(11, 7.5), layout="constrained")
    ax_gap, ax_conv = fig.subplots(2, 1)
    ax_gap.plot(ts, rigid.mechanical(ts) @ [1, 0, -1, 0], "k", lw=1.8,
                label=f"rigid, e = {e_eq:.3f}")
    ks = 10.0 ** np.arange(3, 8)
    err_t, err_e = [], []
    for i, k in enumerate(ks):
        c = 2.0 * zeta * math.sqrt(k * MSTAR)
        model, traj = run(Contact([1.0, -1.0], -0.75, 0.75, stiffness=k, damping=c))
        ev = engagements(model, traj)[:N_IMPACTS]
        err_t.append(max(abs(a - b) for (a, _, _), b in zip(ev, rigid.impact_times)))
        err_e.append(max(abs(-out / inn - e_eq) for _, inn, out in ev))
        print(f"k = {k:8.0e}, c = {c:7.3g}: engagements at "
              + ", ".join(f"{a:.5f}" for a, *_ in ev)
              + "; apparent e = " + ", ".join(f"{-o / i_:.4f}" for _, i_, o in ev))
        if k <= 1e5:
            ax_gap.plot(ts, traj.mechanical(ts) @ [1, 0, -1, 0], color=f"C{i}", lw=1,
                        label=f"compliant, k = {k:.0e}")
    ax_gap.axhline(0.75, color="0.5", lw=0.8, ls=":")
    ax_gap.axhline(-0.75, color="0.5", lw=0.8, ls=":")
    ax_gap.set_xlabel("t")
    ax_gap.set_ylabel("gap x1 - x2")
    ax_gap.legend(fontsize=8, ncol=2)
    ax_conv.loglog(ks, err_t, "o-", label=f"impact times (first {N_IMPACTS})")
    ax_conv.loglog(ks, err_e, "s-", label="apparent restitution")
    ax_conv.loglog(ks, err_t[0] * (ks / ks[0]) ** -0.5, "k:", label="slope -1/2")
    ax_conv.set_xlabel("contact stiffness k")
    ax_conv.set_ylabel("largest deviation from the rigid contact")
    ax_conv.legend(fontsize=8)
    order = -np.polyfit(np.log(ks), np.log(err_t), 1)[0]
    print(f"measured order in k: impact times {order:.3f}, restitution "
          f"{-np.polyfit(np.log(ks), np.log(err_e), 1)[0]:.3f} (expected 0.5)")
    fig.suptitle(f"Compliant (Kelvin-Voigt, zeta = {zeta:g}) versus rigid contact in the "
                 "impact pair")
    path = args.out / "compliant_contact.png"
    fig.savefig(path, dpi=110)
    print(f"figure written to {path}")


if __name__ == "__main__":
    main()
