"""Shared helpers for the benchmarks: timing and the naive solve_ivp baseline."""
from __future__ import annotations

import time

import numpy as np


def best_of(fn, repeat=3):
    """Smallest wall time of ``repeat`` calls (seconds) and the last result."""
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def naive_per_impact(case="collocated", e=0.5, kp=10.0, kv=20.0, xm=1.0, n_impacts=200,
                     x0=(0.3, 0.5, 0.0, 0.0)):
    """Seconds per impact of the naive loop (solve_ivp DOP853, rtol 1e-10, atol 1e-12,
    terminal events, restart after each impact) and its impact times."""
    from hybridpd.loop import closed_loop
    from hybridpd.model import ImpactPair, PDGains, Reference
    from hybridpd.pair.naive import naive_simulate

    cl = closed_loop(ImpactPair(0.1, e, 0.75), PDGains(kp, kv), Reference(xm, 5.0), case)
    t0 = time.perf_counter()
    r = naive_simulate(cl, cl.initial_state(list(x0)), (0.0, 1e6), max_impacts=n_impacts,
                       rtol=1e-10, atol=1e-12)
    el = time.perf_counter() - t0
    return el / max(len(r.impact_times), 1), r


def pair_region_map():
    """The pair's region map as ``f(case, x=..., y=..., e=..., mu=..., ...)``, on this version
    (the one region map over the pair's family) and on earlier ones (for comparison)."""
    try:
        from hybridpd.pair.regions import SymmetricFamily
        from hybridpd.sweeps.regions import region_map
    except ImportError:
        from hybridpd.pair.regions import region_map

        return region_map
    names = set(SymmetricFamily.__dataclass_fields__)

    def region_map_of_case(case, *, x, y, **kw):
        fam = SymmetricFamily(case, **{k: kw.pop(k) for k in list(kw) if k in names})
        return region_map(fam, x, y, **kw)

    return region_map_of_case
