"""Jacobian of the impact map (paper section 4), derived with SymPy and checked numerically.

Run ``python symbolic/jacobian.py`` (``--latex`` for LaTeX, ``--full`` to also print the
fully substituted closed-form flight blocks, which are long).

``P = P43 o P32 o P21 o P10`` on the pre-impact section ``z3 = +L, z4 > 0``, coordinates
``s = (phi, z1, z2, z4) = (t mod T, x2, y2, y1 - y2)``. On wall ``sigma`` the full state is
``X(s) = (z1 + sigma L, z2 + z4, z1, z2, xm cos(w phi), xm sin(w phi))``.

* ``DP10 = DP32``: the impact law (2) in section coordinates (constant matrix).
* ``DP21`` (``sigma = +1``) / ``DP43`` (``sigma = -1``): flight of duration ``tau`` ending at
  ``g = z3(tau) + sigma L = 0``. With ``X(tau) = Phi(tau) X(s)``, ``J = dX/ds`` (6x4),
  ``F = (phi + tau, x2, y2, y1 - y2)(tau)``:
  ``Fs = d F/ds |_tau``, ``Ftau = dF/dtau = (1, M A X(tau))``, ``Gs = c Phi J``,
  ``Gtau = c A X(tau) = z4(tau)``, and ``DP = Fs - Ftau Gs / Gtau`` (implicit function theorem).

The structural form is printed with a generic transition matrix ``Phi_ij`` and ``X(tau)``;
``symbolic/flows.py`` prints ``Phi(tau)`` in closed form. The numerical check compares each
block and ``DP = DP43 DP32 DP21 DP10`` with central finite differences (Richardson-extrapolated)
of the flow-based impact map (closed-form flows + root finding of the flight times), for
both feedback cases.
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

from hybridpd.pair import symbolic as hs

SAMPLE = dict(kp=10.0, kv=20.0, m2=1.0, mu=0.1, e=0.5, L=0.75, w=5.0)
X10 = 1.0
PERTURB = np.array([0.01, -0.02, 0.03, 0.01])


def show(label, expr, latex=False):
    print(f"\n{label}:")
    if latex:
        print(sp.latex(expr))
    else:
        sp.pprint(expr, use_unicode=True, wrap_line=False)


def structural_block(case):
    """Flight block with a generic Phi_ij and X(tau): the structure of (26)."""
    d = hs.derivation(case)
    y = d.symbols
    Phi = sp.Matrix(6, 6, lambda i, j: sp.Symbol(f"Phi_{i + 1}{j + 1}"))
    Xt = sp.Matrix(sp.symbols("x1_tau y1_tau x2_tau y2_tau pc_tau ps_tau", real=True))
    svars = [y["phi"], y["z1"], y["z2"], y["z4"]]
    J = d.flight_state0.jacobian(svars)
    Mz = sp.Matrix([[0, 0, 1, 0, 0, 0], [0, 0, 0, 1, 0, 0], [0, 1, 0, -1, 0, 0]])
    c = sp.Matrix([[1, 0, -1, 0, 0, 0]])
    Fs = sp.Matrix.vstack(sp.Matrix([[1, 0, 0, 0]]), Mz * Phi * J)
    Ftau = sp.Matrix.vstack(sp.Matrix([[1]]), Mz * d.A * Xt)
    Gs = c * Phi * J
    Gtau = (c * d.A * Xt)[0]
    return Fs, Ftau, Gs, Gtau, Fs - Ftau * Gs / Gtau


def central(F, s0, h):
    """Richardson-extrapolated central differences (error O(h^4)) of F at s0; (4, 4)."""
    out = np.zeros((4, 4))
    for j in range(4):
        ds = np.zeros(4)
        ds[j] = h
        d1 = (F(s0 + ds) - F(s0 - ds)) / (2 * h)
        d2 = (F(s0 + ds / 2) - F(s0 - ds / 2)) / h
        out[:, j] = (4 * d2 - d1) / 3
    return out


def fd_flight(s_in, wall, xm, case, h=1e-6):
    """Central differences of the flight block s_in -> s_out with root-found flight time."""
    kw = dict(xm=xm, case=case, **{k: SAMPLE[k] for k in ("kp", "kv", "m2", "w", "L")})

    def F(s):
        tau = hs.flight_time(s, wall=wall, **kw)
        return hs.flight_section_map(s, tau, wall=wall, **kw)

    return central(F, s_in, h)


def fd_map(s0, xm, case, h=1e-6):
    def P(s):
        r = hs.closed_form_map(s, xm=xm, case=case, **SAMPLE)
        assert r.ok
        return r.s4

    return central(P, s0, h)


def rel(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def numeric_check(case):
    o = hs.solve_symmetric_orbit(x10=X10, case=case, **SAMPLE)
    xm = float(o.xm)
    ok = True
    for label, s0 in (("symmetric fixed point", o.section_point),
                      ("perturbed point", o.section_point + PERTURB)):
        r = hs.closed_form_map(s0, xm=xm, case=case, **SAMPLE)
        J = hs.map_jacobian(s0, r.tau1, r.tau2, xm=xm, case=case, **SAMPLE)
        B_fd = central(lambda s: hs.impact_section_map(s, mu=SAMPLE["mu"], e=SAMPLE["e"]),
                       s0, 1e-5)
        e10 = rel(J.DP10, B_fd)
        e21 = rel(J.DP21, fd_flight(r.s1, +1, xm, case))
        e43 = rel(J.DP43, fd_flight(r.s3, -1, xm, case))
        eP = rel(J.DP, fd_map(s0, xm, case))
        rho = float(J.spectral_radius())
        print(f"  {label}: tau1={r.tau1:.12g} tau2={r.tau2:.12g}; max rel. error vs central FD: "
              f"DP10 {e10:.1e}, DP21 {e21:.1e}, DP43 {e43:.1e}, DP {eP:.1e}; "
              f"spectral radius {rho:.6g}")
        ok &= max(e10, e21, e43, eP) < 1e-6
    return ok


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    latex, full = "--latex" in argv, "--full" in argv
    t0 = time.perf_counter()
    ok = True
    d = hs.derivation("collocated")
    show("DP10 = DP32 (impact law (2) in section coordinates (phi, z1, z2, z4))",
         d.impact_block, latex)
    for case in ("collocated", "noncollocated"):
        d = hs.derivation(case)
        print("\n" + "=" * 78 + f"\n{case.upper()}\n" + "=" * 78)
        show("A (X' = A X, X = [x1, y1, x2, y2, pc, ps])", d.A, latex)
        show("state on wall sigma from section coordinates, X(s)", d.flight_state0, latex)
        Fs, Ftau, Gs, Gtau, block = structural_block(case)
        show("Fs = dF/ds at fixed tau (generic Phi = Phi(tau))", Fs, latex)
        show("Ftau = dF/dtau", Ftau, latex)
        show("Gs = dg/ds", Gs, latex)
        show("Gtau = dg/dtau = z4(tau)", Gtau, latex)
        print("\nDP21 (sigma = +1) and DP43 (sigma = -1) = Fs - Ftau Gs / Gtau, entries:")
        for i in range(4):
            for j in range(4):
                show(f"  [{i + 1},{j + 1}]", sp.factor_terms(sp.together(block[i, j])), latex)
        sizes = [sp.count_ops(x) for x in d.flight_block]
        print(f"\nclosed-form flight block (Phi(tau) substituted): count_ops per entry "
              f"min {min(sizes)}, max {max(sizes)}, total {sum(sizes)} (cse'd when lambdified)")
        if full:
            show("closed-form flight block", d.flight_block, latex)
        print(f"\nnumerical check at {SAMPLE}, x10={X10}:")
        ok &= numeric_check(case)
    print(f"\ntotal {time.perf_counter() - t0:.2f} s; checks {'PASSED' if ok else 'FAILED'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
