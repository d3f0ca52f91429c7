"""Figures in the paper's style (matplotlib, Agg-safe; every function returns the Figure).

* :func:`plot_regions` — Figs 4-5: existence and stability regions for several ``e``
  superposed; the intersection (exists and stable) shaded.
* :func:`plot_basin` — Figs 6-7: the basin slice ``(x1, y1)`` coloured by the attractor each
  point reaches (colour-blind-safe), the attractors' section points marked, each basin's share
  in the legend.
* :func:`plot_trajectory` — positions, gap and impacts against time, and the phase portrait.
* :func:`plot_bifurcation` — a brute-force bifurcation diagram (iterates of the impact map
  against a parameter) with continued branches overlaid.
"""
from hybridpd.plotting.basins import plot_basin
from hybridpd.plotting.bifurcation import plot_bifurcation
from hybridpd.plotting.regions import plot_regions
from hybridpd.plotting.trajectory import plot_trajectory

__all__ = ["plot_basin", "plot_bifurcation", "plot_regions", "plot_trajectory"]
