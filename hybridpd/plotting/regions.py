"""Region figures: Figs 4-5 (one panel per ``e``), the convention study and the mu/gamma studies.

Conventions of every figure here: the region where the orbit exists and is stable is filled;
the existence boundary is a dashed line with short ticks on the side where the orbit exists;
legend entries are built from the drawn artists (each drawn artist carries the legend label
as its ``gid``), and the legend sits outside the data; the parameters are stated on the
figure. ``curves=`` takes traced boundary curves (objects with ``.kind``, ``.x``, ``.y``) and
draws them instead of the grid contours.
"""
from __future__ import annotations

import numpy as np

from hybridpd.plotting._common import _COLORS, figure

__all__ = ["plot_m2_study", "plot_param_study", "plot_region_panels", "plot_regions"]

#: Colour-blind-safe colours (Okabe-Ito).
FILL = "#56B4E9"
FILL_EDGE = "#0072B2"
EXIST = "#000000"
VERDICT_COLORS = {"agrees": "#0072B2", "contradicted": "#E69F00", "depends": "#CC79A7",
                  "unresolved": "#BBBBBB"}
PAPER_GAINS = "paper's gains"
_CASE = {"collocated": "collocated", "noncollocated": "non-collocated"}


def param_line(params: dict) -> str:
    """``mu = .., gamma = .., omega = .., n = .., m2 = ..`` in mathtext."""
    parts = []
    for key, sym in (("mu", r"$\mu$"), ("gamma", r"$\gamma$"), ("omega", r"$\omega$"),
                     ("n", "$n$"), ("m2", "$m_2$"), ("x10", "$x_{10}$")):
        if key in params and params[key] is not None:
            parts.append(f"{sym} = {params[key]:g}")
    return ", ".join(parts)


def _params_of(rm) -> dict:
    f = rm.fixed
    out = {"mu": f.get("mu"), "omega": f.get("omega"), "n": f.get("n"), "m2": f.get("m2"),
           "x10": f.get("x10")}
    if "L" in f and "x10" in f:
        out["gamma"] = f["L"] / f["x10"]
    return out


def _tag(artist, label):
    artist.set_gid(label)
    return artist


def _tag_contour(cs, label):
    # ContourSet is a Collection in matplotlib >= 3.8 and a container of collections before
    for a in [cs, *getattr(cs, "collections", [])]:
        try:
            a.set_gid(label)
        except AttributeError:
            pass
    return cs


def _side_ticks(ax, X, Y, field, color, label, every=6, line=True):
    """Short ticks on the ``field > 0.5`` side of its 0.5 contour (the existing side); the
    dashed contour itself unless ``line`` is False (traced curves are drawn instead)."""
    from scipy.ndimage import gaussian_filter

    f = gaussian_filter(field.astype(float), 1.0)
    gy, gx = np.gradient(f)
    x, y = X[0], Y[:, 0]
    sx, sy = (x[-1] - x[0]), (y[-1] - y[0])
    cs = ax.contour(X, Y, field.astype(float), levels=[0.5], colors=[color], linewidths=1.2,
                    linestyles="--")
    _tag_contour(cs, label)
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
            d = g / gn * 0.018
            segs.append([(px, py), (px + d[0] * sx, py + d[1] * sy)])
    if segs:
        from matplotlib.collections import LineCollection

        ax.add_collection(_tag(LineCollection(segs, colors=[color], linewidths=1.0), label))
    return cs


#: Traced boundary kinds drawn like the existence boundary (the rest like stability's).
_EXISTENCE_KINDS = ("existence", "grazing", "viability", "xm_zero", "sticking")


#: Legend words for the traced kinds (the curves are drawn where they bound the shaded region).
_TRACED_LABELS = {
    "grazing": "grazing: the orbit stops existing (traced)",
    "existence": "existence boundary (traced)",
    "fold": "a multiplier crosses +1 (traced)",
    "period_doubling": "a multiplier crosses -1 (traced)",
    "neimark_sacker": "Neimark-Sacker: a complex pair crosses the unit circle (traced)",
}


