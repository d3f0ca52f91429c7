"""plot regions: see :mod:`hybridpd.plotting`."""
from __future__ import annotations

import numpy as np

from hybridpd.plotting._common import _COLORS, figure


def plot_regions(rm, ax=None, title=None):
    """Existence (outline) and existence-and-stability (shaded) regions, one colour per ``e``.

    Parameters
    ----------
    rm : RegionMap
    ax : matplotlib Axes, optional
    """
    from matplotlib.patches import Patch

    fig, ax = figure(ax, figsize=(6, 5))
    X, Y = np.meshgrid(rm.x, rm.y)
    handles = []
    for k, e in enumerate(rm.e):
        c = _COLORS[k % len(_COLORS)]
        st = rm.stable[k].astype(float)
        ex = rm.exists[k].astype(float)
        if st.any():
            ax.contourf(X, Y, st, levels=[0.5, 1.5], colors=[c], alpha=0.25)
            ax.contour(X, Y, st, levels=[0.5], colors=[c], linewidths=1.2)
        if ex.any() and not ex.all():
            ax.contour(X, Y, ex, levels=[0.5], colors=[c], linewidths=1.0, linestyles="--")
        handles.append(Patch(facecolor=c, alpha=0.35, edgecolor=c,
                             label=f"e = {e:g}: exists & stable ({100 * rm.fraction()[k]:.1f}%)"))
    handles.append(Patch(facecolor="none", edgecolor="gray", linestyle="--",
                         label="existence boundary"))
    ax.legend(handles=handles, loc="best", fontsize=8)
    ax.set_xlabel(rm.x_name)
    ax.set_ylabel(rm.y_name)
    f = rm.fixed
    ax.set_title(title or (f"{rm.case}: mu = {f['mu']:g}, gamma = {f['L'] / f['x10']:g}, "
                           f"n = {f['n']}, omega = {f['omega']:g}"), fontsize=9)
    return fig
