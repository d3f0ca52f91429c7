"""Floquet multipliers of a fixed point of a section map (paper (27)).

A fixed point ``s* = P(s*)`` (or of ``P^k``) is asymptotically stable iff every eigenvalue of
``DP(s*)``, a Floquet multiplier, has modulus below 1, and hyperbolic iff none lies within a
tolerance of the unit circle. Written once for every section map: the impact pair's closed
forms, the LTI map and the general map on any hybrid automaton.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hybridpd._results import compact_repr

__all__ = ["Stability", "stability"]

_HYPERBOLIC_TOL = 1e-9


@dataclass(frozen=True)
class Stability:
    """Stability of a fixed point from its Jacobian (paper (27)).

    Attributes
    ----------
    multipliers : ndarray, shape (d,), complex
        Eigenvalues of ``DP`` (Floquet multipliers) by decreasing modulus; ``d`` is the
        section's dimension (4 for the impact pair).
    spectral_radius : float
        Largest modulus of the multipliers.
    stable : bool
        All multipliers inside the unit circle.
    hyperbolic : bool
        No multiplier within ``tol`` of the unit circle.

    Examples
    --------
    >>> import numpy as np
    >>> import hybridpd as hp
    >>> st = hp.stability([[0.0, 1.0], [-0.5, 0.0]])
    >>> st.multipliers.shape, round(st.spectral_radius, 6), st.stable
    ((2,), 0.707107, True)
    """

    __repr__ = compact_repr

    multipliers: np.ndarray
    spectral_radius: float
    stable: bool
    hyperbolic: bool


def stability(DP, tol: float = _HYPERBOLIC_TOL, structural_zeros: int = 0) -> Stability:
    """Multipliers, spectral radius, stability and hyperbolicity of a Jacobian.

    Parameters
    ----------
    DP : array_like, shape (d, d)
        Jacobian of the section map (or of ``P^k``) at a fixed point; finite.
    tol : float, optional
        Distance from the unit circle below which a multiplier makes the fixed point
        non-hyperbolic.
    structural_zeros : int
        Number of multipliers that vanish by construction of the section's coordinates and
        are not multipliers of the motion: a sampled-data controller's held force at a
        section point is overwritten at its next sample, so ``DP`` has rank ``d - 1`` per
        sampled controller. The smallest ones, each within ``1e-9 max(1, |DP|)`` of 0, are
        left out: the rest are the multipliers of the stroboscopic period map (plant and
        controller states).

    Returns
    -------
    Stability

    Raises
    ------
    ValueError
        If ``DP`` is not a finite square matrix.

    Examples
    --------
    >>> import numpy as np
    >>> import hybridpd as hp
    >>> st = hp.stability(np.diag([0.5, -0.25]))
    >>> float(st.spectral_radius), st.stable, st.hyperbolic
    (0.5, True, True)
    >>> hp.stability(np.diag([0.5, -0.25, 0.0]), structural_zeros=1).multipliers.size
    2
    """
    DP = np.asarray(DP, float)
    if DP.ndim != 2 or DP.shape[0] != DP.shape[1] or not np.all(np.isfinite(DP)):
        raise ValueError(f"DP must be a finite square matrix, got shape {DP.shape}")
    ev = np.linalg.eigvals(DP)
    ev = ev[np.argsort(-np.abs(ev))]
    if isinstance(structural_zeros, bool) or int(structural_zeros) != structural_zeros or \
            not 0 <= structural_zeros < len(ev):
        raise ValueError(f"structural_zeros must be an int in [0, {len(ev)}), got "
                         f"{structural_zeros!r}")
    zero = 1e-9 * max(1.0, float(np.linalg.norm(DP, np.inf)))
    drop = int(np.sum(np.abs(ev[len(ev) - int(structural_zeros):]) <= zero))
    ev = ev[:len(ev) - drop]
    rho = float(np.abs(ev[0]))
    return Stability(ev, rho, rho < 1.0, bool(np.all(np.abs(np.abs(ev) - 1.0) > tol)))
