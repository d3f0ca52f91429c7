"""plot trajectory: see :mod:`hybridpd.plotting`.

:func:`plot_trajectory_samples` draws from arrays (sampled positions and velocities of any
number of degrees of freedom, the contacts' gaps and the impacts), so that a trajectory
written to JSON by ``hybridpd simulate --out`` can be drawn again without simulating;
:func:`plot_trajectory` (the impact pair) and :func:`plot_model_trajectory` (a mechanical
model) sample a simulated trajectory and call it.
"""
from __future__ import annotations

import numpy as np

from hybridpd.plotting.style import DOUBLE, MAX_HEIGHT, house_style, series

__all__ = ["plot_model_trajectory", "plot_trajectory", "plot_trajectory_samples"]

#: lines per time panel: the series' styles (colour, dash, marker) never repeat in a panel
_GROUP = 6
#: phase portraits (one per DOF) drawn up to this many DOFs; beyond, only the time panels
_MAX_PHASE = 12
#: columns of the phase-portrait grid at most (1.44 in each at 7.2 in wide)
_PHASE_COLS = 5


def _contact(c) -> dict:
    return {"name": str(c.get("name") or ""), "normal": np.asarray(c["normal"], float),
            "lo": c.get("lo"), "hi": c.get("hi")}


def plot_trajectory_samples(t, q, v, *, dofs=None, contacts=(), impact_times=(),
                            impact_contacts=None, impact_states=None, sticking=(),
                            title=None, fig=None):
    """Positions and contact gaps against time with the impacts marked, and phase portraits.

    Every degree of freedom is drawn: positions and gaps in panels of at most six lines
    (one line style each), and one phase portrait per DOF in a grid of at most five columns
    (up to twelve DOFs; beyond, the time panels only), on a figure 7.2 in wide and at most
    9 in high.

    Parameters
    ----------
    t : array_like, shape (N,)
        Sampling times.
    q, v : array_like, shape (N, n)
        Positions and velocities of the ``n`` degrees of freedom at `t`.
    dofs : sequence of str, optional
        Names of the degrees of freedom (default ``q1 .. qn``).
    contacts : sequence of dict
        Each ``{"normal": (n,), "lo": float or None, "hi": float or None, "name": str}``: the
        gap ``normal . q`` is drawn with its bounds.
    impact_times : array_like, shape (k,)
    impact_contacts : array_like of int, shape (k,), optional
        Contact index of each impact (default 0).
    impact_states : array_like, shape (k, 2n), optional
        Pre-impact states ``[q_1, v_1, ..., q_n, v_n]``: the impacts are marked on the gap at
        their own positions (otherwise as ticks on the time axis).
    sticking : sequence of (t_start, t_end, ...)
        Intervals held on a contact, shaded.
    title : str, optional
    fig : matplotlib Figure, optional
        Drawn into; else a new figure 7.2 in wide in the house style.

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 1, 50)
    >>> q = np.c_[np.sin(t), np.cos(t)]
    >>> fig = plot_trajectory_samples(t, q, np.gradient(q, t, axis=0), dofs=["x1", "x2"],
    ...                               contacts=[{"normal": [1, -1], "lo": -1, "hi": 1}])
    >>> len(fig.axes)      # positions, the gap, two phase portraits
    4
    """
    with house_style():
        return _plot_samples(t, q, v, dofs=dofs, contacts=contacts, impact_times=impact_times,
                             impact_contacts=impact_contacts, impact_states=impact_states,
                             sticking=sticking, title=title, fig=fig)


