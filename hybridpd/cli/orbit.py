"""``hybridpd orbit``."""
from __future__ import annotations

import json

from hybridpd.cli._common import JSON_HELP, add_plant, clearance, command

DESCRIPTION = ("Solves the paper's conditions (13)-(17) for the simple symmetric "
               "orbit of order n (one impact on each wall per period n T), checks its"
               " viability (18) rigorously and its stability (27) from the Jacobian "
               "DP of the impact map: xm, phi0, the viability margin, the Floquet "
               "multipliers and the spectral radius.")


def register(sub):
    p = command(sub, "orbit", help="symmetric periodic orbit: existence and stability",
                description=DESCRIPTION,
                example=("hybridpd orbit --case noncollocated --mu 0.1 --e 0.5 "
                         "--gamma 0.75 --omega 5 --kp 10 --kv 20"))
    add_plant(p, xm=False, gamma=True)
    p.add_argument("--e", type=float, required=True, help="restitution coefficient in [0, 1]")
    p.add_argument("--n", type=int, default=1, help="odd orbit order (period n T)")
    p.add_argument("--kp", type=float, required=True,
                   help="proportional gain kp (> 0)")
    p.add_argument("--kv", type=float, required=True,
                   help="derivative gain kv (> 0)")
    p.add_argument("--json", action="store_true", help=JSON_HELP)
    p.set_defaults(func=run)


def run(args) -> int:
    from hybridpd.analysis.orbits import symmetric_orbit
    from hybridpd.model import ImpactPair, PDGains

    L, x10 = clearance(args)
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
