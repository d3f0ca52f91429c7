"""The reproduction pipeline: both ``m2`` conventions, the studies, the figures, the summary.

Layout of the output directory (every figure as PNG at 300 dpi and as PDF)::

    summary.md, summary.json          verdicts and every number behind them
    scaled_regions_collocated.png, scaled_regions_noncollocated.png
                                      Figs 4-5 in (kp/m2, kv/m2), valid for every m2
    m2_study.png, mu_study.png, gamma_study.png
    m2=<value>/                       one directory per convention:
        fig3_orbit.png, fig4_regions_collocated.png, fig5_regions_noncollocated.png,
        fig6_basins_collocated.png, fig7_basins_noncollocated.png,
        regions_*.nc, basin_*.nc, robustness.json
"""
from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.model import ImpactPair, PDGains
from hybridpd.reproduce import conclusions as C
from hybridpd.reproduce.settings import AUTO, PAPER, Settings
from hybridpd.reproduce.study import box_fractions, choose_m2, stable_intervals

__all__ = ["ConventionRun", "M2Study", "m2_study", "reproduce", "run_convention"]

CASES = ("collocated", "noncollocated")


@dataclass
class ConventionRun:
    """Everything computed under one convention ``(m2, x10)``.

    Attributes
    ----------
    m2, x10, gamma, L : float
    scale : float
        Factor applied to the paper's gain box (``= m2``).
    maps : dict
        ``{case: RegionMap}`` on the scaled box, plus ``"zoom"`` (non-collocated).
    shares : dict
        ``{case: {"exists" | "stability" | "both": [share per e]}}`` on the scaled box.
    orbits : dict
        ``{(case, e): SymmetricOrbitResult}`` at the paper's gains.
    basins : dict
        ``{(case, e): BasinResult or None}`` (None: no orbit, or not stable).
    comparison : RobustnessComparison
    checks : dict
        ``{1..5: result of conclusions.check_*}`` on the run's grids.
    check_grid_checks : dict
        The same on the resolution-check grids.
    check_grids : dict
        ``{1..5: [[nx, ny], [nx2, ny2]]}``: the grids behind the two.
    verdicts : dict
        ``{1..5: verdict}``: the run's, or ``"unresolved"`` if the check grid's differs.
    check_shares : dict
        :attr:`shares` on the check grid.
    basin_window : tuple
        The window shared by every basin (physical units); ``basin_windows`` all tried.
    touches_edge : dict
        ``{case: [bool per e]}``: the symmetric orbit's basin touches the window's edge.
    directory : Path
    timings : dict
    """

    m2: float
    x10: float
    gamma: float
    L: float
    scale: float
    maps: dict = field(default_factory=dict)
    shares: dict = field(default_factory=dict)
    orbits: dict = field(default_factory=dict)
    basins: dict = field(default_factory=dict)
    comparison: object = None
    checks: dict = field(default_factory=dict)
    check_grid_checks: dict = field(default_factory=dict)
    check_grids: dict = field(default_factory=dict)
    verdicts: dict = field(default_factory=dict)
    check_shares: dict = field(default_factory=dict)
    basin_window: tuple = None
    basin_windows: list = field(default_factory=list)
    touches_edge: dict = field(default_factory=dict)
    directory: Path = None
    timings: dict = field(default_factory=dict)
    __repr__ = compact_repr


@dataclass
class M2Study:
    """The convention study (see :mod:`hybridpd.reproduce.study`).

    Attributes
    ----------
    intervals : dict
        ``{case: {e: [StableInterval]}}`` at the paper's gains.
    chosen_m2 : float or None
        By :func:`~hybridpd.reproduce.study.choose_m2`.
    grid : ndarray
        ``m2`` values of the verdicts.
    verdicts : dict
        ``{id: [verdict per grid value]}`` (conclusion 5 on :attr:`robust_grid`).
    evidence : dict
        ``{id: [check result per grid value]}``.
    robust_grid : ndarray
    rho : dict
        ``{(case, e): spectral radius along a fine grid}`` for the figure, with ``rho_grid``.
    checked : dict
        ``{id: [verdict per grid value]}`` on the resolution-check grids.
    gain_grids : (int, int)
        Points per axis of the verdict grid and of the check grid.
    """

    intervals: dict
    chosen_m2: float | None
    grid: np.ndarray
    verdicts: dict
    evidence: dict
    robust_grid: np.ndarray
    rho_grid: np.ndarray
    rho: dict
    checked: dict = None
    gain_grids: tuple = None
    __repr__ = compact_repr


