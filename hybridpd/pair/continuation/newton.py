"""``P^k``, its residual and Jacobian (symbolic chain or finite differences), and the damped
Newton method shared by the orbit search and the correctors."""
from __future__ import annotations

import numpy as np

from hybridpd.analysis.pathfollow import NewtonResult as _NewtonOut  # noqa: F401
from hybridpd.analysis.pathfollow import newton as _newton  # noqa: F401
from hybridpd.model import wrap_phase
from hybridpd.pair.continuation._common import (
    _impact_map,
    _in_domain,
    _map_value,
    _map_with,
    _positive_float,
    _positive_int,
    _section_point,
)
from hybridpd.pair.continuation.trace import trace_map
from hybridpd.pair.impactmap import ImpactMap


def _residual(P: ImpactMap, s: np.ndarray, k: int):
    """``P^k(s) - s`` with the phase difference unwrapped, or None where undefined."""
    if not (np.all(np.isfinite(s)) and s[3] > 0):
        return None
    img, ok = P.apply_many(s[None, :], k)
    if not ok[0]:
        return None
    r = img[0] - s
    r[0] = wrap_phase(r[0], P.period)
    return r


def map_power_jacobian(impact_map_: ImpactMap, s, period: int = 1, *, method: str = "auto",
                       fd_step: float = 1e-6):
    """Jacobian of ``P^k`` at ``s`` (4x4), and how it was obtained.

    Parameters
    ----------
    impact_map_ : ImpactMap
    s : array_like, shape (4,)
        Section point.
    period : int
        ``k``, the number of applications of ``P``.
    method : {"auto", "symbolic", "fd"}
        ``"symbolic"``: chain rule ``DP(s_{k-1}) ... DP(s_0)`` of the symbolic Jacobians
        (every iterate must have the simple pattern ``(+L, -L, +L)``); ``"fd"``: central
        differences of the simulated ``P^k`` (phase unwrapped) with steps
        ``fd_step * max(1, |s_j|)``; ``"auto"``: symbolic when possible.
    fd_step : float
        Relative finite-difference step.

    Returns
    -------
    DP : ndarray, shape (4, 4)
    method : str
        ``"symbolic"`` or ``"fd"``.
    traces : list of MapTrace
        The ``k`` applications of ``P`` along the orbit segment (without margins).

    Raises
    ------
    ValueError
        Unknown method, or ``"symbolic"`` requested on a non-simple pattern.
    RuntimeError
        ``P^k`` undefined at ``s`` or at every finite-difference point of a column.
    """
    if method not in ("auto", "symbolic", "fd"):
        raise ValueError(f"method must be 'auto', 'symbolic' or 'fd', got {method!r}")
    k = _positive_int("period", period)
    fd_step = _positive_float("fd_step", fd_step)
    P = _impact_map(impact_map_)
    s = _section_point(s, "s")
    pts = [s]
    traces = []
    for _ in range(k):
        tr = trace_map(P, pts[-1], margin=False)
        if not tr.ok:
            raise RuntimeError(f"P undefined along the orbit (status {tr.status})")
        traces.append(tr)
        pts.append(tr.s)
    simple = all(tr.simple for tr in traces)
    if method == "symbolic" and not simple:
        raise ValueError("method='symbolic' needs the simple pattern (+L, -L, +L) on every "
                         f"iterate; got {[tr.walls for tr in traces]}")
    if simple and method != "fd":
        J = np.eye(4)
        for si, tr in zip(pts, traces):
            J = P._symbolic(si, tr.steps[0].tau, tr.steps[1].tau).DP.reshape(4, 4) @ J
        return J, "symbolic", traces
    return _fd_jacobian(P, s, k, fd_step), "fd", traces


def _fd_jacobian(P: ImpactMap, s: np.ndarray, k: int, fd_step: float) -> np.ndarray:
    """Central differences of ``P^k`` (one-sided where a side is undefined)."""
    return P.jacobian_fd(s, k=k, h=fd_step, scale=np.maximum(1.0, np.abs(s)), one_sided=True)


def _param_derivative(P: ImpactMap, name: str, s: np.ndarray, k: int, fd_step: float,
                      design=None):
    """``d(P^k(s) - s)/dp`` by central (or one-sided at a domain edge) differences."""
    p = _map_value(P, name, design)
    h = fd_step * max(1.0, abs(p))
    vals = []
    for q in (p + h, p - h):
        Q = _map_with(P, name, q, design) if _in_domain(name, q) else None
        vals.append(None if Q is None else _residual(Q, s, k))
    if vals[0] is not None and vals[1] is not None:
        d, hh = vals[0] - vals[1], 2 * h
    else:
        r0 = _residual(P, s, k)
        if r0 is None:
            raise RuntimeError("P^k undefined at the point")
        if vals[0] is not None:
            d, hh = vals[0] - r0, h
        elif vals[1] is not None:
            d, hh = r0 - vals[1], h
        else:
            raise RuntimeError(f"P^k undefined on both sides of {name} = {p:g}")
    d[0] = wrap_phase(d[0], P.period)
    return d / hh
