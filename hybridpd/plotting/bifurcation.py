"""plot bifurcation diagrams (of any family: the impact pair, a model file, any map): see
:mod:`hybridpd.plotting`."""
from __future__ import annotations

import numpy as np

from hybridpd.analysis.diagrams import CLASSES
from hybridpd.plotting._common import _COLORS, figure, model_title
from hybridpd.plotting.branches import _grow
from hybridpd.plotting.style import DOUBLE, styled

__all__ = ["PARAMETER_LABELS", "bifurcation_legend", "plot_bifurcation"]

#: Axis labels of the parameters (maths text).
PARAMETER_LABELS = {"kp": r"$k_p$ (force/length)", "kv": r"$k_v$ (force$\cdot$time/length)",
                    "e": r"$e$ (1)", "mu": r"$\mu$ (1)", "gamma": r"$\gamma = L / x_{10}$ (1)",
                    "omega": r"$\omega$ (rad/time)", "m2": r"$m_2$ (mass)",
                    "xm": r"$x_m$ (length)", "L": r"$L$ (length)",
                    "x10": r"$x_{10}$ (length)"}
_COORD_LABELS = {"phi": r"impact phase $\varphi = t\ \mathrm{mod}\ T$ (time)",
                 "z1": r"$z_1 = x_2$ at impact (length)",
                 "x2": r"$x_2$ at impact (length)",
                 "z2": r"$z_2 = y_2$ before impact (length/time)",
                 "y2": r"$y_2$ before impact (length/time)",
                 "z4": r"$z_4 = y_1 - y_2$ before impact (length/time)",
                 "x1": r"$x_1 = x_2 + L$ at impact (length)",
                 "y1": r"$y_1$ before impact (length/time)"}
_EVENT_MARKERS = {"period_doubling": ("D", "#CC79A7", "period doubling"),
                  "fold": ("s", "#D55E00", "fold"),
                  "grazing": ("v", "black", "grazing"),
                  "neimark_sacker": ("*", "#009E73", "Neimark-Sacker")}
#: Markers telling branches apart besides their colour (the first branch has none).
_BRANCH_MARKERS = ("", "o", "s", "^", "v", "P")
_SYMBOLS = {"kp": "k_p", "kv": "k_v", "e": "e", "mu": r"\mu", "omega": r"\omega",
            "m2": "m_2", "xm": "x_m", "x10": "x_{10}", "n": "n", "L": "L"}


def _branch_cycles(branch):
    """The ``k`` section points of every orbit of a branch, shape (N, k, 4), and ``L``."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.continuation import branch_map

    k = int(branch.period)
    N = len(branch)
    out = np.full((N, k, 4), np.nan)
    L = np.full(N, np.nan)
    for i in range(N):
        P = branch_map(branch, branch.parameter[i])
        if P is None:
            continue
        L[i] = P.pair.L
        s = branch.points[i]
        if not np.all(np.isfinite(s)) or s[3] <= 0:
            continue
        out[i, 0] = s
        if k > 1:
            r = P.iterate(s, k - 1)
            out[i, 1:] = r[1:]
    return out, L


def _title(diagram):
    md = diagram.metadata
    src = md.get("source")
    start = (", following" if md.get("follow") else
             ", each value started from a simulation" if src else ", one initial condition")
    run = f"last {diagram.points.shape[1]} of {md.get('iterations', '?')} iterates{start}"
    if "fixed" not in md:        # not the impact pair's family
        return (f"{model_title(src, md)}: " if src else "") + run
    f = diagram.fixed
    parts = [f"{diagram.case}"]
    for key in ("e", "mu", "kp", "kv", "omega", "m2", "xm", "x10"):
        if key in f and key != diagram.parameter_name:
            parts.append(f"${_SYMBOLS[key]} = {f[key]:g}$")
    if diagram.parameter_name != "gamma" and "x10" in f and "L" in f:
        parts.append(rf"$\gamma = {f['L'] / f['x10']:g}$")
    elif "L" in f and diagram.parameter_name != "gamma":
        parts.append(f"$L = {f['L']:g}$")
    path = r"$x_m$ from the design" if diagram.design else r"fixed $x_m$"
    return ", ".join(parts) + f"\n{path}; {run}"


def _values_of(diagram, coordinate):
    """``(coordinate, (M, keep) values, axis label)`` of the kept points; the pair's physical
    coordinates from its half clearance ``L``."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.bifdiagram import COORDINATES, section_coordinate

    pair = "L" in diagram.variables and tuple(diagram.names) == COORDINATES[:4]
    if coordinate is None:
        names = list(diagram.names)
        coordinate = "z1" if pair else (names[1] if names[0] == "phi" and len(names) > 1
                                        else names[0])
    if pair and coordinate in COORDINATES:
        y = section_coordinate(diagram.points, coordinate, diagram.L[:, None])
        return coordinate, y, _COORD_LABELS[coordinate]
    if coordinate not in diagram.names:
        allowed = COORDINATES if pair else tuple(diagram.names)
        raise ValueError(f"coordinate must be one of {allowed}, got {coordinate!r}")
    unit = " (model units)" if "source" in diagram.metadata else ""
    return coordinate, diagram.coordinate(coordinate), f"{coordinate} at the section{unit}"


