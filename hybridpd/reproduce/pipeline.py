"""The reproduction pipeline: the certified shares, both ``m2`` conventions, the studies, the
figures, the summary.

Layout of the output directory (every figure as PNG at 300 dpi and as PDF)::

    summary.md, summary.json          verdicts and every number behind them
    robustness.json                   the comparison of conclusion 5 (scaled gains)
    scaled_regions_collocated.png, scaled_regions_noncollocated.png
                                      Figs 4-5 in (kp/m2, kv/m2), valid for every m2
    m2_study.png, mu_study.png, gamma_study.png
    m2=<value>/                       one directory per convention:
        fig3_orbit.png, fig4_regions_collocated.png, fig5_regions_noncollocated.png,
        fig6_basins_collocated.png, fig7_basins_noncollocated.png,
        regions_*.nc, basin_*.nc

The certified shares (:func:`~hybridpd.reproduce.certified.reproduction_shares`) and the
traced region boundaries depend on nothing else the run computes: with a process executor
they are computed in two background processes while the rest runs.
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
from hybridpd.reproduce.study import choose_m2, stable_intervals

__all__ = ["ConventionRun", "M2Study", "m2_study", "reproduce", "run_convention"]

CASES = ("collocated", "noncollocated")


@dataclass
class ConventionRun:
    """Figs 3-7 and the basins of conclusion 4 under one convention ``(m2, x10)``.

    Attributes
    ----------
    m2, x10, gamma, L : float
    scale : float
        Factor applied to the paper's gain box (``= m2``).
    maps : dict
        ``{case: RegionMap}`` on the scaled box, plus ``"zoom"`` (non-collocated).
    orbits : dict
        ``{(case, e): SymmetricOrbitResult}`` at the paper's gains.
    basins : dict
        ``{(case, e): AttractorBasin or None}`` (None: no orbit, or not stable).
    check_4 : dict
        Conclusion 4 at this ``m2`` (:func:`~hybridpd.reproduce.conclusions.check_4`) on
        the run's basin grid; ``check_4_check_grid`` on the resolution-check grid;
        ``verdict_4`` the two by :func:`~hybridpd.reproduce.rules.resolution`.
    basin_grids : list
        ``[run grid, check grid]``.
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
    orbits: dict = field(default_factory=dict)
    basins: dict = field(default_factory=dict)
    check_4: dict = None
    check_4_check_grid: dict = None
    verdict_4: str = None
    basin_grids: list = None
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
    rho_grid : ndarray
    rho : dict
        ``{(case, e): spectral radius along rho_grid}`` for the figure (NaN: no orbit).
    robust_grid : ndarray
        ``m2`` values at which conclusion 5 is read on the printed gain box.
    robust : list
        :func:`~hybridpd.reproduce.conclusions.check_5` at each (run and check grid).
    """

    intervals: dict
    chosen_m2: float | None
    rho_grid: np.ndarray
    rho: dict
    robust_grid: np.ndarray
    robust: list
    __repr__ = compact_repr


def _say(log):
    return log or (lambda *_: None)


def _comparison(m2, settings, grid, n_starts, maxiter, *, scaled=True, uncertainty=None):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.design import robustness_comparison

    P = PAPER
    s = m2 if scaled else 1.0
    # the gain box of the region verdicts (Figs 4-5's box), so that every row reads one box
    kpm, kvm, _ = settings.gains
    return robustness_comparison(
        mu=P["mu"], gamma=P["gamma"], x10=settings.x10, m2=m2, n=P["n"], omega=P["omega"],
        e=0.5, grid=tuple(grid), uncertainty_grid=uncertainty or settings.uncertainty_grid,
        n_starts=n_starts, maxiter=maxiter, kp_range=(0.1 * s, kpm * s),
        kv_range=(0.1 * s, kvm * s))


def m2_study(settings: Settings, *, log=None) -> M2Study:
    """Stable ``m2`` intervals at the paper's gains, the spectral radii along ``m2`` and
    conclusion 5 read on the printed gain box at :attr:`M2Study.robust_grid`.

    The readings of conclusions 1-3 are certified shares
    (:func:`~hybridpd.reproduce.certified.reproduction_shares`); conclusion 4's follow from
    the located interval ends (exact).
    """
    # deferred import: loaded only when this runs, for start-up time
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
    robust_grid = np.logspace(math.log10(lo), math.log10(hi), settings.m2_robust)
    robust = []
    g2 = tuple(settings.check_num(v) for v in settings.m2_robust_grid)
    for m2 in robust_grid:
        # the printed box: only the gain grid's shares matter, not the local searches
        a, b = (_comparison(m2, settings, g, 1, 1, scaled=False, uncertainty=(3, 3))
                for g in (settings.m2_robust_grid, g2))
        robust.append(C.check_5(a, b))
    say(f"m2 study: conclusion 5 on {len(robust_grid)} values of m2")
    return M2Study(intervals, chosen, rho_grid, rho, robust_grid, robust)


def _regions(run, settings, common, *, progress):
    """Region maps of Figs 4-5 on the scaled box (saved as .nc)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.regions import SymmetricFamily
    from hybridpd.sweeps.regions import region_map

    s, d = run.scale, run.directory
    kpm, kvm, num = settings.gains
    for case in CASES:
        t0 = time.perf_counter()
        rm = region_map(SymmetricFamily(case, **common), x=("kp", 0.1 * s, kpm * s, num),
                        y=("kv", 0.1 * s, kvm * s, num), progress=progress)
        rm.save(d / f"regions_{case}.nc")
        run.maps[case] = rm
        run.timings[f"regions {case}"] = time.perf_counter() - t0
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