#: Line styles of the stability kinds (colour-blind-safe, told apart by dash pattern too).
_TRACED_STYLES = {
    "fold": dict(color="#D55E00", ls="--", lw=1.5),
    "period_doubling": dict(color="#CC79A7", ls=":", lw=1.8),
    "neimark_sacker": dict(color="#0072B2", ls="-", lw=1.5),
}


def _draw_curves(ax, curves, labels):
    """Traced boundaries: existence-type kinds dashed black, the others solid blue."""
    for c in curves:
        kind = str(getattr(c, "kind", "boundary"))
        base = kind.split(":")[0]
        ex = base.startswith(_EXISTENCE_KINDS)
        st = dict(color=EXIST, ls="--", lw=1.2) if ex else dict(color=FILL_EDGE, ls="-", lw=1.4)
        if not ex and base in _TRACED_STYLES:
            st = _TRACED_STYLES[base]
        lab = labels.get(base, _TRACED_LABELS.get(base, f"{base.replace('_', ' ')} boundary"))
        ax.plot(np.asarray(c.x, float), np.asarray(c.y, float), gid=lab, **st)


def _panel(ax, X, Y, ex, st, *, curves=None, mark=None, title=None):
    lab_fill = "exists and stable"
    lab_ex = "existence boundary (ticks on the existing side)"
    lab_st = "stability boundary"
    if st.any():
        _tag_contour(ax.contourf(X, Y, st.astype(float), levels=[0.5, 1.5], colors=[FILL]),
                     lab_fill)
    if curves is None:
        if ex.any() and not ex.all():
            _side_ticks(ax, X, Y, ex, EXIST, lab_ex)
        if st.any() and not st.all():
            _tag_contour(ax.contour(X, Y, st.astype(float), levels=[0.5], colors=[FILL_EDGE],
                                    linewidths=1.2), lab_st)
    else:
        _draw_curves(ax, curves, {"existence": lab_ex, "stability": lab_st})
        if ex.any() and not ex.all():
            # the existing side still comes from the grid
            _side_ticks(ax, X, Y, ex, EXIST, lab_ex, line=False)
    if mark is not None:
        xl, yl = (X[0, 0], X[0, -1]), (Y[0, 0], Y[-1, 0])
        if xl[0] <= mark[0] <= xl[1] and yl[0] <= mark[1] <= yl[1]:
            ax.plot(*mark, marker="*", ms=12, color="#D55E00", mec="k", ls="none",
                    gid=PAPER_GAINS)
    ax.set_xlim(X[0, 0], X[0, -1])
    ax.set_ylim(Y[0, 0], Y[-1, 0])
    if title:
        ax.set_title(title, fontsize=9)


def _legend_from_gids(fig, axes, *, loc="outside lower center", ncol=4):
    """A figure legend whose entries are exactly the labelled artists drawn on ``axes``."""
    from matplotlib.collections import LineCollection
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    seen = {}
    for ax in axes:
        for a in ax.get_children():
            g = a.get_gid() if hasattr(a, "get_gid") else None
            if g and g not in seen:
                seen[g] = a
    handles = []
    for g, a in seen.items():
        if isinstance(a, Line2D):
            h = Line2D([], [], color=a.get_color(), ls=a.get_linestyle(), lw=a.get_linewidth(),
                       marker=a.get_marker(), ms=a.get_markersize(),
                       mfc=a.get_markerfacecolor(), mec=a.get_markeredgecolor())
        elif isinstance(a, LineCollection) or "boundary" in g:
            col = a.get_edgecolor()[0] if len(a.get_edgecolor()) else "k"
            ls = "--" if "existence" in g else "-"
            h = Line2D([], [], color=col, ls=ls, lw=1.2)
        else:
            fc = a.get_facecolor()
            if np.ndim(fc) == 2:  # a collection: its first colour, none if it is empty
                fc = fc[0] if len(fc) else "none"
            h = Patch(facecolor=fc, edgecolor=a.get_edgecolor()[0]
                      if np.ndim(a.get_edgecolor()) == 2 and len(a.get_edgecolor()) else "none",
                      hatch=a.get_hatch() if hasattr(a, "get_hatch") else None)
        h.set_label(g)
        handles.append(h)
    if handles:
        fig.legend(handles=handles, loc=loc, ncol=min(ncol, len(handles)), fontsize=8,
                   frameon=False)
    return [h.get_label() for h in handles]


