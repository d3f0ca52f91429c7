"""Command-line interface: ``hybridpd {simulate,orbit,regions,basin,design,reproduce}``.

Every command validates its input through the library; a bad value prints one line on
stderr and exits with status 2 (an infeasible design exits with 3). Machine-readable output
(``--json``) goes to stdout as one JSON object; progress goes to stderr.
"""
from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from ._version import __version__

EXIT_BAD_INPUT = 2
EXIT_INFEASIBLE = 3


class UsageError(Exception):
    """Bad command-line input (exit status 2)."""


class _Parser(argparse.ArgumentParser):
    # argparse prints the whole usage and exits; the project wants one line and status 2.
    def error(self, message):
        raise UsageError(message)


def _add_plant(p, *, xm=True, gamma=False):
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
        p.add_argument("--L", type=float, required=True, help="half clearance (> 0)")
    if xm:
        p.add_argument("--xm", type=float, required=True, help="reference amplitude (>= 0)")


def _clearance(args):
    from .model import check_positive

    x10 = check_positive("x10", args.x10)
    if args.L is not None:
        return check_positive("L", args.L), x10
    return check_positive("gamma", args.gamma) * x10, x10


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="hybridpd", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"hybridpd {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    p = sub.add_parser("simulate", help="simulate the controlled impact pair")
    _add_plant(p)
    p.add_argument("--e", type=float, required=True, help="restitution coefficient in [0, 1]")
    p.add_argument("--kp", type=float, required=True)
    p.add_argument("--kv", type=float, required=True)
    p.add_argument("--x0", type=float, nargs=4, required=True, metavar=("X1", "Y1", "X2", "Y2"))
    p.add_argument("--t-end", type=float, required=True)
    p.add_argument("--max-impacts", type=int, default=100_000)
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=_cmd_simulate)

    p = sub.add_parser("orbit", help="symmetric periodic orbit: existence and stability")
    _add_plant(p, xm=False, gamma=True)
    p.add_argument("--e", type=float, required=True, help="restitution coefficient in [0, 1]")
    p.add_argument("--n", type=int, default=1, help="odd orbit order (period n T)")
    p.add_argument("--kp", type=float, required=True)
    p.add_argument("--kv", type=float, required=True)
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=_cmd_orbit)

    p = sub.add_parser("regions", help="existence/stability regions over (kp, kv)")
    _add_plant(p, xm=False, gamma=True)
    p.add_argument("--e", type=float, nargs="+", required=True)
    p.add_argument("--n", type=int, default=1)
    p.add_argument("--kp", type=float, nargs=3, required=True, metavar=("MIN", "MAX", "NUM"))
    p.add_argument("--kv", type=float, nargs=3, required=True, metavar=("MIN", "MAX", "NUM"))
    _add_sweep(p)
    p.set_defaults(func=_cmd_regions)

    p = sub.add_parser("basin", help="basin of attraction of the symmetric orbit")
    _add_plant(p, xm=False, gamma=True)
    p.add_argument("--e", type=float, required=True)
    p.add_argument("--n", type=int, default=1)
    p.add_argument("--kp", type=float, required=True)
    p.add_argument("--kv", type=float, required=True)
    p.add_argument("--x1", type=float, nargs=3, required=True, metavar=("MIN", "MAX", "NUM"))
    p.add_argument("--y1", type=float, nargs=3, required=True, metavar=("MIN", "MAX", "NUM"))
    p.add_argument("--iterations", type=int, default=1500)
    p.add_argument("--no-early-exit", action="store_true",
                   help="run every trajectory for all iterations")
    _add_sweep(p)
    p.set_defaults(func=_cmd_basin)

    p = sub.add_parser("design", help="PD gains and reference for a desired primary-mass "
                                      "motion (optionally robust to e and mu)")
    _add_plant(p, xm=False, gamma=True)
    p.add_argument("--e", type=float, required=True, help="nominal restitution coefficient")
    p.add_argument("--n", type=int, default=1)
    p.add_argument("--kp-range", type=float, nargs=2, default=(0.1, 100.0), metavar=("LO", "HI"))
    p.add_argument("--kv-range", type=float, nargs=2, default=(0.1, 100.0), metavar=("LO", "HI"))
    p.add_argument("--e-range", type=float, nargs=2, default=None, metavar=("LO", "HI"))
    p.add_argument("--mu-range", type=float, nargs=2, default=None, metavar=("LO", "HI"))
    p.add_argument("--x10-tol", type=float, default=0.1,
                   help="robust design: allowed relative error of the primary amplitude")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=_cmd_design)

    p = sub.add_parser("reproduce", help="reproduce the paper's Figs 4-7 and check its "
                                         "conclusions (writes PNGs, data and summary.md)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--quick", action="store_true", help="coarse grids (default; ~1-2 min)")
    g.add_argument("--full", action="store_true", help="200 x 200 grids")
    p.add_argument("--out", default="reproduce-out", help="output directory")
    p.add_argument("--executor", default="processes", choices=["serial", "processes", "dask"])
    p.add_argument("--workers", type=int, default=None)
    p.set_defaults(func=_cmd_reproduce)
    return parser


