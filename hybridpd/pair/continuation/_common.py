"""Shared constants and small helpers of the continuation package (validation, phases,
parameters of an :class:`~hybridpd.pair.impactmap.ImpactMap`)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hybridpd.model import ImpactPair, PDGains, Reference, check_array, check_finite, check_int
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.orbits import symmetric_orbits

#: Parameters :func:`continue_orbit` can follow (all others fixed).
PARAMETERS = ("kp", "kv", "e", "mu", "xm", "omega", "L", "m2")
#: Parameters :func:`continue_orbit` can follow along the design path (``x10`` given: the
#: reference amplitude ``xm`` follows the symmetric-orbit design, as in
#: :func:`continue_symmetric`).
DESIGN_PARAMETERS = ("kp", "kv", "e", "mu", "omega", "L", "m2", "gamma", "x10")
#: Parameters :func:`continue_symmetric` can follow (``xm`` is an output there; ``gamma`` moves
#: ``L = gamma * x10`` with ``x10`` fixed; ``m2`` moves both masses, ``m1 = mu m2``).
SYMMETRIC_PARAMETERS = ("kp", "kv", "e", "mu", "omega", "L", "x10", "m2", "gamma")
#: Kinds of :class:`BifurcationEvent`.
EVENT_KINDS = ("fold", "period_doubling", "neimark_sacker", "grazing", "stability_change",
               "existence")

_NONREAL_TOL = 1e-9        # |Im lambda| above this (relative) counts as a complex pair
_END_GRAZE = 1e-4          # a branch whose corrector fails this close to grazing ends there
_JUMP_TOL = 1e-3           # a located crossing this far from the critical value is a jump
_NEAR_BRANCH = 5e-2        # a stuck continuation this close to a +1 multiplier: branch point


def _min(values):
    return float(min(values)) if values else np.nan


def _section_point(s, name, closure=False) -> np.ndarray:
    a = check_array(name, s, shape=(4,))  # (phi, z1, z2, z4)
    if a[3] < 0 or (a[3] == 0 and not closure):
        raise ValueError(f"{name}[3] = z4 must be > 0 (approaching the +L wall), got {a[3]!r}")
    return a


def _impact_map(P):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.impactmap import ImpactMap

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


def _wrap_diff(d, T):
    """Nearest representative of a phase difference modulo ``T`` (in ``[-T/2, T/2)``)."""
    return (d + 0.5 * T) % T - 0.5 * T


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


def _check_parameter(name, allowed):
    if not isinstance(name, str) or name not in allowed:
        raise ValueError(f"parameter must be one of {allowed}, got {name!r}")
    return name


@dataclass(frozen=True)
class _Design:
    """The design path: ``xm`` is the amplitude that puts the primary mass on the order-``n``
    triangle wave of amplitude ``x10`` (paper (20)), recomputed at every parameter value."""

    x10: float
    n: int = 1


def design_xm(pair: ImpactPair, gains: PDGains, omega: float, x10: float, n: int = 1,
              case="collocated") -> float:
    """Reference amplitude ``xm`` of the order-``n`` symmetric orbit realising ``x10``.

    The closed-form solution of (13)-(14) and (20) (the *formal* orbit: its viability is not
    required); NaN where the conditions are singular or give ``xm <= 0``.
    """
    r = symmetric_orbits(gains.kp, gains.kv, mu=pair.mu, e=pair.e, L=pair.L, omega=omega,
                         m2=pair.m2, x10=x10, n=n, case=case, margin=False, jacobian=False)
    xm = float(np.asarray(r.xm).reshape(-1)[0])
    return xm if np.isfinite(xm) and xm > 0 else np.nan


def _map_value(P: ImpactMap, name: str, design: _Design | None = None) -> float:
    if name == "gamma":
        return P.pair.L / design.x10
    if name == "x10":
        return design.x10
    return {"kp": P.gains.kp, "kv": P.gains.kv, "e": P.pair.e, "mu": P.pair.mu,
            "L": P.pair.L, "m2": P.pair.m2, "xm": P.reference.xm,
            "omega": P.reference.omega}[name]


def _map_with(P: ImpactMap, name: str, value: float, design: _Design | None = None):
    """A copy of ``P`` with one parameter changed (the others and the tolerances kept).

    With a ``design``, ``xm`` follows the design at the new value (``gamma`` moves
    ``L = gamma * x10``; ``x10`` moves the design itself); None where the design has no
    amplitude.
    """
    pair, g, ref = P.pair, P.gains, P.reference
    if name in ("kp", "kv"):
        g = PDGains(**{"kp": g.kp, "kv": g.kv, name: value})
    elif name in ("e", "mu", "L", "m2", "gamma"):
        if name == "gamma":
            name, value = "L", value * design.x10
        pair = ImpactPair(**{"mu": pair.mu, "e": pair.e, "L": pair.L, "m2": pair.m2,
                             name: value})
    elif name in ("xm", "omega"):
        ref = Reference(**{"xm": ref.xm, "omega": ref.omega, name: value})
    if design is not None:
        if name == "x10":
            design = _Design(value, design.n)
        xm = design_xm(pair, g, ref.omega, design.x10, design.n, P.case)
        if not np.isfinite(xm):
            return None
        ref = Reference(xm, ref.omega)
    return ImpactMap(pair, g, ref, P.case, tol=P.tol, max_impacts=P.max_impacts)


def _fixed_parameters(P: ImpactMap) -> dict:
    return {"kp": P.gains.kp, "kv": P.gains.kv, "e": P.pair.e, "mu": P.pair.mu,
            "L": P.pair.L, "m2": P.pair.m2, "xm": P.reference.xm,
            "omega": P.reference.omega, "case": P.case.value}


def _scale(x):
    return max(1.0, float(np.max(np.abs(x[1:4]))))


def _f(x):
    return None if x is None or not np.isfinite(x) else float(x)


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
