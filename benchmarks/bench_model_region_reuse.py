"""What a further cell of a model's region map costs, against one cold orbit.

Run ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_model_region_reuse.py [--n 4 10]``.
The model is ``examples/models/drivetrain_stops.toml``: a motor drives a load through a
flexible shaft, the load's travel limited by a compliant (rubber) stop on one side and a
rigid one on the other, under a PD loop on the motor with a sine reference. Prints

* one **cold orbit**: :func:`~hybridpd.analysis.model_orbits.orbit_from_model` from the
  file at the centre gains (a transient simulation to seed it, the choice of the
  stroboscopic phase, Newton), best of three after a warm-up;
* for each ``n``, an ``n x n`` **region map** over ``(controller.kp, controller.kv)``
  (serial, default options: every cell continued from its solved neighbours, a transient
  only where that fails): its wall time, the cost of a further cell
  ``(t(n x n) - t(2 x 2)) / (n^2 - 4)`` and its ratio to the cold orbit (goal: at most 1/3);
* the **naive** way, measured in the same run: a cold ``orbit_from_model`` in every cell of
  the smallest map (the cost per cell and the ratio against the map's), with the largest
  difference of the spectral radii where both find the same orbit (on the map's section;
  must be below 1e-6) and how many cells hold another coexisting orbit; and one
  stroboscopic fixed point by Newton with central differences on a ``solve_ivp`` period
  map of the same equations (DOP853, rtol 1e-11, one integration per sampling interval,
  the stops located as events), its time and its distance to the package's fixed point.
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


def _template():
    from hybridpd.mechanics.params import ModelTemplate

    return ModelTemplate.load(MODEL)


def _orbit(tpl, kp, kv):
    from hybridpd.analysis.model_orbits import orbit_from_model

    return orbit_from_model(tpl.model({"controller.kp": kp, "controller.kv": kv}))


def _region_map(n):
    from hybridpd.sweeps.model_regions import ModelSearch
    from hybridpd.sweeps.regions import region_map

    t0 = time.perf_counter()
    rm = region_map(ModelSearch(MODEL), ("controller.kp", *KP, n), ("controller.kv", *KV, n),
                    progress=False)
    return time.perf_counter() - t0, rm


def _centre(n):
    return (np.linspace(*KP, n)[n // 2] if n > 1 else 0.5 * sum(KP),
            np.linspace(*KV, n)[n // 2] if n > 1 else 0.5 * sum(KV))


def _naive_cells(tpl, rm):
    """Cold orbits in every cell (on the map's section): seconds per cell, the largest
    |rho - rho_map| where both found the same orbit, how many cells that was, and in how
    many the cold search found another orbit than the map's (coexisting orbits)."""
    from hybridpd.analysis.model_orbits import orbit_from_model

    phase = rm.fixed["section_phase"]
    t0 = time.perf_counter()
    worst, same, other = 0.0, 0, 0
    for iy, kv in enumerate(rm.y):
        for ix, kp in enumerate(rm.x):
            model = tpl.model({"controller.kp": float(kp), "controller.kv": float(kv)})
            po, _ = orbit_from_model(model, phase=phase)
            if not (po.converged and rm.exists[0, iy, ix]):
                continue
            for k in ("", "2"):
                s = getattr(rm, f"section_point{k}")[0, iy, ix]
                if np.all(np.isfinite(s)) and np.max(np.abs(s - po.s)) <= 1e-6 * max(
                        1.0, float(np.max(np.abs(s)))):
                    same += 1
                    rho = rm.spectral_radius[0, iy, ix] if not k else \
                        rm.spectral_radius2[0, iy, ix]
                    worst = max(worst, abs(po.spectral_radius - rho))
                    break
            else:
                other += 1
    return (time.perf_counter() - t0) / rm.x.size / rm.y.size, worst, same, other


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--n", type=int, nargs="+", default=[4, 10])
    args = p.parse_args(argv)
    if any(n < 3 for n in args.n):
        p.error("--n: every grid side must be >= 3")
    tpl = _template()
    kp, kv = _centre(1)
    _orbit(tpl, kp, kv)                                   # compile and cache
    cold = min(_timed(lambda: _orbit(tpl, kp, kv)) for _ in range(3))
    print(f"{MODEL.name}: one cold orbit (orbit_from_model at kp = {kp:g}, kv = {kv:g}): "
          f"{1e3 * cold:.0f} ms")
    t2, _ = _region_map(2)
    print(f"2 x 2 region map: {1e3 * t2:.0f} ms")
    maps = {}
    for n in args.n:
        t, rm = _region_map(n)
        maps[n] = rm
        further = (t - t2) / (n * n - 4)
        print(f"{n} x {n} region map: {t:.2f} s; a further cell {1e3 * further:.0f} ms = "
              f"{further / cold:.2f} of a cold orbit (goal <= 0.33); "
              f"{int(rm.exists.sum())} of {n * n} cells with an orbit")
    n0 = min(maps)
    per, worst, same, other = _naive_cells(tpl, maps[n0])
    t_n0 = _region_map(n0)[0]
    print(f"naive: a cold orbit in every cell of the {n0} x {n0} map (on its section): "
          f"{1e3 * per:.0f} ms per cell, {per * n0 * n0 / t_n0:.1f} x the map's time; in "
          f"{same} cells it finds one of the map's orbits (spectral radii agree to "
          f"{worst:.1e}), in {other} another coexisting orbit")
    assert worst < 1e-6, worst
    po, P = _orbit(tpl, kp, kv)
    s_pkg, phi0 = np.asarray(po.s, float), P.phase
    assert P.section.names == ("motor", "motor_dot", "load", "load_dot", "h0"), P.names
    sys.path.insert(0, str(ROOT / "tests"))
    from _drivetrain_reference import naive_period_map

    pm = naive_period_map(tpl.data, kp, kv)
    t0 = time.perf_counter()
    s, h, d = s_pkg * (1 + 1e-3), 1e-6, s_pkg.size
    for it in range(1, 11):                               # bounded Newton
        r = pm(s, phi0) - s
        J = np.column_stack([(pm(s + h * e, phi0) - pm(s - h * e, phi0)) / (2 * h)
                             for e in np.eye(d)]) - np.eye(d)
        s = s - np.linalg.solve(J, r)
        if np.max(np.abs(r)) < 1e-9:
            break
    t_naive = time.perf_counter() - t0
    print(f"naive solve_ivp fixed point (Newton, central differences): {it} steps in "
          f"{t_naive:.1f} s = {t_naive / cold:.0f} cold orbits of this package; distance to "
          f"the package's fixed point {np.max(np.abs(s - s_pkg)):.1e}")


def _timed(fn):
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()
