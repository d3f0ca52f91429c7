"""Figures of the reproduction's studies, in the house style (:mod:`hybridpd.plotting.style`).

* :func:`plot_m2_study` — spectral radius at the paper's gains against ``m2`` and each
  conclusion's verdict against ``m2``;
* :func:`plot_param_study` — shares of the gain box against ``mu`` or ``gamma`` and the
  ``(parameter, kv)`` maps;
* :func:`plot_scaled_regions` — Figs 4-5 once for every ``m2``, in the scaled gains
  ``(kp/m2, kv/m2)``, with the paper's gains as the ray ``(10/m2, 20/m2)``;
* :func:`plot_rho_along_m2` — the spectral radius of one orbit along ``m2`` (what a basin panel
  with no stable orbit shows instead).
"""
from __future__ import annotations

import numpy as np

from hybridpd.plotting._common import legend_from_gids, line_proxy, patch_proxy, register, set_all
from hybridpd.plotting.style import DOUBLE, axis_label, house_figure, series, styled

__all__ = ["VERDICT_STYLES", "plot_m2_study", "plot_param_study", "plot_rho_along_m2",
           "plot_scaled_regions"]

#: Fill colour and hatch of each verdict (never colour alone).
VERDICT_STYLES = {"agrees": dict(color="#0072B2", hatch=""),
                  "contradicted": dict(color="#E69F00", hatch="xxx"),
                  "depends": dict(color="#CC79A7", hatch="///"),
                  "unresolved": dict(color="#DDDDDD", hatch="...")}
_CASE = {"collocated": "collocated", "noncollocated": "non-collocated"}


