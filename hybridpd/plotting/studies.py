"""Figures of the reproduction's studies, in the house style (:mod:`hybridpd.plotting.style`).

* :func:`plot_m2_study` — spectral radius at the paper's gains against ``m2`` and each
  claim's verdict on the printed gain box at the values of ``m2`` where it was computed;
* :func:`plot_param_study` — shares of the gain box against ``mu`` or ``gamma`` (existence and
  existence with stability each on its own axis, certified intervals where given) and the
  ``(parameter, kv)`` maps;
* :func:`plot_scaled_regions` — Figs 4-5 once for every ``m2``, in the scaled gains
  ``(kp/m2, kv/m2)``, with the paper's gains as the ray ``(10/m2, 20/m2)``;
* :func:`plot_rho_along_m2` — the spectral radius of one orbit along ``m2`` (what a basin panel
  with no stable orbit shows instead).

Their texts carry no sub- or superscripts (mathtext draws them at 70 % of the font size,
under the 7 pt minimum) and log axes are labelled with plain numbers.
"""
from __future__ import annotations

import numpy as np

from hybridpd.plotting._common import (
    legend_from_gids,
    legend_handles,
    line_proxy,
    patch_proxy,
    register,
    set_all,
)
from hybridpd.plotting.style import DOUBLE, house_figure, series, styled

__all__ = ["LABELS", "VERDICT_STYLES", "plot_m2_study", "plot_param_study",
           "plot_rho_along_m2", "plot_scaled_regions"]

#: Marker, colour and fill of each verdict (shape and fill differ, never colour alone).
VERDICT_STYLES = {"agrees": dict(color="#0072B2", marker="o", mfc="#0072B2"),
                  "contradicted": dict(color="#D55E00", marker="X", mfc="#D55E00"),
                  "unresolved": dict(color="0.35", marker="s", mfc="white"),
                  "split": dict(color="#CC79A7", marker="D", mfc="white")}
#: Hatch of an exactly known verdict interval, per verdict.
_EXACT_HATCH = {"agrees": "", "contradicted": "xxx", "unresolved": "...", "split": "///"}
#: Axis labels with units, in plain text.
LABELS = {"m2": "m2 (mass)", "kp/m2": "kp/m2 (1/time^2)", "kv/m2": "kv/m2 (1/time)",
          "kv": "kv (force·time/length)", "mu": "μ = m1/m2 (1)", "gamma": "γ = L/x10 (1)",
          "rho": "spectral radius of DP (1)", "share": "share of the gain box (%)"}
_CASE = {"collocated": "collocated", "noncollocated": "non-collocated"}


def _plain_log(ax, which="xy"):
    """Plain numbers (0.1, 1, 10) on the log axes ``which``, no ``10^k`` superscripts."""
    from matplotlib.ticker import FuncFormatter, NullFormatter

    for w in which:
        axis = ax.xaxis if w == "x" else ax.yaxis
        axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        axis.set_minor_formatter(NullFormatter())


def _param_text(params: dict) -> str:
    names = (("mu", "μ"), ("gamma", "γ"), ("omega", "ω"), ("n", "n"), ("m2", "m2"),
             ("x10", "x10"))
    return ", ".join(f"{sym} = {params[k]:g}" for k, sym in names if params.get(k) is not None)


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
        register(ax, ln, "m2 of the figures", line_proxy(color="k", lw=0.9, ls=(0, (6, 2))))
    ax.set_xscale("log")
    vals = np.concatenate([np.asarray(v, float)[np.isfinite(v)] for (c, _), v in
                           study.rho.items() if c == case] + [np.array([1.0])])
    if vals.max() / max(vals.min(), 1e-300) > 20:
        ax.set_yscale("log")
        _plain_log(ax)
    else:
        # a narrow range: a log axis would label one tick in it
        _plain_log(ax, "x")
    ax.set_xlabel(LABELS["m2"])
    ax.set_ylabel(LABELS["rho"])


def _reading_rows(readings) -> list:
    """``[(row label, runs, criterion)]``: one row per conclusion, one per criterion of a
    claim read under two criteria (labelled a, b; the criteria are named in the key)."""
    rows = []
    for key, runs in readings.items():
        if isinstance(runs, dict):
            for k, (crit, r) in enumerate(runs.items()):
                rows.append((f"{key}, criterion {'ab'[k]}", r, crit))
        else:
            rows.append((f"conclusion {key}", runs, None))
    return rows