def _cmd_design(args) -> int:
    from .design import InfeasibleDesignError, design

    L, x10 = _clearance(args)
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
        print(json.dumps(d))
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


def _cmd_reproduce(args) -> int:
    from .reproduce import reproduce

    path = reproduce(args.out, mode="full" if args.full else "quick", executor=args.executor,
                     max_workers=args.workers, progress=sys.stderr.isatty(),
                     log=lambda m: print(f"hybridpd reproduce: {m}", file=sys.stderr))
    print(path.read_text())
    print(f"(written to {path.parent})", file=sys.stderr)
    return 0


def _add_sweep(p):
    p.add_argument("--executor", default="serial", choices=["serial", "processes", "dask"])
    p.add_argument("--workers", type=int, default=None, help="worker count (default: all cores)")
    p.add_argument("--out", default=None, help="write the result (.npz)")
    p.add_argument("--json", action="store_true")


def _progress_wanted(args) -> bool:
    return sys.stderr.isatty()


def _cmd_orbit(args) -> int:
    from .model import ImpactPair, PDGains
    from .orbits import symmetric_orbit

    L, x10 = _clearance(args)
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


def _cmd_regions(args) -> int:
    from .regions import region_map

    L, x10 = _clearance(args)
    for nm in ("kp", "kv"):
        num = getattr(args, nm)[2]
        if num != int(num):
            raise ValueError(f"--{nm} NUM must be an integer, got {num:g}")
    rm = region_map(args.case, x=("kp", *args.kp), y=("kv", *args.kv), e=args.e, mu=args.mu,
                    omega=args.omega, L=L, x10=x10, m2=args.m2, n=args.n,
                    executor=args.executor, max_workers=args.workers,
                    progress=_progress_wanted(args))
    if args.out:
        rm.save(args.out)
    if args.json:
        print(json.dumps(rm.to_dict()))
        return 0
    print(f"{args.case} regions on kp x kv = {len(rm.x)} x {len(rm.y)}:")
    for k, e in enumerate(rm.e):
        print(f"  e = {e:g}: exists {100 * rm.fraction('exists')[k]:.2f}%, exists & stable "
              f"{100 * rm.fraction('stable')[k]:.2f}% (area {rm.area('stable')[k]:.4g})")
    return 0


def _cmd_basin(args) -> int:
    from .basins import LABELS, ImpactMapper, basin_of_attraction
    from .impactmap import ImpactMap
    from .model import ImpactPair, PDGains
    from .orbits import symmetric_orbit

    L, x10 = _clearance(args)
    orb = symmetric_orbit(ImpactPair(args.mu, args.e, L, args.m2), PDGains(args.kp, args.kv),
                          args.omega, x10=x10, n=args.n, case=args.case)
    if not orb.exists:
        raise ValueError(f"no symmetric orbit at these parameters: {orb.reason}")
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
                            max_workers=args.workers, progress=_progress_wanted(args))
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


def _cmd_simulate(args) -> int:
    from .impactpair import ControlledImpactPair
    from .model import ImpactPair, PDGains, Reference

    sysm = ControlledImpactPair(ImpactPair(args.mu, args.e, args.L, args.m2),
                                PDGains(args.kp, args.kv), Reference(args.xm, args.omega),
                                args.case)
    traj = sysm.simulate(args.x0, (0.0, args.t_end), max_impacts=args.max_impacts)
    d = traj.to_dict()
    if args.json:
        print(json.dumps(d))
        return 0
    print(f"{args.case} impact pair, t in [0, {traj.t_final:g}]: {traj.n_impacts} impacts "
          f"({int((traj.walls > 0).sum())} on wall +L, {int((traj.walls < 0).sum())} on -L), "
          f"{len(traj.sticking)} sticking interval(s); stopped: {d['termination']}")
    for imp in d["impacts"][:10]:
        print(f"  t = {imp['t']:.10f}  wall {imp['wall']:+d}  pre = "
              + " ".join(f"{v:+.6f}" for v in imp["pre"]))
    if traj.n_impacts > 10:
        print(f"  ... {traj.n_impacts - 10} more (use --json for all)")
    for a, b in d["sticking"]:
        print(f"  sticking on [{a:.10f}, {b:.10f}]")
    return 0


def main(argv=None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        return int(args.func(args) or 0)
    except UsageError as exc:
        print(f"hybridpd: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except ValueError as exc:
        print(f"hybridpd: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("hybridpd: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader of our stdout went away (e.g. `| head`): not an error of ours
        sys.stderr.close()
        return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