def run_convention(m2, settings: Settings, out, *, executor="processes", max_workers=None,
                   progress=False, log=None, tick=None, figure_hook=None,
                   study=None, cache=None) -> ConventionRun:
    """Figs 3-7, their data and conclusion 4's basins under one ``m2`` (see module doc).

    Conclusion 4 is measured on the run's basin grid and on the resolution-check grid
    (:attr:`Settings.basin_check_scale`); the convention's verdict is
    :func:`~hybridpd.reproduce.rules.resolution` of the two. ``figure_hook(path, fig)``, if
    given, sees every figure before it is saved; ``study`` (an :class:`M2Study`) lets a
    basin panel with no stable orbit show the orbit's spectral radius along ``m2``;
    ``cache`` (a dict, see :func:`~hybridpd.reproduce.figures.trace_scaled`) lets
    conventions share the traced boundaries, which depend on ``kp/m2, kv/m2`` only.
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
    _regions(run, settings, common, progress=progress)
    tick(f"m2 = {m2:g}: regions")
    for case in CASES:
        for e in P["e"]:
            run.orbits[(case, e)] = symmetric_orbit(
                ImpactPair(P["mu"], e, settings.L, m2), PDGains(P["kp"], P["kv"]), P["omega"],
                x10=settings.x10, n=P["n"], case=case)
    check_basins, grid2 = _basins(run, settings, executor=executor, max_workers=max_workers,
                                  progress=progress, say=say)
    run.check_4 = _check_4(run, run.basins, settings.basin, settings)
    run.check_4_check_grid = _check_4(run, check_basins, grid2, settings)
    run.verdict_4 = resolution(run.check_4["verdict"], run.check_4_check_grid["verdict"])
    run.basin_grids = [list(settings.basin), list(grid2)]
    tick(f"m2 = {m2:g}: basins")
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


def _certified_job(settings, cases, groups=None):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.certified import reproduction_shares

    return reproduction_shares(settings, cases, groups)


#: The certified groups of the verdicts in two jobs per case (the collocated proofs cost
#: about three times the non-collocated ones: four jobs keep both workers busy to the end),
#: then those of the studies' values (full mode), one job per study and case.
_VERDICT_JOBS = (("limit", "mu_ends", "mu_moves"), ("main", "readings"))


def _certified_jobs(settings) -> dict:
    jobs = {f"certified {c} {'+'.join(g)}": (_certified_job, (settings, (c,), g))
            for c in CASES for g in _VERDICT_JOBS}
    if settings.certify_every_value:
        for study in ("gamma", "mu"):
            for c in CASES:
                jobs[f"certified {study} values {c}"] = (
                    _certified_job, (settings, (c,), (f"{study}_values",)))
    return jobs


def _traced_job(settings):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.figures import trace_scaled

    t0, c0 = time.perf_counter(), time.process_time()
    return trace_scaled(settings), time.perf_counter() - t0, time.process_time() - c0


class _Background:
    """The work that depends on nothing else of the run: in worker processes (``parallel``)
    started at once, or inline when first needed."""

    def __init__(self, jobs: dict, parallel: bool):
        self._jobs, self._done, self._pool, self._futures = dict(jobs), {}, None, {}
        if parallel:
            import concurrent.futures as cf

            self._pool = cf.ProcessPoolExecutor(max_workers=2)
            self._futures = {k: self._pool.submit(fn, *args) for k, (fn, args) in jobs.items()}

    def get(self, name):
        if name not in self._done:
            if self._pool is not None:
                self._done[name] = self._futures[name].result()
            else:
                fn, args = self._jobs[name]
                self._done[name] = fn(*args)
        return self._done[name]

    def close(self):
        if self._pool is not None:
            for f in self._futures.values():
                f.cancel()
            self._pool.shutdown(wait=True)
            self._pool = None


def _steps(n_conv: int) -> int:
    """Progress steps of a run: the m2, mu and gamma studies, conclusion 5, three per
    convention (regions, basins, figures), the certified shares, the figures of the studies
    and the summary."""
    return 4 + 3 * n_conv + 3


def reproduce(out="reproduce-out", *, mode="quick", executor="processes", max_workers=None,
              progress=True, log=print, settings: Settings | None = None,
              figure_hook=None) -> Path:
    """Compute Figs 3-7 under every convention, the studies, ``summary.md`` and ``.json``.

    Parameters
    ----------
    out : path
        Output directory (created).
    mode : {"quick", "full"}
        :meth:`Settings.quick` (under a minute on 2 cores) or :meth:`Settings.full`.
    executor : {"serial", "processes", "dask"}
        For the basin sweeps (region maps are vectorised and run in-process); with
        ``"processes"`` or ``"dask"`` the certified shares and the traced boundaries are
        computed in two local background processes meanwhile.
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
    if mode not in ("quick", "full"):
        raise ValueError(f"mode must be 'quick' or 'full', got {mode!r}")
    if settings is None:
        settings = Settings.quick() if mode == "quick" else Settings.full()
    elif not isinstance(settings, Settings):
        raise ValueError(f"settings must be a Settings, got {type(settings).__name__}")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    parallel = executor != "serial"
    # the traced boundaries first: the first convention's figures wait for them, the
    # certified shares are needed only at the end
    bg = _Background({"traced boundaries": (_traced_job, (settings,)),
                      **_certified_jobs(settings)}, parallel)
    try:
        return _reproduce(out, mode, settings, bg, executor=executor, max_workers=max_workers,
                          progress=progress, log=log, figure_hook=figure_hook)
    finally:
        bg.close()


