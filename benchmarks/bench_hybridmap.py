"""The general impact map (any automaton) against the pair's fast paths, and a drivetrain basin.

1. The impact pair (collocated, e = 0.5, the symmetric orbit of the README's parameters), near
   its fixed point: applications of ``P`` per second and ``DP`` per second through

   * the general path (:class:`hybridpd.analysis.hybridmap.SectionMap`, one point per call;
     the compiled batch loop of the section map's mapper (:func:`hybridpd.analysis.mappers.mapper`), one
     application per point, with the section embedding in Python; and its iterations of
     ``P`` inside the compiled loop, as a basin uses it),
   * the compiled closed-form engine (:class:`hybridpd.pair.impactmap.ImpactMap`, batch;
     ``DP`` from the symbolic blocks),
   * the naive ``solve_ivp`` loop (DOP853, rtol 1e-10, atol 1e-12; one ``P`` = 2 impacts;
     its ``DP`` = 8 applications of ``P`` by central differences),

   printed as ratios.
2. A 100 x 100 basin of the n = 3 drivetrain of ``examples/models/drivetrain.toml`` (section:
   the releases of the backlash's ``hi`` wall, crossed once per forcing period whatever the
   number of rebounds before; one iteration = ``P``), 500 iterations, early exit on, on 2
   worker processes (target: <= 60 s). The impact section's ``P^8`` used before is no longer
   an orbit: its returns include rebounds of one burst, which Newton now refuses.

Run: ``python benchmarks/bench_hybridmap.py [--grid N] [--iterations K] [--workers W]``.
"""
from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
from _common import best_of, naive_per_impact


def pair_rates():
    from hybridpd import ImpactPair, PDGains
    from hybridpd.analysis.hybridmap import SectionMap
    from hybridpd.analysis.mappers import mapper
    from hybridpd.pair.impactmap import ImpactMap
    from hybridpd.pair.orbits import symmetric_orbit
    from hybridpd.pair.section import impact_pair_section

    orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    P = SectionMap(impact_pair_section(orb.system()))
    Q = ImpactMap(orb.pair, orb.gains, orb.reference())
    rng = np.random.default_rng(0)
    N = 2000
    S = orb.fixed_point + 1e-3 * rng.normal(size=(N, 4))
    S[:, 3] = np.abs(S[:, 3])
    P(S[0])
    P.apply(S[0], jacobian=True)
    Q.apply_batch(S[:10])
    Q.jacobian(S[0])
    n1 = 300
    t_gen, _ = best_of(lambda: [P(s) for s in S[:n1]])
    t_gen_dp, _ = best_of(lambda: [P.apply(s, jacobian=True) for s in S[:n1]])
    m = mapper(P, orb.fixed_point, n_iter=1, early_exit=False)
    m.labels(S[:10])
    t_batch, _ = best_of(lambda: m.labels(S))
    mi = mapper(P, orb.fixed_point, n_iter=200, early_exit=False)
    mi.labels(S[:2])
    t_it, (_, its) = best_of(lambda: mi.labels(S[:50]))
    t_cf, _ = best_of(lambda: Q.apply_batch(S))
    t_cf_dp, _ = best_of(lambda: [Q.jacobian(s) for s in S[:n1]])
    per_imp, _ = naive_per_impact(n_impacts=100)
    r = {
        "general, per call": n1 / t_gen,
        "general, compiled batch": N / t_batch,
        "general, compiled iterations": its.sum() / t_it,
        "closed form, batch": N / t_cf,
        "naive solve_ivp": 1.0 / (2 * per_imp),
    }
    d = {
        "general (saltation)": n1 / t_gen_dp,
        "closed form (symbolic)": n1 / t_cf_dp,
        "naive solve_ivp (central FD)": 1.0 / (8 * 2 * per_imp),
    }
    # accuracy of the general path on the same points
    err = max(np.max(np.abs(P.section.wrap(P(s) - Q(s)))) for s in S[:50])
    dperr = max(np.max(np.abs(P.jacobian(s) - Q.jacobian(s)))
                / np.max(np.abs(P.jacobian(s))) for s in S[:20])
    return r, d, err, dperr


def drivetrain_basin(grid, iterations, workers):
    from hybridpd.analysis.mappers import mapper
    from hybridpd.analysis.model_orbits import orbit_from_model
    from hybridpd.mechanics.modelfile import load_model
    from hybridpd.sweeps.basins import basin_of_attraction

    f = Path(__file__).resolve().parents[1] / "examples" / "models" / "drivetrain.toml"
    model = load_model(f)
    orb, P = orbit_from_model(model, 0, 1, 1, event="release")
    assert orb.converged and orb.stable
    t0 = time.perf_counter()
    m = mapper(P, orb.s, period=1, n_iter=iterations)
    t_cert = time.perf_counter() - t0
    names = P.section.names
    i, j = names.index("motor"), names.index("motor_dot")
    x = (orb.s[i] - 1.0, orb.s[i] + 1.0, grid)
    y = (orb.s[j] - 5.0, orb.s[j] + 5.0, grid)
    ex = "serial" if workers <= 1 else "processes"
    t0 = time.perf_counter()
    b = basin_of_attraction(m, x, y, axes=("motor", "motor_dot"), max_period=0, executor=ex,
                            max_workers=workers)
    el = time.perf_counter() - t0
    # the worst case: every point iterated to the end (no early exit), on a 10 x 10 grid
    m0 = mapper(P, orb.s, period=1, n_iter=iterations, early_exit=False)
    t0 = time.perf_counter()
    b0 = basin_of_attraction(m0, x[:2] + (10,), y[:2] + (10,), axes=("motor", "motor_dot"),
                             max_period=0)
    full = (time.perf_counter() - t0) / b0.iterations.sum()
    return el, t_cert, b, orb, full


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--grid", type=int, default=100)
    ap.add_argument("--iterations", type=int, default=500)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--skip-basin", action="store_true")
    args = ap.parse_args()
    r, d, err, dperr = pair_rates()
    print("impact pair, P applications per second:")
    for k, v in r.items():
        print(f"  {k:28s} {v:12.0f} /s   ({v / r['naive solve_ivp']:8.1f} x naive, "
              f"{v / r['closed form, batch']:7.3f} x closed form)")
    print("impact pair, DP evaluations per second:")
    for k, v in d.items():
        print(f"  {k:28s} {v:12.0f} /s   ({v / d['naive solve_ivp (central FD)']:8.1f} x naive)")
    print(f"  general vs closed form: max |P diff| {err:.1e}, max rel |DP diff| {dperr:.1e}")
    if args.skip_basin:
        return
    el, t_cert, b, orb, full = drivetrain_basin(args.grid, args.iterations, args.workers)
    counts = {a.name: int((b.labels == a.label).sum()) for a in b.attractors}
    print(f"drivetrain basin {args.grid} x {args.grid}, {args.iterations} iterations of P "
          f"(spectral radius {orb.spectral_radius:.3f}), {args.workers} worker(s): {el:.1f} s "
          f"(target <= 60 s; certification {t_cert:.1f} s); labels {counts}; "
          f"mean iterations run {b.iterations.mean():.1f}")
    print(f"  without early exit: {full * 1e6:.0f} us per iteration of P (one core), i.e. "
          f"{full * args.grid ** 2 * args.iterations / max(args.workers, 1):.0f} s for the "
          f"full grid run to the end on {args.workers} worker(s)")


if __name__ == "__main__":
    main()
