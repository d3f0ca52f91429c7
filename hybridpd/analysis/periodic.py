"""Periodic orbits, Floquet multipliers and basins of the impact map of any hybrid automaton.

Built on :class:`~hybridpd.analysis.hybridmap.SectionMap` (the map ``P`` on a guard's section,
with ``DP`` from exact flows and saltation matrices):

* :func:`find_orbit` solves ``P^k(s) = s`` by damped Newton (``DP^k - I`` from the saltation
  chain, or central finite differences), for any impact sequence: whatever the automaton does
  between two firings of the section's guard (other contacts, sticking, sampling instants,
  mode switches) is part of ``P``. The phase residual is wrapped to ``[-T/2, T/2)``.
* :class:`PeriodicOrbit` holds the fixed point, the impact sequence, the Floquet multipliers
  (eigenvalues of ``DP^k``), the spectral radius and the stability verdict;
  :func:`measured_contraction` estimates the spectral radius independently, from iterated
  small perturbations of the simulated map.
* :class:`SectionMapper` labels section points by iterating ``P`` in one compiled loop (an
  "initial condition -> label" mapper with the labels of :mod:`hybridpd.analysis.labels`);
  :func:`hybridpd.sweeps.section_basins.section_basin` applies it over a 2-D slice.

Stability: stable iff every multiplier has modulus < 1; hyperbolic iff none is within
``1e-9`` of the unit circle (the convention of :mod:`hybridpd.analysis.impactmap`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hybridpd._deprecated import moved_names
from hybridpd._jit import njit
from hybridpd._repr import compact_repr
from hybridpd.analysis.certify import BasinMapper, certify_ball
from hybridpd.analysis.floquet import stability
from hybridpd.analysis.hybridmap import (
    ST_RETURNED,
    SectionMap,
    _to_return,
)
from hybridpd.analysis.labels import OFF_SECTION

__all__ = [
    "PeriodicOrbit",
    "SectionMapper",
    "find_orbit",
    "measured_contraction",
    "orbit_from_model",
]


@dataclass(frozen=True, eq=False)
class PeriodicOrbit:
    """A fixed point of ``P^k`` found by :func:`find_orbit`.

    Attributes
    ----------
    s : ndarray, shape (dim,)
        Section point (pre-jump, coordinates of :class:`~hybridpd.analysis.hybridmap.Section`).
    period : int
        ``k``: number of returns to the section per period.
    converged : bool
        The wrapped residual ``|P^k(s) - s|_inf`` is below ``tol`` (relative to ``max(1, |s|)``).
    reason : str
        Why Newton stopped (``"converged"``, ``"max_iter"``, ``"map undefined: <status>"``,
        ``"singular"``, ``"line search failed"``).
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
    __repr__ = compact_repr

    def to_dict(self) -> dict:
        """JSON-ready summary (fields of ``hybridpd orbit --json`` where they apply)."""
        f = lambda x: None if x is None or not np.isfinite(x) else float(x)
        return {
            "exists": bool(self.converged), "reason": self.reason, "period": self.period,
            "fixed_point": [float(v) for v in self.s], "coordinates": list(self.names),
            "state": [float(v) for v in self.z], "t_period": f(self.t_period),
            "iterations": self.iterations, "residual": f(self.residual),
            "impact_sequence": [[g, k] for g, k in self.signature],
            "multipliers": [[float(z.real), float(z.imag)] for z in self.multipliers],
            "spectral_radius": f(self.spectral_radius), "stable": bool(self.stable),
            "hyperbolic": bool(self.hyperbolic), "grazing": bool(self.grazing),
        }


def _scale(s):
    return max(1.0, float(np.max(np.abs(s))))


def _resid(P: SectionMap, s, k, jac):
    r = P.apply(s, k, jacobian=jac == "exact")
    if not r.ok:
        return None, None, r
    F = P.section.wrap(r.s - s)
    J = None
    if jac == "exact":
        J = r.DP - np.eye(P.dim)
    elif jac == "fd":
        J = P.jacobian_fd(s, k) - np.eye(P.dim)
    return F, J, r


