"""``hybridpd bifurcation``: a brute-force bifurcation diagram of the impact map."""
from __future__ import annotations

import math
import sys

from hybridpd.cli._common import (
    EXIT_NO_ORBIT,
    UsageError,
    add_executor,
    add_max_period,
    add_model,
    add_output,
    add_pair,
    check_image,
    check_out,
    executor_of,
    print_json,
    require,
    stamp_controllers,
    write_figure,
)

#: Parameters the command can sweep (``--param NAME``).
SWEEPABLE = ("kp", "kv", "e", "mu", "gamma", "omega", "m2")
_REQUIRED = ("e", "mu", "gamma", "omega", "kp", "kv")

_DESCRIPTION = """\
Brute-force bifurcation diagram of the impact map P in one parameter.

For NUM values of the swept parameter between MIN and MAX, P is iterated ITERATIONS times
from one initial condition (or, with --follow, from the previous value's final state) and
the last KEEP section points (phi, z1, z2, z4) are kept. Each value is classified
(periodic with its period, quasiperiodic, chaotic, diverged, sticking, no_impact,
unresolved, undefined) and the largest Lyapunov exponent of P is estimated from the
product of the Jacobians DP along the iterates.

The reference amplitude xm follows the design at every value: the one that puts the
primary mass on the order-N symmetric orbit of amplitude x10 (gamma = L / x10, see the
conventions (CONVENTIONS.md)). Every parameter other than the swept one must be given (m2 and x10
default to 1); the swept one must not be. The diagram is written to --out (.nc or .zarr).

With --model FILE.toml the map is the model's section map (--contact, --wall, --event,
--period) and --param sweeps any numeric entry of the file, named by its dotted TOML path
(controller.kp, contact.0.restitution, system.masses.2, reference.omega, ...; --list-params
prints them with their values); the diagram is written to --out as .nc or .zarr.
"""

_EPILOG = """\
example (the paper's parameters, kv swept, following):
  hybridpd bifurcation --case collocated --mu 0.1 --e 0.1 --gamma 0.75 --omega 5 --n 1 \\
      --kp 10 --param kv 10 35 200 --iterations 1000 --keep 100 --follow \\
      --out kv.nc --plot kv.png
  hybridpd bifurcation --model examples/models/robot_joint_pd.toml --event release \\
      --param controller.kv 0.5 12 60 --out kv.nc --plot kv.png

exit status:
  0  done
  2  bad input (one line on stderr)
  3  --model: no value has an answer (no periodic, quasi-periodic or chaotic motion, no
     sticking): one line on stderr counts the classes; the diagram is written all the same
"""


def register(sub):
    p = sub.add_parser("bifurcation", help="brute-force bifurcation diagram of the impact map",
                       description=_DESCRIPTION, epilog=_EPILOG)
    # m2 defaults to None: with --model a given --m2 is refused
    add_pair(p, names=("case", "mu", "m2", "omega", "gamma", "x10", "e", "kp", "kv", "n"),
             m2=None)
    p.add_argument("--param", nargs=4, default=None, metavar=("NAME", "MIN", "MAX", "NUM"),
                   help=f"swept parameter (required), from MIN to MAX (MIN < MAX) in NUM >= 2 "
                   f"values: for the impact pair one of {', '.join(SWEEPABLE)}; with --model "
                   "a dotted path of the file (see --list-params)")
    p.add_argument("--iterations", type=int, default=1000,
                   help="iterations of P per value (default 1000)")
    p.add_argument("--keep", type=int, default=100,
                   help="last iterates kept per value (8 <= KEEP <= ITERATIONS, default 100)")
    p.add_argument("--follow", action="store_true",
                   help="start each value from the previous value's final state")
    p.add_argument("--initial", type=float, nargs=4, metavar=("PHI", "Z1", "Z2", "Z4"),
                   help="initial section point (default: the symmetric fixed point at MIN, "
                   "displaced by 1e-3 in z1)")
    add_max_period(p, 32)
    add_output(p, out=(".nc", ".zarr", ".npz"), what="the diagram (required)",
               plot="the diagram")
    p.add_argument("--coordinate", default="z1",
                   choices=["phi", "z1", "z2", "z4", "x1", "y1", "x2", "y2"],
                   help="section coordinate on the plot's y axis (default z1)")
    add_model(p, set_option=False)
    add_executor(p, default="serial", quiet=False)
    p.set_defaults(func=run)


