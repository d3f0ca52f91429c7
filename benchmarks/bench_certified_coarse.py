"""Certified maps on coarse grids: how many of the cells of one class are proved.

The paper's two boxes at 9 x 9 cells (``mu = 0.1``, ``gamma = 0.75``, ``omega = 5``,
``n = 1``, ``m2 = 1``): collocated ``e = 0.1``, ``kp`` in ``[0.1, 20]``, ``kv`` in
``[0.1, 50]``; non-collocated ``e = 0.5``, ``kp`` in ``[5, 9]``, ``kv`` in ``[0.1, 4]``.

For each grid: the wall and CPU time of :func:`hybridpd.pair.certified.certified_map` with
its default options, the proved cells per class and the undecided ones per reason. Then a
dense sampler: ``--k`` x ``--k`` interior points of every cell and its four corners with the
package's point classifier (:func:`hybridpd.symmetric_orbits`); a cell is *of one class*
when all its points agree. As an independent cross-check, the paper's orbit written from
its equations alone (``tests/_paper_orbit.py``: ``expm`` flows, a linear solve of (13)-(14),
viability by dense sampling of the gap, finite-difference multipliers) classifies the
centre and four inner points of every cell. Printed: the proved / one-class ratio (target
>= 2/3), the proved cells a sample of either sampler contradicts (must be 0), and the
points where the two samplers disagree (near a boundary only).

Run: ``python benchmarks/bench_certified_coarse.py [--k 15] [--paper-points 5]``.
"""
import argparse
import pathlib
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "tests"))

FIXED = dict(mu=0.1, gamma=0.75, omega=5.0)
GRIDS = (("collocated", 0.1, ("kp", 0.1, 20.0, 9), ("kv", 0.1, 50.0, 9)),
         ("noncollocated", 0.5, ("kp", 5.0, 9.0, 9), ("kv", 0.1, 4.0, 9)))
NAMES = {1: "stable", 2: "unstable", 3: "no orbit"}


def sampled_classes(case, e, xe, ye, k):
    """Per cell (row = kv): the class all ``k x k`` interior points and the 4 corners share
    (1, 2, 3), else 0; and the classes of every point, ``(ny, nx, k*k + 4)``."""
    import hybridpd as hp

    ny, nx = ye.size - 1, xe.size - 1
    u = (np.arange(k) + 0.5) / k
    P, Q = [], []
    for j in range(ny):
        for i in range(nx):
            px = xe[i] + u * (xe[i + 1] - xe[i])
            py = ye[j] + u * (ye[j + 1] - ye[j])
            A, B = np.meshgrid(px, py)
            P.append(np.concatenate([A.ravel(), [xe[i], xe[i], xe[i + 1], xe[i + 1]]]))
            Q.append(np.concatenate([B.ravel(), [ye[j], ye[j + 1], ye[j], ye[j + 1]]]))
    P, Q = np.concatenate(P), np.concatenate(Q)
    r = hp.symmetric_orbits(P, Q, mu=FIXED["mu"], e=e, L=FIXED["gamma"], omega=FIXED["omega"],
                            case=case)
    c = np.where(~r.exists, 3, np.where(r.stable, 1, 2)).reshape(ny, nx, -1)
    one = np.where((c == c[..., :1]).all(axis=2), c[..., 0], 0)
    return one, c


def paper_classes(case, e, xe, ye, m):
    """The independent reference's class at the centre (``m >= 1``) and four inner points
    (``m >= 5``, at a quarter of the cell from its sides) of every cell: ``(ny, nx, m)``."""
    from _paper_orbit import paper_class

    offs = [(0.5, 0.5), (0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)][:m]
    ny, nx = ye.size - 1, xe.size - 1
    out = np.zeros((ny, nx, len(offs)), int)
    for j in range(ny):
        for i in range(nx):
            for q, (a, b) in enumerate(offs):
                kp = xe[i] + a * (xe[i + 1] - xe[i])
                kv = ye[j] + b * (ye[j + 1] - ye[j])
                out[j, i, q] = paper_class(case, kp, kv, mu=FIXED["mu"], e=e,
                                           L=FIXED["gamma"], omega=FIXED["omega"])
    return out


def point_agreement(case, e, xe, ye, m):
    """The package's point classifier at the reference's points, for the disagreement count."""
    import hybridpd as hp

    offs = [(0.5, 0.5), (0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)][:m]
    ny, nx = ye.size - 1, xe.size - 1
    kp = np.array([[[xe[i] + a * (xe[i + 1] - xe[i]) for a, _ in offs] for i in range(nx)]
                   for _ in range(ny)])
    kv = np.array([[[ye[j] + b * (ye[j + 1] - ye[j]) for _, b in offs] for _ in range(nx)]
                   for j in range(ny)])
    r = hp.symmetric_orbits(kp.ravel(), kv.ravel(), mu=FIXED["mu"], e=e, L=FIXED["gamma"],
                            omega=FIXED["omega"], case=case)
    return np.where(~r.exists, 3, np.where(r.stable, 1, 2)).reshape(ny, nx, len(offs))


