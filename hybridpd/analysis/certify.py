"""The one early-exit certification of the basin mappers (:mod:`hybridpd.analysis.mappers`).

For a stable fixed point ``s*`` of a map with Jacobian ``DP`` (spectral radius ``rho < 1``),
``Q`` solving the Lyapunov equation of ``DP / rho_t`` (``rho_t = (1 + rho) / 2``) defines a
norm in which the map contracts by about ``rho_t``. :func:`certify_ball` searches the largest
``Q``-ball (starting from the one whose image under the criterion's coordinates ``C`` lies in
half the criterion ball) whose sampled images, on nested spheres, fall inside
``kappa = (1 + rho_t) / 2`` of its radius, and returns 0.9 of that radius: an iterate inside
it stays inside and satisfies the criterion. The certification is numerical (sampled), not
interval-rigorous.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["certify_ball"]


def certify_ball(DP, fixed_point, criterion: float, images, wrap, *, C=None,
                 n_dirs: int | None = None, seed: int = 12345) -> tuple:
    """``(Q, r2)`` of the certified ball ``{d : d^T Q d < r2}`` around ``fixed_point``.

    Parameters
    ----------
    DP : ndarray, shape (dim, dim) or None
        Jacobian of the map at the fixed point (None or non-finite: no ball).
    fixed_point : ndarray, shape (dim,)
    criterion : float
        Bound on ``|C d|^2`` (squared distance in the criterion's coordinates).
    images : callable
        ``images(points) -> (images, ok)`` for points of shape ``(N, dim)``.
    wrap : callable
        Differences of section points with the phase wrapped.
    C : ndarray, shape (m, dim), optional
        Criterion coordinates of a deviation (default: the identity).
    n_dirs : int, optional
        Sampled directions (default ``100 + 25 dim``).
    seed : int
        Seed of the directions (the certification is reproducible).

    Returns
    -------
    Q : ndarray, shape (dim, dim)
    r2 : float
        Squared radius; 0 (with ``Q = I``) when nothing is certified.
    """
    fp = np.asarray(fixed_point, float)
    dim = fp.size
    none = (np.eye(dim), 0.0)
    if DP is None or not np.all(np.isfinite(DP)):
        return none
    rho = float(np.max(np.abs(np.linalg.eigvals(DP))))
    if not rho < 0.999:
        return none
    from scipy.linalg import solve_discrete_lyapunov

    rho_t = 0.5 * (1.0 + rho)
    kappa = 0.5 * (1.0 + rho_t)
    Q = solve_discrete_lyapunov((DP / rho_t).T, np.eye(dim))
    Q = 0.5 * (Q + Q.T)
    C = np.eye(dim) if C is None else np.asarray(C, float)
    Li = np.linalg.cholesky(np.linalg.inv(Q))
    lam = np.linalg.eigvalsh(Li.T @ C.T @ C @ Li).max()
    r = math.sqrt(criterion / lam) * 0.5
    Lq_inv_T = np.linalg.inv(np.linalg.cholesky(Q).T)   # |Lq^T d| is the Q-norm
    dirs = np.random.default_rng(seed).normal(size=(n_dirs or 100 + 25 * dim, dim))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)

    def contracts(rows, r):
        for frac in (1.0, 0.5, 0.25, 0.1):
            img, good = images(fp + (r * frac) * rows @ Lq_inv_T.T)
            if not np.all(good):
                return False
            dd = wrap(img - fp)
            # strict contraction with a safety factor: images in the kappa r frac ball
            if np.any(np.sqrt(np.einsum("ij,jk,ik->i", dd, Q, dd)) >= kappa * r * frac):
                return False
        return True

    # a few directions first: a radius that fails, fails on most of them (same answer as
    # all directions at once, at a fraction of the applications where the map is costly)
    m = min(len(dirs), 2 * dim + 8)
    for _ in range(30):
        if contracts(dirs[:m], r) and (m == len(dirs) or contracts(dirs[m:], r)):
            return Q, (0.9 * r) ** 2
        r *= 0.5
    return none
