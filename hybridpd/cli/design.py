"""``hybridpd design``."""
from __future__ import annotations

import sys

from hybridpd.cli._common import (
    EXIT_INFEASIBLE,
    JSON_HELP,
    add_plant,
    clearance,
    command,
    print_json,
)

DESCRIPTION = ("Chooses PD gains (kp, kv) and the reference amplitude xm so that the "
               "primary mass moves between +x10 and -x10 on an existing, stable "
               "symmetric orbit with the largest stability and viability margins; "
               "with --e-range/--mu-range the orbit must stay stable, with the "
               "amplitude within --x10-tol, over the whole uncertainty box. Exit "
               "status 3 if infeasible.")


def register(sub):
    p = command(sub, "design", help="PD gains for a desired primary-mass motion (optionally robust to e and mu)",
                description=DESCRIPTION,
                example=("hybridpd design --case collocated --mu 0.1 --e 0.5 --gamma "
                         "0.75 --omega 5 --json"))
    add_plant(p, xm=False, gamma=True)
    p.add_argument("--e", type=float, required=True, help="nominal restitution coefficient")
    p.add_argument("--n", type=int, default=1,
                   help="odd order of the symmetric orbit (period n T)")
    p.add_argument("--kp-range", type=float, nargs=2, default=(0.1, 100.0), metavar=("LO", "HI"),
                   help="search or uncertainty interval")
    p.add_argument("--kv-range", type=float, nargs=2, default=(0.1, 100.0), metavar=("LO", "HI"),
                   help="search or uncertainty interval")
    p.add_argument("--e-range", type=float, nargs=2, default=None, metavar=("LO", "HI"),
                   help="search or uncertainty interval")
    p.add_argument("--mu-range", type=float, nargs=2, default=None, metavar=("LO", "HI"),
                   help="search or uncertainty interval")
    p.add_argument("--x10-tol", type=float, default=0.1,
                   help="robust design: allowed relative error of the primary amplitude")
    p.add_argument("--json", action="store_true", help=JSON_HELP)
    p.set_defaults(func=run)


def run(args) -> int:
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.design import InfeasibleDesignError, design

    L, x10 = clearance(args)
    try:
        res = design(args.case, mu=args.mu, e=args.e, omega=args.omega, L=L, x10=x10,
                     m2=args.m2, n=args.n, kp_range=tuple(args.kp_range),
                     kv_range=tuple(args.kv_range),
                     e_range=None if args.e_range is None else tuple(args.e_range),
                     mu_range=None if args.mu_range is None else tuple(args.mu_range),
                     x10_tol=args.x10_tol)
    except InfeasibleDesignError as exc:
        print(f"hybridpd: infeasible: {exc}".replace("\n", " "), file=sys.stderr)
        return EXIT_INFEASIBLE
    d = res.to_dict()
    if args.json:
        print_json(d)
        return 0
    print(f"{args.case} design: kp = {res.kp:.6g}, kv = {res.kv:.6g}, xm = {res.xm:.6g}, "
          f"phi0 = {res.phi0:.6g}")
    print(f"  spectral radius {res.spectral_radius:.6g}, viability margin "
          f"{res.viability_margin:.6g}")
    if "worst_spectral_radius" in d:
        wc = d["worst_case"]
        print(f"  robust: worst spectral radius {d['worst_spectral_radius']:.6g} at "
              f"e = {wc['e']:.4g}, mu = {wc['mu']:.4g}")
    return 0