def _verdict_panel(ax, readings, m2_range):
    rows = _reading_rows(readings)
    for row, (label, runs, _) in enumerate(rows):
        for r in runs:
            st = VERDICT_STYLES[r["verdict"]]
            if r.get("exact"):
                from matplotlib.patches import Rectangle

                lo, hi = r["m2"]
                patch = Rectangle((lo, row - 0.22), hi - lo, 0.44, facecolor="white",
                                  edgecolor=st["color"], hatch=_EXACT_HATCH[r["verdict"]],
                                  lw=0.8, zorder=4)
                ax.add_patch(patch)
                register(ax, patch, f"{r['verdict']} on the whole bar (its ends located exactly)",
                         patch_proxy(facecolor="white", edgecolor=st["color"],
                                     hatch=_EXACT_HATCH[r["verdict"]], lw=0.8))
                continue
            xs = np.asarray(r["computed"], float)
            (ln,) = ax.plot(xs, np.full(xs.size, row), ls="none", marker=st["marker"],
                            color=st["color"], mfc=st["mfc"], mec=st["color"], ms=6,
                            zorder=5)
            register(ax, ln, f"{r['verdict']} at this m2 (computed here only)",
                     line_proxy(ls="none", marker=st["marker"], color=st["color"],
                                mfc=st["mfc"], mec=st["color"], ms=6))
    ax.set_xscale("log")
    _plain_log(ax, "x")
    if m2_range is not None:
        ax.set_xlim(m2_range[0] / 1.6, m2_range[1] * 1.6)
    ax.set_ylim(len(rows) - 0.5, -0.5)
    ax.set_yticks(range(len(rows)), [lab for lab, _, _ in rows])
    ax.grid(axis="x", color="0.85", lw=0.5)
    ax.set_xlabel(LABELS["m2"] + ": the paper's gain box read at this secondary mass")


@styled
def plot_m2_study(study, *, readings, m2_range=None, runs=()):
    """The convention study (7.2 in wide): spectral radius at the paper's gains against
    ``m2`` (interval ends marked), and each claim's verdict on the printed gain box.

    Parameters
    ----------
    study : M2Study
    readings : dict
        ``{claim: runs}`` (:func:`hybridpd.reproduce.rules.m2_readings`; ``{criterion:
        runs}`` for a claim with two criteria). A verdict is drawn as a marker at each
        computed ``m2`` (nothing is claimed between them), or as a hatched bar over an
        interval whose ends are located bifurcation points (``"exact"`` runs).
    m2_range : (lo, hi), optional
    runs : sequence of float
        The ``m2`` of the figures, marked.
    """
    rows = _reading_rows(readings)
    fig = house_figure(DOUBLE, min(8.6, 5.2 + 0.2 * len(rows)))
    gs = fig.add_gridspec(3, 2, height_ratios=[2.0, 0.25 + 0.16 * len(rows), 0.5])
    axes = []
    for col, case in enumerate(("noncollocated", "collocated")):
        ax = fig.add_subplot(gs[0, col])
        _rho_panel(ax, study, case, runs)
        ax.set_title(f"{_CASE[case]}, kp = 10, kv = 20\n(no line: no orbit)")
        axes.append(ax)
    ax = fig.add_subplot(gs[1, :])
    _verdict_panel(ax, readings, m2_range)
    ax.set_title("each claim's verdict on the gain box as printed, read at m2")
    legend_from_gids(fig, axes, ncol=3)
    # the verdicts' own key, under their panel: what a marker and a bar mean
    key = fig.add_subplot(gs[2, :])
    key.set_axis_off()
    pairs = legend_handles([ax])
    crit = [f"{lab}: {c}" for lab, _, c in rows if c is not None]
    if pairs:
        labels, handles = zip(*pairs)
        key.legend(list(handles), list(labels), loc="upper center", ncol=2,
                   title="verdict key" + ("\n" + "; ".join(crit) if crit else ""),
                   frameon=False)
    fig.suptitle("Convention study: μ = 0.1, γ = 0.75, ω = 5, n = 1, m2 varied")
    return fig


def _cert_bars(ax, points, k, e_count):
    """Certified intervals ``{p: [(lo, hi) per e]}`` of series ``k`` as vertical bars, the
    series' markers at both ends (offset along the log axis so that the ``e`` stay apart)."""
    s = series(k)
    shift = 10 ** (0.06 * (k - (e_count - 1) / 2))
    for p, ivs in sorted(points.items()):
        iv = ivs[k]
        if iv is None:
            continue
        x = p * shift
        (ln,) = ax.plot([x, x], [100 * iv[0], 100 * iv[1]], color=s["color"], ls="-", lw=1.6,
                        marker="_", ms=7, mew=1.6, zorder=6)
        register(ax, ln, "certified interval (decides the remark)",
                 line_proxy(color="0.2", ls="-", lw=1.6, marker="_", ms=7, mew=1.6))


