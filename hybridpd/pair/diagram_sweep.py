"""The impact pair's brute-force bifurcation diagram as a sweep (any executor, a cluster).

:func:`pair_diagram` gives exactly what
:func:`hybridpd.pair.bifdiagram.bifurcation_diagram` gives without ``follow``: every value
starts from the same initial point, so the values are independent and run in chunks on any
executor (a scheduler address runs them on an existing Dask cluster). Following the attractor
from value to value is sequential and stays with ``bifurcation_diagram``.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from hybridpd.model import ImpactPair
from hybridpd.pair.bifdiagram import BifurcationDiagram, bifurcation_diagram

__all__ = ["pair_diagram"]

_FIELDS = ("points", "code", "period", "lyapunov_spectrum", "xm", "L", "final", "status")


def _diagram_chunk(chunk, *, pair, gains, omega, parameter, kwargs):
    """Values of one chunk (module-level: runs in worker processes)."""
    d = bifurcation_diagram(ImpactPair(*pair), tuple(gains), omega, parameter, chunk["value"],
                            **kwargs)
    return {f: getattr(d, f) for f in _FIELDS}


def pair_diagram(pair: ImpactPair, gains, omega: float, parameter: str, values, *,
                 executor="serial", max_workers=None, progress: bool = False,
                 **kwargs) -> BifurcationDiagram:
    """:func:`~hybridpd.pair.bifdiagram.bifurcation_diagram` (without ``follow``) as a sweep.

    Parameters
    ----------
    pair, gains, omega, parameter, values
        As in :func:`~hybridpd.pair.bifdiagram.bifurcation_diagram`.
    executor, max_workers, progress
        As in :func:`hybridpd.sweeps.sweep.run_sweep`.
    **kwargs
        The other arguments of ``bifurcation_diagram`` (not ``follow=True``).

    Returns
    -------
    BifurcationDiagram
        The same as the serial call.
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.sweeps.sweep import run_sweep

    if kwargs.get("follow"):
        raise ValueError("follow=True runs the values in order: use bifurcation_diagram")
    v = np.asarray(values, float)
    # the run on the first two values checks every argument and fixes the initial point
    head = bifurcation_diagram(pair, gains, omega, parameter, v[:2], **kwargs)
    kw = dict(kwargs, initial=[float(x) for x in head.initial])
    M = v.size
    cs = max(2, -(-M // 16))
    while M % cs == 1 and cs < M:          # every chunk needs two values
        cs += 1
    res = run_sweep(_diagram_chunk, {"value": v}, chunk_size=cs, executor=executor,
                    max_workers=max_workers, progress=progress, label="bifurcation diagram",
                    func_kwargs={"pair": [pair.mu, pair.e, pair.L, pair.m2],
                                 "gains": [float(gains[0]), float(gains[1])]
                                 if not hasattr(gains, "kp") else [gains.kp, gains.kv],
                                 "omega": float(omega), "parameter": parameter, "kwargs": kw})
    o = res.outputs
    return dataclasses.replace(head, values=v, lyapunov=o["lyapunov_spectrum"][:, 0],
                               **{f: o[f] for f in _FIELDS})
