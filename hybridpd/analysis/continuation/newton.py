"""``P^k``, its residual and Jacobian (symbolic chain or finite differences), and the damped
Newton method shared by the orbit search and the correctors."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hybridpd.analysis.continuation._common import (
    _impact_map,
    _in_domain,
    _map_value,
    _map_with,
    _positive_float,
    _positive_int,
    _section_point,
    _wrap_diff,
)
from hybridpd.analysis.continuation.trace import trace_map
from hybridpd.analysis.impactmap import ImpactMap


def _residual(P: ImpactMap, s: np.ndarray, k: int):
    """``P^k(s) - s`` with the phase difference unwrapped, or None where undefined."""
    if not (np.all(np.isfinite(s)) and s[3] > 0):
        return None
    img, ok = P.apply_many(s[None, :], k)
    if not ok[0]:
        return None
    r = img[0] - s
    r[0] = _wrap_diff(r[0], P.period)
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
        return P.apply(s, k, jacobian=True).DP, "symbolic", traces
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
    d[0] = _wrap_diff(d[0], P.period)
    return d / hh


# ----------------------------------------------------------------------------------------
# Damped Newton
# ----------------------------------------------------------------------------------------


@dataclass
class _NewtonOut:
    x: np.ndarray
    converged: bool
    reason: str
    history: list
    iterations: int
    step: float


def _newton(resid, jac, x0, *, tol, max_iter, scale, min_lambda=2.0 ** -12):
    """Damped Newton with backtracking on ``||F||_inf``.

    ``resid(x)`` returns the residual or None where undefined; ``jac(x)`` the Jacobian (may
    raise). Converged when ``||F|| <= tol * scale(x)``, or when a full Newton step is itself
    below ``tol * scale(x)`` (the residual then sits at its rounding floor, which exceeds
    ``tol`` for strongly unstable orbits whose multipliers amplify rounding).
    """
    x = np.array(x0, dtype=float)
    r = resid(x)
    if r is None:
        return _NewtonOut(x, False, "map undefined at the initial point", [], 0, np.nan)
    nr = float(np.max(np.abs(r)))
    hist = [nr]
    last = np.nan
    for it in range(1, max_iter + 1):
        if nr <= tol * scale(x):
            return _NewtonOut(x, True, "residual below tol", hist, it - 1, last)
        try:
            J = jac(x)
            dx = np.linalg.solve(J, -r)
        except (np.linalg.LinAlgError, RuntimeError, ValueError) as exc:
            return _NewtonOut(x, False, f"Jacobian failed: {exc}", hist, it - 1, last)
        if not np.all(np.isfinite(dx)):
            return _NewtonOut(x, False, "singular Jacobian", hist, it - 1, last)
        last = float(np.max(np.abs(dx)))
        lam = 1.0
        accepted = False
        while lam >= min_lambda:
            xn = x + lam * dx
            rn = resid(xn)
            if rn is not None:
                nrn = float(np.max(np.abs(rn)))
                if nrn <= (1.0 - 1e-4 * lam) * nr:
                    accepted = True
                    break
            lam *= 0.5
        if not accepted:
            if last <= tol * scale(x):
                return _NewtonOut(x, True, "Newton step below tol (residual at rounding floor)",
                                  hist, it, last)
            return _NewtonOut(x, False, "line search failed (no decrease of the residual)",
                              hist, it, last)
        x, r, nr = xn, rn, nrn
        hist.append(nr)
        if lam == 1.0 and last <= tol * scale(x):
            return _NewtonOut(x, True, "Newton step below tol", hist, it, last)
    if nr <= tol * scale(x):
        return _NewtonOut(x, True, "residual below tol", hist, max_iter, last)
    return _NewtonOut(x, False, f"max_iter = {max_iter} reached", hist, max_iter, last)
