"""Draw a model file's bifurcation diagram (:class:`~hybridpd.sweeps.model_diagrams.ModelDiagram`)."""
from __future__ import annotations

import numpy as np

from hybridpd.plotting._common import figure, model_title

__all__ = ["plot_model_diagram"]

_COLORS = {"periodic": "#0072B2", "not_periodic": "#D55E00"}
_MARK = {"periodic": ".", "not_periodic": "x"}


def plot_model_diagram(d, coordinate: str | None = None, ax=None, title=None):
    """The kept section points of one coordinate against the swept entry.

    Parameters
    ----------
    d : ModelDiagram
    coordinate : str, optional
        Section coordinate on the y axis (default: the first after ``phi``).
    ax : matplotlib Axes, optional
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.sweeps.model_diagrams import DIAGRAM_CLASSES

    names = list(d.coords)
    if coordinate is None:
        coordinate = names[1] if names[0] == "phi" and len(names) > 1 else names[0]
    if coordinate not in names:
        raise ValueError(f"coordinate must be one of {names}, got {coordinate!r}")
    j = names.index(coordinate)
    fig, ax = figure(ax, figsize=(7.2, 3.6), layout="constrained")
    for c, cls in enumerate(DIAGRAM_CLASSES[:2]):
        sel = d.code == c
        if not np.any(sel):
            continue
        k = d.points.shape[1]
        xs = np.repeat(d.values[sel], k)
        ys = d.points[sel, :, j].ravel()
        ax.plot(xs, ys, ls="none", marker=_MARK[cls], ms=2 if cls == "periodic" else 3,
                color=_COLORS[cls], label=f"{cls.replace('_', ' ')} ({int(sel.sum())} values)")
    und = d.code == 2
    if np.any(und):
        ax.plot(d.values[und], np.full(int(und.sum()), np.nan), ls="none")
        for v in d.values[und]:
            ax.axvline(v, color="0.8", lw=0.6, zorder=0)
    ax.set_xlabel(f"{d.parameter_name} (model units)", fontsize=8)
    ax.set_ylabel(f"{coordinate} at the section (model units)", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.legend(fontsize=7, frameon=False, loc="best",
              title=("grey lines: map undefined" if np.any(und) else None), title_fontsize=7)
    ax.set_title(title if title is not None else
                 f"{model_title(d.source, d.metadata)}: last {d.points.shape[1]} of "
                 f"{d.metadata.get('iterations')} iterates", fontsize=8)
    return fig
