"""Closed-form flows of the PD closed loop between impacts, derived with SymPy.

Run ``python symbolic/flows.py`` (``--latex`` for LaTeX output). For both feedback cases it
prints the system matrix ``A`` (``X' = A X``, ``X = [x1, y1, x2, y2, pc, ps]``), the flow
``X(t)`` from ``X(0) = [x1_0, y1_0, x2_0, y2_0, pc_0, ps_0]`` and the gap ``z3 = x1 - x2`` with
its first derivative, then checks:

* symbolically: ``X(0) = X0`` and ``dX/dt = A X`` (using the derivative rules of ``DCh``,
  ``DSh`` and ``D = alpha^2 - kp/m2``, ``alpha = kv/(2 m2)``);
* numerically: the lambdified transition matrix against ``scipy.linalg.expm(A t)`` at random
  parameters and at / around critical damping ``kv^2 = 4 kp m2`` (``D = 0``), including
  continuity of ``Phi`` across ``D = 0``.

Collocated: the tracking error ``x2 - xd`` obeys ``m2 x'' + kv x' + kp x = 0``, so with
``e0 = x2_0 - pc_0``, ``e0' = y2_0 + w ps_0``:
``x2(t) - pc(t) = e0 (DCh + alpha DSh) + e0' DSh``, written with the entire functions
``DCh(a, D, t) = exp(-a t) cosh(sqrt(D) t)``, ``DSh(a, D, t) = exp(-a t) sinh(sqrt(D) t)/sqrt(D)``
(valid for every sign of ``D``). Non-collocated: ``x2`` is a cubic polynomial in ``t`` plus
sinusoids of frequency ``w`` (no exponentials).
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
from scipy.linalg import expm

from hybridpd.pair import symbolic as hs


def show(label, expr, latex=False):
    print(f"\n{label}:")
    if latex:
        print(sp.latex(expr))
    else:
        sp.pprint(expr, use_unicode=True, wrap_line=False)


def symbolic_check(d):
    y = d.symbols
    t = y["t"]
    X0 = sp.Matrix(y["X0"])
    full = {k: v for k, v in d.param_subs.items()}
    at0 = sp.simplify(d.flow.subs(t, 0) - X0)
    ode = (d.flow.diff(t) - d.A * d.flow).xreplace(full)
    ode = sp.simplify(sp.expand(ode))
    ok = at0 == sp.zeros(6, 1) and ode == sp.zeros(6, 1)
    print(f"\nsymbolic check: X(0) = X0: {at0 == sp.zeros(6, 1)}, "
          f"X' - A X = 0: {ode == sp.zeros(6, 1)}")
    return ok


def numeric_check(case, rng):
    worst = 0.0
    cont = 0.0
    for _ in range(200):
        kp = 10 ** rng.uniform(-1, 2.5)
        m2 = 10 ** rng.uniform(-0.7, 0.7)
        w = 10 ** rng.uniform(-0.5, 1.2)
        t = rng.uniform(-1.0, 3.0)
        kcrit = 2 * np.sqrt(kp * m2)
        kind = rng.integers(4)
        kv = [10 ** rng.uniform(-1, 2), kcrit, kcrit * (1 + rng.choice([-1, 1]) * 1e-9),
              kcrit * (1 + rng.uniform(-1e-3, 1e-3))][kind]
        P = hs.transition_matrix(t, kp=kp, kv=kv, m2=m2, w=w, case=case)
        E = expm(hs.system_matrix(kp=kp, kv=kv, m2=m2, w=w, case=case) * t)
        worst = max(worst, np.max(np.abs(P - E)) / max(1.0, np.max(np.abs(E))))
        # continuity across D = 0: Phi at kv = kcrit (1 +- 1e-12) vs at kcrit
        Pc = [hs.transition_matrix(t, kp=kp, kv=kcrit * (1 + dd), m2=m2, w=w, case=case)
              for dd in (-1e-12, 0.0, 1e-12)]
        scale = max(1.0, np.max(np.abs(Pc[1])))
        cont = max(cont, np.max(np.abs(Pc[0] - Pc[1])) / scale,
                   np.max(np.abs(Pc[2] - Pc[1])) / scale)
    print(f"  Phi(t) vs expm(A t), 200 random points incl. critical damping: "
          f"max rel. error {worst:.2e}; relative jump across D = 0 "
          f"(kv = kcrit (1 +- 1e-12)): {cont:.2e}")
    return worst < 1e-10 and cont < 1e-9


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    latex = "--latex" in argv
    t0 = time.perf_counter()
    rng = np.random.default_rng(1)
    ok = True
    for case in ("collocated", "noncollocated"):
        d = hs.derivation(case)
        print("\n" + "=" * 78 + f"\n{case.upper()}\n" + "=" * 78)
        show("A", d.A, latex)
        if case == "collocated":
            print("\nalpha = kv/(2 m2), D = alpha^2 - kp/m2; "
                  "DCh(a, D, t) = exp(-a t) cosh(sqrt(D) t), "
                  "DSh(a, D, t) = exp(-a t) sinh(sqrt(D) t)/sqrt(D)")
        names = ["x1(t)", "y1(t)", "x2(t)", "y2(t)", "pc(t)", "ps(t)"]
        for name, ex in zip(names, d.flow):
            show(name, ex, latex)
        show("z3(t) = x1 - x2", d.gap[0], latex)
        show("z3'(t) = y1 - y2", d.gap[1], latex)
        ok &= symbolic_check(d)
        ok &= numeric_check(case, rng)
    print(f"\ntotal {time.perf_counter() - t0:.2f} s; checks {'PASSED' if ok else 'FAILED'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
