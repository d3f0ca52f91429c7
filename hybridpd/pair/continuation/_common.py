"""Shared constants and small helpers of the continuation package (validation, phases,
parameters of an :class:`~hybridpd.pair.impactmap.ImpactMap`)."""
from __future__ import annotations

import math

import numpy as np

from hybridpd.model import check_finite, check_int
from hybridpd.pair.family import (  # noqa: F401 (the continuation package's names)
    DESIGN_PARAMETERS,
    PARAMETERS,
    _check_parameter,
    _Design,
    _fixed_parameters,
    _map_with,
    _min,
    design_xm,
)
from hybridpd.pair.impactmap import ImpactMap, _section_point  # noqa: F401

#: Parameters :func:`continue_symmetric` can follow (``xm`` is an output there; ``gamma`` moves
#: ``L = gamma * x10`` with ``x10`` fixed; ``m2`` moves both masses, ``m1 = mu m2``).
SYMMETRIC_PARAMETERS = ("kp", "kv", "e", "mu", "omega", "L", "x10", "m2", "gamma")
#: Kinds of :class:`BifurcationEvent`.
EVENT_KINDS = ("fold", "period_doubling", "neimark_sacker", "grazing", "stability_change",
               "existence")

_END_GRAZE = 1e-4          # a branch whose corrector fails this close to grazing ends there
_NEAR_BRANCH = 5e-2        # a stuck continuation this close to a +1 multiplier: branch point


def _impact_map(P):
    if not isinstance(P, ImpactMap):
        raise ValueError(f"impact_map_ must be an ImpactMap, got {type(P).__name__}")
    return P


def _positive_int(name, value) -> int:
    return check_int(name, value, 1)


def _positive_float(name, value) -> float:
    v = check_finite(name, value)
    if v <= 0:
        raise ValueError(f"{name} must be > 0, got {value!r}")
    return v


def _domain(name):
    """``(lo, hi, lo_closed)`` of a parameter's admissible values."""
    if name == "e":
        return 0.0, 1.0, True
    if name == "xm":
        return 0.0, math.inf, True
    return 0.0, math.inf, False


def _in_domain(name, v) -> bool:
    lo, hi, closed = _domain(name)
    if not math.isfinite(v):
        return False
    return (v >= lo if closed else v > lo) and v <= hi


def _map_value(P: ImpactMap, name: str, design: _Design | None = None) -> float:
    if name == "gamma":
        return P.pair.L / design.x10
    if name == "x10":
        return design.x10
    return {"kp": P.gains.kp, "kv": P.gains.kv, "e": P.pair.e, "mu": P.pair.mu,
            "L": P.pair.L, "m2": P.pair.m2, "xm": P.reference.xm,
            "omega": P.reference.omega}[name]


def _scale(x):
    return max(1.0, float(np.max(np.abs(x[1:4]))))


def _path_steps(name, p0, stop, step, max_step, min_step, max_steps, defaults):
    """Validate a continuation path ``p0 -> stop`` and its step sizes.

    ``defaults = (n_steps, n_max, min_fraction)``: unset sizes become ``span / n_steps``,
    ``span / n_max`` and ``span * min_fraction``. Returns
    ``(span, step, max_step, min_step, max_steps)``.
    """
    if not _in_domain(name, stop):
        lo, hi, _ = _domain(name)
        raise ValueError(f"stop = {stop!r} is outside the domain of {name} ({lo:g}, {hi:g})")
    if stop == p0:
        raise ValueError(f"stop must differ from the starting value {name} = {p0!r}")
    n_steps, n_max, min_fraction = defaults
    span = abs(stop - p0)
    step = span / n_steps if step is None else _positive_float("step", step)
    max_step = span / n_max if max_step is None else _positive_float("max_step", max_step)
    min_step = span * min_fraction if min_step is None else _positive_float("min_step", min_step)
    if min_step > step:
        raise ValueError(f"min_step = {min_step!r} must not exceed step = {step!r}")
    return span, step, max(max_step, step), min_step, _positive_int("max_steps", max_steps)
