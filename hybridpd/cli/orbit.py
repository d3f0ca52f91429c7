"""``hybridpd orbit``: the pair's symmetric orbit, or a periodic orbit of a model file."""
from __future__ import annotations

import json

import numpy as np

from hybridpd.cli._common import JSON_HELP, UsageError, add_plant, check_pair_command, command

# the pair options: required without --model, not used with it
_PAIR = ("case", "mu", "omega", "e", "kp", "kv")

DESCRIPTION = ("Solves the paper's conditions (13)-(17) for the simple symmetric "
               "orbit of order n (one impact on each wall per period n T), checks its"
               " viability (18) rigorously and its stability (27) from the Jacobian "
               "DP of the impact map: xm, phi0, the viability margin, the Floquet "
               "multipliers and the spectral radius. With --model FILE.toml it finds a "
               "periodic orbit of a general mechanical model by Newton's method on the "
               "impact map of one contact and reports its Floquet multipliers.")


def register(sub):
    p = command(sub, "orbit", help="periodic orbit and its stability (the pair's symmetric "
                "orbit, or any model file's)",
                description=DESCRIPTION,
                example=("hybridpd orbit --case noncollocated --mu 0.1 --e 0.5 "
                         "--gamma 0.75 --omega 5 --kp 10 --kv 20\n  hybridpd orbit --model "
                         "examples/models/drivetrain.toml --contact 0 --event release --json"))
    add_plant(p, xm=False, gamma=True, required=False)
    p.add_argument("--e", type=float, default=None, help="restitution coefficient in [0, 1]")
    p.add_argument("--n", type=int, default=1, help="odd orbit order (period n T)")
    p.add_argument("--kp", type=float, default=None, help="proportional gain kp (> 0)")
    p.add_argument("--kv", type=float, default=None, help="derivative gain kv (> 0)")
    p.add_argument("--model", default=None, metavar="FILE.toml",
                   help="mechanical model file (then the impact-pair options are not used)")
    p.add_argument("--contact", type=int, default=0,
                   help="--model: 0-based contact whose impacts define the section")
    p.add_argument("--wall", type=int, choices=[-1, 1], default=None,
                   help="--model: +1 (hi) or -1 (lo) bound of the contact (default hi)")
    p.add_argument("--event", default="impact", choices=["impact", "release"],
                   help="--model: section on the contact's impacts, or on the ends of its "
                   "sticking phases")
    p.add_argument("--period", type=int, default=1,
                   help="--model: returns to the section per period (k of P^k)")
    p.add_argument("--guess", type=float, nargs="+", default=None,
                   help="--model: section point (default: the last impact of a transient "
                   "simulation from the file's initial state)")
    p.add_argument("--transient", type=float, default=None,
                   help="--model: time of that simulation (default 50 periods)")
    p.add_argument("--set", nargs=2, action="append", default=None, metavar=("KEY", "VALUE"),
                   help="--model: set a numeric entry of the file by its dotted path "
                        "(controller.kp, contact.0.restitution, ...; a pattern controller.*.kp "
                        "or a list a.b,c.d sets every entry it matches) first; repeatable")
    p.add_argument("--json", action="store_true", help=JSON_HELP)
    p.set_defaults(func=run)


def run(args) -> int:
    if args.model is not None:
        return _run_model(args)
    L, x10 = check_pair_command(args, _PAIR, outputs=False)
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.analysis.orbits import symmetric_orbit
    from hybridpd.model import ImpactPair, PDGains

    orb = symmetric_orbit(ImpactPair(args.mu, args.e, L, args.m2), PDGains(args.kp, args.kv),
                          args.omega, x10=x10, n=args.n, case=args.case)
    d = orb.to_dict()
    if args.json:
        print(json.dumps(d))
        return 0
    print(f"{args.case} symmetric orbit, n = {orb.n}, x10 = {x10:g}, L = {L:g}: {orb.reason}")
    print(f"  xm = {orb.xm:.10g}, phi0 = {orb.phi0:.10g} (T = {orb.T:.6g}), R = {orb.R:.6g}")
    print(f"  viability margin = {orb.viability_margin:.6g}")
    if orb.exists:
        mods = ", ".join(f"{abs(z):.6g}" for z in orb.multipliers)
        print(f"  multipliers |lambda| = {mods}")
        print(f"  spectral radius = {orb.spectral_radius:.10g} -> "
              f"{'stable' if orb.stable else 'unstable'}"
              f"{'' if orb.hyperbolic else ' (not hyperbolic)'}")
    return 0


def _run_model(args) -> int:
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.analysis.model_orbits import orbit_from_model
    from hybridpd.mechanics.modelfile import load_model

    if args.period < 1:
        raise UsageError(f"--period must be >= 1, got {args.period}")
    if args.set:
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.mechanics.params import ModelTemplate

        values = {}
        for key, val in args.set:
            try:
                values[key] = float(val)
            except ValueError:
                raise ValueError(f"--set {key}: VALUE must be a number, got {val!r}") from None
        model = ModelTemplate.load(args.model).model(values)
    else:
        model = load_model(args.model)
    orb, P = orbit_from_model(model, args.contact, args.wall, args.period, guess=args.guess,
                              transient=args.transient, event=args.event)
    sec = P.section
    d = orb.to_dict()
    n = model.system.n
    lay = model.automaton.layout
    z = orb.z
    pk = sec.automaton.packed
    zp = (pk.Rh[sec.mode_index, sec.guard_index] @ np.append(z, 1.0))[:-1]

    def mech(x):      # [q_1, v_1, ..., q_n, v_n]
        return [float(x[lay["q"][i]]) if j == 0 else float(x[lay["v"][i]])
                for i in range(n) for j in (0, 1)]

    d.update({"model": model.source, "contact": args.contact,
              "wall": 1 if sec.guard.endswith("+") else -1, "event": args.event,
              "T": sec.period, "phi0": float(orb.s[0]) if sec.has_phase else None,
              "t0": float(orb.s[0]) if sec.has_phase else 0.0, "n": orb.period,
              "pre": mech(z), "post": mech(zp)})
    if args.json:
        print(json.dumps(d))
        return 0
    print(f"{model.source}: period-{orb.period} orbit on contact {args.contact} "
          f"(wall {d['wall']:+d}): {orb.reason} after {orb.iterations} Newton iterations "
          f"(residual {orb.residual:.3g})")
    print("  section point: " + ", ".join(f"{k} = {v:.10g}" for k, v in zip(orb.names, orb.s)))
    print(f"  period {orb.t_period:.10g}; impact sequence: "
          + " ".join(f"{g}({k})" for g, k in orb.signature))
    if orb.detail:
        print(f"  no orbit: {orb.detail}")
    if orb.converged:
        mods = ", ".join(f"{abs(m):.6g}" for m in orb.multipliers)
        print(f"  multipliers |lambda| = {mods}")
        print(f"  spectral radius = {orb.spectral_radius:.10g} -> "
              f"{'stable' if orb.stable else 'unstable'}"
              f"{'' if orb.hyperbolic else ' (not hyperbolic)'}")
    return 0
