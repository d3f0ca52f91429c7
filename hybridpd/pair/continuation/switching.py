"""Branch switching: start the family born at a bifurcation point of a continued branch.

Three kinds of switch, chosen from the :class:`~hybridpd.analysis.continuation.BifurcationEvent`:

``period_doubling``
    A real multiplier of ``DP^k`` at -1 with eigenvector ``v``. The period-``2k`` orbit born
    there lies, to first order, along ``v`` at a parameter ``p_c + O(a^2)``, ``a`` its
    amplitude. It is found by Newton's method on the augmented system

    .. math:: P^{2k}(s) - s = 0, \\qquad v \\cdot (s - s_c) = \\pm a

    in the unknowns ``(s, p)`` from ``(s_c \\pm a v, p_c)``: the parameter is an unknown, so
    the side of the bifurcation on which the new orbits exist (super- or subcritical) is
    found, not assumed. The parent orbit (also a fixed point of ``P^{2k}``) meets the
    constraint only at ``p - p_c = O(a)``, farther from the start, and is rejected by its
    minimal period. Both signs of ``a`` are tried (they give the two points ``s`` and
    ``P^k(s)`` of the same cycle: the second is tried only when the first fails).
``fold`` at a *branch point* (a real multiplier at +1 while the branch goes on, e.g. the
    symmetry-breaking pitchfork of the symmetric family)
    The same augmented system with ``P^k`` and the +1 eigenvector; the start must lie off
    the parent branch (checked by correcting the parent at the same parameter). The two signs
    of ``a`` give the two (symmetric partner) branches.
``grazing``
    The parent branch ends where a flight touches a wall tangentially (paper (19)); no
    smooth family continues it. The map is stepped just past the grazing value, iterated
    from the grazing orbit until it settles (the motion the system actually jumps to), the
    period ``K`` of the settled motion is detected and Newton's method on ``P^K`` polishes
    it. This is a *nonsmooth* switch: the new branch does not emanate from the grazing
    point, it is the attractor reached from it.

The new orbit is then continued with :func:`~hybridpd.analysis.continuation.continue_orbit`
on the parent's parameter path (the map's family, :meth:`ImpactMap.family
<hybridpd.pair.impactmap.ImpactMap.family>`) (the design path ``x10`` fixed, ``xm`` following, for a branch
of :func:`~hybridpd.pair.continuation.symmetric.continue_symmetric` or a design-path
map continuation; fixed ``xm`` otherwise).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.analysis.continuation import BifurcationEvent, Branch, continue_orbit
from hybridpd.analysis.family import map_residual
from hybridpd.analysis.pathfollow import newton
from hybridpd.analysis.periodic import PeriodicOrbit, find_orbit
from hybridpd.model import (
    Case,
    ImpactPair,
    PDGains,
    Reference,
    check_int,
    check_positive,
    wrap_phase,
)
from hybridpd.pair.family import (
    _Design,
    _map_with,
    _scale,
)
from hybridpd.pair.impactmap import ImpactMap

__all__ = ["BranchSwitch", "branch_map", "switch_branch"]

_SWITCH_KINDS = ("period_doubling", "fold", "grazing")


@dataclass(frozen=True)
class BranchSwitch:
    """The result of a branch switch.

    Attributes
    ----------
    kind : str
        ``"period_doubling"``, ``"branch_point"`` or ``"grazing"``.
    event : BifurcationEvent
        The event switched at (on the parent branch).
    parameter_name : str
    critical_value : float
        The parameter at the event.
    eigenvector : ndarray, shape (4,), or None
        The real critical eigenvector ``v`` of ``DP^k`` at the event (unit 2-norm in
        ``(phi, z1, z2, z4)``); None for a grazing switch.
    critical_multiplier : complex
        The multiplier nearest -1 (flip) or +1 (branch point) at the event; NaN for grazing.
    starts : tuple of PeriodicOrbit
        The orbits found on the new branch (one per sign of the amplitude that converged
        to a new orbit; one for grazing), each a fixed point of ``P^period`` at the
        parameter in :attr:`start_parameters`.
    start_parameters : ndarray, shape (len(starts),)
    amplitude : float
        ``a``: the step along ``v`` (smooth switch) or the parameter offset past grazing.
    period : int
        Period (in applications of ``P``) of the new branch: ``2k`` at a flip, ``k`` at a
        branch point, the detected period after a grazing.
    branches : tuple of Branch
        The continued new branch(es), one per start (empty when ``stop`` was not given).
    design : dict or None
        ``{"x10": ..., "n": ...}`` when the parameter path is the design path (``xm``
        follows), None for fixed ``xm``.
    reason : str
        What happened (which amplitudes were tried, why a start was rejected).
    """

    kind: str
    event: BifurcationEvent
    parameter_name: str
    critical_value: float
    eigenvector: np.ndarray | None
    critical_multiplier: complex
    starts: tuple
    start_parameters: np.ndarray
    amplitude: float
    period: int
    branches: tuple
    design: dict | None
    reason: str
    __repr__ = compact_repr

    @property
    def ok(self) -> bool:
        """At least one orbit of the new branch was found."""
        return len(self.starts) > 0

    def to_dict(self) -> dict:
        """JSON-ready summary."""
        ev = self.eigenvector
        m = self.critical_multiplier
        return {
            "kind": self.kind, "event": self.event.to_dict(),
            "parameter_name": self.parameter_name,
            "critical_value": float(self.critical_value),
            "eigenvector": None if ev is None else [float(x) for x in ev],
            "critical_multiplier": None if not np.isfinite(m) else [float(m.real),
                                                                     float(m.imag)],
            "starts": [o.to_dict() for o in self.starts],
            "start_parameters": [float(p) for p in self.start_parameters],
            "amplitude": float(self.amplitude), "period": int(self.period),
            "branches": [b.to_dict() for b in self.branches], "design": self.design,
            "reason": self.reason}


def _design_of(branch: Branch):
    f = branch.fixed
    if branch.family == "symmetric" or "x10" in f or branch.parameter_name == "x10":
        x10 = f.get("x10", np.nan)
        return _Design(float(x10) if np.isfinite(x10) else 1.0, int(f.get("n", 1)))
    return None


def branch_map(branch: Branch, value: float) -> ImpactMap | None:
    """The impact map at parameter ``value`` on the parameter path of ``branch``.

    Fixed ``xm`` for a map continuation at fixed ``xm``; on the design path (``x10`` fixed,
    ``xm`` following, paper (20)) for a symmetric family or a design-path continuation.
    None where the design has no reference amplitude.

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.pair.continuation import continue_symmetric
    >>> br = continue_symmetric(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0, "kv", 21.0)
    >>> P = branch_map(br, br.parameter[-1])
    >>> bool(abs(P.reference.xm - br.xm[-1]) < 1e-12)
    True
    """
    f = dict(branch.fixed)
    name = branch.parameter_name
    design = _design_of(branch)
    pair = ImpactPair(mu=f.get("mu", 1.0), e=f.get("e", 0.5), L=f.get("L", 1.0),
                      m2=f.get("m2", 1.0))
    gains = PDGains(f.get("kp", 1.0), f.get("kv", 1.0))
    ref = Reference(f.get("xm", 1.0) if design is None else 1.0, f.get("omega", 1.0))
    base = ImpactMap(pair, gains, ref, Case.parse(f.get("case", branch.case)))
    return _map_with(base, name, float(value), design)


def _critical(DP, target):
    """The eigenvalue of ``DP`` nearest ``target`` and its real unit eigenvector."""
    w, V = np.linalg.eig(DP)
    i = int(np.argmin(np.abs(w - target)))
    v = np.real(V[:, i])
    if np.linalg.norm(v) < 1e-12:
        v = np.imag(V[:, i])
    v = v / np.linalg.norm(v)
    return w[i], v * (1.0 if v[np.argmax(np.abs(v))] > 0 else -1.0)


def _augmented_start(branch, Pc, sc, pc, v, K, a, tol, max_iter, fd_step):
    """Newton on ``[P^K(s) - s; v.(s - sc) - a]`` in ``(s, p)`` from ``(sc + a v, pc)``."""
    design = _design_of(branch)
    fam = Pc.family(branch.parameter_name, fd_step=fd_step,
                    **({} if design is None else {"x10": design.x10, "n": design.n}))
    cache = {}

    def map_at(p):
        key = float(p)
        if key not in cache:
            cache[key] = Pc if key == pc else fam.at(key)
        return cache[key]

    def G(u):
        P = map_at(u[4])
        r = None if P is None else map_residual(P, u[:4], K)
        if r is None:
            return None
        d = u[:4] - sc
        d[0] = wrap_phase(d[0], Pc.period)
        return np.append(r, v @ d - a)

    def JG(u):
        P = map_at(u[4])
        if P is None:
            raise RuntimeError("map undefined")
        Fs = P.jacobian(u[:4], K) - np.eye(4)
        Fp = fam.gradient(P, u[:4], K, u[4], at=map_at)
        return np.vstack([np.column_stack([Fs, Fp]), np.append(v, 0.0)])

    return newton(G, JG, np.append(sc + a * v, pc), tol=tol, max_iter=max_iter, scale=_scale)


def _fixed_of_power(P, s, k, scale_tol=1e-7):
    """``s`` is a fixed point of ``P^k`` (relative ``scale_tol``)."""
    img, ok = P.apply_many(s[None, :], k)
    if not ok[0]:
        return False
    r = img[0] - s
    r[0] = wrap_phase(r[0], P.period)
    return bool(np.max(np.abs(r)) <= scale_tol * _scale(s))


def _smooth_switch(branch, event, kind, amplitudes, tol, max_iter, fd_step):
    name = branch.parameter_name
    k = branch.period
    pc = float(event.parameter)
    Pc = branch_map(branch, pc)
    if Pc is None:
        raise ValueError(f"no map at the event ({name} = {pc:g})")
    sc = np.asarray(event.point, float)
    DP = Pc.jacobian(sc, k)
    target = -1.0 if kind == "period_doubling" else 1.0
    lam, v = _critical(DP, target)
    K = 2 * k if kind == "period_doubling" else k
    starts, params, notes = [], [], []
    used = np.nan
    for sign in (1.0, -1.0):
        for a in amplitudes:
            res = _augmented_start(branch, Pc, sc, pc, v, K, sign * a, tol, max_iter, fd_step)
            if not res.converged:
                notes.append(f"a = {sign * a:+.2g}: Newton failed ({res.reason})")
                continue
            p = float(res.x[4])
            P = branch_map(branch, p)
            s = res.x[:4].copy()
            s[0] %= P.period
            if kind == "period_doubling" and _fixed_of_power(P, s, k):
                notes.append(f"a = {sign * a:+.2g}: landed on the parent (period {k})")
                continue
            if kind == "fold":
                parent = find_orbit(P, sc, k, tol=tol)
                if parent.converged and np.max(np.abs(_dphase(parent.s - s, P.period))) \
                        < 0.1 * a:
                    notes.append(f"a = {sign * a:+.2g}: landed on the parent branch")
                    continue
            orb = find_orbit(P, s, K, tol=tol)
            if not orb.converged or orb.minimal_period != K:
                notes.append(f"a = {sign * a:+.2g}: polishing failed or minimal period "
                             f"{orb.minimal_period} != {K}")
                continue
            if any(_same_cycle(orb, o, P.period) and abs(p - q) < 1e-9 * max(1, abs(p))
                   for o, q in zip(starts, params)):
                continue
            starts.append(orb)
            params.append(p)
            used = a
            break
        if kind == "period_doubling" and starts:
            # -a gives the other point of the same cycle: one start suffices
            break
    return lam, v, K, starts, params, used, notes


def _dphase(d, T):
    d = np.array(d, float)
    d[0] = wrap_phase(d[0], T)
    return d


def _same_cycle(a: PeriodicOrbit, b: PeriodicOrbit, T) -> bool:
    """``b.s`` is a point of the cycle of ``a`` (to 1e-6)."""
    return any(np.max(np.abs(_dphase(x - b.s, T))) < 1e-6 for x in a.orbit)


def _grazing_switch(branch, event, offset, settle, max_period, tol):
    name = branch.parameter_name
    pg = float(event.parameter)
    i = min(max(event.index, 0), len(branch) - 1)
    par = branch.parameter
    if i + 1 < len(branch) and branch.viable[i] != branch.viable[i + 1]:
        # symmetric family: past grazing is the side where the orbit is not viable
        toward = np.sign(par[i + 1] - par[i]) * (1.0 if branch.viable[i] else -1.0)
    else:
        # a branch that ends at grazing: step on in the direction it was going
        j = i + 1 if i + 1 < len(branch) else i
        toward = np.sign(par[j] - par[max(i - 1, 0)]) or 1.0
    p = pg + toward * offset * max(1.0, abs(pg))
    P = branch_map(branch, p)
    if P is None:
        return p, None, f"no map past grazing at {name} = {p:g}"
    tr = P.iterate(np.asarray(event.point, float), settle)
    if not np.all(np.isfinite(tr[-1])):
        return p, None, f"the motion from the grazing orbit left the section at {name} = {p:g}"
    last = tr[-1]
    for K in range(1, max_period + 1):
        back = tr[-1 - K]
        if np.max(np.abs(_dphase(back - last, P.period))) < 1e-6 * _scale(last):
            # start from the cycle point farthest from the parent orbit, so that the corrector
            # of a continuation cannot slide back onto the parent
            far = max(tr[-K:], key=lambda x: np.max(np.abs(_dphase(x - event.point,
                                                                    P.period))))
            orb = find_orbit(P, far, K, tol=tol)
            if orb.converged and orb.minimal_period == K:
                return p, orb, f"settled on a period-{K} orbit after {settle} iterations"
    return p, None, (f"the motion from the grazing orbit did not settle on a cycle of period "
                     f"<= {max_period} within {settle} iterations at {name} = {p:g}")


def switch_branch(branch: Branch, event: BifurcationEvent, stop: float | None = None, *,
                  amplitudes=(1e-3, 3e-3, 1e-2, 3e-2, 1e-4), offset: float = 1e-3,
                  settle: int = 3000, max_period: int = 16, tol: float = 1e-12,
                  max_iter: int = 30, fd_step: float = 1e-6, **continue_kwargs) -> BranchSwitch:
    """Start (and optionally continue) the branch born at an event of ``branch``.

    Parameters
    ----------
    branch : Branch
        The parent branch (a map continuation of the pair,
        :func:`~hybridpd.analysis.continuation.continue_orbit` of :meth:`ImpactMap.family
        <hybridpd.pair.impactmap.ImpactMap.family>`, or :func:`continue_symmetric`).
    event : BifurcationEvent
        One of ``branch.events``: ``period_doubling`` (switch to the period-doubled
        branch), ``fold`` that is a *branch point* (a multiplier at +1 while the parent goes
        on: switch to the crossing branch) or ``grazing`` (nonsmooth: the motion reached
        past the grazing point). See the module docstring for the method.
    stop : float, optional
        Continue every new branch found from its start to this parameter value with
        :func:`~hybridpd.analysis.continuation.continue_orbit` on the family of the map at the
        start (on the parent's parameter path); not continued when None.
    amplitudes : sequence of float
        Steps ``a`` along the critical eigenvector tried in turn (smooth switches).
    offset : float
        Relative parameter offset past a grazing point.
    settle : int
        Iterations of ``P`` before the period of the settled motion is read (grazing).
    max_period : int
        Largest period looked for after a grazing.
    tol, max_iter : float, int
        Newton tolerance (see :func:`~hybridpd.analysis.periodic.find_orbit`) and iteration bound.
    fd_step : float
        Relative finite-difference step of ``dF/dp`` (the switch's Newton and the new
        branches' family).
    **continue_kwargs
        Passed to :func:`~hybridpd.analysis.continuation.continue_orbit` (e.g. ``step``,
        ``max_steps``, ``method``); its corrector tolerance defaults to ``1e-12`` here.

    Returns
    -------
    BranchSwitch

    Raises
    ------
    ValueError
        ``event`` not of a switchable kind, a fold that is a turning point (no branch to
        switch to), or bad numerical parameters.

    Examples
    --------
    The symmetric orbit of the collocated loop at ``e = 0.5``, ``kv = 0.5`` loses its
    symmetry in a pitchfork near ``kp = 58.7``; switch to the non-symmetric branch:

    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.pair.continuation import continue_symmetric
    >>> br = continue_symmetric(ImpactPair(0.1, 0.5, 0.75), PDGains(55, 0.5), 5.0, "kp", 62.0)
    >>> sw = switch_branch(br, br.events_of("fold")[0])
    >>> sw.kind, sw.period, len(sw.starts)
    ('branch_point', 1, 2)
    """
    if not isinstance(branch, Branch):
        raise ValueError(f"branch must be a Branch, got {type(branch).__name__}")
    if not isinstance(event, BifurcationEvent):
        raise ValueError(f"event must be a BifurcationEvent, got {type(event).__name__}")
    if event.kind not in _SWITCH_KINDS:
        raise ValueError(f"event.kind must be one of {_SWITCH_KINDS}, got {event.kind!r}")
    if event.kind == "fold" and "turns back" in event.detail:
        raise ValueError("this fold is a turning point of the branch (it turns back): no "
                         "other branch crosses there; switch at a branch point instead")
    amplitudes = tuple(check_positive("amplitudes", a) for a in amplitudes)
    if not amplitudes:
        raise ValueError("amplitudes must not be empty")
    offset = check_positive("offset", offset)
    settle = check_int("settle", settle, 1)
    max_period = check_int("max_period", max_period, 1)
    tol = check_positive("tol", tol)
    max_iter = check_int("max_iter", max_iter, 1)
    fd_step = check_positive("fd_step", fd_step)
    name = branch.parameter_name
    design = _design_of(branch)
    if event.kind == "grazing":
        p, orb, reason = _grazing_switch(branch, event, offset, settle, max_period, tol)
        starts = (orb,) if orb is not None else ()
        params = [p] if orb is not None else []
        lam, v, K, used = complex(np.nan), None, (orb.period if orb else 0), p - event.parameter
        kind = "grazing"
    else:
        lam, v, K, starts, params, used, notes = _smooth_switch(
            branch, event, event.kind, amplitudes, tol, max_iter, fd_step)
        kind = "period_doubling" if event.kind == "period_doubling" else "branch_point"
        reason = (f"{len(starts)} new orbit(s) of period {K} found"
                  + (f"; {'; '.join(notes)}" if notes else ""))
    branches = []
    if stop is not None:
        for orb, p in zip(starts, params):
            P = branch_map(branch, p)
            kw = dict(continue_kwargs)
            # the new branch is checked as fixed points of P^K: correct tightly
            kw.setdefault("tol", 1e-12)
            fam = P.family(name, fd_step=fd_step, **({} if design is None else
                                                    {"x10": design.x10, "n": design.n}))
            branches.append(continue_orbit(fam, fam.value, stop, orb, period=K, **kw))
    return BranchSwitch(
        kind=kind, event=event, parameter_name=name, critical_value=float(event.parameter),
        eigenvector=v, critical_multiplier=complex(lam), starts=tuple(starts),
        start_parameters=np.asarray(params, float), amplitude=float(used)
        if math.isfinite(used) else np.nan, period=int(K), branches=tuple(branches),
        design=None if design is None else {"x10": design.x10, "n": design.n},
        reason=reason)
