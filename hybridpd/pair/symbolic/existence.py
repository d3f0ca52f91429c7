"""The simple symmetric orbit of odd order ``n`` (paper section 3): conditions (9)-(16).

Existence reduces to the linear system ``M [C, S]^T = b`` of (13)-(14) for ``C = xm cos(w t0)``,
``S = xm sin(w t0)``; its closed-form entries come from the generated code of the SymPy
derivation (see :mod:`hybridpd.pair.symbolic.derive`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hybridpd._results import compact_repr, short_repr
from hybridpd.model import check_array, virtual_restitution
from hybridpd.pair.symbolic._numeric import _as_float_arrays, _case, kernel

__all__ = ["SymmetricOrbit", "solve_symmetric_orbit", "symmetric_velocities",
           "virtual_restitution"]


def symmetric_velocities(*, mu, e, w, x10, n=1):
    """Impact velocities of the symmetric orbit of order ``n``, (9)-(11).

    Returns
    -------
    v, y2_pre, y2_post : ndarray
        ``v = y10 = 2 x10 w / (n pi)`` (primary-mass speed; pre-impact ``y1- = +v``,
        post ``y1+ = -v`` at the ``+L`` wall), ``y2_pre = v (e - 2 mu - 1)/(1 + e)`` (10),
        ``y2_post = v (e + 2 e mu - 1)/(1 + e) = R y2_pre`` (11).
    """
    mu, e, w, x10, n = _as_float_arrays(mu=mu, e=e, w=w, x10=x10, n=n)
    v = 2.0 * x10 * w / (n * np.pi)
    return (v[()], (v * (e - 2 * mu - 1) / (1 + e))[()],
            (v * (e + 2 * e * mu - 1) / (1 + e))[()])


def _check_odd(n):
    try:
        nf = check_array("n", n)
    except ValueError:
        nf = None
    if nf is None or not np.all((nf == np.round(nf)) & (nf >= 1) & (np.mod(nf, 2) == 1)):
        raise ValueError(f"n must be a positive odd integer 1, 3, 5, ... (or an array of them), "
                         f"got {short_repr(n)}")
    return nf


@dataclass(frozen=True)
class SymmetricOrbit:
    """Simple symmetric periodic orbit of order ``n`` (paper section 3).

    All array fields share the broadcast shape of the inputs of :func:`solve_symmetric_orbit`.
    The orbit is only *candidate*: viability (18) (no extra impact in between) is not
    checked here.

    Attributes
    ----------
    case : str
        ``"collocated"`` or ``"noncollocated"``.
    kp, kv, m2, mu, e, L, w, x10, n : ndarray
        The inputs, broadcast.
    C, S : ndarray
        ``xm cos(w t0)``, ``xm sin(w t0)`` at the ``+L`` impact (length).
    xm : ndarray
        Reference amplitude ``hypot(C, S)`` (20) (length).
    sn, cs : ndarray
        ``sin(w phi0) = S/xm``, ``cos(w phi0) = C/xm`` (15)-(16).
    phi0 : ndarray
        Phase of the ``+L`` impact, ``atan2(S, C)/w mod T``, in ``[0, T)`` (time).
    T, tau : ndarray
        ``2 pi / w`` and the flight time ``n T / 2`` between impacts (time).
    x20 : ndarray
        ``x10 - L``: secondary-mass position at the ``+L`` impact (may be negative).
    v : ndarray
        ``y10 = 2 x10 w/(n pi)``; ``y1- = +v``, ``y1+ = -v`` at the ``+L`` impact.
    y2_pre, y2_post : ndarray
        Secondary-mass velocity before (10) and after (11) the ``+L`` impact.
    R : ndarray
        Virtual restitution coefficient (12).
    det : ndarray
        Determinant of the 2x2 linear system for ``(C, S)``.
    singular : ndarray of bool
        ``|det|`` below ``1e-13`` times the product of the row norms (then ``C``, ``S`` are
        unreliable or NaN). Never true for ``kv > 0`` (see :class:`Derivation`).
    """

    __repr__ = compact_repr

    case: str
    kp: np.ndarray
    kv: np.ndarray
    m2: np.ndarray
    mu: np.ndarray
    e: np.ndarray
    L: np.ndarray
    w: np.ndarray
    x10: np.ndarray
    n: np.ndarray
    C: np.ndarray
    S: np.ndarray
    xm: np.ndarray
    sn: np.ndarray
    cs: np.ndarray
    phi0: np.ndarray
    T: np.ndarray
    tau: np.ndarray
    x20: np.ndarray
    v: np.ndarray
    y2_pre: np.ndarray
    y2_post: np.ndarray
    R: np.ndarray
    det: np.ndarray
    singular: np.ndarray

    @property
    def section_point(self) -> np.ndarray:
        """Pre-impact point on the section, ``(phi0, x20, y2_pre, v - y2_pre)``, shape (..., 4)."""
        return np.stack(np.broadcast_arrays(self.phi0, self.x20, self.y2_pre,
                                            self.v - self.y2_pre), axis=-1)

    @property
    def post_impact_state(self) -> np.ndarray:
        """Full state right after the ``+L`` impact, ``(x10, -v, x20, y2_post, C, S)``; (..., 6)."""
        return np.stack(np.broadcast_arrays(self.x10, -self.v, self.x20, self.y2_post,
                                            self.C, self.S), axis=-1)


def solve_symmetric_orbit(*, kp, kv, m2=1.0, mu, e, L, w, x10, n=1,
                    case="collocated") -> SymmetricOrbit:
    """Solve the existence conditions (13)-(14) of the symmetric orbit; vectorised.

    Parameters
    ----------
    kp, kv : array_like
        PD gains (> 0).
    m2 : array_like
        Secondary mass (> 0), default 1.
    mu : array_like
        Mass ratio ``m1/m2`` (> 0).
    e : array_like
        Restitution coefficient in [0, 1].
    L : array_like
        Half clearance (> 0).
    w : array_like
        Reference frequency (rad/time, > 0).
    x10 : array_like
        Desired amplitude of the primary mass (> 0); ``x20 = x10 - L``.
    n : int or array_like of odd int
        Orbit order (period ``n T``).
    case : {"collocated", "noncollocated"}

    Returns
    -------
    SymmetricOrbit
        All fields broadcast to the common shape (e.g. a 200x200x3 grid of (kp, kv, e)
        evaluates in a few tens of ms).

    Raises
    ------
    ValueError
        If ``n`` is not a positive odd integer, a parameter is out of range (``kp, kv, m2,
        mu, L, w, x10 > 0``, ``0 <= e <= 1``) or ``case`` is unknown.

    Notes
    -----
    ``x20 = x10 - L`` may be negative (allowed). Existence in the paper's sense also needs
    viability (18), which is not checked here. The determinant of the 2x2 system is
    ``-w (1 + 2 DCh(alpha, D, tau) + exp(-2 alpha tau)) <= -w (1 - exp(-alpha tau))^2 < 0``
    (collocated) and ``-(4/w^3)((kp/m2 - w^2)^2 + (kv w/m2)^2) < 0`` (non-collocated), so
    for ``kv > 0`` the system is never singular; ``singular`` flags numerical trouble only.
    """
    case = _case(case)
    nf = _check_odd(n)
    kp, kv, m2, mu, L, w, x10 = (check_array(name, v, lo=0.0) for name, v in (
        ("kp", kp), ("kv", kv), ("m2", m2), ("mu", mu), ("L", L), ("w", w), ("x10", x10)))
    e = check_array("e", e, lo=0.0, lo_open=False, hi=1.0)
    shape = np.broadcast_shapes(kp.shape, kv.shape, m2.shape, mu.shape, e.shape, L.shape,
                                w.shape, x10.shape, nf.shape)
    f = kernel("existence", case)
    m00, m01, m10, m11, b0, b1 = (np.broadcast_to(np.asarray(q, dtype=float), shape)
                                  for q in f(kp, kv, m2, mu, e, L, w, x10, nf))
    with np.errstate(all="ignore"):
        det = m00 * m11 - m01 * m10
        scale = np.hypot(m00, m01) * np.hypot(m10, m11)
        singular = ~(np.abs(det) > 1e-13 * scale)
        C = (b0 * m11 - m01 * b1) / det
        S = (m00 * b1 - m10 * b0) / det
        C = np.where(singular, np.nan, C)
        S = np.where(singular, np.nan, S)
        xm = np.hypot(C, S)
        sn = S / xm
        cs = C / xm
        T = 2.0 * np.pi / w
        phi0 = np.mod(np.arctan2(S, C) / w, T)
    v, y2m, y2p = symmetric_velocities(mu=mu, e=e, w=w, x10=x10, n=nf)
    b = lambda a: np.broadcast_to(np.asarray(a, dtype=float), shape)[()]
    return SymmetricOrbit(
        case=case, kp=b(kp), kv=b(kv), m2=b(m2), mu=b(mu), e=b(e), L=b(L), w=b(w), x10=b(x10),
        n=b(nf), C=b(C), S=b(S), xm=b(xm), sn=b(sn), cs=b(cs), phi0=b(phi0), T=b(T),
        tau=b(nf * T / 2), x20=b(x10 - L), v=b(v), y2_pre=b(y2m), y2_post=b(y2p),
        R=b(virtual_restitution(mu, e)), det=b(det), singular=b(singular))


# the name of 0.2.0 (the flat hybridpd.symmetric_orbit is the pair-object form)