def _reproduce(out, mode, settings, bg, *, executor, max_workers, progress, log, figure_hook):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.certified import merge_shares
    from hybridpd.reproduce.figures import study_figures
    from hybridpd.reproduce.params import param_study
    from hybridpd.reproduce.summary import build_summary, write_summary
    from hybridpd.sweeps.progress import Progress

    say = _say(log)
    n_conv = len(settings.m2)
    bar = Progress(_steps(n_conv), "reproduce", unit="step", enabled=bool(progress))
    bar.__enter__()
    ticks = [0]

    def tick(msg):
        say(msg)
        bar.update(1)
        ticks[0] += 1

    t_start, c_start = time.perf_counter(), time.process_time()
    timings = {}
    t0 = time.perf_counter()
    study = m2_study(settings, log=say)
    timings["m2 study"] = time.perf_counter() - t0
    tick(f"m2 study: chosen m2 = {study.chosen_m2}")
    conventions = resolve_conventions(settings, study)
    if not conventions:
        raise ValueError(f"m2: 'auto' found no m2 in {list(settings.m2_range)} where all "
                         "non-collocated orbits are stable; give a value of m2 as well")
    # the studies' gain box is the first convention's, scaled by its m2: the scaled box
    s = conventions[0]
    fixed = dict(mu=PAPER["mu"], gamma=PAPER["gamma"], x10=settings.x10, m2=s,
                 omega=PAPER["omega"], n=PAPER["n"])
    kp_axis = np.linspace(0.1 * s, settings.gains[0] * s, settings.param_grid)
    kv_axis = np.linspace(0.1 * s, settings.gains[1] * s, settings.param_grid)
    studies = {}
    for name, rng in (("mu", settings.mu_range), ("gamma", settings.gamma_range)):
        t0 = time.perf_counter()
        studies[name] = param_study(name, values_range=rng, points=settings.param_points,
                                    kp_axis=kp_axis, kv_axis=kv_axis, e=PAPER["e"],
                                    fixed=fixed, map_kp=PAPER["kp"] * s)
        timings[f"{name} study"] = time.perf_counter() - t0
        tick(f"{name} study")
    t0 = time.perf_counter()
    ds = settings.design_search
    comparison = _comparison(1.0, settings, settings.comparison_grid, *ds)
    g5 = tuple(settings.check_num(v) for v in settings.comparison_grid)
    check5 = C.check_5(comparison, _comparison(1.0, settings, g5, 1, 1))
    (out / "robustness.json").write_text(json.dumps(comparison.to_dict(), indent=1))
    timings["robustness comparison"] = time.perf_counter() - t0
    tick("conclusion 5: robustness comparison")
    t0 = time.perf_counter()
    cache, traced_seconds, traced_cpu = bg.get("traced boundaries") \
        if settings.traced_boundaries else ({}, 0.0, 0.0)
    timings["waiting for the traced boundaries"] = time.perf_counter() - t0
    runs = [run_convention(m2, settings, out, executor=executor, max_workers=max_workers,
                           progress=progress, log=say, tick=tick, figure_hook=figure_hook,
                           study=study, cache=cache) for m2 in conventions]
    t0 = time.perf_counter()
    shares = merge_shares([bg.get(k) for k in _certified_jobs(settings)])
    timings["waiting for the certified shares"] = time.perf_counter() - t0
    tick("certified shares")
    t0 = time.perf_counter()
    # the figures draw the summary's table (its readings along m2): the summary first
    data = build_summary(settings=settings, mode=mode, study=study, studies=studies, runs=runs,
                         shares=shares, check5=check5, timings=timings)
    timings["summary"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    study_figures(out, study=study, studies=studies, settings=settings, runs=runs,
                  table=data["table"], shares=shares, hook=figure_hook)
    timings["figures of the studies"] = time.perf_counter() - t0
    tick("figures of the studies")
    timings["traced boundaries (background)"] = traced_seconds
    for k, v in shares["seconds"].items():
        timings[f"certified {k} (background)"] = v
    timings["total"] = time.perf_counter() - t_start
    # CPU apart from the wall time: the machine may be shared; with two idle cores the run
    # takes about the larger of this process's CPU and the background's per worker
    timings["CPU of this process"] = time.process_time() - c_start
    timings["CPU of the background work"] = traced_cpu + sum(shares["cpu_seconds"].values())
    data["timings"] = {k: float(v) for k, v in timings.items()}
    data["figures"] = sorted(p.relative_to(out).as_posix() for p in out.rglob("*.png"))
    path = write_summary(out, data=data)
    tick(f"summary written to {path}")
    bar.close()
    # the last word of a run that reached its end, whatever the bar printed
    say(f"finished {ticks[0]}/{bar.total} steps in {_duration(time.perf_counter() - t_start)}")
    return path


def _duration(seconds: float) -> str:
    """``"48 s"`` or ``"3.2 min"``."""
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.1f} min"
