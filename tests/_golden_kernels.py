"""Record (``--write``) or recompute the golden results of the compiled kernels.

Cases, through the public API only (their signatures are the same before and after the
kernels' arguments became records): simulations of the sample bouncing ball (an
accumulation and a sticking mode, with and without ``tail_tol``), of a diverging mode
stopped by ``max_state``, of a chain of three masses at low restitution (contacts resolved
jointly: the loop with simultaneity groups); a first crossing; the pair's general section
map and its Jacobian; the forced oscillator's section map; the pair's impact map and a
trace of it; and the symmetric orbits of a small gain grid with their viability margins.
Recorded: jump times and states, final states and times, termination codes, map images.

Run from outside the repository with the package to record on the path:
``python tests/_golden_kernels.py --write``.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import _golden

PATH = _golden.DATA / "golden_kernels.npz"


def _traj(out, name, tr):
    out[f"{name}.jt"] = np.asarray(tr.jumps.t, float)
    out[f"{name}.jpre"] = np.asarray(tr.jumps.pre, float)
    out[f"{name}.jpost"] = np.asarray(tr.jumps.post, float)
    out[f"{name}.x_final"] = np.asarray(tr.x_final, float)
    out[f"{name}.t_final"] = np.float64(tr.t_final)
    out[f"{name}.termination"] = np.array(str(tr.termination))


def compute() -> dict:
    from hybridpd import ImpactPair, PDGains
    from hybridpd.analysis.hybridmap import Section, SectionMap
    from hybridpd.hybrid.automaton import Guard, HybridAutomaton, Mode, ZenoOptions
    from hybridpd.hybrid.events import first_crossing
    from hybridpd.hybrid.samples import (
        ball_initial_state,
        bouncing_ball,
        impact_oscillator,
        oscillator_initial_state,
    )
    from hybridpd.mechanics import simulate
    from hybridpd.mechanics.samples import mass_chain
    from hybridpd.pair.batch import impact_map, pack_params, trace_once
    from hybridpd.pair.orbits import symmetric_orbit, symmetric_orbits
    from hybridpd.pair.section import impact_pair_section

    out = {}
    # a ball on a floor: accumulation, then sticking
    g = 9.81
    floor = Guard("floor", c=[1.0, 0.0], d=0.0, direction=-1,
                  reset=([[1.0, 0.0], [0.0, -0.5]], [0.0, 0.0]), target="flight",
                  zeno_target="rest", zeno_reset=(np.zeros((2, 2)), np.zeros(2)))
    modes = [Mode("flight", [[0.0, 1.0], [0.0, 0.0]], b=[0.0, -g], guards=(floor,)),
             Mode("rest", np.zeros((2, 2)))]
    ha = HybridAutomaton(modes, state_names=("x", "v"))
    _traj(out, "ball", ha.simulate([1.0, 0.0], "flight", (0.0, 3.0)))
    _traj(out, "ball_tail", ha.simulate([1.0, 0.3], "flight", (0.0, 3.0),
                                        zeno=ZenoOptions(tail_tol=1e-9)))
    # a vibrating table (the sample ball)
    bb = bouncing_ball(g=g, e=0.5, amplitude=0.1, omega=6 * np.pi)
    _traj(out, "table", bb.simulate(ball_initial_state(0.0, 0.0, amplitude=0.1,
                                                       omega=6 * np.pi), "flight", (0.0, 4.0)))
    # a diverging mode stopped by max_state
    up = HybridAutomaton([Mode("m", [[0.0, 1.0], [1.0, 0.0]],
                               guards=(Guard("g", c=[1.0, 0.0], d=-1e6, direction=1,
                                             target="m"),))])
    _traj(out, "diverge", up.simulate([1.0, 0.0], "m", (0.0, 50.0), max_state=1e3))
    # joint contacts of a chain (the loop with simultaneity groups and its resolver)
    tr = simulate(mass_chain(3, restitution=0.1), np.zeros(6), (0.0, 1.0), max_impacts=100000)
    _traj(out, "chain", tr.hybrid)
    # the event locator alone
    fc = first_crossing([[0.0, 1.0], [-1.0, 0.0]], [1.0, 0.0], 0.0, [0.3, 1.0], 10.0)
    out["crossing.time"] = np.float64(fc.time)
    out["crossing.state"] = fc.state
    out["crossing.err"] = np.float64(fc.error_bound)
    # the pair's general section map, its Jacobian and two returns
    orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    P = SectionMap(impact_pair_section(orb.system()))
    s = orb.fixed_point + np.array([0.003, -0.002, 0.001, 0.004])
    r = P.apply(s, jacobian=True)
    out["pairmap.s"], out["pairmap.DP"], out["pairmap.t_hit"] = r.s, r.DP, np.float64(r.t_hit)
    out["pairmap.s2"] = P(s, 2)
    # the forced oscillator against a stop
    Q = SectionMap(Section(impact_oscillator(omega0=1.0, zeta=0.1, omega=0.8, stop=1.0, e=0.8),
                           "free", "impact",
                           reference=(oscillator_initial_state(0, 0, force=1.0, omega=0.8),
                                      0.0)))
    r = Q.apply(np.array([7.7, 1.66]), jacobian=True)
    out["oscmap.s"], out["oscmap.DP"] = r.s, r.DP
    # the pair's closed-form impact map
    p = pack_params(kp=10, kv=20, m2=1, mu=0.1, e=0.5, L=0.75, w=5, xm=float(orb.xm))
    S = orb.fixed_point + np.linspace(-0.05, 0.05, 12)[:, None] * np.array([1, -1, 0.5, 2])
    img, st, nimp = impact_map(p, 0, np.ascontiguousarray(S))
    out["impact_map.img"], out["impact_map.status"], out["impact_map.n"] = img, st, nimp
    img, st, _k, rec = trace_once(p, 0, np.ascontiguousarray(S[3]))
    out["trace.img"], out["trace.rec"] = img, rec
    # symmetric orbits on a small gain grid with their viability margins
    kp, kv = np.meshgrid(np.linspace(2, 30, 7), np.linspace(1, 30, 7))
    for case in ("collocated", "noncollocated"):
        oa = symmetric_orbits(kp, kv, mu=0.1, e=0.5, L=0.75, omega=5.0, case=case,
                              margin=True)
        for f in ("exists", "reason", "xm", "phi0", "viability_margin", "violation_time",
                  "violation_x1"):
            out[f"orbits.{case}.{f}"] = np.asarray(getattr(oa, f))
    return out


if __name__ == "__main__":
    arrays = compute()
    if "--write" in sys.argv:
        import hybridpd

        print("recording with", hybridpd.__file__)
        _golden.save(PATH, arrays)
    print({k: np.shape(v) for k, v in arrays.items()})
