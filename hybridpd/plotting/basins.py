"""plot basin: see :mod:`hybridpd.plotting`.

Colours follow Okabe & Ito's colour-blind-safe palette: the symmetric orbit blue, other
periodic orbits orange, bluish green, reddish purple, yellow (in label order), sticking sky blue,
divergence vermillion, no convergence grey, unresolved flights black; the half-plane off the
section (``y1 <= y2*``) is hatched.
"""
from __future__ import annotations

import numpy as np

from hybridpd._format import format_percent
from hybridpd.analysis.basins import (
    DIVERGED,
    INADMISSIBLE_LABEL,
    NO_CONVERGENCE,
    OFF_SECTION_LABEL,
    STICKING,
    UNRESOLVED,
    BasinResult,
)
from hybridpd.plotting._common import figure, model_title, patch_proxy, register, set_all
from hybridpd.plotting.style import axis_label, house_figure, styled

__all__ = ["basin_colors", "basin_hatches", "basin_title", "plot_basin", "plot_model_basin"]

_SYMMETRIC = "#0072B2"
_PERIODIC = ("#E69F00", "#009E73", "#CC79A7", "#F0E442")
_OUTCOME_COLORS = {NO_CONVERGENCE: "#999999", DIVERGED: "#D55E00", STICKING: "#56B4E9",
                   UNRESOLVED: "#000000", OFF_SECTION_LABEL: "#FFFFFF",
                   INADMISSIBLE_LABEL: "#FFFFFF"}
_MARKERS = ("D", "o", "s", "^", "v", "P")
#: The fixed point's star is drawn above the section points of the other orbits.
STAR_ZORDER = 6


_PERIODIC_HATCHES = ("////", "\\\\\\\\", "||||", "----", "oo")
_OUTCOME_HATCHES = {NO_CONVERGENCE: "....", DIVERGED: "xxxx", STICKING: "++++",
                    UNRESOLVED: "OO", OFF_SECTION_LABEL: "///", INADMISSIBLE_LABEL: "xx"}


def basin_hatches(labels) -> dict:
    """Hatch of each attractor label: none for the symmetric orbit, one pattern per other
    attractor and outcome (so the legend never relies on colour alone)."""
    out = {}
    for k in labels:
        k = int(k)
        out[k] = ("" if k == 0 else _PERIODIC_HATCHES[(k - 1) % len(_PERIODIC_HATCHES)]
                  if k > 0 else _OUTCOME_HATCHES[k])
    return out


def basin_colors(labels) -> dict:
    """Colour of each attractor label (``0`` symmetric, ``>= 1`` periodic, negative outcomes)."""
    out = {}
    for k in labels:
        k = int(k)
        if k == 0:
            out[k] = _SYMMETRIC
        elif k > 0:
            out[k] = _PERIODIC[(k - 1) % len(_PERIODIC)]
        else:
            out[k] = _OUTCOME_COLORS[k]
    return out


def basin_title(meta: dict) -> str:
    """Two title lines: case, restitution and gains; then the conventions (mu, gamma, omega, n,
    m2). Values the metadata does not hold are left out."""
    gamma = meta.get("gamma")
    if gamma is None and meta.get("x10") and meta.get("L") is not None:
        gamma = meta["L"] / meta["x10"]
    vals = dict(meta, gamma=gamma)

    def part(keys):
        return ", ".join(f"{sym} = {vals[k]:g}" for k, sym in keys if vals.get(k) is not None)

    first = part((("e", "$e$"), ("kp", "$k_p$"), ("kv", "$k_v$")))
    second = part((("mu", "$\\mu$"), ("gamma" if gamma is not None else "L",
                                        "$\\gamma$" if gamma is not None else "$L$"),
                   ("omega", "$\\omega$"), ("n", "$n$"), ("m2", "$m_2$")))
    return f"{str(meta.get('case', '')).capitalize()} PD: {first}\n{second}"


def _pair_slice(b) -> bool:
    """The impact pair's slice ``(x1, y1)`` of its section ``(phi, z1, z2, z4)``."""
    return b.axes == ("x1", "y1") and b.names == ("phi", "z1", "z2", "z4")


