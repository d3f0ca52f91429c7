"""Basins of any section map: a :class:`~hybridpd.analysis.periodic.SectionMapper` over a grid.

The mapper takes one section point to a label (:mod:`hybridpd.analysis.labels`);
:func:`section_basin` is the one basin layer,
:func:`~hybridpd.analysis.basins.basin_of_attraction`, with the mapper as its criterion and
the hooks a section adds: a slice of two of its coordinates (the other coordinates at the
fixed point's values), states outside its admissible set never iterated, and the labelling
serial or through :func:`hybridpd.sweeps.sweep.run_sweep`.
"""
from __future__ import annotations

import pickle
from dataclasses import dataclass, replace

import numpy as np

from hybridpd.analysis.basins import BasinResult, basin_of_attraction
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
        (``metadata["inadmissible"]`` counts them); every ``fraction`` is of all points of
        the slice, these included (they are in no basin).

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
    if not isinstance(mapper, SectionMapper):
        raise ValueError(f"mapper must be a SectionMapper, got {type(mapper).__name__}")
    crit = _SectionCriterion(mapper)
    b = basin_of_attraction(mapper.map, x, y, axes=(axis_x, axis_y), criterion=crit,
                            max_period=0, executor=executor, chunk_size=chunk_size,
                            max_workers=max_workers, progress=progress)
    return replace(b, metadata=dict(b.metadata, inadmissible=crit.inadmissible))


class _SectionCriterion:
    """A :class:`SectionMapper` with the hooks of
    :func:`~hybridpd.analysis.basins.basin_of_attraction`: the slice of two section
    coordinates (refused by name when the section fixes one), states outside the admissible
    set labelled ``inadmissible`` and never iterated, the others labelled serially or on an
    executor."""

    def __init__(self, mapper: SectionMapper):
        self.mapper = mapper
        self.labels, self.fixed_point = mapper.labels, mapper.fixed_point
        self.n_iter, self.criterion, self.period = mapper.n_iter, mapper.criterion, mapper.period
        self.orbit_name = f"period-{mapper.period} orbit"
        self.inadmissible = 0

    def slice(self, x, y, axes) -> tuple:
        sec = self.mapper.map.section
        ix, iy = (_axis_index(a, sec) for a in axes)
        if ix == iy:
            raise ValueError("axis_x and axis_y must differ")
        xs, ys = check_axis("x", x), check_axis("y", y)
        X, Y = np.meshgrid(xs, ys)
        S = np.tile(self.fixed_point, (X.size, 1))
        S[:, ix], S[:, iy] = X.ravel(), Y.ravel()
        return xs, ys, S, (sec.names[ix], sec.names[iy]), {}

    def label_tails(self, S, tail: int = 0, *, executor="serial", chunk_size=None,
                    max_workers=None, progress=False) -> dict:
        sec = self.mapper.map.section
        # states outside the admissible set (a gap beyond its bounds) are never iterated
        bad = np.array([bool(sec.violations(sec.to_state(p)[0])) for p in S]) if sec.bounds \
            else np.zeros(len(S), bool)
        self.inadmissible = int(bad.sum())
        lab = np.full(len(S), INADMISSIBLE, np.int64)
        its = np.zeros(len(S), np.int64)
        todo = S[~bad]
        if len(todo) and executor == "serial":
            lab[~bad], its[~bad] = self.mapper.labels(todo)
        elif len(todo):
            res = run_sweep(_label_chunk, todo, names=[f"s{i}" for i in range(S.shape[1])],
                            chunk_size=chunk_size, executor=executor, max_workers=max_workers,
                            progress=progress,
                            func_kwargs={"mapper": _PickledMapper.of(self.mapper)},
                            metadata={"kind": "section_basin"})
            lab[~bad], its[~bad] = res.outputs["label"], res.outputs["iterations"]
        return {"label": lab, "iterations": its}

    def basin_metadata(self) -> dict:
        return {"certified_radius": self.mapper.certified_radius, "period": self.period}


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
