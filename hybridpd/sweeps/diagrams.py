"""Bifurcation diagrams of any family of maps as a sweep (any executor, a cluster).

:func:`diagram_sweep` gives what :func:`hybridpd.analysis.diagrams.bifurcation_diagram` gives
without ``follow``: every value starts from the same point (or from the family's own start,
e.g. a simulation), so the values are independent and run in chunks on any executor (a
scheduler address runs them on an existing Dask cluster). Following the attractor from value
to value is sequential and stays with ``bifurcation_diagram``. The family must be picklable
and describable by :func:`~hybridpd.sweeps.sweep.run_sweep` (a dataclass, e.g.
:class:`~hybridpd.pair.bifdiagram.ImpactMapFamily`).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from hybridpd.analysis.diagrams import BifurcationDiagram, bifurcation_diagram

__all__ = ["diagram_sweep"]

_FIELDS = ("points", "code", "periods", "spectrum", "final")
#: Statuses carried through a sweep by code (others become ``"other"``; a value where no map
#: was built reads ``"no map"``).
_STATUSES = ("", "no map", "other", "end_time", "sticking", "unresolved", "nonfinite",
             "off_section", "diverged")


def _status_code(why: str) -> int:
    if why.startswith("no map"):
        return 1
    return _STATUSES.index(why) if why in _STATUSES else 2


def _diagram_chunk(chunk, *, builder, kwargs):
    """Values of one chunk (module-level: runs in worker processes)."""
    d = bifurcation_diagram(builder, chunk["value"], follow=False, **kwargs)
    out = {f: getattr(d, f) for f in _FIELDS}
    out["status"] = np.array([_status_code(s) for s in d.status], np.int64)
    return out


def diagram_sweep(builder, values, *, s0=None, executor="serial", max_workers=None,
                  store=None, progress: bool = False, label: str = "bifurcation diagram",
                  **kwargs) -> BifurcationDiagram:
    """:func:`~hybridpd.analysis.diagrams.bifurcation_diagram` without ``follow``, as a sweep.

    Parameters
    ----------
    builder : callable
        The family (module docstring).
    values : array_like, shape (M,)
        Parameter values (at least 2).
    s0 : array_like, optional
        The start of every value (default: the family's ``initial`` hook at all ``values``,
        or its own start per value).
    executor, max_workers, store, progress, label
        As in :func:`hybridpd.sweeps.sweep.run_sweep`.
    **kwargs
        The other arguments of ``bifurcation_diagram`` (not ``follow=True``).

    Returns
    -------
    BifurcationDiagram
        The same as the serial call without ``follow`` (the statuses named in
        ``_STATUSES``, ``"other"`` for any other).

    Examples
    --------
    >>> from dataclasses import dataclass
    >>> import hybridpd as hp
    >>> class Logistic(hp.PoincareMap):
    ...     names = ("x",)
    ...     def __init__(self, r):
    ...         self.r = r
    ...     def apply(self, s, k=1, jacobian=False):
    ...         return hp.MapResult(np.array([self.r * s[0] * (1 - s[0])]))
    >>> @dataclass(frozen=True)
    ... class Family:           # a dataclass: the sweep records its fields
    ...     parameter: str = "r"
    ...     def __call__(self, r):
    ...         return Logistic(r)
    >>> d = diagram_sweep(Family(), [2.8, 3.2, 3.5, 3.55], s0=[0.3])
    >>> d.parameter_name, d.periods.tolist()
    ('r', [1, 2, 4, 8])
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.sweeps.sweep import run_sweep

    if kwargs.pop("follow", False):
        raise ValueError("follow=True runs the values in order: use bifurcation_diagram")
    v = np.asarray(values, float).reshape(-1)
    if s0 is None and hasattr(builder, "initial"):
        prepared = builder.prepare(v) if hasattr(builder, "prepare") else builder
        s0 = prepared.initial(v)
    # the run on the first two values checks every argument and gives the metadata
    head = bifurcation_diagram(builder, v[:2], s0=s0, follow=False, **kwargs)
    kw = dict(kwargs, s0=None if s0 is None else np.asarray(s0, float).tolist())
    M = v.size
    cs = max(2, -(-M // 16))
    while M % cs == 1 and cs < M:          # every chunk needs two values
        cs += 1
    res = run_sweep(_diagram_chunk, {"value": v}, chunk_size=cs, executor=executor,
                    max_workers=max_workers, store=store, progress=progress, label=label,
                    func_kwargs={"builder": builder, "kwargs": kw}, allow_nan=False)
    o = res.outputs
    variables = builder.variables(v) if hasattr(builder, "variables") else {}
    return dataclasses.replace(
        head, values=v, status=tuple(_STATUSES[int(c)] for c in o["status"]),
        variables={k: np.asarray(a, float) for k, a in variables.items()},
        **{f: o[f] for f in _FIELDS})
