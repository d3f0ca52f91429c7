"""``hybridpd simulate``: the impact pair from options, or any mechanical model file.

The plant and reference are given either as ``--L`` and ``--xm`` (clearance and reference
amplitude) or as ``--gamma`` and ``--x10`` (``L = gamma x10``, and ``xm`` the amplitude that
realises the symmetric orbit with primary-mass amplitude ``x10`` at these gains). Both may be
given when they agree.
"""
from __future__ import annotations

import math
import sys

from hybridpd.cli._common import (
    EXIT_DIVERGED,
    EXIT_OK,
    EXIT_STOPPED_EARLY,
    JSON_HELP,
    UsageError,
    add_model,
    add_set,
    case_type,
    check_image,
    check_out,
    command,
    controllers_of,
    dumps_json,
    model_of,
    print_json,
    require,
    save_figure,
    set_values,
)

# the pair options: required without --model, forbidden with it
_PAIR = ("case", "mu", "m2", "omega", "L", "gamma", "x10", "xm", "e", "kp", "kv", "x0")
_REQUIRED = ("case", "mu", "omega", "e", "kp", "kv", "x0")

DESCRIPTION = ("Simulates the impact pair under PD control (or, with --model, any "
               "mechanical model file) from an initial state: exact flows between "
               "impacts, guaranteed location of every impact, Zeno accumulation followed "
               "by sticking and release. Prints the impacts (time, contact, wall, "
               "pre-impact state) and why the run stopped.")

NOTES = """\
exit status:
  0  the run reached --t-end
  2  bad input (one line on stderr)
  4  the run diverged: the state overflowed (nonfinite) or grew past the divergence bound
     (diverged), or contacts closing at one instant had no joint impact
     (simultaneous_contact)
  5  the run stopped before --t-end at a bound: --max-impacts jumps (jump_limit), the bound
     on flow steps (step_limit), or an accumulation of impacts it cannot continue past (zeno)
  With 4 and 5 one line on stderr names the termination and the time it happened; the
  output (text, --json, --out, --plot) is still written."""


def register(sub):
    p = command(sub, "simulate", help="simulate the controlled impact pair or a model file",
                description=DESCRIPTION,
                example=("hybridpd simulate --case collocated --mu 0.1 --e 0.5 --L "
                         "0.75 --omega 5 --kp 10 --kv 20 --xm 1 --x0 0.3 0.5 0 0 "
                         "--t-end 10\n  hybridpd simulate --model "
                         "examples/models/drivetrain.toml --t-end 20 --out run.json "
                         "--plot run.png"), notes=NOTES)
    add_model(p, uses="--set KEY VALUE sets them")
    add_set(p)
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
                   help="amplitude of the primary mass's desired motion (> 0; default 1 "
                        "with --gamma): xm is then the amplitude realising the symmetric orbit")
    p.add_argument("--n", type=int, default=1, help="orbit order for --x10 (odd)")
    p.add_argument("--xm", type=float, default=None,
                   help="reference amplitude (>= 0); or give --x10 (with --gamma or --L)")
    p.add_argument("--e", type=float, default=None, help="restitution coefficient in [0, 1]")
    p.add_argument("--kp", type=float, default=None, help="proportional gain kp (> 0)")
    p.add_argument("--kv", type=float, default=None, help="derivative gain kv (> 0)")
    p.add_argument("--x0", type=float, nargs=4, default=None, metavar=("X1", "Y1", "X2", "Y2"),
                   help="initial positions and velocities of both masses")
    p.add_argument("--t-end", type=float, default=None,
                   help="end time of the simulation (> 0; required)")
    p.add_argument("--max-impacts", type=int, default=100_000,
                   help="stop after this many impacts (with --model: jumps other than "
                        "sampling instants); the run then exits with status 5")
    p.add_argument("--json", action="store_true", help=JSON_HELP)
    p.add_argument("--out", default=None, metavar="FILE.json",
                   help="write the JSON result plus dense samples of the trajectory (times, "
                        "positions q and velocities v of every DOF), for 'hybridpd plot' "
                        "(.json, for the pair and for --model)")
    p.add_argument("--samples", type=int, default=2000,
                   help="number of sampling times written by --out and drawn by --plot")
    p.add_argument("--plot", default=None, metavar="IMAGE",
                   help="draw the trajectory (positions, gaps, impacts, phase portraits) "
                        "to this .png, .pdf or .svg")
    p.set_defaults(func=run)