def _say(log):
    return log or (lambda *_: None)


def _verdicts_at(m2, kp_axis, kv_axis, common) -> dict:
    """Checks 1-3 on one gain grid at one ``m2``."""
    P = PAPER
    grid = (len(kp_axis), len(kv_axis))
    sh = {case: box_fractions(case, kp_axis, kv_axis, e=P["e"], m2=m2, **common)
          for case in CASES}
    return {1: C.check_1(sh["collocated"], sh["noncollocated"], grid),
            2: C.check_2(sh["collocated"], sh["noncollocated"], grid, P["e"]),
            3: C.check_3(sh["collocated"], grid)}


def m2_study(settings: Settings, *, log=None) -> M2Study:
    """Stable ``m2`` intervals at the paper's gains and every verdict against ``m2``.

    The verdicts use the paper's gain box **as printed** (``kp, kv`` in ``[0.1, max]``, not
    scaled), so they show what Figs 4-7 would say for each ``m2``; each is computed on the
    verdict grid and on the resolution-check grid (:meth:`Settings.check_num`).
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.design import robustness_comparison
    from hybridpd.pair.orbits import symmetric_orbits

    say = _say(log)
    P = PAPER
    common = dict(mu=P["mu"], L=settings.L, omega=P["omega"], x10=settings.x10, n=P["n"])
    intervals = {case: {e: stable_intervals(case, e, kp=P["kp"], kv=P["kv"],
                                            m2_range=settings.m2_range, num=settings.m2_grid,
                                            **common)
                        for e in P["e"]} for case in CASES}
    say("m2 study: stable intervals located")
    chosen = choose_m2({(c, e): iv for c, d in intervals.items() for e, iv in d.items()},
                       settings.m2_range)
    lo, hi = settings.m2_range
    rho_grid = np.logspace(math.log10(lo), math.log10(hi), 400)
    rho = {}
    for case in CASES:
        for e in P["e"]:
            r = symmetric_orbits(P["kp"], P["kv"], m2=rho_grid, e=e, case=case, **common)
            rho[(case, e)] = np.where(r.exists, r.spectral_radius, np.nan)
    grid = np.logspace(math.log10(lo), math.log10(hi), settings.m2_verdicts)
    axes = [(np.linspace(0.1, settings.gains[0], g), np.linspace(0.1, settings.gains[1], g))
            for g in (settings.verdict_grid, settings.check_num(settings.verdict_grid))]
    verdicts = {k: [] for k in range(1, 6)}
    checked = {k: [] for k in range(1, 6)}
    evidence = {k: [] for k in range(1, 6)}
    for m2 in grid:
        run_g, check_g = (_verdicts_at(m2, kp, kv, common) for kp, kv in axes)
        for k in (1, 2, 3):
            verdicts[k].append(run_g[k]["verdict"])
            checked[k].append(check_g[k]["verdict"])
            evidence[k].append(run_g[k])
        st = {case: [bool(symmetric_orbits(P["kp"], P["kv"], m2=m2, e=e, case=case,
                                           **common).stable) for e in P["e"]]
              for case in CASES}
        v4 = C.check_4_necessary(st["collocated"], st["noncollocated"])
        verdicts[4].append(v4)
        checked[4].append(v4)
        evidence[4].append({"verdict": v4, "stable": st})
    say(f"m2 study: verdicts on {len(grid)} values of m2")
    robust_grid = np.logspace(math.log10(lo), math.log10(hi), settings.m2_robust)
    for m2 in robust_grid:
        for g, out in ((settings.m2_robust_grid, verdicts[5]),
                       (tuple(settings.check_num(v) for v in settings.m2_robust_grid),
                        checked[5])):
            cmp = robustness_comparison(mu=P["mu"], gamma=P["gamma"], x10=settings.x10, m2=m2,
                                        n=P["n"], omega=P["omega"], e=0.5, grid=g,
                                        uncertainty_grid=(3, 3), n_starts=1, maxiter=40)
            chk = C.check_5(cmp)
            out.append(chk["verdict"])
            if out is verdicts[5]:
                evidence[5].append(chk)
    say(f"m2 study: conclusion 5 on {len(robust_grid)} values of m2")
    return M2Study(intervals, chosen, grid, verdicts, evidence, robust_grid, rho_grid, rho,
                   checked, (settings.verdict_grid, settings.check_num(settings.verdict_grid)))


def _regions(run, settings, common, *, progress, tick):
    """Region maps of Figs 4-5 on the scaled box (saved as .nc) and their shares on the
    run's grid and on the resolution-check grid."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.regions import SymmetricFamily
    from hybridpd.sweeps.regions import region_map

    s, d, m2 = run.scale, run.directory, run.m2
    kpm, kvm, num = settings.gains
    num2 = settings.check_num(num)
    for case in CASES:
        t0 = time.perf_counter()
        rm = region_map(SymmetricFamily(case, **common), x=("kp", 0.1 * s, kpm * s, num),
                        y=("kv", 0.1 * s, kvm * s, num), progress=progress)
        rm.save(d / f"regions_{case}.nc")
        run.maps[case] = rm
        run.shares[case] = box_fractions(case, rm.x, rm.y, **common)
        run.check_shares[case] = box_fractions(
            case, np.linspace(0.1 * s, kpm * s, num2), np.linspace(0.1 * s, kvm * s, num2),
            **common)
        run.timings[f"regions {case}"] = time.perf_counter() - t0
        tick(f"m2 = {m2:g}: regions {case}")
    zk, zv, zn = settings.zoom
    run.maps["zoom"] = region_map(SymmetricFamily("noncollocated", **common),
                                  x=("kp", 0.1 * s, zk * s, zn), y=("kv", 0.1 * s, zv * s, zn),
                                  progress=progress)
    run.maps["zoom"].save(d / "regions_noncollocated_zoom.nc")


