"""The entire functions ``DCh``, ``DSh`` of the collocated closed forms, evaluated with NumPy.

``DCh(a, D, t) = exp(-a t) cosh(sqrt(D) t)`` and ``DSh(a, D, t) = exp(-a t) sinh(sqrt(D) t) /
sqrt(D)`` are analytic in ``D`` (``cos``/``sin`` for ``D < 0``, ``t exp(-a t)`` at ``D = 0``),
so nothing changes branch at critical damping. The generated code of the closed forms calls
them under the names ``DCh`` and ``DSh``.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["dch", "dsh"]

_SERIES_U = 1.0  # use the power series in u = D t^2 for |u| <= _SERIES_U
_NTERMS = 16  # 1/(2*16)! ~ 4e-36: series exact to rounding for |u| <= 1
_CH_COEF = tuple(1.0 / math.factorial(2 * k) for k in range(_NTERMS))
_SH_COEF = tuple(1.0 / math.factorial(2 * k + 1) for k in range(_NTERMS))


def _horner(u, coef):
    acc = np.full_like(u, coef[-1])
    for c in coef[-2::-1]:
        acc = acc * u + c
    return acc


def _damped_pair(a, D, t):
    """Return ``(DCh, DSh)`` arrays for broadcast float inputs (see :func:`dch`)."""
    a, D, t = np.broadcast_arrays(
        np.asarray(a, dtype=float), np.asarray(D, dtype=float), np.asarray(t, dtype=float))
    with np.errstate(all="ignore"):
        u = D * t * t
        small = np.abs(u) <= _SERIES_U
        ea = np.exp(-a * t)
        us = np.where(small, u, 0.0)
        ch_s = _horner(us, _CH_COEF) * ea
        sh_s = t * _horner(us, _SH_COEF) * ea
        neg = D < 0.0
        b = np.sqrt(np.where(neg & ~small, -D, 1.0))
        ch_o = np.cos(b * t) * ea
        sh_o = np.sin(b * t) / b * ea
        r = np.sqrt(np.where(~neg & ~small, D, 1.0))
        ep = np.exp((r - a) * t)
        em = np.exp(-(r + a) * t)
        ch_h = 0.5 * (ep + em)
        sh_h = 0.5 * (ep - em) / r
        ch = np.where(small, ch_s, np.where(neg, ch_o, ch_h))
        sh = np.where(small, sh_s, np.where(neg, sh_o, sh_h))
    return ch, sh


def dch(a, D, t):
    """Damped hyperbolic cosine ``exp(-a t) cosh(sqrt(D) t)``, entire in ``D``.

    Parameters
    ----------
    a : array_like
        Decay rate (1/time), e.g. ``alpha = kv / (2 m2)``.
    D : array_like
        Discriminant (1/time^2), e.g. ``alpha^2 - kp/m2``; any sign. ``D < 0`` gives
        ``exp(-a t) cos(sqrt(-D) t)``; ``D = 0`` gives ``exp(-a t)``.
    t : array_like
        Time. All inputs broadcast.

    Returns
    -------
    ndarray
        Broadcast shape of the inputs. For ``|D t^2| <= 1`` a power series in ``D t^2`` is
        used (no branch at ``D = 0``); elsewhere ``cos`` (``D < 0``) or a product of decaying
        exponentials ``(exp((r - a) t) + exp(-(r + a) t))/2`` (``D > 0``, no overflow of
        ``cosh`` when ``exp(-a t)`` is small). ``d/dt dch = -a dch + D dsh``.
    """
    return _damped_pair(a, D, t)[0][()]


def dsh(a, D, t):
    """Damped scaled hyperbolic sine ``exp(-a t) sinh(sqrt(D) t)/sqrt(D)``, entire in ``D``.

    ``D < 0``: ``exp(-a t) sin(sqrt(-D) t)/sqrt(-D)``; ``D = 0``: ``t exp(-a t)``.
    Same parameters, shapes and numerics as :func:`dch`. ``d/dt dsh = dch - a dsh``.
    """
    return _damped_pair(a, D, t)[1][()]