def _groups(n: int, size: int = _GROUP) -> list:
    """``range(n)`` cut into ``ceil(n / size)`` consecutive groups of near-equal length."""
    return [list(g) for g in np.array_split(np.arange(n), -(-n // size))] if n else []


def _plot_samples(t, q, v, *, dofs, contacts, impact_times, impact_contacts, impact_states,
                  sticking, title, fig):
    from matplotlib.figure import Figure

    t = np.asarray(t, float)
    q = np.asarray(q, float).reshape(t.size, -1)
    v = np.asarray(v, float).reshape(t.size, -1)
    n = q.shape[1]
    dofs = [f"q{i + 1}" for i in range(n)] if dofs is None else list(dofs)
    if len(dofs) != n or v.shape != q.shape:
        raise ValueError(f"q and v must have shape (len(t), len(dofs)) = ({t.size}, "
                         f"{len(dofs)}), got {q.shape} and {v.shape}")
    contacts = [_contact(c) for c in contacts]
    it = np.asarray(impact_times, float).ravel()
    ic = np.zeros(it.size, int) if impact_contacts is None else np.asarray(impact_contacts, int)
    # every DOF is drawn: positions and gaps in panels of at most _GROUP lines, and a grid of
    # phase portraits (up to _MAX_PHASE DOFs, beyond which they would be too small to read)
    pos_groups, gap_groups = _groups(n), _groups(len(contacts))
    phase = n <= _MAX_PHASE
    prow = -(-n // _PHASE_COLS) if phase else 0
    pcol = -(-n // prow) if phase else 1
    heights = [1.45] * (len(pos_groups) + len(gap_groups)) + [1.55] * prow
    fig = fig or Figure(figsize=(DOUBLE, min(MAX_HEIGHT, sum(heights) + 0.35)),
                        layout="constrained")
    gs = fig.add_gridspec(len(heights), pcol, height_ratios=heights)
    row = 0
    first = None
    for g, idx in enumerate(pos_groups):
        ax = fig.add_subplot(gs[row, :], sharex=first)
        first = first or ax
        row += 1
        for i in idx:
            s = series(i - idx[0])
            ax.plot(t, q[:, i], lw=1.0, color=s["color"], ls=s["ls"], label=dofs[i])
        if it.size and g == 0:
            ax.plot(it, np.full(it.size, np.nanmin(q) if q.size else 0.0), "k|", ms=8,
                    label="impacts")
        _shade(ax, sticking, label="sticking" if g == 0 else None)
        ax.set_ylabel("position (length)")
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
        if g == 0 and title:
            ax.set_title(title)
    pre = None if impact_states is None else np.asarray(impact_states, float)
    for g, idx in enumerate(gap_groups):
        axg = fig.add_subplot(gs[row, :], sharex=first)
        row += 1
        marked = False
        for k in idx:
            c = contacts[k]
            w = c["normal"]
            sk = series(k - idx[0])
            line, = axg.plot(t, q @ w, lw=1.0, color=sk["color"], ls=sk["ls"],
                             label=_gap_label(c, dofs, k))
            for b in (c["lo"], c["hi"]):
                if b is not None:
                    axg.axhline(b, color=line.get_color(), lw=0.6, ls=":")
            sel = ic == k
            if sel.any():
                y = (pre[sel][:, 0:2 * n:2] @ w if pre is not None and pre.size
                     else np.full(int(sel.sum()), np.nan))
                axg.plot(it[sel], y, "|", color="k", ms=8, label=None if marked else "impacts")
                marked = True
        _shade(axg, sticking)
        axg.set_ylabel("gap (length)")
        axg.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    for ax in fig.axes:
        ax.set_xlabel("$t$ (time)" if ax is fig.axes[-1] else "")
        if ax is not fig.axes[-1]:
            ax.tick_params(labelbottom=False)
    if not phase:
        fig.axes[-1].set_xlabel(f"$t$ (time); phase portraits are drawn for at most "
                                f"{_MAX_PHASE} DOFs ({n} here)")
    for i in range(n if phase else 0):
        axp = fig.add_subplot(gs[row + i // pcol, i % pcol])
        s = series(i)
        axp.plot(q[:, i], v[:, i], lw=0.8, color=s["color"], ls=s["ls"])
        axp.set_title(f"phase portrait: {dofs[i]}")
        axp.set_xlabel("position (length)")
        axp.set_ylabel("velocity (length/time)" if i % pcol == 0 else "")
    if fig.get_layout_engine() is None:
        fig.tight_layout()
    return fig


def _gap_label(c, dofs, k):
    terms = []
    for w, name in zip(c["normal"], dofs):
        if w == 0:
            continue
        sign = "-" if w < 0 else "+"
        mag = "" if abs(w) == 1 else f"{abs(w):g} "
        terms.append(f"{sign} {mag}{name}")
    text = " ".join(terms).lstrip("+ ") if terms else "0"
    if text.startswith("- "):
        text = "-" + text[2:]
    return f"{c['name'] or f'contact {k}'}: {text}"


def _shade(ax, sticking, label=None):
    # overlapping intervals of several contacts are shaded once: stacked translucent spans
    # would darken where more contacts stick, which the legend does not explain
    merged = []
    for a, b in sorted((float(s[0]), float(s[1])) for s in sticking):
        if merged and a <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], b)
        else:
            merged.append([a, b])
    for k, (a, b) in enumerate(merged):
        ax.axvspan(a, b, facecolor="#D55E00", alpha=0.15, hatch="//", edgecolor="none",
                   label=label if k == 0 else None)


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
    segs = traj.hybrid.segments
    t0 = float(segs[0].t_start) if len(segs) else 0.0
    t = np.linspace(t0, traj.t_final, 2000) if t is None else np.asarray(t, float)
    X = traj(t)
    return plot_trajectory_samples(
        t, X[:, 0::2][:, :2], X[:, 1::2][:, :2], dofs=["x1", "x2"],
        contacts=[{"name": "gap", "normal": [1.0, -1.0], "lo": -L, "hi": L}],
        impact_times=traj.impact_times, impact_states=traj.pre,
        sticking=traj.sticking, fig=fig)


def plot_model_trajectory(traj, model, t=None, fig=None):
    """:func:`plot_trajectory_samples` of a mechanical model's trajectory.

    Parameters
    ----------
    traj : MechanicalTrajectory
    model : MechanicalModel
        The loaded model file (names of the DOFs, contacts).
    t : array_like, optional
        Sampling times (default: 2000 points over ``[t0, t_final]``).
    """
    t = np.linspace(model.t0, traj.t_final, 2000) if t is None else np.asarray(t, float)
    Z = traj.mechanical(t)
    contacts = [{"name": c.name, "normal": c.normal, "lo": c.lo, "hi": c.hi}
                for c in model.contacts]
    return plot_trajectory_samples(
        t, Z[:, 0::2], Z[:, 1::2], dofs=model.system.dofs, contacts=contacts,
        impact_times=traj.impact_times, impact_contacts=traj.contacts,
        impact_states=traj.pre, sticking=traj.sticking, title=model.source, fig=fig)
