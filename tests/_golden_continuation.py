"""Record (``--write``) or recompute the golden map continuations of the impact pair.

Cases (collocated, ``mu = 0.1``, ``L = 0.75``, ``omega = 5``): the period-2 cycle of the
paper's parameters followed in ``kv`` from 20 towards 5 (it turns back at a fold), by
pseudo-arclength and by natural continuation; the symmetric orbit at ``e = 0.1`` followed in
``kv`` from 20 to 23 (the branch ends at grazing); the design path (``x10 = 1`` fixed, ``xm``
following) in ``kv`` to 22.5 (grazing) and in ``m2`` to 1.6; the non-symmetric orbit at
``e = 0.5``, ``kv = 0.5`` in ``kp`` from 60 to 99.3 (period doublings), the switch at its flip
and the switch at the grazing point of the symmetric family (``e = 0.1``, ``kv`` 20 -> 23).
Recorded per branch: parameter, points, multipliers, spectral radius, stability, variables,
metadata, termination, patterns and events (kind, index, parameter, detail, located, point,
multipliers, test value, variables); per switch its starts and its continued branch.

Run with the package on the path: ``python tests/_golden_continuation.py --write``.
"""
from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import _golden

PATH = _golden.DATA / "golden_continuation.npz"
W = 5.0
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")

#: Absolute tolerances off the recording machine (``_golden.check``), with their reasons:
#: a located event's test function is zero up to the location tolerance, so its value
#: there is rounding; the multipliers of a branch through non-simple impact patterns come
#: from a finite-difference DP (relative error ~1e-4, as in the specialisation tests).
ATOL = {"ev.test_value": 1e-8, "switch_grazing.branch0.multipliers": 1e-4}


def atol(arrays: dict) -> dict:
    """:data:`ATOL` for the arrays named ``...<key>`` of ``arrays``."""
    return {n: tol for n in arrays for k, tol in ATOL.items() if n.endswith(k)}


def branch_arrays(name, br) -> dict:
    """The recorded arrays of one branch, prefixed ``name.``.

    Events are recorded in the order (index, kind): two events located between the same
    points (a period doubling and the stability change it causes) come in the order of
    their located parameters, which coincide up to rounding. The numbers printed in an
    event's detail are masked (``#``): they are the stored multipliers and test values
    rounded for reading, compared as numbers in those arrays.
    """
    evs = sorted(br.events, key=lambda e: (e.index, e.kind))
    out = {"parameter": br.parameter, "points": br.points, "multipliers": br.multipliers,
           "spectral_radius": br.spectral_radius, "stable": br.stable,
           "period": np.int64(br.period), "termination": np.array(br.termination),
           "method": np.array(br.method), "patterns": np.array(repr(br.patterns)),
           "metadata": np.array(json.dumps(br.metadata, sort_keys=True, default=str)),
           "variable_names": np.array(sorted(br.variables)),
           "ev.kind": np.array([e.kind for e in evs], dtype="U32"),
           "ev.index": np.array([e.index for e in evs], np.int64),
           "ev.parameter": np.array([e.parameter for e in evs], float),
           "ev.detail": np.array([_NUMBER.sub("#", e.detail) for e in evs], dtype="U400"),
           "ev.located": np.array([e.located for e in evs], bool),
           "ev.point": np.array([e.point for e in evs], float).reshape(len(evs), 4),
           "ev.multipliers": np.array([e.multipliers for e in evs],
                                      complex).reshape(len(evs), 4),
           "ev.test_value": np.array([e.test_value for e in evs], float),
           "ev.variables": np.array(json.dumps([e.variables for e in evs], sort_keys=True))}
    for k, v in br.variables.items():
        out[f"var.{k}"] = np.asarray(v)
    return {f"{name}.{k}": np.asarray(v) for k, v in out.items()}


