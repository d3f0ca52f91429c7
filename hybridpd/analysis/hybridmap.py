r"""The impact (Poincaré) map on a guard of any :class:`~hybridpd.hybrid.automaton.HybridAutomaton`.

The section itself (:class:`~hybridpd.hybrid.section.Section`: the guard, its coordinates
``s``, the phase and the sampling clocks) is defined in :mod:`hybridpd.hybrid.section`.

Map
---
``P^k(s)``: start at the pre-jump state ``z(s)`` at time ``t = phi``, let the automaton fire the
guard at once (the jump's reset is applied by the simulator), and run it until the
``(k+1)``-th firing of the same guard (crossing or grazing; Zeno switches, other guards and
mode changes in between are followed); ``P^k(s)`` is the pre-jump state there. Every run is
bounded by ``t_max`` (time after the start), ``max_jumps`` and ``max_steps``; a map result
always says why it stopped (:data:`MAP_STATUS`).

Jacobian
--------
``DP`` is assembled from the run: exact flows ``Phi = expm(A tau)`` over every segment, and at
every jump the saltation matrix ``S = R + (f+ - R f-) c^T / (c . f-)`` of the guard ``(c, d)``
that fired, its reset ``(R, r)``, ``f- = A_src z- + b_src`` and ``f+ = A_dst z+ + b_dst``. The
final crossing adds the time correction ``dtau = -c Z / (c . f-)`` (``Z`` the accumulated
sensitivity), so ``dz_hit = Z + f- dtau`` and ``dphi' = dphi + dtau dz0``. A Zeno switch (an
accumulation of impacts ending in a sticking mode) enters as its reset ``R_z`` alone: for a
projection onto the contact that is consistent with the flows (``R_z f- = f+`` at the
accumulation point, as for the pair's and the samples' sticking modes), the dependence of the
accumulation time drops out. A grazing jump (``c . f- ~ 0``) has no saltation matrix:
:attr:`MapResult.grazing` flags it and the Jacobian is then infinite or meaningless.

Modes on demand
---------------
A map builds the modes its runs enter, as a simulation does: the compiled return loop hands
back when a run enters a mode not built yet (or takes a Zeno switch whose reset is not packed
yet), the tables are completed and the run is made again (each mode is built once, so this is
bounded by the automaton's ``max_modes``). :class:`SectionMap`, its Jacobian, ``apply_many``
and the basin labeller of :class:`~hybridpd.analysis.mappers.MapMapper` read only the
modes built so far; the exosystem is found over those and every mode built later is checked
against it.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from hybridpd._jit import njit
from hybridpd.analysis.maps import MapResult, PoincareMap, check_returns
from hybridpd.analysis.saltation import sensitivity_chain
from hybridpd.hybrid._kernel import (
    _RC_NEED_MODE,
    FC_T,
    IC_BURST_MODE,
    IC_LAST_GUARD,
    IC_LAZY_GUARD,
    IC_LAZY_MODE,
    IC_MODE,
    IC_NJ,
    IC_NS,
    IC_NZ,
    PackedAutomaton,
    RunBuffers,
    RunOptions,
    _other_active,
)
from hybridpd.hybrid.automaton import TerminationCause, ZenoOptions, run_hybrid
from hybridpd.hybrid.section import Section, _moves, common_multiple, exosystem
from hybridpd.model import check_finite

__all__ = ["MAP_STATUS", "MapResult", "Section", "SectionMap", "common_multiple", "exosystem"]

#: Codes of :attr:`MapResult.status`.
MAP_STATUS = {0: "returned", 1: "jump_limit", 2: "zeno", 3: "nonfinite", 4: "step_limit",
              6: "end_time", 7: "bad_start", 8: "simultaneous", 10: "too_many_modes"}
ST_RETURNED, ST_JUMP_LIMIT, ST_ZENO, ST_NONFINITE, ST_STEP_LIMIT = 0, 1, 2, 3, 4
ST_END_TIME, ST_BAD_START, ST_SIMULTANEOUS = 6, 7, 8
ST_NEED_MODE = 9           # internal: the run entered a mode not built yet
ST_TOO_MANY_MODES = 10
_ON_GUARD_RTOL = 1e-9      # |g| below this (relative) at a pending event: on that guard
_RESOLVED = 4              # a resolved run's bound on jumps, in units of max_jumps
#: Why a return within one burst of impacts is no orbit, and what to do.
FAST_RETURN_HINT = ("the section's guard fires again within one burst of impacts (rebounds); "
                    "section on the ends of the sticking phases instead (event='release', "
                    "command line --event release) or raise the period")


# ----------------------------------------------------------------------------------------
# the compiled return kernel
# ----------------------------------------------------------------------------------------
class ReturnRun(NamedTuple):
    """What a run to the section's guard reads besides its start (``_to_return``, the
    labeller), by name: the automaton's tables ``pk`` and per-mode ``dt_min`` (shape
    ``(M,)``, time), the jump loop's options ``opts``, the section's mode and guard, the
    horizon ``t_max`` (time after the start) and the bounds on jumps and flow steps."""

    pk: PackedAutomaton
    dt_min: np.ndarray
    opts: RunOptions
    mode: int
    guard: int
    t_max: float
    max_jumps: int
    max_steps: int


@njit(cache=True)
def _any_joint(pk, groups, rb, nb, simtol):
    """Whether one of the first ``nb`` jumps recorded in ``rb`` is joint (see
    ``SectionMap.simtol``); ``groups (M, GM)``: the guards' simultaneity groups."""
    G, ng, h = pk.G, pk.ng, pk.h
    jt, jg, jsrc, jkind, jpre = rb.jt, rb.jg, rb.jsrc, rb.jkind, rb.jpre
    for q in range(nb):
        m, g = jsrc[q], jg[q]
        if jkind[q] != 3 and groups[m, g] != 0 and _other_active(
                G[m], ng[m], groups[m], g, jpre[q], h[m], simtol * (1.0 + abs(jt[q]))):
            return True
    return False


