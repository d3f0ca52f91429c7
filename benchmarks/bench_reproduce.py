"""The reproduction's speed: ``reproduce --quick`` <= 60 s and ``--full`` <= 5 min on 2 cores.

Both conventions and the studies included. Prints wall time, this process's CPU time (wall
time on a shared machine mostly measures the other jobs) and the per-step timings recorded in
``summary.json``. Run: ``python benchmarks/bench_reproduce.py [--full] [OUTDIR]``.
"""
import json
import sys
import tempfile
import time


def main(full=False, out=None):
    import resource

    from hybridpd.reproduce import reproduce

    out = out or tempfile.mkdtemp(prefix="bench-reproduce-")
    cpu0 = time.process_time()
    ch0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    path = reproduce(out, mode="full" if full else "quick", progress=False, log=None)
    wall = time.perf_counter() - t0
    ch1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = time.process_time() - cpu0 + (ch1.ru_utime - ch0.ru_utime) + (ch1.ru_stime - ch0.ru_stime)
    target = 300.0 if full else 60.0
    print(f"reproduce --{'full' if full else 'quick'}: wall {wall:.1f} s, CPU {cpu:.1f} s "
          f"(target {target:g} s wall on 2 cores) -> {'OK' if wall <= target else 'SLOW'}")
    data = json.loads((path.parent / "summary.json").read_text())
    for k, v in data["timings"].items():
        print(f"  {k}: {v:.2f} s")
    for r in data["runs"]:
        for k, v in r["timings"].items():
            print(f"  m2 = {r['m2']:g}, {k}: {v:.2f} s")
    return wall


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--full"]
    main(full="--full" in sys.argv[1:], out=args[0] if args else None)
