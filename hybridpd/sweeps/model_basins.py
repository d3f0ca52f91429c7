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

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hybridpd._format import format_percent
from hybridpd._results import compact_repr
from hybridpd.analysis.basins import OUTCOMES
from hybridpd.analysis.labels import LABELS
from hybridpd.analysis.model_orbits import SectionSpec, solve_at
from hybridpd.analysis.periodic import SectionMapper, find_orbit
from hybridpd.sweeps.labelled import decode_attrs, encode_attrs, load_result, save_result
from hybridpd.sweeps.model_regions import _grid_spec, template_of
from hybridpd.sweeps.section_basins import off_section_axis

__all__ = ["ModelBasin", "load_model_basin", "model_basin"]

# paper label -> outcome code (converged handled apart)
_OUTCOME_OF = {1: -1, 2: -2, 3: -3, 4: -4, 5: -5, 6: -6}


@dataclass(frozen=True, eq=False)
class ModelBasin:
    """An attractor-labelled slice of a model file's section.

    Attributes
    ----------
    source : str
        The model file.
    x_name, y_name : str
        Section coordinates spanned by the grid.
    x, y : ndarray
        Grid axes.
    labels : ndarray of int, shape (len(y), len(x))
        ``0`` the orbit, ``>= 1`` other periodic attractors, negative outcomes.
    attractors : tuple of dict
        ``label, name, period, n_periods, points (k x dim), stable, spectral_radius`` of each
        periodic attractor, and ``label, name`` of each outcome present.
    criterion_labels : ndarray of int
        The mapper's labels (:data:`hybridpd.analysis.labels.LABELS`) against the orbit.
    iterations : ndarray of int
    fixed_point : ndarray, shape (dim,)
        The orbit's section point (the slice's other coordinates).
    coords : tuple of str
        Names of the section coordinates.
    metadata : dict
        Model, section, parameter values, iterations and criterion.
    """

    source: str
    x_name: str
    y_name: str
    x: np.ndarray
    y: np.ndarray
    labels: np.ndarray
    attractors: tuple
    criterion_labels: np.ndarray = field(repr=False)
    iterations: np.ndarray = field(repr=False)
    fixed_point: np.ndarray = field(repr=False)
    coords: tuple = ()
    metadata: dict = field(default_factory=dict)
    __repr__ = compact_repr

    def fraction(self, label: int) -> float:
        """Share of the on-section, admissible grid with ``label`` (of the whole grid for
        the off-section and inadmissible labels, ``-5`` and ``-6``)."""
        on = (self.labels != -5) & (self.labels != -6)
        whole = self.labels.size if label in (-5, -6) else int(on.sum())
        return float((self.labels == label).sum() / whole) if whole else 0.0

    def area(self, label: int) -> float:
        """Area of the basin of ``label`` (units of ``x`` times ``y``)."""
        cell = (self.x[1] - self.x[0]) * (self.y[1] - self.y[0])
        return float((self.labels == label).sum() * cell)

    def summary(self) -> list:
        """Lines in words, like the pair's: window, then one line per attractor."""
        lines = [(f"{Path(self.source).name}: slice {self.x_name} in [{self.x[0]:g}, "
                 f"{self.x[-1]:g}], {self.y_name} in [{self.y[0]:g}, {self.y[-1]:g}] "
                 f"({len(self.x)} x {len(self.y)} points)")]
        on = int(((self.labels != -5) & (self.labels != -6)).sum())
        for a in self.attractors:
            n = int((self.labels == a["label"]).sum())
            whole = self.labels.size if a["label"] in (-5, -6) else on
            pct = format_percent(n, whole) if whole else "0 %"
            extra = ""
            if a.get("period"):
                stab = "stable" if a["stable"] else "unstable"
                extra = f"; {stab}, spectral radius {a['spectral_radius']:.4g}"
            where = "window" if a["label"] in (-5, -6) else "on-section, admissible grid"
            if a["label"] == -6:
                extra = f" ({n} points, not iterated)"
            lines.append(f"{a['name']}: {pct} of the {where}, area "
                         f"{self.area(a['label']):.4g}{extra}")
        return lines

    def to_dict(self) -> dict:
        """JSON-ready description (with the labels)."""
        return {"model": self.source, "x_name": self.x_name, "y_name": self.y_name,
                "x": self.x.tolist(), "y": self.y.tolist(), "labels": self.labels.tolist(),
                "attractors": [dict(a, fraction=self.fraction(a["label"]),
                                    area=self.area(a["label"])) for a in self.attractors],
                "fixed_point": self.fixed_point.tolist(), "coordinates": list(self.coords),
                "metadata": self.metadata}

    def to_dataset(self):
        """Dimensions ``(y_name, x_name)``; ``attractor`` (CF flags name the attractors),
        ``criterion_label``, ``iterations``; attractors and settings as attributes."""
        # deferred import: loaded only when this runs, for start-up time
        import xarray as xr

        dims = (self.y_name, self.x_name)
        flags = [a["label"] for a in self.attractors]
        data = {
            "attractor": (dims, self.labels, {
                "long_name": "attractor reached", "flag_values": flags,
                "flag_meanings": " ".join(a["name"].replace(" ", "_")
                                          for a in self.attractors)}),
            "criterion_label": (dims, self.criterion_labels, {
                "long_name": "label against the orbit", "flag_values": list(range(len(LABELS))),
                "flag_meanings": " ".join(LABELS)}),
            "iterations": (dims, self.iterations, {"long_name": "iterations of the map run"})}
        coords = {self.y_name: (self.y_name, self.y), self.x_name: (self.x_name, self.x)}
        attrs = {"kind": "model_basin", "model": self.source, "x_name": self.x_name,
                 "y_name": self.y_name, **encode_attrs({
                     "attractors": list(self.attractors),
                     "section_coordinates": list(self.coords),
                     "fixed_point": [float(v) for v in self.fixed_point],
                     "metadata": dict(self.metadata)})}
        return xr.Dataset(data, coords=coords, attrs=attrs)

    @classmethod
    def from_dataset(cls, ds) -> ModelBasin:
        """Inverse of :meth:`to_dataset`."""
        a = decode_attrs(ds.attrs)
        if a.get("kind") != "model_basin":
            raise ValueError("the dataset does not hold a model basin (attribute kind)")
        ds = ds.transpose(a["y_name"], a["x_name"])
        return cls(a["model"], a["x_name"], a["y_name"], ds[a["x_name"]].values,
                   ds[a["y_name"]].values, ds["attractor"].values.astype(np.int64),
                   tuple(a["attractors"]), ds["criterion_label"].values.astype(np.int64),
                   ds["iterations"].values.astype(np.int64), np.asarray(a["fixed_point"]),
                   tuple(a["section_coordinates"]), dict(a.get("metadata") or {}))

    def save(self, path) -> Path:
        """Write to ``.nc`` or ``.zarr`` (by suffix)."""
        return save_result(self, path)


