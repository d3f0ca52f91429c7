"""The sensitivity of a recorded run of a hybrid automaton: the saltation matrices.

:func:`sensitivity_chain` multiplies, along the flows and jumps a run recorded, each flow's
``expm(A tau)`` and each jump's saltation matrix (its reset corrected by the jump time's
dependence on the state through its guard; the time of a burst of impacts that ends in an
accumulation through the accumulation's time), and counts the directions a singular reset
removes. It is the ``DP`` of :class:`~hybridpd.analysis.hybridmap.SectionMap` and of the
stroboscopic maps (:mod:`hybridpd.analysis.strobe`).
"""
from __future__ import annotations

import numpy as np
from scipy.linalg import expm
from scipy.linalg.lapack import dgeqrf as _geqrf
from scipy.linalg.lapack import dgesdd as _gesdd
from scipy.linalg.lapack import dorgqr as _orgqr

__all__ = ["sensitivity_chain"]

#: A factor's singular value below this (relative to the factor's norm) is a direction the
#: factor removes by construction (a projection onto a contact, a held input overwritten)
_NULL_RTOL = 1e-9


def sensitivity_chain(rec, nseg, nb, modes, pk, Z0, track: bool = False) -> tuple:
    """``(Z, tangent, rank)``: the sensitivity ``dz/dz0 @ Z0`` of a recorded run after its
    first ``nb`` jumps and the flows around them.

    ``rec`` holds the run's records by name (:class:`~hybridpd.hybrid._kernel.RunBuffers`
    or the same names in any object): segments ``st0, st1, smode, sj`` (``nseg`` of them)
    and jumps ``jt, jg, jsrc, jdst, jkind, jpre, jpost``. Flows enter as ``expm(A tau)``,
    jumps as their saltation matrices (:func:`_jump`). ``tangent``: a jump of the chain is
    tangential (no saltation matrix), outside the bursts that end in an accumulation.
    ``rank`` (with ``track``, else None): the dimension of the image of ``Z0`` through the
    chain counted structurally (:func:`_image`): only a jump whose reset is singular drops
    directions, those its linear part removes (singular values below ``1e-9`` of its norm);
    a flow is invertible and removes none, however much it contracts.
    """
    n = Z0.shape[0]
    st0, st1, smode, sj = rec.st0, rec.st1, rec.smode, rec.sj
    Z = Z0
    Q = np.linalg.qr(Z0)[0] if track else None
    q = 0
    tangent = False
    tgrad = []        # d t_jump / d z0 of every jump so far
    burst = _accumulating(rec, nb)
    # a sampled loop's flows between samples repeat (one mode, one duration): each
    # exponential is computed once per chain, and each reset's invertibility once
    flows, regular = {}, {}
    for m in range(nb + 1):
        # flows of the segments at jump count m, then jump m + 1 (table index m)
        while q < nseg and sj[q] == m:
            tau = st1[q] - st0[q]
            if tau > 0.0:
                key = (int(smode[q]), float(tau))
                E = flows.get(key)
                if E is None:
                    E = flows[key] = _flow_sensitivity(modes[smode[q]].A, tau, np.eye(n))
                Z = E @ Z
                if track and Q.shape[1]:
                    # a flow is invertible: the basis is made orthonormal again at the
                    # next jump (:func:`_image`), which is where directions can drop
                    Q = E @ Q
            q += 1
        if m == nb:
            break
        Z, tg, tan, L, R = _jump(m, rec, Z, tgrad, modes, pk, n, track)
        tgrad.append(tg)
        if track and Q.shape[1]:
            key = (int(rec.jsrc[m]), int(rec.jg[m]), int(rec.jkind[m]))
            if key not in regular:
                regular[key] = _invertible(R)
            Q = _image(L, R, Q, regular[key])
        # the closing speed of a burst ending in an accumulation shrinks to zero by design
        # (the more so the shorter the unresolved tail, ZenoOptions.tail_tol): its
        # impacts are no tangential touch of the orbit
        tangent = tangent or (tan and not burst[m])
    if track and Q.shape[1]:
        Q = _orthonormal(Q)        # the flows after the last jump (invertible: rank kept)
    return Z, tangent, (Q.shape[1] if track else None)


def _orthonormal(Q) -> np.ndarray:
    """``Q`` of the reduced QR factorisation of ``Q`` by LAPACK's ``geqrf``/``orgqr`` (what
    ``numpy.linalg.qr`` calls, without its per-call checks: the chain runs it at every jump)."""
    qr, tau, _, info = _geqrf(Q)
    q, _, info2 = _orgqr(qr, tau) if info == 0 else (None, None, 1)
    return q if info2 == 0 else np.linalg.qr(Q)[0]


def _svd(M) -> tuple:
    """``(U, sv)`` of the thin SVD of ``M`` by LAPACK's ``gesdd`` (as :func:`_orthonormal`)."""
    u, sv, _, info = _gesdd(M, full_matrices=0)
    return (u, sv) if info == 0 else np.linalg.svd(M, full_matrices=False)[:2]


def _image(L, R, Q, regular=None):
    """An orthonormal basis of the image of ``span(Q)`` through jump ``q`` (linear part
    ``L``, reset ``R``; ``regular``: whether ``R`` is invertible, if known), counted
    structurally: a jump whose reset is invertible keeps every
    direction (a burst's saltation matrices are ill-conditioned, not singular); a singular
    reset drops the directions it removes (a held input overwritten at a sample, a
    contact's normal velocity projected at the start of a sticking phase)."""
    if _invertible(R) if regular is None else regular:
        return _orthonormal(L @ Q)
    # ``Q`` may have left orthonormality through the flows since the last jump
    U, sv = _svd(L @ _orthonormal(Q))
    # the Frobenius norm bounds the spectral one within sqrt(n): the cut lies far between
    # a removed direction (rounding) and a kept one
    keep = sv > _NULL_RTOL * max(float(np.linalg.norm(L)), 1e-300)
    return U[:, keep]