def _basins(run, settings, *, executor, max_workers, progress, say):
    """Figs 6-7: every basin on one shared window (grown up to the cap), relabelled on the
    check grid; returns the check grid's basins."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.basins import relabel, shared_window_basins

    P = PAPER
    t0 = time.perf_counter()
    w = settings.basin_window
    x10 = settings.x10
    res = shared_window_basins(run.orbits, tuple(v * x10 for v in w), settings.basin,
                               n_iter=settings.iterations,
                               max_growths=settings.basin_extensions, executor=executor,
                               max_workers=max_workers, progress=progress,
                               log=lambda m: say(f"m2 = {run.m2:g}: {m}"))
    run.basins = res.basins
    run.basin_window = res.window
    run.basin_windows = res.windows
    run.touches_edge = {case: [res.touches_edge[(case, e)] for e in P["e"]] for case in CASES}
    for (case, e), b in res.basins.items():
        if b is not None:
            b.save(run.directory / f"basin_{case}_e{e:g}.nc")
    run.timings["basins"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    grid2 = tuple(settings.check_num(v, settings.basin_check_scale) for v in settings.basin)
    check = relabel(run.orbits, res.window, grid2, n_iter=settings.iterations,
                    executor=executor, max_workers=max_workers, progress=progress)
    run.timings["basins (resolution check)"] = time.perf_counter() - t0
    return check, grid2


def _check_4(run, basins, grid, settings):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.basins import boundary_distance

    P = PAPER
    touches = {case: [bool(basins[(case, e)] is not None and basins[(case, e)].reaches_edge)
                      for e in P["e"]] for case in CASES}
    area = lambda case: [None if basins[(case, e)] is None
                         else basins[(case, e)].measure(0).area for e in P["e"]]
    dist = {case: [None if basins[(case, e)] is None else
                   boundary_distance(basins[(case, e)], x10=settings.x10, omega=P["omega"])
                   for e in P["e"]] for case in CASES}
    return C.check_4(area("collocated"), area("noncollocated"), touches,
                     window=run.basin_window, grid=grid, distance=dist)


def _comparison(m2, settings, grid, n_starts, maxiter):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.design import robustness_comparison

    P = PAPER
    return robustness_comparison(
        mu=P["mu"], gamma=P["gamma"], x10=settings.x10, m2=m2, n=P["n"], omega=P["omega"],
        e=0.5, grid=grid, uncertainty_grid=settings.uncertainty_grid, n_starts=n_starts,
        maxiter=maxiter, kp_range=(0.1 * m2, 100.0 * m2), kv_range=(0.1 * m2, 100.0 * m2))


def run_convention(m2, settings: Settings, out, *, executor="processes", max_workers=None,
                   progress=False, log=None, tick=None, figure_hook=None,
                   study=None, cache=None) -> ConventionRun:
    """Figs 3-7, their data and the conclusions' checks under one ``m2`` (see module doc).

    Every check is computed on the run's grids and on the resolution-check grids
    (:meth:`Settings.check_num`); the convention's verdict is
    :func:`~hybridpd.reproduce.rules.resolution` of the two. ``figure_hook(path, fig)``, if
    given, sees every figure before it is saved; ``study`` (an :class:`M2Study`) lets a basin
    panel with no stable orbit show the orbit's spectral radius along ``m2``; ``cache`` (a
    dict) lets conventions share work that depends on ``kp/m2, kv/m2`` only.
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.orbits import symmetric_orbit
    from hybridpd.reproduce.figures import convention_figures
    from hybridpd.reproduce.rules import resolution

    say = _say(log)
    tick = tick or say
    P = PAPER
    run = ConventionRun(m2=float(m2), x10=settings.x10, gamma=P["gamma"], L=settings.L,
                        scale=float(m2))
    d = Path(out) / f"m2={m2:g}"
    d.mkdir(parents=True, exist_ok=True)
    run.directory = d
    common = dict(mu=P["mu"], omega=P["omega"], L=settings.L, x10=settings.x10, m2=m2,
                  n=P["n"], e=P["e"])
    _regions(run, settings, common, progress=progress, tick=tick)
    for case in CASES:
        for e in P["e"]:
            run.orbits[(case, e)] = symmetric_orbit(
                ImpactPair(P["mu"], e, settings.L, m2), PDGains(P["kp"], P["kv"]), P["omega"],
                x10=settings.x10, n=P["n"], case=case)
    check_basins, grid2 = _basins(run, settings, executor=executor, max_workers=max_workers,
                                  progress=progress, say=say)
    tick(f"m2 = {m2:g}: basins")
    t0 = time.perf_counter()
    ds = settings.design_search
    run.comparison = _comparison(m2, settings, settings.comparison_grid, *ds)
    g5 = tuple(settings.check_num(v) for v in settings.comparison_grid)
    check_cmp = _comparison(m2, settings, g5, 1, ds[1])
    (d / "robustness.json").write_text(json.dumps([r.to_dict() for r in run.comparison.rows],
                                                  indent=1))
    run.timings["robustness comparison"] = time.perf_counter() - t0
    tick(f"m2 = {m2:g}: robustness comparison")
    num = settings.gains[2]
    g1, g2 = (num, num), (settings.check_num(num),) * 2
    for sh, g, out_, bas, gb, cmp in (
            (run.shares, g1, run.checks, run.basins, settings.basin, run.comparison),
            (run.check_shares, g2, run.check_grid_checks, check_basins, grid2, check_cmp)):
        col, non = sh["collocated"], sh["noncollocated"]
        out_.update({1: C.check_1(col, non, g), 2: C.check_2(col, non, g, P["e"]),
                     3: C.check_3(col, g), 4: _check_4(run, bas, gb, settings),
                     5: C.check_5(cmp)})
    run.check_grids = {1: [list(g1), list(g2)], 2: [list(g1), list(g2)],
                       3: [list(g1), list(g2)], 4: [list(settings.basin), list(grid2)],
                       5: [list(settings.comparison_grid), list(g5)]}
    run.verdicts = {k: resolution(run.checks[k]["verdict"], run.check_grid_checks[k]["verdict"])
                    for k in run.checks}
    t0 = time.perf_counter()
    convention_figures(run, settings, study=study, hook=figure_hook, cache=cache)
    run.timings["figures"] = time.perf_counter() - t0
    tick(f"m2 = {m2:g}: figures")
    return run


