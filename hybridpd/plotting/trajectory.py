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

_MAX_PHASE = 4  # phase portraits drawn (one per DOF, the first ones), to fit 7.2 in


def _contact(c) -> dict:
    return {"name": str(c.get("name") or ""), "normal": np.asarray(c["normal"], float),
            "lo": c.get("lo"), "hi": c.get("hi")}


def plot_trajectory_samples(t, q, v, *, dofs=None, contacts=(), impact_times=(),
                            impact_contacts=None, impact_states=None, sticking=(),
                            title=None, fig=None):
    """Positions and contact gaps against time with the impacts marked, and phase portraits.

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
    >>> len(fig.axes)
    4
    """
    with house_style():
        return _plot_samples(t, q, v, dofs=dofs, contacts=contacts, impact_times=impact_times,
                             impact_contacts=impact_contacts, impact_states=impact_states,
                             sticking=sticking, title=title, fig=fig)


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
    npp = min(n, _MAX_PHASE)
    rows = 3 if contacts else 2
    fig = fig or Figure(figsize=(DOUBLE, min(MAX_HEIGHT, 2.0 * rows + 0.8)),
                        layout="constrained")
    gs = fig.add_gridspec(rows, npp)
    ax = fig.add_subplot(gs[0, :])
    for i in range(n):
        s = series(i)
        ax.plot(t, q[:, i], lw=1.0, color=s["color"], ls=s["ls"], label=dofs[i])
    if it.size:
        ax.plot(it, np.full(it.size, np.nanmin(q) if q.size else 0.0), "k|", ms=8,
                label="impacts")
    _shade(ax, sticking, label="sticking")
    ax.set_xlabel("$t$ (time)")
    ax.set_ylabel("position (length)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    if title:
        ax.set_title(title)
    if contacts:
        axg = fig.add_subplot(gs[1, :], sharex=ax)
        pre = None if impact_states is None else np.asarray(impact_states, float)
        marked = False
        for k, c in enumerate(contacts):
            w = c["normal"]
            sk = series(k)
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
        axg.set_xlabel("$t$ (time)")
        axg.set_ylabel("gap (length)")
        axg.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    for i in range(npp):
        axp = fig.add_subplot(gs[rows - 1, i])
        s = series(i)
        axp.plot(q[:, i], v[:, i], lw=0.8, color=s["color"], ls=s["ls"])
        axp.set_xlabel(f"{dofs[i]} (length)")
        axp.set_ylabel(f"d{dofs[i]}/dt (length/time)")
        axp.set_title(f"phase portrait: {dofs[i]}")
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
    for k, s in enumerate(sticking):
        ax.axvspan(s[0], s[1], facecolor="#D55E00", alpha=0.15, hatch="//", edgecolor="none",
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
