"""Region figures: Figs 4-5 with one panel per ``e``, and all ``e`` on one axes.

Conventions of every figure here: the region where the orbit exists and is stable is filled;
where it exists but is unstable is hatched (so "no orbit" is the only white); cells whose
orbit returns ``k > 1`` times to the section per period (a model's map records ``k``) carry
one more hatch per ``k`` with the legend entry "k = 2 returns per period"; the existence
boundary is a dashed line with short ticks on the side where the orbit exists; legend entries
are built from the drawn artists (:mod:`hybridpd.plotting._common`) and sit outside the data;
the parameters are stated on the figure. ``curves=`` takes traced boundary curves (objects with
``.kind``, ``.x``, ``.y``) and draws them instead of the grid contours. Every figure is drawn
in the house style (:mod:`hybridpd.plotting.style`) at its print size.
"""
from __future__ import annotations

import numpy as np

from hybridpd.plotting._common import (
    figure,
    legend_from_gids,
    line_proxy,
    param_line,
    patch_proxy,
    register,
    set_all,
    suptitle,
    tag,
)
from hybridpd.plotting.style import DOUBLE, axis_label, house_figure, series, styled

__all__ = ["param_line", "plot_certified_panels", "plot_region_panels", "plot_regions"]

#: Colour-blind-safe colours (Okabe-Ito).
FILL = "#56B4E9"
FILL_EDGE = "#0072B2"
EXIST = "#000000"
UNSTABLE_HATCH = "////"
UNSTABLE_EDGE = "0.45"
PAPER_GAINS = "paper's gains"
LAB_FILL = "exists and stable"
LAB_UNSTABLE = "exists, unstable (hatched)"
LAB_NONE = "no orbit (white)"
LAB_EX = "existence boundary (ticks on the existing side)"
LAB_ST = "stability boundary"
LAB_ZOOM = "zoom window (second row)"
LAB_OUTSIDE = "not computed (grey, dotted)"
OUTSIDE_EDGE, OUTSIDE_HATCH = "0.55", "...."
#: Drawing order of the paper's-gains star: above fills, boundaries and outlines.
MARK_ZORDER = 8
_CASE = {"collocated": "collocated", "noncollocated": "non-collocated"}

#: Certified classes (CF flag value -> legend text and face colour); undecided is hatched.
CERTIFIED = {1: ("proved stable", FILL), 2: ("proved unstable", "#E69F00"),
             3: ("proved no orbit (white)", "white")}
UNDECIDED = "undecided (hatched)"
UNDECIDED_FACE, UNDECIDED_EDGE, UNDECIDED_HATCH = "0.88", "0.55", "xxxx"

#: Cells whose orbit returns k > 1 times per period (one hatch per k, in order of k).
RETURNS_HATCHES, RETURNS_EDGE = ("...", "ooo", "***", "+++"), "#7A1F00"

#: Traced boundary kinds that bound existence (drawn like the existence boundary).
_EXISTENCE_KINDS = ("existence", "grazing", "viability", "xm_zero", "sticking")

#: Legend words and styles of the traced stability kinds (colour *and* dash pattern differ).
_TRACED = {
    "fold": ("a multiplier crosses +1 (traced)", dict(color="#D55E00", ls="-.", lw=1.3)),
    "period_doubling": ("a multiplier crosses -1 (traced)",
                        dict(color="#CC79A7", ls=":", lw=1.6)),
    "neimark_sacker": ("Neimark-Sacker: a complex pair crosses the unit circle (traced)",
                       dict(color="#0072B2", ls="-", lw=1.3)),
}


def _params_of(rm) -> dict:
    f = rm.fixed
    out = {"mu": f.get("mu"), "omega": f.get("omega"), "n": f.get("n"), "m2": f.get("m2"),
           "x10": f.get("x10")}
    if "L" in f and "x10" in f:
        out["gamma"] = f["L"] / f["x10"]
    return out