def find_orbit(P: SectionMap, s0, period: int = 1, *, tol: float = 1e-11, max_iter: int = 50,
               jacobian: str = "exact") -> PeriodicOrbit:
    """Solve ``P^k(s) = s`` by damped Newton from the guess ``s0``.

    Parameters
    ----------
    P : SectionMap
    s0 : array_like, shape (dim,)
        Guess (a section point where the flow fires the guard).
    period : int
        ``k >= 1``.
    tol : float
        Bound on the wrapped residual, relative to ``max(1, |s|_inf)``.
    max_iter : int
        Bound on Newton iterations.
    jacobian : {"exact", "fd"}
        ``DP`` from the saltation chain, or central finite differences of the simulated map.

    Returns
    -------
    PeriodicOrbit
        Always returned; ``converged`` and ``reason`` say whether and why.

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.analysis.orbits import symmetric_orbit
    >>> from hybridpd.analysis.sections import impact_pair_section
    >>> orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    >>> P = SectionMap(impact_pair_section(orb.system()))
    >>> po = find_orbit(P, orb.fixed_point + [0.01, 0.01, -0.02, 0.05])
    >>> po.converged, bool(np.allclose(po.s, orb.fixed_point, atol=1e-9)), po.stable
    (True, True, True)
    """
    if not isinstance(P, SectionMap):
        raise ValueError(f"P must be a SectionMap, got {type(P).__name__}")
    if jacobian not in ("exact", "fd"):
        raise ValueError(f"jacobian must be 'exact' or 'fd', got {jacobian!r}")
    if isinstance(period, bool) or int(period) != period or period < 1:
        raise ValueError(f"period must be an int >= 1, got {period!r}")
    if not (tol > 0):
        raise ValueError(f"tol must be > 0, got {tol!r}")
    k = int(period)
    s = P.section.check_point(s0).copy()
    reason = "max_iter"
    it = 0
    F, J, r = _resid(P, s, k, jacobian)
    for it in range(1, int(max_iter) + 1):
        if F is None:
            reason = f"map undefined: {r.status}"
            break
        nF = np.max(np.abs(F))
        if nF <= tol * _scale(s):
            reason = "converged"
            break
        try:
            ds = -np.linalg.solve(J, F)
        except np.linalg.LinAlgError:
            reason = "singular"
            break
        lam = 1.0
        for _ in range(30):
            s_new = s + lam * ds
            F_new, J_new, r_new = _resid(P, s_new, k, jacobian)
            if F_new is not None and np.max(np.abs(F_new)) < (1 - 1e-4 * lam) * nF:
                break
            lam *= 0.5
        else:
            reason = "line search failed"
            break
        s, F, J, r = s_new, F_new, J_new, r_new
        if P.section.has_phase:
            s[0] %= P.section.period
    return _make_orbit(P, s, k, reason, it, F, r)


def _make_orbit(P, s, k, reason, it, F, r) -> PeriodicOrbit:
    ok = reason == "converged"
    res = float(np.max(np.abs(F))) if F is not None else math.nan
    dim = P.dim
    if r is not None and r.ok:
        rr = P.apply(s, k, jacobian=True)
        DP = rr.DP
        if np.all(np.isfinite(DP)):
            st = stability(DP)
            mult, rho, stab, hyp = st.multipliers, st.spectral_radius, st.stable, st.hyperbolic
        else:
            mult, rho, stab, hyp = np.full(dim, np.nan + 0j), math.nan, False, False
        return PeriodicOrbit(s, k, ok, reason, it, res, rr.t_hit - rr.t_start, rr.signature,
                             DP, mult, rho, bool(stab and ok), bool(hyp), rr.grazing,
                             P.section.to_state(s)[0], P.section.names)
    return PeriodicOrbit(s, k, False, reason, it, res, math.nan, (), np.full((dim, dim), np.nan),
                         np.full(dim, np.nan + 0j), math.nan, False, False, False,
                         P.section.to_state(s)[0], P.section.names)


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
_CONVERGED, _NOT_CONVERGED, _DIVERGED, _ZENO_STICKING, _UNRESOLVED = 0, 1, 2, 3, 4


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
        d[0] = (d[0] + 0.5 * T) - math.floor((d[0] + 0.5 * T) / T) * T - 0.5 * T
    q = 0.0
    e = 0.0
    for i in range(dim):
        e += d[i] * d[i]
        for j in range(dim):
            q += d[i] * Q[i, j] * d[j]
    return q, e


