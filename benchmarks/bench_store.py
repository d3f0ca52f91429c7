"""Cost of writing sweeps as they go (the Zarr store) on a region map and a basin.

For each workload: no store, a fresh store (every chunk written as it arrives), and resuming
the finished store (nothing computed, everything read back); the overhead is printed in
seconds and as a percentage of the run without a store. The script uses only arguments that
earlier versions accepted too, so it can time an older checkout on the same machine
(``PYTHONPATH=<old checkout> python benchmarks/bench_store.py``).
Run: ``python benchmarks/bench_store.py [--quick]``.
"""
import shutil
import sys
import tempfile
import time
from pathlib import Path

from _common import best_of, pair_region_map


def _timed(label, fn, base=None, repeat=3):
    el, out = best_of(fn, repeat=repeat)
    extra = "" if base is None else f"  overhead {el - base:+.3f} s ({100 * (el - base) / base:+.1f}%)"
    print(f"  {label:<26s} {el:7.3f} s{extra}")
    return el, out


def _store_runs(run, tmp: Path, repeat=3):
    base, _ = _timed("no store", lambda: run(None), repeat=repeat)

    def fresh():
        shutil.rmtree(tmp / "run.zarr", ignore_errors=True)
        return run(tmp / "run.zarr")

    _timed("fresh store", fresh, base, repeat)
    _timed("resume finished store", lambda: run(tmp / "run.zarr"), base, repeat)


def main(quick=False):
    import hybridpd
    from hybridpd import ImpactPair, PDGains
    from hybridpd.analysis.mappers import mapper as make_mapper
    from hybridpd.pair.impactmap import ImpactMap
    from hybridpd.pair.orbits import symmetric_orbit
    from hybridpd.sweeps.basins import basin_of_attraction as basin

    def basin_of_attraction(m, x1, y1, **options):
        # the paper's labels alone: no attractor search
        return basin(m, x1, y1, max_period=0, **options)
    region_map = pair_region_map()

    print(f"hybridpd from {Path(hybridpd.__file__).parent}")
    num, nb = (60, 40) if quick else (200, 100)
    common = dict(e=(0.1, 0.5, 0.9), mu=0.1, omega=5.0, gamma=0.75, progress=False)
    region_map("collocated", x=("kp", 0.1, 50, 3), y=("kv", 0.1, 50, 3), **common)  # warm-up
    with tempfile.TemporaryDirectory() as d:
        print(f"region map collocated {num} x {num} x 3, serial (default chunks):")
        _store_runs(lambda st: region_map("collocated", x=("kp", 0.1, 50, num),
                                          y=("kv", 0.1, 50, num), store=st, **common), Path(d))
    orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    mapper = make_mapper(ImpactMap(orb.pair, orb.gains, orb.reference()), orb.fixed_point)
    basin_of_attraction(mapper, (-3, 5, 4), (-2, 10, 4), progress=False)  # warm-up (numba)
    for executor in ("serial", "processes"):
        with tempfile.TemporaryDirectory() as d:
            print(f"basin collocated e=0.5 {nb} x {nb}, {executor}:")
            _store_runs(lambda st, ex=executor: basin_of_attraction(
                mapper, (-3, 5, nb), (-2, 10, nb), executor=ex, store=st, progress=False),
                Path(d))
    # the slower basin (most points run all 1500 iterations): the store's share is smaller
    orb = symmetric_orbit(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0)
    mapper = make_mapper(ImpactMap(orb.pair, orb.gains, orb.reference()), orb.fixed_point)
    with tempfile.TemporaryDirectory() as d:
        print(f"basin collocated e=0.1 {nb} x {nb}, processes (one run each):")
        _store_runs(lambda st: basin_of_attraction(
            mapper, (-3, 5, nb), (-2, 10, nb), executor="processes", store=st, progress=False),
            Path(d), repeat=1)


if __name__ == "__main__":
    t0 = time.perf_counter()
    main(quick="--quick" in sys.argv)
    print(f"total {time.perf_counter() - t0:.1f} s")
