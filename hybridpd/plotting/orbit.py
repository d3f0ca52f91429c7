"""Fig. 3 of the paper on computed orbits: the secondary mass in its phase plane, p0 -> p4.

The cycle of the symmetric orbit: ``p0 = (x20, y20)`` (pre-impact on the ``+L`` wall) jumps to
``p1 = (x20, y21)`` (``y21 = R y20``), flows to ``p2 = (-x20, -y20)``, jumps to
``p3 = (-x20, -y21)`` and flows back to ``p4 = p0``.
"""
from __future__ import annotations

import numpy as np

from hybridpd.plotting._common import _COLORS

__all__ = ["plot_orbit_phase"]


def plot_orbit_phase(orbits, *, params=None, samples=200, title=None):
    """Phase plane ``(x2, y2)`` of the secondary mass on symmetric orbits, one panel per case.

    Parameters
    ----------
    orbits : list of SymmetricOrbitResult
        Orbits that do not exist are listed in their panel's note, not drawn.
    params : dict, optional
        ``mu, gamma, omega, n, m2, x10`` for the caption.
    samples : int
        Points per half-cycle flight.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    from hybridpd.plotting.regions import _legend_from_gids, param_line

    cases = list(dict.fromkeys(o.case.value for o in orbits))
    fig = Figure(figsize=(5.6 * len(cases), 5.4), layout="constrained")
    axes = []
    for i, case in enumerate(cases):
        ax = fig.add_subplot(1, len(cases), i + 1)
        missing = []
        labelled = False
        for k, o in enumerate(o for o in orbits if o.case.value == case):
            e = o.pair.e
            if not o.exists:
                missing.append(f"e = {e:g}: no orbit")
                continue
            c = _COLORS[k % len(_COLORS)]
            t = np.linspace(o.t0, o.t0 + o.tau, samples)
            X = o.flight(t)
            x2, y2 = X[:, 2], X[:, 3]
            tag = f"e = {e:g}" + ("" if o.stable else " (unstable)")
            ax.plot(x2, y2, color=c, lw=1.4, gid=tag)
            ax.plot(-x2, -y2, color=c, lw=1.4)
            p0, p1 = o.pre_plus[2:], o.post_plus[2:]
            ax.plot([p0[0], p1[0]], [p0[1], p1[1]], color=c, ls=":", lw=1.2,
                    gid="impact jump (virtual restitution R)")
            ax.plot([-p0[0], -p1[0]], [-p0[1], -p1[1]], color=c, ls=":", lw=1.2)
            if not labelled:
                for name, (px, py), dx in (("$p_0 = p_4$", p0, 8), ("$p_1$", p1, 8),
                                           ("$p_2$", -p0, -8), ("$p_3$", -p1, -8)):
                    ax.plot(px, py, "o", color="k", ms=4)
                    ax.annotate(name, (px, py), textcoords="offset points",
                                xytext=(dx, 4), ha="left" if dx > 0 else "right", fontsize=9)
                labelled = True
        ax.axvline(0, color="0.7", lw=0.6)
        ax.axhline(0, color="0.7", lw=0.6)
        ax.set_xlabel("$x_2$")
        ax.set_ylabel("$y_2$")
        ax.set_title(f"{case} PD, $k_p$ = {orbits[0].gains.kp:g}, $k_v$ = {orbits[0].gains.kv:g}"
                     + (f"\n({'; '.join(missing)})" if missing else ""), fontsize=9)
        ax.margins(0.12)
        axes.append(ax)
    _legend_from_gids(fig, axes, ncol=5)
    par = params or {}
    fig.suptitle(title or f"Fig. 3: secondary mass on the symmetric orbit; {param_line(par)}",
                 fontsize=10)
    return fig