@njit(cache=True)
def _label_kernel(h, Phi, Ah, dinv, trunc, G, gabs, gsum, cnorm, prio, ng, Rh, target, zt, Rz,
                  dt_min, zf, zi, gc, gdir, W0, T0, gm, gi, k, t_max, J_max, max_steps, C, T,
                  FP, n_iter, criterion, QS, R2, escape, S_out, w, fc, ic, jt, jj, jg, jsrc,
                  jdst, jkind, jpre, jpost, st0, st1, smode, sj, sw, zt_out):
    N = W0.shape[0]
    N1 = W0.shape[1]
    lab = np.empty(N, np.int64)
    its = np.zeros(N, np.int64)
    w0 = np.empty(N1)
    s = np.empty(S_out.shape[1])
    Jh = k + 1
    for p in range(N):
        for i in range(N1):
            w0[i] = W0[p, i]
        t0 = T0[p]
        label = -1
        e2 = np.inf
        for it in range(n_iter):
            st, nb, _J = _to_return(h, Phi, Ah, dinv, trunc, G, gabs, gsum, cnorm, prio, ng,
                                    Rh, target, zt, Rz, dt_min, zf, zi, gc, gdir, w0, t0, gm,
                                    gi, k, t_max, Jh, J_max, max_steps, w, fc, ic, jt, jj, jg,
                                    jsrc, jdst, jkind, jpre, jpost, st0, st1, smode, sj, sw,
                                    zt_out)
            its[p] = it + 1
            if st != ST_RETURNED:
                if st == 6:
                    label = _ZENO_STICKING if ic[0] != gm else _DIVERGED
                elif st == 2:
                    label = _ZENO_STICKING
                elif st == 3:
                    label = _DIVERGED
                else:
                    label = _UNRESOLVED
                break
            Jh = max(nb, 1)
            _coords(w, fc[0], C, T, s)
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
            t0 = fc[0]
        if label < 0:
            label = _CONVERGED if e2 < criterion else _NOT_CONVERGED
        lab[p] = label
    return lab, its


