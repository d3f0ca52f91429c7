"""Shared pieces of the command-line interface: the parser class, common options, errors."""
from __future__ import annotations

import argparse
import sys

EXIT_BAD_INPUT = 2
EXIT_INFEASIBLE = 3


class UsageError(Exception):
    """Bad command-line input (exit status 2)."""


class Parser(argparse.ArgumentParser):
    # argparse prints the whole usage and exits; the project wants one line and status 2.
    def error(self, message):
        raise UsageError(message)


def add_plant(p, *, xm=True, gamma=False, L_required=True):
    p.add_argument("--case", required=True, choices=["collocated", "noncollocated"])
    p.add_argument("--mu", type=float, required=True, help="mass ratio m1/m2 (> 0)")
    p.add_argument("--m2", type=float, default=1.0, help="secondary mass (> 0), default 1")
    p.add_argument("--omega", type=float, required=True, help="reference frequency (> 0)")
    if gamma:
        g = p.add_mutually_exclusive_group(required=True)
        g.add_argument("--L", type=float, help="half clearance (> 0)")
        g.add_argument("--gamma", type=float, help="L / x10 (> 0)")
        p.add_argument("--x10", type=float, default=1.0, help="primary-mass amplitude, default 1")
    else:
        p.add_argument("--L", type=float, required=L_required, help="half clearance (> 0)")
    if xm:
        p.add_argument("--xm", type=float, required=True, help="reference amplitude (>= 0)")


def clearance(args):
    from hybridpd.model import check_positive

    x10 = check_positive("x10", args.x10)
    if args.L is not None:
        return check_positive("L", args.L), x10
    return check_positive("gamma", args.gamma) * x10, x10


def add_sweep(p):
    p.add_argument("--executor", default="serial", choices=["serial", "processes", "dask"])
    p.add_argument("--workers", type=int, default=None, help="worker count (default: all cores)")
    p.add_argument("--out", default=None, help="write the result (.npz)")
    p.add_argument("--json", action="store_true")


def progress_wanted(args) -> bool:
    return sys.stderr.isatty()