def resolve_conventions(settings: Settings, study: M2Study | None) -> list:
    """The ``m2`` values to run: the settings' list with ``"auto"`` replaced by the study's
    choice (dropped, with a note, when no common interval exists)."""
    out = []
    for v in settings.m2:
        if v == AUTO:
            if study is not None and study.chosen_m2 is not None:
                out.append(float(study.chosen_m2))
        else:
            out.append(float(v))
    return list(dict.fromkeys(out))


def reproduce(out="reproduce-out", *, mode="quick", executor="processes", max_workers=None,
              progress=True, log=print, settings: Settings | None = None,
              figure_hook=None) -> Path:
    """Compute Figs 3-7 under every convention, the studies, ``summary.md`` and ``.json``.

    Parameters
    ----------
    out : path
        Output directory (created).
    mode : {"quick", "full"}
        :meth:`Settings.quick` (about a minute on 2 cores) or :meth:`Settings.full`.
    executor : {"serial", "processes", "dask"}
        For the basin sweeps (region maps are vectorised and run in-process).
    max_workers : int, optional
    progress : bool
        Progress on stderr: the steps, and the points of the sweeps inside them (a bar on a
        terminal, a line every ~10 s otherwise).
    log : callable
        Receives one-line status messages as the slow steps finish (default ``print``);
        ``None`` for silence.
    settings : Settings, optional
        Conventions and grid sizes (overrides ``mode``).
    figure_hook : callable, optional
        ``figure_hook(path, fig)`` sees every figure before it is saved (e.g. for checks).

    Returns
    -------
    Path
        ``summary.md`` (``summary.json`` is beside it).
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.params import check_study, param_study
    from hybridpd.reproduce.summary import write_summary

    if mode not in ("quick", "full"):
        raise ValueError(f"mode must be 'quick' or 'full', got {mode!r}")
    if settings is None:
        settings = Settings.quick() if mode == "quick" else Settings.full()
    elif not isinstance(settings, Settings):
        raise ValueError(f"settings must be a Settings, got {type(settings).__name__}")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    say = _say(log)
    n_conv = len(settings.m2)
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.sweeps.progress import Progress

    # the steps; the sweeps inside a step report their own points
    bar = Progress(3 + 6 * n_conv + 1, "reproduce", unit="step", enabled=bool(progress))
    bar.__enter__()

    def tick(msg):
        say(msg)
        bar.update(1)

    t_start = time.perf_counter()
    timings = {}
    t0 = time.perf_counter()
    study = m2_study(settings, log=say)
    timings["m2 study"] = time.perf_counter() - t0
    tick(f"m2 study: chosen m2 = {study.chosen_m2}")
    conventions = resolve_conventions(settings, study)
    if not conventions:
        raise ValueError(f"m2: 'auto' found no m2 in {list(settings.m2_range)} where all "
                         "non-collocated orbits are stable; give a value of m2 as well")
    fixed = dict(mu=PAPER["mu"], gamma=PAPER["gamma"], x10=settings.x10,
                 m2=conventions[0], omega=PAPER["omega"], n=PAPER["n"])
    s = fixed["m2"]
    kp_axis = np.linspace(0.1 * s, settings.gains[0] * s, settings.param_grid)
    kv_axis = np.linspace(0.1 * s, settings.gains[1] * s, settings.param_grid)
    studies = {}
    for name, rng in (("mu", settings.mu_range), ("gamma", settings.gamma_range)):
        t0 = time.perf_counter()
        ps = param_study(name, values_range=rng, points=settings.param_points,
                         kp_axis=kp_axis, kv_axis=kv_axis, e=PAPER["e"], fixed=fixed,
                         map_kp=PAPER["kp"] * s)
        g2 = settings.check_num(settings.param_grid)
        studies[name] = check_study(ps, np.linspace(kp_axis[0], kp_axis[-1], g2),
                                    np.linspace(kv_axis[0], kv_axis[-1], g2))
        timings[f"{name} study"] = time.perf_counter() - t0
        tick(f"{name} study")
    runs = []
    cache = {}
    for m2 in conventions:
        runs.append(run_convention(m2, settings, out, executor=executor,
                                   max_workers=max_workers, progress=progress, log=say, tick=tick,
                                   figure_hook=figure_hook, study=study, cache=cache))
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.figures import study_figures

    t0 = time.perf_counter()
    study_figures(out, study=study, studies=studies, settings=settings, runs=runs,
                  hook=figure_hook)
    timings["figures of the studies"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t_start
    figures = sorted(p.relative_to(out).as_posix() for p in out.rglob("*.png"))
    path = write_summary(out, settings=settings, mode=mode, study=study, studies=studies,
                         runs=runs, timings=timings, figures=figures)
    tick(f"summary written to {path}")
    bar.close()
    return path
