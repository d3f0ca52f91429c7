"""``hybridpd basin``."""
from __future__ import annotations

import sys

from hybridpd.cli._common import (
    EXIT_DIVERGED,
    UsageError,
    add_executor,
    add_grid_axis,
    add_max_period,
    add_model,
    add_output,
    add_pair,
    check_max_period,
    check_model_command,
    check_pair_command,
    command,
    executor_of,
    grid_axis,
    print_json,
    progress_wanted,
    set_option_values,
    stamp_controllers,
    write_figure,
)

# the pair options: required without --model, not used with it
_PAIR = ("case", "mu", "omega", "e", "kp", "kv")

DESCRIPTION = ("Iterates the impact map from every point of a section slice in the "
               "(x1, y1) plane (the other section coordinates at their fixed-point "
               "values) and labels each point by where it goes: the paper's Figs 6-7.")


def register(sub):
    p = command(sub, "basin", help="basin of attraction of the symmetric orbit",
                description=DESCRIPTION,
                example=("hybridpd basin --case collocated --mu 0.1 --e 0.5 --gamma "
                         "0.75 --omega 5 --kp 10 --kv 20 --x x1 -3 5 100 --y y1 -2 10 100"
                         " --executor processes --out basin.npz --plot basin.png\n  hybridpd "
                         "basin --model examples/models/drivetrain.toml --event release --set "
                         "controller.kv 2 --x motor -1.5 1.5 31 --y motor_dot -6 6 31 --out "
                         "basin.nc"),
                notes="exit status:\n  0  done\n  2  bad input (one line on stderr)\n"
                      "  4  --model: the run diverged (the simulation that seeds the orbit "
                      "search)")
    add_pair(p)
    add_model(p)
    add_grid_axis(p, "--x", word="COORD",
                  help="grid over this section coordinate: x1 or y1 for the pair (x1 -3 5 41 "
                       "and y1 -2 10 41 times x10 by default: the reproduction's window); "
                       "--model: a coordinate of the file's section (e.g. motor, motor_dot; "
                       "default: the orbit's first two, around it)")
    add_grid_axis(p, "--y", word="COORD", help="second axis, as --x (a different one)")
    p.add_argument("--iterations", type=int, default=None,
                   help="iterations of the impact map (default 1500, two impacts each; "
                        "--model: 300 of P^k)")
    p.add_argument("--no-early-exit", action="store_true",
                   help="run every trajectory for all iterations")
    add_max_period(p, 8, "largest period of P searched for attractors")
    p.add_argument("--max-extensions", type=int, default=3,
                   help="window extensions while the symmetric orbit's basin touches the edge "
                        "(0: keep the window)")
    add_executor(p, default="serial")
    add_output(p, out=(".nc", ".zarr", ".npz"), plot="the basin (coloured by attractor)")
    p.set_defaults(func=run)


