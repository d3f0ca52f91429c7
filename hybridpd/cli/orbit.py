"""``hybridpd orbit``: the pair's symmetric orbit, or a periodic orbit of a model file."""
from __future__ import annotations

import re
import sys

import numpy as np

from hybridpd.cli._common import (
    EXIT_DIVERGED,
    EXIT_NO_ORBIT,
    EXIT_OK,
    JSON_HELP,
    UsageError,
    add_model_section,
    add_plant,
    add_set,
    check_pair_command,
    command,
    model_of,
    print_json,
)

# the pair options: required without --model, not used with it
_PAIR = ("case", "mu", "omega", "e", "kp", "kv")

DESCRIPTION = ("Solves the paper's conditions (13)-(17) for the simple symmetric "
               "orbit of order n (one impact on each wall per period n T), checks its"
               " viability (18) rigorously and its stability (27) from the Jacobian "
               "DP of the impact map: xm, phi0, the viability margin, the Floquet "
               "multipliers and the spectral radius. With --model FILE.toml it finds a "
               "periodic orbit of a general mechanical model by Newton's method on the "
               "impact map of one contact and reports its Floquet multipliers and its "
               "sequence of jumps over one period (summarised; --full-sequence lists it).")

NOTES = """\
exit status:
  0  an orbit was found
  2  bad input (one line on stderr)
  3  no orbit (the pair's symmetric orbit does not exist, or Newton found no orbit of the
     model; the reason is printed)
  4  the run diverged: the map overflowed, grew past the divergence bound or went
     non-finite (also while simulating the model's transient for a guess)"""

#: distinct runs of equal jumps shown in order before the summary counts them instead
_MAX_RUNS = 16


def register(sub):
    p = command(sub, "orbit", help="periodic orbit and its stability (the pair's symmetric "
                "orbit, or any model file's)",
                description=DESCRIPTION,
                example=("hybridpd orbit --case noncollocated --mu 0.1 --e 0.5 "
                         "--gamma 0.75 --omega 5 --kp 10 --kv 20\n  hybridpd orbit --model "
                         "examples/models/drivetrain.toml --contact 0 --event release --json"),
                notes=NOTES)
    add_plant(p, xm=False, gamma=True, required=False)
    p.add_argument("--e", type=float, default=None, help="restitution coefficient in [0, 1]")
    p.add_argument("--n", type=int, default=1, help="odd orbit order (period n T)")
    p.add_argument("--kp", type=float, default=None, help="proportional gain kp (> 0)")
    p.add_argument("--kv", type=float, default=None, help="derivative gain kv (> 0)")
    add_model_section(p, period_help="returns to the section per period (k of P^k)")
    add_set(p)
    p.add_argument("--guess", type=float, nargs="+", default=None,
                   help="--model: section point (default: the last impact of a transient "
                   "simulation from the file's initial state)")
    p.add_argument("--transient", type=float, default=None,
                   help="--model: time of that simulation (default 50 periods)")
    p.add_argument("--full-sequence", action="store_true",
                   help="--model: list every jump of the period (by default runs of equal "
                        "jumps are counted, e.g. 'sample x 1000'; --json always lists all)")
    p.add_argument("--json", action="store_true", help=JSON_HELP)
    p.set_defaults(func=run)


def run(args) -> int:
    if args.model is not None:
        return _run_model(args)
    if args.set or args.full_sequence:
        raise UsageError("--set and --full-sequence need --model FILE.toml")
    L, x10 = check_pair_command(args, _PAIR, outputs=False)
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.model import ImpactPair, PDGains
    from hybridpd.pair.orbits import symmetric_orbit

    orb = symmetric_orbit(ImpactPair(args.mu, args.e, L, args.m2), PDGains(args.kp, args.kv),
                          args.omega, x10=x10, n=args.n, case=args.case)
    status = _pair_status(orb)
    if args.json:
        print_json(orb.to_dict())
        return _report(status, orb.reason)
    print(f"{args.case} symmetric orbit, n = {orb.n}, x10 = {x10:g}, L = {L:g}: {orb.reason}")
    print(f"  xm = {orb.xm:.10g}, phi0 = {orb.phi0:.10g} (T = {orb.T:.6g}), R = {orb.R:.6g}")
    print(f"  viability margin = {orb.viability_margin:.6g}")
    if orb.exists:
        mods = ", ".join(f"{abs(z):.6g}" for z in orb.multipliers)
        print(f"  multipliers |lambda| = {mods}")
        print(f"  spectral radius = {orb.spectral_radius:.10g} -> "
              f"{'stable' if orb.stable else 'unstable'}"
              f"{'' if orb.hyperbolic else ' (not hyperbolic)'}")
    return _report(status, orb.reason)


def _pair_status(orb) -> int:
    if not orb.exists:
        return EXIT_NO_ORBIT
    finite = np.all(np.isfinite(orb.fixed_point)) and np.all(np.isfinite(orb.multipliers))
    return EXIT_OK if finite else EXIT_DIVERGED


def _report(status: int, reason: str) -> int:
    """The exit status, with one line on stderr saying why when it is not 0."""
    if status == EXIT_NO_ORBIT:
        print(f"hybridpd orbit: no orbit: {reason}", file=sys.stderr)
    elif status == EXIT_DIVERGED:
        print(f"hybridpd orbit: the run diverged: {reason}", file=sys.stderr)
    return status


#: ``find_orbit`` reasons meaning that the map's run overflowed or grew without bound
_DIVERGED = re.compile(r"nonfinite(?!_jacobian)|diverged|overflow")


def model_status(orb) -> int:
    """Exit status of a model's :class:`~hybridpd.analysis.periodic.PeriodicOrbit`."""
    if orb.converged:
        return EXIT_OK
    if orb.reason.startswith("map undefined") and _DIVERGED.search(orb.reason):
        return EXIT_DIVERGED
    return EXIT_NO_ORBIT