@styled
def plot_param_study(ps, *, certified=None):
    """Shares of the gain box against ``mu`` or ``gamma`` and the (parameter, kv) maps
    (7.2 in wide).

    Existence and existence with stability are drawn on separate axes per case, each scaled
    to its own values, so that a share of a few percent is read on a few-percent axis.

    Parameters
    ----------
    ps : ParamStudy
    certified : dict, optional
        ``{"exists" | "exists_stable": {case: {value: [(lo, hi) per e]}}}``: certified
        intervals drawn as bars at their parameter values.
    """
    name = ps.name
    ne = len(ps.e)
    fig = house_figure(DOUBLE, 6.9)
    outer = fig.add_gridspec(2, 1, height_ratios=[1.5, 1])
    top = outer[0].subgridspec(2, len(ps.fractions))
    gs = outer[1].subgridspec(1, ne)
    b = ps.box
    axes = []
    xs = [float(v) for v in ps.values]
    if certified:
        xs += [float(p) for q in certified.values() for d in q.values() for p in d]
    xlim = (min(xs) / 1.8, max(xs) * 1.8)
    for i, (case, q) in enumerate(ps.fractions.items()):
        for j, (quantity, what) in enumerate((("exists", "exists"),
                                              ("both", "exists and stable"))):
            ax = fig.add_subplot(top[j, i])
            top_val = 0.0
            for k, e in enumerate(ps.e):
                y = 100 * np.asarray(q[quantity][k], float)
                _e_line(ax, ps.values, y, k, f"e = {e:g} (sampled grid)")
                top_val = max(top_val, float(np.nanmax(y)))
                pts = (certified or {}).get("exists" if quantity == "exists"
                                            else "exists_stable", {}).get(case)
                if pts:
                    _cert_bars(ax, pts, k, ne)
                    top_val = max(top_val, max(100 * iv[k][1] for iv in pts.values()
                                               if iv[k] is not None))
            ax.set_xscale("log")
            _plain_log(ax, "x")
            ax.set_xlim(*xlim)
            ax.set_ylim(0, max(1.0, 1.08 * top_val))
            ax.set_xlabel(LABELS[name] if j else "")
            ax.set_ylabel(f"{what} (%)")
            if j == 0:
                ax.set_title(f"{_CASE[case]}: share of kp/m2, kv/m2 in [{b['kp'][0]:g}, "
                             f"{b['kp'][1]:g}]\n(lines: {b['kp'][2]} x {b['kv'][2]} grid "
                             "points)")
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
        _plain_log(a, "x")
        a.set_xlabel(LABELS[name])
        a.set_ylabel(LABELS["kv"] if k == 0 else "")
        a.set_title(f"e = {e:g}, kp = {ps.map_kp:g}")
        axes.append(a)
    legend_from_gids(fig, axes, ncol=3)
    sym = {"mu": "μ", "gamma": "γ"}[name]
    fig.suptitle(f"Regions against {sym}: {_param_text(dict(ps.fixed))}")
    return fig


def plot_rho_along_m2(ax, m2_grid, rho, *, m2, k=0, label="this orbit"):
    """Spectral radius of one orbit along ``m2`` on ``ax``, the current ``m2`` marked: what
    a basin panel with no stable orbit shows instead of an empty slice."""
    _e_line(ax, m2_grid, rho, k, label)
    ln = ax.axhline(1.0, color="0.4", lw=0.8, ls=":")
    register(ax, ln, "spectral radius 1", line_proxy(color="0.4", lw=0.8, ls=":"))
    ln = ax.axvline(m2, color="k", lw=0.9, ls=(0, (6, 2)))
    register(ax, ln, "this figure's m2", line_proxy(color="k", lw=0.9, ls=(0, (6, 2))))
    ax.set_xscale("log")
    ax.set_yscale("log")
    _plain_log(ax)
    ax.set_xlabel(LABELS["m2"])
    ax.set_ylabel(LABELS["rho"])
    return ax


