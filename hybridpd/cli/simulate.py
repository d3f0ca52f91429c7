"""``hybridpd simulate``: the impact pair from options, or any mechanical model file."""
from __future__ import annotations

import json

from hybridpd.cli._common import UsageError

# the pair options: required without --model, forbidden with it
_PAIR = ("case", "mu", "m2", "omega", "L", "xm", "e", "kp", "kv", "x0")
_REQUIRED = ("case", "mu", "omega", "L", "xm", "e", "kp", "kv", "x0")


def register(sub):
    p = sub.add_parser("simulate", help="simulate the controlled impact pair, or a mechanical "
                       "model file (--model)")
    p.add_argument("--model", default=None, metavar="FILE.toml",
                   help="mechanical model file (then the impact-pair options are not used)")
    p.add_argument("--case", default=None, choices=["collocated", "noncollocated"])
    p.add_argument("--mu", type=float, default=None, help="mass ratio m1/m2 (> 0)")
    p.add_argument("--m2", type=float, default=None, help="secondary mass (> 0), default 1")
    p.add_argument("--omega", type=float, default=None, help="reference frequency (> 0)")
    p.add_argument("--L", type=float, default=None, help="half clearance (> 0)")
    p.add_argument("--xm", type=float, default=None, help="reference amplitude (>= 0)")
    p.add_argument("--e", type=float, default=None, help="restitution coefficient in [0, 1]")
    p.add_argument("--kp", type=float, default=None)
    p.add_argument("--kv", type=float, default=None)
    p.add_argument("--x0", type=float, nargs=4, default=None, metavar=("X1", "Y1", "X2", "Y2"))
    p.add_argument("--t-end", type=float, required=True)
    p.add_argument("--max-impacts", type=int, default=100_000)
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=run)


def run(args) -> int:
    if args.model is not None:
        given = [f"--{k.replace('_', '-')}" for k in _PAIR if getattr(args, k) is not None]
        if given:
            raise UsageError(f"--model: cannot be combined with the impact-pair options "
                             f"({', '.join(given)})")
        return _run_model(args)
    missing = [f"--{k}" for k in _REQUIRED if getattr(args, k) is None]
    if missing:
        raise UsageError(f"the following arguments are required: {', '.join(missing)} "
                         "(or give --model FILE.toml)")
    return _run_pair(args)


def _run_model(args) -> int:
    from hybridpd.mechanics.modelfile import load_model

    model = load_model(args.model)
    traj = model.simulate(args.t_end, max_impacts=args.max_impacts)
    d = traj.to_dict()
    if args.json:
        print(json.dumps(d))
        return 0
    dofs = model.system.dofs
    print(f"{model.source}: {len(dofs)} DOFs ({', '.join(dofs)}), {len(model.contacts)} "
          f"contact(s); t in [{model.t0:g}, {traj.t_final:g}]: {traj.n_impacts} impacts, "
          f"{len(traj.sticking)} sticking interval(s); stopped: {d['termination']}")
    for imp in d["impacts"][:10]:
        print(f"  t = {imp['t']:.10f}  contact {imp['contact']}  wall {imp['wall']:+d}")
    if traj.n_impacts > 10:
        print(f"  ... {traj.n_impacts - 10} more (use --json for all)")
    for a, b, k in d["sticking"]:
        print(f"  sticking on contact {k} on [{a:.10f}, {b:.10f}]")
    return 0


def _run_pair(args) -> int:
    from hybridpd.model import ImpactPair, PDGains, Reference
    from hybridpd.pair.impactpair import ControlledImpactPair

    m2 = 1.0 if args.m2 is None else args.m2
    sysm = ControlledImpactPair(ImpactPair(args.mu, args.e, args.L, m2),
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
    for a, b, *_ in d["sticking"]:
        print(f"  sticking on [{a:.10f}, {b:.10f}]")
    return 0
