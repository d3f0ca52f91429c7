"""``hybridpd simulate``: the impact pair from options, or any mechanical model file."""
from __future__ import annotations

import json

from hybridpd.cli._common import JSON_HELP, UsageError, case_type, command

# the pair options: required without --model, forbidden with it
_PAIR = ("case", "mu", "m2", "omega", "L", "gamma", "x10", "xm", "e", "kp", "kv", "x0")
_REQUIRED = ("case", "mu", "omega", "xm", "e", "kp", "kv", "x0")

DESCRIPTION = ("Simulates the impact pair under PD control (or, with --model, any "
               "mechanical model file) from an initial state: exact flows between "
               "impacts, guaranteed location of every impact, Zeno accumulation followed "
               "by sticking and release. Prints the impacts (time, contact, wall, "
               "pre-impact state) and why the run stopped.")


def register(sub):
    p = command(sub, "simulate", help="simulate the controlled impact pair or a model file",
                description=DESCRIPTION,
                example=("hybridpd simulate --case collocated --mu 0.1 --e 0.5 --L "
                         "0.75 --omega 5 --kp 10 --kv 20 --xm 1 --x0 0.3 0.5 0 0 "
                         "--t-end 10\n  hybridpd simulate --model "
                         "examples/models/drivetrain.toml --t-end 20 --json"))
    p.add_argument("--model", default=None, metavar="FILE.toml",
                   help="mechanical model file (then the impact-pair options are not used)")
    p.add_argument("--case", default=None, type=case_type, metavar="CASE",
                   help="collocated (the PD loop measures x2) or noncollocated (it measures "
                        "x1; alias non-collocated)")
    p.add_argument("--mu", type=float, default=None, help="mass ratio m1/m2 (> 0)")
    p.add_argument("--m2", type=float, default=None, help="secondary mass m2 (> 0; default 1)")
    p.add_argument("--omega", type=float, default=None, help="reference frequency (> 0)")
    p.add_argument("--L", type=float, default=None,
                   help="half clearance (> 0); or give --gamma (and --x10)")
    p.add_argument("--gamma", type=float, default=None, help="clearance ratio L / x10 (> 0)")
    p.add_argument("--x10", type=float, default=None,
                   help="amplitude of the primary mass's desired motion, with --gamma "
                        "(> 0; default 1)")
    p.add_argument("--xm", type=float, default=None, help="reference amplitude (>= 0)")
    p.add_argument("--e", type=float, default=None, help="restitution coefficient in [0, 1]")
    p.add_argument("--kp", type=float, default=None, help="proportional gain kp (> 0)")
    p.add_argument("--kv", type=float, default=None, help="derivative gain kv (> 0)")
    p.add_argument("--x0", type=float, nargs=4, default=None, metavar=("X1", "Y1", "X2", "Y2"),
                   help="initial positions and velocities of both masses")
    p.add_argument("--t-end", type=float, required=True,
                   help="end time of the simulation (> 0)")
    p.add_argument("--max-impacts", type=int, default=100_000,
                   help="stop after this many impacts (the run says why it stopped)")
    p.add_argument("--json", action="store_true", help=JSON_HELP)
    p.set_defaults(func=run)


def run(args) -> int:
    if args.model is not None:
        given = [f"--{k.replace('_', '-')}" for k in _PAIR if getattr(args, k) is not None]
        if given:
            raise UsageError(f"--model: cannot be combined with the impact-pair options "
                             f"({', '.join(given)})")
        return _run_model(args)
    missing = [f"--{k}" for k in _REQUIRED if getattr(args, k) is None]
    if args.L is None and args.gamma is None:
        missing.append("--L (or --gamma)")
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
    sysm = ControlledImpactPair(ImpactPair(args.mu, args.e, _half_clearance(args), m2),
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


def _half_clearance(args) -> float:
    """``--L``, or ``--gamma`` times ``--x10`` (default 1); both only if they agree."""
    from hybridpd.model import check_positive

    x10 = 1.0 if args.x10 is None else check_positive("x10", args.x10)
    if args.gamma is None:
        if args.x10 is not None:
            raise UsageError("--x10 is only used with --gamma (L = gamma x10)")
        return check_positive("L", args.L)
    L = check_positive("gamma", args.gamma) * x10
    if args.L is not None and abs(check_positive("L", args.L) - L) > 1e-12 * L:
        raise UsageError(f"--L {args.L:g} and --gamma {args.gamma:g} --x10 {x10:g} disagree "
                         f"(gamma x10 = {L:g}); give one or the other")
    return L
