"""``hybridpd simulate``."""
from __future__ import annotations

import json

from hybridpd.cli._common import JSON_HELP, add_plant, command

DESCRIPTION = ("Simulates the impact pair under PD control from an initial state: "
               "exact flows between impacts, guaranteed location of every impact, "
               "Zeno accumulation followed by sticking and release. Prints the "
               "impacts (time, wall, pre-impact state) and why the run stopped.")


def register(sub):
    p = command(sub, "simulate", help="simulate the controlled impact pair",
                description=DESCRIPTION,
                example=("hybridpd simulate --case collocated --mu 0.1 --e 0.5 --L "
                         "0.75 --omega 5 --kp 10 --kv 20 --xm 1 --x0 0.3 0.5 0 0 "
                         "--t-end 10"))
    add_plant(p)
    p.add_argument("--e", type=float, required=True, help="restitution coefficient in [0, 1]")
    p.add_argument("--kp", type=float, required=True,
                   help="proportional gain kp (> 0)")
    p.add_argument("--kv", type=float, required=True,
                   help="derivative gain kv (> 0)")
    p.add_argument("--x0", type=float, nargs=4, required=True, metavar=("X1", "Y1", "X2", "Y2"),
                   help="initial positions and velocities of both masses")
    p.add_argument("--t-end", type=float, required=True,
                   help="end time of the simulation (> 0)")
    p.add_argument("--max-impacts", type=int, default=100_000,
                   help="stop after this many impacts (the run says why it stopped)")
    p.add_argument("--json", action="store_true", help=JSON_HELP)
    p.set_defaults(func=run)


def run(args) -> int:
    from hybridpd.model import ImpactPair, PDGains, Reference
    from hybridpd.pair.impactpair import ControlledImpactPair

    sysm = ControlledImpactPair(ImpactPair(args.mu, args.e, args.L, args.m2),
                                PDGains(args.kp, args.kv), Reference(args.xm, args.omega),
                                args.case)
    traj = sysm.simulate(args.x0, (0.0, args.t_end), max_impacts=args.max_impacts)
    d = traj.to_dict()
    if args.json:
        print(json.dumps(d))
        return 0
    print(f"{args.case} impact pair, t in [0, {traj.t_final:g}]: {traj.n_impacts} impacts "
          f"({int((traj.walls > 0).sum())} on wall +L, {int((traj.walls < 0).sum())} on -L), "
          f"{len(traj.sticking)} sticking interval(s); stopped: {d['termination']}")
    for imp in d["impacts"][:10]:
        print(f"  t = {imp['t']:.10f}  wall {imp['wall']:+d}  pre = "
              + " ".join(f"{v:+.6f}" for v in imp["pre"]))
    if traj.n_impacts > 10:
        print(f"  ... {traj.n_impacts - 10} more (use --json for all)")
    for a, b in d["sticking"]:
        print(f"  sticking on [{a:.10f}, {b:.10f}]")
    return 0
