r"""A guard/reset hybrid automaton for LTI (affine) flows, with exact flows and Zeno handling.

Model
-----
A :class:`HybridAutomaton` has modes (:class:`Mode`) on a common state space ``z in R^n``. In a
mode the state flows by ``z' = A z + b`` (exactly: matrix exponential, see
:mod:`hybridpd.hybrid.events`). Each mode has affine guards (:class:`Guard`) ``g(z) = c . z + d``;
``direction = -1`` means the admissible side is ``g > 0`` and the guard *fires* when the flow
reaches ``g <= 0`` (``+1``: admissible ``g < 0``, fires at ``g >= 0``). Firing applies the affine
reset ``z+ = R z + r`` and switches to the guard's ``target`` mode. Time is hybrid time
``(t, j)``: ``j`` counts jumps, and several jumps may share one ``t``.

Conventions
-----------
* **Event time**: the first floating-point time at which the computed guard value is on the
  forbidden side (``kind='crossing'``), or the local extremum of a tangential touch that stays
  within the rounding bound (``kind='grazing'``; the reset is applied, which for an impact law
  is continuous at zero relative velocity). A near miss above the bound never fires. Crossings
  are never missed, however close together (see :mod:`hybridpd.hybrid.events`).
* **Simultaneous guards**: events within the time resolution are ties; the larger
  ``priority`` wins, then the earlier declared guard. The others are re-examined after the
  jump (on-guard rule below).
* **On the guard at the start of a flow** (after a reset, or initially): the first
  significant Taylor coefficient of ``g`` along the flow (``c A^k z``-type derivatives) decides:
  pointing into the admissible side means no event (a genuine return, e.g. a small rebound
  followed by a re-impact, is still found); pointing out means the guard fires at once; all
  derivatives zero means the guard cannot fire during this flow.
* **Zeno** (:class:`ZenoOptions`): consecutive jumps of the same self-loop guard
  (``target`` = its own mode) whose inter-jump times ``Delta_k`` shrink geometrically (the last
  ``min_ratios`` ratios ``r_k = Delta_k / Delta_{k-1}`` below ``ratio_max`` and each within
  ``ratio_rtol`` of the previous one), or a ``Delta_k <= dt_min``, are an accumulation at
  ``t_inf = t_k + Delta_k r / (1 - r)``. Right after a reset, a guard that fires again at once
  (its first non-zero derivative points out, e.g. restitution ``e = 0`` under a pressing force)
  is an immediate accumulation, ``t_inf = t_k``. If the guard declares a ``zeno_target``, the
  flow is continued in the current mode from ``t_k`` to ``t_inf`` (the remaining infinitely
  many, geometrically small jumps are not resolved), the ``zeno_reset`` is applied and the
  run continues in ``zeno_target`` (a jump of kind ``'zeno'``). Otherwise the run stops with
  cause ``ZENO`` at ``t_k``, and ``t_inf`` is recorded in ``zeno_times``. An accumulation
  predicted after the end time is ignored (the jumps before the end are resolved). More than
  ``max_instant_jumps`` consecutive jumps at one instant also end the run with ``ZENO``.
* **Bounds**: every loop is bounded (``max_jumps``, ``max_steps``, the bisection budget); the
  trajectory always says why it stopped (:class:`TerminationCause`). When the jump limit is
  reached the run stops at the event that would have been jump ``max_jumps + 1``, with the
  pre-jump state.

Numba kernel for reuse
----------------------
``run_hybrid(h, Phi, Ah, dinv, trunc, G, gabs, gsum, cnorm, prio, ng, Rh, target, zt, Rz, dt_min,
t_end, max_jumps, max_steps, zf, zi, w, fc, ic, jt, jj, jg, jsrc, jdst, jkind, jpre, jpost,
st0, st1, smode, sj, sw, zt_out) -> code``

The per-mode arrays are stacked over ``M`` modes and padded to ``GM`` guards
(:attr:`HybridAutomaton.packed`, a :class:`PackedAutomaton`): ``h (M,)``, ``Phi, Ah (M, N1, N1)``,
``dinv (M, N1)``, ``trunc (M,)``, ``G, gabs (M, GM, Kp1, N1)``, ``gsum (M, GM, N1)``,
``cnorm (M, GM)``, ``prio (M, GM) int64``, ``ng (M,) int64``, homogeneous resets
``Rh, Rz (M, GM, N1, N1)`` (``[[R, r], [0, 1]]``), ``target, zt (M, GM) int64`` (``zt = -1``: no
Zeno target), ``dt_min (M,)``. Scalars: ``t_end``, ``max_jumps``, ``max_steps``;
``zf = [ratio_max, ratio_rtol]``, ``zi = [enabled, min_ratios, max_instant_jumps]`` (int64).
Carried state (read and updated, so a full buffer can be resumed): ``w (N1,)`` homogeneous
state, ``fc (8,)`` float (``fc[0]`` time), ``ic (16,)`` int64 (``ic[0]`` mode, ``ic[1]`` jump
count ``j``, ``ic[2] = -1``, ``ic[3] = -1`` initially, ``ic[8]`` steps taken, ``ic[9..11]`` entries
written to the jump/segment/Zeno buffers, reset them to 0 before resuming). Output buffers
(capacity = first dimension): jumps ``jt, jj, jg, jsrc, jdst, jkind`` (kind 1 crossing,
2 grazing, 3 zeno), ``jpre, jpost (cap, N1)``; segments ``st0, st1, smode, sj, sw (cap, N1)``;
``zt_out`` Zeno times. ``code``: 0 end time, 1 jump limit, 2 Zeno, 3 non-finite, 4 step limit,
5 buffer full (resume with fresh or emptied buffers). A basin-of-attraction engine can call
it with small buffers and read only ``w``, ``fc[0]``, ``ic[0]``, ``ic[1]``.
"""
from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from hybridpd._jit import njit
from hybridpd._repr import compact_repr
from hybridpd.hybrid.events import (
    EV_GRAZING,
    EV_NONE,
    EV_NONFINITE,
    EV_START,
    EV_STEP_LIMIT,
    K_DEFAULT,
    THETA_DEFAULT,
    _matvec,
    advance,
    flow_eval,
    flow_to,
    prepare_lti_mode,
)

