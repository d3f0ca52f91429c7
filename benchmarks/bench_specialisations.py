"""The kept specialisation of the map protocol against the general map, on the same points.

The general :class:`hybridpd.analysis.hybridmap.SectionMap` (exact flows, saltation ``DP``)
on the impact pair's automaton against :class:`hybridpd.pair.impactmap.ImpactMap` (PD;
compiled closed-form engine, symbolic ``DP``): ``P`` per call (``apply``), ``P`` in batch
(``apply_batch``), ``DP``. The general map under a filtered PD (one controller state, the
map of :meth:`hybridpd.pair.lti.LTIOrbitResult.section_map`) is timed too, as the rate an
LTI controller's map runs at.

Points: 300 section points within ``1e-3`` of the symmetric orbit of the README's parameters
(``mu = 0.1, e = 0.5, L = 0.75, kp = 10, kv = 20, omega = 5``), collocated. Printed: rates
and the speed-up of each specialisation over the general path (best of 5 runs).

Run: ``python benchmarks/bench_specialisations.py``.
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
from _common import best_of


def points(fp, n, seed=0):
    rng = np.random.default_rng(seed)
    S = fp + 1e-3 * rng.normal(size=(n, fp.size))
    S[:, 3] = np.abs(S[:, 3])
    return S


def rates(G, S, ops):
    """Calls per second of each ``op(points)`` (the first run warms the caches)."""
    out = {}
    for name, (op, count) in ops.items():
        op(S[:5])
        t, _ = best_of(lambda op=op: op(S), repeat=5)
        out[name] = count(S) / t
    return out


def main():
    from hybridpd import ImpactPair, PDGains
    from hybridpd.analysis.hybridmap import SectionMap
    from hybridpd.pair.impactmap import ImpactMap
    from hybridpd.pair.lti import filtered_pd, lti_symmetric_orbit
    from hybridpd.pair.orbits import symmetric_orbit
    from hybridpd.pair.section import impact_pair_section

    pair = ImpactPair(0.1, 0.5, 0.75)
    n = len
    orb = symmetric_orbit(pair, PDGains(10, 20), 5.0)
    G = SectionMap(impact_pair_section(orb.system()))
    Q = ImpactMap(orb.pair, orb.gains, orb.reference())
    S = points(orb.fixed_point, 300)
    r = rates(G, S, {
        "general P": (lambda X: [G.apply(s) for s in X], n),
        "general DP": (lambda X: [G.apply(s, jacobian=True) for s in X], n),
        "closed form P per call": (lambda X: [Q.apply(s) for s in X], n),
        "closed form P batch": (lambda X: Q.apply_batch(X), n),
        "closed form DP": (lambda X: [Q.apply(s, jacobian=True) for s in X], n),
    })
    print("ImpactMap (PD, compiled closed form) against the general SectionMap:")
    for key in ("closed form P per call", "closed form P batch", "closed form DP"):
        ref = r["general DP"] if "DP" in key else r["general P"]
        print(f"  {key:24s} {r[key]:10.0f} /s  general {ref:8.0f} /s  speed-up {r[key] / ref:6.2f}x")

    o = lti_symmetric_orbit(pair, filtered_pd(10, 20, 0.05), 5.0)
    GL = o.section_map()
    SL = points(o.fixed_point, 300)
    r = rates(GL, SL, {
        "general P": (lambda X: [GL.apply(s) for s in X], n),
        "general DP": (lambda X: [GL.apply(s, jacobian=True) for s in X], n),
    })
    print("The general SectionMap under a filtered PD (one controller state):")
    for key in ("general P", "general DP"):
        print(f"  {key:24s} {r[key]:10.0f} /s")


if __name__ == "__main__":
    main()
