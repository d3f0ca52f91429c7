"""The limits mu -> 0, mu -> infinity and gamma -> 0 of the symmetric orbit's conditions.

Run ``python symbolic/limits.py``. The paper (section 5) expects control to become easier as
``mu -> 0`` and the existence region to shrink as ``mu`` grows, and leaves ``gamma = L / x10``
open. With SymPy, from the derivation in :mod:`hybridpd.pair.symbolic`:

* ``mu`` enters the existence conditions (13)-(14) only through the impact velocities of the
  secondary mass, ``y20 = v (e - 1 - 2 mu)/(1 + e)`` and ``y21 = v (e - 1 + 2 e mu)/(1 + e)``,
  both affine in ``mu``; the matrix ``M`` of ``M [C, S]^T = b`` does not depend on ``mu``, so
  ``C = C0 + mu C1`` and ``S = S0 + mu S1`` exactly. Stability depends on ``mu`` only through
  the impact block's entry ``(1 + e) mu / (1 + mu)``.
* **mu -> 0**: ``R -> 1``, ``y20, y21 -> v (e - 1)/(1 + e)``, the impact block entry ``-> 0``
  (the impacts no longer change the secondary mass's velocity). Every quantity is continuous
  at ``mu = 0``, so the existence and stability regions converge to those of the ``mu = 0``
  formulas (:func:`mu0_map`).
* **mu -> infinity**: ``R -> -e``, ``y20 ~ -2 mu v/(1 + e)``, ``y21 ~ 2 e mu v/(1 + e)``,
  ``xm ~ mu hypot(C1, S1)``. The secondary mass's flight is ``x2(t) = A(t) + mu B(t)`` with
  ``B`` the flight from ``(0, y21/mu)`` under the reference ``(C1, S1)`` (not identically zero
  for ``e > 0``). Viability needs ``|x2| <= x10 + L`` (``|x1| <= x10``, ``|x1 - x2| <= L``),
  hence the orbit cannot exist for ``mu > mu_c = (x10 + L + max|A|)/max|B|``
  (:func:`mu_inf_bound`): the existence region is empty in the limit, for every gain pair.
* **gamma -> 0** (``L -> 0`` at fixed ``x10``): right after the ``+L`` impact the gap speed is
  ``z4+ = -v - y21 = -2 e (1 + mu) v/(1 + e)``, independent of ``L``, while the band
  ``|z3| <= L`` shrinks; the gap reaches ``-L`` after ``t_c ~ 2 L/|z4+| -> 0 < n T/2``: an extra
  contact, so for ``e > 0`` no orbit exists as ``gamma -> 0`` (:func:`gamma0_contact_time`).

The script prints these limits and checks them against maps computed with
:func:`hybridpd.pair.orbits.symmetric_orbits` at ``mu = 1e-4``, ``mu = 1e4`` and
``gamma = 1e-4`` (the tests run the same checks).
"""
from __future__ import annotations

import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np
import sympy as sp

from hybridpd.pair import symbolic as hs
from hybridpd.pair.batch import Flights
from hybridpd.pair.orbits import _viability_kernel, symmetric_orbits

PAPER = dict(e=(0.1, 0.5, 0.9), L=0.75, omega=5.0, x10=1.0, m2=1.0, n=1)


def derive(case="collocated") -> dict:
    """SymPy limits of the quantities through which ``mu`` enters (see module docstring)."""
    d = hs.derivation(case)
    y = d.symbols
    mu, e, v = y["mu"], y["e"], y["v"]
    y2m, y2p = y["y2m"], y["y2p"]
    out = {"R_mu0": sp.limit(d.R, mu, 0), "R_muinf": sp.limit(d.R, mu, sp.oo),
           "y20_mu0": sp.limit(d.y2_pre, mu, 0), "y21_mu0": sp.limit(d.y2_post, mu, 0),
           "y20_muinf_coef": sp.limit(d.y2_pre / mu, mu, sp.oo),
           "y21_muinf_coef": sp.limit(d.y2_post / mu, mu, sp.oo),
           "impact_entry_mu0": sp.limit(d.impact_block[2, 3], mu, 0),
           "impact_entry_muinf": sp.limit(d.impact_block[2, 3], mu, sp.oo),
           "z4_post": sp.factor(-v - d.y2_post)}
    # M does not involve mu, b is affine in (y20, y21), which are affine in mu
    out["M_free_of_mu"] = mu not in d.M.free_symbols
    b = d.b.subs({y2m: d.y2_pre, y2p: d.y2_post})
    out["b_affine_in_mu"] = all(sp.simplify(sp.diff(bi, mu, 2)) == 0 for bi in b)
    out["b_mu0"] = sp.simplify(b.subs(mu, 0))
    out["b_muinf_coef"] = sp.simplify(sp.diff(b, mu))
    out["v"] = v
    out["e"] = e
    return out