#: events listed in the text output before it summarises the rest
_SHOWN = 10
#: ``termination`` of a run that stopped before its end time: exit status and why
STOPS = {
    "simultaneous_contact": (EXIT_DIVERGED, ("contacts closing at one instant whose joint "
                                             "impact (the multi-contact LCP) has no solution "
                                             "or a degenerate one")),
    "simultaneous": (EXIT_DIVERGED, "a joint jump the automaton could not resolve"),
    "diverged": (EXIT_DIVERGED, "the state grew past the divergence bound (an unstable loop?)"),
    "nonfinite": (EXIT_DIVERGED, "the state overflowed"),
    "jump_limit": (EXIT_STOPPED_EARLY, "--max-impacts reached before --t-end (raise it)"),
    "step_limit": (EXIT_STOPPED_EARLY, "the bound on flow steps was reached before --t-end"),
    "zeno": (EXIT_STOPPED_EARLY, "an accumulation of impacts the run cannot continue past")}


def stop_status(termination: str, t_final: float) -> int:
    """Exit status of a run that stopped with `termination` (:data:`STOPS`; 0 for
    ``end_time``), with one line on stderr naming the termination when it is not 0."""
    if termination == "end_time":
        return EXIT_OK
    status, why = STOPS.get(termination, (EXIT_STOPPED_EARLY, "stopped before --t-end"))
    print(f"hybridpd simulate: the run stopped at t = {t_final:.12g}: {termination} ({why})",
          file=sys.stderr)
    return status


def _agree(a, b, rtol=1e-6):
    return math.isclose(a, b, rel_tol=rtol, abs_tol=1e-12)


