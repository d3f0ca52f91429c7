"""What a further cell of a model's region map costs, against one cold orbit.

Run ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_model_region_reuse.py [--n 4 10]
[--sample 8] [--no-ivp]`` (about a minute on two idle cores). The model is
``examples/models/drivetrain_stops.toml``: a motor drives a load through a flexible shaft,
the load's travel limited by a compliant (rubber) stop on one side and a rigid one on the
other, under a PD loop on the motor, sampled at 500 Hz, with a sine reference. Every time is
printed as wall and CPU (user + sys of this process) seconds. Prints

* in a fresh process, the first orbit (the JIT kernels loaded from their cache, or
  compiled) and a first 2 x 2 map; everything after is timed warm;
* one **cold orbit**: :func:`~hybridpd.analysis.model_orbits.orbit_from_model` from the
  file at the centre gains (a transient simulation to seed it, the choice of the
  stroboscopic phase, Newton), best of three after a warm-up;
* the **first cell** of a map: what the map does before it can continue anything (the
  section fixed once from a simulation at the file's values, then the first grid point
  solved cold: a transient and Newton), best of three;
* for each ``n``, an ``n x n`` **region map** over ``(controller.kp, controller.kv)``
  (serial, default options: every cell continued from its solved neighbours, a transient
  only where that fails): its time, the cost of a further cell
  ``(t(map) - t(first cell)) / (n^2 - 1)`` and its ratio to the cold orbit (goal: at most
  1/3), and what the map did (Newton runs, cells repaired);
* the **naive** way, measured in the same run: a cold ``orbit_from_model`` in every cell
  of the smallest map (seconds per cell, and the naive loop's time over the map's), and in
  ``--sample`` cells of the largest; the largest difference of the spectral radii where the
  cold search finds one of the map's orbits (must be below 1e-6), and in how many cells it
  finds another, coexisting orbit;
* unless ``--no-ivp``: one stroboscopic fixed point by Newton with central differences on a
  ``solve_ivp`` period map of the same equations (DOP853, rtol 1e-11, one integration per
  sampling interval, the stops located as events), its time and its distance to the
  package's fixed point.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MODEL = ROOT / "examples" / "models" / "drivetrain_stops.toml"
KP, KV = (20.0, 80.0), (2.0, 12.0)


def _clock():
    """``(wall, cpu)`` seconds now (CPU: user + sys of this process)."""
    return time.perf_counter(), time.process_time()


def _since(t):
    w, c = _clock()
    return w - t[0], c - t[1]


def _fmt(wc):
    return f"{wc[0]:.3g} s wall / {wc[1]:.3g} s CPU"


def _best(fn, repeat=3):
    """Smallest ``(wall, cpu)`` of ``repeat`` calls (by wall time) and the last result."""
    best, out = (np.inf, np.inf), None
    for _ in range(repeat):
        t = _clock()
        out = fn()
        best = min(best, _since(t))
    return best, out


def _template():
    from hybridpd.mechanics.params import ModelTemplate

    return ModelTemplate.load(MODEL)


def _orbit(tpl, kp, kv, phase=None):
    from hybridpd.analysis.model_orbits import orbit_from_model

    return orbit_from_model(tpl.model({"controller.kp": kp, "controller.kv": kv}),
                            phase=phase)


def _first_cell(tpl):
    """The map's work before its first continuation: the section fixed at the file's
    values, the first grid point solved from a simulation."""
    from hybridpd.analysis.model_orbits import SectionSpec, solve_at
    from hybridpd.analysis.model_sections import fix_section

    spec = fix_section(tpl.model(), SectionSpec())[0]
    res = solve_at(tpl.model({"controller.kp": KP[0], "controller.kv": KV[0]}), spec)
    assert res.orbits, res.detail
    return res


def _region_map(n):
    from hybridpd.sweeps.model_regions import ModelSearch
    from hybridpd.sweeps.regions import region_map

    t = _clock()
    rm = region_map(ModelSearch(MODEL), ("controller.kp", *KP, n), ("controller.kv", *KV, n),
                    progress=False)
    return _since(t), rm


def _naive_cells(tpl, rm, cells):
    """Cold orbits in `cells` (``(iy, ix)``) of map `rm`, on its section: ``(wall, cpu)``
    per cell, the largest |rho - rho_map| where both found the same orbit, how many cells
    that was, and in how many the cold search found another orbit than the map's."""
    phase = rm.fixed["section_phase"]
    t = _clock()
    worst, same, other = 0.0, 0, 0
    for iy, ix in cells:
        po, _ = _orbit(tpl, float(rm.x[ix]), float(rm.y[iy]), phase)
        if not (po.converged and rm.exists[0, iy, ix]):
            continue
        for k, rho in (("", rm.spectral_radius), ("2", rm.spectral_radius2)):
            s = getattr(rm, f"section_point{k}")[0, iy, ix]
            if np.all(np.isfinite(s)) and np.max(np.abs(s - po.s)) <= 1e-6 * max(
                    1.0, float(np.max(np.abs(s)))):
                same += 1
                worst = max(worst, abs(po.spectral_radius - rho[0, iy, ix]))
                break
        else:
            other += 1
    w, c = _since(t)
    return (w / len(cells), c / len(cells)), worst, same, other