def _side_ticks(ax, X, Y, field, color, label, every=6, line=True, marker="|"):
    """Short ticks on the ``field > 0.5`` side of its 0.5 contour (the existing side); the
    dashed contour itself unless ``line`` is False (traced curves are drawn instead)."""
    from matplotlib.collections import LineCollection
    from scipy.ndimage import gaussian_filter

    f = gaussian_filter(field.astype(float), 1.0)
    gy, gx = np.gradient(f)
    x, y = X[0], Y[:, 0]
    sx, sy = (x[-1] - x[0]), (y[-1] - y[0])
    cs = ax.contour(X, Y, field.astype(float), levels=[0.5], colors=[color], linewidths=1.1,
                    linestyles="--")
    register(ax, cs, label, line_proxy(color=color, ls="--", lw=1.1, marker=marker, ms=5))
    paths = cs.allsegs[0]
    if not line:
        cs.remove()
    segs = []
    nx, ny = len(x), len(y)
    for path in paths:
        for px, py in path[::every]:
            # gradient in axes-fraction units, sampled at the nearest grid node
            i = int(np.clip(round((py - y[0]) / sy * (ny - 1)), 0, ny - 1))
            j = int(np.clip(round((px - x[0]) / sx * (nx - 1)), 0, nx - 1))
            g = np.array([gx[i, j] * (nx - 1), gy[i, j] * (ny - 1)])
            gn = np.hypot(*g)
            if not gn > 0:
                continue
            d = g / gn * 0.025
            segs.append([(px, py), (px + d[0] * sx, py + d[1] * sy)])
    if segs:
        lc = LineCollection(segs, colors=[color], linewidths=0.9)
        ax.add_collection(tag(lc, label))
    return cs


def _draw_curves(ax, curves):
    """Traced boundaries: existence-type kinds dashed black, the stability kinds each with
    their own colour and dash pattern."""
    for c in curves:
        base = str(getattr(c, "kind", "boundary")).split(":")[0]
        if base.startswith(_EXISTENCE_KINDS):
            lab, st = LAB_EX, dict(color=EXIST, ls="--", lw=1.1)
        elif base in _TRACED:
            lab, st = _TRACED[base]
        else:
            lab, st = LAB_ST, dict(color=FILL_EDGE, ls="-", lw=1.3)
        (ln,) = ax.plot(np.asarray(c.x, float), np.asarray(c.y, float), **st)
        proxy = line_proxy(marker="|", ms=5, **st) if lab == LAB_EX else line_proxy(**st)
        register(ax, ln, lab, proxy)


def _fill(ax, X, Y, mask, label, proxy, **kw):
    cs = ax.contourf(X, Y, mask.astype(float), levels=[0.5, 1.5], **kw)
    return register(ax, cs, label, proxy)


def _mark_limits(X, Y, mark, margin=0.06):
    """``(limits, inside)``: the axes limits of a panel over the grid ``X, Y`` and whether
    ``mark`` lies in the grid's box. A mark on or near the box's edge (the paper's gains
    at the lower corner of a box scaled by ``m2 = 100``) gets a margin on that side, so the
    whole star lies inside the axes."""
    x0, x1, y0, y1 = float(X[0, 0]), float(X[0, -1]), float(Y[0, 0]), float(Y[-1, 0])
    lims = [x0, x1, y0, y1]
    if mark is None:
        return lims, False
    inside = x0 <= mark[0] <= x1 and y0 <= mark[1] <= y1
    if inside:
        dx, dy = margin * (x1 - x0), margin * (y1 - y0)
        if mark[0] - x0 < dx:
            lims[0] = x0 - dx
        if x1 - mark[0] < dx:
            lims[1] = x1 + dx
        if mark[1] - y0 < dy:
            lims[2] = y0 - dy
        if y1 - mark[1] < dy:
            lims[3] = y1 + dy
    return lims, inside