class SectionMapper(BasinMapper):
    """Map a section point to a label by iterating ``P^k`` (an "initial condition -> label" mapper).

    Labels are those of :data:`hybridpd.analysis.labels.LABELS`: ``converged`` when, after
    ``n_iter`` iterations, the squared distance in section coordinates (phase wrapped) to the
    cycle is below ``criterion`` (for ``period = k > 1`` the cycle's ``k`` section points
    ``P^j(fixed_point)`` are all fixed points of ``P^k``; the nearest counts); ``diverged`` (non-finite, beyond ``escape``, or no
    further return in the section's mode within ``t_max``); ``zeno_sticking`` (accumulation
    without sticking mode, or still in another mode, e.g. stuck, at ``t_max``);
    ``unresolved`` (jump or step bound); ``off_section`` (the flow does not fire the guard at
    the point).

    **Early exit** as in :mod:`hybridpd.sweeps.basins`: an iterate inside the certified
    contraction ball of a cycle point (:func:`hybridpd.analysis.certify.certify_ball`, one
    ball per cycle point; numerical, sampled) is labelled ``converged`` at once.

    Parameters
    ----------
    P : SectionMap
    fixed_point : array_like, shape (dim,)
    period : int
        ``k``: the mapper iterates ``P^k``.
    n_iter : int
    criterion : float
    early_exit : bool
    escape : float
        Bound on ``|s_i|``.

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.analysis.orbits import symmetric_orbit
    >>> from hybridpd.analysis.sections import impact_pair_section
    >>> orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    >>> m = SectionMapper(SectionMap(impact_pair_section(orb.system())), orb.fixed_point)
    >>> m.label_name(m(orb.fixed_point + [0, 0.01, 0, 0]))
    'converged'
    """

    def __init__(self, P: SectionMap, fixed_point, *, period: int = 1, n_iter: int = 1500,
                 criterion: float = 1e-3, early_exit: bool = True, escape: float = 1e3):
        if not isinstance(P, SectionMap):
            raise ValueError(f"P must be a SectionMap, got {type(P).__name__}")
        self.map = P
        self.fixed_point = P.section.check_point(fixed_point).copy()
        if isinstance(period, bool) or int(period) != period or period < 1:
            raise ValueError(f"period must be an int >= 1, got {period!r}")
        self.period = int(period)
        self._limits(n_iter, criterion, escape)
        # the cycle's points on the section: P^k fixes each of them (k returns per period)
        cyc = [self.fixed_point]
        for _ in range(self.period - 1):
            r = P.apply(cyc[-1])
            if not r.ok:
                break
            cyc.append(r.s)
        self.cycle = np.ascontiguousarray(cyc)
        K = len(cyc)
        self.cert_Q = np.tile(np.eye(P.dim), (K, 1, 1))
        self.cert_r2 = np.zeros(K)
        if early_exit:
            for c in range(K):
                self.cert_Q[c], self.cert_r2[c] = self._certify(self.cycle[c])

    def _run(self, S, n_iter, Qs, r2s, targets=None):
        P = self.map
        targets = self.cycle if targets is None else targets
        sec = P.section
        S = np.asarray(S, float).reshape(-1, P.dim)
        N = S.shape[0]
        n = sec.automaton.n_states
        lab = np.full(N, OFF_SECTION, np.int64)
        its = np.zeros(N, np.int64)
        out = np.full((N, P.dim), np.nan)
        W0 = np.zeros((N, n + 1))
        T0 = np.zeros(N)
        valid = np.zeros(N, bool)
        for i in range(N):
            if not np.all(np.isfinite(S[i])):
                continue
            z, t = sec.to_state(S[i])
            if sec.fires(z) > 0:
                W0[i, :n], W0[i, n], T0[i], valid[i] = z, 1.0, t, True
        if np.any(valid):
            bufs = P._buffers()
            lv, iv = _label_kernel(*P._kernel_args, np.ascontiguousarray(W0[valid]),
                                   T0[valid], sec.mode_index, sec.guard_index, self.period,
                                   P._t_max(self.period), P.max_jumps, P.max_steps,
                                   np.ascontiguousarray(sec.C), sec.period or 0.0,
                                   targets, int(n_iter), self.criterion, Qs, r2s,
                                   self.escape, sub := np.full((int(valid.sum()), P.dim), np.nan),
                                   *bufs)
            lab[valid], its[valid], out[valid] = lv, iv, sub
        return lab, its, out

    def labels(self, S) -> tuple:
        """Labels and iterations used for section points ``S`` of shape ``(N, dim)``."""
        lab, its, _ = self._run(S, self.n_iter, self.cert_Q, self.cert_r2)
        return lab, its

    def _certify(self, fp):
        try:
            DP = self.map.jacobian(fp, self.period)
        except RuntimeError:
            return np.eye(self.map.dim), 0.0

        def images(pts):
            lab, _, img = self._run(pts, 1, np.eye(self.map.dim)[None], np.zeros(1), fp[None])
            return img, (lab != OFF_SECTION) & np.all(np.isfinite(img), axis=1)

        return certify_ball(DP, fp, self.criterion, images, self.map.section.wrap)


