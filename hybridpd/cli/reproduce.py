"""``hybridpd reproduce``."""
from __future__ import annotations

import sys

from hybridpd.cli._common import command

DESCRIPTION = ("Reproduces the paper's region maps (Figs 4-5) and basins (Figs 6-7) "
               "and checks each of its conclusions with numbers, writing the figures,"
               " the data files and a summary into the output directory.")


def register(sub):
    p = command(sub, "reproduce", help="reproduce the paper's Figs 4-7 and check its conclusions",
                description=DESCRIPTION,
                example=("hybridpd reproduce --out paper-figures"))
    g = p.add_mutually_exclusive_group()
    g.add_argument("--quick", action="store_true", help="coarse grids (default; ~1-2 min)")
    g.add_argument("--full", action="store_true", help="200 x 200 grids")
    p.add_argument("--out", default="reproduce-out", help="output directory")
    p.add_argument("--executor", default="processes", choices=["serial", "processes", "dask"],
                   help="where the grid points run")
    p.add_argument("--workers", type=int, default=None,
                   help="worker count (default: all cores)")
    p.set_defaults(func=run)


def run(args) -> int:
    from hybridpd.reproduce import reproduce

    path = reproduce(args.out, mode="full" if args.full else "quick", executor=args.executor,
                     max_workers=args.workers, progress=sys.stderr.isatty(),
                     log=lambda m: print(f"hybridpd reproduce: {m}", file=sys.stderr))
    print(path.read_text())
    print(f"(written to {path.parent})", file=sys.stderr)
    return 0
