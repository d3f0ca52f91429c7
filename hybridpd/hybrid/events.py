r"""Guaranteed first-crossing event location for LTI (affine) flows.

A flow ``z' = A z + b`` is homogenised as ``w = [z; 1]``, ``w' = Abar w`` with
``Abar = [[A, b], [0, 0]]``, so that it is exactly ``w(t0 + s) = expm(Abar s) w(t0)``. An affine
guard ``g(z) = c . z + d`` becomes the row ``chat = [c, d]`` and, along the flow,

.. math::  g(t_0 + u h) = \sum_{k \ge 0} p_k u^k, \qquad
           p_k = \hat c\, (\bar A h)^k w(t_0) / k!,

a power series in the normalised step variable ``u in [0, 1]``. The step ``h`` is chosen per
mode so that ``||D^-1 Abar D||_inf h = theta`` (``theta = 1``) where ``D`` is a power-of-two
diagonal balancing of ``Abar``; with ``K = 20`` the truncated tail is below
``||chat D||_1 ||D^-1 w||_inf theta^(K+1) e^theta / (K+1)!`` (~1e-19 relative), so the
truncated polynomial *is* the flow to working precision. Flows are never ODE steps: a step is
``w <- Phi w`` with ``Phi = sum_k (Abar h)^k / k!``, and a state inside a step is the same
Taylor series of the state.

Event definition and guarantees
-------------------------------
Each guard is normalised to ``f = -direction * g`` so that the admissible side is ``f > 0`` and
an *event* is the first time the flow reaches ``f <= 0``. Per step, every guard gets a rigorous
error polynomial ``E(u) = sum_k e_k u^k + tail`` that bounds the difference between the exact
``f`` and the floating-point value of the polynomial (coefficient rounding, Horner rounding and
truncation, with generous constants). Then

* a cheap whole-step test ``p_0 + sum_k min(p_k, 0) u_hi^k > E`` excludes most steps;
* otherwise a left-first bisection of ``[0, u_hi]`` excludes sub-intervals ``[a, b]`` with the
  bound ``f(u) >= min(P(a), P(a) + P'(a) (b-a) - M2 (b-a)^2 / 2) - E(b)``, where
  ``M2 = sum k(k-1)|p_k| b^(k-2)`` bounds ``|P''|`` on ``[0, b]``. Nothing excluded can hold a
  zero, so a crossing inside a step is never missed, however close two crossings are;
* the first interval that is not excluded is either certified monotone with a sign change
  (a transversal crossing, refined by safeguarded Newton to the first floating-point ``u``
  with ``P(u) <= 0``), or shrinks to the time resolution: it is then *classified* on the
  Taylor-shifted polynomial: if it reaches ``-E`` it is a ``crossing`` (at its first zero),
  otherwise it is a ``grazing`` touch (reported at the local minimum). A near miss whose
  minimum is above the error bound ``E`` (~1e-13 relative) is excluded, i.e. never fires.

Start on the guard (post-reset semantics)
-----------------------------------------
At the start of every call the coefficients ``p_k`` at ``u = 0`` are examined for each guard.
If ``|p_0|`` is within the error bound (four times ``E(1)``, plus ``hot_tol`` for the guard that
has just fired) the state is *on* the guard, the lower coefficients are taken as zero and the
first *significant* coefficient ``p_m`` decides (``|p_m|`` above twice its rounding bound
``e_m`` plus the change of ``p_m`` over one ulp of the event time, which is only known to an
ulp):

* ``p_m > 0``: the flow leaves into the admissible side. The guard does not fire at ``u = 0``;
  in the first step it is searched as ``u^m F(u)`` with ``F = sum_k p_{k+m} u^k``, so a genuine
  return (small rebound, then re-impact) is still found;
* ``p_m < 0``: the flow pushes straight back through the guard: event ``EV_START`` at ``t0``;
* no significant coefficient: ``f`` is identically zero along the flow; the guard is disabled
  for this call (it can never change sign).

A state strictly on the wrong side (``p_0`` below minus the bound) also gives ``EV_START``.

Numba kernels (for reuse from other ``@njit`` code)
---------------------------------------------------
All arrays are C-contiguous ``float64`` unless stated; ``N1 = n + 1`` (homogeneous state),
``Kp1 = K + 1``, ``ng`` guards. The per-mode arrays are produced by :func:`prepare_lti_mode`
(fields of :class:`LTIModeData`).

``advance(w0, t0, t_end, ft, hot, hot_tol, max_steps, w_out) -> (code, t_event, guard, n_steps, err)``
    Flow from the homogeneous state ``w0`` (shape ``(N1,)``, ``w0[-1] == 1``) at ``t0`` until the
    first event or ``t_end``. ``ft``: the mode's tables, a :class:`FlowTables` read by name
    (``Phi, Ah``: ``(N1, N1)``; ``dinv``: ``(N1,)``; ``trunc``: float; ``G, gabs``:
    ``(>= ng, Kp1, N1)``; ``gsum``: ``(>= ng, N1)``; ``cnorm``: ``(>= ng,)``; ``prio``: int64
    ``(>= ng,)``; ``ng``: int, the guards in use). ``hot, max_steps``: int; ``hot``: index of
    the guard that has just fired (``-1``: none) and ``hot_tol`` its extra on-guard tolerance
    (use the ``err`` returned with that event). ``w_out`` (``(N1,)``, written): the state at
    the event (pre-reset) or at ``t_end``. ``code``: ``EV_NONE`` (reached ``t_end``),
    ``EV_CROSSING``, ``EV_GRAZING``, ``EV_START`` (event at ``t0``, see above), ``EV_NONFINITE`` (state overflowed; ``t_event`` is
    the last step start), ``EV_STEP_LIMIT`` (``max_steps`` steps taken). ``guard``: index of the
    winning guard (ties within the time resolution go to the larger ``prio``, then the lower
    index), ``err``: error bound of the guard value at the event. Never allocates more than a
    few small work arrays per call; every loop is bounded.

``flow_eval(w0, h, Phi, Ah, Kp1, taus, out)``
    Exact states at the sorted offsets ``taus >= 0`` (shape ``(m,)``) from ``w0``, written to
    ``out`` (``(m, N1)``), with the same stepping as :func:`advance` (so that a trajectory
    re-evaluated at an event time reproduces the kernel's state to rounding).

``flow_to(w0, tau, h, Phi, Ah, Kp1, out)``
    The single-time version (``out`` shape ``(N1,)``). ``Kp1`` is the Taylor order plus one
    (``G.shape[1]``).

Python API: :func:`prepare_lti_mode`, :func:`first_crossing`, :func:`lti_flow`.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from hybridpd._jit import njit
from hybridpd._results import compact_repr

# re-exported: the kernels below and their users share these
from hybridpd.hybrid._poly import (
    _EPS,
    _OVERSHOOT,
    _STACK,
    EV_CROSSING,
    EV_GRAZING,
    EV_NONE,
    EV_NONFINITE,
    EV_START,
    EV_STEP_LIMIT,
    K_DEFAULT,
    THETA_DEFAULT,
    _classify,
    _first_root,
    _matvec,
    _scaled_norm,
    _series,
)

__all__ = [
    "EV_CROSSING",
    "EV_GRAZING",
    "EV_NONE",
    "EV_NONFINITE",
    "EV_START",
    "EV_STEP_LIMIT",
    "K_DEFAULT",
    "THETA_DEFAULT",
    "CrossingResult",
    "FlowTables",
    "LTIModeData",
    "advance",
    "first_crossing",
    "flow_eval",
    "flow_to",
    "lti_flow",
    "prepare_lti_mode",
]



# ----------------------------------------------------------------------------------------
# Python-side precomputation
# ----------------------------------------------------------------------------------------
class LTIModeData(NamedTuple):
    """Precomputed arrays of one LTI mode and its guards (the kernels' inputs).

    Attributes
    ----------
    h : float
        Step length (time units), ``||D^-1 Abar D||_inf h = theta``.
    Phi : ndarray, shape (N1, N1)
        ``expm(Abar h)`` (Taylor sum to order K); last row exactly ``[0, ..., 0, 1]``.
    Ah : ndarray, shape (N1, N1)
        ``Abar h``.
    dinv : ndarray, shape (N1,)
        ``1 / D`` (powers of two) for the truncation bound.
    trunc : float
        ``theta^(K+1) e^theta / (K+1)!``.
    G : ndarray, shape (ng, K+1, N1)
        ``G[i, k] = fhat_i (Abar h)^k / k!`` with ``fhat_i = -direction_i [c_i, d_i]``.
    gabs : ndarray, shape (ng, K+1, N1)
        ``|fhat_i| |Abar h|^k / k!`` (for rounding bounds).
    gsum : ndarray, shape (ng, N1)
        ``gabs.sum(axis=1)``.
    cnorm : ndarray, shape (ng,)
        ``||fhat_i D||_1``.
    prio : ndarray of int64, shape (ng,)
        Guard priorities (larger wins a tie).
    """

    h: float
    Phi: np.ndarray
    Ah: np.ndarray
    dinv: np.ndarray
    trunc: float
    G: np.ndarray
    gabs: np.ndarray
    gsum: np.ndarray
    cnorm: np.ndarray
    prio: np.ndarray

    def flow_tables(self) -> FlowTables:
        """The tables :func:`advance` reads, with every guard in use."""
        return FlowTables(*self, ng=self.G.shape[0])


class FlowTables(NamedTuple):
    """The tables of one mode that :func:`advance` reads by name: the fields of
    :class:`LTIModeData` and ``ng``, the number of guards in use (the first ``ng`` rows of
    ``G``, ``gabs``, ``gsum``, ``cnorm``, ``prio``; tables padded to more guards than a
    mode has share one shape across modes)."""

    h: float
    Phi: np.ndarray
    Ah: np.ndarray
    dinv: np.ndarray
    trunc: float
    G: np.ndarray
    gabs: np.ndarray
    gsum: np.ndarray
    cnorm: np.ndarray
    prio: np.ndarray
    ng: int


def _as_matrix(name, A):
    A = np.asarray(A, dtype=float)
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise ValueError(f"{name} must be a square 2-D array, got shape {A.shape}")
    if not np.all(np.isfinite(A)):
        raise ValueError(f"{name} must be finite")
    return A


def _as_vector(name, v, n):
    v = np.asarray(v, dtype=float)
    if v.ndim == 0 and n == 1:
        v = v.reshape(1)
    if v.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},), got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name} must be finite")
    return v


def _balance(A, b):
    """Power-of-two diagonal ``D`` (length n+1) that balances ``Abar`` (rows vs columns)."""
    n = A.shape[0]
    D = np.ones(n + 1)
    if n and np.any(A):
        from scipy.linalg import matrix_balance

        # entries at the rounding level of the largest (residues of a projection, zero in
        # exact arithmetic, as in a sticking mode) would have the balancing scale a state by
        # up to 2^32, and the truncation bound of every guard reading it grow with it
        As = np.where(np.abs(A) > 64.0 * _EPS * float(np.abs(A).max()), A, 0.0)
        _, (scale, _) = matrix_balance(As, permute=False, separate=True)
        D[:n] = scale
    bh = b / D[:n] if n else b
    Ahat = A * D[None, :n] / D[:n, None] if n else A
    nrm_a = float(np.max(np.sum(np.abs(Ahat), axis=1))) if n else 0.0
    nb = float(np.max(np.abs(bh))) if n else 0.0
    if nb > 0.0:
        # Scale the homogeneous coordinate so that the constant input does not dominate the
        # norm (and hence the step): results are invariant to the units of b.
        ref = nrm_a if nrm_a > 0.0 else 1.0
        ex = int(np.clip(np.round(np.log2(nb / ref)), -300, 300))
        D[n] = 2.0 ** (-ex)
    return D


def prepare_lti_mode(A, b=None, guards: Sequence = (), K: int = K_DEFAULT,
                     theta: float = THETA_DEFAULT, priorities=None) -> LTIModeData:
    """Precompute the step, transition matrix and guard Taylor matrices of one LTI mode.

    Parameters
    ----------
    A : array_like, shape (n, n)
        Flow matrix of ``z' = A z + b``.
    b : array_like, shape (n,), optional
        Constant input (default zero).
    guards : sequence of (c, d, direction)
        Affine guards ``g(z) = c . z + d`` (``c`` shape ``(n,)``); ``direction = -1`` fires when
        ``g`` passes from ``> 0`` to ``<= 0``, ``+1`` when it passes from ``< 0`` to ``>= 0``.
    K : int
        Taylor order (default 20; the tail is then ~1e-19 relative).
    theta : float
        Normalised step ``||D^-1 Abar D|| h`` (default 1; must be in ``(0, 2]``).
    priorities : sequence of int, optional
        Guard priorities (default 0).

    Returns
    -------
    LTIModeData

    Examples
    --------
    >>> import numpy as np
    >>> md = prepare_lti_mode([[0.0, 1.0], [-1.0, 0.0]], guards=[([1.0, 0.0], 0.0, -1)])
    >>> md.G.shape, round(md.h, 3)
    ((1, 21, 3), 1.0)
    """
    A = _as_matrix("A", A)
    n = A.shape[0]
    if n == 0:
        raise ValueError("A must have at least one state")
    b = np.zeros(n) if b is None else _as_vector("b", b, n)
    K = int(K)
    if not 4 <= K <= 40:
        raise ValueError(f"K must be in [4, 40], got {K}")
    theta = float(theta)
    if not (0.0 < theta <= 2.0):
        raise ValueError(f"theta must be in (0, 2], got {theta}")
    N1 = n + 1
    Abar = np.zeros((N1, N1))
    Abar[:n, :n] = A
    Abar[:n, n] = b
    D = _balance(A, b)
    Ahat = Abar * D[None, :] / D[:, None]
    nrm = float(np.max(np.sum(np.abs(Ahat), axis=1)))
    # Abar = 0 (a frozen state) is exact over any step
    h = min(theta / nrm, 1e12) if nrm > 0.0 else 1e12
    th = nrm * h
    trunc = th ** (K + 1) / math.factorial(K + 1) * math.exp(th)
    Ah = Abar * h
    Phi = np.eye(N1)
    term = np.eye(N1)
    for k in range(1, K + 1):
        term = term @ Ah / k
        Phi = Phi + term
    Phi[n, :] = 0.0
    Phi[n, n] = 1.0
    ng = len(guards)
    G = np.zeros((ng, K + 1, N1))
    gabs = np.zeros((ng, K + 1, N1))
    cnorm = np.zeros(ng)
    absAh = np.abs(Ah)
    for i, gd in enumerate(guards):
        try:
            c, d, direction = gd
        except (TypeError, ValueError):
            raise ValueError(f"guards[{i}] must be a (c, d, direction) triple") from None
        c = _as_vector(f"guards[{i}].c", c, n)
        d = float(d)
        if not math.isfinite(d):
            raise ValueError(f"guards[{i}].d must be finite")
        if direction not in (-1, 1):
            raise ValueError(f"guards[{i}].direction must be -1 or +1, got {direction!r}")
        fh = -float(direction) * np.concatenate([c, [d]])
        G[i, 0] = fh
        gabs[i, 0] = np.abs(fh)
        for k in range(1, K + 1):
            G[i, k] = G[i, k - 1] @ Ah / k
            gabs[i, k] = gabs[i, k - 1] @ absAh / k
        cnorm[i] = float(np.sum(np.abs(fh * D)))
    prio = np.zeros(ng, dtype=np.int64)
    if priorities is not None:
        prio[:] = np.asarray(priorities, dtype=np.int64)
    return LTIModeData(h=float(h), Phi=np.ascontiguousarray(Phi), Ah=np.ascontiguousarray(Ah),
                       dinv=1.0 / D, trunc=float(trunc), G=G, gabs=gabs,
                       gsum=np.ascontiguousarray(gabs.sum(axis=1)), cnorm=cnorm, prio=prio)


# ----------------------------------------------------------------------------------------
# numba kernels
# ----------------------------------------------------------------------------------------
@njit(cache=True)
def advance(w0, t0, t_end, ft, hot, hot_tol, max_steps, w_out):
    """Flow to the first guard event or ``t_end``; see the module docstring for the contract."""
    h, Phi, Ah, dinv, trunc, ng = ft.h, ft.Phi, ft.Ah, ft.dinv, ft.trunc, ft.ng
    G, gabs, gsum, cnorm, prio = ft.G, ft.gabs, ft.gsum, ft.cnorm, ft.prio
    N1 = w0.shape[0]
    Kp1 = G.shape[1]
    c1 = Kp1 * (N1 + 2) * _EPS          # coefficient rounding (G and the mat-vec)
    ch = (2 * Kp1 + 2) * _EPS           # Horner rounding
    w = np.empty(N1)
    wa = np.empty(N1)
    tmp = np.empty(N1)
    term = np.empty(N1)
    p = np.empty(Kp1)
    e = np.empty(Kp1)
    q = np.empty(Kp1)
    sa = np.empty(_STACK)
    sb = np.empty(_STACK)
    ngm = max(ng, 1)
    defl = np.zeros(ngm, np.int64)
    for i in range(N1):
        w[i] = w0[i]
        w_out[i] = w0[i]
    if not (t0 < t_end):
        return EV_NONE, t0, -1, 0, 0.0
    wn = _scaled_norm(w, dinv)
    if not math.isfinite(wn):
        return EV_NONFINITE, t0, -1, 0, 0.0
    for i in range(N1):
        wa[i] = abs(w[i])

    # ---- where does each guard stand at t0?
    sg = -1
    serr = 0.0
    for g in range(ng):
        Gg = G[g]
        Ga = gabs[g]
        # O(N1) pre-test: sum_k e_k <= (c1 + ch) gsum.|w|, so a guard whose value is beyond
        # that bound is decided without its Taylor coefficients (the same decision)
        p0 = 0.0
        sg_abs = 0.0
        for j in range(N1):
            p0 += Gg[0, j] * w[j]
            sg_abs += gsum[g, j] * wa[j]
        tol_hi = 4.0 * ((c1 + ch) * sg_abs + cnorm[g] * wn * trunc)
        if g == hot:
            tol_hi += hot_tol
        if math.isfinite(tol_hi) and p0 > 2.0 * tol_hi:
            continue
        etot = 0.0
        for k in range(Kp1):
            s = 0.0
            sab = 0.0
            for j in range(N1):
                s += Gg[k, j] * w[j]
                sab += Ga[k, j] * wa[j]
            p[k] = s
            e[k] = c1 * sab + ch * abs(s)
            etot += e[k]
        tol_on = 4.0 * (etot + cnorm[g] * wn * trunc)
        if not math.isfinite(tol_on):
            return EV_NONFINITE, t0, -1, 0, 0.0
        if g == hot:
            tol_on += hot_tol
        start = False
        if abs(p[0]) <= tol_on:
            lead = -1
            for k in range(1, Kp1):
                thr = 2.0 * e[k]
                if k + 1 < Kp1:
                    # the event time is known to ~1 ulp of u: p_k moves by ~(k+1) p_{k+1} ulp
                    thr += 8.0 * _EPS * (k + 1) * abs(p[k + 1])
                if abs(p[k]) > thr:
                    lead = k
                    break
            if lead < 0:
                defl[g] = -1
            elif p[lead] < 0.0:
                start = True
            else:
                defl[g] = lead
        elif p[0] < 0.0:
            start = True
        if start and (sg < 0 or prio[g] > prio[sg]):
            sg = g
            serr = tol_on
    if sg >= 0:
        return EV_START, t0, sg, 0, serr

    # ---- stepping
    k = 0
    while True:
        if k >= max_steps:
            for i in range(N1):
                w_out[i] = w[i]
            return EV_STEP_LIMIT, t0 + k * h, -1, k, 0.0
        ts = t0 + k * h
        u_end = (t_end - ts) / h
        u_end = max(u_end, 0.0)         # t0 + k h rounded past t_end
        last = u_end <= 1.0
        u_hi = u_end if last else 1.0
        dmin = 4.0 * _EPS * (1.0 + abs(ts) / h)
        tie = 4.0 * dmin
        wn = _scaled_norm(w, dinv)
        if not math.isfinite(wn):
            for i in range(N1):
                w_out[i] = w[i]
            return EV_NONFINITE, ts, -1, k, 0.0
        for i in range(N1):
            wa[i] = abs(w[i])
        best_u = np.inf
        best_g = -1
        best_kind = EV_NONE
        best_err = 0.0
        for g in range(ng):
            sh = defl[g]
            if sh < 0:
                continue
            if k > 0:
                sh = 0
            m = Kp1 - sh
            Gg = G[g]
            if sh == 0:
                # O(N1) pre-test: |p_k| <= gabs_k.|w|, so p_0 - (gsum - gabs_0).|w| bounds the
                # guard on the whole step; well above the error bound the step is excluded
                # exactly as the full test below would exclude it
                p0 = 0.0
                s0 = 0.0
                s1 = 0.0
                Ga0 = gabs[g, 0]
                gs = gsum[g]
                for j in range(N1):
                    p0 += Gg[0, j] * w[j]
                    s0 += Ga0[j] * wa[j]
                    s1 += gs[j] * wa[j]
                bound = 2.0 * ((c1 + ch) * s1 + cnorm[g] * wn * trunc)
                if math.isfinite(bound) and p0 - (s1 - s0) > bound:
                    continue
            sabs_p = 0.0
            for kk in range(m):
                s = 0.0
                for j in range(N1):
                    s += Gg[kk + sh, j] * w[j]
                p[kk] = s
                sabs_p += abs(s)
            s = 0.0
            gs = gsum[g]
            for j in range(N1):
                s += gs[j] * wa[j]
            tail = cnorm[g] * wn * trunc
            eps_g = c1 * s + ch * sabs_p + tail
            if not math.isfinite(eps_g):
                # about to overflow: the bounds are meaningless, report it rather than guess
                for i in range(N1):
                    w_out[i] = w[i]
                return EV_NONFINITE, ts, -1, k, 0.0
            u_lim = u_hi
            if best_g >= 0 and best_u + tie < u_lim:
                u_lim = best_u + tie
            # cheap whole-interval exclusion
            L = p[0]
            up = 1.0
            for kk in range(1, m):
                up *= u_lim
                if p[kk] < 0.0:
                    L += p[kk] * up
            if L > eps_g:
                continue
            Ga = gabs[g]
            for kk in range(m):
                s = 0.0
                for j in range(N1):
                    s += Ga[kk + sh, j] * wa[j]
                e[kk] = c1 * s + ch * abs(p[kk])
            st, u = _first_root(p, e, m, u_lim, dmin, tail, sa, sb)
            if st == 0:
                continue
            kind = EV_CROSSING
            if st == 2:
                vmax = (u_end - u) if last else (1.0 + _OVERSHOOT - u)
                kind, u = _classify(p, e, m, u, vmax, tail, q)
                if u > u_hi:
                    # beyond this step (or t_end): the next step rediscovers it
                    continue
            if (best_g < 0 or u < best_u - tie
                    or (abs(u - best_u) <= tie and prio[g] > prio[best_g])):
                best_u = u
                best_g = g
                best_kind = kind
                best_err = eps_g
        if best_g >= 0:
            _series(w, Ah, Kp1, best_u, w_out, term, tmp)
            t_ev = ts + best_u * h
            t_ev = min(t_ev, t_end)
            return best_kind, t_ev, best_g, k + 1, best_err
        if last:
            _series(w, Ah, Kp1, u_end, w_out, term, tmp)
            return EV_NONE, t_end, -1, k + 1, 0.0
        _matvec(Phi, w, tmp)
        for i in range(N1):
            w[i] = tmp[i]
        w[N1 - 1] = 1.0
        k += 1


@njit(cache=True)
def flow_to(w0, tau, h, Phi, Ah, Kp1, out):
    """State at offset ``tau >= 0`` from ``w0`` (same stepping as :func:`advance`)."""
    N1 = w0.shape[0]
    w = w0.copy()
    tmp = np.empty(N1)
    term = np.empty(N1)
    nst = math.floor(tau / h) if tau > 0.0 else 0
    if nst > 0 and tau - nst * h < 0.0:
        nst -= 1
    for _ in range(nst):
        _matvec(Phi, w, tmp)
        for i in range(N1):
            w[i] = tmp[i]
        w[N1 - 1] = 1.0
    u = (tau - nst * h) / h
    _series(w, Ah, Kp1, u, out, term, tmp)


@njit(cache=True)
def flow_eval(w0, h, Phi, Ah, Kp1, taus, out):
    """States at the sorted offsets ``taus`` (``>= 0``) from ``w0`` into ``out[i, :]``."""
    N1 = w0.shape[0]
    w = w0.copy()
    tmp = np.empty(N1)
    term = np.empty(N1)
    row = np.empty(N1)
    kcur = 0
    for i in range(taus.shape[0]):
        tau = taus[i]
        kk = math.floor(tau / h) if tau > 0.0 else 0
        if kk > 0 and tau - kk * h < 0.0:
            kk -= 1
        while kcur < kk:
            _matvec(Phi, w, tmp)
            for j in range(N1):
                w[j] = tmp[j]
            w[N1 - 1] = 1.0
            kcur += 1
        u = (tau - kcur * h) / h
        _series(w, Ah, Kp1, u, row, term, tmp)
        for j in range(N1):
            out[i, j] = row[j]


# ----------------------------------------------------------------------------------------
# Python API
# ----------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)  # array field: identity semantics
class CrossingResult:
    """Result of :func:`first_crossing`.

    Attributes
    ----------
    time : float or None
        Time of the first event (same units as ``t_max``), ``None`` if there is none in
        ``[0, t_max]``.
    kind : {'crossing', 'grazing', 'none'}
        ``'crossing'``: ``g`` reaches the forbidden side (the first floating-point time at
        which the computed guard value is on it); ``'grazing'``: a tangential touch within the
        rounding bound, reported at the local extremum; ``'none'``: no event.
    state : ndarray, shape (n,)
        State at ``time`` (or at ``t_max`` when ``kind == 'none'``).
    error_bound : float
        Rigorous bound on the rounding/truncation error of the guard value at the event
        (0 when there is none).
    """

    time: float | None
    kind: str
    state: np.ndarray
    error_bound: float = 0.0
    __repr__ = compact_repr


def first_crossing(A, c, d, z0, t_max, b=None, direction=-1, max_steps=10_000_000,
                   K=K_DEFAULT) -> CrossingResult:
    """First time the flow ``z' = A z + b`` from ``z0`` reaches the guard ``c·z + d``.

    Parameters
    ----------
    A : array_like, shape (n, n)
    c : array_like, shape (n,)
    d : float
    z0 : array_like, shape (n,)
        State at time 0.
    t_max : float
        Horizon (``> 0``).
    b : array_like, shape (n,), optional
        Constant input.
    direction : {-1, +1}
        ``-1``: event when ``g`` passes from ``> 0`` to ``<= 0`` (admissible side ``g > 0``);
        ``+1``: from ``< 0`` to ``>= 0``.
    max_steps : int
        Bound on the number of flow steps (``RuntimeError`` beyond).
    K : int
        Taylor order.

    Returns
    -------
    CrossingResult

    Notes
    -----
    Guaranteed not to miss a crossing in ``(0, t_max]`` (see the module docstring). If ``z0``
    is on the guard (within rounding), the first non-zero derivative decides: positive means
    the flow leaves the guard and nothing fires at ``t = 0``; negative (or ``z0`` strictly on
    the forbidden side) gives a crossing at ``t = 0``.

    Examples
    --------
    Free fall from height 1 with unit upward speed hits ``x = 0`` at ``(1 + sqrt(1 + 2 g)) / g``:

    >>> import numpy as np
    >>> g = 9.81
    >>> res = first_crossing([[0, 1], [0, 0]], [1, 0], 0.0, [1.0, 1.0], 5.0, b=[0, -g])
    >>> res.kind, bool(abs(res.time - (1 + np.sqrt(1 + 2 * g)) / g) < 1e-14)
    ('crossing', True)

    A harmonic oscillator whose maximum is just below the guard never fires:

    >>> first_crossing([[0, 1], [-1, 0]], [-1, 0], 1 - 1e-9, [0.0, 1 - 2e-9], 10.0).kind
    'none'
    """
    A = _as_matrix("A", A)
    n = A.shape[0]
    z0 = _as_vector("z0", z0, n)
    t_max = float(t_max)
    if not (math.isfinite(t_max) and t_max > 0.0):
        raise ValueError(f"t_max must be finite and > 0, got {t_max}")
    md = prepare_lti_mode(A, b, [(c, d, direction)], K=K)
    w0 = np.append(z0, 1.0)
    w_out = np.empty(n + 1)
    code, t, _, _, err = advance(w0, 0.0, t_max, md.flow_tables(), -1, 0.0, int(max_steps),
                                 w_out)
    if code == EV_NONFINITE:
        raise FloatingPointError(f"the flow overflowed before t = {t:g}")
    if code == EV_STEP_LIMIT:
        raise RuntimeError(f"max_steps={max_steps} flow steps reached at t = {t:g}")
    if code == EV_NONE:
        return CrossingResult(None, "none", w_out[:n].copy(), 0.0)
    kind = "grazing" if code == EV_GRAZING else "crossing"
    return CrossingResult(float(t), kind, w_out[:n].copy(), float(err))


def lti_flow(A, z0, times, b=None, t0=0.0) -> np.ndarray:
    """Exact states of ``z' = A z + b`` from ``z(t0) = z0`` at the given times.

    Parameters
    ----------
    A : array_like, shape (n, n)
    z0 : array_like, shape (n,)
    times : array_like, shape (m,) or scalar
        Times ``>= t0`` (any order).
    b : array_like, shape (n,), optional
    t0 : float

    Returns
    -------
    ndarray, shape (m, n) (or (n,) for a scalar time)

    Examples
    --------
    >>> import numpy as np
    >>> x = lti_flow([[0, 1], [-1, 0]], [1.0, 0.0], [np.pi / 2, np.pi])
    >>> np.allclose(x, [[0, -1], [-1, 0]], atol=1e-14)
    True
    """
    A = _as_matrix("A", A)
    n = A.shape[0]
    z0 = _as_vector("z0", z0, n)
    t0 = float(t0)
    ts = np.asarray(times, dtype=float)
    scalar = ts.ndim == 0
    ts = np.atleast_1d(ts)
    if ts.ndim != 1 or not np.all(np.isfinite(ts)):
        raise ValueError("times must be a finite scalar or 1-D array")
    if not math.isfinite(t0):
        raise ValueError("t0 must be finite")
    if np.any(ts < t0):
        raise ValueError("times must be >= t0")
    md = prepare_lti_mode(A, b)
    order = np.argsort(ts, kind="stable")
    out = np.empty((ts.size, n + 1))
    flow_eval(np.append(z0, 1.0), md.h, md.Phi, md.Ah, md.G.shape[1],
              np.ascontiguousarray(ts[order] - t0), out)
    res = np.empty((ts.size, n))
    res[order] = out[:, :n]
    return res[0] if scalar else res