__all__ = [
    "Guard",
    "HybridAutomaton",
    "HybridTrajectory",
    "Jump",
    "JumpTable",
    "Mode",
    "PackedAutomaton",
    "Segment",
    "SegmentTable",
    "TerminationCause",
    "ZenoOptions",
    "run_hybrid",
]


class TerminationCause(enum.Enum):
    """Why a simulation stopped."""

    END_TIME = 0      #: reached the end of ``t_span``
    JUMP_LIMIT = 1    #: the next jump would exceed ``max_jumps``
    ZENO = 2          #: accumulation of jumps without a ``zeno_target`` (or an instant loop)
    NONFINITE = 3     #: the state overflowed / became NaN (unstable flow or reset)
    STEP_LIMIT = 4    #: ``max_steps`` flow steps taken


_RC_BUFFER_FULL = 5
_RC_STEP_LIMIT = 4
# A run that looks small (a span of at most this many flow steps, or at most this many jumps)
# starts interpreted while numba is not loaded (see hybridpd._jit; about 0.25 ms per step,
# 1 ms per jump), in chunks bounded by both; the run carries its state between chunks.
_INTERP_MAX_STEPS = 2000
_INTERP_JUMPS = 64
_KIND_NAMES = {1: "crossing", 2: "grazing", 3: "zeno"}


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class Guard:
    """An affine guard with its reset.

    Parameters
    ----------
    name : str
        Unique within its mode.
    c : array_like, shape (n,)
    d : float
        ``g(z) = c . z + d``.
    direction : {-1, +1}
        ``-1``: admissible side ``g > 0``, fires when ``g`` reaches ``<= 0``; ``+1``: admissible
        ``g < 0``, fires at ``>= 0``.
    reset : (R, r), optional
        ``z+ = R z + r`` with ``R`` shape ``(n, n)``, ``r`` shape ``(n,)``; default identity.
    target : str, optional
        Mode entered after the jump; default the guard's own mode.
    priority : int
        Larger wins when several guards fire at the same time.
    zeno_target : str, optional
        Mode entered when jumps of this guard accumulate (see module docstring).
    zeno_reset : (R, r), optional
        Reset applied at the accumulation time (default identity); only with ``zeno_target``.
    """

    __repr__ = compact_repr

    name: str
    c: np.ndarray
    d: float = 0.0
    direction: int = -1
    reset: tuple | None = None
    target: str | None = None
    priority: int = 0
    zeno_target: str | None = None
    zeno_reset: tuple | None = None

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"Guard name must be a non-empty string, got {self.name!r}")
        c = np.asarray(self.c, dtype=float)
        if c.ndim != 1:
            raise ValueError(f"guard {self.name!r}: c must be 1-D, got shape {c.shape}")
        if not np.all(np.isfinite(c)):
            raise ValueError(f"guard {self.name!r}: c must be finite")
        object.__setattr__(self, "c", c)
        try:
            d = float(self.d)
        except (TypeError, ValueError):
            raise ValueError(f"guard {self.name!r}: d must be a float") from None
        if not math.isfinite(d):
            raise ValueError(f"guard {self.name!r}: d must be finite")
        object.__setattr__(self, "d", d)
        if self.direction not in (-1, 1):
            raise ValueError(f"guard {self.name!r}: direction must be -1 or +1, "
                             f"got {self.direction!r}")
        if isinstance(self.priority, bool) or not isinstance(self.priority, (int, np.integer)):
            raise ValueError(f"guard {self.name!r}: priority must be an int")
        if self.zeno_reset is not None and self.zeno_target is None:
            raise ValueError(f"guard {self.name!r}: zeno_reset given without zeno_target")


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class Mode:
    """A mode: flow ``z' = A z + b`` and its guards.

    Parameters
    ----------
    name : str
    A : array_like, shape (n, n)
    b : array_like, shape (n,), optional
        Constant input (default zero).
    guards : sequence of Guard
    """

    __repr__ = compact_repr

    name: str
    A: np.ndarray
    b: np.ndarray | None = None
    guards: tuple = ()

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"Mode name must be a non-empty string, got {self.name!r}")
        A = np.asarray(self.A, dtype=float)
        if A.ndim != 2 or A.shape[0] != A.shape[1] or A.shape[0] == 0:
            raise ValueError(f"mode {self.name!r}: A must be square (n, n), got {A.shape}")
        if not np.all(np.isfinite(A)):
            raise ValueError(f"mode {self.name!r}: A must be finite")
        n = A.shape[0]
        object.__setattr__(self, "A", A)
        b = np.zeros(n) if self.b is None else np.asarray(self.b, dtype=float)
        if b.shape != (n,):
            raise ValueError(f"mode {self.name!r}: b must have shape ({n},), got {b.shape}")
        if not np.all(np.isfinite(b)):
            raise ValueError(f"mode {self.name!r}: b must be finite")
        object.__setattr__(self, "b", b)
        guards = tuple(self.guards)
        for g in guards:
            if not isinstance(g, Guard):
                raise ValueError(f"mode {self.name!r}: guards must be Guard instances")
        names = [g.name for g in guards]
        if len(set(names)) != len(names):
            raise ValueError(f"mode {self.name!r}: guard names must be unique, got {names}")
        object.__setattr__(self, "guards", guards)