def _existence(case, kp, kv, m2, mu, e, L, w, x10, n):
    from hybridpd.model import Case
    from hybridpd.pair.symbolic._numeric import kernel

    f = kernel("existence", Case.parse(case).value)
    m00, m01, m10, m11, b0, b1 = (np.asarray(q, float) for q in
                                  f(kp, kv, m2, mu, e, L, w, x10, n))
    det = m00 * m11 - m01 * m10
    return (b0 * m11 - m01 * b1) / det, (m00 * b1 - m10 * b0) / det


def mu0_map(case, kp, kv, *, e, L, omega, m2=1.0, x10=1.0, n=1):
    """Existence and stability at ``mu = 0`` from the same closed forms (the limit map).

    Returns ``(exists, stable)`` boolean arrays of the broadcast shape.
    """
    kp, kv, e, L = np.broadcast_arrays(*(np.asarray(a, float) for a in (kp, kv, e, L)))
    shape = kp.shape
    C, S = _existence(case, kp, kv, m2, 0.0, e, L, omega, x10, n)
    C, S = np.broadcast_to(C, shape), np.broadcast_to(S, shape)
    xm = np.hypot(C, S)
    T = 2 * np.pi / omega
    phi0 = np.mod(np.arctan2(S, C) / omega, T)
    v, y2m, y2p = hs.symmetric_velocities(mu=0.0, e=e, w=omega, x10=x10, n=n)
    v, y2m, y2p = (np.broadcast_to(a, shape) for a in (v, y2m, y2p))
    tau = n * T / 2
    x20 = x10 - L
    flat = lambda a: np.ascontiguousarray(np.broadcast_to(a, shape), dtype=float).ravel()
    P = np.stack([flat(kp), flat(kv), flat(m2), flat(0.0), flat(e), flat(L), flat(omega),
                  flat(xm)], axis=1)
    fl = Flights(flat(phi0), flat(x10), -flat(v), flat(x20), flat(y2p), flat(tau))
    code = _viability_kernel(P, 0 if case == "collocated" else 1, fl, 1e-13, False, 16)[0]
    exists = (code.reshape(shape) == 0) & (xm > 0)
    s0 = np.stack([phi0, np.broadcast_to(x20, shape), y2m, v - y2m], axis=-1)
    jac = hs.map_jacobian(s0, tau, tau, xm=xm, kp=kp, kv=kv, m2=m2, mu=0.0, e=e, L=L,
                          w=omega, case=case)
    rho = np.max(np.abs(np.linalg.eigvals(jac.DP)), axis=-1)
    return exists, exists & (rho < 1)


def mu_inf_bound(case, kp, kv, *, e, L, omega, m2=1.0, x10=1.0, n=1, samples=400):
    """``mu_c(kp, kv)``: no symmetric orbit exists for ``mu > mu_c`` (see module docstring)."""
    kp, kv, e = np.broadcast_arrays(*(np.asarray(a, float) for a in (kp, kv, e)))
    C0, S0 = _existence(case, kp, kv, m2, 0.0, e, L, omega, x10, n)
    C1, S1 = _existence(case, kp, kv, m2, 1.0, e, L, omega, x10, n)
    C1, S1 = C1 - C0, S1 - S0          # exact: C is affine in mu
    v, _, y21_0 = hs.symmetric_velocities(mu=0.0, e=e, w=omega, x10=x10, n=n)
    y21_1 = 2 * e * v / (1 + e)
    x20 = x10 - L
    tau = n * np.pi / omega
    t = np.linspace(0.0, tau, samples)[:, None]
    z = np.zeros(kp.shape)
    XA = np.stack(np.broadcast_arrays(x20 + L + z, -v + z, x20 + z, y21_0 + z, C0, S0), -1)
    XB = np.stack(np.broadcast_arrays(z, z, z, y21_1 + z, C1, S1), -1)
    fl = lambda X0: hs.flow(t.reshape((-1,) + (1,) * kp.ndim), X0, kp=kp, kv=kv, m2=m2,
                            w=omega, case=case)[..., 2]
    A = np.max(np.abs(fl(XA)), axis=0)
    B = np.max(np.abs(fl(XB)), axis=0)
    return (x10 + L + A) / B