def _panel(ax, X, Y, ex, st, *, curves=None, mark=None, title=None, outline=None,
           side_ticks=True, returns=None):
    from matplotlib.patches import Rectangle

    lims, mark_inside = _mark_limits(X, Y, mark)
    x0, x1, y0, y1 = float(X[0, 0]), float(X[0, -1]), float(Y[0, 0]), float(Y[-1, 0])
    margin = lims != [x0, x1, y0, y1]
    if margin:
        bg = Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor="white", edgecolor="none",
                       zorder=-10)
    else:
        bg = Rectangle((0, 0), 1, 1, transform=ax.transAxes, facecolor="white",
                       edgecolor="none", zorder=-10)
    ax.add_patch(bg)
    if (~ex).any():
        register(ax, bg, LAB_NONE, patch_proxy(facecolor="white", edgecolor="0.3", lw=0.6))
    unstable = ex & ~st
    if unstable.any():
        _fill(ax, X, Y, unstable, LAB_UNSTABLE,
              patch_proxy(facecolor="white", edgecolor=UNSTABLE_EDGE, hatch=UNSTABLE_HATCH,
                          lw=0.6),
              colors="none", hatches=[UNSTABLE_HATCH])
        for a in ax.collections[-1:]:
            a.set_edgecolor(UNSTABLE_EDGE)
            a.set_linewidth(0.0)
    if st.any():
        _fill(ax, X, Y, st, LAB_FILL, patch_proxy(facecolor=FILL, edgecolor=FILL_EDGE, lw=0.6),
              colors=[FILL])
    if returns is not None:
        _returns(ax, X, Y, ex, returns)
    if curves is None:
        if ex.any() and not ex.all() and side_ticks:
            _side_ticks(ax, X, Y, ex, EXIST, LAB_EX)
        elif ex.any() and not ex.all():
            cs = ax.contour(X, Y, ex.astype(float), levels=[0.5], colors=[EXIST],
                            linewidths=1.1, linestyles="--")
            register(ax, cs, "existence boundary", line_proxy(color=EXIST, ls="--", lw=1.1))
        if (st & ex).any() and (ex & ~st).any():
            # the stability boundary separates stable from unstable orbits: where the orbit
            # does not exist on one side the boundary is the existence one, drawn dashed
            cs = ax.contour(X, Y, np.ma.masked_where(~ex, st.astype(float)), levels=[0.5],
                            colors=[FILL_EDGE], linewidths=1.1)
            register(ax, cs, LAB_ST, line_proxy(color=FILL_EDGE, ls="-", lw=1.1))
    else:
        _draw_curves(ax, curves)
        if ex.any() and not ex.all():
            # the existing side still comes from the grid
            _side_ticks(ax, X, Y, ex, EXIST, LAB_EX, line=False)
    if outline is not None:
        x0, x1, y0, y1 = outline
        r = Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor="none", edgecolor="k", lw=1.0,
                      ls=":", zorder=4)
        ax.add_patch(r)
        register(ax, r, LAB_ZOOM, patch_proxy(facecolor="none", edgecolor="k", ls=":", lw=1.0))
    if mark_inside:
        # above everything drawn, never clipped; the limits keep it inside the axes
        (ln,) = ax.plot(*mark, marker="*", ms=10, color="#D55E00", mec="k", mew=0.9,
                        ls="none", zorder=MARK_ZORDER, clip_on=False)
        register(ax, ln, PAPER_GAINS, line_proxy(marker="*", ms=10, color="#D55E00",
                                                 mec="k", mew=0.9, ls="none"))
    if margin:
        # the margin that keeps the star inside the axes lies outside the computed box (added
        # last: its legend entry comes last)
        out = Rectangle((0, 0), 1, 1, transform=ax.transAxes, facecolor="0.9",
                        edgecolor=OUTSIDE_EDGE, hatch=OUTSIDE_HATCH, lw=0.0, zorder=-11)
        ax.add_patch(out)
        register(ax, out, LAB_OUTSIDE, patch_proxy(facecolor="0.9", edgecolor=OUTSIDE_EDGE,
                                                   hatch=OUTSIDE_HATCH, lw=0.6))
    ax.set_xlim(lims[0], lims[1])
    ax.set_ylim(lims[2], lims[3])
    if title:
        ax.set_title(title)


def _returns(ax, X, Y, ex, returns):
    """Cells whose orbit returns ``k > 1`` times per period: one hatch per ``k`` over the
    stable fill or unstable hatch, with a legend entry each."""
    k = np.where(ex, np.asarray(returns), 0)
    for i, kk in enumerate(int(v) for v in np.unique(k) if v > 1):
        hatch = RETURNS_HATCHES[i % len(RETURNS_HATCHES)]
        _fill(ax, X, Y, k == kk, f"k = {kk} returns per period",
              patch_proxy(facecolor="white", edgecolor=RETURNS_EDGE, hatch=hatch, lw=0.6),
              colors="none", hatches=[hatch])
        for a in ax.collections[-1:]:
            a.set_edgecolor(RETURNS_EDGE)
            a.set_linewidth(0.0)