@njit(cache=True)
def _pending_guard(w, mode, G, ng):
    """The unique guard of ``mode`` on which the pending state ``w`` sits, or -1 / -2 (ties).

    ``G[mode, g, 0]`` is the guard's row ``-direction [c, d]``: the value is on the firing
    side or within ``_ON_GUARD_RTOL`` of it, relative to the terms that make it up.
    """
    found = -1
    N1 = w.shape[0]
    for g in range(ng[mode]):
        val = 0.0
        scale = 0.0
        for i in range(N1):
            val += G[mode, g, 0, i] * w[i]
            scale += abs(G[mode, g, 0, i] * w[i])
        if val <= _ON_GUARD_RTOL * max(scale, 1e-300):
            if found >= 0:
                return -2
            found = g
    return found


@njit(cache=True)
def _to_return(run, w0, t0, k, J0, rb):
    """Run from the pre-jump state ``w0`` (mode ``run.mode``) at ``t0`` to the ``(k+1)``-th
    firing of the section's guard ``run.guard``, first allowing ``J0`` jumps.

    ``run`` is a :class:`ReturnRun`, ``rb`` the run's buffers (:mod:`hybridpd.hybrid._kernel`).

    Returns ``(status, n_before, J)``: ``n_before`` jumps precede the target firing; its
    pre-jump state is left in ``w`` and its time in ``fc[0]``; the tables hold the run.
    ``ST_NEED_MODE``: the run entered a mode not built yet (its code in ``ic[0]``), or took a
    Zeno switch whose reset is not packed (``ic[16]``, ``ic[17]``): complete the tables
    (:meth:`SectionMap._complete`) and run again.
    """
    w, fc, ic, jt, jg, jsrc, jkind, jpre = (rb.w, rb.fc, rb.ic, rb.jt, rb.jg, rb.jsrc, rb.jkind,
                                            rb.jpre)
    pk, dt_min, opts = run.pk, run.dt_min, run.opts
    gm, gi, t_max, J_max, max_steps = (run.mode, run.guard, run.t_max, run.max_jumps,
                                       run.max_steps)
    G, ng = pk.G, pk.ng
    N1 = w0.shape[0]
    J = min(max(J0, k), J_max)
    while True:
        for i in range(N1):
            w[i] = w0[i]
        fc[:] = 0.0
        fc[FC_T] = t0
        ic[:] = 0
        ic[IC_MODE] = gm
        ic[IC_LAST_GUARD] = -1
        ic[IC_BURST_MODE] = -1
        rc = run_hybrid(pk, dt_min, t0 + t_max, J, max_steps, opts, rb)
        nj = ic[IC_NJ]
        if nj == 0 or jsrc[0] != gm or jg[0] != gi or jt[0] != t0 or jkind[0] == 3:
            return ST_BAD_START, 0, J
        count = 0
        nzj = 0
        for q in range(nj):
            if jkind[q] == 3:
                nzj += 1
            elif jsrc[q] == gm and jg[q] == gi:
                count += 1
                if count == k + 1:
                    for i in range(N1):
                        w[i] = jpre[q, i]
                    fc[FC_T] = jt[q]
                    return ST_RETURNED, q, J
        if rc == _RC_NEED_MODE:
            return ST_NEED_MODE, nj, J
        if rc != 1:
            return ST_END_TIME if rc == 0 else rc, nj, J
        if count == k and ic[IC_NZ] == nzj and ic[IC_MODE] == gm:
            pg = _pending_guard(w, gm, G, ng)
            if pg == gi:
                return ST_RETURNED, nj, J
            if pg == -2 or pg == -1:
                if J >= J_max:
                    return ST_JUMP_LIMIT, nj, J
                J += 1        # ambiguous pending event: take it and read the table
                continue
        if J >= J_max:
            return ST_JUMP_LIMIT, nj, J
        J = min(2 * J, J_max)


