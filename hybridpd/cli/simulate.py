"""``hybridpd simulate``."""
from __future__ import annotations

import json

from hybridpd.cli._common import add_plant


def register(sub):
    p = sub.add_parser("simulate", help="simulate the controlled impact pair")
    add_plant(p)
    p.add_argument("--e", type=float, required=True, help="restitution coefficient in [0, 1]")
    p.add_argument("--kp", type=float, required=True)
    p.add_argument("--kv", type=float, required=True)
    p.add_argument("--x0", type=float, nargs=4, required=True, metavar=("X1", "Y1", "X2", "Y2"))
    p.add_argument("--t-end", type=float, required=True)
    p.add_argument("--max-impacts", type=int, default=100_000)
    p.add_argument("--json", action="store_true")
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