def _e_line(ax, x, y, k, label, **kw):
    s = series(k)
    n = max(1, len(x) // 8)
    (ln,) = ax.plot(x, y, color=s["color"], ls=s["ls"], marker=s["marker"], markevery=n,
                    ms=3.5, **kw)
    register(ax, ln, label, line_proxy(color=s["color"], ls=s["ls"], marker=s["marker"],
                                       ms=3.5))
    return ln


def _rho_panel(ax, study, case, runs):
    for k, e in enumerate(sorted({key[1] for key in study.rho if key[0] == case})):
        rho = study.rho[(case, e)]
        _e_line(ax, study.rho_grid, rho, k, f"e = {e:g}")
        for iv in study.intervals[case][e]:
            for end in (iv.lo, iv.hi):
                if end.kind == "window":
                    continue
                ok = np.isfinite(rho)
                y = 1.0 if end.kind == "stability" else float(
                    np.interp(np.log(end.m2), np.log(study.rho_grid[ok]), rho[ok]))
                lab = ("interval end: a multiplier on the unit circle"
                       if end.kind == "stability" else "interval end: existence lost")
                mk = "o" if end.kind == "stability" else "s"
                (ln,) = ax.plot(end.m2, y, mk, mfc="white", mec="k", ms=5, zorder=5)
                register(ax, ln, lab, line_proxy(marker=mk, mfc="white", mec="k", ms=5,
                                                 ls="none"))
    ln = ax.axhline(1.0, color="0.4", lw=0.8, ls=":")
    register(ax, ln, "spectral radius 1", line_proxy(color="0.4", lw=0.8, ls=":"))
    for m in runs:
        ln = ax.axvline(m, color="k", lw=0.9, ls=(0, (6, 2)))
        register(ax, ln, "conventions of the run", line_proxy(color="k", lw=0.9,
                                                             ls=(0, (6, 2))))
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(axis_label("m2"))
    ax.set_ylabel("spectral radius of $DP$ (1)")


@styled
def plot_m2_study(study, *, m2_range=None, runs=()):
    """The convention study: spectral radius at the paper's gains against ``m2`` (interval
    ends marked) and each conclusion's verdict against ``m2`` (7.2 in wide)."""
    fig = house_figure(DOUBLE, 5.6)
    gs = fig.add_gridspec(2, 2, height_ratios=[2.0, 1])
    axes = []
    for col, case in enumerate(("noncollocated", "collocated")):
        ax = fig.add_subplot(gs[0, col])
        _rho_panel(ax, study, case, runs)
        ax.set_title(f"{_CASE[case]}, $k_p$ = 10, $k_v$ = 20 (no line: no orbit)")
        axes.append(ax)
    ax = fig.add_subplot(gs[1, :])
    ids = sorted(study.verdicts)
    lo, hi = np.log10(study.grid[0]), np.log10(study.grid[-1])
    for row, k in enumerate(ids):
        grid = study.robust_grid if k == 5 else study.grid
        lg = np.log10(grid)
        edges = np.concatenate([[lo], (lg[1:] + lg[:-1]) / 2, [hi]])
        for j, v in enumerate(study.verdicts[k]):
            st = VERDICT_STYLES[v]
            bars = ax.barh(row, 10 ** edges[j + 1] - 10 ** edges[j], left=10 ** edges[j],
                           height=0.8, color=st["color"], hatch=st["hatch"], edgecolor="white",
                           lw=0.5)
            register(ax, bars, v, patch_proxy(facecolor=st["color"], hatch=st["hatch"],
                                              edgecolor="0.3", lw=0.5))
    ax.set_xscale("log")
    ax.set_xlim(10 ** lo, 10 ** hi)
    ax.set_yticks(range(len(ids)), [f"conclusion {k}" for k in ids])
    ax.invert_yaxis()
    ax.set_xlabel(axis_label("m2") + ", gain box as printed in the paper")
    ax.set_title("verdict against $m_2$ (run grid)")
    axes.append(ax)
    legend_from_gids(fig, axes, ncol=4)
    fig.suptitle(r"Convention study: $\mu$ = 0.1, $\gamma$ = 0.75, $\omega$ = 5, $n$ = 1, "
                 "$m_2$ varied")
    return fig


@styled
def plot_param_study(ps):
    """Shares of the gain box against ``mu`` or ``gamma`` and the (parameter, kv) maps
    (7.2 in wide)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.plotting._common import param_line

    name = ps.name
    ne = len(ps.e)
    fig = house_figure(DOUBLE, 5.8)
    outer = fig.add_gridspec(2, 1, height_ratios=[1.15, 1])
    top = outer[0].subgridspec(1, len(ps.fractions))
    gs = outer[1].subgridspec(1, ne)
    b = ps.box
    axes = []
    for i, (case, q) in enumerate(ps.fractions.items()):
        ax = fig.add_subplot(top[0, i])
        for k, e in enumerate(ps.e):
            s = series(k)
            n = max(1, len(ps.values) // 8)
            for quantity, ls, lab in (("both", "-", "exists and stable"),
                                      ("exists", ":", "exists")):
                (ln,) = ax.semilogx(ps.values, 100 * q[quantity][k], color=s["color"], ls=ls,
                                    marker=s["marker"], markevery=n, ms=3.5,
                                    mfc=s["color"] if ls == "-" else "white")
                register(ax, ln, f"e = {e:g}: {lab}",
                         line_proxy(color=s["color"], ls=ls, marker=s["marker"], ms=3.5,
                                    mfc=s["color"] if ls == "-" else "white"))
        ax.set_xlabel(axis_label(name))
        ax.set_ylabel("share of the gain box (%)")
        ax.set_title(f"{_CASE[case]}: $k_p$ in [{b['kp'][0]:g}, {b['kp'][1]:g}], "
                     f"$k_v$ in [{b['kv'][0]:g}, {b['kv'][1]:g}]\n"
                     f"({b['kp'][2]} x {b['kv'][2]} grid)")
        axes.append(ax)
    for k, e in enumerate(ps.e):
        a = fig.add_subplot(gs[0, k])
        V, KV = np.meshgrid(ps.values, ps.map_kv)
        c, n = ps.maps["collocated"]["stable"][k], ps.maps["noncollocated"]["stable"][k]
        if c.any():
            cs = a.contourf(V, KV, c.astype(float), levels=[0.5, 1.5], colors=["#56B4E9"])
            register(a, cs, "collocated: exists and stable",
                     patch_proxy(facecolor="#56B4E9", edgecolor="#0072B2"))
        if n.any():
            cs = a.contourf(V, KV, n.astype(float), levels=[0.5, 1.5], colors="none",
                            hatches=["////"])
            set_all(cs, edgecolor="#D55E00")
            register(a, cs, "non-collocated: exists and stable (hatched)",
                     patch_proxy(facecolor="white", edgecolor="#D55E00", hatch="////"))
        a.set_xscale("log")
        a.set_xlabel(axis_label(name))
        a.set_ylabel(axis_label("kv") if k == 0 else "")
        a.set_title(f"e = {e:g}, $k_p$ = {ps.map_kp:g}")
        axes.append(a)
    legend_from_gids(fig, axes, ncol=3)
    sym = {"mu": r"$\mu$", "gamma": r"$\gamma$"}[name]
    fig.suptitle(f"Regions against {sym}: {param_line(dict(ps.fixed))}")
    return fig


def plot_rho_along_m2(ax, m2_grid, rho, *, m2, k=0, label="this orbit"):
    """Spectral radius of one orbit along ``m2`` on ``ax``, the current ``m2`` marked: what
    a basin panel with no stable orbit shows instead of an empty slice."""
    _e_line(ax, m2_grid, rho, k, label)
    ln = ax.axhline(1.0, color="0.4", lw=0.8, ls=":")
    register(ax, ln, "spectral radius 1", line_proxy(color="0.4", lw=0.8, ls=":"))
    ln = ax.axvline(m2, color="k", lw=0.9, ls=(0, (6, 2)))
    register(ax, ln, "this figure's $m_2$", line_proxy(color="k", lw=0.9, ls=(0, (6, 2))))
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(axis_label("m2"))
    ax.set_ylabel("spectral radius of $DP$ (1)")
    return ax


@styled
def plot_scaled_regions(sm, *, ray=None, zoom=None, params=None, title=None):
    """Figs 4-5 for every ``m2``: the regions in ``(kp/m2, kv/m2)`` on log axes, one panel
    per ``e``.

    Parameters
    ----------
    sm : object
        ``x``, ``y`` (the scaled gains ``kp/m2``, ``kv/m2``, log-spaced), ``e``,
        ``exists``/``stable`` (bool, shape ``(len(e), len(y), len(x))``) and ``case``.
    ray : dict, optional
        The paper's gains along ``m2``: ``{"kp": 10, "kv": 20, "m2": ndarray, "events":
        {e: [(m2, "exists" | "stable")]}}``; drawn as the line ``(kp/m2, kv/m2)`` with the
        ``m2`` decades marked and, per panel, the ``m2`` where the orbit starts to exist or
        to be stable (increasing ``m2``).
    zoom : (kp_max, kv_max), optional
        The zoom window of Fig. 5 (scaled gains, from the box's lower corner) to outline.
    params : dict, optional
        For the caption (``m2`` is left out: the figure holds for every ``m2``).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        7.2 in wide.
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.plotting._common import param_line
    from hybridpd.plotting.regions import _panel

    x, y = np.asarray(sm.x, float), np.asarray(sm.y, float)
    X, Y = np.meshgrid(x, y)
    ne = len(sm.e)
    fig = house_figure(DOUBLE, 3.7)
    axes = []
    for k, e in enumerate(sm.e):
        ax = fig.add_subplot(1, ne, k + 1)
        _panel(ax, X, Y, sm.exists[k], sm.stable[k], side_ticks=False, title=f"e = {e:g}")
        if zoom is not None:
            from matplotlib.patches import Rectangle

            r = Rectangle((x[0], y[0]), zoom[0] - x[0], zoom[1] - y[0], facecolor="none",
                          edgecolor="k", ls=":", lw=1.0, zorder=4)
            ax.add_patch(r)
            register(ax, r, "zoom window of Fig. 5",
                     patch_proxy(facecolor="none", edgecolor="k", ls=":", lw=1.0))
        if ray is not None:
            _ray(ax, ray, float(e), x, y)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(x[0], x[-1])
        ax.set_ylim(y[0], y[-1])
        ax.set_xlabel(axis_label("kp/m2"))
        ax.set_ylabel(axis_label("kv/m2") if k == 0 else "")
        axes.append(ax)
    legend_from_gids(fig, axes, ncol=3)
    head = title or f"{_CASE.get(sm.case, sm.case)} PD in scaled gains, valid for every $m_2$"
    par = dict(params or {})
    par.pop("m2", None)
    fig.suptitle(f"{head}: {param_line(par)}")
    return fig


def _ray(ax, ray, e, x, y):
    m = np.asarray(ray["m2"], float)
    kx, ky = ray["kp"] / m, ray["kv"] / m
    inside = (kx >= x[0]) & (kx <= x[-1]) & (ky >= y[0]) & (ky <= y[-1])
    ray_ls = (0, (10, 2))
    (ln,) = ax.plot(np.where(inside, kx, np.nan), np.where(inside, ky, np.nan), color="k",
                    lw=1.0, ls=ray_ls, zorder=6)
    register(ax, ln, r"paper's gains $(10/m_2, 20/m_2)$",
             line_proxy(color="k", lw=1.0, ls=ray_ls))
    for dec in (0.1, 1, 10, 100, 1000):
        px, py = ray["kp"] / dec, ray["kv"] / dec
        if x[0] <= px <= x[-1] and y[0] <= py <= y[-1]:
            (pt,) = ax.plot(px, py, "|", color="k", ms=6, mew=1.0, zorder=7)
            register(ax, pt, "$m_2$ = 0.1, 1, 10, 100, 1000 (mass)",
                     line_proxy(color="k", marker="|", ms=6, mew=1.0, ls="none"))
            ax.annotate(f"{dec:g}", (px, py), textcoords="offset points", xytext=(3, -9),
                        fontsize=7)
    for m2, what in ray.get("events", {}).get(e, ()):
        px, py = ray["kp"] / m2, ray["kv"] / m2
        if not (x[0] <= px <= x[-1] and y[0] <= py <= y[-1]):
            continue
        mk, lab = (("o", "orbit starts to be stable (increasing $m_2$)") if what == "stable"
                   else ("s", "orbit starts to exist (increasing $m_2$)"))
        (pt,) = ax.plot(px, py, mk, mfc="white", mec="k", ms=5, zorder=8)
        register(ax, pt, lab, line_proxy(marker=mk, mfc="white", mec="k", ms=5, ls="none"))
        ax.annotate(f"{m2:.3g}", (px, py), textcoords="offset points", xytext=(4, 3),
                    fontsize=7)
