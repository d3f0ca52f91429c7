"""The parts of a hybrid automaton: modes, affine guards with resets, Zeno options, stop causes.

:class:`Mode` (an affine flow and its guards), :class:`Guard` (an affine guard, its reset and
target), :class:`ZenoOptions` (detection of accumulating jumps) and :class:`TerminationCause`
(why a run stopped). Their semantics (event time, ties, the on-guard rule, Zeno switching)
are documented in :mod:`hybridpd.hybrid.automaton`, which assembles them.
"""
from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.hybrid._kernel import RunOptions

__all__ = ["Guard", "Mode", "TerminationCause", "ZenoOptions"]


class TerminationCause(enum.Enum):
    """Why a simulation stopped."""

    END_TIME = 0      #: reached the end of ``t_span``
    JUMP_LIMIT = 1    #: the next jump would exceed ``max_jumps``
    ZENO = 2          #: accumulation of jumps without a ``zeno_target`` (or an instant loop)
    NONFINITE = 3     #: the state overflowed / became NaN (unstable flow or reset)
    STEP_LIMIT = 4    #: ``max_steps`` flow steps taken
    SIMULTANEOUS = 7  #: a joint jump of a guard group that the resolver could not resolve
    DIVERGED = 8      #: the state grew past ``max_state`` (see :meth:`HybridAutomaton.simulate`)


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
        Mode entered when jumps of this guard accumulate (see
        :mod:`hybridpd.hybrid.automaton`).
    zeno_reset : (R, r), optional
        Reset applied at the accumulation time (default identity); only with ``zeno_target``.
    group : int
        Simultaneity group (default 0: none). When a guard of a non-zero group fires while
        another guard of the same group of its mode is on its guard (or closing onto it within
        the simultaneity tolerance), the joint jump is handed to the ``resolver`` of
        :meth:`HybridAutomaton.simulate` (without one the reset applies as usual).
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
    group: int = 0

    def __post_init__(self):
        if isinstance(self.group, bool) or not isinstance(self.group, (int, np.integer)) \
                or self.group < 0:
            raise ValueError(f"guard {self.name!r}: group must be an int >= 0")
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
    """Detection of accumulating jumps (see :mod:`hybridpd.hybrid.automaton`).

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
    tail_tol : float, optional
        Accept an accumulation found by its ratios only once the extrapolated tail
        ``t_inf - t_k`` is below ``tail_tol (1 + |t_k|)``; until then the jumps are resolved
        one by one (default ``None``: accept at once).
    """

    enabled: bool = True
    min_ratios: int = 3
    ratio_max: float = 0.99
    ratio_rtol: float = 0.02
    dt_min: float | None = None
    max_instant_jumps: int = 100
    tail_tol: float | None = None

    def __post_init__(self):
        if int(self.min_ratios) < 1:
            raise ValueError("zeno.min_ratios must be >= 1")
        if not (0.0 < float(self.ratio_max) < 1.0):
            raise ValueError("zeno.ratio_max must be in (0, 1)")
        if not (float(self.ratio_rtol) >= 0.0):
            raise ValueError("zeno.ratio_rtol must be >= 0")
        if self.dt_min is not None and not (float(self.dt_min) >= 0.0):
            raise ValueError("zeno.dt_min must be >= 0")
        if self.tail_tol is not None and not (float(self.tail_tol) >= 0.0):
            raise ValueError("zeno.tail_tol must be >= 0")
        if int(self.max_instant_jumps) < 1:
            raise ValueError("zeno.max_instant_jumps must be >= 1")

    def run_options(self, max_state: float = -1.0) -> RunOptions:
        """The options of the compiled jump loop (read by name there).

        Parameters
        ----------
        max_state : float
            Stop a run as diverged when a state component exceeds this in magnitude at the
            start of a flow (state units; ``<= 0``: never).

        Returns
        -------
        RunOptions
        """
        return RunOptions(float(self.ratio_max), float(self.ratio_rtol),
                          -1.0 if self.tail_tol is None else float(self.tail_tol),
                          float(max_state), bool(self.enabled), int(self.min_ratios),
                          int(self.max_instant_jumps))