@dataclass(frozen=True)
class ZenoOptions:
    """Detection of accumulating jumps (see the module docstring).

    Parameters
    ----------
    enabled : bool
        Detect accumulations (otherwise only ``max_jumps`` bounds a Zeno run).
    min_ratios : int
        Number of consecutive consistent ratios ``r_k = Delta_k / Delta_{k-1}`` required.
    ratio_max : float
        Ratios must be below this (``< 1``: shrinking intervals).
    ratio_rtol : float
        Consecutive ratios must agree to this relative tolerance.
    dt_min : float, optional
        Inter-jump time (time units) at or below which jumps on one guard are an accumulation
        regardless of the ratios; default ``1e-9`` times the mode's flow step.
    max_instant_jumps : int
        Consecutive jumps at the same instant allowed before stopping with ``ZENO``.
    """

    enabled: bool = True
    min_ratios: int = 3
    ratio_max: float = 0.99
    ratio_rtol: float = 0.02
    dt_min: float | None = None
    max_instant_jumps: int = 100

    def __post_init__(self):
        if int(self.min_ratios) < 1:
            raise ValueError("zeno.min_ratios must be >= 1")
        if not (0.0 < float(self.ratio_max) < 1.0):
            raise ValueError("zeno.ratio_max must be in (0, 1)")
        if not (float(self.ratio_rtol) >= 0.0):
            raise ValueError("zeno.ratio_rtol must be >= 0")
        if self.dt_min is not None and not (float(self.dt_min) >= 0.0):
            raise ValueError("zeno.dt_min must be >= 0")
        if int(self.max_instant_jumps) < 1:
            raise ValueError("zeno.max_instant_jumps must be >= 1")


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class Jump:
    """One jump: at hybrid time ``(t, j)`` (``j`` counts this jump), ``pre -> post``."""

    __repr__ = compact_repr

    t: float
    j: int
    guard: str
    pre: np.ndarray
    post: np.ndarray
    source: str
    target: str
    kind: str


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class JumpTable:
    """All jumps of a run, as arrays (index it for :class:`Jump` records).

    Attributes
    ----------
    t : ndarray, shape (m,)
        Jump times.
    j : ndarray of int, shape (m,)
        Jump counter after the jump (1, 2, ...).
    guard : tuple of str
        Guard that fired (for ``kind == 'zeno'``: the accumulating guard).
    pre, post : ndarray, shape (m, n)
        States before / after the reset.
    source, target : tuple of str
        Modes before / after.
    kind : tuple of str
        ``'crossing'``, ``'grazing'`` or ``'zeno'``.
    """

    __repr__ = compact_repr

    t: np.ndarray
    j: np.ndarray
    guard: tuple
    pre: np.ndarray
    post: np.ndarray
    source: tuple
    target: tuple
    kind: tuple

    def __len__(self):
        return int(self.t.size)

    def __getitem__(self, i) -> Jump:
        i = range(len(self))[i]
        return Jump(float(self.t[i]), int(self.j[i]), self.guard[i], self.pre[i].copy(),
                    self.post[i].copy(), self.source[i], self.target[i], self.kind[i])

    def __iter__(self):
        return (self[i] for i in range(len(self)))


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class Segment:
    """One flow segment on ``[t_start, t_end]`` in ``mode`` at jump count ``j``."""

    __repr__ = compact_repr

    t_start: float
    t_end: float
    mode: str
    j: int
    x_start: np.ndarray


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class SegmentTable:
    """All flow segments (possibly of zero length), as arrays.

    Attributes
    ----------
    t_start, t_end : ndarray, shape (m,)
    mode : tuple of str
    j : ndarray of int, shape (m,)
    x_start : ndarray, shape (m, n)
        State at ``t_start`` (after the jumps at that time).
    """

    __repr__ = compact_repr

    t_start: np.ndarray
    t_end: np.ndarray
    mode: tuple
    j: np.ndarray
    x_start: np.ndarray

    def __len__(self):
        return int(self.t_start.size)

    def __getitem__(self, i) -> Segment:
        i = range(len(self))[i]
        return Segment(float(self.t_start[i]), float(self.t_end[i]), self.mode[i],
                       int(self.j[i]), self.x_start[i].copy())

    def __iter__(self):
        return (self[i] for i in range(len(self)))