# ----------------------------------------------------------------------------------------
# mechanical model files
# ----------------------------------------------------------------------------------------
def orbit_from_model(model, contact: int = 0, wall: int | None = None, period: int = 1, *,
                     guess=None, transient: float | None = None, tol: float = 1e-11,
                     event: str = "impact", map_options: dict | None = None) -> tuple:
    """A periodic orbit of a mechanical model on the section of one of its contacts.

    Parameters
    ----------
    model : MechanicalModel
        A loaded model file (:func:`hybridpd.mechanics.modelfile.load_model`).
    contact : int
        0-based contact index (file order).
    wall : {+1, -1}, optional
        Bound of the contact (default ``hi`` if the contact has one, else ``lo``).
    period : int
        Number of returns to the section per period (``k`` of ``P^k``).
    guess : array_like, optional
        Section point (coordinates of :func:`~hybridpd.analysis.sections.mechanical_section`).
        Default: simulate from the file's initial state for ``transient`` and take the last
        pre-impact state on the section.
    transient : float, optional
        Time of that simulation (default 50 reference periods, or 200 time units).
    tol : float
        Newton tolerance.
    event : {"impact", "release"}
        Section on the impacts, or on the ends of sticking phases (one crossing per phase
        however many impacts precede the sticking).
    map_options : dict, optional
        Keyword arguments of :class:`~hybridpd.analysis.hybridmap.SectionMap`.

    Returns
    -------
    (PeriodicOrbit, SectionMap)
    """
    from hybridpd.analysis.sections import mechanical_section

    ma = model.automaton
    if isinstance(contact, bool) or int(contact) != contact or \
            not 0 <= int(contact) < len(ma.contacts):
        raise ValueError(f"contact must be an index in [0, {len(ma.contacts)}), got {contact!r}")
    c = ma.contacts[int(contact)]
    walls = [w for w, _ in c.bounds]
    if wall is None:
        wall = 1 if 1 in walls else -1
    if wall not in walls:
        raise ValueError(f"wall must be one of {walls} for contact {contact} (its bounds), "
                         f"got {wall!r}")
    sec = mechanical_section(ma, int(contact), wall, event=event)
    P = SectionMap(sec, **dict(map_options or {}))
    if guess is None:
        guess = _guess_from_simulation(model, sec, transient)
    s0 = np.asarray(guess, float)
    if s0.shape != (sec.dim,):
        raise ValueError(f"guess must have {sec.dim} numbers {sec.names}, got {s0.size}")
    return find_orbit(P, s0, period, tol=tol), P


def _guess_from_simulation(model, sec, transient):
    from hybridpd.mechanics.simulate import simulate

    if transient is None:
        transient = 50.0 * sec.period if sec.has_phase else 200.0
    if not (float(transient) > 0 and math.isfinite(float(transient))):
        raise ValueError(f"transient must be finite and > 0, got {transient!r}")
    tr = simulate(model.automaton, model.x0, (model.t0, model.t0 + float(transient)))
    J = tr.hybrid.jumps
    # the first firing of a burst (after a jump of another guard): the start of a pattern
    hits = [i for i in range(len(J)) if J.source[i] == sec.mode and J.guard[i] == sec.guard
            and J.kind[i] == "crossing" and (i == 0 or J.guard[i - 1] != sec.guard)]
    if not hits:
        raise ValueError(f"guess: no impact on the section ({sec.guard} in mode {sec.mode}) "
                         f"within the transient of {float(transient):g}; give --guess")
    i = hits[-1]
    return sec.from_state(J.pre[i], J.t[i])


__getattr__ = moved_names(__name__, {"section_basin": "hybridpd.sweeps.section_basins"})
