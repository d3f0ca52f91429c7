"""``hybridpd certify``."""
from __future__ import annotations

import sys

from hybridpd.cli import _common as cli

DESCRIPTION = ("Proves, cell by cell, the class of the impact pair's symmetric orbit on a "
               "grid of PD gains (kp, kv): proved stable, proved unstable, proved no orbit "
               "or undecided, in interval arithmetic with every proved cell confirmed in "
               "arb, and writes the proof (the box tree of every proved cell and the "
               "enclosures that decided it) to a certificate file. With --verify FILE it "
               "re-proves a certificate in arb alone and exits with status 1 if any claim "
               "fails.")

_PAIR = ("case", "mu", "omega", "e", "kp", "kv")


def register(sub):
    p = cli.command(sub, "certify", help="certified classes of a (kp, kv) grid, their certificate",
                    description=DESCRIPTION,
                    example=("hybridpd certify --case collocated --mu 0.1 --e 0.1 --gamma 0.75 "
                             "--omega 5 --kp 0.1 20 9 --kv 0.1 50 9 --certificate "
                             "cert.json.gz\n  hybridpd certify --verify cert.json.gz"),
                    notes="exit status: 0 proved (or verified), 1 a certificate failed "
                          "verification, 2 bad input")
    cli.add_pair(p, grid=("kp", "kv"), many=("e",))
    p.add_argument("--depth", type=cli.depth_arg, default="auto",
                   help="bisections of an undecided part of a cell (default auto: 3 for a "
                        "101 x 101 grid, one more for every factor 2 fewer cells, at most 12)")
    p.add_argument("--max-parts", type=lambda t: cli._auto_or_int(t, 1, None), default="auto",
                   help="parts classified per cell at most (default auto: the full tree of "
                        "--depth, at most 512)")
    p.add_argument("--no-confirm", action="store_true",
                   help="skip the confirmation of every proved cell in arb")
    p.add_argument("--certificate", default=None, metavar="FILE",
                   help="write the certificate (JSON; .json.gz compressed)")
    p.add_argument("--verify", default=None, metavar="FILE",
                   help="re-prove the certificate FILE in arb alone instead")
    p.add_argument("--no-viability", action="store_true",
                   help="--verify: skip the pieces of the flight (the largest part of the work)")
    p.add_argument("--json", action="store_true", help=cli.JSON_HELP)
    p.set_defaults(func=run)


def run(args) -> int:
    if args.verify is not None:
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.pair.certificate import verify_certificate

        chk = verify_certificate(args.verify, viability=not args.no_viability)
        if args.json:
            cli.print_json({"ok": chk.ok, "cells": chk.cells, "reproved": chk.reproved,
                            "failed": chk.failed, "structure_errors": chk.structure_errors,
                            "disagreements": chk.disagreements, "leaves": chk.leaves,
                            "pieces": chk.pieces, "viability": chk.viability,
                            "precision": chk.precision, "seconds": chk.seconds})
        else:
            print(chk.summary())
            for f in chk.failed:
                print(f"  e = {f['e']:g}, cell ({f['ix']}, {f['iy']}) claimed {f['claimed']}: "
                      f"{f['why']}")
            for err in chk.structure_errors:
                print(f"  {err}")
        return 0 if chk.ok else 1
    missing = [f"--{k}" for k in _PAIR if getattr(args, k) is None]
    if args.L is None and args.gamma is None:
        missing.append("--L or --gamma")
    if missing:
        raise cli.UsageError(f"the following arguments are required: {', '.join(missing)} "
                             "(or give --verify FILE)")
    L, x10 = cli.clearance(args)
    for nm in ("kp", "kv"):
        num = getattr(args, nm)[2]
        if num != int(num):
            raise ValueError(f"--{nm} NUM must be an integer, got {num:g}")
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.certified import certified_map

    cm = certified_map(args.case, x=("kp", *args.kp), y=("kv", *args.kv), e=args.e,
                       mu=args.mu, omega=args.omega, L=L, x10=x10, m2=args.m2, n=args.n,
                       depth=args.depth, max_parts=args.max_parts,
                       confirm=not args.no_confirm, certificate=args.certificate)
    if args.json:
        cli.print_json(cm.to_dict())
        return 0
    print(f"certified {cm.case} map, {cm.x.size} x {cm.y.size} cells, {cm.seconds:.1f} s "
          f"(arb confirmation {cm.arb_seconds:.1f} s):")
    for line, u in zip(cm.summary(), cm.arb_unconfirmed):
        print(f"  {line}; not confirmed in arb: {int(u)}")
    if args.certificate:
        print(f"certificate: {args.certificate}", file=sys.stderr)
    return 0