def run(args) -> int:
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.analysis.labels import LABELS
    from hybridpd.analysis.mappers import Growth
    from hybridpd.model import ImpactPair, PDGains
    from hybridpd.pair.orbits import symmetric_orbit
    from hybridpd.reproduce.basins import orbit_mapper
    from hybridpd.sweeps.basins import basin_of_attraction

    if args.model is not None:
        return _run_model(args)
    if args.set:
        raise UsageError("--set needs --model FILE.toml")
    L, x10 = check_pair_command(args, _PAIR)
    if args.iterations is None:
        args.iterations = 1500
    orb = symmetric_orbit(ImpactPair(args.mu, args.e, L, args.m2), PDGains(args.kp, args.kv),
                          args.omega, x10=x10, n=args.n, case=args.case)
    if not orb.exists:
        raise ValueError(f"no symmetric orbit at these parameters: {orb.reason}")
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.settings import Settings

    win = Settings.__dataclass_fields__["basin_window"].default
    x1 = _pair_axis("--x", args.x, "x1", (win[0] * x10, win[1] * x10, 41))
    y1 = _pair_axis("--y", args.y, "y1", (win[2] * x10, win[3] * x10, 41))
    if args.iterations < 1:
        raise ValueError(f"--iterations must be >= 1, got {args.iterations}")
    check_max_period(args)
    if args.max_extensions < 0:
        raise ValueError(f"--max-extensions must be >= 0, got {args.max_extensions}")
    mapper = orbit_mapper(orb, n_iter=args.iterations, early_exit=not args.no_early_exit)
    ab = basin_of_attraction(mapper, x1, y1, max_period=args.max_period,
                             grow=Growth(args.max_extensions), executor=executor_of(args),
                             max_workers=args.workers, progress=progress_wanted(args))
    if args.out:
        ab.save(args.out)
    if args.plot:
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.plotting.basins import plot_basin

        write_figure(plot_basin(ab), args.plot)
    fp = ab.fixed_point
    if args.json:
        print_json({
            **ab.to_dict(),
            "x1": ab.x.tolist(), "y1": ab.y.tolist(), "labels": ab.criterion_labels.tolist(),
            "label_names": list(LABELS),
            "fixed_point": {"phi": float(fp[0]), "z1": float(fp[1]), "z2": float(fp[2]),
                            "z4": float(fp[3]), "x1": float(fp[1] + L),
                            "y1": float(fp[2] + fp[3]), "y2": float(fp[2])},
            "converged_fraction": ab.converged_fraction, "spectral_radius": orb.spectral_radius,
            "stable": orb.stable, "certified_radius": mapper.certified_radius,
            "attractor_labels": ab.labels.tolist()})
        return 0
    print(f"{args.case} basin, e = {args.e:g}, kp = {args.kp:g}, kv = {args.kv:g} "
          f"(slice phi = phi* = {fp[0]:.6g}, y2 = y2* = {fp[2]:.6g})")
    for line in ab.summary():
        print(f"  {line}")
    for a in ab.attractors:
        if a.periodic:
            pts = "; ".join(f"({p[0]:.6g}, {p[1]:.6g}, {p[2]:.6g}, {p[3]:.6g})" for p in a.points)
            print(f"  {a.name}: section points (phi, z1, z2, z4) {pts}; multipliers "
                  + ", ".join(f"{abs(z):.4g}" for z in a.multipliers) + " (moduli)")
    return 0


def _pair_axis(flag: str, given, name: str, default: tuple) -> tuple:
    """The pair's slice axis ``(MIN, MAX, NUM)`` of ``flag`` (``name MIN MAX NUM``; the
    pair's slice is the plane (x1, y1): ``name`` is the only coordinate it takes there)."""
    if given is None:
        return default
    coord = given[0]
    if coord != name:
        raise ValueError(f"{flag}: the impact pair's slice is ({'x1, y1'}): {flag} takes "
                         f"{name}, got {coord!r} (other coordinates: --model)")
    return grid_axis(flag, given)[1:]


def _run_model(args) -> int:
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.analysis.model_orbits import default_axes, model_map
    from hybridpd.analysis.model_sections import DivergedRun
    from hybridpd.sweeps.basins import basin_of_attraction

    check_model_command(args, _PAIR, "set the file's entries with --set KEY VALUE")
    if (args.x is None) != (args.y is None):
        raise UsageError("--model: give both --x COORD MIN MAX NUM and --y COORD MIN MAX NUM, "
                         "or neither (the slice through the orbit in its first two section "
                         "coordinates)")
    values = set_option_values(args)
    if values:
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.sweeps.model_regions import template_of

        template_of(args.model).check(*values)
    try:
        ms = model_map(args.model, values=values, contact=args.contact, wall=args.wall,
                       event=args.event, period=args.period, periods=args.periods,
                       mode=args.mode, phase=args.phase)
        gx, gy = (args.x, args.y) if args.x is not None else default_axes(ms.fixed_point,
                                                                          ms.map.names)
        (xn, *x), (yn, *y) = grid_axis("--x", gx), grid_axis("--y", gy)
        if xn == yn:
            raise ValueError(f"--x and --y must be different coordinates, both are {xn!r}")
        mb = basin_of_attraction(
            ms.mapper(n_iter=300 if args.iterations is None else args.iterations), x, y,
            axes=(xn, yn), max_period=args.max_period, executor=executor_of(args),
            max_workers=args.workers, progress=progress_wanted(args))
    except DivergedRun as exc:
        print(f"hybridpd basin: the run diverged: {exc}", file=sys.stderr)
        return EXIT_DIVERGED
    mb = stamp_controllers(mb, args)
    if args.out:
        mb.save(args.out)
    if args.plot:
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.plotting.basins import plot_basin

        write_figure(plot_basin(mb), args.plot)
    if args.json:
        print_json(mb.to_dict())
        return 0
    for line in mb.summary():
        print(line)
    return 0