class PackedAutomaton(NamedTuple):
    """Stacked per-mode arrays (the inputs of :func:`run_hybrid`; see the module docstring)."""

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
    Rh: np.ndarray
    target: np.ndarray
    zt: np.ndarray
    Rz: np.ndarray


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class HybridTrajectory:
    """Result of :meth:`HybridAutomaton.simulate`.

    Attributes
    ----------
    t0, t_final : float
        Start and the time reached (``t_final`` is the end time unless the run stopped early).
    termination : TerminationCause
    segments : SegmentTable
        Flow segments in order; a segment of zero length marks jumps at one instant.
    jumps : JumpTable
    zeno_times : ndarray
        Estimated accumulation times (one per Zeno event, switched or terminating).
    x_final : ndarray, shape (n,)
        State at ``t_final`` (after any jumps there).
    mode_final : str
    j_final : int
        Number of jumps.
    n_steps : int
        Flow steps taken (exact matrix-exponential steps, not ODE steps).
    state_names : tuple of str

    Calling the trajectory, ``traj(t)`` (= :meth:`state_at`), gives the exact state at any
    time(s) in ``[t0, t_final]``, right-continuous at jumps.
    """

    __repr__ = compact_repr

    t0: float
    t_final: float
    termination: TerminationCause
    segments: SegmentTable
    jumps: JumpTable
    zeno_times: np.ndarray
    x_final: np.ndarray
    mode_final: str
    j_final: int
    n_steps: int
    state_names: tuple
    _automaton: HybridAutomaton = field(repr=False, compare=False, default=None)
    _seg_mode_idx: np.ndarray = field(repr=False, compare=False, default=None)
    _seg_w: np.ndarray = field(repr=False, compare=False, default=None)

    def _locate(self, t):
        ts = np.asarray(t, dtype=float)
        scalar = ts.ndim == 0
        ts = np.atleast_1d(ts)
        if ts.ndim != 1 or not np.all(np.isfinite(ts)):
            raise ValueError("t must be a finite scalar or 1-D array")
        if np.any(ts < self.t0) or np.any(ts > self.t_final):
            raise ValueError(f"t must lie in [t0, t_final] = [{self.t0!r}, {self.t_final!r}]")
        idx = np.searchsorted(self.segments.t_start, ts, side="right") - 1
        return ts, scalar, np.clip(idx, 0, len(self.segments) - 1)

    def state_at(self, t) -> np.ndarray:
        """Exact state(s) at time(s) ``t``: shape ``(n,)`` for a scalar, ``(m, n)`` otherwise."""
        ts, scalar, idx = self._locate(t)
        n = len(self.state_names)
        out = np.empty((ts.size, n))
        pk = self._automaton.packed
        Kp1 = pk.G.shape[2]
        for s in np.unique(idx):
            sel = np.nonzero(idx == s)[0]
            order = sel[np.argsort(ts[sel], kind="stable")]
            taus = np.maximum(ts[order] - self.segments.t_start[s], 0.0)
            m = int(self._seg_mode_idx[s])
            buf = np.empty((order.size, n + 1))
            flow_eval(self._seg_w[s], pk.h[m], pk.Phi[m], pk.Ah[m], Kp1,
                      np.ascontiguousarray(taus), buf)
            out[order] = buf[:, :n]
        # the run's own final state, bit for bit (the dense series may differ by rounding)
        out[ts == self.t_final] = self.x_final
        return out[0] if scalar else out

    __call__ = state_at

    def mode_at(self, t):
        """Mode name(s) at time(s) ``t`` (right-continuous)."""
        _, scalar, idx = self._locate(t)
        names = [self.segments.mode[i] for i in idx]
        return names[0] if scalar else names


# ----------------------------------------------------------------------------------------
# the compiled jump loop
# ----------------------------------------------------------------------------------------
@njit(cache=True)
def _add_seg(st0, st1, smode, sj, sw, ic, t0, t1, mode, j, w):
    si = ic[10]
    st0[si] = t0
    st1[si] = t1
    smode[si] = mode
    sj[si] = j
    for i in range(w.shape[0]):
        sw[si, i] = w[i]
    ic[10] = si + 1


@njit(cache=True)
def _add_jump(jt, jj, jg, jsrc, jdst, jkind, jpre, jpost, ic, t, j, g, src, dst, kind, pre,
              post):
    k = ic[9]
    jt[k] = t
    jj[k] = j
    jg[k] = g
    jsrc[k] = src
    jdst[k] = dst
    jkind[k] = kind
    for i in range(pre.shape[0]):
        jpre[k, i] = pre[i]
        jpost[k, i] = post[i]
    ic[9] = k + 1


@njit(cache=True)
def _finite(w):
    for i in range(w.shape[0]):
        if not math.isfinite(w[i]):
            return False
    return True