def _axes_legend(ax):
    """The gid legend of one axes, beside it (outside the data)."""
    from matplotlib.figure import Figure

    tmp = Figure()
    labels = _legend_from_gids(tmp, [ax])
    if tmp.legends:
        handles = tmp.legends[0].legend_handles
        ax.legend(handles=handles, labels=labels, loc="upper left", bbox_to_anchor=(1.02, 1.0),
                  fontsize=7, frameon=False, borderaxespad=0.0)


def plot_region_panels(rm, *, zoom=None, curves=None, mark=None, params=None, title=None):
    """One panel per ``e`` (Figs 4-5): the stable region filled, boundaries marked.

    Parameters
    ----------
    rm : RegionMap
        Over ``(kp, kv)`` (any two axes work; labels use their names).
    zoom : RegionMap, optional
        Second row with the same ``e`` on a smaller box.
    curves : dict or list, optional
        Traced boundaries (objects with ``.kind``, ``.x``, ``.y``) drawn instead of the grid
        contours: a list (same for every panel of the first row), ``{e: list}``, or
        ``{(row, e): list}`` (row 1 is the zoom).
    mark : (x, y), optional
        Point marked with a star (e.g. the paper's gains ``(10, 20)``).
    params : dict, optional
        ``mu, gamma, omega, n, m2, x10`` for the caption (default: from ``rm.fixed``).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    maps = [rm] + ([zoom] if zoom is not None else [])
    ne = len(rm.e)
    fig = Figure(figsize=(4.2 * ne, 3.9 * len(maps) + 1.0), layout="constrained")
    axes = []
    for row, m in enumerate(maps):
        X, Y = np.meshgrid(m.x, m.y)
        for k, e in enumerate(m.e):
            ax = fig.add_subplot(len(maps), ne, row * ne + k + 1)
            if isinstance(curves, dict):  # per e, or per (row, e) with a zoom row
                cv = curves.get((row, float(e)), curves.get(float(e)) if row == 0 else None)
            else:
                cv = curves if row == 0 else None
            fe, fs = m.fraction("exists")[k], m.fraction("stable")[k]
            from hybridpd._format import pct as _pct

            _panel(ax, X, Y, m.exists[k], m.stable[k], curves=cv,
                   mark=mark, title=f"e = {e:g}{' (zoom)' if row else ''}\nexists {_pct(fe)}, "
                                    f"exists and stable {_pct(fs)}")
            ax.set_xlabel(_axis_label(m.x_name))
            ax.set_ylabel(_axis_label(m.y_name))
            axes.append(ax)
    _legend_from_gids(fig, axes)
    head = title or f"{_CASE.get(rm.case, rm.case)} PD"
    if mark is not None and not any(a.get_gid() == PAPER_GAINS for ax in axes
                                    for a in ax.get_children()):
        head += f" (the point $k_p$ = {mark[0]:g}, $k_v$ = {mark[1]:g} lies outside the box)"
    fig.suptitle(f"{head}: {param_line(params or _params_of(rm))}", fontsize=10)
    return fig


def _axis_label(name):
    return {"kp": "$k_p$", "kv": "$k_v$", "mu": r"$\mu$", "L": "$L$", "omega": r"$\omega$",
            "m2": "$m_2$", "x10": "$x_{10}$", "gamma": r"$\gamma$"}.get(name, name)


def plot_regions(rm, ax=None, title=None, curves=None):
    """All ``e`` on one axes: stable regions as hatched outlines, one colour per ``e``.

    Without ``ax`` this returns :func:`plot_region_panels` (one panel per ``e``), which reads
    better in print. ``curves`` as in :func:`plot_region_panels` (one list for all ``e``).
    """
    if ax is None:
        return plot_region_panels(rm, curves=curves, title=title)
    fig, ax = figure(ax)
    X, Y = np.meshgrid(rm.x, rm.y)
    hatches = ("//", "\\\\", "||", "--", "xx", "..")
    for k, e in enumerate(rm.e):
        c = _COLORS[k % len(_COLORS)]
        st = rm.stable[k].astype(float)
        lab = f"e = {e:g}: exists, stable"
        if st.any():
            cs = ax.contourf(X, Y, st, levels=[0.5, 1.5], colors="none",
                             hatches=[hatches[k % len(hatches)]])
            for a in [cs, *getattr(cs, "collections", [])]:
                try:
                    a.set_edgecolor(c)
                    a.set_gid(lab)
                except AttributeError:
                    pass
            _tag_contour(ax.contour(X, Y, st, levels=[0.5], colors=[c], linewidths=1.2), lab)
        if rm.exists[k].any() and not rm.exists[k].all():
            _side_ticks(ax, X, Y, rm.exists[k], c, f"e = {e:g}: exists on the ticked side")
    if curves is not None:
        _draw_curves(ax, curves, {})
    _axes_legend(ax)
    ax.set_xlabel(_axis_label(rm.x_name))
    ax.set_ylabel(_axis_label(rm.y_name))
    ax.set_title(title or f"{rm.case}: {param_line(_params_of(rm))}", fontsize=9)
    return fig


def plot_m2_study(study, *, m2_range=None, runs=()):
    """The convention study: spectral radius at the paper's gains against ``m2`` (interval
    ends marked) and each conclusion's verdict against ``m2``."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    fig = Figure(figsize=(11, 7.5), layout="constrained")
    gs = fig.add_gridspec(2, 2, height_ratios=[2.2, 1])
    for col, case in enumerate(("noncollocated", "collocated")):
        ax = fig.add_subplot(gs[0, col])
        for k, (key, rho) in enumerate(kv for kv in study.rho.items() if kv[0][0] == case):
            ax.loglog(study.rho_grid, rho, color=_COLORS[k], gid=f"e = {key[1]:g}")
            for iv in study.intervals[case][key[1]]:
                for end in (iv.lo, iv.hi):
                    if end.kind == "stability":
                        ax.plot(end.m2, 1.0, "o", color=_COLORS[k], mec="k", ms=6,
                                gid="interval end: a multiplier on the unit circle")
                    elif end.kind != "window":
                        ok = np.isfinite(rho)
                        y = np.interp(np.log(end.m2), np.log(study.rho_grid[ok]), rho[ok])
                        ax.plot(end.m2, y, "s", color=_COLORS[k], mec="k", ms=6,
                                gid=f"interval end: {end.kind} lost (grazing)"
                                if end.kind == "viability" else f"interval end: {end.kind}")
        ax.axhline(1.0, color="0.4", lw=0.8, ls=":", gid="spectral radius 1")
        for m in runs:
            ax.axvline(m, color="k", lw=1.0, ls="-.", gid="convention of the run")
        ax.set_xlabel("$m_2$")
        ax.set_ylabel("spectral radius of $DP$")
        ax.set_title(f"{_CASE[case]}, $k_p$ = 10, $k_v$ = 20 (no curve: no orbit)", fontsize=9)
    ax = fig.add_subplot(gs[1, :])
    names = ("agrees", "contradicted", "depends", "unresolved")
    ids = sorted(study.verdicts)
    lo = np.log10(study.grid[0])
    hi = np.log10(study.grid[-1])
    for row, k in enumerate(ids):
        grid = study.robust_grid if k == 5 else study.grid
        lg = np.log10(grid)
        edges = np.concatenate([[lo], (lg[1:] + lg[:-1]) / 2, [hi]])
        for j, v in enumerate(study.verdicts[k]):
            ax.barh(row, 10 ** edges[j + 1] - 10 ** edges[j], left=10 ** edges[j], height=0.8,
                    color=VERDICT_COLORS[v], edgecolor="white", gid=v)
    ax.set_xscale("log")
    ax.set_xlim(10 ** lo, 10 ** hi)
    ax.set_yticks(range(len(ids)), [f"conclusion {k}" for k in ids])
    ax.invert_yaxis()
    ax.set_xlabel("$m_2$ (gain box as printed in the paper)")
    ax.set_title("verdict against $m_2$", fontsize=9)
    present = {v for k in ids for v in study.verdicts[k]}
    _legend_from_gids(fig, fig.axes[:2], loc="outside right upper", ncol=1)
    ax.legend(handles=[Patch(color=VERDICT_COLORS[n], label=n) for n in names if n in present],
              loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8, frameon=False)
    fig.suptitle(r"Convention study: $\mu$ = 0.1, $\gamma$ = 0.75, $\omega$ = 5, $n$ = 1, "
                 "$m_2$ varied", fontsize=10)
    return fig


