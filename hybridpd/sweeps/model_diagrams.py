"""Bifurcation diagrams of any model file in one of its numeric entries.

A model file with one entry swept (a dotted path, :mod:`hybridpd.mechanics.params`) is a
family of section maps, :class:`ModelFamily`: at each value it simulates the model from its
initial state for a transient and starts the chosen section's map ``P^k`` (in the mode where
the motion crosses it) from the last crossing. :func:`model_diagram` runs the one diagram,
:func:`hybridpd.analysis.diagrams.bifurcation_diagram`, over that family as a sweep on any
executor (:func:`hybridpd.sweeps.diagrams.diagram_sweep`; a scheduler address runs it on an
existing Dask cluster). Without Lyapunov exponents every non-periodic value is
``quasiperiodic`` (quasi-periodic or chaotic); a value whose simulated motion or map
diverges is ``diverged``; a map that stops otherwise (no crossing, sticking for good) is
``undefined`` with its reason in ``status``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hybridpd.analysis.diagrams import BifurcationDiagram, StoppedMap
from hybridpd.analysis.model_sections import (
    DivergedRun,
    SectionSpec,
    fix_section,
    simulated_returns,
)
from hybridpd.mechanics.params import ModelTemplate
from hybridpd.sweeps.model_regions import template_of

__all__ = ["ModelFamily", "model_diagram"]


@dataclass(frozen=True, eq=False)
class ModelFamily:
    """A model file's section maps along one entry, started by simulation.

    Parameters
    ----------
    data : dict
        The parsed model file.
    source : str
        Where it came from (for titles).
    parameter : str
        The swept entry (dotted path).
    spec : dict
        The fields of a :class:`~hybridpd.analysis.model_orbits.SectionSpec`.
    main_mode : str
        The mode of the diagram's chart (the points of maps in other modes are recorded in
        its coordinates).

    Calling it with a value gives ``(P, start)``: the section map in the mode where the
    simulated motion crosses the section, and the last crossing (``ValueError`` where the
    motion does not cross it).

    Examples
    --------
    >>> pair = {"system": {"dofs": ["x1", "x2"], "masses": [0.1, 1.0], "input": [0.0, 1.0]},
    ...         "contact": [{"between": ["x1", "x2"], "lo": -0.75, "hi": 0.75,
    ...                      "restitution": 0.5}],
    ...         "controller": {"type": "pd", "kp": 10.0, "kv": 20.0, "measure": "x2"},
    ...         "reference": {"type": "sine", "amplitude": 0.4, "omega": 5.0,
    ...                       "feedforward_mass": 1.0},
    ...         "initial": {"q": [0.3, 0.0], "v": [0.5, 0.0]}}
    >>> fam = ModelFamily.of(pair, "controller.kv")       # the stroboscopic section
    >>> P, start = fam(20.0)
    >>> P.names, bool(np.allclose(P(start), start, atol=1e-6))
    (('x1', 'x1_dot', 'x2', 'x2_dot'), True)
    >>> from hybridpd.analysis.model_sections import SectionSpec
    >>> P, start = ModelFamily.of(pair, "controller.kv", SectionSpec(event="impact"))(20.0)
    >>> P.names
    ('phi', 'x1_dot', 'x2', 'x2_dot')
    """

    data: dict
    source: str
    parameter: str
    spec: dict
    main_mode: str = ""

    @classmethod
    def of(cls, model, parameter: str, spec: SectionSpec | None = None) -> ModelFamily:
        """The family of ``model`` (path, dict or template) in ``parameter``; the chart's
        mode is that of the motion of the file's own values."""
        template = template_of(model)
        base = template.model()
        spec, mode, _ = fix_section(base, spec or SectionSpec())
        P = spec.section_map(base, mode or None)
        fields = {k: getattr(spec, k) for k in spec.__dataclass_fields__}
        return cls(template.data, template.source, parameter, fields, P.section.mode)

    def __call__(self, value):
        spec = SectionSpec(**self.spec)
        model = ModelTemplate(self.data, self.source).model({self.parameter: value})
        try:
            sim = simulated_returns(model, spec)
        except DivergedRun:
            # no start: the motion diverges at this value, which is then classed diverged
            P = spec.section_map(model, self.main_mode or None)
            return StoppedMap(P, "diverged"), np.full(P.dim, np.nan)
        P = spec.section_map(model, sim.mode)
        if spec.event == "stroboscopic" and self.main_mode and sim.mode != self.main_mode:
            # one chart for the whole diagram: the state at the phase, in the chart of the
            # main mode (an image in another mode is then undefined, and said so)
            z = P.section.to_state(sim.candidates[0][1])[0]
            P = spec.section_map(model, self.main_mode)
            return P, P.section.from_state(z)
        return P, sim.candidates[0][1]

    def project(self, P, points) -> np.ndarray:
        """``points`` of ``P`` in the chart of :attr:`main_mode`."""
        if P.section.mode == self.main_mode:
            return points
        chart = SectionSpec(**self.spec).section_map(
            ModelTemplate(self.data, self.source).model(), self.main_mode or None).section
        return np.array([chart.from_state(*P.section.to_state(q)) if np.all(np.isfinite(q))
                         else np.full(len(q), np.nan) for q in points])

    @property
    def metadata(self) -> dict:
        """``source`` and ``spec``."""
        return {"source": self.source, "spec": dict(self.spec)}


