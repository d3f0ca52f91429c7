"""plot trajectory: see :mod:`hybridpd.plotting`."""
from __future__ import annotations

import numpy as np


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