@njit(cache=True)
def _zeno_switch(mode, g, t_k, t_inf, h, Phi, Ah, Rz, zt, max_jumps, Kp1, w, fc, ic,
                 jt, jj, jg, jsrc, jdst, jkind, jpre, jpost, st0, st1, smode, sj, sw, zt_out):
    """Accumulation of guard ``g`` of ``mode`` at ``t_inf`` from state ``w`` at ``t_k``.

    Returns -1 to continue the run, else a termination code.
    """
    N1 = w.shape[0]
    zt_out[ic[11]] = t_inf
    ic[11] += 1
    target = zt[mode, g]
    if target < 0:
        _add_seg(st0, st1, smode, sj, sw, ic, t_k, t_k, mode, ic[1], w)
        return 2
    if ic[1] >= max_jumps:
        _add_seg(st0, st1, smode, sj, sw, ic, t_k, t_k, mode, ic[1], w)
        return 1
    wz = np.empty(N1)
    post = np.empty(N1)
    if t_inf > t_k:
        # the mode's own flow over the unresolved tail of the accumulation
        _add_seg(st0, st1, smode, sj, sw, ic, t_k, t_inf, mode, ic[1], w)
        flow_to(w, t_inf - t_k, h[mode], Phi[mode], Ah[mode], Kp1, wz)
    else:
        for i in range(N1):
            wz[i] = w[i]
    _matvec(Rz[mode, g], wz, post)
    post[N1 - 1] = 1.0
    ic[1] += 1
    _add_jump(jt, jj, jg, jsrc, jdst, jkind, jpre, jpost, ic, t_inf, ic[1], g, mode, target, 3,
              wz, post)
    for i in range(N1):
        w[i] = post[i]
    fc[0] = t_inf
    fc[1] = 0.0
    ic[0] = target
    ic[2] = -1
    ic[3] = -1
    ic[5] = 0
    ic[6] = 0
    ic[7] = 0
    if not _finite(post):
        _add_seg(st0, st1, smode, sj, sw, ic, t_inf, t_inf, target, ic[1], w)
        return 3
    return -1


@njit(cache=True)
def run_hybrid(h, Phi, Ah, dinv, trunc, G, gabs, gsum, cnorm, prio, ng, Rh, target, zt, Rz,
               dt_min, t_end, max_jumps, max_steps, zf, zi, w, fc, ic,
               jt, jj, jg, jsrc, jdst, jkind, jpre, jpost, st0, st1, smode, sj, sw, zt_out):
    """Run the automaton from the carried state; see the module docstring for the contract."""
    N1 = w.shape[0]
    Kp1 = G.shape[2]
    wout = np.empty(N1)
    post = np.empty(N1)
    ratio_max = zf[0]
    rtol = zf[1]
    zon = zi[0] != 0
    min_ratios = zi[1]
    max_inst = zi[2]
    while True:
        if (ic[9] + 2 > jt.shape[0] or ic[10] + 3 > st0.shape[0]
                or ic[11] + 2 > zt_out.shape[0]):
            return 5
        t = fc[0]
        mode = ic[0]
        si = ic[10]
        _add_seg(st0, st1, smode, sj, sw, ic, t, t, mode, ic[1], w)
        code, tev, g, nst, err = advance(
            w, t, t_end, h[mode], Phi[mode], Ah[mode], dinv[mode], trunc[mode], G[mode],
            gabs[mode], gsum[mode], cnorm[mode], prio[mode], ng[mode], ic[2], fc[1],
            max_steps - ic[8], wout)
        ic[8] += nst
        st1[si] = tev
        if code == EV_NONE or code == EV_NONFINITE or code == EV_STEP_LIMIT:
            for i in range(N1):
                w[i] = wout[i]
            fc[0] = tev
            if code == EV_NONE:
                return 0
            if code == EV_NONFINITE:
                return 3
            return 4
        if code == EV_START and g == ic[2] and zon:
            # immediate accumulation: the guard that just fired fires again at once
            rc = _zeno_switch(mode, g, t, t, h, Phi, Ah, Rz, zt, max_jumps, Kp1, w, fc, ic,
                              jt, jj, jg, jsrc, jdst, jkind, jpre, jpost, st0, st1, smode,
                              sj, sw, zt_out)
            if rc >= 0:
                return rc
            continue
        if ic[1] >= max_jumps:
            for i in range(N1):
                w[i] = wout[i]
            fc[0] = tev
            return 1
        _matvec(Rh[mode, g], wout, post)
        post[N1 - 1] = 1.0
        tgt = target[mode, g]
        kind = 2 if code == EV_GRAZING else 1
        ic[1] += 1
        _add_jump(jt, jj, jg, jsrc, jdst, jkind, jpre, jpost, ic, tev, ic[1], g, mode, tgt,
                  kind, wout, post)
        for i in range(N1):
            w[i] = post[i]
        fc[0] = tev
        ic[0] = tgt
        if tgt == mode:
            ic[2] = g
            fc[1] = err
        else:
            ic[2] = -1
            fc[1] = 0.0
        if not _finite(post):
            _add_seg(st0, st1, smode, sj, sw, ic, tev, tev, tgt, ic[1], w)
            return 3
        if not zon:
            continue
        if tev == t:
            ic[7] += 1
            if ic[7] > max_inst:
                zt_out[ic[11]] = tev
                ic[11] += 1
                _add_seg(st0, st1, smode, sj, sw, ic, tev, tev, tgt, ic[1], w)
                return 2
        else:
            ic[7] = 0
        if tgt != mode:
            ic[3] = -1
            continue
        if not (ic[3] == mode and ic[4] == g and ic[5] >= 1):
            ic[3] = mode
            ic[4] = g
            ic[5] = 1
            ic[6] = 0
            fc[2] = tev
            fc[3] = -1.0
            fc[4] = -1.0
            continue
        dt = tev - fc[2]
        if fc[3] > 0.0:
            r = dt / fc[3]
            if r < ratio_max:
                if ic[6] >= 1 and abs(r - fc[4]) <= rtol * fc[4]:
                    ic[6] += 1
                else:
                    ic[6] = 1
            else:
                ic[6] = 0
            fc[4] = r
        fc[3] = dt
        fc[2] = tev
        ic[5] += 1
        if dt <= dt_min[mode] or ic[6] >= min_ratios:
            r = fc[4]
            t_inf = tev
            if 0.0 < r < 1.0:
                t_inf = tev + dt * r / (1.0 - r)
            if dt <= dt_min[mode] and t_inf > t_end:
                t_inf = t_end
            if t_inf <= t_end:
                rc = _zeno_switch(mode, g, tev, t_inf, h, Phi, Ah, Rz, zt, max_jumps, Kp1, w,
                                  fc, ic, jt, jj, jg, jsrc, jdst, jkind, jpre, jpost, st0, st1,
                                  smode, sj, sw, zt_out)
                if rc >= 0:
                    return rc


