"""The package's one phase wrap, in Python and compiled: one expression, written twice.

A phase difference ``d`` is taken to ``[-T/2, T/2)`` modulo the period ``T`` by
``(d + T/2) % T - T/2``. :func:`wrap_phase` evaluates it on scalars and NumPy arrays (the map
protocol, the sections, the continuations, the attractor catalogue);
:func:`wrap_phase_kernel` is its twin for numba kernels (the impact pair's basin labels, the
section kernel's distances). Both are the same expression, so they round alike: the tests
compare them bit for bit and compare their source expressions.
"""
from __future__ import annotations

from hybridpd._jit import njit

__all__ = ["wrap_phase", "wrap_phase_kernel"]


def wrap_phase(d, T):
    """A phase (difference) ``d`` taken to ``[-T/2, T/2)`` modulo the period ``T`` (scalars or
    arrays): the package's one phase wrap.

    Examples
    --------
    >>> float(wrap_phase(0.75, 1.0)), float(wrap_phase(-0.5, 1.0)), float(wrap_phase(2.25, 1.0))
    (-0.25, -0.5, 0.25)
    """
    return (d + 0.5 * T) % T - 0.5 * T


@njit(cache=True)
def wrap_phase_kernel(d, T):
    """:func:`wrap_phase` for numba kernels (the same expression)."""
    return (d + 0.5 * T) % T - 0.5 * T
