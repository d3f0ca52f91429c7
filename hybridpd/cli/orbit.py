"""``hybridpd orbit``: the pair's symmetric orbit, or a periodic orbit of a model file."""
from __future__ import annotations

import re
import sys

import numpy as np

from hybridpd.cli._common import (
    EXIT_DIVERGED,
    EXIT_NO_ORBIT,
    EXIT_OK,
    UsageError,
    add_model,
    add_output,
    add_pair,
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
               "periodic orbit of a general mechanical model by Newton's method on its "
               "section map (by default the stroboscopic one: the state at one phase of the "
               "reference, mapped over the common period; --event impact|release for a "
               "contact's section) and reports its Floquet multipliers and its "
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
                         "examples/models/robot_joint_sampled.toml --json"),
                notes=NOTES)
    add_pair(p)
    add_model(p)
    p.add_argument("--guess", type=float, nargs="+", default=None,
                   help="--model: section point (default: where a transient simulation from "
                   "the file's initial state last crosses the section)")
    p.add_argument("--transient", type=float, default=None,
                   help="--model: time of that simulation (default 50 periods)")
    p.add_argument("--full-sequence", action="store_true",
                   help="--model: list every jump of the period (by default runs of equal "
                        "jumps are counted, e.g. 'sample x 1000'; --json always lists all)")
    add_output(p)
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
    if orb.reason == "diverged" or (orb.reason.startswith("map undefined")
                                    and _DIVERGED.search(orb.reason)):
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
    from hybridpd.analysis.model_orbits import orbit_from_model, orbit_record
    from hybridpd.analysis.model_sections import DivergedRun

    model = model_of(args)
    try:
        orb, P = orbit_from_model(model, args.contact, args.wall, args.period,
                                  guess=args.guess, transient=args.transient,
                                  event=args.event, periods=args.periods, mode=args.mode,
                                  phase=args.phase)
    except DivergedRun as exc:
        print(f"hybridpd orbit: the run diverged: {exc}", file=sys.stderr)
        return EXIT_DIVERGED
    except ValueError as exc:
        why = _transient_diverged(model, args) if args.guess is None else None
        if why is None:
            raise
        print(f"hybridpd orbit: the run diverged: {why} ({exc})", file=sys.stderr)
        return EXIT_DIVERGED
    d = orbit_record(model, orb, P)
    status = model_status(orb)
    if args.json:
        print_json(d)
        return _report(status, orb.reason)
    k = (f"{orb.period} return{'s' if orb.period != 1 else ''} to the section per period"
         if orb.converged else f"period {orb.period}")
    print(f"{model.source}: orbit on {_section_words(d)}, {k}): {orb.reason} after "
          f"{orb.iterations} Newton iterations (residual {orb.residual:.3g})")
    if d.get("section_choice"):
        print(f"  section: {d['section_choice']}")
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
        zeros = d.get("structural_zeros") or 0
        print(f"  multipliers |lambda| = {mods}"
              + (f" (and {zeros} structural zero{'s' if zeros != 1 else ''}: directions the "
                 "period's jumps remove)" if zeros else ""))
        print(f"  spectral radius = {orb.spectral_radius:.10g} -> "
              f"{'stable' if orb.stable else 'unstable'}"
              f"{'' if orb.hyperbolic else ' (not hyperbolic)'}")
        if orb.quantities.get("jacobian") == "central differences":
            print(f"  DP by central differences (relative step "
                  f"{orb.quantities['jacobian_step']:g}, estimated error "
                  f"{orb.quantities['jacobian_error']:.2g}): a jump of the period has no "
                  "saltation matrix")
    return _report(status, orb.reason)


def _section_words(d) -> str:
    """The section of a model's orbit record in words (up to the mode)."""
    if d["event"] == "stroboscopic":
        if d.get("reason") == "sampling_incommensurate":   # no common period exists
            return (f"the stroboscopic section (phase phi0 = {d['phi0']:.6g}; the sampling "
                    f"and the reference have no common period, mode {d['section_mode']}")
        return (f"the stroboscopic section (phase phi0 = {d['phi0']:.6g} of the common "
                f"period {d['T']:.6g}, mode {d['section_mode']}")
    return (f"contact {d['contact']} (wall {d['wall']:+d}, {d['event']} in mode "
            f"{d['section_mode']}")


def _transient_diverged(model, args) -> str | None:
    """Why the transient simulation that seeds Newton stopped, if it diverged (else None)."""
    T = model.automaton.loop.reference_period
    transient = args.transient
    if transient is None:   # orbit_from_model's default
        transient = 50.0 * T if T else 200.0
    tr = model.simulate(model.t0 + float(transient))
    if tr.termination in ("diverged", "nonfinite"):
        return (f"the transient simulation from the file's initial state stopped at "
                f"t = {tr.t_final:.6g}: {tr.termination}")
    return None