# ----------------------------------------------------------------------------------------
# the automaton
# ----------------------------------------------------------------------------------------
def _reset_matrix(where, reset, n):
    Rh = np.eye(n + 1)
    if reset is None:
        return Rh
    try:
        R, r = reset
    except (TypeError, ValueError):
        raise ValueError(f"{where} must be a pair (R, r)") from None
    R = np.asarray(R, dtype=float)
    r = np.asarray(r, dtype=float)
    if R.shape != (n, n):
        raise ValueError(f"{where}: R must have shape ({n}, {n}), got {R.shape}")
    if r.shape != (n,):
        raise ValueError(f"{where}: r must have shape ({n},), got {r.shape}")
    if not (np.all(np.isfinite(R)) and np.all(np.isfinite(r))):
        raise ValueError(f"{where} must be finite")
    Rh[:n, :n] = R
    Rh[:n, n] = r
    return Rh


class HybridAutomaton:
    """Guard/reset hybrid automaton with exact LTI flows.

    Parameters
    ----------
    modes : sequence of Mode
        All modes share the state dimension ``n``; names are unique; guard targets name modes.
    state_names : sequence of str, optional
        Names of the ``n`` state components (default ``x0, x1, ...``).
    K : int
        Taylor order of the flow/guard series (default 20).
    theta : float
        Normalised flow step (default 1).

    Examples
    --------
    A ball bouncing on the floor (``e = 0.5``); the impacts accumulate at ``2 v0 / (g (1-e))``
    and the ball then rests:

    >>> import numpy as np
    >>> g, e = 9.81, 0.5
    >>> A = [[0.0, 1.0], [0.0, 0.0]]
    >>> bounce = Guard("floor", c=[1.0, 0.0], d=0.0, direction=-1,
    ...                reset=([[1, 0], [0, -e]], [0, 0]), target="flight",
    ...                zeno_target="rest", zeno_reset=(np.zeros((2, 2)), np.zeros(2)))
    >>> ha = HybridAutomaton([Mode("flight", A, b=[0.0, -g], guards=(bounce,)),
    ...                       Mode("rest", np.zeros((2, 2)))], state_names=("x", "v"))
    >>> traj = ha.simulate([0.0, 1.0], "flight", (0.0, 2.0))
    >>> traj.termination.name, traj.mode_final
    ('END_TIME', 'rest')
    >>> bool(abs(traj.zeno_times[0] - 2 * 1.0 / (g * (1 - e))) < 1e-12)
    True
    >>> traj(0.1).round(6)
    array([0.05095, 0.019  ])
    """

    def __init__(self, modes: Sequence[Mode], state_names=None, K: int = K_DEFAULT,
                 theta: float = THETA_DEFAULT):
        modes = tuple(modes)
        if not modes:
            raise ValueError("modes must contain at least one Mode")
        for m in modes:
            if not isinstance(m, Mode):
                raise ValueError(f"modes must be Mode instances, got {type(m).__name__}")
        names = [m.name for m in modes]
        if len(set(names)) != len(names):
            raise ValueError(f"modes: names must be unique, got {names}")
        n = modes[0].A.shape[0]
        for m in modes:
            if m.A.shape != (n, n):
                raise ValueError(f"modes: mode {m.name!r} has A of shape {m.A.shape}, "
                                 f"expected ({n}, {n}) like mode {modes[0].name!r}")
        if state_names is None:
            state_names = tuple(f"x{i}" for i in range(n))
        else:
            state_names = tuple(str(s) for s in state_names)
            if len(state_names) != n:
                raise ValueError(f"state_names must have {n} entries, got {len(state_names)}")
        index = {nm: i for i, nm in enumerate(names)}
        M = len(modes)
        GM = max(1, max(len(m.guards) for m in modes))
        N1 = n + 1
        Kp1 = int(K) + 1
        pk = {
            "h": np.zeros(M), "Phi": np.zeros((M, N1, N1)), "Ah": np.zeros((M, N1, N1)),
            "dinv": np.ones((M, N1)), "trunc": np.zeros(M), "G": np.zeros((M, GM, Kp1, N1)),
            "gabs": np.zeros((M, GM, Kp1, N1)), "gsum": np.zeros((M, GM, N1)),
            "cnorm": np.zeros((M, GM)), "prio": np.zeros((M, GM), np.int64),
            "ng": np.zeros(M, np.int64), "Rh": np.tile(np.eye(N1), (M, GM, 1, 1)),
            "target": np.zeros((M, GM), np.int64), "zt": np.full((M, GM), -1, np.int64),
            "Rz": np.tile(np.eye(N1), (M, GM, 1, 1))}
        for i, m in enumerate(modes):
            for gi, g in enumerate(m.guards):
                where = f"mode {m.name!r} guard {g.name!r}"
                if g.c.shape != (n,):
                    raise ValueError(f"{where}: c must have shape ({n},), got {g.c.shape}")
                tname = m.name if g.target is None else g.target
                if tname not in index:
                    raise ValueError(f"{where}: unknown target mode {tname!r}")
                pk["target"][i, gi] = index[tname]
                pk["Rh"][i, gi] = _reset_matrix(f"{where} reset", g.reset, n)
                if g.zeno_target is not None:
                    if g.zeno_target not in index:
                        raise ValueError(f"{where}: unknown zeno_target mode {g.zeno_target!r}")
                    pk["zt"][i, gi] = index[g.zeno_target]
                    pk["Rz"][i, gi] = _reset_matrix(f"{where} zeno_reset", g.zeno_reset, n)
            md = prepare_lti_mode(m.A, m.b, [(g.c, g.d, g.direction) for g in m.guards],
                                  K=K, theta=theta, priorities=[g.priority for g in m.guards])
            ngi = len(m.guards)
            pk["h"][i] = md.h
            pk["Phi"][i] = md.Phi
            pk["Ah"][i] = md.Ah
            pk["dinv"][i] = md.dinv
            pk["trunc"][i] = md.trunc
            pk["G"][i, :ngi] = md.G
            pk["gabs"][i, :ngi] = md.gabs
            pk["gsum"][i, :ngi] = md.gsum
            pk["cnorm"][i, :ngi] = md.cnorm
            pk["prio"][i, :ngi] = md.prio
            pk["ng"][i] = ngi
        self._modes = modes
        self._index = index
        self._n = n
        self._state_names = state_names
        self._packed = PackedAutomaton(**pk)

    @property
    def modes(self) -> tuple:
        """The modes, in order (their index is the mode code of the kernels)."""
        return self._modes

    @property
    def mode_names(self) -> tuple:
        return tuple(m.name for m in self._modes)

    @property
    def n_states(self) -> int:
        return self._n

    @property
    def state_names(self) -> tuple:
        return self._state_names

    @property
    def packed(self) -> PackedAutomaton:
        """Stacked arrays for :func:`run_hybrid` (read-only by convention)."""
        return self._packed

    def mode_index(self, name: str) -> int:
        """Index of the mode called ``name`` (``ValueError`` if unknown)."""
        try:
            return self._index[name]
        except (KeyError, TypeError):
            raise ValueError(f"unknown mode {name!r}; modes are {self.mode_names}") from None

    def simulate(self, x0, mode0: str, t_span, max_jumps: int = 10_000,
                 max_steps: int | None = None, zeno: ZenoOptions | None = None
                 ) -> HybridTrajectory:
        """Simulate from ``x0`` in ``mode0`` over ``t_span``.

        Parameters
        ----------
        x0 : array_like, shape (n,)
            Initial state (finite).
        mode0 : str
            Initial mode name.
        t_span : (float, float)
            ``(t0, t1)`` with ``t0 < t1`` (time units of the flow matrices).
        max_jumps : int
            Maximum number of jumps (``>= 0``), Zeno switches included.
        max_steps : int, optional
            Maximum number of exact flow steps (default ``10**7``).
        zeno : ZenoOptions, optional
            Accumulation detection (default :class:`ZenoOptions()`).

        Returns
        -------
        HybridTrajectory
        """
        n = self._n
        x0 = np.asarray(x0, dtype=float)
        if x0.shape != (n,):
            raise ValueError(f"x0 must have shape ({n},), got {x0.shape}")
        if not np.all(np.isfinite(x0)):
            raise ValueError("x0 must be finite")
        mi = self.mode_index(mode0)
        try:
            t0, t1 = (float(v) for v in t_span)
        except (TypeError, ValueError):
            raise ValueError(f"t_span must be a pair (t0, t1), got {t_span!r}") from None
        if not (math.isfinite(t0) and math.isfinite(t1)):
            raise ValueError("t_span must be finite")
        if not t1 > t0:
            raise ValueError(f"t_span must be increasing (t0 < t1), got {(t0, t1)!r}")
        if isinstance(max_jumps, bool) or int(max_jumps) != max_jumps or max_jumps < 0:
            raise ValueError(f"max_jumps must be an int >= 0, got {max_jumps!r}")
        max_jumps = int(max_jumps)
        if max_steps is None:
            max_steps = 10_000_000
        if isinstance(max_steps, bool) or int(max_steps) != max_steps or max_steps < 1:
            raise ValueError(f"max_steps must be an int >= 1, got {max_steps!r}")
        max_steps = int(max_steps)
        if zeno is None:
            zeno = ZenoOptions()
        if not isinstance(zeno, ZenoOptions):
            raise ValueError("zeno must be a ZenoOptions instance")
        pk = self._packed
        dt_min = (pk.h * 1e-9 if zeno.dt_min is None
                  else np.full(len(self._modes), float(zeno.dt_min)))
        zf = np.array([zeno.ratio_max, zeno.ratio_rtol], dtype=float)
        zi = np.array([int(bool(zeno.enabled)), int(zeno.min_ratios),
                       int(zeno.max_instant_jumps)], dtype=np.int64)
        N1 = n + 1
        w = np.append(x0, 1.0)
        fc = np.zeros(8)
        fc[0] = t0
        ic = np.zeros(16, np.int64)
        ic[0] = mi
        ic[2] = -1
        ic[3] = -1
        chunks = []
        cap = min(max_jumps + 4, 2048)
        small = (t1 - t0) <= _INTERP_MAX_STEPS * float(np.min(pk.h)) or max_jumps <= _INTERP_JUMPS
        while True:
            interp = small and run_hybrid.prefer_interpreter()
            steps = min(max_steps, int(ic[8]) + _INTERP_MAX_STEPS) if interp else max_steps
            if interp:
                cap = min(cap, _INTERP_JUMPS + 4)
            bufs = {
                "jt": np.empty(cap), "jj": np.empty(cap, np.int64), "jg": np.empty(cap, np.int64),
                "jsrc": np.empty(cap, np.int64), "jdst": np.empty(cap, np.int64),
                "jkind": np.empty(cap, np.int64), "jpre": np.empty((cap, N1)),
                "jpost": np.empty((cap, N1)), "st0": np.empty(cap + 2), "st1": np.empty(cap + 2),
                "smode": np.empty(cap + 2, np.int64), "sj": np.empty(cap + 2, np.int64),
                "sw": np.empty((cap + 2, N1)), "zt_out": np.empty(cap)}
            ic[9:12] = 0
            run = run_hybrid.interpret if interp else run_hybrid
            rc = run(pk.h, pk.Phi, pk.Ah, pk.dinv, pk.trunc, pk.G, pk.gabs, pk.gsum, pk.cnorm,
                     pk.prio, pk.ng, pk.Rh, pk.target, pk.zt, pk.Rz, dt_min, t1, max_jumps,
                     steps, zf, zi, w, fc, ic, **bufs)
            nj, ns, nz = int(ic[9]), int(ic[10]), int(ic[11])
            chunks.append({k: (v[:nj] if k.startswith("j") else v[:ns] if k.startswith("s")
                               else v[:nz]) for k, v in bufs.items()})
            if rc != _RC_BUFFER_FULL and not (rc == _RC_STEP_LIMIT and steps < max_steps):
                break
            cap = min(max(max_jumps - int(ic[1]), 0) + 4, 65536)
        cat = {k: np.concatenate([c[k] for c in chunks]) for k in chunks[0]}
        return self._make_trajectory(t0, rc, cat, w, fc, ic)

    def _make_trajectory(self, t0, rc, cat, w, fc, ic) -> HybridTrajectory:
        n = self._n
        mn = self.mode_names
        gnames = [[g.name for g in m.guards] for m in self._modes]
        jsrc = cat["jsrc"]
        jumps = JumpTable(
            t=cat["jt"].copy(), j=cat["jj"].copy(),
            guard=tuple(gnames[s][g] for s, g in zip(jsrc, cat["jg"])),
            pre=cat["jpre"][:, :n].copy(), post=cat["jpost"][:, :n].copy(),
            source=tuple(mn[s] for s in jsrc), target=tuple(mn[d] for d in cat["jdst"]),
            kind=tuple(_KIND_NAMES[int(k)] for k in cat["jkind"]))
        segs = SegmentTable(t_start=cat["st0"].copy(), t_end=cat["st1"].copy(),
                            mode=tuple(mn[m] for m in cat["smode"]), j=cat["sj"].copy(),
                            x_start=cat["sw"][:, :n].copy())
        return HybridTrajectory(
            t0=t0, t_final=float(fc[0]), termination=TerminationCause(int(rc)),
            segments=segs, jumps=jumps, zeno_times=cat["zt_out"].copy(),
            x_final=w[:n].copy(), mode_final=mn[int(ic[0])], j_final=int(ic[1]),
            n_steps=int(ic[8]), state_names=self._state_names, _automaton=self,
            _seg_mode_idx=cat["smode"].copy(), _seg_w=np.ascontiguousarray(cat["sw"]))