def load_model_basin(path) -> ModelBasin:
    """Read a :class:`ModelBasin` written by :meth:`ModelBasin.save`."""
    return load_result(ModelBasin, path)


def _grid(name, spec, sec):
    def check(key):
        if key not in sec.names:
            raise ValueError(off_section_axis(name, key, sec))

    return _grid_spec(name, spec, "COORDINATE", check)


def _orbit_name(label, period, n_periods):
    what = f"period-{period} orbit ({n_periods} T)"
    return f"the {what}" if label == 0 else f"attractor {label}: {what}"


def _orbit_entry(label, po):
    return {"label": int(label), "name": _orbit_name(label, po.period, po.n_periods),
            "period": int(po.period), "n_periods": int(po.n_periods),
            "points": [[float(v) for v in po.s]], "stable": bool(po.stable),
            "spectral_radius": float(po.spectral_radius)}


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


def model_basin(model, x, y, *, values: dict | None = None, contact: int = 0,
                wall: int | None = None, event: str = "impact", period="auto",
                periods: int | None = None, mode: str | None = None, n_iter: int = 300,
                criterion: float = 1e-3,
                max_period: int = 4, max_attractors: int = 4, executor="serial",
                max_workers=None, progress: bool = False) -> ModelBasin:
    """Basin of a model file's periodic orbit on a 2-D slice of its section, by attractor.

    Parameters
    ----------
    model : str, Path, dict or ModelTemplate
    x, y : (str, float, float, int)
        ``(COORDINATE, MIN, MAX, NUM)``: a section coordinate (e.g. ``"motor"``,
        ``"motor_dot"``; ``phi`` is the reference phase) and its grid.
    values : dict, optional
        ``{dotted path: value}`` set in the file first (e.g. ``{"controller.kp": 30}``).
    contact, wall, event, period, periods, mode
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
    ModelBasin

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
                       mode=mode)
    res = solve_at(m, spec)
    if not res.orbits:
        raise ValueError(f"no periodic orbit of this section to take the basin of "
                         f"({res.detail})")
    po = res.orbits[0]
    P = spec.section_map(m, po.mode)
    names = P.section.names
    xn, xg = _grid("x", x, P.section)
    yn, yg = _grid("y", y, P.section)
    if xn == yn:
        raise ValueError(f"x and y must be different coordinates, both are {xn!r}")
    mapper = SectionMapper(P, po.s, period=po.period, n_iter=n_iter, criterion=criterion)
    b = section_basin(mapper, xn, yn, xg, yg, executor=executor, max_workers=max_workers,
                      progress=progress)
    crit = b.labels
    lab = np.where(crit == 0, 0, -1)
    for code, out in _OUTCOME_OF.items():
        lab[crit == code] = out
    atts = [_orbit_entry(0, po)]
    X, Y = np.meshgrid(b.x1, b.y1)
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
    for code in sorted(set(np.unique(lab).tolist()) - {a["label"] for a in atts}, reverse=True):
        atts.append({"label": int(code), "name": OUTCOMES[code][1]})
    meta = {"values": dict(values or {}), "spec": {f: getattr(spec, f) for f in
                                                    ("contact", "wall", "event", "period",
                                                     "periods")},
            "n_iter": int(n_iter), "criterion": float(criterion), "section_mode": po.mode,
            "inadmissible": int(b.metadata.get("inadmissible", 0))}
    return ModelBasin(template.source, xn, yn, b.x1, b.y1, lab, tuple(atts), crit,
                      b.iterations, po.s.copy(), tuple(names), meta)
