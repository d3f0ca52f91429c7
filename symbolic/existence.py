"""Existence of the simple symmetric orbit (paper section 3), derived with SymPy.

Run ``python symbolic/existence.py`` (add ``--latex`` for LaTeX output). Prints, for the
collocated and non-collocated PD loop:

* the virtual restitution coefficient R (12) and the secondary-mass velocities (10)-(11),
  checked against the impact law (2) applied directly;
* the conditions (13)-(14) as the linear system ``M [C, S]^T = b`` in
  ``C = xm cos(w t0)``, ``S = xm sin(w t0)`` (``tau = n T/2``, ``cos(w tau) = -1``);
* its determinant (never zero for ``kv > 0``), ``C``, ``S``, ``sn = S/xm``, ``cs = C/xm``,
  ``xm = sqrt(C^2 + S^2)`` (15)-(17), (20);
* a numerical check: the flight of duration ``n T/2`` from the post-impact state, integrated
  with ``scipy.integrate.solve_ivp``, lands on ``(x2, y2) = (-x20, -y20)``.

Symbols: ``y_10 = v = 2 x10 w/(n pi)``, ``x_20 = x10 - L``, ``y_20`` (pre-impact m2 velocity,
(10)), ``y_21 = R y_20`` (post, (11)), ``alpha = kv/(2 m2)``, ``D = alpha^2 - kp/m2``,
``DCh(a, D, t) = exp(-a t) cosh(sqrt(D) t)``, ``DSh(a, D, t) = exp(-a t) sinh(sqrt(D) t)/sqrt(D)``.
"""
from __future__ import annotations

import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
# small matrices only: a multi-threaded BLAS just adds overhead (and stalls on a busy machine)
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

from hybridpd.pair import symbolic as hs

SAMPLE = dict(kp=10.0, kv=20.0, m2=1.0, mu=0.1, e=0.5, L=0.75, w=5.0, x10=1.0)


def show(label, expr, latex=False):
    print(f"\n{label}:")
    if latex:
        print(sp.latex(expr))
    else:
        sp.pprint(expr, use_unicode=True, wrap_line=False)


def check_impact_law():
    d = hs.derivation("collocated")
    y = d.symbols
    mu, e, v = y["mu"], y["e"], y["v"]
    # impact law (2) applied to pre-impact (y1, y2) = (v, y20): y1+ must be -v, y2+ = y21
    y1m, y2m = v, d.y2_pre
    y1p = ((mu - e) * y1m + (1 + e) * y2m) / (1 + mu)
    y2p = ((1 + e) * mu * y1m + (1 - mu * e) * y2m) / (1 + mu)
    ok1 = sp.simplify(y1p + v) == 0
    ok2 = sp.simplify(y2p - d.y2_post) == 0
    ok3 = sp.simplify(d.y2_post - d.R * d.y2_pre) == 0
    print(f"\nimpact law check: y1+ = -v: {ok1}, y2+ = (11): {ok2}, y21 = R y20: {ok3}")
    return ok1 and ok2 and ok3


def numeric_check(case, n):
    o = hs.solve_symmetric_orbit(n=n, case=case, **SAMPLE)
    A = hs.system_matrix(kp=o.kp, kv=o.kv, m2=o.m2, w=o.w, case=case)
    sol = solve_ivp(lambda t, x: A @ x, (0.0, float(o.tau)), o.post_impact_state,
                    method="DOP853", rtol=1e-13, atol=1e-13)
    xe = sol.y[:, -1]
    err = max(abs(xe[2] + o.x20), abs(xe[3] + o.y2_pre), abs(xe[0] + o.x10))
    print(f"  n={n}: xm={float(o.xm):.12g}  sn={float(o.sn):.12g}  cs={float(o.cs):.12g}  "
          f"phi0={float(o.phi0):.12g}  det={float(o.det):.6g}  "
          f"|landing error| (solve_ivp) = {err:.2e}")
    return err < 1e-9


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    latex = "--latex" in argv
    t0 = time.perf_counter()
    ok = True
    d = hs.derivation("collocated")
    show("R (12)", d.R, latex)
    show("y20, pre-impact velocity of m2 (10)", d.y2_pre, latex)
    show("y21, post-impact velocity of m2 (11)", d.y2_post, latex)
    ok &= check_impact_law()
    for case in ("collocated", "noncollocated"):
        d = hs.derivation(case)
        print("\n" + "=" * 78 + f"\n{case.upper()}\n" + "=" * 78)
        show("conditions (13)-(14): [x2(tau) + x20, y2(tau) + y20] = 0",
             sp.Matrix(d.existence_conditions), latex)
        show("M in M [C, S]^T = b", sp.simplify(d.M), latex)
        show("b", sp.simplify(d.b), latex)
        det = sp.factor(sp.simplify(d.det))
        show("det M", det, latex)
        show("C = xm cos(w t0)", sp.simplify(d.C), latex)
        show("S = xm sin(w t0)", sp.simplify(d.S), latex)
        show("xm (20)", sp.sqrt(sp.Symbol("C") ** 2 + sp.Symbol("S") ** 2), latex)
        show("sn (15) = S / xm", sp.Symbol("S") / sp.Symbol("x_m"), latex)
        show("cs (16) = C / xm", sp.Symbol("C") / sp.Symbol("x_m"), latex)
        print(f"\nsizes (count_ops): C {sp.count_ops(d.C)}, S {sp.count_ops(d.S)}, "
              f"sn {sp.count_ops(d.sn)}, cs {sp.count_ops(d.cs)}")
        print(f"numerical check at {SAMPLE}:")
        for n in (1, 3):
            ok &= numeric_check(case, n)
    # vectorised timing
    kp, kv, e = np.meshgrid(np.linspace(0.5, 100, 200), np.linspace(0.5, 100, 200),
                            [0.1, 0.5, 0.9], indexing="ij")
    for case in ("collocated", "noncollocated"):
        t1 = time.perf_counter()
        o = hs.solve_symmetric_orbit(kp=kp, kv=kv, e=e, mu=0.1, L=0.75, w=5.0, x10=1.0, case=case)
        dt = time.perf_counter() - t1
        print(f"\n{case}: 200x200x3 grid of (kp, kv, e) in {dt * 1e3:.1f} ms, "
              f"singular: {int(np.sum(o.singular))}, nan xm: {int(np.sum(np.isnan(o.xm)))}")
    print(f"\ntotal {time.perf_counter() - t0:.2f} s; checks {'PASSED' if ok else 'FAILED'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