def _certified_panel(ax, rm, k, title=True):
    """The certified classes of the cells of ``rm.certified[k]``: proved classes filled,
    undecided cells hatched in a neutral grey; each cell drawn as its box."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd._format import pct as _pct
    from hybridpd.pair.certified import cell_edges

    xe, ye = cell_edges(rm.x), cell_edges(rm.y)
    f = np.asarray(rm.certified[k])
    for code, (label, face) in CERTIFIED.items():
        if (f == code).any():
            m = ax.pcolormesh(xe, ye, np.ma.masked_where(f != code, np.ones(f.shape)),
                              cmap=_one_colour(face), vmin=0, vmax=1, shading="flat")
            register(ax, m, label, patch_proxy(facecolor=face, edgecolor="0.3", lw=0.6))
    if (f == 0).any():
        m = ax.pcolor(xe, ye, np.ma.masked_where(f != 0, np.ones(f.shape)),
                      cmap=_one_colour(UNDECIDED_FACE), vmin=0, vmax=1, hatch=UNDECIDED_HATCH,
                      edgecolor=UNDECIDED_EDGE, linewidth=0.0)
        register(ax, m, UNDECIDED, patch_proxy(facecolor=UNDECIDED_FACE, edgecolor=UNDECIDED_EDGE,
                                               hatch=UNDECIDED_HATCH, lw=0.6))
    ax.set_xlim(xe[0], xe[-1])
    ax.set_ylim(ye[0], ye[-1])
    if title:
        N = f.size
        ax.set_title(f"e = {rm.e[k]:g}: {_pct((f != 0).sum() / N)} of {N} cells proved\n"
                     f"stable/unstable/no orbit: {(f == 1).sum()}/{(f == 2).sum()}/"
                     f"{(f == 3).sum()}")


def _one_colour(face):
    from matplotlib.colors import ListedColormap

    return ListedColormap([face])


@styled
def plot_certified_panels(rm, *, params=None, title=None):
    """One panel per ``e``: the certified class of every grid point's cell.

    Proved stable, proved unstable and proved no orbit are filled (blue, orange, white);
    undecided cells are hatched in a neutral grey. Each cell is drawn as the box the proof
    covers (half-way to the neighbouring points; see
    :func:`hybridpd.pair.certified.cell_edges`).

    Parameters
    ----------
    rm : RegionMap
        With ``certified`` (``region_map(..., certify=True)``).
    params : dict, optional
        Caption parameters (default: from ``rm.fixed``).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    if getattr(rm, "certified", None) is None:
        raise ValueError("rm has no certified classes: make it with region_map(..., "
                         "certify=True)")
    ne = len(rm.e)
    fig = house_figure(DOUBLE, 3.4)
    axes = []
    for k in range(ne):
        ax = fig.add_subplot(1, ne, k + 1)
        _certified_panel(ax, rm, k)
        ax.set_xlabel(axis_label(rm.x_name))
        ax.set_ylabel(axis_label(rm.y_name) if k == 0 else "")
        axes.append(ax)
    legend_from_gids(fig, axes, ncol=4)
    head = title or f"{_CASE.get(rm.case, rm.case)} PD, certified"
    suptitle(fig, f"{head}: {param_line(params or _params_of(rm))}")
    return fig


