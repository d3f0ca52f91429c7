"""Periodic orbits, Floquet multipliers and basins of the impact map of any hybrid automaton.

Built on :class:`~hybridpd.analysis.hybridmap.SectionMap` (the map ``P`` on a guard's section,
with ``DP`` from exact flows and saltation matrices):

* :func:`find_orbit` solves ``P^k(s) = s`` by the package's damped Newton
  (:func:`~hybridpd.analysis.pathfollow.newton`) with Broyden updates (``DP^k - I`` from the
  saltation chain, or central finite differences, only at the start and where an updated step
  fails: on an orbit with many jumps one costs tens of map applications), for any impact
  sequence: whatever the automaton does between two firings of the section's guard (other
  contacts, sticking, sampling instants, mode switches) is part of ``P``. The phase residual
  is wrapped to ``[-T/2, T/2)``.
* :class:`PeriodicOrbit` holds the fixed point, the impact sequence, the Floquet multipliers
  (eigenvalues of ``DP^k``), the spectral radius and the stability verdict;
  :func:`measured_contraction` estimates the spectral radius independently, from iterated
  small perturbations of the simulated map.
* :func:`_label_kernel` labels section points by iterating ``P`` in one compiled loop under
  a :class:`LabelSpec` (the kernel of a section map's basin mapper,
  :class:`hybridpd.analysis.mappers.MapMapper`).

Stability: stable iff every multiplier has modulus < 1; hyperbolic iff none is within
``1e-9`` of the unit circle (the convention of :mod:`hybridpd.pair.impactmap`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from hybridpd._jit import njit
from hybridpd._phase import wrap_phase_kernel
from hybridpd._results import compact_repr
from hybridpd.analysis.floquet import stability
from hybridpd.analysis.hybridmap import (
    ST_NEED_MODE,
    ST_RETURNED,
    SectionMap,
    _to_return,
)
from hybridpd.analysis.maps import MapResult, PoincareMap, check_returns
from hybridpd.analysis.pathfollow import newton
from hybridpd.hybrid._kernel import FC_T, IC_MODE

__all__ = [
    "ORBIT_REFUSALS",
    "LabelSpec",
    "PeriodicOrbit",
    "find_orbit",
    "measured_contraction",
]


@dataclass(frozen=True, eq=False)
class PeriodicOrbit:
    """A fixed point of ``P^k`` found by :func:`find_orbit`.

    Attributes
    ----------
    s : ndarray, shape (dim,)
        Section point (pre-jump, coordinates of :class:`~hybridpd.hybrid.section.Section`).
    period : int
        ``k``: number of returns to the section per period.
    converged : bool
        The wrapped residual ``|P^k(s) - s|_inf`` is below ``tol`` (relative to ``max(1, |s|)``).
    reason : str
        Why Newton stopped (``"converged"``, ``"max_iter"``, ``"map undefined: <status>"``,
        ``"singular"``, ``"line search failed"``, ``"diverged"``: an iterate or its image
        grew past :data:`DIVERGENCE_BOUND` times the scale of the start, or the map's run
        diverged or went non-finite), or why its solution is no orbit (one of
        :data:`ORBIT_REFUSALS`: ``"degenerate_return"``, ``"grazing"``, ``"not_periodic"``,
        ``"fast_return"``, ``"sampling_incommensurate"``).
    iterations : int
    residual : float
        Final ``|P^k(s) - s|_inf`` (phase wrapped).
    t_period : float
        Time from the start to the ``k``-th return (the orbit's period in time units).
    signature : tuple
        ``(guard, kind)`` of every jump over one period: the impact sequence.
    DP : ndarray, shape (dim, dim)
        ``DP^k`` at ``s``.
    multipliers : ndarray, complex
        Eigenvalues of ``DP``, by decreasing modulus.
    spectral_radius : float
    stable, hyperbolic : bool
    grazing : bool
        A tangential contact on the orbit: ``DP`` is not defined there.
    z : ndarray, shape (n,)
        Full state at the section point.
    names : tuple of str
        Names of the section coordinates.
    n_periods : int
        ``m``: the return time in reference periods, ``t_period = m T`` (1 without a
        reference phase; 0 where no orbit was accepted).
    detail : str
        Why a Newton solution was not accepted as an orbit (or a refusal's hint); empty for
        an orbit.
    return_error : float
        Relative distance between the section point and where an independent simulation of
        one period returns (NaN where not checked).
    mode : str
        The section's mode (e.g. ``"stick0+1+"``: the contacts held where the section's guard
        fires).
    quantities : dict
        The map's own quantities at the orbit
        (:meth:`~hybridpd.analysis.maps.PoincareMap.point_quantities`; empty for most maps),
        also readable as attributes: ``orb.walls`` is ``orb.quantities["walls"]``.

    Examples
    --------
    The impact pair's symmetric orbit, found again by Newton on the general map:

    >>> import hybridpd as hp
    >>> from hybridpd.pair.section import impact_pair_section
    >>> orb = hp.symmetric_orbit(hp.ImpactPair(0.1, 0.5, 0.75), hp.PDGains(10, 20), 5.0)
    >>> po = hp.find_orbit(hp.SectionMap(impact_pair_section(orb.system())), orb.fixed_point)
    >>> po.reason, po.period, round(po.spectral_radius, 6), bool(po.stable)
    ('converged', 1, 0.523818, True)
    >>> po.signature
    (('wall+', 'crossing'), ('wall-', 'crossing'))
    """

    s: np.ndarray
    period: int
    converged: bool
    reason: str
    iterations: int
    residual: float
    t_period: float
    signature: tuple
    DP: np.ndarray = field(repr=False)
    multipliers: np.ndarray
    spectral_radius: float
    stable: bool
    hyperbolic: bool
    grazing: bool
    z: np.ndarray = field(repr=False)
    names: tuple = ()
    n_periods: int = 0
    detail: str = ""
    return_error: float = math.nan
    mode: str = ""
    quantities: dict = field(default_factory=dict, repr=False)
    __repr__ = compact_repr

    def __getattr__(self, name):
        # only reached for names that are no field: the map's quantities
        if name.startswith("__") or name == "quantities":
            raise AttributeError(name)
        try:
            return self.quantities[name]
        except KeyError:
            raise AttributeError(f"{type(self).__name__!r} has no attribute {name!r} (the "
                                 f"map's quantities: {sorted(self.quantities)})") from None

    def to_dict(self) -> dict:
        """JSON-ready summary (fields of ``hybridpd orbit --json`` where they apply). Where no
        orbit was accepted (``exists`` false) there are no multipliers to judge:
        ``multipliers``, ``spectral_radius``, ``stable`` and ``hyperbolic`` are None."""
        f = lambda x: None if x is None or not np.isfinite(x) else float(x)
        ok = bool(self.converged)
        return {
            "exists": bool(self.converged), "reason": self.reason, "period": self.period,
            "fixed_point": [f(v) for v in self.s], "coordinates": list(self.names),
            "state": [f(v) for v in self.z], "t_period": f(self.t_period),
            "iterations": self.iterations, "residual": f(self.residual),
            "impact_sequence": [[g, k] for g, k in self.signature],
            "multipliers": [[f(z.real), f(z.imag)] for z in self.multipliers] if ok else None,
            "spectral_radius": f(self.spectral_radius) if ok else None,
            "stable": bool(self.stable) if ok else None,
            "hyperbolic": bool(self.hyperbolic) if ok else None, "grazing": bool(self.grazing),
            "n_periods": int(self.n_periods), "detail": self.detail,
            "return_error": f(self.return_error), "mode": self.mode,
        }


def _scale(s):
    return max(1.0, float(np.max(np.abs(s))))


#: Newton's iterates and their images diverge beyond this many times the scale
#: ``max(1, |s0|_inf)`` of the start (or where they are not finite): reason ``"diverged"``.
DIVERGENCE_BOUND = 1e6


#: Reasons for which :func:`find_orbit` reports no orbit although Newton's residual vanished.
ORBIT_REFUSALS = ("degenerate_return", "grazing", "not_periodic", "fast_return",
                  "sampling_incommensurate")


def find_orbit(P: PoincareMap, s0, period: int = 1, *, tol: float = 1e-11, max_iter: int = 50,
               jacobian: str = "exact", verify: bool = True, min_lambda: float = 2.0 ** -29,
               **checks) -> PeriodicOrbit:
    """Solve ``P^k(s) = s`` by damped Newton from the guess ``s0``, on any map.

    ``P`` is any :class:`~hybridpd.analysis.maps.PoincareMap`: the general section map of a
    hybrid automaton, a specialisation, or a map written by the user. Newton runs on the
    residual ``P^k(s) - s`` (phase wrapped to ``[-T/2, T/2)`` when the map has a phase) with
    Broyden updates of ``DP^k - I`` (recomputed only where an updated step fails); ``DP``
    is the map's own (``MapResult.DP``) where it gives one, else central finite differences
    (:meth:`~hybridpd.analysis.maps.PoincareMap.jacobian_fd`). The multipliers are the
    eigenvalues of ``DP^k`` at the solution (minus the map's
    :attr:`~hybridpd.analysis.maps.PoincareMap.structural_zeros`).

    A map that knows more about its orbits is asked through its hooks: ``P.refuse`` before
    Newton (e.g. a sampled-data loop whose sampling never returns with the phase),
    ``P.accept`` for every trial point, ``P.validate`` for a vanishing residual. The section
    map of a hybrid automaton (:class:`~hybridpd.analysis.hybridmap.SectionMap`) refuses or
    rejects, with the reasons of :data:`ORBIT_REFUSALS`: a return after zero time
    (``degenerate_return``), a tangential contact (``grazing``), a return within one burst of
    impacts (``fast_return``, shorter than ``min_return``), a return time that is no whole
    number of reference periods (``periods`` if given) or from which an independent
    simulation of one period does not return (``not_periodic``; ``verify``), and sampling
    clocks without a common period with the reference (``sampling_incommensurate``).

    Parameters
    ----------
    P : PoincareMap
    s0 : array_like, shape (dim,)
        Guess.
    period : int
        ``k >= 1``: the number of returns to the section per period of the orbit.
    tol : float
        Bound on the wrapped residual, relative to ``max(1, T)`` for the phase and to
        ``max(1, |s|_inf)`` for the other coordinates.
    max_iter : int
        Bound on Newton iterations.
    jacobian : {"exact", "fd"}
        ``"exact"``: the map's ``DP`` where it gives one (finite differences otherwise);
        ``"fd"``: always central finite differences of the map.
    verify : bool
        Passed to ``P.validate`` (a section map simulates one period independently).
    min_lambda : float
        Smallest damping factor of Newton's line search, in ``(0, 1]`` (the factors are
        ``1, 1/2, ...``): a step that must be damped further fails.
    **checks
        Options of the map's hooks: for a section map ``periods`` (reference periods of the
        orbit, default any), ``min_return`` (shortest acceptable return, default ``T / 20``)
        and ``sampling_period`` (the ``dt`` of a sampled-data controller of an automaton
        whose section does not know its clocks).

    Returns
    -------
    PeriodicOrbit
        Always returned for valid arguments (non-convergence and refusals included);
        ``converged`` and ``reason`` (and ``detail``) say whether and why.

    Raises
    ------
    ValueError
        Bad arguments (not a map, a non-finite or wrongly sized ``s0``, ...).

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.pair.orbits import symmetric_orbit
    >>> from hybridpd.pair.section import impact_pair_section
    >>> orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    >>> P = SectionMap(impact_pair_section(orb.system()))
    >>> po = find_orbit(P, orb.fixed_point + [0.01, 0.01, -0.02, 0.05])
    >>> po.converged, bool(np.allclose(po.s, orb.fixed_point, atol=1e-9)), po.stable
    (True, True, True)
    >>> po.n_periods
    1
    """
    if not isinstance(P, PoincareMap):
        raise ValueError(f"P must be a PoincareMap, got {type(P).__name__}")
    if jacobian not in ("exact", "fd"):
        raise ValueError(f"jacobian must be 'exact' or 'fd', got {jacobian!r}")
    try:
        k = check_returns(period)
    except (ValueError, TypeError, OverflowError):
        raise ValueError(f"period must be an int >= 1 (returns per period), got {period!r}") \
            from None
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) \
            or not (math.isfinite(tol) and tol > 0):
        raise ValueError(f"tol must be a finite number > 0, got {tol!r}")
    if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) \
            or max_iter < 1:
        raise ValueError(f"max_iter must be an int >= 1, got {max_iter!r}")
    if isinstance(min_lambda, bool) or not isinstance(min_lambda, (int, float)) \
            or not 0 < min_lambda <= 1:
        raise ValueError(f"min_lambda must be a number in (0, 1], got {min_lambda!r}")
    periods = checks.get("periods")
    if periods is not None and (isinstance(periods, bool) or int(periods) != periods
                                or periods < 1):
        raise ValueError(f"periods must be None or an int >= 1, got {periods!r}")
    try:
        s = P.check_point(s0).copy()
    except (ValueError, TypeError) as exc:
        raise ValueError(f"s0 is no point of the map's section: {exc}") from None
    refused = P.refuse(s, k, **checks)
    if refused is not None:
        return _no_orbit(P, s, k, refused[0], 0, None, refused[1])
    eq = _OrbitEquation(P, k, jacobian, checks, DIVERGENCE_BOUND * _scale(s))
    F = eq.run(s, True)[0]
    if F is None or eq.diverged(s, True):
        return _no_orbit(P, s, k, eq.undefined() if F is None else "diverged", 1, None, eq.why)
    max_iter = int(max_iter)
    res = newton(eq.resid, eq.jac, s, tol=tol, max_iter=max_iter, norm=eq.norm, broyden=True,
                 difference=eq.difference, canonical=P.canonical,
                 min_lambda=float(min_lambda), step_test=False)
    # the counts and words of this module: an iteration is one test of the residual
    its = min(len(res.history), max_iter)
    reason = {"converged": "converged", "singular": "singular", "max_iter": "max_iter",
              "line_search": "line search failed"}.get(res.status)
    F = res.residual
    if res.status == "jacobian":    # the map failed where its Jacobian was asked for again:
        its = len(res.history) + 1  # that iteration ends, the next one reports it
        reason, F = eq.undefined() if its <= max_iter else "max_iter", None
        its = min(its, max_iter)
    elif res.converged and res.iterations == max_iter:
        reason = "max_iter"     # converged by the last step: this module's loop never saw it
    if eq.diverged(res.x, reason != "converged"):
        return _no_orbit(P, res.x, k, "diverged", its, None, eq.why)
    return _make_orbit(P, res.x, k, reason, its, F, jacobian, dict(checks, verify=verify))


class _OrbitEquation:
    """``F(s) = P^k(s) - s`` (phase wrapped), its Jacobian and norm for
    :func:`~hybridpd.analysis.pathfollow.newton`. Never raises for a finite ``s``: a run the
    map cannot complete, or a Jacobian that is not finite, is a result.

    The latest run is kept: Newton asks for the residual and the Jacobian at one point in
    turn, and one exact run gives both. A trial point the map does not ``accept`` is rejected
    like one where the map is undefined.
    """

    def __init__(self, P, k, jacobian, checks, bound=math.inf):
        self.P, self.k, self.jacobian, self.checks = P, k, jacobian, checks
        self.last = (None, None, None, None)
        self.bound, self.why = bound, ""

    def run(self, s, jac):
        """``(F, J, MapResult)``, ``J`` only with ``jac``; ``(None, None, r_or_status)``
        where undefined."""
        if self.last[0] != s.tobytes() or (jac and self.last[2] is None):
            self.last = (s.tobytes(),) + self._run(s, self.jacobian if jac else "none")
        return self.last[1:]

    def _run(self, s, jac):
        P = self.P
        if not np.all(np.isfinite(s)):
            return None, None, "nonfinite_point"
        try:
            r = P.apply(s, self.k, jacobian=jac == "exact")
            if not r.ok:
                if r.status in ("nonfinite", "diverged"):
                    return self._diverged(f"the map's run stopped: {r.status}")
                return None, None, r
            if not np.all(np.isfinite(r.s)):
                return self._diverged("the image is not finite")
            F = P.wrap(r.s - s)
            J = None
            if jac == "exact" and r.DP is not None:
                J = r.DP - np.eye(P.dim)
            if jac == "fd" or (jac == "exact" and (J is None or not np.all(np.isfinite(J)))):
                # no DP from the map, or no saltation matrix somewhere on the way (a
                # tangential jump): the map's differences still give Newton a direction
                J = P.jacobian_fd(s, self.k) - np.eye(P.dim)
        except (ValueError, RuntimeError, FloatingPointError, np.linalg.LinAlgError) as exc:
            return None, None, f"{type(exc).__name__}: {exc}"
        if not np.all(np.isfinite(F)) or (J is not None and not np.all(np.isfinite(J))):
            return None, None, "nonfinite_jacobian" if np.all(np.isfinite(F)) else "nonfinite"
        return F, J, r

    def resid(self, s):
        F, _, r = self.run(s, False)
        return None if F is None or not self.P.accept(r, **self.checks) else F

    def jac(self, s):
        J = self.run(s, True)[1]
        if J is None:
            raise RuntimeError(self.undefined())
        return J

    def norm(self, s, F):
        """``|F|`` relative to the solver's scales: the phase against ``max(1, T)``, the
        other coordinates against ``max(1, |s|_inf)`` of those coordinates."""
        T = self.P.period
        if T is not None:
            rest = _scale(s[1:]) if s.size > 1 else 1.0
            tail = float(np.max(np.abs(F[1:]))) / rest if F.size > 1 else 0.0
            return max(abs(float(F[0])) / max(1.0, T), tail)
        return float(np.max(np.abs(F))) / _scale(s)

    def difference(self, a, b):
        return self.P.wrap(a - b)

    def _diverged(self, what, past_bound=False):
        self.why = what + (f", past {DIVERGENCE_BOUND:g} times the scale of the start "
                           f"({self.bound:.3g})" if past_bound else "")
        return None, None, "diverged"

    def diverged(self, s, image=True) -> bool:
        """Whether the iterate `s` is not finite or grew past the bound
        (:data:`DIVERGENCE_BOUND` times the scale of the start), or (with `image`) its image
        did, or the map's run from it diverged."""
        if not np.all(np.isfinite(s)):
            self.why = "the iterate is not finite"
            return True
        if float(np.max(np.abs(s))) > self.bound:
            self._diverged(f"the iterate reached |s| = {np.max(np.abs(s)):.3g}", True)
            return True
        if not image:
            return False
        r = self.run(s, False)[2]
        if isinstance(r, MapResult) and float(np.max(np.abs(r.s))) > self.bound:
            self._diverged(f"its image reached |P(s)| = {np.max(np.abs(r.s)):.3g}", True)
            return True
        return isinstance(r, str) and r == "diverged"

    def undefined(self) -> str:
        r = self.last[3]
        if isinstance(r, str) and r == "diverged":
            return "diverged"
        return f"map undefined: {r.status if isinstance(r, MapResult) else r}"


