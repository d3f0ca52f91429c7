"""Brute-force bifurcation diagrams of any model file in one of its numeric entries.

:func:`model_diagram` sweeps one entry of a model file (a dotted path,
:mod:`hybridpd.mechanics.params`) over ``N`` values; at each value it simulates the model from
its initial state for a transient, takes the last crossing of the chosen section (in the
mode where the motion crosses it), iterates the section map ``P^k`` ``iterations`` times and keeps the last ``keep`` section points. Each
value is classified: ``periodic`` with the smallest period ``p`` (applications of ``P^k``)
after which the kept points repeat (to ``1e-6`` relative), ``not_periodic`` (no period up to
``max_period``: quasi-periodic or chaotic), or ``undefined`` (the map stopped: no crossing,
divergence, sticking for good; the reason is kept). The values are independent, so they run
as a sweep on any executor (a scheduler address runs them on an existing Dask cluster).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.analysis.model_orbits import SectionSpec, simulated_returns
from hybridpd.mechanics.params import ModelTemplate
from hybridpd.sweeps.labelled import decode_attrs, encode_attrs, load_result, save_result
from hybridpd.sweeps.model_regions import template_of

__all__ = ["DIAGRAM_CLASSES", "ModelDiagram", "load_model_diagram", "model_diagram"]

#: Classes of a value of a model diagram.
DIAGRAM_CLASSES = ("periodic", "not_periodic", "undefined")


@dataclass(frozen=True, eq=False)
class ModelDiagram:
    """A brute-force bifurcation diagram of a model file (module docstring).

    Attributes
    ----------
    source : str
    parameter_name : str
        The swept entry (dotted path).
    values : ndarray, shape (M,)
    points : ndarray, shape (M, keep, dim)
        The last ``keep`` section points per value (NaN where the map stopped).
    code : ndarray of int, shape (M,)
        Index into :data:`DIAGRAM_CLASSES`.
    period : ndarray of int, shape (M,)
        Detected period (applications of ``P^k``), 0 unless periodic.
    coords : tuple of str
        Section coordinate names.
    metadata : dict
        Section, iterations, keep.
    """

    source: str
    parameter_name: str
    values: np.ndarray
    points: np.ndarray = field(repr=False)
    code: np.ndarray = field(repr=False)
    period: np.ndarray = field(repr=False)
    coords: tuple = ()
    metadata: dict = field(default_factory=dict)
    __repr__ = compact_repr

    def counts(self) -> dict:
        """``{class: number of values}``."""
        return {c: int(np.sum(self.code == i)) for i, c in enumerate(DIAGRAM_CLASSES)}

    def summary(self) -> str:
        """A few lines in words."""
        c = ", ".join(f"{n} {k}" for k, n in self.counts().items() if n)
        per = {int(p): int(np.sum(self.period == p)) for p in np.unique(self.period) if p}
        out = (f"{Path(self.source).name}: diagram in {self.parameter_name} "
               f"[{self.values[0]:g}, {self.values[-1]:g}] ({len(self.values)} values): {c}")
        if per:
            out += "\n  periods: " + ", ".join(f"{p}: {n} values" for p, n in per.items())
        return out

    def to_dict(self) -> dict:
        """JSON-ready form."""
        return {"model": self.source, "parameter": self.parameter_name,
                "values": self.values.tolist(),
                "classification": [DIAGRAM_CLASSES[int(c)] for c in self.code],
                "period": self.period.tolist(), "counts": self.counts(),
                "coordinates": list(self.coords), "metadata": self.metadata}

    def to_dataset(self):
        """Dimensions ``(value, iterate, coordinate)``; attributes name the parameter."""
        # deferred import: loaded only when this runs, for start-up time
        import xarray as xr

        data = {"points": (("value", "iterate", "coordinate"), self.points),
                "code": ("value", self.code, {
                    "flag_values": list(range(len(DIAGRAM_CLASSES))),
                    "flag_meanings": " ".join(DIAGRAM_CLASSES)}),
                "period": ("value", self.period)}
        coords = {"value": ("value", self.values, {"long_name": self.parameter_name}),
                  "coordinate": ("coordinate", list(self.coords))}
        attrs = {"kind": "model_diagram", "model": self.source,
                 "parameter_name": self.parameter_name,
                 **encode_attrs({"metadata": dict(self.metadata)})}
        return xr.Dataset(data, coords=coords, attrs=attrs)

    @classmethod
    def from_dataset(cls, ds) -> ModelDiagram:
        """Inverse of :meth:`to_dataset`."""
        a = decode_attrs(ds.attrs)
        if a.get("kind") != "model_diagram":
            raise ValueError("the dataset does not hold a model diagram (attribute kind)")
        return cls(a["model"], a["parameter_name"], ds["value"].values,
                   ds["points"].transpose("value", "iterate", "coordinate").values,
                   ds["code"].values.astype(np.int64), ds["period"].values.astype(np.int64),
                   tuple(str(c) for c in ds["coordinate"].values),
                   dict(a.get("metadata") or {}))

    def save(self, path) -> Path:
        """Write to ``.nc`` or ``.zarr`` (by suffix)."""
        return save_result(self, path)


def load_model_diagram(path) -> ModelDiagram:
    """Read a :class:`ModelDiagram` written by :meth:`ModelDiagram.save`."""
    return load_result(ModelDiagram, path)


def _detect_period(pts, wrap, max_period):
    scale = max(1.0, float(np.max(np.abs(pts))))
    for p in range(1, min(int(max_period), len(pts) - 1) + 1):
        d = wrap(pts[p:] - pts[:-p])
        if float(np.max(np.abs(d))) <= 1e-6 * scale:
            return p
    return 0


def _diagram_chunk(chunk, *, data, source, name, spec, iterations, keep, max_period, dim,
                   main_mode=""):
    """Values of one chunk (module-level: runs in worker processes)."""
    template = ModelTemplate(data, source)
    sspec = SectionSpec(**spec)
    chart = sspec.section_map(template.model(), main_mode or None).section
    m = len(chunk["value"])
    pts = np.full((m, keep, dim), np.nan)
    code = np.full(m, 2, np.int64)
    period = np.zeros(m, np.int64)
    k = 1 if sspec.period == "auto" else int(sspec.period)
    for i in range(m):
        try:
            model = template.model({name: chunk["value"][i]})
            sim = simulated_returns(model, sspec)
            P = sspec.section_map(model, sim.mode)
            s = sim.candidates[0][1]
        except ValueError:
            continue
        it = P.iterate(s, iterations, k)
        tail = it[-keep:]
        if P.section.mode != chart.mode:       # the diagram's chart: that of the main mode
            tail = np.array([chart.from_state(*P.section.to_state(q)) if np.all(np.isfinite(q))
                             else np.full(dim, np.nan) for q in tail])
        pts[i] = tail
        if np.all(np.isfinite(tail)):
            period[i] = _detect_period(tail, P.section.wrap, max_period)
            code[i] = 0 if period[i] else 1
    return {"points": pts, "code": code, "period": period}


def model_diagram(model, param, *, contact: int = 0, wall: int | None = None,
                  event: str = "impact", period="auto", mode: str | None = None,
                  iterations: int = 300,
                  keep: int = 50, max_period: int = 16, executor="serial", max_workers=None,
                  store=None, progress: bool = True) -> ModelDiagram:
    """A brute-force bifurcation diagram of a model file in one numeric entry.

    Parameters
    ----------
    model : str, Path, dict or ModelTemplate
    param : (str, float, float, int)
        ``(KEY, MIN, MAX, NUM)``: a dotted path and its values.
    contact, wall, event, period
        The section, in whichever mode the motion crosses it at each value (``period``: the
        diagram iterates ``P^k``; ``"auto"`` iterates ``P`` and detects the period; ``mode``
        fixes the section's mode, as in :class:`~hybridpd.analysis.model_orbits.SectionSpec`).
    iterations, keep, max_period
        Iterations per value, points kept, largest period detected.
    executor, max_workers, store, progress
        As in :func:`hybridpd.sweeps.sweep.run_sweep`.

    Returns
    -------
    ModelDiagram
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.sweeps.model_regions import _axis
    from hybridpd.sweeps.sweep import run_sweep

    template = template_of(model)
    name, values = _axis("param", param, template)
    if not (int(iterations) == iterations and 1 <= keep <= iterations):
        raise ValueError(f"need 1 <= keep <= iterations, got keep = {keep!r}, iterations = "
                         f"{iterations!r}")
    if not 1 <= int(max_period) < keep:
        raise ValueError(f"max_period must be in [1, keep), got {max_period!r}")
    spec = SectionSpec(contact=contact, wall=wall, event=event, period=period, mode=mode)
    base = template.model()
    try:
        P = spec.section_map(base, simulated_returns(base, spec).mode)
    except ValueError:
        P = spec.section_map(base)
    specd = {k: getattr(spec, k) for k in spec.__dataclass_fields__}
    res = run_sweep(_diagram_chunk, {"value": values}, chunk_size=max(1, len(values) // 16),
                    executor=executor, max_workers=max_workers, store=store,
                    progress=progress, label=f"diagram of {Path(template.source).name}",
                    func_kwargs={"data": template.data, "source": template.source,
                                 "name": name, "spec": specd, "iterations": int(iterations),
                                 "keep": int(keep), "max_period": int(max_period),
                                 "dim": P.dim, "main_mode": P.section.mode},
                    metadata={"kind": "model_diagram", "version": 1})
    o = res.outputs
    meta = {"spec": specd, "iterations": int(iterations), "keep": int(keep),
            "max_period": int(max_period),
            "T": P.section.period if P.section.has_phase else math.nan}
    return ModelDiagram(template.source, name, values, o["points"], o["code"], o["period"],
                        tuple(P.section.names), meta)