def report(case, e, x, y, k, m):
    from hybridpd.pair.certified import REASONS, certified_map

    t0, c0 = time.perf_counter(), time.process_time()
    cm = certified_map(case, x=x, y=y, e=[e], **FIXED)
    tw, tc = time.perf_counter() - t0, time.process_time() - c0
    flags, reasons = cm.flags[0].astype(int), cm.reasons[0].astype(int)
    print(f"{case}, e = {e:g}, kp in [{x[1]:g}, {x[2]:g}] x kv in [{y[1]:g}, {y[2]:g}], "
          f"{x[3]} x {y[3]} cells:")
    print(f"  certifier (depth {cm.depth}, the default): {tw:.1f} s wall, {tc:.1f} s CPU "
          f"(arb confirmation {cm.arb_seconds:.1f} s wall), {cm.boxes_evaluated} boxes "
          f"classified, arb unconfirmed {int(cm.arb_unconfirmed[0])}")
    for f, name in NAMES.items():
        print(f"    proved {name}: {int((flags == f).sum())}")
    und = flags == 0
    for r in np.unique(reasons[und]):
        print(f"    undecided {int((reasons[und] == r).sum())}: {REASONS[r]}")
    t0 = time.perf_counter()
    one, pts = sampled_classes(case, e, cm.x_edges, cm.y_edges, k)
    ts = time.perf_counter() - t0
    t0 = time.perf_counter()
    ref = paper_classes(case, e, cm.x_edges, cm.y_edges, m)
    tr = time.perf_counter() - t0
    pkg = point_agreement(case, e, cm.x_edges, cm.y_edges, m)
    n_one = int((one != 0).sum())
    proved = flags != 0
    proved_one = int((proved & (one != 0)).sum())
    bad_pkg = int((proved & (pts != flags[..., None]).any(axis=2)).sum())
    bad_ref = int((proved & (ref != flags[..., None]).any(axis=2)).sum())
    print(f"  sampler ({k} x {k} points and the corners per cell, {ts:.1f} s): {n_one} cells "
          f"of one class (" + ", ".join(f"{NAMES[f]} {int((one == f).sum())}" for f in NAMES)
          + ")")
    print(f"  proved / one class: {int(proved.sum())} / {n_one} = "
          f"{proved.sum() / max(n_one, 1):.2f} (target >= 0.67); proved cells of one class: "
          f"{proved_one}; one-class cells left undecided: {n_one - proved_one}")
    print(f"  proved cells contradicted by a sample: {bad_pkg} (package points), {bad_ref} "
          f"(independent reference, {m} points per cell, {tr:.1f} s)")
    print(f"  points where the package and the reference disagree: "
          f"{int((pkg != ref).sum())} of {ref.size}")
    left = np.argwhere((one != 0) & ~proved)
    for j, i in left:
        print(f"    undecided one-class cell kp [{cm.x_edges[i]:.4g}, {cm.x_edges[i + 1]:.4g}] "
              f"kv [{cm.y_edges[j]:.4g}, {cm.y_edges[j + 1]:.4g}]: sampled "
              f"{NAMES[int(one[j, i])]}, {REASONS[reasons[j, i]]}")
    return proved.sum() / max(n_one, 1), bad_pkg + bad_ref


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--k", type=int, default=15, help="sampled points per cell and axis (15)")
    ap.add_argument("--paper-points", type=int, default=5, choices=range(1, 6),
                    help="points per cell of the independent reference (1 to 5; 5)")
    ap.add_argument("--case", choices=("collocated", "noncollocated", "both"), default="both")
    args = ap.parse_args()
    from hybridpd.pair.certified import certified_map

    # warm-up: generated code, compiled loops, the libm self-test
    certified_map("collocated", x=("kp", 9, 11, 2), y=("kv", 19, 21, 2), e=[0.5], **FIXED)
    worst = np.inf
    for case, e, x, y in GRIDS:
        if args.case in (case, "both"):
            ratio, bad = report(case, e, x, y, args.k, args.paper_points)
            worst = min(worst, ratio)
            if bad:
                print("  ERROR: a proved cell is contradicted")
    print(f"smallest proved / one-class ratio: {worst:.2f}")


if __name__ == "__main__":
    main()