def _sweep(args):
    name, lo, hi, num = args.param
    if name not in SWEEPABLE:
        raise ValueError(f"--param NAME must be one of {', '.join(SWEEPABLE)}, got {name!r}")
    try:
        lo, hi, num_f = float(lo), float(hi), float(num)
    except ValueError:
        raise ValueError(f"--param MIN MAX NUM must be numbers, got {args.param[1:]}") from None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ValueError(f"--param MIN and MAX must be finite, got {lo:g}, {hi:g}")
    if lo >= hi:
        raise ValueError(f"--param MIN must be < MAX, got {lo:g} >= {hi:g}")
    if num_f != int(num_f) or num_f < 2:
        raise ValueError(f"--param NUM must be an integer >= 2, got {num}")
    if getattr(args, name) is not None:
        raise ValueError(f"{name} is swept by --param and must not also be given as --{name}")
    missing = [f"--{k}" for k in _REQUIRED if k != name and getattr(args, k) is None]
    if missing:
        raise ValueError(f"missing {', '.join(missing)} (every parameter but the swept one is "
                         "required)")
    return name, lo, hi, int(num_f)


def run(args) -> int:
    require(args, "param", "out")
    if args.model is not None:
        return _run_model(args)
    if args.case is None:
        raise UsageError("the following arguments are required: --case (or give --model "
                         "FILE.toml)")
    # deferred import: loaded only when this runs, for start-up time
    import numpy as np

    from hybridpd.analysis.diagrams import bifurcation_diagram
    from hybridpd.model import ImpactPair, PDGains
    from hybridpd.pair.bifdiagram import PAIR_SETTINGS, ImpactMapFamily

    name, lo, hi, num = _sweep(args)
    if args.iterations < 1:
        raise ValueError(f"--iterations must be >= 1, got {args.iterations}")
    if args.keep > args.iterations:
        raise ValueError(f"--keep ({args.keep}) must not exceed --iterations "
                         f"({args.iterations})")
    check_out(args.out)
    check_image(args.plot)
    values = np.linspace(lo, hi, num)
    v0 = {k: getattr(args, k) for k in ("e", "mu", "gamma", "omega", "kp", "kv", "m2")}
    v0["m2"] = 1.0 if v0["m2"] is None else v0["m2"]
    v0[name] = lo
    if not (v0["gamma"] > 0 and args.x10 > 0):
        raise ValueError(f"gamma and x10 must be > 0, got {v0['gamma']!r}, {args.x10!r}")
    pair = ImpactPair(v0["mu"], v0["e"], v0["gamma"] * args.x10, v0["m2"])
    fam = ImpactMapFamily(pair, PDGains(v0["kp"], v0["kv"]), v0["omega"], name, args.case,
                          args.x10, args.n)
    opts = dict(PAIR_SETTINGS, s0=args.initial, iterations=args.iterations, keep=args.keep,
                max_period=args.max_period)
    executor = executor_of(args)
    if executor == "serial":
        d = bifurcation_diagram(fam, values, **dict(opts, follow=args.follow))
    elif args.follow:
        raise UsageError("--follow runs the values one after another: it cannot be spread "
                         "over --executor/--scheduler workers")
    else:
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.sweeps.diagrams import diagram_sweep

        opts.pop("follow")
        d = diagram_sweep(fam, values, executor=executor, max_workers=args.workers, **opts)
    d.save(args.out)
    branch = None
    if args.plot:
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.plotting.bifurcation import plot_bifurcation

        branches, branch = _symmetric_branch(pair, v0, name, hi, args)
        write_figure(plot_bifurcation(d, coordinate=args.coordinate, branches=branches),
                    args.plot)
    if args.json:
        lya = [None if not np.isfinite(x) else float(x) for x in d.lyapunov]
        print_json({
            "parameter": name, "values": values.tolist(), "classification": d.classification,
            "period": [int(k) for k in d.period], "lyapunov": lya,
            "cycles": [d.cycle(i).tolist() for i in range(len(d))],
            "xm": [None if not np.isfinite(x) else float(x) for x in d.xm],
            "counts": d.counts(), "fixed": d.fixed, "case": d.case,
            "iterations": d.iterations, "keep": d.keep, "follow": d.follow,
            "out": str(args.out), "plot": args.plot, "branch": branch})
        return 0
    counts = ", ".join(f"{n} {c}" for c, n in d.counts().items() if n)
    print(f"{args.case} bifurcation diagram in {name} [{lo:g}, {hi:g}] ({num} values, last "
          f"{d.keep} of {d.iterations} iterates{', following' if d.follow else ''}): {counts}")
    periods = {int(k): int(np.sum(d.period == k)) for k in np.unique(d.period) if k}
    if periods:
        print("  periods: " + ", ".join(f"{k}: {n} values" for k, n in periods.items()))
        if any(k > 1 for k in periods):
            print("  (period k: the kept section points repeat every k applications of P, "
                  "i.e. k impacts per cycle; the paper's symmetric orbit has period 1)")
    if branch:
        print(f"  {branch['note']}")
    print(f"  wrote {args.out}" + (f" and {args.plot}" if args.plot else ""))
    return 0


