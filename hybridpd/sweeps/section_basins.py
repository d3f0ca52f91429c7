"""Basins of any section map: a :class:`~hybridpd.analysis.periodic.SectionMapper` over a grid.

The mapper takes one section point to a label (:mod:`hybridpd.analysis.labels`); this module is
the thin layer that applies it over a 2-D slice of the section (the other coordinates at the
fixed point's values), serially or through :func:`hybridpd.sweeps.sweep.run_sweep`.
"""
from __future__ import annotations

import pickle
from dataclasses import dataclass

import numpy as np

from hybridpd.analysis.basins import OUTCOMES, Attractor, BasinResult, from_criterion, outcome
from hybridpd.analysis.labels import INADMISSIBLE
from hybridpd.analysis.periodic import SectionMapper
from hybridpd.model import check_axis
from hybridpd.sweeps.sweep import run_sweep

__all__ = ["off_section_axis", "section_basin"]


def off_section_axis(what: str, name: str, sec) -> str:
    """The message refusing ``name`` as a slice axis of section `sec`: a state the section
    fixes (moving it would leave the section: the constraint is named) or no state at all."""
    why = sec.fixed_by(name) if hasattr(sec, "fixed_by") else ""
    if why:
        return (f"{what}: {name!r} is no coordinate of this section ({why}); a slice along it "
                f"would leave the section. The section's coordinates are {list(sec.names)}")
    return f"{what}: {name!r} is no section coordinate; they are {list(sec.names)}"


def section_basin(mapper: SectionMapper, axis_x, axis_y, x, y, *, executor="serial",
                  chunk_size=None, max_workers=None, progress=False) -> BasinResult:
    """Label a 2-D slice of the section: coordinates ``axis_x, axis_y`` on a grid, the others
    at the fixed point's values.

    Parameters
    ----------
    mapper : SectionMapper
        Labels one section point (fixed point, iterations, criterion).
    axis_x, axis_y : int or str
        Section coordinates (index or name, see ``Section.names``) spanned by the grid.
    x, y : (min, max, num)
        Grid axes, in the units of those coordinates.
    executor : str or executor, optional
        ``"serial"`` (default), or an executor accepted by
        :func:`hybridpd.sweeps.sweep.run_sweep` (``"processes"``, ``"dask"``, a Dask ``Client``).
    chunk_size, max_workers, progress
        Passed to :func:`~hybridpd.sweeps.sweep.run_sweep` when not serial.

    Returns
    -------
    BasinResult
        ``x``/``y`` on the coordinates ``x_name``/``y_name``, ``labels`` of shape
        ``(ny, nx)`` (``0``: the mapper's criterion holds, negative outcomes), the mapper's
        labels as ``criterion_labels``. Points whose state lies outside the section's
        admissible set (:meth:`~hybridpd.hybrid.section.Section.violations`: a contact's
        gap beyond its bounds) are labelled ``inadmissible`` and never iterated
        (``metadata["inadmissible"]`` counts them); ``fraction`` is of the others.

    Raises
    ------
    ValueError
        If an axis is unknown, both axes are the same, or a grid axis is malformed.

    Examples
    --------
    >>> import hybridpd as hp
    >>> from hybridpd.pair.section import impact_pair_section
    >>> orb = hp.symmetric_orbit(hp.ImpactPair(0.1, 0.5, 0.75), hp.PDGains(10, 20), 5.0)
    >>> P = hp.SectionMap(impact_pair_section(orb.system()))
    >>> b = hp.section_basin(hp.SectionMapper(P, orb.fixed_point, n_iter=50), "z1", "z4",
    ...                      (-0.5, 0.5, 3), (1.0, 2.0, 2))
    >>> b.labels.shape
    (2, 3)
    """
    names = mapper.map.section.names
    ix, iy = (_axis_index(a, mapper.map.section) for a in (axis_x, axis_y))
    if ix == iy:
        raise ValueError("axis_x and axis_y must differ")
    xs, ys = check_axis("x", x), check_axis("y", y)
    X, Y = np.meshgrid(xs, ys)
    pts = np.tile(mapper.fixed_point, (X.size, 1))
    pts[:, ix], pts[:, iy] = X.ravel(), Y.ravel()
    sec = mapper.map.section
    # states outside the admissible set (a gap beyond its bounds) are never iterated
    bad = np.array([bool(sec.violations(sec.to_state(p)[0])) for p in pts]) if sec.bounds \
        else np.zeros(len(pts), bool)
    lab = np.full(len(pts), INADMISSIBLE, np.int64)
    its = np.zeros(len(pts), np.int64)
    todo = pts[~bad]
    if not len(todo):
        pass
    elif executor == "serial":
        lab[~bad], its[~bad] = mapper.labels(todo)
    else:
        res = run_sweep(_label_chunk, todo, names=[f"s{i}" for i in range(pts.shape[1])],
                        chunk_size=chunk_size, executor=executor, max_workers=max_workers,
                        progress=progress, func_kwargs={"mapper": _PickledMapper.of(mapper)},
                        metadata={"kind": "section_basin"})
        lab[~bad], its[~bad] = res.outputs["label"], res.outputs["iterations"]
    crit = lab.reshape(Y.shape)
    att = from_criterion(crit)
    orbit = Attractor(0, f"period-{mapper.period} orbit", mapper.period,
                      mapper.fixed_point.reshape(1, -1))
    entries = (orbit,) + tuple(outcome(k, mapper.n_iter) for k in sorted(OUTCOMES, reverse=True)
                               if np.any(att == k))
    meta = {"n_iter": mapper.n_iter, "criterion": mapper.criterion,
            "certified_radius": mapper.certified_radius, "period": mapper.period,
            "inadmissible": int(bad.sum())}
    return BasinResult(xs, ys, att, entries, its.reshape(Y.shape), names[ix], names[iy],
                       mapper.fixed_point.copy(), tuple(names), crit, metadata=meta)


def _axis_index(a, sec) -> int:
    names = sec.names
    if isinstance(a, str):
        if a not in names:
            raise ValueError(off_section_axis("axis", a, sec))
        return names.index(a)
    if isinstance(a, bool) or int(a) != a or not 0 <= int(a) < len(names):
        raise ValueError(f"axis must be an index in [0, {len(names)}) or a name, got {a!r}")
    return int(a)


@dataclass(frozen=True, eq=False)
class _PickledMapper:
    """A mapper as bytes (the sweep records its arguments by digest and ships them to the
    worker processes)."""

    blob: np.ndarray

    @classmethod
    def of(cls, mapper: SectionMapper) -> _PickledMapper:
        return cls(np.frombuffer(pickle.dumps(mapper), dtype=np.uint8))

    def load(self) -> SectionMapper:
        return pickle.loads(self.blob.tobytes())


def _label_chunk(chunk, mapper: _PickledMapper):
    S = np.stack([chunk[f"s{i}"] for i in range(len(chunk))], axis=1)
    lab, its = mapper.load().labels(S)
    return {"label": lab, "iterations": its}
