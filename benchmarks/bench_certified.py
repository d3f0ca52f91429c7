"""Benchmark of the certified region maps against the uncertified point map of the same grid.

The paper's boxes (Figs 4-5): mu = 0.1, gamma = 0.75, n = 1, omega = 5, e = 0.1, 0.5, 0.9,
scaled gains kp/m2, kv/m2 in [0.1, 50] (m2 = 1), 101 x 101 grid points per e. For each
feedback case: the wall and CPU time of :func:`hybridpd.pair.certified.certified_map`
(serial, bisection depth 3; target < 60 s per case on a 2-core machine), split into the
interval proofs and their confirmation in arb (every proved cell proved again in
python-flint's balls; the cells arb cannot confirm are counted and written undecided), of
``region_map(..., certify=True, executor="processes")`` (both cores), the share of proved
cells per e (and each class's share as the interval [proved, proved + undecided]), and, as
the naive approach measured in the same run, the uncertified point map of the same grid
(``region_map``), with the ratio of the two times. Every proved cell is also checked against
its grid point's verdict. Run: ``python benchmarks/bench_certified.py [--num 101]``.
"""
import argparse
import time

import numpy as np
from _common import pair_region_map

BOX = dict(mu=0.1, gamma=0.75, omega=5.0, e=(0.1, 0.5, 0.9))


def main():
    from hybridpd.pair.certified import certified_map
    region_map = pair_region_map()

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--num", type=int, default=101, help="grid points per axis (101)")
    ap.add_argument("--depth", type=int, default=3, help="bisections of undecided cells (3)")
    args = ap.parse_args()
    axes = dict(x=("kp", 0.1, 50.0, args.num), y=("kv", 0.1, 50.0, args.num))
    for case in ("collocated", "noncollocated"):  # warm-up: generated code, compiled loops
        certified_map(case, x=("kp", 9, 11, 2), y=("kv", 19, 21, 2), e=[0.5], mu=0.1,
                      gamma=0.75, omega=5.0)
        region_map(case, x=("kp", 1, 2, 2), y=("kv", 1, 2, 2), progress=False, **BOX)
    for case in ("collocated", "noncollocated"):
        t0, c0 = time.perf_counter(), time.process_time()
        rm = region_map(case, progress=False, **axes, **BOX)
        tp, cp = time.perf_counter() - t0, time.process_time() - c0
        t0, c0 = time.perf_counter(), time.process_time()
        cm = certified_map(case, depth=args.depth, **axes, **BOX)
        tc, cc = time.perf_counter() - t0, time.process_time() - c0
        t0 = time.perf_counter()
        rmc = region_map(case, progress=False, certify=True, certify_depth=args.depth,
                         executor="processes", **axes, **BOX)
        tq = time.perf_counter() - t0 - tp
        point = np.where(~rm.exists, 3, np.where(rm.stable, 1, 2))
        proved = cm.flags != 0
        bad = int((cm.flags[proved] != point[proved]).sum())
        differ = int((rmc.certified != cm.flags).sum())
        n = args.num
        print(f"{case}, {n} x {n} x 3 cells (kp/m2, kv/m2 in [0.1, 50]):")
        print(f"  certified map: {tc:.1f} s wall, {cc:.1f} s CPU serial (target < 60 s), of which "
              f"the arb confirmation {cm.arb_seconds:.1f} s wall ({100 * cm.arb_seconds / (tc - cm.arb_seconds):.0f} % "
              f"over the interval proofs); cells arb did not confirm: "
              f"{', '.join(str(int(u)) for u in cm.arb_unconfirmed)}")
        print(f"  certified map: {tc:.1f} s wall, {cc:.1f} s CPU serial (target < 60 s); "
              f"{tq:.1f} s wall with 2 worker processes (cells whose flags differ: {differ}, "
              f"arb confirming cell by cell there, without blocks); "
              f"{cm.boxes_evaluated} boxes classified (cells and their parts)")
        print(f"  point map of the same grid: {tp:.2f} s wall, {cp:.2f} s CPU -> the "
              f"certified map costs {tc / tp:.0f}x the uncertified one (serial)")
        frac = cm.proved_fraction()
        print(f"  proved cells: {', '.join(f'e = {e:g}: {100 * f:.1f}%' for e, f in zip(cm.e, frac))}"
              f" (target >= 50%); proved cells contradicting their grid point: {bad}")
        for line in cm.summary():
            print(f"    {line}")


if __name__ == "__main__":
    main()
