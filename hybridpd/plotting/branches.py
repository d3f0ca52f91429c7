"""Plot a continued branch of the impact pair (:func:`plot_branch`): a quantity against the
parameter, with the events marked."""
from __future__ import annotations

import numpy as np

from hybridpd.analysis.branch import Branch

_EVENT_STYLE = {
    "fold": ("s", "tab:red"),
    "period_doubling": ("D", "tab:purple"),
    "neimark_sacker": ("*", "tab:green"),
    "grazing": ("v", "black"),
    "stability_change": ("o", "tab:orange"),
    "existence": ("x", "tab:gray")}


def plot_branch(branch: Branch, ax=None, quantity="spectral_radius", *, events: bool = True,
                label: str | None = None, logy: bool | None = None):
    """Plot a branch: a quantity against the parameter, with its events marked.

    Stable parts are drawn solid, unstable parts dashed, non-viable (formal) parts dotted.

    Parameters
    ----------
    branch : Branch
    ax : matplotlib Axes, optional
        Drawn into when given; otherwise a new :class:`matplotlib.figure.Figure` (no pyplot)
        is created.
    quantity : str or int
        ``"spectral_radius"`` (with the unit level), ``"margin"`` (with 0), ``"xm"``,
        ``"min_impact_speed"``, ``"multipliers"`` (all moduli) or a coordinate index
        0-3 of the fixed point ``(phi, z1, z2, z4)``.
    events : bool
        Mark the events (one marker style per kind, labelled in the legend).
    label : str, optional
        Legend label of the curve.
    logy : bool, optional
        Logarithmic y axis; default: for ``spectral_radius``/``multipliers`` when the values
        span more than two decades.

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.pair.continuation import continue_symmetric
    >>> br = continue_symmetric(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0, "kv", 23.0)
    >>> fig = plot_branch(br, quantity="margin")
    >>> fig.axes[0].get_xlabel()
    'kv'
    """
    if ax is None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(6, 4))
        ax = fig.add_subplot(1, 1, 1)
    else:
        fig = ax.figure
    p = branch.parameter
    names = {0: "phi", 1: "z1", 2: "z2", 3: "z4"}
    if quantity == "multipliers":
        Y = np.abs(branch.multipliers)
        ylabel = "|multipliers|"
    elif isinstance(quantity, (int, np.integer)) and 0 <= int(quantity) <= 3:
        Y = branch.points[:, int(quantity)][:, None]
        ylabel = names[int(quantity)]
    elif quantity in ("spectral_radius", "margin", "xm", "min_impact_speed"):
        Y = np.asarray(getattr(branch, quantity), float)[:, None]
        ylabel = quantity.replace("_", " ")
    else:
        raise ValueError("quantity must be 'spectral_radius', 'margin', 'xm', "
                         f"'min_impact_speed', 'multipliers' or 0-3, got {quantity!r}")
    st = branch.stable
    un = branch.viable & ~branch.stable
    nv = ~branch.viable
    color = None
    for j in range(Y.shape[1]):
        y = Y[:, j]
        line, = ax.plot(p, np.where(st | _grow(st), y, np.nan), "-", color=color, lw=1.6,
                        label=(label or branch.parameter_name + " branch") + " (stable)"
                        if j == 0 else None)
        color = line.get_color()
        ax.plot(p, np.where(un | _grow(un), y, np.nan), "--", color=color, lw=1.2,
                label="unstable" if j == 0 and un.any() else None)
        if nv.any():
            ax.plot(p, np.where(nv | _grow(nv), y, np.nan), ":", color=color, lw=1.0,
                    label="not viable (formal)" if j == 0 else None)
    if quantity in ("spectral_radius", "multipliers"):
        ax.axhline(1.0, color="gray", lw=0.8)
        finite = Y[np.isfinite(Y) & (Y > 0)]
        if logy is None:
            logy = finite.size > 0 and finite.max() / max(finite.min(), 1e-300) > 100
    elif quantity == "margin":
        ax.axhline(0.0, color="gray", lw=0.8)
    if logy:
        ax.set_yscale("log")
    if events:
        seen = set()
        for ev in branch.events:
            mk, c = _EVENT_STYLE.get(ev.kind, ("o", "k"))
            yv = _event_y(branch, ev, quantity)
            ax.plot([ev.parameter], [yv], mk, color=c, ms=8, mfc="none" if mk != "x" else c,
                    mew=1.5, label=ev.kind.replace("_", " ") if ev.kind not in seen else None)
            seen.add(ev.kind)
    ax.set_xlabel(branch.parameter_name)
    ax.set_ylabel(ylabel)
    ax.legend(fontsize=7, loc="best")
    return fig


def _grow(mask):
    """Extend a mask by one point on each side, so that solid/dashed pieces connect."""
    m = mask.copy()
    m[1:] |= mask[:-1]
    m[:-1] |= mask[1:]
    return m


def _event_y(branch, ev, quantity):
    if quantity in ("spectral_radius", "multipliers"):
        return float(np.max(np.abs(ev.multipliers))) if np.all(np.isfinite(ev.multipliers)) \
            else 1.0
    if isinstance(quantity, (int, np.integer)):
        return float(ev.point[int(quantity)])
    if quantity == "margin" and ev.kind == "grazing":
        return 0.0
    if quantity == "xm":
        return ev.xm
    i = min(ev.index, len(branch) - 2)
    y = np.asarray(getattr(branch, quantity), float)
    pa, pb = branch.parameter[i], branch.parameter[i + 1]
    w = 0.0 if pb == pa else (ev.parameter - pa) / (pb - pa)
    return float(y[i] + w * (y[i + 1] - y[i]))
