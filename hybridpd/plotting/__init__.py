"""Figures in the paper's style (matplotlib, Agg-safe; every function returns the Figure).

* :func:`plot_regions` — Figs 4-5: existence and stability regions for several ``e``
  superposed; the intersection (exists and stable) shaded.
* :func:`plot_basin` — Figs 6-7: the basin slice ``(x1, y1)`` coloured by the attractor each
  point reaches (colour-blind-safe), the attractors' section points marked, each basin's share
  in the legend.
* :func:`plot_trajectory` — positions, gap and impacts against time, and the phase portrait;
  :func:`plot_model_trajectory` the same for a mechanical model with any number of DOFs,
  and :func:`plot_trajectory_samples` from arrays (e.g. a ``simulate --out`` JSON file).
* :func:`plot_bifurcation` — a brute-force bifurcation diagram (iterates of the impact map
  against a parameter) with continued branches overlaid.
* :func:`plot_region_panels` — Figs 4-5 with one panel per ``e``;
  :func:`plot_orbit_phase` — Fig. 3, the secondary mass's phase plane on the orbit.
* :func:`plot_scaled_regions`, :func:`plot_m2_study`, :func:`plot_param_study` — the
  reproduction's m2-free picture and studies.
* :func:`plot_file` — any result file hybridpd writes, its kind read from its metadata
  (``hybridpd plot``).

Every figure is drawn in one house style for print (:mod:`hybridpd.plotting.style`: final
size 3.5 or 7.2 in wide, no text under 7 pt, Okabe-Ito colours with a second encoding, units
on the axes), applied inside each function, never globally.
"""
from hybridpd.plotting.basins import plot_basin
from hybridpd.plotting.bifurcation import plot_bifurcation
from hybridpd.plotting.files import plot_file
from hybridpd.plotting.orbit import plot_orbit_phase
from hybridpd.plotting.regions import plot_region_panels, plot_regions
from hybridpd.plotting.studies import plot_m2_study, plot_param_study, plot_scaled_regions
from hybridpd.plotting.trajectory import (
    plot_model_trajectory,
    plot_trajectory,
    plot_trajectory_samples,
)

__all__ = ["plot_basin", "plot_bifurcation", "plot_file", "plot_m2_study",
           "plot_model_trajectory", "plot_orbit_phase", "plot_param_study",
           "plot_region_panels", "plot_regions", "plot_scaled_regions", "plot_trajectory",
           "plot_trajectory_samples"]
