"""``hybridpd boundaries``: traced boundary curves of the symmetric orbit in a parameter box."""
from __future__ import annotations

from hybridpd.cli._common import add_grid_axis, add_output, add_pair, grid_axis, print_json
from hybridpd.pair.testfunctions import PARAMETERS

_EPILOG = """\
examples:
  hybridpd boundaries --case noncollocated --mu 0.1 --e 0.5 --gamma 0.75 --omega 5 --n 1 \\
      --x kp 0.1 20 --y kv 0.1 6 --json
  hybridpd boundaries --case collocated --mu 0.1 --gamma 0.75 --omega 5 --kv 20 --n 1 \\
      --x kp 0.1 50 --y e 0.05 1

The JSON object is {"x": NAME, "y": NAME, "curves": [{"kind": K, NAME_x: [...],
NAME_y: [...], "ends": [END, END]}, ...], "codim2": [{"kind": K, NAME_x: v, NAME_y: v}, ...]}
plus the box, the fixed parameters and seeding statistics. Kinds: existence, grazing, fold,
period_doubling, neimark_sacker; ends: box_edge, closed, codim2:<kind>, stalled, max_steps.
"""


def register(sub):
    p = sub.add_parser(
        "boundaries", help="traced boundary curves of the symmetric orbit in a parameter box",
        description="Trace the existence, grazing, fold, period-doubling and Neimark-Sacker "
        "boundaries of the simple symmetric orbit over a box of two parameters (any two of "
        f"{', '.join(PARAMETERS)}; the others fixed) by pseudo-arclength continuation of "
        "closed-form test functions, and locate the codimension-2 points where they meet. "
        "Every parameter but the two swept ones is required (m2 and x10 default to 1, "
        "L = gamma x10).",
        epilog=_EPILOG)
    # m2 defaults to None: boundary_curves then takes the pair's own default
    add_pair(p, names=("case", "mu", "m2", "omega", "gamma", "x10", "e", "kp", "kv", "n"),
             required=("case",), m2=None)
    add_grid_axis(p, "--x", num=False, required=True,
                  help=f"horizontal axis: a parameter among {', '.join(PARAMETERS)} and its "
                       "range (MIN < MAX; the curves are traced, not gridded)")
    add_grid_axis(p, "--y", num=False, required=True,
                  help="second axis, as --x (a different one)")
    p.add_argument("--seed-grid", type=int, default=41,
                   help="points per axis of the coarse seeding map (>= 3), default 41")
    p.add_argument("--max-step", type=float, default=0.02,
                   help="largest step along a curve as a fraction of the box, default 0.02")
    add_output(p)
    p.set_defaults(func=run)


def run(args) -> int:
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.boundaries import boundary_curves

    x = grid_axis("--x", args.x, num=False)
    y = grid_axis("--y", args.y, num=False)
    fixed = {k: getattr(args, k) for k in ("kp", "kv", "e", "mu", "gamma", "omega")}
    res = boundary_curves(args.case, x=x, y=y, m2=args.m2, x10=args.x10, n=args.n,
                          seed_grid=args.seed_grid, max_step=args.max_step, **fixed)
    if args.json:
        print_json(res.to_dict())
        return 0
    print(f"{args.case}, n = {res.plane.n}: {len(res.curves)} boundary curves in "
          f"{res.x_name} x {res.y_name} = [{res.plane.x.lo:g}, {res.plane.x.hi:g}] x "
          f"[{res.plane.y.lo:g}, {res.plane.y.hi:g}] ({res.seconds:.2f} s)")
    for c in res.curves:
        print(f"  {c.kind:16s} {len(c):5d} points  ({c.x[0]:.6g}, {c.y[0]:.6g}) -> "
              f"({c.x[-1]:.6g}, {c.y[-1]:.6g})  ends {c.ends[0]}, {c.ends[1]}")
    for q in res.codim2:
        print(f"  codim-2 {q.kind:28s} {res.x_name} = {q.x:.8g}, {res.y_name} = {q.y:.8g}")
    return 0
