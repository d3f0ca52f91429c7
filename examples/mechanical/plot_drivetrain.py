"""A motor-shaft-gear-load drivetrain with backlash under PD: encoder on the motor or on the load
==============================================================================================

The drivetrain of ``examples/models/drivetrain.toml``: a motor (inertia 1) drives a gear (0.2)
through a flexible shaft (stiffness 50, damping 0.2); the gear drives the load (2, bearing
friction 0.5) through a backlash of +-0.1 rad (restitution 0.5); the motor has an end stop.
A PD with feed-forward makes the load follow ``xd = cos 2t``. This is the impact pair's two
cases on a real drivetrain: the encoder on the motor (collocated with the torque) or on the
load (non-collocated: the backlash and the shaft sit inside the loop).

With a small derivative gain both loops are stable and the load encoder tracks the load
better; raising ``kv`` from 2 to 5 keeps the motor-encoder loop bounded but destabilises the
load-encoder loop: the load and the motor (banging into its stop) oscillate violently.

Run: ``python examples/mechanical/plot_drivetrain.py [--out DIR] [--t-end T]``.
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


def parse(argv=None):
    p = argparse.ArgumentParser(description=(__doc__ or "").strip().split("\n")[0])
    p.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "hybridpd-examples",
                   help="directory for the figure (default: %(default)s)")
    p.add_argument("--t-end", type=float, default=40.0, help="simulated time (s)")
    p.add_argument("--quick", action="store_true",
                   help="a shorter run: a smoke test of the example, not its figure")
    args = p.parse_args(argv)
    if args.quick:
        args.t_end = min(args.t_end, 5.0)
    return args


def run(measure, kv, t_end):
    d = tomllib.loads(MODEL.read_text())
    d = copy.deepcopy(d)
    d["controller"].update(measure=measure, kv=kv)
    model = model_from_dict(d)
    traj = model.simulate(t_end)
    ts = np.linspace(0.0, t_end, 8001)
    z = traj(ts)
    return traj, ts, z


def main(argv=None):
    args = parse(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    fig = Figure(figsize=(11, 7), layout="constrained")
    axes = fig.subplots(2, 2, sharex=True)
    for row, kv in enumerate((2.0, 5.0)):
        for col, measure in enumerate(("motor", "load")):
            traj, ts, z = run(measure, kv, args.t_end)
            err = np.cos(2.0 * ts) - z[:, 0]
            late = ts > args.t_end / 2
            rms = float(np.sqrt(np.mean(err[late] ** 2)))
            held = sum(b - a for a, b, _ in traj.sticking)
            print(f"encoder on the {measure:5s}, kp 20, kv {kv:g}: {traj.n_impacts} backlash "
                  f"impacts, gear and load held together {held:.1f} s of {args.t_end:g} s, "
                  f"load tracking error (rms, second half) {rms:.3g} rad, "
                  f"largest |load| {np.abs(z[:, 0]).max():.3g} rad")
            ax = axes[row, col]
            ax.plot(ts, np.cos(2.0 * ts), "k--", lw=1, label="reference $x_d$")
            ax.plot(ts, z[:, 0], lw=1.2, label="load")
            ax.plot(ts, z[:, 4], lw=0.8, alpha=0.7, label="motor")
            for a, b, _ in traj.sticking:
                ax.axvspan(a, b, color="0.9", lw=0)
            if np.abs(z[:, 0]).max() > 3:
                ax.set_ylim(-3, 3)
                ax.text(0.02, 0.93, f"unstable: violent oscillation, |load| up to "
                        f"{np.abs(z[:, 0]).max():.3g} rad (clipped)", transform=ax.transAxes,
                        color="C3", fontsize=9, va="top",
                        bbox=dict(facecolor="white", edgecolor="none", alpha=0.85))
            ax.set_title(f"encoder on the {measure}, kv = {kv:g}: rms error {rms:.3g} rad",
                         fontsize=10)
            ax.set_ylabel("angle (rad)")
    axes[0, 0].legend(loc="upper right", fontsize=8)
    for ax in axes[1]:
        ax.set_xlabel("t (s)")
    fig.suptitle("PD on a drivetrain with backlash (kp = 20; grey: gear and load held "
                 "together)")
    path = args.out / "drivetrain.png"
    fig.savefig(path, dpi=110)
    print(f"figure written to {path}")


if __name__ == "__main__":
    main()
