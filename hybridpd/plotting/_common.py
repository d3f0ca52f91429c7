"""Shared helpers of the figures."""
from __future__ import annotations

_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown")


def figure(ax, **kw):
    # A bare Figure (no pyplot) renders headless and leaves no global figure state behind.
    if ax is not None:
        return ax.figure, ax
    from matplotlib.figure import Figure

    fig = Figure(**kw)
    return fig, fig.add_subplot(1, 1, 1)
