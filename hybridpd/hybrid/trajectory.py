"""The result of a hybrid run: jumps, flow segments and the trajectory with exact dense output.

:class:`JumpTable` (of :class:`Jump` records) and :class:`SegmentTable` (of :class:`Segment`
records) hold a run as arrays; :class:`HybridTrajectory` adds the final state, the stop
cause and the exact state at any time (the mode's flow from the segment start).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.hybrid.events import flow_eval
from hybridpd.hybrid.modes import TerminationCause

if TYPE_CHECKING:
    from hybridpd.hybrid.automaton import HybridAutomaton

__all__ = ["HybridTrajectory", "Jump", "JumpTable", "Segment", "SegmentTable"]


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
    reason : str
        Why the run stopped before the end time, in one line (the bound reached, the guard
        or the instant involved); empty when it reached the end time.

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
    reason: str = ""
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
        pk = self._automaton._packed_now()
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
