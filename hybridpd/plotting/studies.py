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

Their symbols carry no subscripts (``kp/m2``, ``m2``: spelled plainly), a unit's power is
rendered as mathematics (``time$^{-2}$``), and log axes are labelled with plain numbers.
Curves that coincide stay distinguishable (line widths, dash patterns and staggered markers
differ) and the panel says where they coincide.
"""
from __future__ import annotations

import numpy as np

from hybridpd.plotting._common import (
    legend_from_gids,
    legend_handles,
    line_proxy,
    patch_proxy,
    register,
    tag,
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
LABELS = {"m2": "m2 (mass)", "kp/m2": "kp/m2 (time$^{-2}$)", "kv/m2": "kv/m2 (time$^{-1}$)",
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


def _e_line(ax, x, y, k, label, *, stagger=1, lw=None, **kw):
    """Series ``k`` (colour, dash pattern, marker); with ``stagger = n`` the markers of the
    ``n`` series sit at different points, so that coinciding curves still show each."""
    s = series(k)
    n = max(1, len(x) // 8)
    every = ((k % stagger) * n // stagger, n)
    width = {} if lw is None else {"lw": lw}
    (ln,) = ax.plot(x, y, color=s["color"], ls=s["ls"], marker=s["marker"], markevery=every,
                    ms=3.5, **width, **kw)
    register(ax, ln, label, line_proxy(color=s["color"], ls=s["ls"], marker=s["marker"],
                                       ms=3.5, **width))
    return ln


#: Relative difference under which two curves are said to coincide (they are drawn within
#: a line width of each other).
COINCIDE_RTOL = 1e-2


def coincide_from(grid, curves, rtol=COINCIDE_RTOL):
    """The smallest grid value from which on every curve is defined and all agree within
    ``rtol`` (relative) up to the grid's end; None if they differ at the end.

    Examples
    --------
    >>> import numpy as np
    >>> from hybridpd.plotting.studies import coincide_from
    >>> g = np.array([1.0, 2.0, 3.0, 4.0])
    >>> float(coincide_from(g, [np.array([1, 2, 5, 5.0]), np.array([1, 3, 5, 5.0])]))
    3.0
    """
    Y = np.asarray([np.asarray(c, float) for c in curves])
    if len(Y) < 2:
        return None
    ok = np.all(np.isfinite(Y), axis=0)
    Z = np.where(ok, Y, 0.0)
    same = ok & (Z.max(axis=0) - Z.min(axis=0) <= rtol * np.abs(Z).max(axis=0))
    if not same[-1]:
        return None
    k = len(same) - 1
    while k > 0 and same[k - 1]:
        k -= 1
    return float(np.asarray(grid, float)[k])


def _rho_panel(ax, study, case, runs):
    """Spectral radius against ``m2`` per ``e``; returns where the curves coincide, in words
    (:func:`coincidence_note`), for the caller to state."""
    es = sorted({key[1] for key in study.rho if key[0] == case})
    for k, e in enumerate(es):
        rho = study.rho[(case, e)]
        # widest first: where the curves coincide each still shows beneath the next
        _e_line(ax, study.rho_grid, rho, k, f"e = {e:g}", stagger=len(es),
                lw=1.0 + 0.6 * (len(es) - 1 - k))
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
    return coincidence_note(study.rho_grid, {e: study.rho[(case, e)] for e in es})


def _round(v: float) -> str:
    return f"{v:.0f}" if v >= 10 else f"{v:.2g}"


def coincidence_note(grid, curves: dict) -> str:
    """Where the curves ``{e: values}`` coincide (within :data:`COINCIDE_RTOL`): all of
    them from some grid value on, and a pair of them from well before; "" if nowhere.

    Examples
    --------
    >>> import numpy as np
    >>> from hybridpd.plotting.studies import coincidence_note
    >>> g = np.array([1.0, 10.0, 20.0, 50.0, 100.0])
    >>> coincidence_note(g, {0.1: [1, 2, 3, 3, 3.0], 0.5: [2, 2, 3, 3, 3.0],
    ...                      0.9: [3, 1, 2, 3, 3.0]})
    'the curves coincide (within 1 %):\\ne = 0.1, 0.5 for m2 ≥ 10, all e for m2 ≥ 50'
    """
    import itertools

    es = list(curves)
    end = float(np.asarray(grid, float)[-1])
    every = coincide_from(grid, [curves[e] for e in es])
    parts = []
    for a, b in itertools.combinations(es, 2):
        c = coincide_from(grid, [curves[a], curves[b]])
        if c is not None and c < end and (every is None or c < every / 1.5):
            parts.append(f"e = {a:g}, {b:g} for m2 ≥ {_round(c)}")
    if every is not None and every < end:
        parts.append(("all e" if len(es) > 2 else f"e = {es[0]:g}, {es[1]:g}")
                     + f" for m2 ≥ {_round(every)}")
    if not parts:
        return ""
    return (f"the curves coincide (within {100 * COINCIDE_RTOL:g} %):\n"
            + ", ".join(parts))


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
    fig = house_figure(DOUBLE, min(8.6, 5.4 + 0.2 * len(rows)))
    gs = fig.add_gridspec(3, 2, height_ratios=[2.0, 0.25 + 0.16 * len(rows), 0.5])
    grid = np.asarray(study.rho_grid, float)
    lo, hi = m2_range if m2_range is not None else (grid[0], grid[-1])
    xlim = (float(lo) / 1.6, float(hi) * 1.6)     # one m2 range for every panel
    axes = []
    for col, case in enumerate(("noncollocated", "collocated")):
        ax = fig.add_subplot(gs[0, col])
        note = _rho_panel(ax, study, case, runs)
        ax.set_xlim(*xlim)
        ax.set_title(f"{_CASE[case]}, kp = 10, kv = 20 (no line: no orbit)"
                     + (f"\n{note}" if note else ""))
        axes.append(ax)
    ax = fig.add_subplot(gs[1, :])
    _verdict_panel(ax, readings, m2_range)
    ax.set_xlim(*xlim)
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
    fig.suptitle("Convention study: μ = 0.1, γ = 0.75, ω = 5, n = 1, m2 varied\n"
                 "coinciding curves stay apart: the wider line drawn under the narrower, "
                 "markers staggered")
    return fig


#: A non-collocated region of the maps with at most this many grid points has them marked.
FEW_POINTS = 3
#: Legend words of the certified bars.
CERT_LABEL = "certified interval (decides the remark)"
#: Legend words of certified intervals that decide nothing (the gamma study).
CERT_PLAIN = "certified interval"
#: More certified values than this in the sampled range are drawn as a band, not as bars.
BAND_FROM = 8
#: Hatch of each series' band (colour and hatch tell the series apart).
_BAND_HATCH = ("", "////", "\\\\\\\\")


def _cert_bars(ax, points, k, e_count, *, span=None, label=CERT_LABEL):
    """Certified intervals ``{p: [(lo, hi) per e]}`` of series ``k`` as vertical bars in the
    series' colour, a cap at both ends (offset along the log axis so that the ``e`` stay
    apart). Where more than :data:`BAND_FROM` values lie in ``span`` (the sampled range) they
    are drawn as one band between the lower and upper ends instead (bars that close would
    hide each other), hatched per series; the values outside stay bars. The legend entry
    shows one mark per ``e``, in the colours drawn."""
    s = series(k)
    inside = {p: iv for p, iv in points.items()
              if span is not None and span[0] / 1.01 <= p <= span[1] * 1.01}
    band = len(inside) > BAND_FROM
    if band:
        proxy = tuple(patch_proxy(facecolor=series(j)["color"], alpha=0.3,
                                  edgecolor=series(j)["color"], hatch=_BAND_HATCH[j % 3])
                      for j in range(e_count))
        xs = sorted(inside)
        lo = [100 * inside[p][k][0] if inside[p][k] is not None else np.nan for p in xs]
        hi = [100 * inside[p][k][1] if inside[p][k] is not None else np.nan for p in xs]
        poly = ax.fill_between(xs, lo, hi, facecolor=s["color"], alpha=0.3,
                               edgecolor=s["color"], hatch=_BAND_HATCH[k % 3], lw=0.8,
                               zorder=1.5)
        register(ax, poly, label, proxy)
    else:
        proxy = tuple(line_proxy(color=series(j)["color"], ls="none", marker="|", ms=9,
                                 mew=1.6) for j in range(e_count))
    shift = 10 ** (0.06 * (k - (e_count - 1) / 2))
    for p, ivs in sorted(points.items()):
        iv = ivs[k]
        if iv is None or (band and p in inside):
            continue
        x = p * shift
        (ln,) = ax.plot([x, x], [100 * iv[0], 100 * iv[1]], color=s["color"], ls="-", lw=1.6,
                        marker="_", ms=7, mew=1.6, zorder=6)
        register(ax, ln, label, proxy)


def _gaps(values, extra, decades=1.0):
    """``(far, near)``: the points of ``extra`` more than ``decades`` below the smallest of
    ``values`` (drawn on an axis of their own, left of a break), and the rest with
    ``values``."""
    v0 = min(float(v) for v in values)
    far = sorted({float(p) for p in extra if float(p) < v0 / 10 ** decades})
    near = [float(v) for v in values] + [float(p) for p in extra if float(p) not in far]
    return far, near


def _break_marks(left, right):
    """The ``//`` of a broken axis between ``left`` and ``right`` (their facing spines
    hidden)."""
    left.spines["right"].set_visible(False)
    right.spines["left"].set_visible(False)
    right.tick_params(axis="y", left=False, labelleft=False)
    kw = dict(color="k", lw=0.8, clip_on=False, zorder=10)
    d = 0.025
    for ax, x in ((left, 1.0), (right, 0.0)):
        tr = ax.transAxes
        w = d * (6.0 if ax is left else 1.0)      # the left axes is about 6 times narrower
        for y in (0.0, 1.0):
            ax.plot([x - w, x + w], [y - d, y + d], transform=tr, **kw)


def _cells(ax, xe, ye, mask, *, face, edge, hatch, label, lw, zorder):
    """The grid cells where ``mask`` holds, filled with ``face`` (or hatched), their union
    outlined in ``edge``: a region of a single grid point still shows as its cell."""
    # deferred import: loaded only when this runs, for start-up time
    from matplotlib.collections import LineCollection
    from matplotlib.colors import ListedColormap

    m = np.asarray(mask, bool)
    pc = ax.pcolor(xe, ye, np.ma.masked_where(~m, np.ones(m.shape)),
                   cmap=ListedColormap([face]), vmin=0, vmax=1, hatch=hatch or None,
                   # a filled cell's edge in its face colour: no seams between the cells
                   edgecolor=edge if face == "none" else face,
                   linewidth=0.0 if face == "none" else 0.4, zorder=zorder)
    register(ax, pc, label, patch_proxy(facecolor="white" if face == "none" else face,
                                        edgecolor=edge, hatch=hatch or None, lw=lw))
    pad = np.pad(m, 1)
    segs = []
    ny, nx = m.shape
    for i in range(ny):
        for j in range(nx):
            if not m[i, j]:
                continue
            if not pad[i + 1, j]:          # left neighbour outside the region
                segs.append([(xe[j], ye[i]), (xe[j], ye[i + 1])])
            if not pad[i + 1, j + 2]:
                segs.append([(xe[j + 1], ye[i]), (xe[j + 1], ye[i + 1])])
            if not pad[i, j + 1]:
                segs.append([(xe[j], ye[i]), (xe[j + 1], ye[i])])
            if not pad[i + 2, j + 1]:
                segs.append([(xe[j], ye[i + 1]), (xe[j + 1], ye[i + 1])])
    if segs:
        ax.add_collection(tag(LineCollection(segs, colors=[edge], linewidths=lw,
                                             zorder=zorder + 0.1), label))
    return pc


def _share_axes(fig, spec, far, xlim):
    """One share panel in ``spec``: a single log axis over ``xlim``, or (``far`` points
    given) a narrow axis around them left of a break and the main one: ``(left, main)``."""
    if not far:
        ax = fig.add_subplot(spec)
        ax.set_xscale("log")
        _plain_log(ax, "x")
        ax.set_xlim(*xlim)
        return None, ax
    sub = spec.subgridspec(1, 2, width_ratios=[1, 6], wspace=0.0)
    left = fig.add_subplot(sub[0, 0])
    main = fig.add_subplot(sub[0, 1], sharey=left)
    for a in (left, main):
        a.set_xscale("log")
        _plain_log(a, "x")
    left.set_xlim(min(far) / 2.2, max(far) * 2.2)
    left.set_xticks(far, [f"{p:g}" for p in far])
    left.minorticks_off()
    main.set_xlim(*xlim)
    _break_marks(left, main)
    return left, main


@styled
def plot_param_study(ps, *, certified=None):
    """Shares of the gain box against ``mu`` or ``gamma`` and the (parameter, kv) maps
    (7.2 in wide).

    Existence and existence with stability are drawn on separate axes per case, each scaled
    to its own values, so that a share of a few percent is read on a few-percent axis. The
    share axes span the sampled values; certified intervals more than a decade below them
    (the limit ``mu -> 0``) are drawn on a narrow axis of their own, left of a break. The
    maps draw each grid point as its cell (a region of one point still shows), the
    non-collocated cells hatched and outlined over the collocated fill.

    Parameters
    ----------
    ps : ParamStudy
    certified : dict, optional
        ``{"exists" | "exists_stable": {case: {value: [(lo, hi) per e]}}}``: certified
        intervals drawn as bars at their parameter values.
    """
    # deferred import: loaded only when this runs, for start-up time
    from matplotlib.legend_handler import HandlerTuple

    from hybridpd.pair.certified import cell_edges

    name = ps.name
    ne = len(ps.e)
    fig = house_figure(DOUBLE, 6.9)
    outer = fig.add_gridspec(2, 1, height_ratios=[1.5, 1])
    top = outer[0].subgridspec(2, len(ps.fractions))
    gs = outer[1].subgridspec(1, ne)
    b = ps.box
    axes = []
    cert_x = ([float(p) for q in certified.values() for d in q.values() for p in d]
              if certified else [])
    far, near = _gaps(ps.values, cert_x)
    xlim = (min(near) / 1.8, max(near) * 1.8)
    span = (float(np.min(ps.values)), float(np.max(ps.values)))
    for i, (case, q) in enumerate(ps.fractions.items()):
        for j, (quantity, what) in enumerate((("exists", "exists"),
                                              ("both", "exists and stable"))):
            left, ax = _share_axes(fig, top[j, i], far, xlim)
            top_val = 0.0
            for k, e in enumerate(ps.e):
                y = 100 * np.asarray(q[quantity][k], float)
                _e_line(ax, ps.values, y, k, f"e = {e:g} (sampled grid)")
                top_val = max(top_val, float(np.nanmax(y)))
                pts = (certified or {}).get("exists" if quantity == "exists"
                                            else "exists_stable", {}).get(case)
                if pts:
                    for a in (ax, left):
                        if a is not None:
                            _cert_bars(a, pts, k, ne, span=span,
                                       label=CERT_LABEL if name == "mu" else CERT_PLAIN)
                    top_val = max(top_val, max(100 * iv[k][1] for iv in pts.values()
                                               if iv[k] is not None))
            ax.set_ylim(0, max(1.0, 1.08 * top_val))
            first = ax if left is None else left
            ax.set_xlabel(LABELS[name] if j else "")
            first.set_ylabel(f"{what} (%)")
            if left is not None:
                sym = {"mu": "μ", "gamma": "γ"}.get(name, name)
                left.set_xlabel(f"limit\n{sym} → 0 (1)" if j else "")
            if j == 0:
                head = f"{_CASE[case]}: share of the gain box"
                box = (f"kp/m2, kv/m2 in [{b['kp'][0]:g}, {b['kp'][1]:g}]\n(lines: "
                       f"{b['kp'][2]} x {b['kv'][2]} grid points)")
                ax.set_title(f"{head}\n{box}")
            axes += [a for a in (left, ax) if a is not None]
    xe = cell_edges(ps.values, "log")
    ye = cell_edges(ps.map_kv)
    for k, e in enumerate(ps.e):
        a = fig.add_subplot(gs[0, k])
        c, n = ps.maps["collocated"]["stable"][k], ps.maps["noncollocated"]["stable"][k]
        if np.any(c):
            _cells(a, xe, ye, c, face="#56B4E9", edge="#0072B2", hatch="",
                   label="collocated: exists and stable", lw=0.8, zorder=2)
        if np.any(n):
            _cells(a, xe, ye, n, face="none", edge="#D55E00", hatch="////",
                   label="non-collocated: exists and stable (hatched)", lw=1.4,
                   zorder=3)
        if np.any(n) and np.sum(n) <= FEW_POINTS:
            # a region of a few points (a half cell on the box's edge) has its points marked
            V, KV = np.meshgrid(ps.values, ps.map_kv)
            (pts,) = a.plot(V[n], KV[n], ls="none", marker="D", ms=4, mfc="white",
                            mec="#D55E00", mew=1.2, zorder=4, clip_on=False)
            register(a, pts, "grid points of a small non-collocated region",
                     line_proxy(ls="none", marker="D", ms=4, mfc="white", mec="#D55E00",
                                mew=1.2))
        a.set_xscale("log")
        _plain_log(a, "x")
        a.set_xlim(xe[0], xe[-1])
        a.set_ylim(ye[0], ye[-1])
        a.set_xlabel(LABELS[name])
        a.set_ylabel(LABELS["kv"] if k == 0 else "")
        a.set_title(f"e = {e:g}, kp = {ps.map_kp:g}")
        axes.append(a)
    # a tuple handle (the certified bars' colours) draws its bars side by side
    legend_from_gids(fig, axes, ncol=3, handler_map={tuple: HandlerTuple(ndivide=None, pad=0.6)})
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
    # the whole grid, where the orbit exists or not: side by side panels share the range
    ax.set_xlim(float(m2_grid[0]) / 1.3, float(m2_grid[-1]) * 1.3)
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
