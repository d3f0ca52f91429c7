"""Traced boundary curves and codimension-2 points on a matplotlib Axes.

:func:`draw_boundaries` draws the curves of a
:class:`~hybridpd.pair.boundaries.BoundaryResult` with one style per kind (colours from
the colour-blind-safe Okabe-Ito palette *and* distinct line styles, so the kinds stay apart in
grey-scale too) and marks the codimension-2 points with one marker per kind. With ``color``
all kinds share that colour and differ by line style only (to superpose several results,
e.g. one per restitution coefficient as in Figs 4-5).
"""
from __future__ import annotations

from hybridpd.plotting._common import figure
from hybridpd.plotting.style import SINGLE, axis_label, styled

__all__ = ["CODIM2_STYLES", "KIND_STYLES", "draw_boundaries"]

#: Line style and legend label of each boundary kind.
KIND_STYLES = {
    "grazing": dict(color="#0072B2", linestyle="-", linewidth=1.8,
                    label="grazing: the orbit stops existing (paper (19))"),
    "existence": dict(color="#000000", linestyle=(0, (8, 3)), linewidth=1.6,
                      label="existence: masses stick after a plastic impact"),
    "fold": dict(color="#D55E00", linestyle="--", linewidth=1.6,
                 label="fold / branch point: a multiplier at +1"),
    "period_doubling": dict(color="#CC79A7", linestyle=":", linewidth=2.0,
                            label="period doubling: a multiplier at -1"),
    "neimark_sacker": dict(color="#009E73", linestyle="-.", linewidth=1.6,
                           label="Neimark-Sacker: a complex pair on the unit circle")}

#: Marker and legend label of each codimension-2 kind (others: a plus sign).
CODIM2_STYLES = {
    "grazing+fold": dict(marker="o", label="grazing meets fold"),
    "grazing+neimark_sacker": dict(marker="s", label="grazing meets Neimark-Sacker"),
    "grazing+period_doubling": dict(marker="p", label="grazing meets period doubling"),
    "fold+neimark_sacker": dict(marker="D", label="fold meets Neimark-Sacker"),
    "fold+period_doubling": dict(marker="h", label="fold meets period doubling"),
    "resonance_1_1": dict(marker="^", label="1:1 resonance (pair at +1)"),
    "resonance_1_2": dict(marker="v", label="1:2 resonance (pair at -1)"),
    "grazing+grazing": dict(marker="X", label="two turning points graze at once")}


@styled
def draw_boundaries(ax, result, *, color=None, codim2: bool = True, legend: bool = True,
                    kinds=None, label_suffix: str = "", markersize: float = 6.0):
    """Draw traced boundary curves (and codimension-2 points) on ``ax``.

    Parameters
    ----------
    ax : matplotlib Axes or None
        Where to draw (a new Figure when None).
    result : BoundaryResult or sequence of BoundaryCurve
        The curves (the codimension-2 points are drawn only from a BoundaryResult).
    color : str, optional
        One colour for every kind (line styles still differ per kind).
    codim2 : bool
        Mark the codimension-2 points (black markers, white edge).
    legend : bool
        Add a legend with one entry per kind drawn (labels in words).
    kinds : sequence of str, optional
        Only these kinds.
    label_suffix : str
        Appended to the legend labels (e.g. ``", e = 0.1"``).
    markersize : float

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> from hybridpd.pair.boundaries import boundary_curves
    >>> res = boundary_curves("noncollocated", x=("kp", 0.1, 20), y=("kv", 0.1, 6), e=0.5,
    ...                       mu=0.1, gamma=0.75, omega=5.0, seed_grid=21)
    >>> fig = draw_boundaries(None, res)
    >>> [t.get_text().split(":")[0] for t in fig.axes[0].get_legend().get_texts()][:2]
    ['fold / branch point', 'Neimark-Sacker']
    """
    fig, ax = figure(ax, house=(SINGLE, 3.6))
    curves = getattr(result, "curves", result)
    seen, done = set(), set()
    for c in curves:
        if kinds is not None and c.kind not in kinds:
            continue
        st = dict(KIND_STYLES.get(c.kind, dict(color="gray", linestyle="-", label=c.kind)))
        label = st.pop("label") + label_suffix
        if color is not None:
            st["color"] = color
        ax.plot(c.x, c.y, label=label if c.kind not in seen else "_nolegend_", **st)
        seen.add(c.kind)
    if codim2 and hasattr(result, "codim2"):
        for p in result.codim2:
            st = CODIM2_STYLES.get(p.kind, dict(marker="P", label=p.kind))
            ax.plot([p.x], [p.y], linestyle="none", marker=st["marker"], markersize=markersize,
                    markerfacecolor="black", markeredgecolor="white", zorder=5,
                    label=st["label"] if p.kind not in done else "_nolegend_")
            done.add(p.kind)
    if hasattr(result, "plane"):
        ax.set_xlim(result.plane.x.lo, result.plane.x.hi)
        ax.set_ylim(result.plane.y.lo, result.plane.y.hi)
        ax.set_xlabel(axis_label(result.plane.x.name))
        ax.set_ylabel(axis_label(result.plane.y.name))
    if legend and (seen or done):
        ax.legend(loc="best")
    return fig
