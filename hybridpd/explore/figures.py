"""The explorer's saved figures and data: what each panel's buttons write.

Figures are the package's, in the house style (:mod:`hybridpd.plotting.style`): the region
map of ``hybridpd regions --plot``, the basin of ``hybridpd basin --plot``, the branch of
:func:`hybridpd.plotting.branches.plot_branch`, and two drawn here for the selected orbit (its
time series and phase portrait, and its multipliers on the unit circle). Data are the
command line's result files, written by the results' own ``save`` (a region map ``.nc``,
a basin ``.npz``, a branch ``.nc``) or, for an orbit, ``hybridpd orbit --json``'s object
(:meth:`~hybridpd.pair.orbits.SymmetricOrbitResult.to_dict`).
"""
from __future__ import annotations

import io
import tempfile
from pathlib import Path

import numpy as np

from hybridpd.explore.state import orbit_series
from hybridpd.plotting.style import DOUBLE, axis_label, house_figure, series, styled

__all__ = ["PANELS", "data_bytes", "figure_bytes", "figure_of", "plot_multipliers",
           "plot_orbit"]

#: The panels whose figure and data can be saved, and the suffix of their data file.
PANELS = {"map": ".nc", "orbit": ".json", "multipliers": ".json", "basin": ".npz",
          "branch": ".nc"}


def _gains_title(orb) -> str:
    return (f"{orb.case.value.replace('non', 'non-')} PD, $k_p$ = {orb.gains.kp:.6g}, "
            f"$k_v$ = {orb.gains.kv:.6g}, e = {orb.pair.e:g}")


@styled
def plot_orbit(orb, samples: int = 200):
    """The orbit over one period: positions and the gap ``z3 = x1 - x2`` against time (the
    walls ``z3 = +-L`` and the impacts marked) and the phase portrait of both masses.

    Parameters
    ----------
    orb : SymmetricOrbitResult
        An orbit that exists.
    samples : int
        Points per half-period.

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> import hybridpd as hp
    >>> orb = hp.symmetric_orbit(hp.ImpactPair(0.1, 0.5, 0.75), hp.PDGains(10, 20), 5.0)
    >>> [ax.get_xlabel() for ax in plot_orbit(orb).axes]
    ['$t$ (time)', '$t$ (time)', 'position (length)']
    """
    s = orbit_series(orb, samples)
    fig = house_figure(DOUBLE, 2.8)
    a, b, c = fig.subplots(1, 3)
    st1, st2 = series(0), series(1)
    a.plot(s["t"], s["x1"], color=st1["color"], ls=st1["ls"], label="$x_1$")
    a.plot(s["t"], s["x2"], color=st2["color"], ls=st2["ls"], label="$x_2$")
    a.plot(s["impact_t"], s["impact_pre"][:, 0], "kv", ms=4, label="impact")
    a.set_xlabel(axis_label("t"))
    a.set_ylabel("position (length)")
    a.legend(loc="best")
    L = orb.pair.L
    b.plot(s["t"], s["z3"], color="k", label="$z_3 = x_1 - x_2$")
    for w in (L, -L):
        b.axhline(w, color="0.5", ls="--", lw=0.8)
    b.plot(s["impact_t"], [L, -L], "kv", ms=4)
    b.set_xlabel(axis_label("t"))
    b.set_ylabel("gap $z_3$ (length)")
    b.set_title(f"viability margin {orb.viability_margin:.4g}")
    for k, (x, y) in enumerate((("x1", "y1"), ("x2", "y2"))):
        st = series(k)
        c.plot(s[x], s[y], color=st["color"], ls=st["ls"], label=f"mass {k + 1}")
        pre, post = s["impact_pre"], s["impact_post"]
        for j in range(2):     # the velocity jump at each impact, dotted
            c.plot([pre[j, 2 * k], post[j, 2 * k]], [pre[j, 2 * k + 1], post[j, 2 * k + 1]],
                   color=st["color"], ls=":", marker="o", ms=3)
    c.set_xlabel("position (length)")
    c.set_ylabel("velocity (length/time)")
    c.legend(loc="best")
    fig.suptitle(_gains_title(orb) + f", n = {orb.n}: {orb.reason}")
    return fig


@styled
def plot_multipliers(orb):
    """The Floquet multipliers of the orbit (eigenvalues of ``DP``) on the unit circle.

    Examples
    --------
    >>> import hybridpd as hp
    >>> orb = hp.symmetric_orbit(hp.ImpactPair(0.1, 0.5, 0.75), hp.PDGains(10, 20), 5.0)
    >>> len(plot_multipliers(orb).axes[0].lines)
    2
    """
    if orb.multipliers is None:
        raise ValueError(f"the orbit does not exist ({orb.reason}): no multipliers")
    fig = house_figure("single", 3.4)
    ax = fig.add_subplot(1, 1, 1)
    th = np.linspace(0, 2 * np.pi, 361)
    ax.plot(np.cos(th), np.sin(th), color="0.5", lw=0.8, label="unit circle")
    z = np.asarray(orb.multipliers)
    ax.plot(z.real, z.imag, "o", color=series(0)["color"], ms=5, mfc="none",
            label="multipliers")
    ax.set_aspect("equal")
    lim = max(1.1, 1.1 * float(np.max(np.abs(z))))
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_xlabel("Re $\\lambda$")
    ax.set_ylabel("Im $\\lambda$")
    verdict = "stable" if orb.stable else "unstable"
    ax.set_title(f"spectral radius {orb.spectral_radius:.10g} ({verdict})")
    return fig


def figure_of(panel: str, result):
    """The house-style figure of a panel's result (``panel`` from :data:`PANELS`)."""
    if panel == "map":
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.plotting.regions import plot_region_panels

        return plot_region_panels(result)
    if panel == "orbit":
        return plot_orbit(result)
    if panel == "multipliers":
        return plot_multipliers(result)
    if panel == "basin":
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.plotting.basins import plot_basin

        return plot_basin(result)
    if panel == "branch":
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.plotting.branches import plot_branch
        from hybridpd.plotting.style import house_style

        with house_style():
            return plot_branch(result)
    raise ValueError(f"panel must be one of {', '.join(PANELS)}, got {panel!r}")


def figure_bytes(panel: str, result, fmt: str = "png") -> bytes:
    """The panel's figure as an image file's bytes (300 dpi, as ``--plot`` writes)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.plotting.style import house_style

    fig = figure_of(panel, result)
    buf = io.BytesIO()
    with house_style():
        fig.savefig(buf, format=fmt, dpi=300)
    return buf.getvalue()


def data_bytes(panel: str, result) -> bytes:
    """The panel's result as the command line writes it (suffix :data:`PANELS` ``[panel]``)."""
    if panel not in PANELS:
        raise ValueError(f"panel must be one of {', '.join(PANELS)}, got {panel!r}")
    if panel in ("orbit", "multipliers"):
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.cli._common import dumps_json

        return (dumps_json(result.to_dict()) + "\n").encode()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"{panel}{PANELS[panel]}"
        result.save(path)
        return path.read_bytes()
