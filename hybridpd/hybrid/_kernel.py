"""The compiled jump loop of :class:`hybridpd.hybrid.automaton.HybridAutomaton`: ``run_hybrid``.

The loop alternates exact flows to the next event (:func:`hybridpd.hybrid.events.advance`)
with resets, records jumps and segments in caller-provided buffers and detects Zeno
accumulations (semantics: :mod:`hybridpd.hybrid.automaton`). Also here: the packed kernel
inputs (:class:`PackedAutomaton`) and the return and jump-kind codes. The kernels are
compiled lazily (:mod:`hybridpd._jit`).

Calling contract
----------------
``run_hybrid(pk, dt_min, t_end, max_jumps, max_steps, opts, rb) -> code``, with ``pk`` the
tables (a :class:`PackedAutomaton`), ``opts`` the run's options (a :class:`RunOptions`, made by
:meth:`ZenoOptions.run_options <hybridpd.hybrid.modes.ZenoOptions.run_options>`) and ``rb``
the carried state and record buffers (a :class:`RunBuffers`); the kernels read all three by
name.

The per-mode arrays are stacked over ``M`` modes and padded to ``GM`` guards
(:attr:`HybridAutomaton.packed`, a :class:`PackedAutomaton`): ``h (M,)``, ``Phi, Ah (M, N1, N1)``,
``dinv (M, N1)``, ``trunc (M,)``, ``G, gabs (M, GM, Kp1, N1)``, ``gsum (M, GM, N1)``,
``cnorm (M, GM)``, ``prio (M, GM) int64``, ``ng (M,) int64``, the distinct homogeneous
resets ``R (P, N1, N1)`` (``[[R, r], [0, 1]]``; many guards share one, so each is stored once)
and each guard's row in it, ``rh, rz (M, GM) int64`` (reset, Zeno reset),
``target, zt (M, GM) int64`` (``zt = -1``: no Zeno target), ``dt_min (M,)``. Scalars:
``t_end``, ``max_jumps``, ``max_steps``; options ``opts.zeno_on``, ``opts.min_ratios``,
``opts.ratio_max``, ``opts.ratio_rtol``, ``opts.max_instant_jumps`` (accumulations, see
:class:`~hybridpd.hybrid.modes.ZenoOptions`).
Carried state (read and updated, so a full buffer can be resumed): ``w (N1,)`` homogeneous
state, ``fc (8,)`` float (``fc[0]`` time), ``ic (18,)`` int64 (``ic[0]`` mode, ``ic[1]`` jump
count ``j``, ``ic[2] = -1``, ``ic[3] = -1`` initially, ``ic[8]`` steps taken, ``ic[9..11]`` entries
written to the jump/segment/Zeno buffers, reset them to 0 before resuming). Output buffers
(capacity = first dimension): jumps ``jt, jj, jg, jsrc, jdst, jkind`` (kind 1 crossing,
2 grazing, 3 zeno), ``jpre, jpost (cap, N1)``; segments ``st0, st1, smode, sj, sw (cap, N1)``;
``zt_out`` Zeno times. ``code``: 0 end time, 1 jump limit, 2 Zeno, 3 non-finite, 4 step limit,
5 buffer full (resume with fresh or emptied buffers). A basin-of-attraction engine can call
it with small buffers and read only ``w``, ``fc[0]``, ``ic[0]``, ``ic[1]``. With
``opts.tail_tol >= 0`` an accumulation detected by its ratios is accepted only once the
extrapolated tail ``t_inf - t_k`` is below ``tail_tol (1 + |t_k|)`` (more jumps are resolved
until then); a negative ``tail_tol`` accepts it at once. ``opts.max_state > 0`` stops the run
with code 8 (diverged) when a state component exceeds it in magnitude at the start of a flow.

``run_hybrid_ex(pk, ..., rb, groups)`` adds two returns to the same loop, with ``groups`` a
:class:`JointGroups` (``gkind, simtol, gid, fired``):
code 6 when the current mode ``ic[0]`` is not built: a target (or Zeno target) ``-2 - r``
names the mode reserved as number ``r`` (the jump is applied and recorded with that code as
target, then the loop returns; build the mode, set ``ic[0]`` to its index, patch the tables
and resume), and code 7
when a guard of non-zero group ``gkind[mode, g]`` (shape ``(M, GM)``) fires while another
guard of the same group is on its guard or closing onto it within ``simtol (1 + |t|)``: the
joint jump is then the caller's (``w`` holds the pre-jump state, ``fc[0]`` its time and
``ic[12]`` the guard; apply the jump, set ``ic[0]``, ``ic[2] = ic[3] = -1`` and resume).
``simtol < 0`` disables the groups. ``gid (M, GM)`` names each guard across modes and
``fired`` holds the guards of groups fired at the current instant ``fc[5]`` (``ic[14]`` of
them): a guard of a group that fires there after ``_REFIRE_AFTER`` firings of it returns
code 7 with ``ic[13] = 1`` (the joint jump then resolves the contacts' accumulation;
``ic[15]`` counts those at the instant, ``fc[6]`` is the start of the flow that ended
there).

Code 6 also comes back (in both loops) from a Zeno switch whose reset is not packed yet
(``rz[mode, g] = -1``): the jump is recorded with the state flowed to the accumulation time
as its post state, ``ic[16] = mode + 1``, ``ic[17] = g``; the caller applies the reset to
``w`` (and the recorded post state), packs it, sets ``ic[16] = 0`` and resumes (building
``ic[0]`` first if it is a reserved code). ``ic`` has at least 18 entries.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from hybridpd._jit import njit
from hybridpd.hybrid.events import (
    EV_GRAZING,
    EV_NONE,
    EV_NONFINITE,
    EV_START,
    EV_STEP_LIMIT,
    FlowTables,
    _matvec,
    advance,
    flow_to,
)

__all__ = ["JointGroups", "PackedAutomaton", "RunBuffers", "RunOptions", "run_hybrid",
           "run_hybrid_ex"]

_RC_BUFFER_FULL = 5
_RC_STEP_LIMIT = 4
_RC_NEED_MODE = 6
_RC_SIMULTANEOUS = 7
_RC_DIVERGED = 8
_KIND_NAMES = {1: "crossing", 2: "grazing", 3: "zeno", 4: "simultaneous"}
#: Entries of the carried integer state ``ic`` (module docstring): the mode, the jump count,
#: the guard whose start event is suppressed, the burst being tracked for an accumulation
#: (its mode, guard, length and run of equal ratios), the jumps at the current instant, the
#: flow steps taken, the entries written to the jump/segment/Zeno buffers, the guard of a
#: joint jump handed back and whether it refired, the guards of groups fired at the instant
#: and the joint jumps there, and the Zeno reset to apply (mode + 1, guard).
(IC_MODE, IC_JUMPS, IC_LAST_GUARD, IC_BURST_MODE, IC_BURST_GUARD, IC_BURST_LEN, IC_RATIOS,
 IC_INSTANT, IC_STEPS, IC_NJ, IC_NS, IC_NZ, IC_JOINT_GUARD, IC_REFIRE, IC_FIRED, IC_JOINTS,
 IC_LAZY_MODE, IC_LAZY_GUARD) = range(18)
#: Entries of the carried float state ``fc``: the time, the last event's location error,
#: the tracked burst's last jump time, interval and ratio, the current instant of group
#: firings, and the start of the flow that ended there.
FC_T, FC_LOC_ERR, FC_BURST_T, FC_BURST_DT, FC_BURST_RATIO, FC_INSTANT, FC_FLOW_START = range(7)
# a guard of a group firing at one instant after this many firings of it there goes to the
# resolver: a short cascade of impacts (a contact hit twice) stays in the loop, impacts
# that keep coming back are resolved together
_REFIRE_AFTER = 2


class PackedAutomaton(NamedTuple):
    """Stacked per-mode arrays (the inputs of :func:`run_hybrid`; see the module docstring).

    ``Rh[m, g]`` and ``Rz[m, g]`` (also with further indices) are the homogeneous reset and
    Zeno reset of guard ``g`` of mode ``m``: rows of the shared table ``R``.
    """

    h: np.ndarray
    Phi: np.ndarray
    Ah: np.ndarray
    dinv: np.ndarray
    trunc: np.ndarray
    G: np.ndarray
    gabs: np.ndarray
    gsum: np.ndarray
    cnorm: np.ndarray
    prio: np.ndarray
    ng: np.ndarray
    R: np.ndarray
    rh: np.ndarray
    target: np.ndarray
    zt: np.ndarray
    rz: np.ndarray

    @property
    def Rh(self) -> _Resets:
        return _Resets(self.R, self.rh)

    @property
    def Rz(self) -> _Resets:
        return _Resets(self.R, self.rz)


class RunOptions(NamedTuple):
    """The options of one run of the jump loop, read by name in the kernels (module
    docstring). Made by :meth:`ZenoOptions.run_options
    <hybridpd.hybrid.modes.ZenoOptions.run_options>`; the types are fixed (floats, a bool,
    ints) so that every run shares one compiled specialisation.

    Attributes
    ----------
    ratio_max, ratio_rtol : float
        Ratios of consecutive inter-jump times below ``ratio_max`` that agree to
        ``ratio_rtol`` (relative) make an accumulation.
    tail_tol : float
        Accept an accumulation once its extrapolated tail is below ``tail_tol (1 + |t|)``
        (negative: at once).
    max_state : float
        Stop (code 8) when a state component exceeds it in magnitude at the start of a flow
        (non-positive: never).
    zeno_on : bool
        Detect accumulations.
    min_ratios : int
        Consistent ratios required.
    max_instant_jumps : int
        Jumps at one instant allowed before stopping with code 2.
    """

    ratio_max: float
    ratio_rtol: float
    tail_tol: float
    max_state: float
    zeno_on: bool
    min_ratios: int
    max_instant_jumps: int


class JointGroups(NamedTuple):
    """The simultaneity groups of :func:`run_hybrid_ex` (module docstring).

    Attributes
    ----------
    gkind : ndarray of int64, shape (M, GM)
        Group of each guard (0: none).
    simtol : float
        Relative time within which another guard of the group closing onto its guard makes
        the jump joint (negative: groups off).
    gid : ndarray of int64, shape (M, GM)
        Identity of each guard across modes.
    fired : ndarray of int64, shape (F,)
        The guards of groups fired at the current instant (written).
    """

    gkind: np.ndarray
    simtol: float
    gid: np.ndarray
    fired: np.ndarray


class _Resets:
    """``[m, g, ...]`` -> ``R[rows[m, g], ...]``: the resets of every guard, as if stacked."""

    def __init__(self, R, rows):
        self._R, self._rows = R, rows

    @property
    def shape(self) -> tuple:
        return self._rows.shape + self._R.shape[1:]

    def __getitem__(self, key):
        key = key if isinstance(key, tuple) else (key,)
        if len(key) < 2:
            raise IndexError("index the resets by [mode, guard, ...]")
        return self._R[(self._rows[key[0], key[1]],) + key[2:]]


class RunBuffers(NamedTuple):
    """The carried state and the record buffers of one run of the jump loop (module
    docstring): ``w (N1,)``, ``fc (8,)``, ``ic (18,) int64``; jumps ``jt, jj, jg, jsrc, jdst,
    jkind (cap,)``, ``jpre, jpost (cap, N1)``; segments ``st0, st1, smode, sj (cap + 2,)``,
    ``sw (cap + 2, N1)``; Zeno times ``zt_out (cap,)``. The kernels read them by name."""

    w: np.ndarray
    fc: np.ndarray
    ic: np.ndarray
    jt: np.ndarray
    jj: np.ndarray
    jg: np.ndarray
    jsrc: np.ndarray
    jdst: np.ndarray
    jkind: np.ndarray
    jpre: np.ndarray
    jpost: np.ndarray
    st0: np.ndarray
    st1: np.ndarray
    smode: np.ndarray
    sj: np.ndarray
    sw: np.ndarray
    zt_out: np.ndarray

    @classmethod
    def empty(cls, cap: int, n1: int, w=None, fc=None, ic=None) -> RunBuffers:
        """Buffers for ``cap`` jumps of states of length ``n1`` (the carried ``w``, ``fc``,
        ``ic`` fresh unless given)."""
        i64 = np.int64
        return cls(np.empty(n1) if w is None else w, np.zeros(8) if fc is None else fc,
                   np.zeros(18, i64) if ic is None else ic, np.empty(cap),
                   *(np.empty(cap, i64) for _ in range(5)), np.empty((cap, n1)),
                   np.empty((cap, n1)), np.empty(cap + 2), np.empty(cap + 2),
                   np.empty(cap + 2, i64), np.empty(cap + 2, i64), np.empty((cap + 2, n1)),
                   np.empty(cap))

    def records(self) -> dict:
        """Copies of what the run recorded (jumps, segments, Zeno times), by name."""
        nj, ns, nz = int(self.ic[IC_NJ]), int(self.ic[IC_NS]), int(self.ic[IC_NZ])
        return {k: (v[:nj] if k.startswith("j") else v[:ns] if k.startswith("s")
                    else v[:nz]).copy() for k, v in self._asdict().items()
                if k not in ("w", "fc", "ic")}



@njit(cache=True)
def _add_seg(rb, t0, t1, mode, j, w):
    st0, st1, smode, sj, sw, ic = rb.st0, rb.st1, rb.smode, rb.sj, rb.sw, rb.ic
    si = ic[IC_NS]
    st0[si] = t0
    st1[si] = t1
    smode[si] = mode
    sj[si] = j
    for i in range(w.shape[0]):
        sw[si, i] = w[i]
    ic[IC_NS] = si + 1


@njit(cache=True)
def _add_jump(rb, t, g, src, dst, kind, pre, post):
    """Record a jump (its count: the carried jump count ``ic[1]``)."""
    jt, jj, jg, jsrc, jdst, jkind, jpre, jpost, ic = (rb.jt, rb.jj, rb.jg, rb.jsrc, rb.jdst,
                                                      rb.jkind, rb.jpre, rb.jpost, rb.ic)
    k = ic[IC_NJ]
    jt[k] = t
    jj[k] = ic[IC_JUMPS]
    jg[k] = g
    jsrc[k] = src
    jdst[k] = dst
    jkind[k] = kind
    for i in range(pre.shape[0]):
        jpre[k, i] = pre[i]
        jpost[k, i] = post[i]
    ic[IC_NJ] = k + 1


@njit(cache=True)
def _finite(w):
    for i in range(w.shape[0]):
        if not math.isfinite(w[i]):
            return False
    return True


@njit(cache=True)
def _zeno_switch(pk, rb, mode, g, t_k, t_inf, max_jumps, Kp1):
    """Accumulation of guard ``g`` of ``mode`` at ``t_inf`` from state ``rb.w`` at ``t_k``.

    Returns -1 to continue the run, else a termination code.
    """
    h, Phi, Ah, R, rz, zt = pk.h, pk.Phi, pk.Ah, pk.R, pk.rz, pk.zt
    w, fc, ic, zt_out = rb.w, rb.fc, rb.ic, rb.zt_out
    N1 = w.shape[0]
    zt_out[ic[IC_NZ]] = t_inf
    ic[IC_NZ] += 1
    target = zt[mode, g]
    if target == -1:
        _add_seg(rb, t_k, t_k, mode, ic[IC_JUMPS], w)
        return 2
    if ic[IC_JUMPS] >= max_jumps:
        _add_seg(rb, t_k, t_k, mode, ic[IC_JUMPS], w)
        return 1
    wz = np.empty(N1)
    post = np.empty(N1)
    if t_inf > t_k:
        # the mode's own flow over the unresolved tail of the accumulation
        _add_seg(rb, t_k, t_inf, mode, ic[IC_JUMPS], w)
        flow_to(w, t_inf - t_k, h[mode], Phi[mode], Ah[mode], Kp1, wz)
    else:
        for i in range(N1):
            wz[i] = w[i]
    lazy = rz[mode, g] < 0
    if lazy:
        # the Zeno reset is not packed yet: the jump is recorded with the state at t_inf
        # and handed back (code 6, ic[16] = mode + 1, ic[17] = g), the caller applies it
        for i in range(N1):
            post[i] = wz[i]
    else:
        _matvec(R[rz[mode, g]], wz, post)
    post[N1 - 1] = 1.0
    ic[IC_JUMPS] += 1
    _add_jump(rb, t_inf, g, mode, target, 3, wz, post)
    for i in range(N1):
        w[i] = post[i]
    fc[FC_T] = t_inf
    fc[FC_LOC_ERR] = 0.0
    ic[IC_MODE] = target
    ic[IC_LAST_GUARD] = -1
    ic[IC_BURST_MODE] = -1
    ic[IC_BURST_LEN] = 0
    ic[IC_RATIOS] = 0
    if t_inf > t_k:
        ic[IC_INSTANT] = 0           # an instant accumulation still counts towards an instant loop
    else:
        ic[IC_INSTANT] += 1
    if lazy:
        ic[IC_LAZY_MODE] = mode + 1
        ic[IC_LAZY_GUARD] = g
        return _RC_NEED_MODE
    if not _finite(post):
        _add_seg(rb, t_inf, t_inf, target, ic[IC_JUMPS], w)
        return 3
    return -1


@njit(cache=True)
def _mode_tables(pk, mode):
    """The tables of ``mode`` that :func:`~hybridpd.hybrid.events.advance` reads."""
    return FlowTables(pk.h[mode], pk.Phi[mode], pk.Ah[mode], pk.dinv[mode], pk.trunc[mode],
                      pk.G[mode], pk.gabs[mode], pk.gsum[mode], pk.cnorm[mode], pk.prio[mode],
                      pk.ng[mode])


@njit(cache=True)
def run_hybrid_ex(pk, dt_min, t_end, max_jumps, max_steps, opts, rb, groups):
    """:func:`run_hybrid` with modes built on demand and simultaneity groups (module docstring)."""
    h, G, ng, R, rh, target = pk.h, pk.G, pk.ng, pk.R, pk.rh, pk.target
    w, fc, ic, jt, st0, st1, zt_out = rb.w, rb.fc, rb.ic, rb.jt, rb.st0, rb.st1, rb.zt_out
    # One function on purpose: numba compiles the whole jump loop into one native loop.
    N1 = w.shape[0]
    Kp1 = G.shape[2]
    wout = np.empty(N1)
    post = np.empty(N1)
    ratio_max, rtol, tail_tol = opts.ratio_max, opts.ratio_rtol, opts.tail_tol
    zon, min_ratios, max_inst = opts.zeno_on, opts.min_ratios, opts.max_instant_jumps
    max_state = opts.max_state
    gkind, simtol, gid, fired = groups.gkind, groups.simtol, groups.gid, groups.fired
    ft_mode = 0
    ft = _mode_tables(pk, 0)
    while True:
        if (ic[IC_NJ] + 2 > jt.shape[0] or ic[IC_NS] + 3 > st0.shape[0]
                or ic[IC_NZ] + 2 > zt_out.shape[0]):
            return 5
        if ic[IC_MODE] < 0 or ng[ic[IC_MODE]] < 0:
            return _RC_NEED_MODE
        if max_state > 0.0:
            for i in range(N1 - 1):
                if abs(w[i]) > max_state:
                    _add_seg(rb, fc[FC_T], fc[FC_T], ic[IC_MODE], ic[IC_JUMPS], w)
                    return _RC_DIVERGED
        t = fc[FC_T]
        mode = ic[IC_MODE]
        si = ic[IC_NS]
        _add_seg(rb, t, t, mode, ic[IC_JUMPS], w)
        if mode != ft_mode:
            # the mode's tables, gathered again only when the mode changes
            ft = _mode_tables(pk, mode)
            ft_mode = mode
        code, tev, g, nst, err = advance(w, t, t_end, ft, ic[IC_LAST_GUARD], fc[FC_LOC_ERR],
                                         max_steps - ic[IC_STEPS], wout)
        ic[IC_STEPS] += nst
        st1[si] = tev
        if code == EV_NONE or code == EV_NONFINITE or code == EV_STEP_LIMIT:
            for i in range(N1):
                w[i] = wout[i]
            fc[FC_T] = tev
            if code == EV_NONE:
                return 0
            if code == EV_NONFINITE:
                return 3
            return 4
        if code == EV_START and g == ic[IC_LAST_GUARD] and zon:
            # immediate accumulation: the guard that just fired fires again at once
            rc = _zeno_switch(pk, rb, mode, g, t, t, max_jumps, Kp1)
            if rc >= 0:
                return rc
            continue
        if ic[IC_JUMPS] >= max_jumps:
            for i in range(N1):
                w[i] = wout[i]
            fc[FC_T] = tev
            return 1
        if simtol >= 0.0 and gkind[mode, g] != 0:
            again = _fired_before(gid[mode, g], tev, fc, ic, fired) >= _REFIRE_AFTER
            if again or _other_active(G[mode], ng[mode], gkind[mode], g, wout, h[mode],
                                      simtol * (1.0 + abs(tev))):
                for i in range(N1):
                    w[i] = wout[i]
                fc[FC_T] = tev
                fc[FC_FLOW_START] = t
                ic[IC_JOINT_GUARD] = g
                ic[IC_REFIRE] = 1 if again else 0
                return _RC_SIMULTANEOUS
            _note_fired(gid[mode, g], ic, fired)
        _matvec(R[rh[mode, g]], wout, post)
        post[N1 - 1] = 1.0
        tgt = target[mode, g]
        kind = 2 if code == EV_GRAZING else 1
        ic[IC_JUMPS] += 1
        _add_jump(rb, tev, g, mode, tgt, kind, wout, post)
        for i in range(N1):
            w[i] = post[i]
        fc[FC_T] = tev
        ic[IC_MODE] = tgt
        if tgt == mode:
            ic[IC_LAST_GUARD] = g
            fc[FC_LOC_ERR] = err
        else:
            ic[IC_LAST_GUARD] = -1
            fc[FC_LOC_ERR] = 0.0
        if not _finite(post):
            _add_seg(rb, tev, tev, tgt, ic[IC_JUMPS], w)
            return 3
        if not zon:
            continue
        if tev == t:
            ic[IC_INSTANT] += 1
            if ic[IC_INSTANT] > max_inst:
                zt_out[ic[IC_NZ]] = tev
                ic[IC_NZ] += 1
                _add_seg(rb, tev, tev, tgt, ic[IC_JUMPS], w)
                return 2
        else:
            ic[IC_INSTANT] = 0
        if tgt != mode:
            ic[IC_BURST_MODE] = -1
            continue
        if not (ic[IC_BURST_MODE] == mode and ic[IC_BURST_GUARD] == g and ic[IC_BURST_LEN] >= 1):
            ic[IC_BURST_MODE] = mode
            ic[IC_BURST_GUARD] = g
            ic[IC_BURST_LEN] = 1
            ic[IC_RATIOS] = 0
            fc[FC_BURST_T] = tev
            fc[FC_BURST_DT] = -1.0
            fc[FC_BURST_RATIO] = -1.0
            continue
        dt = tev - fc[FC_BURST_T]
        if fc[FC_BURST_DT] > 0.0:
            r = dt / fc[FC_BURST_DT]
            if r < ratio_max:
                if ic[IC_RATIOS] >= 1 and abs(r - fc[FC_BURST_RATIO]) <= rtol * fc[FC_BURST_RATIO]:
                    ic[IC_RATIOS] += 1
                else:
                    ic[IC_RATIOS] = 1
            else:
                ic[IC_RATIOS] = 0
            fc[FC_BURST_RATIO] = r
        fc[FC_BURST_DT] = dt
        fc[FC_BURST_T] = tev
        ic[IC_BURST_LEN] += 1
        if dt <= dt_min[mode] or ic[IC_RATIOS] >= min_ratios:
            r = fc[FC_BURST_RATIO]
            t_inf = tev
            if 0.0 < r < 1.0:
                t_inf = tev + dt * r / (1.0 - r)
            if tail_tol >= 0.0 and dt > dt_min[mode] and t_inf - tev > tail_tol * (1.0 + abs(tev)):
                # the extrapolated tail is still too long to trust the ratio: resolve more
                continue
            if dt <= dt_min[mode] and t_inf > t_end:
                t_inf = t_end
            if t_inf <= t_end:
                rc = _zeno_switch(pk, rb, mode, g, tev, t_inf, max_jumps, Kp1)
                if rc >= 0:
                    return rc


@njit(cache=True)
def _fired_before(me, tev, fc, ic, fired):
    """How often the guard of identity ``me`` has fired already at the instant ``tev``.

    The guards of groups that fired at one instant ``fc[5]`` are kept in ``fired[:ic[14]]``
    (beyond its capacity further ones are not kept: the instant-jump bound still holds);
    a later instant starts afresh (``ic[15]``, the joint jumps of the instant, too).
    """
    if fc[FC_INSTANT] != tev:
        fc[FC_INSTANT] = tev
        ic[IC_FIRED] = 0
        ic[IC_JOINTS] = 0
        return 0
    count = 0
    for q in range(min(ic[IC_FIRED], fired.shape[0])):
        if fired[q] == me:
            count += 1
    return count


@njit(cache=True)
def _note_fired(me, ic, fired):
    if ic[IC_FIRED] < fired.shape[0]:
        fired[ic[IC_FIRED]] = me
    ic[IC_FIRED] += 1


@njit(cache=True)
def _other_active(Gm, ngm, gk, g, w, hm, tau):
    """Whether another guard of group ``gk[g]`` is on its guard at ``w`` or reaches it within
    ``tau`` (time units) while closing: the jump must then be resolved jointly."""
    N1 = w.shape[0]
    for q in range(ngm):
        if q == g or gk[q] != gk[g]:
            continue
        f = 0.0
        fa = 0.0
        d1 = 0.0
        d1a = 0.0
        for j in range(N1):
            f += Gm[q, 0, j] * w[j]
            fa += abs(Gm[q, 0, j] * w[j])
            d1 += Gm[q, 1, j] * w[j]
            d1a += abs(Gm[q, 1, j] * w[j])
        if d1 > 64.0 * 2.220446049250313e-16 * d1a:
            continue                      # separating: it takes no part
        if f <= 64.0 * 2.220446049250313e-16 * fa + max(-d1, 0.0) / hm * tau:
            return True
    return False


@njit(cache=True)
def run_hybrid(pk, dt_min, t_end, max_jumps, max_steps, opts, rb):
    """Run the automaton from the carried state; see the module docstring for the contract."""
    none = JointGroups(np.zeros((1, 1), np.int64), -1.0, np.zeros((1, 1), np.int64),
                       np.zeros(1, np.int64))
    return run_hybrid_ex(pk, dt_min, t_end, max_jumps, max_steps, opts, rb, none)
