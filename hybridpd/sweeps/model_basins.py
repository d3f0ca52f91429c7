"""Basins of attraction of any model file, labelled by attractor like the pair's.

:func:`model_basin` finds a periodic orbit of one section of a model file (as
:class:`hybridpd.sweeps.model_regions.ModelSearch` does per cell), then labels a 2-D slice
of the section (two section coordinates on a grid, the others at the orbit's values) by where
the map takes each point: ``0`` the orbit; ``1, 2, ...`` other periodic attractors found
among the points that do not reach it (each found by iterating the map from one such point
and solving ``P^k(s) = s`` for ``k`` up to ``max_period``, then every remaining point is
labelled against it by the compiled mapper); negative codes the outcomes of
:data:`hybridpd.analysis.basins.OUTCOMES` (no convergence, divergence, sticking,
unresolved, off the section). The grid runs as a sweep on any executor (a scheduler address
runs it on an existing Dask cluster). The result converts to a labelled xarray Dataset
(``.nc``, ``.zarr``) that ``hybridpd plot`` draws.
"""
from __future__ import annotations

import numpy as np

from hybridpd.analysis.basins import OUTCOMES, Attractor, BasinResult, from_criterion, outcome
from hybridpd.analysis.model_orbits import STATUS, SectionSpec, solve_at
from hybridpd.analysis.model_sections import DivergedRun, fix_section
from hybridpd.analysis.periodic import SectionMapper, find_orbit
from hybridpd.sweeps.model_regions import _grid_spec, template_of
from hybridpd.sweeps.section_basins import off_section_axis

__all__ = ["DEFAULT_NUM", "default_axes", "model_basin"]

#: Points per axis of the default slice (a run of the section map each).
DEFAULT_NUM = 21


def _grid(name, spec, sec):
    def check(key):
        if key not in sec.names:
            raise ValueError(off_section_axis(name, key, sec))

    return _grid_spec(name, spec, "COORDINATE", check)


def _orbit_name(label, period, n_periods):
    what = f"period-{period} orbit ({n_periods} T)"
    return f"the {what}" if label == 0 else f"attractor {label}: {what}"


def _orbit_entry(label, po):
    return Attractor(int(label), _orbit_name(label, po.period, po.n_periods), int(po.period),
                     np.asarray(po.s, float).reshape(1, -1), po.multipliers,
                     float(po.spectral_radius), bool(po.stable))


def _find_attractor(P, s, max_period, known, n_transient=200):
    """A stable periodic orbit reached from `s` (None if none is found)."""
    it = P.iterate(s, n_transient)
    ok = np.all(np.isfinite(it), axis=1)
    if not ok[-1]:
        return None
    last = it[-1]
    for k in range(1, int(max_period) + 1):
        po = find_orbit(P, last, k, max_iter=20)
        if po.converged and po.stable:
            if any(np.max(np.abs(P.section.wrap(po.s - q))) < 1e-6 * max(1.0, np.max(np.abs(q)))
                   for q in known):
                return None
            return po
    return None


def default_axes(s, names, num: int = DEFAULT_NUM) -> tuple:
    """The default slice of a basin through the section point ``s``: its first two section
    coordinates, each over ``s_i +- r`` with ``r = max(|s_0|, |s_1|)`` (at least 1e-6),
    ``num`` points each (``(x, y)`` as :func:`model_basin` takes them).

    Examples
    --------
    >>> default_axes([0.5, -2.0, 7.0], ("link", "link_dot", "h0"), 5)
    (('link', -1.5, 2.5, 5), ('link_dot', -4.0, 0.0, 5))
    """
    r = max(float(abs(s[0])), float(abs(s[1])), 1e-6)
    return tuple((names[i], float(s[i]) - r, float(s[i]) + r, int(num)) for i in (0, 1))


