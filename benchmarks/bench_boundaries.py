"""Benchmark of the traced region boundaries against a 1000 x 1000 status mask.

Boxes (mu = 0.1, gamma = 0.75, omega = 5, n = 1, m2 = 1):

* non-collocated, e = 0.5, kp in [0.1, 20], kv in [0.1, 6] (the zoom of Fig. 5);
* collocated, e = 0.1, (kp, kv) in [0.1, 50]^2 (Fig. 4).

For each box: wall time of :func:`~hybridpd.pair.boundaries.boundary_curves` (all kinds,
default settings; target <= 5 s), number of curves and points, the largest test-function
value at the points and the implied position error ``|F| / |grad F|`` (box units); then a
1000 x 1000 status mask from the independent orbit evaluation (time), and the largest
distance between the traced curves and the mask's boundaries both ways (box units and mask
cells). Run: ``python benchmarks/bench_boundaries.py [--num 1000]``.
"""
import argparse
import time

import numpy as np

from hybridpd.pair.boundaries import boundary_curves
from hybridpd.pair.boundarymask import compare_with_mask, region_status
from hybridpd.pair.testcurve import TestCurve

BOXES = [("noncollocated", 0.5, ("kp", 0.1, 20.0), ("kv", 0.1, 6.0)),
         ("collocated", 0.1, ("kp", 0.1, 50.0), ("kv", 0.1, 50.0))]
FIXED = dict(mu=0.1, gamma=0.75, omega=5.0, n=1, m2=1.0)


def position_error(res):
    """Largest ``|F| / |grad F|`` over the curve points (box units)."""
    worst = 0.0
    for c in res.curves:
        tr = TestCurve(res.plane, c.kind)
        for u in c.u:
            ((F, g),), _ = tr.fgrad(u)
            worst = max(worst, abs(F) / max(np.linalg.norm(g), 1e-300))
    return worst


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--num", type=int, default=1000, help="mask points per axis (1000)")
    args = ap.parse_args()
    boundary_curves("collocated", x=("kp", 1, 2), y=("kv", 1, 2), e=0.5, **FIXED)  # warm-up
    for case, e, x, y in BOXES:
        times, cpu = [], []
        for _ in range(2):
            t0, c0 = time.perf_counter(), time.process_time()
            res = boundary_curves(case, x=x, y=y, e=e, **FIXED)
            times.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
        kinds = {}
        for c in res.curves:
            kinds[c.kind] = kinds.get(c.kind, 0) + 1
        print(f"{case}, e = {e}, {x[0]} in [{x[1]:g}, {x[2]:g}], {y[0]} in [{y[1]:g}, {y[2]:g}]")
        print(f"  traced: {min(times):.2f} s wall, {min(cpu):.2f} s CPU (best of 2; target "
              f"<= 5 s), {len(res.curves)} "
              f"curves {kinds}, {res.n_points()} points, {len(res.codim2)} codim-2 points "
              f"{sorted({q.kind for q in res.codim2})}, {res.n_evals} vectorised evaluations, "
              f"{res.n_seeds} seed edges, unresolved {res.unresolved}")
        print(f"  accuracy: max |test function| {max(c.max_test for c in res.curves):.1e}, "
              f"max position error |F|/|grad F| {position_error(res):.1e} (box units)")
        xs = np.linspace(x[1], x[2], args.num)
        ys = np.linspace(y[1], y[2], args.num)
        t0, c0 = time.perf_counter(), time.process_time()
        status = region_status(res.plane, xs, ys)
        tm, cm = time.perf_counter() - t0, time.process_time() - c0
        cmp = compare_with_mask(res, status, xs, ys)
        print(f"  {args.num} x {args.num} mask: {tm:.1f} s wall, {cm:.1f} s CPU "
              f"({cm / min(cpu):.0f}x the tracing's CPU), {cmp.n_mask_edges} boundary edges; "
              f"resolution {cmp.cell:.1e} (box units)")
        print(f"  distance mask boundary -> curves: max {cmp.mask_to_curves:.2e} "
              f"({cmp.mask_to_curves_cells:.2f} cells); curve points -> mask boundary: max "
              f"{cmp.curves_to_mask:.2e} ({cmp.curves_to_mask_cells:.2f} cells)")


if __name__ == "__main__":
    main()