def _no_orbit(P, s, k, reason, it, F, detail="") -> PeriodicOrbit:
    dim = P.dim
    res = float(np.max(np.abs(F))) if F is not None else math.nan
    return PeriodicOrbit(s, k, False, reason, it, res, math.nan, (), np.full((dim, dim), np.nan),
                         np.full(dim, np.nan + 0j), math.nan, False, False, False,
                         P.state(s), P.names, detail=detail, mode=P.mode)


def _make_orbit(P, s, k, reason, it, F, jacobian, checks) -> PeriodicOrbit:
    ok = reason == "converged"
    if F is None:
        return _no_orbit(P, s, k, reason, it, F)
    res = float(np.max(np.abs(F)))
    dim = P.dim
    try:
        rr = P.apply(s, k, jacobian=jacobian == "exact")
        DP = rr.DP if rr.DP is not None or not rr.ok else P.jacobian_fd(s, k)
    except (ValueError, RuntimeError, FloatingPointError, np.linalg.LinAlgError) as exc:
        return _no_orbit(P, s, k, "map undefined", it, F, f"{type(exc).__name__}: {exc}")
    if not rr.ok:
        return _no_orbit(P, s, k, f"map undefined: {rr.status}", it, F)
    if np.all(np.isfinite(DP)):
        zeros = P.structural_zeros if rr.structural_zeros is None or rr.DP is None \
            else rr.structural_zeros
        st = stability(DP, structural_zeros=min(zeros, dim - 1))
        mult, rho, stab, hyp = st.multipliers, st.spectral_radius, st.stable, st.hyperbolic
    else:
        mult, rho, stab, hyp = np.full(dim, np.nan + 0j), math.nan, False, False
    t_per = rr.t_hit - rr.t_start
    m, detail, err = 0, "", math.nan
    if ok:
        reason, m, detail, err = P.validate(s, k, rr, **checks)
        ok = reason == "converged"
    q = P.point_quantities(s, k, rr, **checks)
    return PeriodicOrbit(s, k, ok, reason, it, res, t_per, rr.signature, DP, mult, rho,
                         bool(stab and ok), bool(hyp), bool(rr.grazing or q.get("grazing")),
                         P.state(s), P.names, n_periods=m, detail=detail, return_error=err,
                         mode=P.mode, quantities=q)


