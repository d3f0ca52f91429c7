r"""The package's one finite-difference rule: derivatives from values at ``x + h_j e_j``,
``x - h_j e_j`` and ``x``.

Along each direction ``j`` the derivative is the central difference
``(f(x + h_j e_j) - f(x - h_j e_j)) / (2 h_j)`` where both sides are defined, else the
one-sided difference from the centre on the side that is (forward first), and undefined where
neither side is or the centre is not. "Defined" is the caller's: a map that returns, a point
inside a parameter's domain or a box. :func:`difference_quotients` applies the rule to values
already evaluated, batch-shaped; the callers only evaluate:
:meth:`~hybridpd.analysis.maps.PoincareMap.jacobian_fd` and
:meth:`~hybridpd.analysis.maps.PoincareMap.jacobians_fd` (``DP`` of a map),
:func:`~hybridpd.analysis.family.parameter_gradient` (``dF/dp`` of a family) and the test
curves' gradients over a parameter box (:meth:`hybridpd.pair.testcurve.TestCurve.fgrad`).
"""
from __future__ import annotations

import numpy as np

__all__ = ["difference_quotients"]


def difference_quotients(plus, minus, steps, centre=None, *, ok_plus=None, ok_minus=None,
                         ok_centre=None, wrap=None) -> tuple:
    """Difference quotients along ``m`` directions by the one rule (module docstring).

    Parameters
    ----------
    plus, minus : array_like, shape (..., m, n)
        Values (``n`` of them) at ``x + h_j e_j`` and ``x - h_j e_j``, row ``j`` for direction
        ``j`` (anything where the side is undefined).
    steps : array_like, shape (..., m)
        The steps ``h_j > 0`` (units of ``x_j``).
    centre : array_like, shape (..., n), optional
        Values at ``x``; without them no one-sided difference is taken (and the centre is
        taken as defined).
    ok_plus, ok_minus : array_like of bool, shape (..., m), optional
        Where each side is defined (default: everywhere).
    ok_centre : array_like of bool, shape (...), optional
        Where the centre is defined (default: everywhere).
    wrap : callable, optional
        Applied to every difference of values (e.g. the phase wrap of
        :meth:`~hybridpd.analysis.maps.PoincareMap.wrap`; it sees the ``n`` values on the
        last axis).

    Returns
    -------
    quotients : ndarray, shape (..., m, n)
        Row ``j``: the derivative of the ``n`` values along direction ``j`` (values per unit
        of ``x_j``); NaN where undefined.
    defined : ndarray of bool, shape (..., m)
        Where a difference was taken.

    Examples
    --------
    >>> q, ok = difference_quotients([[3.0], [9.0]], [[1.0], [0.0]], [1.0, 1.0], [2.0],
    ...                              ok_minus=[True, False])
    >>> q[:, 0].tolist(), ok.tolist()
    ([1.0, 7.0], [True, True])
    """
    plus, minus = np.asarray(plus, float), np.asarray(minus, float)
    steps = np.asarray(steps, float)
    wrap = _same if wrap is None else wrap
    both = None
    for ok, per_point in ((ok_plus, False), (ok_minus, False), (ok_centre, True)):
        if ok is not None:
            ok = np.asarray(ok, bool)[..., None] if per_point else np.asarray(ok, bool)
            both = ok if both is None else both & ok
    central = wrap(plus - minus) / (2 * steps)[..., None]
    if both is None or both.all():   # the common case: central everywhere, nothing to select
        return central, np.ones(steps.shape, bool)
    with np.errstate(invalid="ignore"):
        both = np.broadcast_to(both, steps.shape).copy()
        q = np.where(both[..., None], central, np.nan)
        if centre is None:
            return q, both
        c = np.asarray(centre, float)[..., None, :]
        okp, okm = _mask(ok_plus, steps), _mask(ok_minus, steps)
        okc = np.ones((), bool) if ok_centre is None else np.asarray(ok_centre, bool)[..., None]
        fwd = okp & ~okm & okc
        bwd = ~okp & okm & okc
        q = np.where(fwd[..., None], wrap(plus - c) / steps[..., None], q)
        q = np.where(bwd[..., None], wrap(c - minus) / steps[..., None], q)
    return q, both | fwd | bwd


def _mask(ok, steps):
    return np.ones(steps.shape, bool) if ok is None else np.asarray(ok, bool)


def _same(d):
    return d