def plot_param_study(ps):
    """Shares of the gain box against ``mu`` or ``gamma`` and the (parameter, kv) maps."""
    from matplotlib.figure import Figure

    sym = {"mu": r"$\mu$", "gamma": r"$\gamma$"}[ps.name]
    ne = len(ps.e)
    fig = Figure(figsize=(4.2 * ne, 8.5), layout="constrained")
    outer = fig.add_gridspec(2, 1)
    top = outer[0].subgridspec(1, len(ps.fractions))
    gs = outer[1].subgridspec(1, ne)
    b = ps.box
    axes = []
    for i, (case, q) in enumerate(ps.fractions.items()):
        ax = fig.add_subplot(top[0, i])
        for k, e in enumerate(ps.e):
            ax.semilogx(ps.values, 100 * q["both"][k], color=_COLORS[k],
                        gid=f"e = {e:g}: exists and stable")
            ax.semilogx(ps.values, 100 * q["exists"][k], color=_COLORS[k], ls=":",
                        gid=f"e = {e:g}: exists")
        ax.set_xlabel(sym)
        ax.set_ylabel("% of the gain box")
        ax.set_title(f"{_CASE[case]}: gain box $k_p$ in [{b['kp'][0]:g}, {b['kp'][1]:g}], "
                     f"$k_v$ in [{b['kv'][0]:g}, {b['kv'][1]:g}]", fontsize=9)
        axes.append(ax)
    for k, e in enumerate(ps.e):
        a = fig.add_subplot(gs[0, k])
        V, KV = np.meshgrid(ps.values, ps.map_kv)
        c, n = ps.maps["collocated"]["stable"][k], ps.maps["noncollocated"]["stable"][k]
        if c.any():
            _tag_contour(a.contourf(V, KV, c.astype(float), levels=[0.5, 1.5], colors=[FILL]),
                         "collocated: exists and stable")
        if n.any():
            cs = a.contourf(V, KV, n.astype(float), levels=[0.5, 1.5], colors="none",
                            hatches=["////"])
            for art in [cs, *getattr(cs, "collections", [])]:
                try:
                    art.set_edgecolor("#D55E00")
                    art.set_gid("non-collocated: exists and stable (hatched)")
                except AttributeError:
                    pass
        a.set_xscale("log")
        a.set_xlabel(sym)
        a.set_ylabel("$k_v$")
        a.set_title(f"e = {e:g}, $k_p$ = {ps.map_kp:g}", fontsize=9)
        axes.append(a)
    _legend_from_gids(fig, axes, ncol=4)
    fx = dict(ps.fixed)
    fig.suptitle(f"Regions against {sym}: {param_line(fx)}", fontsize=10)
    return fig
