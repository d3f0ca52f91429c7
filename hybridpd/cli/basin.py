"""``hybridpd basin``."""
from __future__ import annotations

import json

import numpy as np

from hybridpd.cli._common import add_plant, add_sweep, clearance, progress_wanted


def register(sub):
    p = sub.add_parser("basin", help="basin of attraction of the symmetric orbit")
    add_plant(p, xm=False, gamma=True)
    p.add_argument("--e", type=float, required=True)
    p.add_argument("--n", type=int, default=1)
    p.add_argument("--kp", type=float, required=True)
    p.add_argument("--kv", type=float, required=True)
    p.add_argument("--x1", type=float, nargs=3, default=None, metavar=("MIN", "MAX", "NUM"),
                   help="slice window in x1 (default: the reproduction's, -3 x10 .. 5 x10, "
                        "41 points)")
    p.add_argument("--y1", type=float, nargs=3, default=None, metavar=("MIN", "MAX", "NUM"),
                   help="slice window in y1 (default -2 x10 .. 10 x10, 41 points)")
    p.add_argument("--iterations", type=int, default=1500)
    p.add_argument("--no-early-exit", action="store_true",
                   help="run every trajectory for all iterations")
    add_sweep(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from hybridpd.analysis.impactmap import ImpactMap
    from hybridpd.analysis.orbits import symmetric_orbit
    from hybridpd.model import ImpactPair, PDGains
    from hybridpd.sweeps.basins import LABELS, ImpactMapper, basin_of_attraction

    L, x10 = clearance(args)
    orb = symmetric_orbit(ImpactPair(args.mu, args.e, L, args.m2), PDGains(args.kp, args.kv),
                          args.omega, x10=x10, n=args.n, case=args.case)
    if not orb.exists:
        raise ValueError(f"no symmetric orbit at these parameters: {orb.reason}")
    from hybridpd.reproduce.settings import Settings

    win = Settings.__dataclass_fields__["basin_window"].default
    if args.x1 is None:
        args.x1 = [win[0] * x10, win[1] * x10, 41]
    if args.y1 is None:
        args.y1 = [win[2] * x10, win[3] * x10, 41]
    for nm in ("x1", "y1"):
        num = getattr(args, nm)[2]
        if num != int(num):
            raise ValueError(f"--{nm} NUM must be an integer, got {num:g}")
    if args.iterations < 1:
        raise ValueError(f"--iterations must be >= 1, got {args.iterations}")
    mapper = ImpactMapper(ImpactMap(orb.pair, orb.gains, orb.reference(), orb.case),
                          orb.fixed_point, n_iter=args.iterations,
                          early_exit=not args.no_early_exit)
    b = basin_of_attraction(mapper, args.x1, args.y1, executor=args.executor,
                            max_workers=args.workers, progress=progress_wanted(args))
    if args.out:
        b.save(args.out)
    fp = b.fixed_point
    if args.json:
        print(json.dumps({
            "x1": b.x1.tolist(), "y1": b.y1.tolist(), "labels": b.labels.tolist(),
            "label_names": list(LABELS),
            "fixed_point": {"phi": float(fp[0]), "z1": float(fp[1]), "z2": float(fp[2]),
                            "z4": float(fp[3]), "x1": float(fp[1] + L),
                            "y1": float(fp[2] + fp[3]), "y2": float(fp[2])},
            "converged_fraction": b.converged_fraction, "spectral_radius": orb.spectral_radius,
            "stable": orb.stable, "certified_radius": mapper.certified_radius,
        }))
        return 0
    print(f"{args.case} basin, e = {args.e:g}, kp = {args.kp:g}, kv = {args.kv:g}: converged "
          f"{100 * b.converged_fraction:.2f}% of the on-section grid")
    counts = np.bincount(b.labels.ravel(), minlength=len(LABELS))
    for name, c in zip(LABELS, counts):
        print(f"  {name:15s} {int(c)}")
    return 0