def model_diagram(model, param, *, contact: int = 0, wall: int | None = None,
                  event: str = "auto", period="auto", mode: str | None = None,
                  phase: float | None = None,
                  iterations: int = 300, keep: int = 50, max_period: int = 16,
                  executor="serial", max_workers=None, store=None,
                  progress: bool = True) -> BifurcationDiagram:
    """A brute-force bifurcation diagram of a model file in one numeric entry.

    Parameters
    ----------
    model : str, Path, dict or ModelTemplate
    param : (str, float, float, int)
        ``(KEY, MIN, MAX, NUM)``: a dotted path and its values.
    contact, wall, event, period, mode, phase
        The section (:class:`~hybridpd.analysis.model_orbits.SectionSpec`; ``period``: the
        diagram iterates ``P^k``, ``"auto"`` iterates ``P``).
    iterations, keep, max_period
        Iterations per value, points kept (``8 <= keep <= iterations``), largest period
        detected (at most ``keep // 2``).
    executor, max_workers, store, progress
        As in :func:`hybridpd.sweeps.sweep.run_sweep`.

    Returns
    -------
    BifurcationDiagram
        With ``names`` the section's coordinates and ``metadata`` holding ``source``,
        ``spec`` and the section's period ``T``.
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.sweeps.diagrams import diagram_sweep
    from hybridpd.sweeps.model_regions import _axis

    template = template_of(model)
    name, values = _axis("param", param, template)
    fam = ModelFamily.of(template, name, SectionSpec(contact=contact, wall=wall, event=event,
                                                     period=period, mode=mode, phase=phase))
    spec = SectionSpec(**fam.spec)
    k = 1 if spec.period == "auto" else int(spec.period)
    d = diagram_sweep(fam, values, period=k, iterations=iterations, keep=keep,
                      max_period=min(int(max_period), int(keep) // 2), period_tol=1e-6,
                      executor=executor, max_workers=max_workers, store=store,
                      progress=progress, label=f"diagram of {Path(template.source).name}",
                      parameter=name)
    P = spec.section_map(template.model(), fam.main_mode or None)
    T = P.section.period if P.section.period else math.nan
    return BifurcationDiagram(d.parameter_name, d.values, d.points, d.code, d.periods,
                              d.status, d.spectrum, d.final, tuple(P.section.names), {},
                              dict(d.metadata, T=T))
