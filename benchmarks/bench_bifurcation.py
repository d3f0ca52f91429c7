"""Benchmark of the brute-force bifurcation diagram (paper parameters, kv swept).

A 200-value diagram in kv (collocated, e = 0.1, kp = 10, x10 = 1 with xm following the
design), 1000 iterations of the impact map per value, the last 100 kept, following, with the
Lyapunov exponents (100 finite-difference Jacobians per value, batched). Prints the wall time,
the cost per iterate of P (with and without the exponents) and the naive solve_ivp loop's
cost per iterate (its cost per impact times the diagram's mean impacts per iterate), as a
ratio. Run: ``python benchmarks/bench_bifurcation.py``.
"""
import numpy as np
from _common import best_of, naive_per_impact

from hybridpd import ImpactPair, PDGains
from hybridpd.pair.impactmap import ImpactMap

try:                   # this version: the pair's family through the one diagram
    from hybridpd.analysis.diagrams import bifurcation_diagram as _any_diagram
    from hybridpd.pair.bifdiagram import PAIR_SETTINGS, ImpactMapFamily

    def bifurcation_diagram(pair, gains, omega, parameter, values, **kw):
        fam = ImpactMapFamily(pair, gains, omega, parameter)
        return _any_diagram(fam, values, **dict(PAIR_SETTINGS, **kw))
except ImportError:    # earlier versions (the same run on main, for comparison)
    from hybridpd.pair.bifdiagram import bifurcation_diagram


def main():
    pair = ImpactPair(0.1, 0.1, 0.75)
    kv = np.linspace(10.0, 35.0, 200)
    kw = dict(iterations=1000, keep=100, follow=True)

    def run(lyapunov=True):
        return bifurcation_diagram(pair, PDGains(10, 10), 5.0, "kv", kv, lyapunov=lyapunov,
                                   **kw)

    bifurcation_diagram(pair, PDGains(10, 10), 5.0, "kv", kv[:3], **kw)     # warm-up (numba)
    t, d = best_of(run, repeat=2)
    t0, _ = best_of(lambda: run(False), repeat=2)
    n_it = kv.size * kw["iterations"]
    per, per0 = t / n_it, t0 / n_it
    # mean impacts per application of P along the kept iterates
    imps = []
    for i in range(0, kv.size, 20):
        P = ImpactMap(pair, PDGains(10, kv[i]), _ref(d, i))
        imps.append(float(np.mean(P.apply_batch(d.points[i]).n_impacts)))
    m_imp = float(np.mean(imps))
    naive, _ = naive_per_impact("collocated", e=0.1, kp=10.0, kv=20.0, xm=float(d.xm[40]),
                                n_impacts=200)
    naive_it = naive * m_imp
    print(f"diagram: 200 kv values x {kw['iterations']} iterates (keep {kw['keep']}, "
          f"following): {t:.2f} s with Lyapunov exponents, {t0:.2f} s without")
    print(f"  classes { {c: n for c, n in d.counts().items() if n} }; periods "
          f"{ {int(k): int(np.sum(d.period == k)) for k in np.unique(d.period) if k} }")
    print(f"per iterate of P: {per * 1e6:.2f} us (with exponents), {per0 * 1e6:.2f} us "
          f"(iteration and classification only); {m_imp:.2f} impacts per iterate")
    print(f"naive solve_ivp loop: {naive * 1e3:.2f} ms per impact = {naive_it * 1e3:.2f} ms "
          f"per iterate -> ratio naive / diagram = {naive_it / per:.0f}x "
          f"({naive_it / per0:.0f}x without exponents)")


def _ref(d, i):
    from hybridpd.model import Reference

    return Reference(float(d.xm[i]), 5.0)


if __name__ == "__main__":
    main()