def _symmetric_branch(pair, v0, name, stop, args):
    """The symmetric orbit continued over the sweep (drawn over the diagram, stable solid,
    unstable dashed), and what was drawn: ``{"drawn", "points", "termination", "note"}``
    (``termination``: why the continuation stopped, with the parameter value; ``note``: a
    line saying what was drawn or why not)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.model import PDGains
    from hybridpd.pair.continuation import continue_symmetric

    try:
        br = continue_symmetric(pair, PDGains(v0["kp"], v0["kv"]), v0["omega"], name,
                                stop, x10=args.x10, n=args.n, case=args.case)
    except ValueError as exc:
        return (), {"drawn": False, "points": 0, "termination": None,
                    "note": f"no continued branch drawn: {exc}"}
    return [br], {"drawn": True, "points": len(br), "termination": br.termination,
                  "note": (f"continued symmetric branch drawn ({len(br)} points, stopped: "
                           f"{br.termination})")}


def _run_model(args) -> int:
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.sweeps.model_diagrams import model_diagram

    if args.periods is not None:
        raise UsageError("--periods: the diagram iterates P^k (--period); it does not select "
                         "orbits by their reference periods")
    given = [f"--{k}" for k in ("case", *_REQUIRED, "m2") if getattr(args, k) is not None]
    if given:
        raise UsageError(f"{', '.join(given)}: impact-pair options, not used with --model "
                         "(sweep the file's entry with --param KEY MIN MAX NUM)")
    check_out(args.out)
    check_image(args.plot)
    d = model_diagram(args.model, tuple(args.param), contact=args.contact, wall=args.wall,
                      event=args.event, period=args.period, iterations=args.iterations,
                      mode=args.mode, phase=args.phase, keep=args.keep,
                      max_period=min(args.max_period, args.keep // 2),
                      executor=executor_of(args), max_workers=args.workers, progress=False)
    d = stamp_controllers(d, args)
    d.save(args.out)
    if args.plot:
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.plotting.bifurcation import plot_bifurcation

        write_figure(plot_bifurcation(d), args.plot)
    if args.json:
        print_json(dict(d.to_dict(), out=str(args.out), plot=args.plot))
    else:
        print(d.summary())
        print(f"  wrote {args.out}" + (f" and {args.plot}" if args.plot else ""))
    return _no_answer(d)


def _no_answer(d) -> int:
    """:data:`~hybridpd.cli._common.EXIT_NO_ORBIT` with one line on stderr saying what every
    value reported when no value of a model's diagram has an answer (periodic,
    quasi-periodic or chaotic motion, sticking or no impact); else 0."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.analysis.diagrams import ANSWERS

    counts = d.counts()
    if any(counts.get(c) for c in ANSWERS):
        return 0
    text = ", ".join(f"{n} {c}" for c, n in counts.items() if n)
    print(f"hybridpd bifurcation: no value has an answer (no motion the map could follow): "
          f"{text}", file=sys.stderr)
    return EXIT_NO_ORBIT