def geometry(args):
    """``(L, xm)`` from ``--L/--xm`` or ``--gamma/--x10`` (see the module docstring)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.model import ImpactPair, PDGains, check_positive
    from hybridpd.pair.orbits import symmetric_orbit

    relative = args.gamma is not None or args.x10 is not None
    if args.L is None and args.gamma is None:
        raise ValueError("give the clearance: --L, or --gamma with --x10")
    if args.xm is None and not relative:
        raise ValueError("give the reference: --xm, or --x10 (with --gamma or --L)")
    L = None if args.L is None else check_positive("L", args.L)
    x10 = None
    if relative:
        x10 = check_positive("x10", 1.0 if args.x10 is None else args.x10)
    if args.gamma is not None:
        Lg = check_positive("gamma", args.gamma) * x10
        if L is not None and not _agree(L, Lg):
            raise ValueError(f"--L {L:g} disagrees with --gamma {args.gamma:g} x --x10 "
                             f"{x10:g} = {Lg:g}; give one pair or consistent values")
        L = Lg
    xm = args.xm
    if xm is not None and xm < 0:
        raise ValueError(f"xm must be >= 0, got {xm!r}")
    if relative:
        orb = symmetric_orbit(ImpactPair(args.mu, args.e, L, args.m2),
                              PDGains(args.kp, args.kv), args.omega, x10=x10, n=args.n,
                              case=args.case)
        if not math.isfinite(orb.xm) or orb.xm <= 0:
            raise ValueError(f"--x10 {x10:g}: no reference amplitude realises it ({orb.reason})")
        if xm is not None and not _agree(xm, orb.xm):
            raise ValueError(f"--xm {xm:g} disagrees with the amplitude {orb.xm:.10g} that "
                             f"realises --x10 {x10:g}; give one pair or consistent values")
        xm = orb.xm
    return L, xm


def run(args) -> int:
    require(args, "t_end")
    check_out(args.out, "--out", (".json",))
    check_image(args.plot)
    if not 2 <= args.samples <= 1_000_000:
        raise ValueError(f"--samples must be in [2, 1000000], got {args.samples}")
    if args.model is not None:
        given = [f"--{k.replace('_', '-')}" for k in _PAIR if getattr(args, k) is not None]
        if given:
            raise UsageError(f"--model: cannot be combined with the impact-pair options "
                             f"({', '.join(given)})")
        return _run_model(args)
    if args.set:
        raise UsageError("--set needs --model FILE.toml (the impact pair's parameters are "
                         "its options)")
    if args.m2 is None:
        args.m2 = 1.0
    missing = [f"--{k}" for k in _REQUIRED if getattr(args, k) is None]
    if missing:
        raise UsageError(f"the following arguments are required: {', '.join(missing)} "
                         "(or give --model FILE.toml)")
    return _run_pair(args)


def _run_model(args) -> int:
    # deferred import: loaded only when this runs, for start-up time
    model = model_of(args)
    if not args.t_end > model.t0:
        raise ValueError(f"--t-end must be > the model's t0 = {model.t0:g}, got {args.t_end:g}")
    traj = model.simulate(args.t_end, max_impacts=args.max_impacts)
    d = traj.to_dict()
    contacts = [{"name": c.name, "normal": [float(w) for w in c.normal],
                 "lo": c.lo, "hi": c.hi} for c in model.contacts]
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.plotting._common import model_title

    controllers = controllers_of(args)
    _write(args, d, traj.mechanical, model.t0, traj.t_final, model.system.dofs, contacts,
           title=model_title(model.source, {"controllers": controllers}),
           parameters={"model": str(model.source), "controllers": controllers,
                       **set_values(args)})
    status = stop_status(d["termination"], traj.t_final)
    if args.json:
        print_json(d)
        return status
    dofs = model.system.dofs
    print(f"{model.source}: {len(dofs)} DOFs ({', '.join(dofs)}), {len(model.contacts)} "
          f"contact(s); t in [{model.t0:g}, {traj.t_final:g}]: {traj.n_impacts} impacts, "
          f"{len(traj.sticking)} sticking interval(s); stopped: {d['termination']}")
    for imp in d["impacts"][:_SHOWN]:
        print(f"  t = {imp['t']:.10f}  contact {imp['contact']}  wall {imp['wall']:+d}")
    if traj.n_impacts > _SHOWN:
        print(f"  ... {traj.n_impacts - _SHOWN} more (use --json for all)")
    for a, b, k in d["sticking"][:_SHOWN]:
        print(f"  sticking on contact {k} on [{a:.10f}, {b:.10f}]")
    if len(d["sticking"]) > _SHOWN:
        print("  " + sticking_tail(d["sticking"], _SHOWN))
    for t_inf, k, _, n_res in traj.accumulations[:_SHOWN]:
        print(f"  accumulation of impacts on contact {k} at t = {t_inf:.12f} "
              f"({n_res} resolved)")
    if len(traj.accumulations) > _SHOWN:
        print(f"  ... {len(traj.accumulations) - _SHOWN} more accumulations")
    return status


def _run_pair(args) -> int:
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.model import ImpactPair, PDGains, Reference
    from hybridpd.pair.impactpair import ControlledImpactPair

    if not args.t_end > 0:
        raise ValueError(f"--t-end must be > 0 (the run starts at t = 0), got {args.t_end:g}")
    L, xm = geometry(args)
    sysm = ControlledImpactPair(ImpactPair(args.mu, args.e, L, args.m2),
                                PDGains(args.kp, args.kv), Reference(xm, args.omega),
                                args.case)
    traj = sysm.simulate(args.x0, (0.0, args.t_end), max_impacts=args.max_impacts)
    d = traj.to_dict()
    params = {"case": args.case, "mu": args.mu, "m2": args.m2, "e": args.e, "L": L,
              "xm": xm, "omega": args.omega, "kp": args.kp, "kv": args.kv}
    _write(args, d, lambda t: traj(t)[:, :4], 0.0, traj.t_final, ("x1", "x2"),
           [{"name": "gap", "normal": [1.0, -1.0], "lo": -L, "hi": L}],
           title=(f"{args.case} impact pair: mu = {args.mu:g}, e = {args.e:g}, L = {L:g}, "
                  f"kp = {args.kp:g}, kv = {args.kv:g}, xm = {xm:.6g}, "
                  f"omega = {args.omega:g}"), parameters=params)
    status = stop_status(d["termination"], traj.t_final)
    if args.json:
        print_json(d)
        return status
    print(f"{args.case} impact pair (L = {L:g}, xm = {xm:.10g}), t in [0, {traj.t_final:g}]: "
          f"{traj.n_impacts} impacts ({int((traj.walls > 0).sum())} on wall +L, "
          f"{int((traj.walls < 0).sum())} on -L), "
          f"{len(traj.sticking)} sticking interval(s); stopped: {d['termination']}")
    for imp in d["impacts"][:10]:
        print(f"  t = {imp['t']:.10f}  wall {imp['wall']:+d}  pre = "
              + " ".join(f"{v:+.6f}" for v in imp["pre"]))
    if traj.n_impacts > 10:
        print(f"  ... {traj.n_impacts - 10} more (use --json for all)")
    for a, b, *_ in d["sticking"][:_SHOWN]:
        print(f"  sticking on [{a:.10f}, {b:.10f}]")
    if len(d["sticking"]) > _SHOWN:
        print("  " + sticking_tail(d["sticking"], _SHOWN))
    return status


def sticking_tail(sticking, shown: int) -> str:
    """The line after the first `shown` sticking intervals ``(a, b, contact)``: how many more
    and how long they hold, then how many and how long in all.

    Examples
    --------
    >>> sticking_tail([(0.0, 1.0, 0), (2.0, 2.5, 0), (3.0, 3.25, 1)], 1)
    '... 2 more sticking intervals (0.75 time units); 3 intervals, 1.75 time units held in all (use --json for all)'
    """
    rest = sticking[shown:]
    held = sum(b - a for a, b, *_ in rest)
    total = sum(b - a for a, b, *_ in sticking)
    return (f"... {len(rest)} more sticking intervals ({held:.6g} time units); "
            f"{len(sticking)} intervals, {total:.6g} time units held in all (use --json for "
            "all)")


def trajectory_record(result: dict, state, t0, t_final, dofs, contacts, *, samples=2000,
                      title=None, parameters=None) -> dict:
    """The ``simulate --out`` JSON document: the ``--json`` result plus dense samples.

    ``state(t)`` returns the mechanical states ``[q_1, v_1, ..., q_n, v_n]`` at the times
    ``t`` (shape ``(len(t), 2n)``); the record holds ``samples = {"t", "q", "v"}`` with
    ``q`` and ``v`` of shape ``(len(t), n)``, the DOF names, the contacts (normal and
    bounds of each gap), and ``"kind": "trajectory"`` so that ``hybridpd plot`` recognises
    it.
    """
    import numpy as np

    t = np.linspace(float(t0), float(t_final), int(samples))
    Z = np.asarray(state(t), float)
    return {"kind": "trajectory", "format": 1, "title": title, "dofs": list(dofs),
            "contacts": contacts, "parameters": parameters or {}, **result,
            "samples": {"t": t.tolist(), "q": Z[:, 0::2].tolist(), "v": Z[:, 1::2].tolist()}}


def _write(args, result, state, t0, t_final, dofs, contacts, *, title, parameters):
    if args.out is None and args.plot is None:
        return
    from pathlib import Path

    rec = trajectory_record(result, state, t0, t_final, dofs, contacts,
                            samples=args.samples, title=title, parameters=parameters)
    if args.out is not None:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(dumps_json(rec))
    if args.plot is not None:
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.plotting.trajectory import plot_trajectory_samples

        imp = result["impacts"]
        fig = plot_trajectory_samples(
            rec["samples"]["t"], rec["samples"]["q"], rec["samples"]["v"], dofs=dofs,
            contacts=contacts, impact_times=[d["t"] for d in imp],
            impact_contacts=[d["contact"] for d in imp],
            impact_states=[d["pre"] for d in imp] if imp else None,
            sticking=result["sticking"], title=title)
        save_figure(fig, args.plot)