def jump_label(guard: str, kind: str) -> str:
    """``guard`` for a transversal crossing, ``guard (kind)`` for a grazing or Zeno jump."""
    return guard if kind == "crossing" else f"{guard} ({kind})"


def sequence_summary(signature, max_runs: int = _MAX_RUNS) -> str:
    """The jumps of one period in a line: runs of equal jumps compressed (``sample x 1000``),
    or, beyond ``max_runs`` runs, each kind of jump counted in order of first appearance.

    Examples
    --------
    >>> sig = [("release0+", "crossing")] + [("sample", "crossing")] * 3 \\
    ...     + [("contact0+", "grazing")]
    >>> sequence_summary(sig)
    'release0+, sample x 3, contact0+ (grazing)'
    >>> sequence_summary([("a", "crossing"), ("b", "crossing")] * 3, max_runs=4)
    'a x 3, b x 3 (counts in order of first appearance, 6 runs)'
    """
    labels = [jump_label(g, k) for g, k in signature]
    if not labels:
        return "none"
    runs = []
    for lab in labels:
        if runs and runs[-1][0] == lab:
            runs[-1][1] += 1
        else:
            runs.append([lab, 1])
    if len(runs) <= max_runs:
        return ", ".join(lab if n == 1 else f"{lab} x {n}" for lab, n in runs)
    counts: dict = {}
    for lab in labels:
        counts[lab] = counts.get(lab, 0) + 1
    return (", ".join(lab if n == 1 else f"{lab} x {n}" for lab, n in counts.items())
            + f" (counts in order of first appearance, {len(runs)} runs)")


def _run_model(args) -> int:
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.analysis.model_orbits import orbit_from_model

    model = model_of(args)
    try:
        orb, P = orbit_from_model(model, args.contact, args.wall, args.period,
                                  guess=args.guess, transient=args.transient,
                                  event=args.event, periods=args.periods, mode=args.mode)
    except ValueError as exc:
        why = _transient_diverged(model, args) if args.guess is None else None
        if why is None:
            raise
        print(f"hybridpd orbit: the run diverged: {why} ({exc})", file=sys.stderr)
        return EXIT_DIVERGED
    d = _model_record(model, orb, P, args)
    status = model_status(orb)
    if args.json:
        print_json(d)
        return _report(status, orb.reason)
    k = (f"{orb.period} return{'s' if orb.period != 1 else ''} to the section per period"
         if orb.converged else f"period {orb.period}")
    print(f"{model.source}: orbit on contact {args.contact} (wall {d['wall']:+d}, "
          f"{args.event} in mode {P.section.mode}, {k}): {orb.reason} after "
          f"{orb.iterations} Newton iterations (residual {orb.residual:.3g})")
    print("  section point: " + ", ".join(f"{k} = {v:.10g}" for k, v in zip(orb.names, orb.s)))
    sig = orb.signature
    if args.full_sequence:
        seq = " ".join(jump_label(g, k) for g, k in sig) or "none"
    else:
        seq = sequence_summary(sig)
    print(f"  period {orb.t_period:.10g}; jumps per period: {len(sig)}: {seq}")
    if orb.detail:
        print(f"  no orbit: {orb.detail}")
    if orb.converged:
        mods = ", ".join(f"{abs(m):.6g}" for m in orb.multipliers)
        print(f"  multipliers |lambda| = {mods}")
        print(f"  spectral radius = {orb.spectral_radius:.10g} -> "
              f"{'stable' if orb.stable else 'unstable'}"
              f"{'' if orb.hyperbolic else ' (not hyperbolic)'}")
    return _report(status, orb.reason)


def _model_record(model, orb, P, args) -> dict:
    """The ``--json`` object of a model's orbit: the orbit's fields, the section, and the
    pre- and post-jump mechanical states ``[q_1, v_1, ..., q_n, v_n]``."""
    sec = P.section
    d = orb.to_dict()
    n = model.system.n
    lay = model.automaton.layout
    z = orb.z
    reset = sec.automaton.mode(sec.mode).guards[sec.guard_index].reset
    zp = z if reset is None else reset[0] @ z + reset[1]

    def mech(x):      # [q_1, v_1, ..., q_n, v_n]
        return [float(x[lay["q"][i]]) if j == 0 else float(x[lay["v"][i]])
                for i in range(n) for j in (0, 1)]

    d.update({"model": model.source, "contact": args.contact,
              "wall": 1 if sec.guard.endswith("+") else -1, "event": args.event,
              "section_mode": sec.mode, "T": sec.period,
              "phi0": float(orb.s[0]) if sec.has_phase else None,
              "t0": float(orb.s[0]) if sec.has_phase else 0.0, "n": orb.period,
              "pre": mech(z), "post": mech(zp)})
    return d


def _transient_diverged(model, args) -> str | None:
    """Why the transient simulation that seeds Newton stopped, if it diverged (else None)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.analysis.sections import mechanical_section

    ma = model.automaton
    try:
        walls = [w for w, _ in ma.contacts[int(args.contact)].bounds]
        wall = args.wall if args.wall is not None else (1 if 1 in walls else -1)
        sec = mechanical_section(ma, int(args.contact), wall, event=args.event)
    except (ValueError, IndexError):
        return None
    transient = args.transient
    if transient is None:   # orbit_from_model's default
        transient = 50.0 * sec.reference_period if sec.has_phase else 200.0
    tr = model.simulate(model.t0 + float(transient))
    if tr.termination in ("diverged", "nonfinite"):
        return (f"the transient simulation from the file's initial state stopped at "
                f"t = {tr.t_final:.6g}: {tr.termination}")
    return None
