"""Shared helpers of the figures: bare figures, legends built from what is drawn, captions.

Legend entries are built from the drawn artists: each labelled artist carries its label as
its ``gid``, and :func:`register` records the legend handle that draws it (a proxy with the
artist's colour *and* its line style, marker or hatch), so a legend never claims what is not
drawn and never tells two entries apart by colour alone.
"""
from __future__ import annotations

import numpy as np

from hybridpd.plotting.style import SERIES, house_figure

#: Series colours (Okabe-Ito), in the order of :data:`~hybridpd.plotting.style.SERIES`.
_COLORS = tuple(s["color"] for s in SERIES)

_KEY = "_hybridpd_legend"


def figure(ax, house=None, **kw):
    # A bare Figure (no pyplot) renders headless and leaves no global figure state behind.
    if ax is not None:
        return ax.figure, ax
    if house is not None:  # (width, height) of a figure in the house style
        fig = house_figure(*house)
    else:
        from matplotlib.figure import Figure

        fig = Figure(**kw)
    return fig, fig.add_subplot(1, 1, 1)


def set_all(artist, **props):
    """``artist.set(**props)`` and the same on its sub-collections (contour sets of older
    matplotlib); an artist without one of the properties is left as it is."""
    for a in [artist, *getattr(artist, "collections", [])]:
        try:
            a.set(**props)
        except AttributeError:
            pass
    return artist


def tag(artist, label):
    """Set ``label`` as the artist's gid (and its sub-collections' for contour sets)."""
    return set_all(artist, gid=label)


def register(ax, artist, label, proxy):
    """Tag ``artist`` with ``label`` and record ``proxy`` as its legend handle on ``ax``."""
    tag(artist, label)
    ax.__dict__.setdefault(_KEY, {}).setdefault(label, proxy)
    return artist


def line_proxy(**kw):
    from matplotlib.lines import Line2D

    return Line2D([], [], **kw)


def patch_proxy(**kw):
    from matplotlib.patches import Patch

    return Patch(**kw)


def _proxy_of(a):
    """A legend handle copying a drawn artist's style (for artists not registered)."""
    from matplotlib.collections import LineCollection
    from matplotlib.lines import Line2D

    if isinstance(a, Line2D):
        return line_proxy(color=a.get_color(), ls=a.get_linestyle(), lw=a.get_linewidth(),
                          marker=a.get_marker(), ms=a.get_markersize(),
                          mfc=a.get_markerfacecolor(), mec=a.get_markeredgecolor())
    if isinstance(a, LineCollection):
        col = a.get_edgecolor()[0] if len(a.get_edgecolor()) else "k"
        return line_proxy(color=col, ls=a.get_linestyle()[0] if a.get_linestyle() else "-")
    fc = a.get_facecolor()
    if np.ndim(fc) == 2:
        fc = fc[0] if len(fc) else "none"
    ec = a.get_edgecolor()
    if np.ndim(ec) == 2:
        ec = ec[0] if len(ec) else "0.3"
    return patch_proxy(facecolor=fc, edgecolor=ec,
                       hatch=a.get_hatch() if hasattr(a, "get_hatch") else None)


def legend_handles(axes) -> list:
    """``[(label, handle)]`` of every labelled artist drawn on ``axes``, in drawing order."""
    seen = {}
    for ax in axes:
        reg = ax.__dict__.get(_KEY, {})
        for a in ax.get_children():
            g = a.get_gid() if hasattr(a, "get_gid") else None
            if g and g not in seen:
                seen[g] = reg.get(g) or _proxy_of(a)
    return list(seen.items())


def legend_from_gids(fig, axes, *, loc="outside lower center", ncol=3, **kw):
    """A figure legend whose entries are exactly the labelled artists drawn on ``axes``."""
    pairs = legend_handles(axes)
    if pairs:
        labels, handles = zip(*pairs)
        fig.legend(handles=list(handles), labels=list(labels), loc=loc,
                   ncol=min(ncol, len(handles)), **kw)
    return [p[0] for p in pairs]


def param_line(params: dict) -> str:
    """``mu = .., gamma = .., omega = .., n = .., m2 = ..`` in mathtext."""
    symbols = (("mu", r"$\mu$"), ("gamma", r"$\gamma$"), ("omega", r"$\omega$"), ("n", "$n$"),
               ("m2", "$m_2$"), ("x10", "$x_{10}$"))
    return ", ".join(f"{sym} = {params[key]:g}" for key, sym in symbols
                     if params.get(key) is not None)


#: How a model file's ``controller.type`` is named in titles and legends.
def model_controllers(source, metadata: dict | None = None) -> str:
    """The controllers of the model a result was computed for, in words: the result's
    ``metadata["controllers"]`` if it holds them, else read from the model file at `source`
    if it is still there, else ``"the model's controller"`` (never a guessed type)."""
    meta = metadata or {}
    if meta.get("controllers"):
        return str(meta["controllers"])
    # deferred import: loaded only when this runs, for start-up time
    from pathlib import Path

    try:
        if source is not None and Path(str(source)).is_file():
            # deferred import: loaded only when this runs, for start-up time
            from hybridpd.mechanics.modelfile import describe_controllers, read_model_file

            return describe_controllers(read_model_file(source)[0])
    except (ValueError, OSError):
        pass
    return "the model's controller"


def model_title(source, metadata: dict | None = None) -> str:
    """``"<file name>, <controllers>"``: the head of a model figure's title."""
    # deferred import: loaded only when this runs, for start-up time
    from pathlib import Path

    return f"{Path(str(source)).name}, {model_controllers(source, metadata)}"


def suptitle(fig, text: str, chars_per_inch: float = 13.0):
    """``fig.suptitle(text)`` wrapped to the figure's width (about `chars_per_inch`
    characters of the house font per inch), so a long title (a model naming every
    controller) is never cut at the figure's edge."""
    import textwrap

    width = max(20, int(fig.get_figwidth() * chars_per_inch))
    return fig.suptitle("\n".join(textwrap.wrap(text, width)))
