"""The paper's open questions on ``mu`` and ``gamma = L / x10``, answered with numbers.

The paper expects the existence region to shrink as ``mu`` grows (the control cannot act on a
heavy primary mass) and control to become easier as ``mu -> 0``; it leaves the influence of
``L`` (that is ``gamma``) to future work. :func:`param_study` measures both on the paper's gain
box: the share of the box where the orbit exists, where its candidate is stable, and where
both hold, against the parameter on a log axis, and a map of existence and stability in the
``(parameter, kv)`` plane at ``kp = 10``. The limits ``mu -> 0``, ``mu -> inf`` and ``gamma -> 0``
are derived in ``symbolic/limits.py`` and compared there (and in the tests) with maps computed
at ``mu = 1e-4, 1e4`` and ``gamma = 1e-4``, which this study reports as ``limits``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.model import Case
from hybridpd.pair.orbits import symmetric_orbits
from hybridpd.reproduce.study import candidate_stability

__all__ = ["LIMIT_POINTS", "ParamStudy", "check_study", "param_shares", "param_study"]

#: Parameter values at which the limits are checked.
LIMIT_POINTS = {"mu": (1e-4, 1e4), "gamma": (1e-4,)}


@dataclass(frozen=True)
class ParamStudy:
    """Regions against ``mu`` or ``gamma``.

    Attributes
    ----------
    name : {"mu", "gamma"}
    values : ndarray
        The parameter (log-spaced).
    e : ndarray
    fractions : dict
        ``{case: {"exists" | "stability" | "both": ndarray (len(e), len(values))}}``: shares
        of the gain box.
    box : dict
        ``{"kp": [lo, hi, num], "kv": [lo, hi, num]}``.
    map_kv : ndarray
        ``kv`` axis of the ``(parameter, kv)`` maps (at ``kp = map_kp``).
    map_kp : float
    maps : dict
        ``{case: {"exists": bool (len(e), len(map_kv), len(values)), "stable": ...}}``.
    limits : dict
        ``{str(value): {case: {quantity: [share per e]}}}`` at :data:`LIMIT_POINTS`.
    fixed : dict
        The other parameters.
    check : dict or None
        The resolution check: ``{"box", "fractions", "limits"}`` as above on a grid with
        another number of cells (:func:`check_study`).
    """

    name: str
    values: np.ndarray
    e: np.ndarray
    fractions: dict
    box: dict
    map_kv: np.ndarray
    map_kp: float
    maps: dict
    limits: dict
    fixed: dict
    check: dict = None
    __repr__ = compact_repr

    def to_dict(self) -> dict:
        return {"name": self.name, "values": self.values.tolist(), "e": self.e.tolist(),
                "box": self.box, "map_kp": self.map_kp, "fixed": self.fixed,
                "fractions": {c: {q: a.tolist() for q, a in d.items()}
                              for c, d in self.fractions.items()},
                "limits": self.limits,
                "check": None if self.check is None else {
                    "box": self.check["box"], "limits": self.check["limits"],
                    "fractions": {c: {q: a.tolist() for q, a in d.items()}
                                  for c, d in self.check["fractions"].items()}}}


def _box(kp_axis, kv_axis):
    return {"kp": [float(kp_axis[0]), float(kp_axis[-1]), len(kp_axis)],
            "kv": [float(kv_axis[0]), float(kv_axis[-1]), len(kv_axis)]}


def check_study(study: ParamStudy, kp_axis, kv_axis) -> ParamStudy:
    """``study`` with :attr:`ParamStudy.check` filled: its shares and limits recomputed on
    the gain grid ``kp_axis x kv_axis`` (the same box, another number of cells)."""
    from dataclasses import replace

    kp_axis, kv_axis = np.asarray(kp_axis, float), np.asarray(kv_axis, float)
    fixed = dict(study.fixed)
    fractions, limits = {}, {}
    for case in study.fractions:
        fractions[case] = param_shares(case, study.name, study.values, kp_axis, kv_axis,
                                       e=study.e, fixed=fixed)
        lim = param_shares(case, study.name, LIMIT_POINTS[study.name], kp_axis, kv_axis,
                           e=study.e, fixed=fixed)
        for k, v in enumerate(LIMIT_POINTS[study.name]):
            limits.setdefault(f"{v:g}", {})[case] = {q: a[:, k].tolist() for q, a in lim.items()}
    return replace(study, check={"box": _box(kp_axis, kv_axis), "fractions": fractions,
                                 "limits": limits})


def _plant(name, value, fixed):
    mu = value if name == "mu" else fixed["mu"]
    L = value * fixed["x10"] if name == "gamma" else fixed["gamma"] * fixed["x10"]
    return mu, L


def param_shares(case, name, values, kp_axis, kv_axis, *, e, fixed) -> dict:
    """Shares of the gain box per ``e`` and parameter value (see :class:`ParamStudy`)."""
    if name not in ("mu", "gamma"):
        raise ValueError(f"name must be 'mu' or 'gamma', got {name!r}")
    es = np.atleast_1d(np.asarray(e, float))
    vals = np.atleast_1d(np.asarray(values, float))
    kp_axis, kv_axis = np.asarray(kp_axis, float), np.asarray(kv_axis, float)
    # bounded memory: about 1e5 grid points (and their 4x4 Jacobians) at a time
    per = max(1, int(1e5 // (len(es) * kp_axis.size * kv_axis.size)))
    if vals.size > per:
        parts = [param_shares(case, name, vals[i:i + per], kp_axis, kv_axis, e=es,
                              fixed=fixed) for i in range(0, vals.size, per)]
        return {q: np.concatenate([p[q] for p in parts], axis=1) for q in parts[0]}
    E, V, KV, KP = np.meshgrid(es, vals, kv_axis, kp_axis, indexing="ij")
    mu, L = _plant(name, V, fixed)
    kw = dict(mu=mu, e=E, L=L, omega=fixed["omega"], m2=fixed["m2"], x10=fixed["x10"],
              n=fixed["n"])
    r = symmetric_orbits(KP, KV, case=case, **kw)
    rho = candidate_stability(case, KP, KV, **kw)
    with np.errstate(invalid="ignore"):
        st = np.nan_to_num(rho, nan=np.inf) < 1.0
    mean = lambda a: a.mean(axis=(2, 3))
    return {"exists": mean(r.exists), "stability": mean(st), "both": mean(r.stable)}


def param_study(name, *, values_range, points, kp_axis, kv_axis, e, fixed, map_kp=10.0,
                cases=("collocated", "noncollocated"), log=None) -> ParamStudy:
    """Measure the regions against ``mu`` or ``gamma`` (see the module docstring).

    Parameters
    ----------
    name : {"mu", "gamma"}
    values_range : (lo, hi)
        Log-spaced range of the parameter.
    points : int
        Number of parameter values (also the columns of the maps).
    kp_axis, kv_axis : array_like
        The gain box (its ``kv`` axis is also the maps' ``kv`` axis).
    e : sequence of float
    fixed : dict
        ``mu, gamma, x10, m2, omega, n`` (the swept one is ignored).
    map_kp : float
        ``kp`` of the ``(parameter, kv)`` maps.
    log : callable, optional
        Progress messages.

    Examples
    --------
    >>> fx = dict(mu=0.1, gamma=0.75, x10=1.0, m2=1.0, omega=5.0, n=1)
    >>> s = param_study("mu", values_range=(0.01, 10), points=3, kp_axis=[5, 10],
    ...                 kv_axis=[10, 20], e=[0.5], fixed=fx, cases=("collocated",))
    >>> s.fractions["collocated"]["both"].shape
    (1, 3)
    """
    lo, hi = (float(v) for v in values_range)
    if not 0 < lo < hi:
        raise ValueError(f"values_range must satisfy 0 < lo < hi, got {values_range!r}")
    vals = np.logspace(np.log10(lo), np.log10(hi), int(points))
    es = np.atleast_1d(np.asarray(e, float))
    kv_axis = np.asarray(kv_axis, float)
    kp_axis = np.asarray(kp_axis, float)
    fractions, maps, limits = {}, {}, {}
    for case in cases:
        case = Case.parse(case).value
        fractions[case] = param_shares(case, name, vals, kp_axis, kv_axis, e=es, fixed=fixed)
        E, KV, V = np.meshgrid(es, kv_axis, vals, indexing="ij")
        mu, L = _plant(name, V, fixed)
        r = symmetric_orbits(map_kp, KV, mu=mu, e=E, L=L, omega=fixed["omega"],
                             m2=fixed["m2"], x10=fixed["x10"], n=fixed["n"], case=case)
        maps[case] = {"exists": r.exists, "stable": r.stable}
        lim = param_shares(case, name, LIMIT_POINTS[name], kp_axis, kv_axis, e=es,
                           fixed=fixed)
        for k, v in enumerate(LIMIT_POINTS[name]):
            limits.setdefault(f"{v:g}", {})[case] = {q: a[:, k].tolist() for q, a in lim.items()}
        if log is not None:
            log(f"{name} study {case}: done")
    box = _box(kp_axis, kv_axis)
    fx = {k: v for k, v in fixed.items() if k != name}
    return ParamStudy(name, vals, es, fractions, box, kv_axis, float(map_kp), maps, limits, fx)