def _ivp_fixed_point(tpl, kp, kv, cold):
    """Newton with central differences on the independent solve_ivp period map."""
    po, P = _orbit(tpl, kp, kv)
    s_pkg, phi0 = np.asarray(po.s, float), P.phase
    assert P.section.names == ("motor", "motor_dot", "load", "load_dot", "h0"), P.names
    sys.path.insert(0, str(ROOT / "tests"))
    from _drivetrain_reference import naive_period_map

    pm = naive_period_map(tpl.data, kp, kv)
    t = _clock()
    s, h, d = s_pkg * (1 + 1e-3), 1e-6, s_pkg.size
    it = 0
    for it in range(1, 11):             # bounded Newton: stops at the residual 1e-9
        r = pm(s, phi0) - s
        J = np.column_stack([(pm(s + h * e, phi0) - pm(s - h * e, phi0)) / (2 * h)
                             for e in np.eye(d)]) - np.eye(d)
        s = s - np.linalg.solve(J, r)
        if np.max(np.abs(r)) < 1e-9:
            break
    wc = _since(t)
    print(f"naive solve_ivp fixed point (Newton, central differences): {it} steps in "
          f"{_fmt(wc)} = {wc[0] / cold[0]:.0f} cold orbits of this package; distance to the "
          f"package's fixed point {np.max(np.abs(s - s_pkg)):.1e}")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--n", type=int, nargs="+", default=[4, 10],
                   help="grid sides of the maps (each >= 2; default 4 10)")
    p.add_argument("--sample", type=int, default=8,
                   help="cells of the largest map checked against cold orbits (default 8)")
    p.add_argument("--no-ivp", action="store_true", help="skip the solve_ivp fixed point")
    args = p.parse_args(argv)
    if any(n < 2 or n > 100 for n in args.n):
        p.error("--n: every grid side must be in [2, 100]")
    if args.sample < 0:
        p.error("--sample must be >= 0")
    tpl = _template()
    kp, kv = 0.5 * sum(KP), 0.5 * sum(KV)
    t = _clock()
    _orbit(tpl, kp, kv)                                   # compile and cache
    first_orbit = _since(t)
    t2 = _region_map(2)[0]                                # the map's own first calls
    print(f"in a fresh process: the first orbit {_fmt(first_orbit)} (numba kernels loaded "
          f"or compiled), then a 2 x 2 map {_fmt(t2)}")
    cold, _ = _best(lambda: _orbit(tpl, kp, kv))
    print(f"{MODEL.name}: one cold orbit (orbit_from_model at kp = {kp:g}, kv = {kv:g}): "
          f"{_fmt(cold)}")
    first, _ = _best(lambda: _first_cell(tpl))
    print(f"the first cell of a map (section fixed at the file's values, kp = {KP[0]:g}, "
          f"kv = {KV[0]:g} solved cold): {_fmt(first)}")
    maps = {}
    for n in sorted(set(args.n)):
        t, rm = _region_map(n)
        maps[n] = rm
        further = ((t[0] - first[0]) / (n * n - 1), (t[1] - first[1]) / (n * n - 1))
        print(f"{n} x {n} region map: {_fmt(t)}; a further cell {1e3 * further[0]:.0f} ms "
              f"wall / {1e3 * further[1]:.0f} ms CPU = {further[0] / cold[0]:.2f} "
              f"({further[1] / cold[1]:.2f} CPU) of a cold orbit (goal <= 0.33); "
              f"{int(rm.exists.sum())} of {n * n} cells with an orbit, "
              f"{int(rm.n_orbits.sum())} orbits, {int(rm.attempts.sum())} Newton runs, "
              f"{rm.metadata['repaired_cells']} cells repaired")
    n0, n1 = min(maps), max(maps)
    all0 = [(iy, ix) for iy in range(n0) for ix in range(n0)]
    per, worst, same, other = _naive_cells(tpl, maps[n0], all0)
    t_n0 = _region_map(n0)[0]
    print(f"naive: a cold orbit in every cell of the {n0} x {n0} map (on its section): "
          f"{1e3 * per[0]:.0f} ms wall / {1e3 * per[1]:.0f} ms CPU per cell, the loop "
          f"{per[0] * n0 * n0 / t_n0[0]:.1f} x the map's time; in {same} cells it finds one "
          f"of the map's orbits (spectral radii agree to {worst:.1e}), in {other} another "
          f"coexisting orbit")
    assert worst < 1e-6, worst
    if args.sample and n1 != n0:
        rng = np.random.default_rng(0)
        pick = rng.choice(n1 * n1, size=min(args.sample, n1 * n1), replace=False)
        per, worst, same, other = _naive_cells(tpl, maps[n1], [divmod(int(c), n1)
                                                               for c in pick])
        print(f"naive: cold orbits in {len(pick)} cells of the {n1} x {n1} map: "
              f"{1e3 * per[0]:.0f} ms wall per cell; in {same} cells one of the map's orbits "
              f"(spectral radii agree to {worst:.1e}), in {other} another coexisting orbit")
        assert worst < 1e-6, worst
    if not args.no_ivp:
        _ivp_fixed_point(tpl, kp, kv, cold)


if __name__ == "__main__":
    main()