@styled
def plot_basin(basin, ax=None, title=None, *, legend: bool = True):
    """The basin slice ``(x1, y1)`` coloured by attractor, with section points marked.

    Parameters
    ----------
    basin : BasinResult
        The impact pair's slice ``(x1, y1)`` (:func:`hybridpd.sweeps.basins.
        basin_of_attraction` of its mapper); a basin of any other map or model file is drawn by
        :func:`plot_model_basin`.
    ax : matplotlib Axes, optional
        Draw there (legend below the axes); else a new figure 7.2 in wide in the house style
        (legend beside the axes).
    title : str, optional
        Replaces the default title (case, gains and conventions).
    legend : bool
        Draw the legend (below the axes, outside the data).

    Returns
    -------
    matplotlib.figure.Figure

    Notes
    -----
    The legend lists every label present on the grid with its share of all points of the
    slice, the off-section ones included (:func:`hybridpd._format.format_percent`; the
    legend's title names that denominator),
    then the markers: the symmetric orbit's fixed point (drawn above every other marker) and
    the section points of the other periodic orbits, projected on the slice (they have their
    own ``phi`` and ``y2``). The slice's fixed coordinates ``phi*`` and ``y2*`` are stated
    under the axes.
    """
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Rectangle

    if not isinstance(basin, BasinResult):
        raise ValueError(f"basin must be a BasinResult, got {type(basin).__name__}")
    if not _pair_slice(basin):
        return plot_model_basin(basin, ax=ax, title=title)
    # deferred import: only the pair's slice needs the pair
    from hybridpd.pair.basins import slice_points

    lab, entries, pb, edges = basin.labels, list(basin.attractors), basin, basin.edges
    if ax is None:
        fig = house_figure("double", 4.2)
        ax = fig.add_subplot(1, 1, 1)
        beside = True
    else:
        fig, ax = figure(ax)
        beside = False
    meta = dict(pb.metadata)
    L = float(meta.get("L", 0.0))
    x, y = pb.x1, pb.y1
    dx = (x[-1] - x[0]) / max(len(x) - 1, 1)
    dy = (y[-1] - y[0]) / max(len(y) - 1, 1)
    codes = sorted(a.label for a in entries)
    colors = basin_colors(codes)
    # one colour bin per code present; off-section cells are left to the hatched band
    idx = np.searchsorted(codes, lab)
    img = np.ma.masked_where(lab == OFF_SECTION_LABEL, idx)
    cmap = ListedColormap([colors[k] for k in codes])
    norm = BoundaryNorm(np.arange(len(codes) + 1) - 0.5, len(codes))
    extent = (x[0] - dx / 2, x[-1] + dx / 2, y[0] - dy / 2, y[-1] + dy / 2)
    ax.imshow(img, origin="lower", cmap=cmap, norm=norm, extent=extent, aspect="auto",
              interpolation="nearest")
    fp = pb.fixed_point
    handles = []
    present = set(np.unique(lab).tolist())
    hatches = basin_hatches(codes)
    X, Y = np.meshgrid(x, y)
    for a in entries:
        if a.label not in present or a.label == OFF_SECTION_LABEL:
            continue
        h = hatches[a.label]
        if h:
            cs = ax.contourf(X, Y, (lab == a.label).astype(float), levels=[0.5, 1.5],
                             colors="none", hatches=[h])
            set_all(cs, edgecolor="0.15", linewidth=0.0)
        share = format_percent(int((lab == a.label).sum()), int(lab.size))
        proxy = patch_proxy(facecolor=colors[a.label], edgecolor="0.3", hatch=h)
        register(ax, ax.images[-1] if not h else cs, a.name, proxy)
        handles.append(patch_proxy(facecolor=colors[a.label], edgecolor="0.3", hatch=h,
                                   label=f"{a.name}: {share}"))
    if OFF_SECTION_LABEL in present:
        band = Rectangle((extent[0], extent[2]), extent[1] - extent[0],
                         min(fp[2], extent[3]) - extent[2], facecolor="white",
                         edgecolor="0.45", hatch="///", linewidth=0, zorder=1.5,
                         label="off the section ($y_1 \\leq y_2^*$)")
        ax.add_patch(band)
        register(ax, band, band.get_label(),
                 patch_proxy(facecolor="white", edgecolor="0.45", hatch="///"))
        handles.append(band)
    outside = []
    for a in entries:
        if a.label < 0:
            continue
        xy = slice_points(a, L)
        inside = ((xy[:, 0] >= extent[0]) & (xy[:, 0] <= extent[1]) & (xy[:, 1] >= extent[2])
                  & (xy[:, 1] <= extent[3]))
        if not inside.any():
            outside.append(a.name)
            continue
        ln = _mark(ax, a, xy[inside], len(xy), colors[a.label])
        register(ax, ln, "fixed point of the symmetric orbit" if a.label == 0
                 else f"section points of the {a.name}", None)
        handles.append(ln)
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_xlabel(axis_label("x1") + " at the impact")
    ax.set_ylabel(axis_label("y1") + " before it")
    ax.set_title(title if title is not None else basin_title(meta))
    if legend:
        where = (dict(loc="upper left", bbox_to_anchor=(1.03, 1.0)) if beside else
                 dict(loc="upper center", bbox_to_anchor=(0.5, -0.16)))
        import textwrap

        for h in handles:   # legends of a print figure wrap rather than widen it
            h.set_label("\n".join(textwrap.wrap(h.get_label(), 44)))
        leg = ax.legend(handles=handles, ncol=1, frameon=False,
                        title=_note(fp, len(x), len(y), outside, edges, int(lab.size)),
                        **where)
        leg._legend_box.align = "left"
    return fig