@styled
def plot_scaled_regions(sm, *, ray=None, zoom=None, box=None, params=None, title=None):
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
    box : (kp_min, kp_max, kv_min, kv_max), optional
        The scaled box of the certified verdicts, outlined.
    params : dict, optional
        For the caption (``m2`` is left out: the figure holds for every ``m2``).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        7.2 in wide.
    """
    # deferred import: loaded only when this runs, for start-up time
    from matplotlib.patches import Rectangle

    from hybridpd.plotting.regions import _panel

    x, y = np.asarray(sm.x, float), np.asarray(sm.y, float)
    X, Y = np.meshgrid(x, y)
    ne = len(sm.e)
    fig = house_figure(DOUBLE, 3.9)
    axes = []
    for k, e in enumerate(sm.e):
        ax = fig.add_subplot(1, ne, k + 1)
        _panel(ax, X, Y, sm.exists[k], sm.stable[k], side_ticks=False, title=f"e = {e:g}")
        if box is not None:
            # dash-dotted: a hollow box with a solid edge would read as "no orbit" in the key
            box_ls = (0, (6, 1.5, 1.5, 1.5))
            r = Rectangle((box[0], box[2]), box[1] - box[0], box[3] - box[2], facecolor="none",
                          edgecolor="0.3", ls=box_ls, lw=1.4, zorder=4)
            ax.add_patch(r)
            register(ax, r, f"box of the certified verdicts ([{box[0]:g}, {box[1]:g}] squared)",
                     patch_proxy(facecolor="none", edgecolor="0.3", ls=box_ls, lw=1.4))
        if zoom is not None:
            r = Rectangle((x[0], y[0]), zoom[0] - x[0], zoom[1] - y[0], facecolor="none",
                          edgecolor="k", ls=":", lw=1.0, zorder=4)
            ax.add_patch(r)
            register(ax, r, "zoom window of Fig. 5",
                     patch_proxy(facecolor="none", edgecolor="k", ls=":", lw=1.0))
        if ray is not None:
            _ray(ax, ray, float(e), x, y)
        ax.set_xscale("log")
        ax.set_yscale("log")
        _plain_log(ax)
        ax.set_xlim(x[0], x[-1])
        ax.set_ylim(y[0], y[-1])
        ax.set_xlabel(LABELS["kp/m2"])
        ax.set_ylabel(LABELS["kv/m2"] if k == 0 else "")
        axes.append(ax)
    legend_from_gids(fig, axes, ncol=3)
    head = title or f"{_CASE.get(sm.case, sm.case)} PD in scaled gains, valid for every m2"
    par = dict(params or {})
    par.pop("m2", None)
    fig.suptitle(f"{head}: {_param_text(par)}")
    return fig


_LABEL_BOX = dict(boxstyle="round,pad=0.12", fc="white", ec="none", alpha=0.85)


def _ray(ax, ray, e, x, y):
    m = np.asarray(ray["m2"], float)
    kx, ky = ray["kp"] / m, ray["kv"] / m
    inside = (kx >= x[0]) & (kx <= x[-1]) & (ky >= y[0]) & (ky <= y[-1])
    ray_ls = (0, (10, 2))
    (ln,) = ax.plot(np.where(inside, kx, np.nan), np.where(inside, ky, np.nan), color="k",
                    lw=1.0, ls=ray_ls, zorder=6)
    register(ax, ln, "paper's gains (10/m2, 20/m2)", line_proxy(color="k", lw=1.0, ls=ray_ls))
    for dec in (0.1, 1, 10, 100, 1000):
        px, py = ray["kp"] / dec, ray["kv"] / dec
        if x[0] <= px <= x[-1] and y[0] <= py <= y[-1]:
            (pt,) = ax.plot(px, py, "|", color="k", ms=6, mew=1.0, zorder=7)
            register(ax, pt, "m2 = 0.1, 1, 10, 100, 1000 (mass)",
                     line_proxy(color="k", marker="|", ms=6, mew=1.0, ls="none"))
            # below and right of the ray: the event labels go above and left of it
            ax.annotate(f"{dec:g}", (px, py), textcoords="offset points", xytext=(5, -10),
                        fontsize=7, ha="left", va="center", bbox=_LABEL_BOX, zorder=9)
    for m2, what in ray.get("events", {}).get(e, ()):
        px, py = ray["kp"] / m2, ray["kv"] / m2
        if not (x[0] <= px <= x[-1] and y[0] <= py <= y[-1]):
            continue
        mk, lab = (("o", "orbit starts to be stable (increasing m2)") if what == "stable"
                   else ("s", "orbit starts to exist (increasing m2)"))
        (pt,) = ax.plot(px, py, mk, mfc="white", mec="k", ms=5, zorder=8)
        register(ax, pt, lab, line_proxy(marker=mk, mfc="white", mec="k", ms=5, ls="none"))
        ax.annotate(f"m2 = {m2:.3g}", (px, py), textcoords="offset points", xytext=(-6, 6),
                    fontsize=7, ha="right", va="bottom", bbox=_LABEL_BOX, zorder=9)
