"""``hybridpd regions``."""
from __future__ import annotations

import json

from hybridpd.cli._common import (
    add_plant,
    add_sweep,
    check_image,
    check_out,
    clearance,
    command,
    executor_of,
    progress_wanted,
    save_figure,
)

DESCRIPTION = ("Maps, on a grid of PD gains (kp, kv) and for each restitution "
               "coefficient e, where the symmetric orbit exists (with viability) and "
               "where it is also stable: the paper's Figs 4-5.")


def register(sub):
    p = command(sub, "regions", help="existence/stability regions over (kp, kv)",
                description=DESCRIPTION,
                example=("hybridpd regions --case collocated --mu 0.1 --e 0.1 0.5 0.9"
                         " --gamma 0.75 --omega 5 --kp 0.1 50 200 --kv 0.1 50 200 "
                         "--out regions.nc --plot regions.png"))
    add_plant(p, xm=False, gamma=True)
    p.add_argument("--e", type=float, nargs="+", required=True,
                   help="one or more restitution coefficients in [0, 1]")
    p.add_argument("--n", type=int, default=1,
                   help="odd order of the symmetric orbit (period n T)")
    p.add_argument("--kp", type=float, nargs=3, required=True, metavar=("MIN", "MAX", "NUM"),
                   help="grid axis: NUM points from MIN to MAX")
    p.add_argument("--kv", type=float, nargs=3, required=True, metavar=("MIN", "MAX", "NUM"),
                   help="grid axis: NUM points from MIN to MAX")
    add_sweep(p, what="the region map (one panel per e)")
    p.set_defaults(func=run)


def run(args) -> int:
    from hybridpd.sweeps.regions import region_map

    check_out(args.out)
    check_image(args.plot)
    L, x10 = clearance(args)
    for nm in ("kp", "kv"):
        num = getattr(args, nm)[2]
        if num != int(num):
            raise ValueError(f"--{nm} NUM must be an integer, got {num:g}")
    rm = region_map(args.case, x=("kp", *args.kp), y=("kv", *args.kv), e=args.e, mu=args.mu,
                    omega=args.omega, L=L, x10=x10, m2=args.m2, n=args.n,
                    executor=executor_of(args), max_workers=args.workers,
                    store=args.store, progress=progress_wanted(args))
    if args.out:
        rm.save(args.out)
    if args.plot:
        from hybridpd.plotting.regions import plot_region_panels

        save_figure(plot_region_panels(rm), args.plot)
    if args.json:
        print(json.dumps(rm.to_dict()))
        return 0
    print(f"{args.case} regions on kp x kv = {len(rm.x)} x {len(rm.y)}:")
    for k, e in enumerate(rm.e):
        print(f"  e = {e:g}: exists {100 * rm.fraction('exists')[k]:.2f}%, exists & stable "
              f"{100 * rm.fraction('stable')[k]:.2f}% (area {rm.area('stable')[k]:.4g})")
    return 0