def _stability_words(a) -> str:
    if a.stable is None or not np.isfinite(a.spectral_radius):
        return ""
    return (", stable" if a.stable else
            f", unstable: spectral radius {a.spectral_radius:.4g}")


def _mark(ax, a, xy, n_total: int, color):
    """Markers of an attractor's section points inside the window (projected on the slice)."""
    part = "" if len(xy) == n_total else f", {len(xy)} of {n_total} inside the window"
    if a.label == 0:
        # on top of every other marker: the star is what the panel is about
        (ln,) = ax.plot(xy[:, 0], xy[:, 1], ls="none", marker="*", ms=11, mfc="white",
                        mec="black", mew=1.2, zorder=STAR_ZORDER,
                        label=f"fixed point of the symmetric orbit{_stability_words(a)}")
        return ln
    k = (a.label - 1) % len(_MARKERS)
    # under the star (a section point near the fixed point still shows around its arms)
    (ln,) = ax.plot(xy[:, 0], xy[:, 1], ls="none", marker=_MARKERS[k], ms=6, mfc=color,
                    mec="black", mew=1.2, zorder=STAR_ZORDER - 1,
                    label=f"section points of the {a.name} (projected{part}"
                          f"{_stability_words(a)})")
    return ln


def _note(fp, nx: int, ny: int, outside, edges, points: int) -> str:
    """Legend title: the slice's fixed coordinates, the grid and the shares' one denominator
    (all points of the slice, the off-section ones in no basin), what lies outside the
    window."""
    note = (f"slice: $\\phi = \\phi^* = {fp[0]:.4g}$, $y_2 = y_2^* = {fp[2]:.4g}$;\n"
            f"{nx} x {ny} points; shares of all {points} points")
    if outside:
        note += "\nsection points outside the window:\n" + ", ".join(outside)
    if edges:
        note += ("\nthe symmetric orbit's basin reaches the window's edge\n("
                 + ", ".join(e.replace("x1", "$x_1$").replace("y1", "$y_1$") for e in edges)
                 + "):\nit may extend beyond the window")
    return note


def plot_model_basin(basin, ax=None, title=None):
    """A model file's (or any map's) basin: the slice coloured by attractor, section points
    of the periodic attractors marked (the pair's colours and markers, outcomes in the pair's
    outcome colours, the off-section part hatched).

    Parameters
    ----------
    basin : BasinResult
        Of a model file (:func:`hybridpd.analysis.model_orbits.model_map`) or any map.
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
    codes = sorted(a.label for a in basin.attractors)
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
    coords = basin.names or basin.axes
    ix, iy = coords.index(basin.x_name), coords.index(basin.y_name)
    for a in basin.attractors:
        share = format_percent(basin.fraction(a.label))
        if a.label == -5:
            handles.append(Patch(facecolor="white", edgecolor="0.3", hatch="///",
                                 label=f"{a.name}: {share}"))
            continue
        handles.append(Patch(facecolor=colors[a.label], edgecolor="0.3",
                             hatch=hatches.get(a.label, ""), label=f"{a.name}: {share}"))
        if a.periodic and a.points.size:
            pts = np.asarray(a.points)
            star = a.label == 0
            (ln,) = ax.plot(pts[:, ix], pts[:, iy], ls="none",
                            marker="*" if star else _MARKERS[(a.label - 1) % len(_MARKERS)],
                            ms=12 if star else 7, mfc="white" if star else colors[a.label],
                            mec="black", mew=1.0,
                            zorder=STAR_ZORDER if star else STAR_ZORDER - 1,
                            label=f"its section point ({'stable' if a.stable else 'unstable'}"
                                  f", spectral radius {a.spectral_radius:.3g})")
            handles.append(ln)
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_xlabel(f"{basin.x_name} at the section (model units)", fontsize=8)
    ax.set_ylabel(f"{basin.y_name} at the section (model units)", fontsize=8)
    ax.tick_params(labelsize=7)
    spec = basin.metadata.get("spec", {})
    vals = ", ".join(f"{k} = {v:g}" for k, v in basin.metadata.get("values", {}).items())
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.analysis.model_sections import section_words

    where = section_words(spec.get("event", "impact"), spec.get("contact", 0),
                          spec.get("wall"), spec.get("phase"))
    head = f"{model_title(basin.source, basin.metadata)}:\n{where}" + (f", {vals}" if vals else "")
    ax.set_title(title if title is not None else head, fontsize=8)
    others = ", ".join(f"{n} = {v:.3g}" for n, v in zip(coords, basin.base)
                       if n not in (basin.x_name, basin.y_name))
    others = "\n".join(", ".join(parts) for parts in _rows(others.split(", "), 3))
    fig.legend(handles=handles, loc="outside lower center", fontsize=7, frameon=False,
               title=f"slice through the orbit:\n{others}\nshares of all {lab.size} points\n"
                     "(off the section and inadmissible ones in no basin)", title_fontsize=7)
    return fig


def _rows(items, n):
    return [items[i:i + n] for i in range(0, len(items), n)]