@styled
def plot_region_panels(rm, *, zoom=None, curves=None, mark=None, params=None, title=None,
                       certified=None):
    """One panel per ``e`` (Figs 4-5): the stable region filled, boundaries marked.

    Parameters
    ----------
    rm : RegionMap
        Over ``(kp, kv)`` (any two axes work; labels use their names and units).
    zoom : RegionMap, optional
        Second row with the same ``e`` on a smaller box, outlined on the first row.
    curves : dict or list, optional
        Traced boundaries (objects with ``.kind``, ``.x``, ``.y``) drawn instead of the grid
        contours: a list (same for every panel of the first row), ``{e: list}``, or
        ``{(row, e): list}`` (row 1 is the zoom).
    mark : (x, y), optional
        Point marked with a star (e.g. the paper's gains ``(10, 20)``).
    params : dict, optional
        ``mu, gamma, omega, n, m2, x10`` for the caption (default: from ``rm.fixed``).
    title : str, optional
    certified : bool, optional
        Add a row with the certified class of every cell (proved classes filled, undecided
        hatched; see :func:`plot_certified_panels`). Default: when ``rm`` has certified
        classes and no ``zoom`` is given.

    Returns
    -------
    matplotlib.figure.Figure
        7.2 in wide (the house style).
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd._format import pct as _pct

    has_cert = getattr(rm, "certified", None) is not None
    if certified is None:
        certified = has_cert and zoom is None
    if certified and not has_cert:
        raise ValueError("certified=True needs a region map made with certify=True")
    if certified and zoom is not None:
        raise ValueError("draw either a zoom row or the certified row, not both")
    maps = [rm] + ([zoom] if zoom is not None else [])
    ne = len(rm.e)
    rows = len(maps) + (1 if certified else 0)
    fig = house_figure(DOUBLE, min(9.0, 2.45 * rows + 1.0))
    axes = []
    outline = None
    if zoom is not None:
        outline = (float(zoom.x[0]), float(zoom.x[-1]), float(zoom.y[0]), float(zoom.y[-1]))
    for row, m in enumerate(maps):
        X, Y = np.meshgrid(m.x, m.y)
        for k, e in enumerate(m.e):
            ax = fig.add_subplot(rows, ne, row * ne + k + 1)
            if isinstance(curves, dict):  # per e, or per (row, e) with a zoom row
                cv = curves.get((row, float(e)), curves.get(float(e)) if row == 0 else None)
            else:
                cv = curves if row == 0 else None
            fe, fs = m.fraction("exists")[k], m.fraction("stable")[k]
            _panel(ax, X, Y, m.exists[k], m.stable[k], curves=cv, mark=mark,
                   outline=outline if row == 0 else None, returns=m.returns()[k],
                   title=f"e = {e:g}{' (zoom)' if row else ''}: exists {_pct(fe)},\n"
                         f"exists and stable {_pct(fs)}")
            ax.set_xlabel(axis_label(m.x_name))
            ax.set_ylabel(axis_label(m.y_name) if k == 0 else "")
            axes.append(ax)
    if certified:
        for k in range(ne):
            ax = fig.add_subplot(rows, ne, len(maps) * ne + k + 1)
            _certified_panel(ax, rm, k)
            ax.set_xlabel(axis_label(rm.x_name))
            ax.set_ylabel(axis_label(rm.y_name) if k == 0 else "")
            axes.append(ax)
    legend_from_gids(fig, axes, ncol=3)
    head = title or _head(rm)
    if mark is not None and not any(a.get_gid() == PAPER_GAINS for ax in axes
                                    for a in ax.get_children()):
        head += f" (the point $k_p$ = {mark[0]:g}, $k_v$ = {mark[1]:g} lies outside the box)"
    line = _subject(rm) if params is None else param_line(params)
    suptitle(fig, f"{head}: {line}" if line else head)
    return fig


@styled
def plot_regions(rm, ax=None, title=None, curves=None):
    """All ``e`` on one axes: stable regions hatched, one colour, hatch and line style per
    ``e``.

    Without ``ax`` this returns :func:`plot_region_panels` (one panel per ``e``), which reads
    better in print. ``curves`` as in :func:`plot_region_panels` (one list for all ``e``).
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.plotting.style import HATCHES

    if ax is None:
        return plot_region_panels(rm, curves=curves, title=title)
    fig, ax = figure(ax)
    X, Y = np.meshgrid(rm.x, rm.y)
    for k, e in enumerate(rm.e):
        s = series(k)
        c, h = s["color"], HATCHES[1 + k % (len(HATCHES) - 1)]
        st = rm.stable[k].astype(float)
        lab = f"e = {e:g}: exists, stable"
        if st.any():
            cs = ax.contourf(X, Y, st, levels=[0.5, 1.5], colors="none", hatches=[h])
            set_all(cs, edgecolor=c)
            register(ax, cs, lab, patch_proxy(facecolor="white", edgecolor=c, hatch=h))
            ax.contour(X, Y, st, levels=[0.5], colors=[c], linewidths=1.1,
                       linestyles=[s["ls"]])
        if rm.exists[k].any() and not rm.exists[k].all():
            lab_e = f"e = {e:g}: exists on the ticked side"
            _side_ticks(ax, X, Y, rm.exists[k], c, lab_e, marker=s["marker"])
    if curves is not None:
        _draw_curves(ax, curves)
    _axes_legend(ax)
    ax.set_xlabel(axis_label(rm.x_name))
    ax.set_ylabel(axis_label(rm.y_name))
    ax.set_title(title or f"{_head(rm)}: {_subject(rm)}")
    return fig


def _head(rm) -> str:
    """The title's head: the pair's case and PD loop, or a model file and its controllers
    (named from the model, never assumed)."""
    model = rm.fixed.get("model")
    if model is None:
        return f"{_CASE.get(rm.case, rm.case)} PD"
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.plotting._common import model_title

    return model_title(model, rm.metadata)


def _subject(rm) -> str:
    """The pair's fixed parameters, or a model's section."""
    f = rm.fixed
    if f.get("model") is None:
        return param_line(_params_of(rm))
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.analysis.model_sections import section_words

    return "periodic orbits on the " + section_words(
        f.get("section_event", "impact"), f.get("section_contact", 0), f.get("section_wall"),
        f.get("section_phase"))


def _axes_legend(ax):
    """The gid legend of one axes, beside it (outside the data)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.plotting._common import legend_handles

    pairs = legend_handles([ax])
    if pairs:
        labels, handles = zip(*pairs)
        ax.legend(handles=list(handles), labels=list(labels), loc="upper left",
                  bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
