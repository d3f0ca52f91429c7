"""The drivetrain with a digital PD: zero-order hold at several sampling periods
=============================================================================

The drivetrain of ``examples/models/drivetrain.toml`` (motor, flexible shaft, gear, backlash,
load; encoder on the motor, kp 20, kv 5, feed-forward) with the PD implemented as a
discrete-time python-control system (``dt > 0``). The loop is sampled-data: the torque is
held between the sampling instants ``k dt`` (exact jumps of the hybrid automaton, a clock
state with an affine guard), the plant flows exactly in between. As ``dt`` shrinks the motion
converges to the continuous-time loop's (first order in ``dt``); slow sampling adds phase lag
and makes the load hit the gear harder. An input delay of whole samples is one more option
(``delay = 1`` shown dashed).

Run: ``python examples/mechanical/plot_sampled_drivetrain.py [--out DIR] [--t-end T]``.
"""
from __future__ import annotations

import argparse
import copy
import sys
import tempfile
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from hybridpd.mechanics.modelfile import model_from_dict

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

# the examples folder, from the script run (sphinx-gallery defines no __file__)
MODEL = Path(sys.argv[0]).resolve().parents[1] / "models" / "drivetrain.toml"
PERIODS = (0.002, 0.02, 0.05, 0.1)


def parse(argv=None):
    p = argparse.ArgumentParser(description=(__doc__ or "").strip().split("\n")[0])
    p.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "hybridpd-examples",
                   help="directory for the figure (default: %(default)s)")
    p.add_argument("--t-end", type=float, default=12.0, help="simulated time (s)")
    p.add_argument("--quick", action="store_true",
                   help="a shorter run: a smoke test of the example, not its figure")
    args = p.parse_args(argv)
    if args.quick:
        args.t_end = min(args.t_end, 2.0)
    return args


def simulate(t_end, dt=None, delay=0):
    """The trajectory and the torque row (``u = force @ state``) of the drivetrain."""
    d = copy.deepcopy(tomllib.loads(MODEL.read_text()))
    if dt is not None:
        d["controller"].update(dt=dt, delay=delay)
    model = model_from_dict(d)
    return model.simulate(t_end), model.automaton.loop.force


def main(argv=None):
    args = parse(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    ts = np.linspace(0.0, args.t_end, 6001)
    cont, force = simulate(args.t_end)
    zc = cont(ts)
    fig = Figure(figsize=(11, 8), layout="constrained")
    ax_load, ax_u, ax_err = fig.subplots(3, 1)
    ax_load.plot(ts, np.cos(2 * ts), "k--", lw=1, label="reference")
    ax_load.plot(ts, zc[:, 0], "k", lw=1.5, label="continuous PD")
    window = ts <= min(args.t_end, 2.0)
    ax_u.plot(ts[window], zc[window] @ force, "k", lw=1.2, label="continuous")
    errs = []
    for i, dt in enumerate(PERIODS):
        tr, force = simulate(args.t_end, dt)
        z = tr(ts)
        err = np.abs(z[:, 0] - zc[:, 0]).max()
        errs.append(err)
        print(f"dt = {dt:<6g}: {tr.samples.size} samples, {tr.n_impacts} impacts, "
              f"largest load deviation from the continuous loop {err:.3g} rad")
        ax_load.plot(ts, z[:, 0], color=f"C{i}", lw=1, label=f"dt = {dt:g}")
        ax_u.plot(ts[window], (z @ force)[window], color=f"C{i}", lw=1, label=f"dt = {dt:g}")
    trd, _ = simulate(args.t_end, 0.05, delay=1)
    ax_load.plot(ts, trd(ts)[:, 0], color="C2", ls=":", lw=1.2, label="dt = 0.05, delay 1")
    fine = np.array(PERIODS[:3])
    slope = np.polyfit(np.log(fine), np.log(errs[:3]), 1)[0]
    print(f"measured order of convergence in dt (three smallest periods): {slope:.2f}")
    ax_err.loglog(PERIODS, errs, "o-", label="largest load deviation")
    ax_err.loglog(fine, errs[0] * fine / fine[0], "k:", label="slope 1")
    ax_load.set_ylabel("load angle (rad)")
    ax_load.set_xlabel("t (s)")
    ax_load.legend(ncol=4, fontsize=8, loc="upper right")
    ax_u.set_ylabel("motor torque (N m)")
    ax_u.set_xlabel("t (s), first 2 s: the held torque steps")
    ax_u.legend(ncol=5, fontsize=8)
    ax_err.set_xlabel("sampling period dt (s)")
    ax_err.set_ylabel("max |load - continuous| (rad)")
    ax_err.legend(fontsize=8)
    fig.suptitle("Sampled-data PD (zero-order hold) on the drivetrain with backlash")
    path = args.out / "sampled_drivetrain.png"
    fig.savefig(path, dpi=110)
    print(f"figure written to {path}")


if __name__ == "__main__":
    main()
