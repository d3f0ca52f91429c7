"""Draw a model file's attractor-labelled basin (:class:`~hybridpd.sweeps.model_basins.ModelBasin`).

The colours and markers are the pair's (:func:`hybridpd.plotting.basins.basin_colors`): the
orbit whose basin is taken blue with a star at its section point, further periodic attractors
orange, bluish green, ... with their own markers, outcomes in the pair's outcome colours, the
off-section part hatched.
"""
from __future__ import annotations

import numpy as np

from hybridpd._format import format_percent
from hybridpd.plotting._common import figure, model_title
from hybridpd.plotting.basins import _MARKERS, basin_colors, basin_hatches

__all__ = ["plot_model_basin"]


def plot_model_basin(basin, ax=None, title=None):
    """The slice coloured by attractor, section points of the periodic attractors marked.

    Parameters
    ----------
    basin : ModelBasin
    ax : matplotlib Axes, optional
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Patch

    fig, ax = figure(ax, figsize=(3.5, 4.6), layout="constrained")
    lab = basin.labels
    x, y = basin.x, basin.y
    dx, dy = x[1] - x[0], y[1] - y[0]
    codes = sorted(a["label"] for a in basin.attractors)
    colors = basin_colors(codes)
    idx = np.searchsorted(codes, lab)
    img = np.ma.masked_where(lab == -5, idx)
    extent = (x[0] - dx / 2, x[-1] + dx / 2, y[0] - dy / 2, y[-1] + dy / 2)
    ax.imshow(img, origin="lower", extent=extent, aspect="auto", interpolation="nearest",
              cmap=ListedColormap([colors[k] for k in codes]),
              norm=BoundaryNorm(np.arange(len(codes) + 1) - 0.5, len(codes)))
    # every basin but the orbit's own gets a hatch too, so that none differs by colour alone
    hatches = basin_hatches([k for k in codes if k != -5])
    for k in codes:
        if k != -5 and hatches[k] and np.any(lab == k):
            ax.contourf(x, y, (lab == k).astype(float), levels=[0.5, 1.5], colors="none",
                        hatches=[hatches[k]])
    if np.any(lab == -5):
        ax.contourf(x, y, (lab == -5).astype(float), levels=[0.5, 1.5], colors="none",
                    hatches=["///"])
    handles = []
    ix, iy = basin.coords.index(basin.x_name), basin.coords.index(basin.y_name)
    for a in basin.attractors:
        share = format_percent(basin.fraction(a["label"]))
        if a["label"] == -5:
            handles.append(Patch(facecolor="white", edgecolor="0.3", hatch="///",
                                 label=f"{a['name']}: {share} of the window"))
            continue
        handles.append(Patch(facecolor=colors[a["label"]], edgecolor="0.3",
                             hatch=hatches.get(a["label"], ""), label=f"{a['name']}: {share}"))
        if a.get("points"):
            pts = np.asarray(a["points"])
            star = a["label"] == 0
            (ln,) = ax.plot(pts[:, ix], pts[:, iy], ls="none",
                            marker="*" if star else _MARKERS[(a["label"] - 1) % len(_MARKERS)],
                            ms=12 if star else 7, mfc="white" if star else colors[a["label"]],
                            mec="black", mew=1.0, zorder=3,
                            label=f"its section point ({'stable' if a['stable'] else 'unstable'}"
                                  f", spectral radius {a['spectral_radius']:.3g})")
            handles.append(ln)
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_xlabel(f"{basin.x_name} at the section (model units)", fontsize=8)
    ax.set_ylabel(f"{basin.y_name} at the section (model units)", fontsize=8)
    ax.tick_params(labelsize=7)
    spec = basin.metadata.get("spec", {})
    vals = ", ".join(f"{k} = {v:g}" for k, v in basin.metadata.get("values", {}).items())
    head = (f"{model_title(basin.source, basin.metadata)}:\ncontact {spec.get('contact', 0)} "
            f"({spec.get('event', 'impact')})" + (f", {vals}" if vals else ""))
    ax.set_title(title if title is not None else head, fontsize=8)
    others = ", ".join(f"{n} = {v:.3g}" for n, v in zip(basin.coords, basin.fixed_point)
                       if n not in (basin.x_name, basin.y_name))
    others = "\n".join(", ".join(parts) for parts in _rows(others.split(", "), 3))
    fig.legend(handles=handles, loc="outside lower center", fontsize=7, frameon=False,
               title=f"slice through the orbit:\n{others}", title_fontsize=7)
    return fig


def _rows(items, n):
    return [items[i:i + n] for i in range(0, len(items), n)]