def model_basin(model, x=None, y=None, *, values: dict | None = None, contact: int = 0,
                wall: int | None = None, event: str = "auto", period="auto",
                periods: int | None = None, mode: str | None = None,
                phase: float | None = None, n_iter: int = 300,
                criterion: float = 1e-3,
                max_period: int = 4, max_attractors: int = 4, executor="serial",
                max_workers=None, progress: bool = False) -> BasinResult:
    """Basin of a model file's periodic orbit on a 2-D slice of its section, by attractor.

    Parameters
    ----------
    model : str, Path, dict or ModelTemplate
    x, y : (str, float, float, int), optional
        ``(COORDINATE, MIN, MAX, NUM)``: a section coordinate (e.g. ``"motor"``,
        ``"motor_dot"``; ``phi`` is the reference phase) and its grid. Not given: the
        slice of :func:`default_axes` through the orbit found.
    values : dict, optional
        ``{dotted path: value}`` set in the file first (e.g. ``{"controller.kp": 30}``).
    contact, wall, event, period, periods, mode, phase
        The section and the orbit (as in :class:`~hybridpd.sweeps.model_regions.
        model_region_map`; ``mode`` as in :class:`~hybridpd.analysis.model_orbits.
        SectionSpec`).
    n_iter, criterion
        Iterations of ``P^k`` per point and the squared-distance criterion of convergence.
    max_period, max_attractors
        Periods searched for further attractors, and how many are looked for.
    executor, max_workers, progress
        As in :func:`hybridpd.sweeps.sweep.run_sweep` (``"serial"`` labels in one compiled
        call).

    Returns
    -------
    BasinResult
        On the coordinates ``x_name``, ``y_name`` of the section (``names``); the
        mapper's labels against the orbit as ``criterion_labels``; the model file as
        ``metadata["model"]`` (:attr:`~hybridpd.analysis.basins.BasinResult.source`).

    Raises
    ------
    ValueError
        Bad coordinates, paths or section, or no periodic orbit found to take the basin of.
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.sweeps.section_basins import section_basin

    template = template_of(model)
    m = template.model(values)
    spec = SectionSpec(contact=contact, wall=wall, event=event, period=period, periods=periods,
                       mode=mode, phase=phase)
    spec = fix_section(m, spec)[0]
    res = solve_at(m, spec)
    if not res.orbits:
        # a motion that diverges is said to (DivergedRun), not only that no orbit was found
        err = DivergedRun if STATUS[res.status] == "diverged" else ValueError
        raise err(f"no periodic orbit of this section to take the basin of ({res.detail})")
    po = res.orbits[0]
    P = spec.section_map(m, po.mode)
    names = P.section.names
    if x is None or y is None:
        dx, dy = default_axes(po.s, names)
        x, y = x or dx, y or dy
    xn, xg = _grid("x", x, P.section)
    yn, yg = _grid("y", y, P.section)
    if xn == yn:
        raise ValueError(f"x and y must be different coordinates, both are {xn!r}")
    mapper = SectionMapper(P, po.s, period=po.period, n_iter=n_iter, criterion=criterion)
    b = section_basin(mapper, xn, yn, xg, yg, executor=executor, max_workers=max_workers,
                      progress=progress)
    crit = b.criterion_labels
    lab = from_criterion(crit)
    atts = [_orbit_entry(0, po)]
    X, Y = np.meshgrid(b.x, b.y)
    ix, iy = names.index(xn), names.index(yn)
    known = [po.s]
    for k in range(1, int(max_attractors) + 1):
        rest = np.argwhere(lab == -1)
        if not len(rest):
            break
        r0 = rest[len(rest) // 2]
        s = po.s.copy()
        s[ix], s[iy] = X[tuple(r0)], Y[tuple(r0)]
        other = _find_attractor(P, s, max_period, known)
        if other is None:
            break
        known.append(other.s)
        om = SectionMapper(P, other.s, period=other.period, n_iter=n_iter, criterion=criterion)
        pts = np.tile(po.s, (len(rest), 1))
        pts[:, ix], pts[:, iy] = X[tuple(rest.T)], Y[tuple(rest.T)]
        got, _ = om.labels(pts)
        lab[tuple(rest[got == 0].T)] = k
        atts.append(_orbit_entry(k, other))
    atts += [outcome(code) for code in sorted(OUTCOMES, reverse=True) if np.any(lab == code)]
    meta = {"values": dict(values or {}), "spec": {f: getattr(spec, f) for f in
                                                    ("contact", "wall", "event", "period",
                                                     "periods", "phase")},
            "n_iter": int(n_iter), "criterion": float(criterion), "section_mode": po.mode,
            "inadmissible": int(b.metadata.get("inadmissible", 0))}
    return BasinResult(b.x, b.y, lab, tuple(atts), b.iterations, xn, yn, po.s.copy(),
                       tuple(names), crit, metadata=dict(meta, model=str(template.source)))
