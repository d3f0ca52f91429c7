"""``hybridpd regions``."""
from __future__ import annotations

import sys

import numpy as np

from hybridpd.cli import _common as cli

DESCRIPTION = ("Maps, on a grid of PD gains (kp, kv) and for each restitution "
               "coefficient e, where the symmetric orbit exists (with viability) and "
               "where it is also stable: the paper's Figs 4-5. With --model FILE.toml it "
               "maps, over two numeric entries of the file (dotted paths such as "
               "controller.kp), where a periodic orbit of one contact's section exists and "
               "is stable, following each family of orbits from cell to cell.")

# the pair options: required without --model, not used with it
_PAIR = ("case", "mu", "omega", "e", "kp", "kv")

NOTES = """\
exit status:
  0  done
  2  bad input (one line on stderr)
  3  --model: no cell has an orbit (one line on stderr says what every cell reported,
     e.g. 'no cell has an orbit: 16 diverged'; the output is written all the same)"""


def register(sub):
    p = cli.command(sub, "regions", help="existence/stability regions over (kp, kv)",
                description=DESCRIPTION,
                example=("hybridpd regions --case collocated --mu 0.1 --e 0.1 0.5 0.9"
                         " --gamma 0.75 --omega 5 --kp 0.1 50 200 --kv 0.1 50 200 "
                         "--out regions.nc --plot regions.png\n  hybridpd regions --model "
                         "examples/models/drivetrain.toml --x controller.kp 5 60 40 --y "
                         "controller.kv 1 20 40 --event release --out dt.nc --plot dt.png"),
                notes=NOTES)
    cli.add_pair(p, grid=("kp", "kv"), many=("e",))
    cli.add_model(p, set_option=False)
    cli.add_grid_axis(p, "--x", word="KEY", help="--model: grid axis over the file's entry KEY "
                      "(a dotted path such as controller.kp, contact.0.restitution, "
                      "system.masses.2; a pattern controller.*.kp or a list a.b,c.d sets every "
                      "entry it matches; --list-params lists them)")
    cli.add_grid_axis(p, "--y", word="KEY", help="second axis, as --x (a different one)")
    p.add_argument("--tile", type=int, default=8,
                   help="--model: side of the square tiles of cells (one task each)")
    p.add_argument("--certify", action="store_true",
                   help="also prove the class of every grid point's cell (the box half-way "
                        "to its neighbours) in interval arithmetic: proved stable, proved "
                        "unstable, proved no orbit or undecided (variable 'certified' of "
                        "--out; the figure draws the proved classes)")
    p.add_argument("--certify-depth", type=cli.depth_arg, default="auto",
                   help="--certify: bisections of an undecided cell (default auto: 3 for a "
                        "101 x 101 grid, one more for every factor 2 fewer cells)")
    cli.add_executor(p, default="serial")
    cli.add_output(p, out=(".nc", ".zarr", ".npz"), store=True,
                   plot="the region map (one panel per e)")
    p.set_defaults(func=run)


def run(args) -> int:
    if args.model is not None:
        return _run_model(args)
    if args.x is not None or args.y is not None:
        raise cli.UsageError("--x and --y need --model FILE.toml (the pair's axes are --kp, --kv)")
    L, x10 = cli.check_pair_command(args, _PAIR)
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.regions import SymmetricFamily
    from hybridpd.sweeps.regions import region_map

    for nm in ("kp", "kv"):
        num = getattr(args, nm)[2]
        if num != int(num):
            raise ValueError(f"--{nm} NUM must be an integer, got {num:g}")
    fam = SymmetricFamily(args.case, e=args.e, mu=args.mu, omega=args.omega, L=L, x10=x10,
                          m2=args.m2, n=args.n)
    rm = region_map(fam, x=("kp", *args.kp), y=("kv", *args.kv),
                    executor=cli.executor_of(args), max_workers=args.workers,
                    store=args.store, progress=cli.progress_wanted(args),
                    certify=args.certify, certify_depth=args.certify_depth)
    if args.out:
        rm.save(args.out)
    if args.plot:
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.plotting.regions import plot_region_panels

        cli.write_figure(plot_region_panels(rm), args.plot)
    shares = _certified_shares(rm)
    if args.json:
        cli.print_json(dict(rm.to_dict(), **({"certified_shares": shares} if shares else {})))
        return 0
    print(f"{args.case} regions on kp x kv = {len(rm.x)} x {len(rm.y)}:")
    for k, e in enumerate(rm.e):
        print(f"  e = {e:g}: exists {100 * rm.fraction('exists')[k]:.2f}%, exists & stable "
              f"{100 * rm.fraction('stable')[k]:.2f}% (area {rm.area('stable')[k]:.4g})")
    for e, sh in zip(rm.e, shares):
        parts = [f"{name} [{100 * v['share'][0]:.2f}, {100 * v['share'][1]:.2f}]%"
                 for name, v in sh.items() if name != "undecided"]
        print(f"  e = {e:g}, certified cells: " + ", ".join(parts)
              + f" (undecided {sh['undecided']['proved']} of {sh['undecided']['cells']} "
                "cells)")
    return 0


def _certified_shares(rm) -> list:
    """Per ``e``, each certified class's count and share interval (``[]`` uncertified)."""
    if rm.certified is None:
        return []
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.certified import class_shares

    return [{k: {**v, "share": list(v["share"])} for k, v in class_shares(f).items()}
            for f in rm.certified]


def _run_model(args) -> int:
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.sweeps.model_regions import ModelSearch
    from hybridpd.sweeps.regions import region_map

    cli.check_model_command(args, _PAIR, "sweep the file's entries with --x KEY and --y KEY", "KEY")
    fam = ModelSearch(args.model, contact=args.contact, wall=args.wall, event=args.event,
                      period=args.period, periods=args.periods,
                      options={k: v for k, v in (("mode", args.mode), ("phase", args.phase))
                               if v is not None} or None)
    rm = region_map(fam, tuple(args.x), tuple(args.y), tile=args.tile,
                    executor=cli.executor_of(args), max_workers=args.workers,
                    store=args.store, progress=cli.progress_wanted(args))
    rm = cli.stamp_controllers(rm, args)
    if args.out:
        rm.save(args.out)
    if args.plot:
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.plotting.regions import plot_region_panels

        cli.write_figure(plot_region_panels(rm), args.plot)
    if args.json:
        cli.print_json(rm.to_dict())
    else:
        print(rm.summary())
    return _no_answer(rm)


def _no_answer(rm) -> int:
    """:data:`~hybridpd.cli._common.EXIT_NO_ORBIT` with one line on stderr saying what every
    cell reported when no cell of a model's map has an orbit; else 0."""
    if np.any(rm.exists):
        return 0
    counts = ", ".join(f"{n} {what}" for what, n in rm.counts().items() if n)
    print(f"hybridpd regions: no cell has an orbit: {counts}", file=sys.stderr)
    return cli.EXIT_NO_ORBIT
