"""``hybridpd reproduce``."""
from __future__ import annotations

import json
import sys

from hybridpd.cli._common import (
    add_executor,
    add_output,
    add_pair,
    command,
    executor_of,
    print_json,
)

DESCRIPTION = ("Reproduces the paper's figures (Fig. 3 phase plane, Figs 4-5 region "
               "maps, Figs 6-7 basins) under two conventions for the unstated secondary "
               "mass m2, runs the convention study (where the paper's orbits exist and are "
               "stable as m2 varies) and the mu and gamma studies, and checks each of the "
               "paper's conclusions with numbers, writing figures, data, summary.md and "
               "summary.json into the output directory (--json prints summary.json). The "
               "clearance is L = 0.75 x10.")


def register(sub):
    p = command(sub, "reproduce", help="reproduce the paper's Figs 3-7 and check its conclusions",
                description=DESCRIPTION,
                example="hybridpd reproduce --out paper-figures --json")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--quick", action="store_true", help="coarse grids (default; ~1 min)")
    g.add_argument("--full", action="store_true", help="200 x 200 grids (a few minutes)")
    p.add_argument("--out", default="reproduce-out", help="output directory")
    p.add_argument("--m2", nargs="+", default=None, metavar="M2",
                   help="secondary-mass conventions (> 0, or 'auto' for the study's choice); "
                        "default: 1 auto")
    # None: the settings' own default
    add_pair(p, names=("x10",), x10=None)
    p.add_argument("--basin-window", type=float, nargs=4, default=None,
                   metavar=("X1MIN", "X1MAX", "Y1MIN", "Y1MAX"),
                   help="basin slice window in units of x10 (default -3 5 -2 10)")
    p.add_argument("--m2-range", type=float, nargs=2, default=None, metavar=("LO", "HI"),
                   help="range of the convention study (default 0.1 1000)")
    add_executor(p, default="processes")
    add_output(p)
    p.set_defaults(func=run)


def _m2_values(values):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce import AUTO

    out = []
    for v in values:
        if v == AUTO:
            out.append(AUTO)
            continue
        try:
            out.append(float(v))
        except ValueError:
            raise ValueError(f"--m2 values must be numbers > 0 or 'auto', got {v!r}") from None
    return tuple(out)


def run(args) -> int:
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce import Settings, reproduce

    kw = {}
    if args.m2 is not None:
        kw["m2"] = _m2_values(args.m2)
    if args.x10 is not None:
        kw["x10"] = args.x10
    if args.basin_window is not None:
        kw["basin_window"] = tuple(args.basin_window)
    if args.m2_range is not None:
        kw["m2_range"] = tuple(args.m2_range)
    settings = Settings.full(**kw) if args.full else Settings.quick(**kw)
    _check_out_dir(args.out)
    path = reproduce(args.out, mode="full" if args.full else "quick", executor=executor_of(args),
                     max_workers=args.workers, progress=not args.quiet,
                     log=_log(args.quiet),
                     settings=settings)
    data = json.loads((path.parent / "summary.json").read_text())
    if args.json:
        print_json(data)
        return 0
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.markdown import terminal_lines

    for line in terminal_lines(data):
        print(line)
    print(f"written to {path.parent} (summary.md, summary.json, figures)")
    return 0


def _check_out_dir(out) -> None:
    """Refuse (ValueError: one line, status 2), before anything is computed, an ``--out``
    that is an existing file or a directory that cannot be created or written."""
    # deferred import: loaded only when this runs, for start-up time
    import tempfile
    from pathlib import Path

    p = Path(out)
    if p.exists() and not p.is_dir():
        raise ValueError(f"--out {str(out)!r} is an existing file: give a directory (reproduce "
                         "writes figures, data, summary.md and summary.json into it)")
    try:
        p.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=p):
            pass
    except OSError as exc:
        raise ValueError(f"--out {str(out)!r}: cannot write there "
                         f"({exc.strerror or type(exc).__name__})") from None


def _log(quiet: bool):
    if quiet:
        return lambda m: None
    return lambda m: print(f"hybridpd reproduce: {m}", file=sys.stderr, flush=True)