@styled
def plot_bifurcation(diagram, ax=None, coordinate: str | None = None, branches=(), *,
                     events: bool = True, title: str | None = None, markersize: float = 1.0,
                     color: str = "k", label: str | None = None, legend: bool = True,
                     note: bool = True):
    """A bifurcation diagram in the impact-oscillator style, with continued branches.

    Small dots: for every parameter value, the recorded iterates of ``P`` (one coordinate of
    the section points). Continued branches (:class:`~hybridpd.pair.continuation.Branch`)
    are drawn over them, every point of a period-``k`` cycle, stable parts solid and unstable
    parts dashed (non-viable formal orbits of a symmetric family are not drawn), with their
    events marked.

    Parameters
    ----------
    diagram : BifurcationDiagram
        Of any family (:mod:`hybridpd.analysis.diagrams`).
    ax : matplotlib Axes, optional
        Drawn into when given, else a new Figure (no pyplot).
    coordinate : str, optional
        One of the diagram's ``names``; for the impact pair also the physical ``x1, y1, x2,
        y2`` (:data:`~hybridpd.pair.bifdiagram.COORDINATES`; default ``z1``). Default: the
        first coordinate after the phase.
    branches : sequence of Branch or (Branch, label)
        Continued branches in the diagram's parameter (on the same parameter path); pieces
        with the same label share one colour and one legend entry.
    events : bool
        Mark the branches' period-doubling, fold/branch, grazing and Neimark-Sacker events.
    title : str, optional
        Default: the fixed parameters and the run settings.
    markersize : float
        Size of the dots (points).
    color : str
        Colour of the dots.
    label : str, optional
        Legend label of the dots (default ``"iterates of P"``).
    legend : bool
        Draw the legend (:func:`bifurcation_legend`) of all labelled artists of ``ax``.
    note : bool
        Write the counts of the non-periodic classes in a corner.

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> import numpy as np
    >>> from hybridpd import ImpactPair, PDGains, bifurcation_diagram
    >>> from hybridpd.pair.bifdiagram import ImpactMapFamily
    >>> fam = ImpactMapFamily(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0, "kv")
    >>> d = bifurcation_diagram(fam, np.linspace(18, 20, 3), iterations=100, keep=10,
    ...                         max_period=5, follow=False)
    >>> fig = plot_bifurcation(d, coordinate="x1")
    >>> fig.axes[0].get_xlabel()
    '$k_v$ (force$\\\\cdot$time/length)'
    """
    coordinate, y, ylabel = _values_of(diagram, coordinate)
    fig, ax = figure(ax, house=(DOUBLE, 4.2))
    x = np.repeat(diagram.values[:, None], y.shape[1], axis=1)
    ok = np.isfinite(y)
    if ok.any():
        ax.plot(x[ok], y[ok], linestyle="none", marker=".", ms=markersize, color=color,
                rasterized=True, zorder=2, label=label or "iterates of $P$")
    colors = {}
    seen = set(ax.get_legend_handles_labels()[1])
    for item in branches:
        br, blabel = item if isinstance(item, tuple) else (item, None)
        name = blabel or (f"period-{br.period} branch"
                          + (" (symmetric)" if br.family == "symmetric" else ""))
        # branches with the same label are pieces of one family: one colour, one entry
        k = colors.setdefault(name, len(colors))
        _draw_branch(ax, br, coordinate, (_COLORS[k % len(_COLORS)],
                                          _BRANCH_MARKERS[k % len(_BRANCH_MARKERS)]),
                     name, events, seen)
    for v in diagram.values[diagram.code == CLASSES.index("undefined")]:
        ax.axvline(v, color="0.85", lw=0.6, zorder=0)   # no map, or it stopped
    ax.set_xlabel(PARAMETER_LABELS.get(diagram.parameter_name, diagram.parameter_name
                                       + (" (model units)" if "source" in diagram.metadata
                                          else "")))
    ax.set_ylabel(ylabel)
    lo, hi = float(np.min(diagram.values)), float(np.max(diagram.values))
    # half a step beyond the end values, so that their iterates are not cut by the frame
    pad = 0.5 * (hi - lo) / max(len(diagram.values) - 1, 1)
    ax.set_xlim(lo - pad, hi + pad)
    ax.set_title(title if title is not None else _title(diagram))
    if legend:
        bifurcation_legend(ax)
    counts = {c: n for c, n in diagram.counts().items() if n and c != "periodic"}
    per = {int(k): int(np.sum(diagram.periods == k)) for k in np.unique(diagram.periods)
           if k > 1}
    lines = []
    if counts:
        lines.append(", ".join(f"{n} {c.replace('_', ' ')}" for c, n in counts.items())
                     + (" (grey lines: no map, or it stopped)" if counts.get("undefined")
                        else ""))
    if per:
        lines.append("period k (at " + ", ".join(f"{n} values: k = {k}" for k, n in per.items())
                     + "): the section points repeat every k applications of $P$")
    if note and lines:
        ax.text(0.01, 0.01, "\n".join(lines), transform=ax.transAxes, fontsize=7, color="0.3",
                va="bottom")
    if ok.any():   # a flat diagram: a readable range instead of an offset of 1e-13
        lo_, hi_ = float(np.min(y[ok])), float(np.max(y[ok]))
        if hi_ - lo_ <= 1e-9 * max(1.0, abs(hi_)):
            pad = max(1e-3, 0.05 * abs(hi_))
            ax.set_ylim(lo_ - pad, hi_ + pad)
    ax.ticklabel_format(axis="y", useOffset=False)
    return fig