def gamma0_contact_time(*, mu, e, omega, x10=1.0, n=1, L):
    """Leading-order time of the extra contact on ``-L`` after the ``+L`` impact, ``L -> 0``."""
    v, _, y21 = hs.symmetric_velocities(mu=mu, e=e, w=omega, x10=x10, n=n)
    return 2 * L / np.abs(-v - y21)


def check_mu0(case, grid=21, mu=1e-4):
    """Share of a gain grid where the map at ``mu`` equals the ``mu = 0`` limit map."""
    kp, kv = np.meshgrid(np.linspace(0.1, 50, grid), np.linspace(0.1, 50, grid))
    agree = []
    for e in PAPER["e"]:
        ex0, st0 = mu0_map(case, kp, kv, e=e, L=PAPER["L"], omega=PAPER["omega"])
        r = symmetric_orbits(kp, kv, mu=mu, e=e, L=PAPER["L"], omega=PAPER["omega"], case=case)
        agree.append((float(np.mean(ex0 == r.exists)), float(np.mean(st0 == r.stable))))
    return agree


def check_muinf(case, grid=21, mu=1e4):
    """``(max mu_c over the box, existing points at mu, existing points at 1.05 mu_c)``."""
    kp, kv = np.meshgrid(np.linspace(0.1, 50, grid), np.linspace(0.1, 50, grid))
    out = []
    for e in PAPER["e"]:
        muc = mu_inf_bound(case, kp, kv, e=e, L=PAPER["L"], omega=PAPER["omega"])
        r = symmetric_orbits(kp, kv, mu=mu, e=e, L=PAPER["L"], omega=PAPER["omega"], case=case)
        above = symmetric_orbits(kp, kv, mu=1.05 * muc, e=e, L=PAPER["L"],
                                 omega=PAPER["omega"], case=case)
        out.append((float(np.max(muc)), int(r.exists.sum()), int(above.exists.sum())))
    return out


def check_gamma0(case, gamma=1e-4, kp=10.0, kv=20.0, mu=0.1):
    """``[(exists, wall, computed contact time / predicted)]`` per ``e`` at small ``gamma``."""
    out = []
    for e in PAPER["e"]:
        L = gamma * PAPER["x10"]
        r = symmetric_orbits(kp, kv, mu=mu, e=e, L=L, omega=PAPER["omega"], case=case)
        tc = gamma0_contact_time(mu=mu, e=e, omega=PAPER["omega"], L=L)
        out.append((bool(r.exists), int(r.violation_wall), float(r.violation_time / tc)))
    return out


def main() -> int:
    ok = True
    for case in ("collocated", "noncollocated"):
        print("=" * 72 + f"\n{case}\n" + "=" * 72)
        d = derive(case)
        for k in ("R_mu0", "R_muinf", "y20_mu0", "y21_mu0", "y20_muinf_coef", "y21_muinf_coef",
                  "impact_entry_mu0", "impact_entry_muinf", "z4_post"):
            print(f"{k:>20} = {sp.simplify(d[k])}")
        print(f"{'M free of mu':>20} = {d['M_free_of_mu']}")
        print(f"{'b affine in mu':>20} = {d['b_affine_in_mu']}")
        ok &= bool(d["M_free_of_mu"] and d["b_affine_in_mu"])
        ok &= sp.simplify(d["R_mu0"] - 1) == 0 and sp.simplify(d["R_muinf"] + d["e"]) == 0
        a = check_mu0(case)
        print(f"mu -> 0: share of the gain grid where the map at mu = 1e-4 equals the limit "
              f"map (exists, stable) per e: {a}")
        ok &= all(x >= 0.99 and y >= 0.99 for x, y in a)
        b = check_muinf(case)
        print(f"mu -> inf: (max mu_c over the box, existing points at mu = 1e4, existing points "
              f"at 1.05 mu_c) per e: {b}")
        ok &= all(m < 1e4 and n0 == 0 and n1 == 0 for m, n0, n1 in b)
        g = check_gamma0(case)
        print(f"gamma -> 0 (gamma = 1e-4, kp = 10, kv = 20): (exists, contact wall, contact time "
              f"/ 2L/|z4+|) per e: {g}")
        ok &= all((not ex) and w == -1 and abs(q - 1) < 0.05 for ex, w, q in g)
    print(f"\nchecks {'PASSED' if ok else 'FAILED'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
