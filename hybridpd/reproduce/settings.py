"""Parameters and grid sizes of a reproduction run.

The paper fixes ``mu, gamma, n, omega, e`` and the gains of Figs 6-7 (:data:`PAPER`); it leaves
open the secondary mass ``m2``, the amplitude ``x10`` (only ``gamma = L / x10`` is given) and
the window of the basin slices. Those are fields of :class:`Settings`, never constants of the
pipeline.
"""
from __future__ import annotations

from dataclasses import dataclass

from hybridpd.model import check_positive

__all__ = ["AUTO", "PAPER", "Settings"]

#: The paper's parameters (captions of Figs 4-7).
PAPER = dict(mu=0.1, gamma=0.75, n=1, omega=5.0, e=(0.1, 0.5, 0.9), kp=10.0, kv=20.0)

#: Placeholder for "the ``m2`` chosen by the convention study's rule" in :attr:`Settings.m2`.
AUTO = "auto"


def _pair(name, value, *, positive=True):
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a pair (lo, hi), got {value!r}") from None
    if not lo < hi or (positive and lo <= 0):
        raise ValueError(f"{name} must satisfy {'0 < ' if positive else ''}lo < hi, "
                         f"got {value!r}")
    return lo, hi


def _count(name, value, minimum=2):
    if int(value) != value or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


