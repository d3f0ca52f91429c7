r"""Simultaneous impacts: Newton's law for several contacts at once, as an LCP.

When several rigid contacts are active at one instant (the one that fires, the others on
their bounds or closing onto them within the event tolerance, and every held contact), the
impulses are found together. With the oriented normals ``W`` (rows ``-wall_i w_i``, so that
``u = W v`` is each contact's *separating* velocity) and the pre-impact velocities ``u^-``:

.. math::  u^+ = u^- + A \lambda, \qquad A = W M^{-1} W^T,

.. math::  0 \le \lambda \;\perp\; u^+ - b \ge 0, \qquad b_i = e_i \max(-u^-_i, 0),

a linear complementarity problem (LCP): a contact pushes (``lambda_i > 0``) only if it leaves
with exactly the restitution velocity ``e_i |u^-_i|`` (zero for a held or touching contact),
and one that does not push leaves at least that fast. The impulses act through ``M^-1``:
``v^+ = v^- + M^-1 W^T lambda``. For one contact this is the single-contact law of
:mod:`hybridpd.mechanics.contacts`. When the normals are independent ``A`` is positive
definite and the solution is unique, and the generalised momentum changes only along the
contact normals (it is conserved along every free direction). Only contacts that are
closing or touching take part (a separating contact is not active); on such sets the
kinetic energy did not increase in any of 6000 random cases (random ``M``, normals,
restitutions, equal or not), which the tests recheck; for ``e = 0`` it is a projection and
dissipative by construction.

Known limit: the outcome is discontinuous near simultaneity. Two impacts ``1e-9`` apart in
time are sequential (each the single-contact law), two within the tolerance are joint; on
coupled contacts the two answers differ (three equal masses, middle one moving, ``e = 0.5``:
joint ``v = [0.5, 0, 0.5]``, sequential a cascade of single impacts).

:func:`solve_lcp` solves small LCPs exactly by principal pivoting (Murty's least-index
rule, finite for positive definite ``A``), with enumeration of the active sets as a fallback
for small degenerate problems; every answer is verified by the complementarity conditions.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from hybridpd._results import compact_repr

__all__ = ["Cascade", "MultiImpact", "impact_cascade", "multi_impact", "solve_lcp"]


def _check(A, q, z, tol):
    y = A @ z + q
    return bool(np.all(z >= -tol) and np.all(y >= -tol) and abs(float(z @ y)) <= tol * (
        1.0 + float(np.abs(z).sum())))


def _solve_set(A, q, J, n):
    z = np.zeros(n)
    if J:
        AJ = A[np.ix_(J, J)]
        if np.linalg.cond(AJ) > 1e12:
            return None
        z[J] = np.linalg.solve(AJ, -q[J])
    return z


def solve_lcp(A, q, tol: float | None = None) -> np.ndarray | None:
    """Solve ``z >= 0, A z + q >= 0, z . (A z + q) = 0`` for small ``A``.

    Parameters
    ----------
    A : array_like, shape (k, k)
        Positive definite for a unique solution (``W M^-1 W^T`` with independent ``W``).
    q : array_like, shape (k,)
    tol : float, optional
        Complementarity tolerance (default ``1e-11 max|q| (1 + max|A|)``: relative to ``q``,
        since the solution scales with it; an absolute floor would accept ``z = 0`` for
        every small ``q``, e.g. the impact of contacts closing at 1e-12, and leave them
        closing).

    Returns
    -------
    ndarray, shape (k,) or None
        ``z``, verified by the complementarity conditions, or ``None`` when no solution was
        found (no solution, or a degenerate problem: singular principal blocks).

    Examples
    --------
    >>> import numpy as np
    >>> z = solve_lcp([[2.0, 1.0], [1.0, 2.0]], [-1.5, -1.5])
    >>> np.allclose(z, [0.5, 0.5])
    True
    """
    A = np.asarray(A, dtype=float)
    q = np.asarray(q, dtype=float)
    k = q.shape[0]
    if A.shape != (k, k):
        raise ValueError(f"A must have shape ({k}, {k}), got {A.shape}")
    if tol is None:
        tol = 1e-11 * float(np.abs(q).max(initial=0.0)) * (
            1.0 + float(np.abs(A).max(initial=0.0)))
    if k == 0:
        return np.zeros(0)
    # Murty's principal pivoting, least-index rule
    inJ = np.zeros(k, bool)
    for _ in range(min(1000, 4 * 2 ** min(k, 20))):
        z = _solve_set(A, q, list(np.flatnonzero(inJ)), k)
        if z is None:
            break
        y = A @ z + q
        bad = [i for i in range(k) if (inJ[i] and z[i] < -tol) or (not inJ[i] and y[i] < -tol)]
        if not bad:
            z[~inJ] = 0.0
            return z if _check(A, q, np.maximum(z, 0.0), 10 * tol) else None
        inJ[bad[0]] = not inJ[bad[0]]
    if k > 12:
        return None
    for r in range(k + 1):
        for J in itertools.combinations(range(k), r):
            z = _solve_set(A, q, list(J), k)
            if z is not None and _check(A, q, z, tol):
                return np.maximum(z, 0.0)
    return None


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class MultiImpact:
    """Outcome of :func:`multi_impact`.

    Attributes
    ----------
    v : ndarray, shape (n,)
        Post-impact generalised velocities.
    impulses : ndarray, shape (k,)
        ``lambda >= 0`` per contact (generalised-force impulse along its oriented normal).
    u_pre, u_post : ndarray, shape (k,)
        Separating normal velocities before and after.
    """

    v: np.ndarray
    impulses: np.ndarray
    u_pre: np.ndarray
    u_post: np.ndarray
    __repr__ = compact_repr


def multi_impact(Minv, W, v, restitution, held=None) -> MultiImpact | None:
    """Newton's law for ``k`` contacts at once (module docstring).

    Parameters
    ----------
    Minv : array_like, shape (n, n)
        Inverse mass matrix.
    W : array_like, shape (k, n)
        Oriented normals: ``W v`` is each contact's separating velocity (``-wall w`` for a
        contact at ``wall``).
    v : array_like, shape (n,)
        Pre-impact velocities.
    restitution : array_like, shape (k,)
        ``e_i`` in ``[0, 1]``.
    held : array_like of bool, shape (k,), optional
        Held (sticking) contacts: their target velocity is 0.

    Returns
    -------
    MultiImpact or None
        ``None`` when the LCP has no (non-degenerate) solution.

    Examples
    --------
    Three equal masses, the middle one moving at 1 onto both neighbours' clearances:

    >>> import numpy as np
    >>> W = np.array([[1.0, -1.0, 0.0], [0.0, -1.0, 1.0]])
    >>> out = multi_impact(np.eye(3), W, [0.0, 1.0, 0.0], [0.5, 0.5])
    >>> np.round(out.v, 12)
    array([0.5, 0. , 0.5])
    """
    Minv = np.asarray(Minv, dtype=float)
    W = np.atleast_2d(np.asarray(W, dtype=float))
    v = np.asarray(v, dtype=float)
    e = np.asarray(restitution, dtype=float).reshape(-1)
    held = np.zeros(W.shape[0], bool) if held is None else np.asarray(held, bool)
    u = W @ v
    b = np.where(held, 0.0, e * np.maximum(-u, 0.0))
    A = W @ Minv @ W.T
    lam = solve_lcp(A, u - b)
    if lam is None:
        return None
    v1 = v + Minv @ (W.T @ lam)
    return MultiImpact(v=v1, impulses=lam, u_pre=u, u_post=W @ v1)


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class Cascade:
    """Outcome of :func:`impact_cascade`.

    Attributes
    ----------
    v : ndarray, shape (n,)
        Velocities after the cascade.
    hits : tuple of int
        The contact (row of ``W``) of every impact, in order.
    accumulated : bool
        The impacts accumulated (the closing speeds fell below ``rtol`` of the first, or the
        impact bound was reached) and the cascade ended in its plastic limit: every contact
        still being hit then leaves at zero relative velocity.
    held : ndarray of bool, shape (k,)
        Contacts at zero relative velocity at the end that were held, or that the plastic
        limit stopped.
    u_post : ndarray, shape (k,)
        Separating velocities at the end (all ``>= 0`` to rounding).
    """

    v: np.ndarray
    hits: tuple
    accumulated: bool
    held: np.ndarray
    u_post: np.ndarray
    __repr__ = compact_repr


def impact_cascade(Minv, W, v, restitution, held=None, rtol: float = 1e-12,
                   max_impacts: int = 1000) -> Cascade | None:
    """The impacts of ``k`` contacts in one configuration, one at a time, to the end.

    The most closing contact takes Newton's law together with the held ones (held contacts
    push with target velocity 0, :func:`multi_impact`; a held one set moving apart is held
    no longer), then the next most closing one, and so on, positions fixed: the sequential
    model of impacts that follow each other in no time. It ends when no contact closes
    (``u >= -rtol`` times the first closing speed), or, when the closing speeds shrink
    geometrically (impacts accumulating between coupled contacts) below ``rtol`` of the
    first one or after ``max_impacts`` impacts, in the limit of the accumulation: the
    plastic joint impact of the held contacts and every contact hit in the last round
    (each contact hit once more after the slowest), whose relative velocities vanish.

    Parameters
    ----------
    Minv : array_like, shape (n, n)
    W : array_like, shape (k, n)
        Oriented normals (rows ``-wall w``): ``W v`` are the separating velocities.
    v : array_like, shape (n,)
    restitution : array_like, shape (k,)
    held : array_like of bool, shape (k,), optional
    rtol : float
        Closing speeds below ``rtol`` times the first are zero.
    max_impacts : int
        Bound on the impacts resolved one by one.

    Returns
    -------
    Cascade or None
        ``None`` when one of the impacts has no LCP solution.

    Examples
    --------
    Three unit masses in a row, both clearances closed, the first moving at 1 onto the
    others: with ``e = 1`` the cascade ends after two impacts (Newton's cradle); with
    ``e = 0`` the impacts alternate and accumulate, and in the limit the three move
    together with the momentum of the first:

    >>> import numpy as np
    >>> W = np.array([[-1.0, 1.0, 0.0], [0.0, -1.0, 1.0]])
    >>> out = impact_cascade(np.eye(3), W, [1.0, 0.0, 0.0], [1.0, 1.0])
    >>> out.hits, out.accumulated, np.round(out.v, 12)
    ((0, 1), False, array([0., 0., 1.]))
    >>> out = impact_cascade(np.eye(3), W, [1.0, 0.0, 0.0], [0.0, 0.0])
    >>> out.accumulated, np.round(out.v, 12)
    (True, array([0.33333333, 0.33333333, 0.33333333]))
    """
    Minv = np.asarray(Minv, dtype=float)
    W = np.atleast_2d(np.asarray(W, dtype=float))
    v = np.array(v, dtype=float)
    e = np.asarray(restitution, dtype=float).reshape(-1)
    k = W.shape[0]
    held = np.zeros(k, bool) if held is None else np.array(held, bool)
    u = W @ v
    first = float(np.max(-u, initial=0.0))
    tol = rtol * first
    hits = []
    limit = True                 # no break: the bound on the impacts was reached
    for _ in range(int(max_impacts)):
        u = W @ v
        closing = np.where(held, np.inf, u)
        i = int(np.argmin(closing))
        if not closing[i] < -tol:
            limit = False        # nothing closes any more
            break
        J = np.flatnonzero(held).tolist() + [i]
        out = multi_impact(Minv, W[J], v, np.append(np.zeros(len(J) - 1), e[i]),
                           np.append(np.ones(len(J) - 1, bool), False))
        if out is None:
            return None
        v = out.v
        hits.append(i)
        u = W @ v
        held[J[:-1]] = u[J[:-1]] <= tol
        if -float(out.u_pre[-1]) < tol:
            break                # the impacts accumulated
    # the last round: each contact hit once more after the slowest
    last = len(hits) - 1
    seen = set()
    while last >= 0 and hits[last] not in seen:
        seen.add(hits[last])
        last -= 1
    u = W @ v
    rnd = sorted(seen)
    # a cascade that repeats contacts and leaves them at rest (to 1e-9) accumulated as well
    again = len(hits) > len(set(hits)) and bool(np.all(np.abs(u[rnd]) <= 1e-9 * first))
    if not (limit or again):
        return Cascade(v, tuple(hits), False, held | (np.abs(u) <= tol), u)
    J = sorted(set(np.flatnonzero(held).tolist()) | seen)
    out = multi_impact(Minv, W[J], v, np.zeros(len(J)), held[J])
    if out is None:
        return None
    v = out.v
    u = W @ v
    held = held.copy()
    held[J] = np.abs(u[J]) <= max(tol, 1e-12 * float(np.abs(out.u_pre).max(initial=0.0)))
    return Cascade(v, tuple(hits), True, held, u)
