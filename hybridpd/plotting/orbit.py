"""Fig. 3 of the paper on computed orbits: the secondary mass in its phase plane, p0 -> p4.

The cycle of the symmetric orbit: ``p0 = (x20, y20)`` (pre-impact on the ``+L`` wall) jumps to
``p1 = (x20, y21)`` (``y21 = R y20``), flows to ``p2 = (-x20, -y20)``, jumps to
``p3 = (-x20, -y21)`` and flows back to ``p4 = p0``.
"""
from __future__ import annotations

import numpy as np

from hybridpd.plotting._common import legend_from_gids, line_proxy, param_line, register
from hybridpd.plotting.style import DOUBLE, axis_label, house_figure, series, styled

__all__ = ["plot_orbit_phase"]


@styled
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
        7.2 in wide (3.5 in for one case).
    """
    cases = list(dict.fromkeys(o.case.value for o in orbits))
    fig = house_figure(DOUBLE if len(cases) > 1 else "single", 3.9)
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
            sty = series(k)
            c = sty["color"]
            t = np.linspace(o.t0, o.t0 + o.tau, samples)
            X = o.flight(t)
            x2, y2 = X[:, 2], X[:, 3]
            tag = f"e = {e:g}" + ("" if o.stable else " (unstable)")
            # an unstable orbit: hollow markers (not only another label)
            kw = dict(color=c, lw=1.2, ls=sty["ls"], marker=sty["marker"], ms=3.5,
                      mfc=c if o.stable else "white", markevery=max(1, samples // 6))
            (ln,) = ax.plot(x2, y2, **kw)
            register(ax, ln, tag, line_proxy(**{k_: v for k_, v in kw.items()
                                                 if k_ != "markevery"}))
            ax.plot(-x2, -y2, **kw)
            p0, p1 = o.pre_plus[2:], o.post_plus[2:]
            for sgn in (1, -1):
                (jl,) = ax.plot([sgn * p0[0], sgn * p1[0]], [sgn * p0[1], sgn * p1[1]],
                                color=c, ls=":", lw=1.0)
                register(ax, jl, "impact jump (virtual restitution R)",
                         line_proxy(color="0.3", ls=":", lw=1.0))
            if not labelled:
                for name, (px, py), dx in (("$p_0 = p_4$", p0, 6), ("$p_1$", p1, 6),
                                           ("$p_2$", -p0, -6), ("$p_3$", -p1, -6)):
                    ax.plot(px, py, "o", color="k", ms=3)
                    ax.annotate(name, (px, py), textcoords="offset points",
                                xytext=(dx, 3), ha="left" if dx > 0 else "right")
                labelled = True
        ax.axvline(0, color="0.7", lw=0.6)
        ax.axhline(0, color="0.7", lw=0.6)
        ax.set_xlabel(axis_label("x2"))
        ax.set_ylabel(axis_label("y2"))
        ax.set_title(f"{case.replace('non', 'non-')} PD, $k_p$ = {orbits[0].gains.kp:g}, "
                     f"$k_v$ = {orbits[0].gains.kv:g}"
                     + (f"\n({'; '.join(missing)})" if missing else ""))
        ax.margins(0.12)
        axes.append(ax)
    legend_from_gids(fig, axes, ncol=3)
    par = params or {}
    fig.suptitle(title or f"Fig. 3: secondary mass on the symmetric orbit; {param_line(par)}")
    return fig
