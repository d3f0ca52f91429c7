"""plot basin: see :mod:`hybridpd.plotting`."""
from __future__ import annotations

import numpy as np

from hybridpd.plotting._common import figure
from hybridpd.sweeps.basins import LABELS


def plot_basin(basin, ax=None, title=None):
    """The basin slice with labels as colours and the fixed point marked."""
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch


    fig, ax = figure(ax, figsize=(6, 5))
    colors = ["#3b75af", "#f2f2f2", "#d95f02", "#7570b3", "#e7298a", "#ffffff"]
    cmap = ListedColormap(colors)
    x, y = basin.x1, basin.y1
    dx = (x[-1] - x[0]) / max(len(x) - 1, 1)
    dy = (y[-1] - y[0]) / max(len(y) - 1, 1)
    ax.imshow(basin.labels, origin="lower", cmap=cmap, vmin=-0.5, vmax=len(LABELS) - 0.5,
              extent=(x[0] - dx / 2, x[-1] + dx / 2, y[0] - dy / 2, y[-1] + dy / 2),
              aspect="auto", interpolation="nearest")
    fp = basin.fixed_point
    L = basin.metadata.get("L", 0.0)
    ax.plot(fp[1] + L, fp[2] + fp[3], marker="*", color="gold", markeredgecolor="k",
            markersize=14, label="fixed point")
    present = sorted(set(np.unique(basin.labels).tolist()))
    handles = [Patch(facecolor=colors[k], edgecolor="gray", label=LABELS[k]) for k in present]
    handles.append(ax.lines[-1])
    ax.legend(handles=handles, loc="best", fontsize=8)
    ax.set_xlabel("x1 at impact")
    ax.set_ylabel("y1 (pre-impact)")
    m = basin.metadata
    ax.set_title(title or (f"{m.get('case', '')}: e = {m.get('e', float('nan')):g}, kp = "
                           f"{m.get('kp', float('nan')):g}, kv = {m.get('kv', float('nan')):g}; "
                           f"converged {100 * basin.converged_fraction:.1f}%"), fontsize=9)
    return fig