def switch_arrays(name, sw) -> dict:
    out = {"kind": np.array(sw.kind), "critical_value": np.float64(sw.critical_value),
           "eigenvector": np.zeros(0) if sw.eigenvector is None else sw.eigenvector,
           "critical_multiplier": np.complex128(sw.critical_multiplier),
           "starts": np.array([o.s for o in sw.starts]).reshape(-1, 4),
           "start_parameters": sw.start_parameters, "amplitude": np.float64(sw.amplitude),
           "period": np.int64(sw.period), "reason": np.array(sw.reason),
           "design": np.array(json.dumps(sw.design, sort_keys=True))}
    arrays = {f"{name}.{k}": np.asarray(v) for k, v in out.items()}
    for i, b in enumerate(sw.branches):
        arrays |= branch_arrays(f"{name}.branch{i}", b)
    return arrays


def cases():
    """The maps and starts of the cases: ``{name: (P, s0, parameter, stop, options)}``."""
    from hybridpd import ImpactPair, PDGains, Reference
    from hybridpd.analysis.periodic import find_orbit
    from hybridpd.pair.impactmap import ImpactMap
    from hybridpd.pair.orbits import symmetric_orbit

    e01 = ImpactPair(0.1, 0.1, 0.75)
    o = symmetric_orbit(e01, PDGains(10, 20), W)
    P2 = ImpactMap(e01, PDGains(10, 20), Reference(o.xm, W))
    c2 = find_orbit(P2, P2.iterate(np.array([0.3, -2.1, -2.3, 0.5]), 200)[-1], period=2)
    Ps = ImpactMap(e01, o.gains, o.reference())
    od = symmetric_orbit(e01, PDGains(10, 21.5), W)
    Pd = ImpactMap(e01, PDGains(10, 21.5), Reference(0.5, W))
    e05 = ImpactPair(0.1, 0.5, 0.75)
    om = symmetric_orbit(e05, PDGains(10, 20), W)
    Pm = ImpactMap(e05, PDGains(10, 20), om.reference())
    oa = symmetric_orbit(e05, PDGains(60, 0.5), W)
    Pa = ImpactMap(oa.pair, oa.gains, oa.reference())
    ra = find_orbit(Pa, Pa.iterate(oa.fixed_point + np.array([0, 1e-3, 0, 0]), 3000)[-1])
    return {
        "period2_kv": (P2, c2, "kv", 5.0, dict(period=2)),
        "period2_kv_natural": (P2, c2, "kv", 5.0, dict(period=2, method="natural", step=0.5)),
        "symmetric_kv_grazing": (Ps, o.fixed_point, "kv", 23.0, {}),
        "design_kv": (Pd, od.fixed_point, "kv", 22.5, dict(x10=1.0, step=0.1)),
        "design_m2": (Pm, om.fixed_point, "m2", 1.6, dict(x10=1.0, step=0.2)),
        "asym_kp": (Pa, ra, "kp", 99.3, {}),
    }


def follow(P, s0, name, stop, *, x10=None, n=1, **options):
    """A case continued on the one engine with the pair's family of ``P``."""
    from hybridpd.analysis.continuation import continue_orbit

    fam = P.family(name, x10=x10, n=n)
    return continue_orbit(fam, fam.value, stop, s0, **options)


def compute() -> dict:
    """The golden arrays (recorded with the pair's own continuation engine of the time, which
    the one engine with the pair's family replaced)."""
    from hybridpd import ImpactPair, PDGains
    from hybridpd.pair.continuation import continue_symmetric, switch_branch

    arrays, branches = {}, {}
    for name, (P, s0, par, stop, kw) in cases().items():
        branches[name] = follow(P, s0, par, stop, **kw)
        arrays |= branch_arrays(name, branches[name])
    br = branches["asym_kp"]
    pd = min(br.events_of("period_doubling"), key=lambda ev: abs(ev.parameter - 99.24))
    arrays |= switch_arrays("switch_flip", switch_branch(br, pd, pd.parameter - 0.004))
    sym = continue_symmetric(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), W, "kv", 23.0)
    g = sym.events_of("grazing")[0]
    arrays |= switch_arrays("switch_grazing", switch_branch(sym, g, 20.0))
    return arrays


if __name__ == "__main__":
    if "--write" not in sys.argv[1:]:
        sys.exit("usage: python tests/_golden_continuation.py --write")
    arrays = compute()
    _golden.save(PATH, arrays)
    print(f"wrote {PATH} ({PATH.stat().st_size} bytes): {len(arrays)} arrays")
