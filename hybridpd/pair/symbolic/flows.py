"""Closed-form flows between impacts and the section coordinates (paper section 2).

``X = [x1, y1, x2, y2, pc, ps]``, ``X' = A X`` between impacts; ``Phi(t) = expm(A t)`` in
closed form (collocated: the entire functions ``DCh``, ``DSh``; non-collocated: polynomials
and sinusoids). Section coordinates ``s = (phi, z1, z2, z4)``; see :mod:`hybridpd.pair.symbolic`.
"""
from __future__ import annotations

import numpy as np

from hybridpd.pair.symbolic._numeric import _as_float_arrays, _case, _stack, kernel

__all__ = ["flow", "gap", "gap_derivatives", "section_from_state", "state_from_section",
           "system_matrix", "transition_matrix"]


def _flow_args(t, X0, kp, kv, m2, w):
    t, X0, kp, kv, m2, w = _as_float_arrays(t=t, X0=X0, kp=kp, kv=kv, m2=m2, w=w)
    if X0.shape[-1:] != (6,):
        raise ValueError(f"X0 must have shape (..., 6) [x1, y1, x2, y2, pc, ps], got {X0.shape}")
    shape = np.broadcast_shapes(t.shape, X0.shape[:-1], kp.shape, kv.shape, m2.shape, w.shape)
    return t, X0, kp, kv, m2, w, shape


def system_matrix(*, kp, kv, m2=1.0, w, case="collocated") -> np.ndarray:
    """Closed-loop 6x6 matrix ``A`` of ``X' = A X``, ``X = [x1, y1, x2, y2, pc, ps]``.

    Parameters
    ----------
    kp, kv, m2, w : array_like
        Gains (N/m, N s/m), secondary mass (kg), reference frequency (rad/s); broadcast.
    case : {"collocated", "noncollocated"}

    Returns
    -------
    ndarray, shape (..., 6, 6)
        Row ``y2'``: collocated ``[0, 0, -kp/m2, -kv/m2, kp/m2 - w^2, -kv w/m2]``;
        non-collocated ``[-kp/m2, -kv/m2, 0, 0, kp/m2 - w^2, -kv w/m2]``.
    """
    case = _case(case)
    kp, kv, m2, w = _as_float_arrays(kp=kp, kv=kv, m2=m2, w=w)
    shape = np.broadcast_shapes(kp.shape, kv.shape, m2.shape, w.shape)
    A = np.zeros(shape + (6, 6))
    A[..., 0, 1] = 1.0
    A[..., 2, 3] = 1.0
    i, j = (2, 3) if case == "collocated" else (0, 1)
    A[..., 3, i] = -kp / m2
    A[..., 3, j] = -kv / m2
    A[..., 3, 4] = kp / m2 - w**2
    A[..., 3, 5] = -kv * w / m2
    A[..., 4, 5] = -w
    A[..., 5, 4] = w
    return A


def transition_matrix(t, *, kp, kv, m2=1.0, w, case="collocated") -> np.ndarray:
    """Closed-form state-transition matrix ``Phi(t) = expm(A t)``.

    Parameters
    ----------
    t : array_like
        Time since the initial state (any sign).
    kp, kv, m2, w : array_like
        Parameters (see :func:`system_matrix`); all broadcast with ``t``.
    case : {"collocated", "noncollocated"}

    Returns
    -------
    ndarray, shape (..., 6, 6)
        ``X(t) = Phi(t) @ X(0)``. Continuous across critical damping ``kv^2 = 4 kp m2``.
    """
    case = _case(case)
    t, kp, kv, m2, w = _as_float_arrays(t=t, kp=kp, kv=kv, m2=m2, w=w)
    shape = np.broadcast_shapes(t.shape, kp.shape, kv.shape, m2.shape, w.shape)
    vals = kernel("transition", case)(t, kp, kv, m2, w)
    return _stack(vals, shape).reshape(shape + (6, 6))


