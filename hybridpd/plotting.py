"""Figures in the paper's style (matplotlib, Agg-safe; every function returns the Figure).

* :func:`plot_regions` — Figs 4-5: existence and stability regions for several ``e``
  superposed; the intersection (exists and stable) shaded.
* :func:`plot_basin` — Figs 6-7: the basin slice ``(x1, y1)`` with the fixed point marked.
* :func:`plot_trajectory` — positions, gap and impacts against time, and the phase portrait.
"""
from __future__ import annotations

import numpy as np

__all__ = ["plot_basin", "plot_regions", "plot_trajectory"]

_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown")


def _figure(ax, **kw):
    # A bare Figure (no pyplot) renders headless and leaves no global figure state behind.
    if ax is not None:
        return ax.figure, ax
    from matplotlib.figure import Figure

    fig = Figure(**kw)
    return fig, fig.add_subplot(1, 1, 1)


def plot_regions(rm, ax=None, title=None):
    """Existence (outline) and existence-and-stability (shaded) regions, one colour per ``e``.

    Parameters
    ----------
    rm : RegionMap
    ax : matplotlib Axes, optional
    """
    from matplotlib.patches import Patch

    fig, ax = _figure(ax, figsize=(6, 5))
    X, Y = np.meshgrid(rm.x, rm.y)
    handles = []
    for k, e in enumerate(rm.e):
        c = _COLORS[k % len(_COLORS)]
        st = rm.stable[k].astype(float)
        ex = rm.exists[k].astype(float)
        if st.any():
            ax.contourf(X, Y, st, levels=[0.5, 1.5], colors=[c], alpha=0.25)
            ax.contour(X, Y, st, levels=[0.5], colors=[c], linewidths=1.2)
        if ex.any() and not ex.all():
            ax.contour(X, Y, ex, levels=[0.5], colors=[c], linewidths=1.0, linestyles="--")
        handles.append(Patch(facecolor=c, alpha=0.35, edgecolor=c,
                             label=f"e = {e:g}: exists & stable ({100 * rm.fraction()[k]:.1f}%)"))
    handles.append(Patch(facecolor="none", edgecolor="gray", linestyle="--",
                         label="existence boundary"))
    ax.legend(handles=handles, loc="best", fontsize=8)
    ax.set_xlabel(rm.x_name)
    ax.set_ylabel(rm.y_name)
    f = rm.fixed
    ax.set_title(title or (f"{rm.case}: mu = {f['mu']:g}, gamma = {f['L'] / f['x10']:g}, "
                           f"n = {f['n']}, omega = {f['omega']:g}"), fontsize=9)
    return fig


def plot_basin(basin, ax=None, title=None):
    """The basin slice with labels as colours and the fixed point marked."""
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    from hybridpd.sweeps.basins import LABELS

    fig, ax = _figure(ax, figsize=(6, 5))
    colors = ["#3b75af", "#f2f2f2", "#d95f02", "#7570b3", "#e7298a", "#ffffff"]
    cmap = ListedColormap(colors)
    x, y = basin.x1, basin.y1
    dx = (x[-1] - x[0]) / max(len(x) - 1, 1)
    dy = (y[-1] - y[0]) / max(len(y) - 1, 1)
    ax.imshow(basin.labels, origin="lower", cmap=cmap, vmin=-0.5, vmax=len(LABELS) - 0.5,
              extent=(x[0] - dx / 2, x[-1] + dx / 2, y[0] - dy / 2, y[-1] + dy / 2),
              aspect="auto", interpolation="nearest")
    fp = basin.fixed_point
    L = basin.metadata.get("L", 0.0)
    ax.plot(fp[1] + L, fp[2] + fp[3], marker="*", color="gold", markeredgecolor="k",
            markersize=14, label="fixed point")
    present = sorted(set(np.unique(basin.labels).tolist()))
    handles = [Patch(facecolor=colors[k], edgecolor="gray", label=LABELS[k]) for k in present]
    handles.append(ax.lines[-1])
    ax.legend(handles=handles, loc="best", fontsize=8)
    ax.set_xlabel("x1 at impact")
    ax.set_ylabel("y1 (pre-impact)")
    m = basin.metadata
    ax.set_title(title or (f"{m.get('case', '')}: e = {m.get('e', float('nan')):g}, kp = "
                           f"{m.get('kp', float('nan')):g}, kv = {m.get('kv', float('nan')):g}; "
                           f"converged {100 * basin.converged_fraction:.1f}%"), fontsize=9)
    return fig


def plot_trajectory(traj, L, t=None, fig=None):
    """Positions ``x1, x2`` and the gap ``x1 - x2`` against time with impacts marked, and
    the phase portraits of both masses.

    Parameters
    ----------
    traj : ImpactPairTrajectory
    L : float
        Half clearance (draws the walls ``+-L`` on the gap plot).
    t : array_like, optional
        Sampling times (default: 2000 points over the simulated span).
    """
    from matplotlib.figure import Figure

    fig = fig or Figure(figsize=(10, 7))
    segs = traj.hybrid.segments
    t0 = float(segs[0].t_start) if len(segs) else 0.0
    t = np.linspace(t0, traj.t_final, 2000) if t is None else np.asarray(t, float)
    X = traj(t)
    ax1 = fig.add_subplot(2, 2, (1, 2))
    ax1.plot(t, X[:, 0], label="x1 (primary)")
    ax1.plot(t, X[:, 2], label="x2 (secondary)")
    ax1.plot(t, X[:, 0] - X[:, 2], color="gray", lw=0.8, label="gap x1 - x2")
    for w in (-L, L):
        ax1.axhline(w, color="k", lw=0.5, ls=":")
    if traj.n_impacts:
        gap = traj.pre[:, 0] - traj.pre[:, 2]
        ax1.plot(traj.impact_times, gap, "k|", markersize=8, label="impacts")
    for a, b in traj.sticking:
        ax1.axvspan(a, b, color="tab:red", alpha=0.15)
    ax1.set_xlabel("t")
    ax1.legend(loc="upper right", fontsize=8)
    ax2 = fig.add_subplot(2, 2, 3)
    ax2.plot(X[:, 0], X[:, 1], lw=0.8)
    ax2.set_xlabel("x1")
    ax2.set_ylabel("y1")
    ax2.set_title("primary mass", fontsize=9)
    ax3 = fig.add_subplot(2, 2, 4)
    ax3.plot(X[:, 2], X[:, 3], lw=0.8, color="tab:orange")
    ax3.set_xlabel("x2")
    ax3.set_ylabel("y2")
    ax3.set_title("secondary mass", fontsize=9)
    fig.tight_layout()
    return fig