@dataclass(frozen=True)
class Settings:
    """Conventions and grid sizes of one reproduction run.

    Attributes
    ----------
    gains : (kp_max, kv_max, num)
        Region maps (Figs 4-5) on ``linspace(0.1, max, num)`` for both gains, for ``m2 = 1``;
        for another ``m2`` both axes are multiplied by ``m2`` (only ``kp/m2`` and ``kv/m2``
        matter at fixed ``mu``), so the pictures are comparable.
    zoom : (kp_max, kv_max, num)
        Non-collocated zoom panel (scaled with ``m2`` likewise).
    basin : (num_x1, num_y1)
        Basin grid over :attr:`basin_window`.
    iterations : int
        Iterations of ``P`` for the basin criterion (the paper: 1500).
    traced_boundaries : bool
        Draw the region boundaries of Figs 4-5 as traced curves (pseudo-arclength
        continuation of the test functions, sharp at any zoom) instead of grid contours.
    basin_extensions : int
        The cap on the growths of the basin window: one window is shared by every panel of
        Figs 6-7 and both cases, and grown (each touching side pushed out to twice its
        distance from the fixed point) while some symmetric orbit's basin touches its edge.
        If a basin still touches it after the last growth, its area is a lower bound.
    check_scale : float
        The resolution check of the sampled verdicts (the robustness comparison of
        conclusion 5): recomputed on grids with this many times the cells per axis (about
        twice as fine in full mode, half as fine in quick mode); a verdict that changes is
        ``"unresolved"``. The region verdicts need no such check: they are decided by
        certified shares.
    basin_check_scale : float
        The same for the basin slices, whose cost grows with their cells and with the
        iterations of the weakly damped orbits: half as fine in both modes by default.
    comparison_grid : (int, int)
        Gain grid of the robustness comparison (conclusion 5).
    uncertainty_grid : (int, int)
        Plants ``(e, mu)`` of that comparison's uncertainty box.
    design_search : (n_starts, maxiter)
        Local refinements of the comparison's best designs (they do not change the shares of
        the gain box that conclusion 5 rests on).
    m2 : tuple of float or ``"auto"``
        The conventions for the secondary mass; ``"auto"`` is the smallest value of the 1-2-5
        series at or above every threshold at which all six orbits of Figs 6-7 (both cases,
        every ``e``, the paper's gains) exist and are stable
        (:func:`~hybridpd.reproduce.study.choose_m2`).
    x10 : float
        Primary-mass amplitude; ``L = gamma * x10``.
    basin_window : (x1_min, x1_max, y1_min, y1_max)
        Window of the basin slices in units of ``x10`` (positions) and ``x10`` per time
        (velocities).
    m2_range : (lo, hi)
        Range of the convention study (log axis).
    m2_grid : int
        Points of the log grid on which the stable intervals are bracketed.
    m2_verdicts : int
        Points of the log grid of ``m2`` at which the paper's gain box as printed is read
        (conclusions 1-3, certified shares of the box ``[0.1/m2, 50/m2]^2``).
    m2_robust : int
        Points of that grid on which conclusion 5 (a sampled robustness comparison) is
        re-evaluated, with a gain grid of ``m2_robust_grid`` and 3 x 3 plants.
    certified : (int, int, float)
        ``(grid, levels, width)`` of the certified shares of the scaled box that decide the
        region verdicts (:func:`~hybridpd.reproduce.certified.certified_shares`): base cells
        per axis, refinement levels at most, the undecided share at which refinement stops.
    certified_readings : (int, int, float)
        The same for the readings of the printed box along ``m2`` (where the verdicts need
        less resolution).
    certified_ends : (int, int, float)
        The same for the remarks on ``mu``: the scaled box at ``mu = 1e-4`` and at both ends
        of :attr:`mu_range` (a coarse base grid refined deeper: the proofs at extreme ``mu``
        need smaller cells).
    certified_values : (int, int, float)
        The same for every other value of the ``mu`` and ``gamma`` studies, when
        :attr:`certify_every_value` (existence against ``mu``, existence and stability against
        ``gamma``).
    certify_every_value : bool
        Certify the ``mu`` and ``gamma`` studies at every one of their :attr:`param_points`
        values (full mode). Otherwise the ``mu`` study is certified at the ends of its range,
        at the paper's ``mu`` and at the two values between which its sampled share moves most
        against the remark's trend (:func:`~hybridpd.reproduce.certified.mu_move_values`), and
        the ``gamma`` study is sampled only: certifying ``2 x 3 x param_points`` boxes costs
        several minutes of CPU.
    mu_range, gamma_range : (lo, hi)
        Ranges of the ``mu`` and ``gamma`` studies (log axes).
    param_points : int
        Points of the ``mu`` / ``gamma`` curves and rows of the ``(mu, kv)``, ``(gamma, kv)``
        maps.
    param_grid : int
        Gain-grid size (per axis) of the stable-fraction curves and the ``kv`` axis of the maps.
    """

    gains: tuple
    zoom: tuple
    basin: tuple
    iterations: int = 1500
    basin_extensions: int = 1
    check_scale: float = 2.0
    basin_check_scale: float = 0.5
    traced_boundaries: bool = True
    comparison_grid: tuple = (48, 48)
    uncertainty_grid: tuple = (5, 5)
    design_search: tuple = (3, 150)
    m2: tuple = (1.0, AUTO)
    x10: float = 1.0
    basin_window: tuple = (-3.0, 5.0, -2.0, 10.0)
    m2_range: tuple = (0.1, 1000.0)
    m2_grid: int = 2001
    m2_verdicts: int = 9
    m2_robust: int = 3
    m2_robust_grid: tuple = (12, 12)
    certified: tuple = (16, 3, 0.02)
    certified_readings: tuple = (8, 2, 0.05)
    certified_ends: tuple = (8, 5, 0.05)
    certified_values: tuple = (8, 3, 0.1)
    certify_every_value: bool = False
    mu_range: tuple = (0.01, 10.0)
    gamma_range: tuple = (0.05, 2.0)
    param_points: int = 41
    param_grid: int = 31

    def __post_init__(self):
        for nm in ("gains", "zoom"):
            v = getattr(self, nm)
            if len(v) != 3:
                raise ValueError(f"{nm} must be (kp_max, kv_max, num), got {v!r}")
            check_positive(f"{nm} kp_max", v[0])
            check_positive(f"{nm} kv_max", v[1])
            _count(f"{nm} num", v[2])
        if len(self.basin) != 2:
            raise ValueError(f"basin must be (num_x1, num_y1), got {self.basin!r}")
        for v in self.basin:
            _count("basin num", v)
        _count("iterations", self.iterations, 1)
        _count("basin_extensions", self.basin_extensions + 1, 1)
        check_positive("check_scale", self.check_scale)
        check_positive("basin_check_scale", self.basin_check_scale)
        for v in self.comparison_grid:
            _count("comparison_grid", v)
        for v in self.uncertainty_grid:
            _count("uncertainty_grid", v)
        for v in self.design_search:
            _count("design_search", v, 1)
        if not self.m2:
            raise ValueError("m2 must list at least one convention")
        for v in self.m2:
            if v != AUTO:
                check_positive("m2", v)
        check_positive("x10", self.x10)
        if len(self.basin_window) != 4:
            raise ValueError(f"basin_window must be (x1_min, x1_max, y1_min, y1_max), "
                             f"got {self.basin_window!r}")
        _pair("basin_window x1", self.basin_window[:2], positive=False)
        _pair("basin_window y1", self.basin_window[2:], positive=False)
        for nm in ("m2_range", "mu_range", "gamma_range"):
            _pair(nm, getattr(self, nm))
        _count("m2_grid", self.m2_grid, 3)
        _count("m2_verdicts", self.m2_verdicts, 2)
        _count("m2_robust", self.m2_robust, 1)
        for v in self.m2_robust_grid:
            _count("m2_robust_grid", v)
        for nm in ("certified", "certified_readings", "certified_ends", "certified_values"):
            v = getattr(self, nm)
            if len(v) != 3:
                raise ValueError(f"{nm} must be (grid, levels, width), got {v!r}")
            _count(f"{nm} grid", v[0])
            _count(f"{nm} levels", v[1] + 1, 1)
            if not 0.0 <= float(v[2]) <= 1.0:
                raise ValueError(f"{nm} width must lie in [0, 1], got {v[2]!r}")
        for nm in ("param_points", "param_grid"):
            _count(nm, getattr(self, nm))
        if not isinstance(self.certify_every_value, bool):
            raise ValueError(f"certify_every_value must be True or False, "
                             f"got {self.certify_every_value!r}")

    @classmethod
    def quick(cls, **kw) -> Settings:
        """Coarse grids: under a minute on 2 cores (warm)."""
        base = dict(gains=(50.0, 50.0, 61), zoom=(20.0, 6.0, 61), basin=(41, 41),
                    comparison_grid=(12, 12), uncertainty_grid=(3, 3), design_search=(1, 40),
                    basin_extensions=1, check_scale=0.5, m2_verdicts=5,
                    certified=(16, 3, 0.08), certified_readings=(8, 2, 0.08),
                    certified_ends=(8, 5, 0.08),
                    param_points=25, param_grid=21)
        return cls(**{**base, **kw})

    @classmethod
    def full(cls, **kw) -> Settings:
        """The 200 x 200 grids of the paper's figures (a few minutes on 2 cores)."""
        base = dict(gains=(50.0, 50.0, 201), zoom=(20.0, 6.0, 201), basin=(201, 201),
                    basin_extensions=1, m2_grid=8001, m2_verdicts=9, m2_robust=5,
                    m2_robust_grid=(16, 16), certified=(32, 4, 0.01),
                    certified_readings=(16, 3, 0.02),
                    certified_ends=(16, 5, 0.02), certified_values=(8, 3, 0.1),
                    certify_every_value=True, param_points=31, param_grid=31)
        return cls(**{**base, **kw})

    def check_num(self, num: int, scale: float | None = None) -> int:
        """Points per axis of the resolution check for ``num`` points (at least 3), with
        :attr:`check_scale` or ``scale``."""
        s = self.check_scale if scale is None else scale
        return max(3, round((int(num) - 1) * s) + 1)

    @property
    def gamma(self) -> float:
        return PAPER["gamma"]

    @property
    def L(self) -> float:
        """Half clearance ``gamma * x10``."""
        return PAPER["gamma"] * self.x10
