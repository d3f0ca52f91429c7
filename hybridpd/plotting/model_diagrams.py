"""Deprecated: a model file's diagram is the one diagram, drawn by
:func:`hybridpd.plotting.bifurcation.plot_bifurcation`."""
from __future__ import annotations

import warnings

from hybridpd._deprecated import REMOVAL

__all__: list = []


def __getattr__(name):
    # the name of hybridpd 0.2.0, kept one more release
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.plotting.bifurcation import plot_bifurcation

    if name != "plot_model_diagram":
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    warnings.warn(f"{__name__}.plot_model_diagram is deprecated and will be removed in "
                  f"hybridpd {REMOVAL}; use hybridpd.plotting.bifurcation.plot_bifurcation",
                  DeprecationWarning, stacklevel=2)
    return lambda d, coordinate=None, ax=None, title=None: plot_bifurcation(
        d, ax=ax, coordinate=coordinate, title=title)