# ----------------------------------------------------------------------------------------
# the map
# ----------------------------------------------------------------------------------------
class OnSection:
    """What a map whose points are those of its ``section`` reads from it: the coordinates'
    names, the mode, the points and their full states, and one structural zero per sampling
    clock set from the phase (the held force at a section point is overwritten at the next
    sample)."""

    section = None

    @property
    def names(self) -> tuple:
        return self.section.names

    @property
    def mode(self) -> str:
        return self.section.mode

    @property
    def structural_zeros(self) -> int:
        return len(self.section.clocks)

    def check_point(self, s) -> np.ndarray:
        return self.section.check_point(s)

    def state(self, s) -> np.ndarray:
        return self.section.to_state(s)[0]


class SectionMap(OnSection, PoincareMap):
    """The impact map ``P`` of a :class:`Section` (module docstring), its powers and ``DP``.

    The reference implementation of the map protocol (:class:`~hybridpd.analysis.maps.
    PoincareMap`): any automaton, any section, ``DP`` from saltation matrices. The impact
    pair's specialisations are checked against it.

    Parameters
    ----------
    section : Section
    t_max : float, optional
        Bound on the time of one application of ``P^k`` (default ``50 k T``, or ``1000`` time
        units without exosystem phase).
    max_jumps : int
        Bound on the jumps of one application of ``P^k`` (including Zeno switches); a run
        handed to the resolver (:meth:`apply`) may take four times as many, since it records
        one jump per contact of a joint jump.
    max_steps : int
        Bound on the exact flow steps of one application.
    zeno : ZenoOptions, optional
        Accumulation rules (default the automaton's own, ``section.automaton.zeno``, which
        its simulations use too); ``tail_tol`` included.
    simtol : float or None
        Guards of one simultaneity group (a mechanical model's impacts) that close within
        ``simtol (1 + |t|)`` of each other take one joint jump in a simulation; the map
        applies jumps one at a time, so where that happens :meth:`apply` reports status
        ``"simultaneous"`` (no image) instead of a sequential answer. ``None`` skips the check.
        The compiled iterations of basins do not check.
    joint : {"refuse", "resolve"}
        With a section that carries a resolver (a mechanical model's): ``"resolve"`` makes
        an application whose sequential run crosses a joint jump again by the simulator with
        the resolver, as a simulation takes it (tens to hundreds of times slower on long
        chains of contacts); ``"refuse"`` (default) reports ``"simultaneous"``. A run that
        stops at contacts refiring at one instant (status ``"zeno"``: the compiled loop has
        no answer at all) always goes to the resolver.
    max_table_bytes : float
        Bound on the automaton's packed tables (:attr:`HybridAutomaton.table_bytes`, bytes)
        up to which the map builds the modes its runs enter (default 256 MB). A run that
        needs one more beyond it has status ``"too_many_modes"`` (a point of a basin is then
        ``unresolved``): an orbit search that wanders through very many sets of held
        contacts stops and says so instead of filling the memory.

    Examples
    --------
    The pair's symmetric orbit is a fixed point of the general map:

    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.pair.orbits import symmetric_orbit
    >>> from hybridpd.pair.section import impact_pair_section
    >>> orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    >>> P = SectionMap(impact_pair_section(orb.system()))
    >>> bool(np.allclose(P(orb.fixed_point), orb.fixed_point, atol=1e-10))
    True
    """

    def __init__(self, section: Section, *, t_max: float | None = None, max_jumps: int = 10_000,
                 max_steps: int = 10_000_000, zeno: ZenoOptions | None = None,
                 simtol: float | None = 1e-12, max_table_bytes: float = 256e6,
                 joint: str = "refuse"):
        if not isinstance(section, Section):
            raise ValueError(f"section must be a Section, got {type(section).__name__}")
        if not (math.isfinite(float(max_table_bytes)) and float(max_table_bytes) > 0):
            raise ValueError(f"max_table_bytes must be finite and > 0, got {max_table_bytes!r}")
        self.max_table_bytes = float(max_table_bytes)
        self.section = section
        if t_max is not None and not (float(t_max) > 0 and math.isfinite(float(t_max))):
            raise ValueError(f"t_max must be finite and > 0, got {t_max!r}")
        self.t_max = None if t_max is None else float(t_max)
        if isinstance(max_jumps, bool) or int(max_jumps) != max_jumps or max_jumps < 1:
            raise ValueError(f"max_jumps must be an int >= 1, got {max_jumps!r}")
        self.max_jumps = int(max_jumps)
        if isinstance(max_steps, bool) or int(max_steps) != max_steps or max_steps < 1:
            raise ValueError(f"max_steps must be an int >= 1, got {max_steps!r}")
        self.max_steps = int(max_steps)
        # the automaton's own rules by default: the map then resolves an accumulation where
        # a simulation of the automaton does (a shorter resolved burst moves its end, and
        # with it the orbit, by the error of the earlier extrapolation)
        zeno = section.automaton.zeno if zeno is None else zeno
        if not isinstance(zeno, ZenoOptions):
            raise ValueError("zeno must be a ZenoOptions instance")
        self.zeno = zeno
        if simtol is not None and not (math.isfinite(float(simtol)) and float(simtol) >= 0):
            raise ValueError(f"simtol must be >= 0 or None, got {simtol!r}")
        self.simtol = None if simtol is None else float(simtol)
        if joint not in ("refuse", "resolve"):
            raise ValueError(f"joint must be 'refuse' or 'resolve', got {joint!r}")
        self.joint = joint
        self._run_opts = zeno.run_options()
        self._tables_for = -1           # the tables' version when the kernel's were taken
        self._checked = 0               # modes checked against the section's exosystem
        self._hint = {}

    @property
    def _tables(self) -> tuple:
        """The jump loop's tables over the modes built so far and ``dt_min`` (taken afresh
        whenever they changed: a mode built or a reset packed may make them new arrays)."""
        ha = self.section.automaton
        if self._tables_for != ha._store.version:
            self._check_exosystem()
            pk = ha.packed
            dt_min = (pk.h * 1e-9 if self.zeno.dt_min is None
                      else np.full(pk.h.shape[0], float(self.zeno.dt_min)))
            self._pk_dt = (pk, dt_min)
            self._groups = ha._store.gkind()
            self._tables_for = ha._store.version
        return self._pk_dt

    def _return_run(self, k: int) -> ReturnRun:
        """What the compiled runs to ``P^k`` read (:class:`ReturnRun`), over the tables as
        they are now."""
        pk, dt_min = self._tables
        sec = self.section
        return ReturnRun(pk, dt_min, self._run_opts, sec.mode_index, sec.guard_index,
                         float(self._t_max(k)), self.max_jumps, self.max_steps)

    def _check_exosystem(self):
        """Every mode built since the section was made moves its exosystem as the first
        mode does (the phase coordinate assumes it); ``ValueError`` otherwise."""
        sec = self.section
        ha = sec.automaton
        if not sec.exo:
            self._checked = ha.n_built
            return
        modes, pk = ha._slim(), ha.packed
        S = set(sec.exo)
        for mi in range(self._checked, len(modes)):
            for i in sec.exo:
                if _moves(modes[mi], mi, pk, i, S, modes[0], 0.0):
                    raise ValueError(
                        f"mode {modes[mi].name!r} moves the exosystem state {i} of the "
                        "section (its flow or a reset): the phase coordinate needs states "
                        "that evolve alike in every mode")
        self._checked = len(modes)

    def _complete(self, ic) -> bool:
        """What a run handed back for (``ST_NEED_MODE``): the Zeno reset of ``ic[16] - 1``,
        ``ic[17]`` is packed and the mode ``ic[0]`` built if it is a reserved code; the run
        is then made again. False (nothing done) when a mode is needed and the tables have
        reached ``max_table_bytes``."""
        ha = self.section.automaton
        if ic[IC_MODE] < -1 and ha.table_bytes >= self.max_table_bytes:
            return False
        if ic[IC_LAZY_MODE]:
            ha._zeno_reset(int(ic[IC_LAZY_MODE]) - 1, int(ic[IC_LAZY_GUARD]))
            ic[IC_LAZY_MODE] = 0
        if ic[IC_MODE] < -1:
            ha.build_code(int(ic[IC_MODE]))
        return True

    @property
    def dim(self) -> int:
        return self.section.dim

    @property
    def period(self) -> float | None:
        return self.section.period

    # ---- what an orbit of a section map must satisfy (hooks of find_orbit)
    def _min_return(self, min_return):
        sec = self.section
        if min_return is None:
            return sec.reference_period / 20.0 if sec.has_phase else 0.0
        if not (float(min_return) >= 0 and math.isfinite(float(min_return))):
            raise ValueError(f"min_return must be finite and >= 0, got {min_return!r}")
        return float(min_return)

    def refuse(self, s0, k, *, min_return=None, sampling_period=None, **options):
        """``sampling_incommensurate`` (sampling clocks that never return with the phase)
        and ``fast_return`` (``P^k`` returns within one burst of impacts), before Newton."""
        sec = self.section
        T = sec.reference_period if sec.has_phase else None
        if not sec.sampling_commensurate:
            near = "; ".join(f"dt = {dt:g} -> {d:.10g} (T / {round(T / d)})"
                             for dt, d in sec.nearest_commensurate_dt().items())
            return "sampling_incommensurate", (
                f"the sampling periods and the reference period T = {T:.10g} have no common "
                f"multiple m T (m <= 64): the sampling instants never return with the phase, "
                f"so no motion repeats. The nearest sampling periods that divide T: {near}")
        if sampling_period is not None and T and not sec.clocks:
            dt = check_finite("sampling_period", sampling_period)
            if not dt > 0:
                raise ValueError(f"sampling_period must be finite and > 0, got {dt!r}")
            if not common_multiple(T, [dt]):
                d = T / max(1, round(T / dt))
                return "sampling_incommensurate", (
                    f"the sampling period {dt:g} and the reference period {T:g} have no common "
                    f"multiple m T (m <= 64): the sampling clock never returns with the "
                    f"phase; the nearest sampling period that divides T is {d:.10g} (T / "
                    f"{round(T / d)})")
        r = self.apply(s0, k)
        mr = self._min_return(min_return)
        if r.ok and r.t_hit - r.t_start < mr:
            return "fast_return", (f"P^{k} returns {r.t_hit - r.t_start:.3g} after the start "
                                   f"(< min_return = {mr:.3g}): {FAST_RETURN_HINT}")
        return None

    def accept(self, result, *, min_return=None, **options) -> bool:
        """A trial point of Newton is rejected where ``P^k`` returns sooner than
        ``min_return``: the points that return to themselves at once (a tangential
        reopening) are zeros of ``P^k(s) - s`` but no orbits."""
        return result.t_hit - result.t_start >= self._min_return(min_return)

    def validate(self, s, k, result, *, periods=None, min_return=None, verify=True,
                 **options) -> tuple:
        """``(reason, n_periods, detail, return_error)`` of a zero of ``P^k(s) - s``: a
        non-zero return time (``degenerate_return``), transversal (``grazing``), not within a
        burst (``fast_return``), a whole number of reference periods (``periods`` if given)
        and an independent simulation of one period returning to it (``not_periodic``)."""
        sec = self.section
        rr, t_per = result, result.t_hit - result.t_start
        T = sec.reference_period if sec.has_phase else None
        scale_t = T if T else max(1.0, abs(rr.t_start))
        mr = self._min_return(min_return)
        if not t_per > 1e-9 * scale_t:
            return "degenerate_return", 0, (f"P^{k} returns {t_per:.3g} after the start: the "
                                            "point returns to itself at once, not after a "
                                            "period"), math.nan
        if rr.grazing:
            return "grazing", 0, "a contact on the orbit is tangential (no saltation matrix)", \
                math.nan
        if t_per < mr:
            return "fast_return", 0, (f"the orbit's return takes {t_per:.3g} (< min_return = "
                                      f"{mr:.3g}): {FAST_RETURN_HINT}"), math.nan
        m = 1
        if T:
            m = round(t_per / T)
            if m < 1 or abs(t_per - m * T) > 1e-7 * max(m, 1) * T:
                return "not_periodic", 0, (f"return time {t_per:.12g} is not a whole number of "
                                           f"reference periods T = {T:.12g}"), math.nan
            if periods is not None and m != int(periods):
                return "not_periodic", m, (f"return time {t_per:.12g} = {m} T, not the "
                                           f"requested {int(periods)} T"), math.nan
        if not verify:
            return "converged", m, "", math.nan
        err = self.return_error(s, k, t_per)
        if not err <= 1e-6:
            return "not_periodic", m, (f"simulating {t_per:.6g} from the section point does "
                                       f"not return to it (relative error {err:.3g})"), err
        return "converged", m, "", err

    def return_error(self, s, k, t_per) -> float:
        """Relative distance between the section state and the state where an independent run
        of the automaton's simulator fires the section's guard for the ``(k+1)``-th time."""
        sec = self.section
        z0, t0 = sec.to_state(s)
        try:
            jumps = self.max_jumps * (_RESOLVED if sec.resolver is not None else 1)
            tr = sec.automaton.simulate(z0, sec.mode, (t0, t0 + t_per * (1 + 1e-9) + 1e-12),
                                        max_jumps=jumps, max_steps=self.max_steps,
                                        zeno=self.zeno, resolver=sec.resolver,
                                        simtol=1e-12 if self.simtol is None else self.simtol)
        except (ValueError, RuntimeError, FloatingPointError):
            return math.inf
        J = tr.jumps
        hits = [i for i in range(len(J)) if J.source[i] == sec.mode and J.guard[i] == sec.guard
                and J.kind[i] != "zeno"]
        if len(hits) < k + 1:
            return math.inf
        i = hits[k]
        dz = J.pre[i] - z0
        scale = max(1.0, float(np.max(np.abs(z0))))
        return float(max(np.max(np.abs(dz)) / scale, abs(J.t[i] - t0 - t_per) / max(1.0, t_per)))

    def _t_max(self, k):
        if self.t_max is not None:
            return self.t_max
        return 50.0 * k * self.section.period if self.section.has_phase else 1000.0

    def _buffers(self) -> RunBuffers:
        return RunBuffers.empty(self.max_jumps + 4, self.section.automaton.n_states + 1)

    def _run(self, s, k):
        sec = self.section
        z0, t0 = sec.to_state(s)
        bufs = self._buffers()
        w0 = np.append(z0, 1.0)
        if not sec.fires(z0) > 0:
            return ST_BAD_START, 0, z0, t0, bufs
        J0 = self._hint.get(k, k + 1)
        # modes on demand: a run that enters a mode not built yet stops there; the mode is
        # built and the run made again (each mode is built once: bounded by max_modes)
        while True:
            st, nb, _J = _to_return(self._return_run(k), w0, t0, int(k), J0, bufs)
            if st != ST_NEED_MODE:
                break
            if not self._complete(bufs.ic):
                st = ST_TOO_MANY_MODES
                break
        if st == ST_RETURNED:
            self._hint[k] = max(int(nb), 1)   # next time: stop right at the return
        return int(st), int(nb), z0, t0, bufs

    def apply(self, s, k: int = 1, jacobian: bool = False) -> MapResult:
        """Apply ``P^k`` to the section point ``s`` (optionally with ``DP^k``).

        Parameters
        ----------
        s : array_like, shape (dim,)
            Section point; the flow must fire the guard there.
        k : int
            Number of returns (``>= 1``).
        jacobian : bool
            Also compute ``DP^k`` from exact flows and saltation matrices.

        Returns
        -------
        MapResult
        """
        k = check_returns(k)
        sec = self.section
        st, nb, z0, t0, bufs = self._run(sec.check_point(s), k)
        w, fc, ic = bufs.w, bufs.fc, bufs.ic
        jt, jg, jsrc, jdst, jkind = bufs.jt, bufs.jg, bufs.jsrc, bufs.jdst, bufs.jkind
        ha = sec.automaton
        n = ha.n_states
        mn = ha.built_mode_names
        if st == ST_BAD_START:
            return MapResult(np.full(self.dim, np.nan), False, MAP_STATUS[st], t0, t0, z0,
                             sec.mode, (), False)
        modes = ha._slim()
        kinds = {1: "crossing", 2: "grazing", 3: "zeno"}
        jumps = tuple((float(jt[q]), mn[jsrc[q]], modes[jsrc[q]].guards[jg[q]].name,
                       ha._name_of(int(jdst[q])), kinds[int(jkind[q])]) for q in range(nb))
        z_hit = w[:n].copy()
        t_hit = float(fc[FC_T])
        if self._joint_jump(bufs, nb):     # the sequential answer is not the model's
            st = ST_SIMULTANEOUS
        if sec.resolver is not None and (st == ST_ZENO or (st == ST_SIMULTANEOUS
                                                           and self.joint == "resolve")):
            return self._resolved(k, z0, t0)
        mode_final = ha._name_of(int(ic[IC_MODE])) if st != ST_RETURNED else sec.mode
        if st != ST_RETURNED:
            return MapResult(np.full(self.dim, np.nan), False, MAP_STATUS[st], t0, t_hit,
                             z_hit, mode_final, jumps, any(j[4] == "grazing" for j in jumps))
        img = sec.from_state(z_hit, t_hit)
        m = modes[sec.mode_index]
        f_hit = m.A @ z_hit + m.b
        scale = np.abs(sec.c) @ np.abs(f_hit) + 1e-300
        grazing = (any(j[4] == "grazing" for j in jumps)
                   or abs(sec.c @ f_hit) <= 1e-9 * scale)
        DP = None
        if jacobian:
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                DP, tangent = self._jacobian(s, bufs, nb, z_hit)
            grazing = grazing or tangent
        return MapResult(img, True, "returned", t0, t_hit, z_hit, mode_final, jumps, grazing,
                         DP)

    def _resolved(self, k, z0, t0) -> MapResult:
        """``P^k`` by the simulator with the section's resolver: the application where the
        compiled run meets what only the resolver decides (a joint jump, or contacts that
        keep refiring at one instant), exactly as a simulation of the model takes it. The
        span grows from ``(k + 1/2)`` periods up to ``t_max``; ``DP`` is left to finite
        differences (no saltation matrix of a joint jump)."""
        sec = self.section
        ha = sec.automaton
        t_max = self._t_max(k)
        span = min((k + 0.5) * sec.period, t_max) if sec.has_phase else t_max
        while True:
            tr = ha.simulate(z0, sec.mode, (t0, t0 + span),
                             max_jumps=_RESOLVED * self.max_jumps, max_steps=self.max_steps,
                             zeno=self.zeno, resolver=sec.resolver,
                             simtol=1e-12 if self.simtol is None else self.simtol)
            J = tr.jumps
            hits = [i for i in range(len(J)) if J.source[i] == sec.mode
                    and J.guard[i] == sec.guard and J.kind[i] != "zeno"]
            if not hits or J.t[hits[0]] != t0:
                return MapResult(np.full(self.dim, np.nan), False, MAP_STATUS[ST_BAD_START],
                                 t0, t0, z0, sec.mode, (), False)
            ended = tr.termination is TerminationCause.END_TIME
            if len(hits) > k or not ended or span >= t_max:
                break
            span = min(2.0 * span, t_max)
        nb = hits[k] if len(hits) > k else len(J)
        jumps = tuple((float(J.t[q]), J.source[q], J.guard[q], J.target[q], J.kind[q])
                      for q in range(nb))
        grazing = any(j[4] == "grazing" for j in jumps)
        if len(hits) <= k:
            cause = tr.termination.name.lower()
            status = "nonfinite" if cause == "diverged" else cause
            return MapResult(np.full(self.dim, np.nan), False, status, t0, float(tr.t_final),
                             np.asarray(tr.x_final, float), tr.mode_final, jumps, grazing)
        z_hit, t_hit = J.pre[nb].copy(), float(J.t[nb])
        return MapResult(sec.from_state(z_hit, t_hit), True, "returned", t0, t_hit, z_hit,
                         sec.mode, jumps, grazing)

    def _joint_jump(self, bufs, nb) -> bool:
        """Whether one of the first ``nb`` jumps fired while another guard of its group was
        on its guard or closing onto it within ``simtol (1 + |t|)`` (the simulation's rule)."""
        pk = self._tables[0]
        if self.simtol is None or not self._groups.any():
            return False
        return _any_joint(pk, self._groups, bufs, int(nb), self.simtol)

    def _jacobian(self, s, bufs, nb, z_hit) -> np.ndarray:
        sec = self.section
        ha = sec.automaton
        modes, pk = ha._slim(), ha.packed     # the modes of the run are all built
        Z, tangent = sensitivity_chain(bufs, int(bufs.ic[IC_NS]), nb, modes, pk,
                                       np.eye(ha.n_states))[:2]
        mode = modes[sec.mode_index]
        f = mode.A @ z_hit + mode.b
        cf = sec.c @ f
        dtau = -(sec.c @ Z) / cf
        Zhit = Z + np.outer(f, dtau)
        E = sec.embedding(s)
        Dy = sec.C @ Zhit @ E
        if not sec.has_phase:
            return Dy, tangent
        row = dtau @ E
        row[0] += 1.0
        return np.vstack([row, Dy]), tangent
