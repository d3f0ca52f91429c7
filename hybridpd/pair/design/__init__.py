"""Gain design: PD gains and reference that make a desired primary-mass motion a stable orbit.

The user states the desired motion of the primary mass — a triangle wave of amplitude ``x10``
(length) and frequency ``omega`` (rad/time) with one impact on each wall per ``n`` reference
periods (``n`` odd) — the plant (``m2``, ``mu``, ``e``, ``L``) and the feedback case. For
every gain pair ``(kp, kv)`` the conditions (13)-(14) then fix the reference amplitude ``xm``
and the impact phase ``phi0`` (:func:`hybridpd.pair.orbits.symmetric_orbits`); the design chooses
the gains.

Objective (maximised)
---------------------
For a gain pair whose symmetric orbit exists (solvable with ``xm > 0`` and viable) and is
stable, with spectral radius ``rho`` of ``DP`` and viability margin ``nu`` (distance to
grazing, ``min (L - |z3|)/L`` over the interior turning points of ``z3``, 1 when ``z3`` is
monotone between the impacts):

* ``objective="min"`` (default): ``J = min(1 - rho, w * nu)`` — the design is as good as its
  weaker margin; ``w = viability_weight`` (default 1) trades a unit of viability margin
  against a unit of stability margin (``w > 0`` required).
* ``objective="sum"``: ``J = (1 - rho) + w * nu``; with a small ``w`` this is the
  lexicographic choice "best stability margin, then the farthest from grazing". ``w = 0``
  ignores grazing, and the optimum may then sit on the existence boundary (19): at
  ``mu = 1, e = 0.5, gamma = 0.75, omega = 5`` (collocated) it has ``nu ~ 1e-8``, while the
  default ``min`` objective balances ``1 - rho = nu = 0.285``.

Both are > 0 exactly on the feasible set (exists and stable). Outside it the search uses a
penalty ``<= 0`` that keeps the optimiser pointed back at the feasible set: ``max(1 - rho, -1)``
for an existing but unstable orbit, ``-1 + max(min(nu, 0), -1)`` when viability fails, ``-3``
when the conditions have no solution or the masses stick.

Search
------
Global, then local: the objective is evaluated (vectorised) on a ``grid`` over the gain box
(``kp_range x kv_range``, default ``[0.1, 100]^2``, log-spaced by default: the feasible
regions span decades), the best ``n_starts`` separated local maxima of the grid are refined
with bounded Nelder-Mead (:func:`scipy.optimize.minimize`, in normalised log or linear
coordinates), and the best refined point is re-evaluated with
:func:`hybridpd.pair.orbits.symmetric_orbit`. The map and the optimiser reports are returned as
evidence. If no grid point is feasible (and no refinement finds one)
:class:`InfeasibleDesignError` is raised.

Robust design
-------------
With uncertainty boxes for ``e`` and/or ``mu`` the gains *and* the reference amplitude ``xm``
stay those designed for the nominal plant; the reference phase is free (the system settles
wherever). A plant ``(e', mu')`` then settles on the symmetric orbit with the same ``xm`` and
another primary-mass amplitude ``x10'``. Because (13)-(14) are linear in
``(C, S) = xm (cos w t0, sin w t0)`` with right-hand sides affine in ``x10`` (``L`` fixed),
``C = C0 + x10 C1``, ``S = S0 + x10 S1`` and ``xm(x10)^2 = xm_design^2`` is a quadratic in
``x10``. Of its positive roots, **the orbit is the one closest to the desired** ``x10`` (the
branch continued from the nominal plant while the two roots stay apart; the other root is
typically an unstable saddle-type orbit at small amplitude and is reported as ``x10_alt``).
A plant fails if there is no positive root, the orbit does not exist or is unstable, or
``|x10'/x10 - 1| > x10_tol``. The robust objective is the worst case of ``J`` over the plants
(an ``uncertainty_grid`` over the box, corners included, plus the nominal plant); it is
positive exactly when every plant passes. The worst case and where it happens are reported,
and the design is re-checked on a finer validation grid.

Examples
--------
>>> from hybridpd.pair.design import design
>>> d = design("collocated", mu=0.1, e=0.5, gamma=0.75, omega=5.0, grid=(24, 24))
>>> d.orbit.exists and d.orbit.stable
True
>>> 0 < d.spectral_radius < 1
True

Modules
-------
``objective`` (the objective, shifted orbits of perturbed plants), ``results`` (result
objects), ``search`` (:func:`design`, :func:`robustness`) and ``comparison``
(:func:`robustness_comparison`); everything is importable from this package.
"""
from __future__ import annotations

from hybridpd.pair.design.comparison import (
    ComparisonRow,
    RobustnessComparison,
    robustness_comparison,
)
from hybridpd.pair.design.objective import (
    PLANT_STATUS,
    design_objective,
    shifted_amplitude,
    shifted_orbit,
)
from hybridpd.pair.design.results import (
    DesignMap,
    DesignResult,
    InfeasibleDesignError,
    OptimizerRun,
    RobustReport,
)
from hybridpd.pair.design.search import design, robustness

__all__ = ["PLANT_STATUS", "ComparisonRow", "DesignMap", "DesignResult", "InfeasibleDesignError",
           "OptimizerRun", "RobustReport", "RobustnessComparison", "design", "design_objective",
           "robustness", "robustness_comparison", "shifted_amplitude", "shifted_orbit"]