def _invertible(L) -> bool:
    sv = np.linalg.svd(L, compute_uv=False)
    return bool(sv[-1] > _NULL_RTOL * sv[0])


def _jump(q, rec, Z, tgrad, modes, pk, n, linear=False):
    """Sensitivity after jump ``q``: ``(Z+, d t_q / d z0, tangential, linear part, reset)``
    (the linear part ``dz+/dz-`` of a crossing only with `linear`, else None).

    A guard crossing gets its saltation matrix. A crossing at the instant of the jump
    before it whose guard that jump's reset has already passed (a release forced by a
    sample of a held input, a contact force changing sign at a reset) happens at that
    jump's time whatever the perturbation: ``Z+ = R Z + (f+ - R f-) dt_{q-1}``. A Zeno
    switch at the estimated accumulation time ``t_inf = t_k + D r / (1 - r)`` (``D = t_k -
    t_{k-1}``, ``r = D / (t_{k-1} - t_{k-2})``, the last resolved impacts of the guard;
    ``t_k`` for an immediate accumulation) gets ``Z+ = R_z Z + (R_z f- - f+) dt_inf``, with
    ``dt_inf`` from the impact-time sensitivities: the derivative of the simulated map.
    """
    jg, jsrc, jdst, jkind, jpre, jpost, jt = (rec.jg, rec.jsrc, rec.jdst, rec.jkind, rec.jpre,
                                              rec.jpost, rec.jt)
    src, dst, g = int(jsrc[q]), int(jdst[q]), int(jg[q])
    ms, md = modes[src], modes[dst]
    zm, zp = jpre[q, :n], jpost[q, :n]
    fm = ms.A @ zm + ms.b
    fp = md.A @ zp + md.b
    if jkind[q] == 3:
        Rz = pk.Rz[src, g, :n, :n]
        tg = _zeno_time_gradient(q, jt, jg, jsrc, jkind, tgrad, Z.shape[1])
        return Rz @ Z + np.outer(Rz @ fm - fp, tg), tg, False, Rz, Rz
    R = pk.Rh[src, g, :n, :n]
    guard = ms.guards[g]
    c = guard.c
    if q >= 1 and jt[q] == jt[q - 1] and jkind[q] == 1:
        past = guard.direction * (c @ zm + guard.d)
        if past > 1e-9 * (np.abs(c) @ np.abs(zm) + abs(guard.d)):
            tg = tgrad[q - 1]
            return R @ Z + np.outer(fp - R @ fm, tg), tg, False, R, R
    cf = c @ fm
    tangent = abs(cf) <= 1e-9 * (np.abs(c) @ np.abs(fm)) or jkind[q] == 2
    cZ = c @ Z
    tg = -cZ / cf
    # np.outer's values by broadcasting, without its per-call work (run at every jump)
    d = (fp - R @ fm)[:, None]
    S = R + d * c / cf if linear else None
    return R @ Z + d * cZ / cf, tg, tangent, S, R


def _zeno_time_gradient(q, jt, jg, jsrc, jkind, tgrad, m):
    same = [i for i in range(q - 1, max(q - 4, -1), -1)
            if jg[i] == jg[q] and jsrc[i] == jsrc[q] and jkind[i] != 3]
    if len(same) < 3 or same != list(range(q - 1, q - 4, -1)) or jt[q] == jt[q - 1]:
        return tgrad[q - 1].copy() if q >= 1 and jt[q] == jt[q - 1] else np.zeros(m)
    k, k1, k2 = same
    D, D1 = jt[k] - jt[k1], jt[k1] - jt[k2]
    r = D / D1
    if not (0.0 < r < 1.0) or abs(jt[k] + D * r / (1 - r) - jt[q]) > \
            1e-9 * max(1.0, abs(jt[q])):
        return np.zeros(m)      # another rule (dt_min, end time) set t_inf: no gradient
    dD = tgrad[k] - tgrad[k1]
    dr = (dD - r * (tgrad[k1] - tgrad[k2])) / D1
    return tgrad[k] + (dD * r + D * dr / (1 - r)) / (1 - r)


def _flow_sensitivity(A, tau, Z) -> np.ndarray:
    """``expm(A tau) @ Z``: by its Taylor series where ``|A tau|_1 <= 1/2`` (the short flights
    between the impacts of a burst: a few products with ``Z``, each term below 1e-17 of the
    sum ends it), else by ``scipy.linalg.expm``."""
    At = A * tau
    if float(np.abs(At).sum(axis=0).max()) > 0.5:
        return expm(At) @ Z
    out = Z.copy()
    term = Z
    for j in range(1, 40):
        term = (At @ term) / j
        out += term
        if float(np.abs(term).max()) <= 1e-17 * float(np.abs(out).max()):
            break
    return out


def _accumulating(bufs, nb) -> np.ndarray:
    """Per jump ``q < nb``: a crossing of a burst that ends in a Zeno switch (the jumps from
    ``q`` on fire the same guard of the same mode up to a jump of kind ``'zeno'`` of it)."""
    jg, jsrc, jkind = bufs.jg, bufs.jsrc, bufs.jkind
    out = np.zeros(nb, bool)
    ends = False
    for q in range(nb - 1, -1, -1):
        if jkind[q] == 3:
            ends = True
        elif q + 1 < nb and ends and jkind[q] == 1 and jg[q] == jg[q + 1] and \
                jsrc[q] == jsrc[q + 1]:
            out[q] = True
        else:
            ends = False
    return out


# the sections of the models, once defined here