def flow(t, X0, *, kp, kv, m2=1.0, w, case="collocated") -> np.ndarray:
    """State at time ``t`` from the state ``X0`` at time 0 (closed form).

    Parameters
    ----------
    t : array_like
        Elapsed time.
    X0 : array_like, shape (..., 6)
        ``[x1, y1, x2, y2, pc, ps]`` at time 0 (``pc = xm cos(w t0)``, ``ps = xm sin(w t0)``).
    kp, kv, m2, w : array_like
        Parameters; broadcast with ``t`` and ``X0[..., 0]``.
    case : {"collocated", "noncollocated"}

    Returns
    -------
    ndarray, shape (..., 6)
        ``X(t)``, no impacts taken into account.
    """
    case = _case(case)
    t, X0, kp, kv, m2, w, shape = _flow_args(t, X0, kp, kv, m2, w)
    vals = kernel("flow", case)(t, *np.moveaxis(X0, -1, 0), kp, kv, m2, w)
    return _stack(vals, shape)


def gap_derivatives(t, X0, *, kp, kv, m2=1.0, w, case="collocated", order=3) -> np.ndarray:
    """Gap ``z3 = x1 - x2`` and its time derivatives at time ``t`` (closed form).

    Parameters
    ----------
    t, X0, kp, kv, m2, w, case
        As in :func:`flow`.
    order : int, 0..3
        Highest derivative returned.

    Returns
    -------
    ndarray, shape (..., order + 1)
        ``[z3, z3', z3'', z3''']`` truncated to ``order + 1`` entries
        (``z3' = z4 = y1 - y2``; ``z3^(k) = c A^k X(t)``).
    """
    case = _case(case)
    if not 0 <= int(order) <= 3:
        raise ValueError(f"order must be in 0..3, got {order!r}")
    t, X0, kp, kv, m2, w, shape = _flow_args(t, X0, kp, kv, m2, w)
    vals = kernel("gap", case)(t, *np.moveaxis(X0, -1, 0), kp, kv, m2, w)
    return _stack(vals[: int(order) + 1], shape)


def gap(t, X0, *, kp, kv, m2=1.0, w, case="collocated", order=0) -> np.ndarray:
    """The ``order``-th time derivative (0..3) of ``z3 = x1 - x2`` at time ``t``; shape ``(...)``.

    See :func:`gap_derivatives`.
    """
    return gap_derivatives(t, X0, kp=kp, kv=kv, m2=m2, w=w, case=case, order=order)[..., -1]


# ----------------------------------------------------------------------------------------
# Section coordinates
# ----------------------------------------------------------------------------------------


def state_from_section(s, *, xm, L, w, wall=1) -> np.ndarray:
    """Full state on wall ``wall`` from section coordinates.

    Parameters
    ----------
    s : array_like, shape (..., 4)
        ``(phi, z1, z2, z4)``: phase (time mod T), ``x2``, ``y2``, ``y1 - y2``.
    xm, L, w : array_like
        Reference amplitude, half clearance, reference frequency.
    wall : {+1, -1}
        The state lies on ``z3 = wall * L``.

    Returns
    -------
    ndarray, shape (..., 6)
        ``(z1 + wall L, z2 + z4, z1, z2, xm cos(w phi), xm sin(w phi))``.
    """
    s, xm, L, w, wall = _as_float_arrays(s=s, xm=xm, L=L, w=w, wall=wall)
    phi, z1, z2, z4 = np.moveaxis(s, -1, 0)
    shape = np.broadcast_shapes(phi.shape, xm.shape, L.shape, w.shape, wall.shape)
    return _stack([z1 + wall * L, z2 + z4, z1, z2, xm * np.cos(w * phi), xm * np.sin(w * phi)],
                  shape)


def section_from_state(X, *, w) -> np.ndarray:
    """Section coordinates ``(phi, z1, z2, z4)`` of a full state (shape (..., 6) -> (..., 4)).

    ``phi = atan2(ps, pc)/w mod T``; the wall (``z3``) is not checked.
    """
    X, w = _as_float_arrays(X=X, w=w)
    T = 2.0 * np.pi / w
    phi = np.mod(np.arctan2(X[..., 5], X[..., 4]) / w, T)
    shape = np.broadcast_shapes(phi.shape, X.shape[:-1])
    return _stack([phi, X[..., 2], X[..., 3], X[..., 1] - X[..., 3]], shape)