def bifurcation_legend(ax, **kw):
    """The legend of every labelled artist in ``ax``, the diagram dots enlarged to be
    visible (call it again after drawing several diagrams into one axes)."""
    kw.setdefault("fontsize", 7)
    kw.setdefault("loc", "best")
    kw.setdefault("framealpha", 0.9)
    leg = ax.legend(**kw)
    for h in leg.legend_handles:
        if getattr(h, "get_linestyle", lambda: "")() in ("None", "none") \
                and getattr(h, "get_marker", lambda: "")() == ".":
            h.set_markersize(6)
    return leg


bifurcation_legend = styled(bifurcation_legend)


def _draw_branch(ax, br, coordinate, style, name, events, seen):
    """Draw one branch (``style``: colour and marker), labelling the first artist of every
    kind not yet in ``seen``."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.bifdiagram import section_coordinate

    c, marker = style
    cyc, L = _branch_cycles(br)
    yc = section_coordinate(cyc, coordinate, L[:, None])
    p = br.parameter
    stable = br.stable & br.viable
    unstable = br.viable & ~br.stable
    for m, ls, lab in ((stable, "-", "stable"), (unstable, "--", "unstable")):
        if not m.any():
            continue
        mm = _grow(m) & br.viable
        text = f"{name}, {lab}"
        for q in range(yc.shape[1]):
            ax.plot(p, np.where(mm, yc[:, q], np.nan), ls=ls, color=c, lw=1.4, zorder=3,
                    marker=marker or None, ms=3.5, markevery=max(1, len(p) // 10),
                    label=text if text not in seen else None)
            seen.add(text)
    if not events:
        return
    for ev in br.events:
        if ev.kind not in _EVENT_MARKERS or not ev.viable:
            continue
        mk, col, text = _EVENT_MARKERS[ev.kind]
        if ev.kind == "fold" and "turns back" not in ev.detail:
            mk, text = "o", "branch point"
        if not ev.located:   # a sign change between two points, not an event at this point
            mk, col, text = "X", "0.45", f"{text}? (not located, uncertain)"
        s = np.asarray(ev.point, float)
        Lv = float(L[min(ev.index, len(L) - 1)])
        yv = float(section_coordinate(s, coordinate, Lv))
        ax.plot([ev.parameter], [yv], mk, color=col, mfc="none", ms=7, mew=1.3, zorder=4,
                label=text if text not in seen else None)
        seen.add(text)