def measured_contraction(P: SectionMap, s, period: int = 1, *, n_iter: int = 40,
                         eps: float = 1e-7, n_dirs: int = 4, seed: int = 0) -> float:
    """Spectral radius estimated from iterated perturbations of the simulated map.

    ``n_dirs`` random perturbations of size ``eps`` are iterated ``n_iter`` times by ``P^k``
    (renormalised to ``eps`` after each step, power-iteration style on the nonlinear map);
    the estimate is the geometric mean growth of the last half of the steps, maximised over
    the directions. It converges to the spectral radius of ``DP^k`` when the dominant
    multiplier is simple (or a complex pair).
    """
    rng = np.random.default_rng(seed)
    s = P.section.check_point(s)
    k = int(period)
    best = 0.0
    for _ in range(int(n_dirs)):
        d = rng.normal(size=P.dim)
        d *= eps / np.linalg.norm(d)
        logs = []
        for _ in range(int(n_iter)):
            img = P(s + d, k)
            d = P.section.wrap(img - s)
            g = np.linalg.norm(d) / eps
            logs.append(math.log(g))
            d *= eps / np.linalg.norm(d)
        best = max(best, math.exp(np.mean(logs[len(logs) // 2:])))
    return best


# ----------------------------------------------------------------------------------------
# basins: a compiled mapper
# ----------------------------------------------------------------------------------------
class LabelSpec(NamedTuple):
    """What a basin's labelling needs besides the map, by name (one pack for the section
    kernel and the impact pair's).

    Attributes
    ----------
    C : ndarray, shape (m, dim)
        Criterion coordinates of a deviation (the phase apart, when ``T > 0``).
    T : float
        The phase's period (0: no phase).
    FP : ndarray, shape (K, dim)
        The cycle's points (each a fixed point of ``P^k``).
    period : int
        ``k``: applications of ``P`` per iteration.
    n_iter : int
        Iterations per point.
    criterion : float
        Squared distance below which a point has converged.
    QS, R2 : ndarray, shapes (K, dim, dim) and (K,)
        The early-exit balls ``d^T Q d < r2`` (``r2 = 0``: none).
    escape : float
        Bound on the coordinates.
    cycle_tol : float
        Relative tolerance of the cycle early exit where a labeller has one (0: off).
    """

    C: np.ndarray
    T: float
    FP: np.ndarray
    period: int
    n_iter: int
    criterion: float
    QS: np.ndarray
    R2: np.ndarray
    escape: float
    cycle_tol: float


class LabelPoints(NamedTuple):
    """The points the compiled labeller works through, by name: their current iterates
    (pre-jump states ``W0 (N, N1)`` at times ``T0 (N,)``, updated where a run is handed
    back) and its outputs, the last section points ``S_out (N, dim)``, the labels ``lab (N,)``
    and the iterations done ``its (N,)`` (int64; read as the iteration to resume from)."""

    W0: np.ndarray
    T0: np.ndarray
    S_out: np.ndarray
    lab: np.ndarray
    its: np.ndarray


_CONVERGED, _NOT_CONVERGED, _DIVERGED, _ZENO_STICKING, _UNRESOLVED = 0, 1, 2, 3, 4
_TO_RESOLVER = 1 << 60      # the labeller's code of a run handed to the resolver


def _n_finite(rows) -> int:
    """Number of leading finite rows (``iterate`` fills the rows after a failure with NaN)."""
    bad = ~np.all(np.isfinite(rows), axis=1)
    return int(np.argmax(bad)) if bad.any() else len(rows)


@njit(cache=True)
def _coords(w, t, C, T, out):
    m = C.shape[0]
    off = 0
    if T > 0.0:
        out[0] = t - math.floor(t / T) * T
        off = 1
    for i in range(m):
        acc = 0.0
        for j in range(C.shape[1]):
            acc += C[i, j] * w[j]
        out[off + i] = acc


@njit(cache=True)
def _dist(s, fp, T, Q):
    """``(d^T Q d, |d|^2)`` of the wrapped difference ``d = s - fp``."""
    dim = s.shape[0]
    d = np.empty(dim)
    for i in range(dim):
        d[i] = s[i] - fp[i]
    if T > 0.0:
        d[0] = wrap_phase_kernel(d[0], T)
    q = 0.0
    e = 0.0
    for i in range(dim):
        e += d[i] * d[i]
        for j in range(dim):
            q += d[i] * Q[i, j] * d[j]
    return q, e


@njit(cache=True)
def _label_kernel(run, spec, pts, p0, resolve, rb):
    """Label the points ``p0, p0 + 1, ...`` of ``pts`` (a :class:`LabelPoints`).

    ``run``: what the runs to ``P^k`` read (a :class:`~hybridpd.analysis.hybridmap.ReturnRun`
    of the map, ``k = spec.period``); ``spec``: the labelling's options
    (:class:`LabelSpec`); ``rb``: the run's buffers (:mod:`hybridpd.hybrid._kernel`).

    Returns ``(p, code)``: ``p = N`` when every point is labelled; otherwise the run of
    point ``p`` handed back: ``ST_NEED_MODE`` (a mode not built yet, code ``code``, or a Zeno
    reset not packed), or, with ``resolve``, an application that stopped at contacts
    refiring at one instant (code ``_TO_RESOLVER``: the map's own ``apply`` takes it to the
    section's resolver). Its current iterate is left in ``W0[p]``, ``T0[p]`` and its
    iterations so far in ``its[p]``, so that a call from ``p`` resumes it there.
    """
    w, fc, ic = rb.w, rb.fc, rb.ic
    W0, T0, S_out, lab, its = pts.W0, pts.T0, pts.S_out, pts.lab, pts.its
    gm = run.mode
    k, C, T, FP, QS, R2 = spec.period, spec.C, spec.T, spec.FP, spec.QS, spec.R2
    n_iter, criterion, escape = spec.n_iter, spec.criterion, spec.escape
    N = W0.shape[0]
    N1 = W0.shape[1]
    w0 = np.empty(N1)
    s = np.empty(S_out.shape[1])
    Jh = k + 1
    for p in range(p0, N):
        for i in range(N1):
            w0[i] = W0[p, i]
        t0 = T0[p]
        label = -1
        e2 = np.inf
        for it in range(its[p], n_iter):
            st, nb, _J = _to_return(run, w0, t0, k, Jh, rb)
            if st == ST_NEED_MODE:
                for i in range(N1):
                    W0[p, i] = w0[i]
                T0[p] = t0
                its[p] = it
                return p, ic[IC_MODE]
            if st == 2 and resolve:
                for i in range(N1):
                    W0[p, i] = w0[i]
                T0[p] = t0
                its[p] = it
                return p, _TO_RESOLVER
            its[p] = it + 1
            if st != ST_RETURNED:
                if st == 6:
                    label = _ZENO_STICKING if ic[IC_MODE] != gm else _DIVERGED
                elif st == 2:
                    label = _ZENO_STICKING
                elif st == 3:
                    label = _DIVERGED
                else:
                    label = _UNRESOLVED
                break
            Jh = max(nb, 1)
            _coords(w, fc[FC_T], C, T, s)
            for i in range(s.shape[0]):
                S_out[p, i] = s[i]
            e2 = np.inf
            hit = False
            for c in range(FP.shape[0]):
                q, ec = _dist(s, FP[c], T, QS[c])
                e2 = min(e2, ec)
                if q < R2[c]:
                    hit = True
            big = False
            for i in range(s.shape[0]):
                if not (abs(s[i]) <= escape):
                    big = True
            if big:
                label = _DIVERGED
                break
            if hit:
                label = _CONVERGED
                break
            for i in range(N1):
                w0[i] = w[i]
            t0 = fc[FC_T]
        if label < 0:
            label = _CONVERGED if e2 < criterion else _NOT_CONVERGED
        lab[p] = label
    return N, 0
