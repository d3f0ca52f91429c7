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
  With ``ZenoOptions.tail_tol`` an accumulation found by its ratios is accepted only once the
  extrapolated tail ``t_inf - t_k`` is below ``tail_tol (1 + |t_k|)``; the jumps before are
  resolved one by one. An immediate accumulation counts towards ``max_instant_jumps``.
* **Modes on demand**: with a ``mode_builder`` a mode is built (flow prepared, guards
  packed into the kernel's tables) the first time a run enters it or a caller names it; a
  guard naming a mode not built yet carries a reservation code, and the jump loop hands
  control back to build it. :meth:`HybridAutomaton.materialize` builds every reachable mode
  (iterating ``modes`` does so first, for analyses that need them all); ``packed`` holds the
  tables of the modes built so far, and every map of a section builds modes as it enters
  them, as a simulation does.
* **Simultaneity groups**: a guard of a non-zero ``group`` that fires while another guard of
  its group is on its guard (or closing onto it within ``simtol (1 + |t|)``) hands the joint
  jump to the ``resolver`` of :meth:`HybridAutomaton.simulate` (jumps of kind
  ``'simultaneous'``, one per guard the resolver names, all at one instant); a resolver that
  finds no joint jump stops the run with ``SIMULTANEOUS``. A guard of a group that fires
  again at an instant where it (a guard of the same name, in any mode) has fired already is
  handed to the resolver too, with ``refire = 1, 2, ...`` (how often this happened at the
  instant): impacts that keep coming back in no time accumulate, and the resolver resolves
  them together (it may answer with kind ``'zeno'``). The resolver's jumps count towards
  ``max_instant_jumps`` like the loop's own, so a joint jump that changes nothing cannot
  repeat without bound.
* **Divergence**: with ``max_state`` the run stops with ``DIVERGED`` when a state component
  exceeds it at a jump or the start of a flow.
* **Bounds**: every loop is bounded (``max_jumps``, ``max_steps``, the bisection budget); the
  trajectory always says why it stopped (:class:`TerminationCause`, and in one line
  :attr:`HybridTrajectory.reason`). When the jump limit is
  reached the run stops at the event that would have been jump ``max_jumps + 1``, with the
  pre-jump state.

Modules
-------
This module holds :class:`HybridAutomaton` (building, packing, :meth:`~HybridAutomaton.simulate`)
and re-exports everything public of :mod:`hybridpd.hybrid.modes` (:class:`Mode`,
:class:`Guard`, :class:`ZenoOptions`, :class:`TerminationCause`),
:mod:`hybridpd.hybrid.trajectory` (:class:`HybridTrajectory`, :class:`JumpTable`,
:class:`SegmentTable`, :class:`Jump`, :class:`Segment`) and :mod:`hybridpd.hybrid._kernel`
(``run_hybrid``, the numba jump loop for reuse, e.g. by a basin-of-attraction engine, and its
inputs :class:`PackedAutomaton`, :class:`RunOptions` and :class:`JointGroups`; the calling
contract is documented there).
"""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from hybridpd.hybrid._kernel import (
    _KIND_NAMES,
    _RC_BUFFER_FULL,
    _RC_NEED_MODE,
    _RC_SIMULTANEOUS,
    _RC_STEP_LIMIT,
    FC_FLOW_START,
    FC_LOC_ERR,
    FC_T,
    IC_BURST_MODE,
    IC_FIRED,
    IC_INSTANT,
    IC_JOINT_GUARD,
    IC_JOINTS,
    IC_JUMPS,
    IC_LAST_GUARD,
    IC_LAZY_GUARD,
    IC_LAZY_MODE,
    IC_MODE,
    IC_NJ,
    IC_NZ,
    IC_REFIRE,
    IC_STEPS,
    JointGroups,
    PackedAutomaton,
    RunBuffers,
    RunOptions,
    run_hybrid,
    run_hybrid_ex,
)
from hybridpd.hybrid._store import ModeStore, reset_matrix
from hybridpd.hybrid.events import K_DEFAULT, THETA_DEFAULT
from hybridpd.hybrid.modes import Guard, Mode, TerminationCause, ZenoOptions
from hybridpd.hybrid.trajectory import (
    HybridTrajectory,
    Jump,
    JumpTable,
    Segment,
    SegmentTable,
)

__all__ = [
    "Guard",
    "HybridAutomaton",
    "HybridTrajectory",
    "JointGroups",
    "Jump",
    "JumpTable",
    "Mode",
    "PackedAutomaton",
    "RunOptions",
    "Segment",
    "SegmentTable",
    "TerminationCause",
    "ZenoOptions",
    "run_hybrid",
    "run_hybrid_ex",
]


# A run that looks small (a span of at most this many flow steps, or at most this many jumps)
# starts interpreted while numba is not loaded (see hybridpd._jit; about 0.25 ms per step,
# 1 ms per jump), in chunks bounded by both; the run carries its state between chunks.
_INTERP_MAX_STEPS = 2000
_INTERP_JUMPS = 64
# guards of simultaneity groups remembered per instant (to see one fire again there)
_FIRED_CAP = 64



def _check_modes(modes) -> tuple:
    """``modes`` as a tuple of :class:`Mode` with unique names and one state dimension."""
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
    return modes


def _check_run_args(t_span, max_jumps, max_steps, zeno):
    """Validated ``(t0, t1, max_jumps, max_steps, zeno)`` of :meth:`HybridAutomaton.simulate`."""
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
    if max_steps is None:
        max_steps = 10_000_000
    if isinstance(max_steps, bool) or int(max_steps) != max_steps or max_steps < 1:
        raise ValueError(f"max_steps must be an int >= 1, got {max_steps!r}")
    if zeno is None:
        zeno = ZenoOptions()
    if not isinstance(zeno, ZenoOptions):
        raise ValueError("zeno must be a ZenoOptions instance")
    return t0, t1, int(max_jumps), int(max_steps), zeno


class HybridAutomaton:
    """Guard/reset hybrid automaton with exact LTI flows.

    Parameters
    ----------
    modes : sequence of Mode
        All modes share the state dimension ``n``; names are unique; guard targets name modes
        (of this list, or modes that ``mode_builder`` builds).
    state_names : sequence of str, optional
        Names of the ``n`` state components (default ``x0, x1, ...``).
    K : int
        Taylor order of the flow/guard series (default 20).
    theta : float
        Normalised flow step (default 1).
    mode_builder : callable, optional
        ``mode_builder(name) -> Mode``: builds a mode the first time a run enters it (or names
        it as a target); it raises ``ValueError`` for a name that is no mode. With a builder,
        memory and set-up grow with the modes visited, not with all modes (see
        :meth:`materialize`).
    max_modes : int
        Bound on the number of modes :meth:`materialize` builds (default 4096).
    zeno : ZenoOptions, optional
        The accumulation rules of this automaton (default :class:`ZenoOptions()`): used by
        :meth:`simulate` and by every map of a section of it
        (:class:`~hybridpd.analysis.hybridmap.SectionMap`) unless they are given others, so
        that a map and a simulation of one automaton resolve an accumulation alike.

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
                 theta: float = THETA_DEFAULT, mode_builder=None, max_modes: int = 4096,
                 zeno: ZenoOptions | None = None):
        modes = _check_modes(modes)
        if zeno is not None and not isinstance(zeno, ZenoOptions):
            raise ValueError("zeno must be a ZenoOptions instance")
        self.zeno = ZenoOptions() if zeno is None else zeno
        n = modes[0].A.shape[0]
        if state_names is None:
            state_names = tuple(f"x{i}" for i in range(n))
        else:
            state_names = tuple(str(s) for s in state_names)
            if len(state_names) != n:
                raise ValueError(f"state_names must have {n} entries, got {len(state_names)}")
        if mode_builder is not None and not callable(mode_builder):
            raise ValueError("mode_builder must be callable (name -> Mode)")
        if isinstance(max_modes, bool) or int(max_modes) != max_modes or max_modes < 1:
            raise ValueError(f"max_modes must be an int >= 1, got {max_modes!r}")
        self._n = n
        self._state_names = state_names
        self._builder = mode_builder
        self._max_modes = int(max_modes)
        self._store = ModeStore(n, K, theta)
        self._index = {}                 # name -> row of a built mode
        self._names = []                 # row -> name
        self._built = []                 # row -> Mode, its guards without resets (_full)
        self._full_cache = {}            # row -> Mode with resets, the last few asked for
        # a builder that gives a guard's Zeno reset on its own: those are packed when first
        # used (most Zeno targets are never entered, their resets would be most of the tables)
        self._lazy_zeno = callable(getattr(mode_builder, "zeno_reset", None))
        self._reserved = {}              # name -> reservation number r (target code -2 - r)
        self._res_names = []             # r -> name
        self._code_rows = {}             # target code -> row, once built
        given = {m.name: m for m in modes}
        for m in modes:
            self._reserve(m.name)
        for m in modes:
            if m.name not in self._index:
                self._build(m.name, given)

    # ---- modes on demand
    def _reserve(self, name, where=None) -> int:
        """Row of the mode ``name`` if built, else its reservation code ``-2 - r``."""
        i = self._index.get(name)
        if i is not None:
            return i
        r = self._reserved.get(name)
        if r is None:
            if self._builder is None and where is not None:
                raise ValueError(f"{where}: unknown target mode {name!r}")
            r = len(self._res_names)
            self._reserved[name] = r
            self._res_names.append(name)
        return -2 - r

    def _build(self, name, given=None) -> int:
        """Build the mode ``name`` into a new row (``ValueError`` if it is no mode)."""
        m = given.get(name) if given else None
        if m is None:
            if self._builder is None:
                raise ValueError(f"unknown mode {name!r}; modes are {tuple(self._names)}")
            m = self._builder(name)
            if not isinstance(m, Mode) or m.name != name:
                raise ValueError(f"mode_builder({name!r}) must return a Mode named {name!r}")
            if m.A.shape != (self._n, self._n):
                raise ValueError(f"mode {name!r}: A must have shape ({self._n}, {self._n})")
        if self._builder is not None and given is None and len(self._names) >= self._max_modes:
            raise ValueError(
                f"max_modes: more than {self._max_modes} modes would be built; simulate builds "
                "the modes it visits, an analysis of every mode needs them all")
        row = self._store.add(m, self._reserve, lazy_zeno=self._lazy_zeno)
        self._index[name] = row
        self._names.append(name)
        # the resets live in the packed tables (stored once each, shared between modes);
        # a mode keeps its guards without them (mode() puts them back), so that an automaton
        # with many modes does not hold every reset matrix twice
        self._built.append(dataclasses.replace(m, guards=tuple(
            dataclasses.replace(g, reset=None, zeno_reset=None) for g in m.guards)))
        r = self._reserved.get(name)
        if r is not None:
            self._store.patch(-2 - r, row)
            self._code_rows[-2 - r] = row
        return row

    def materialize(self) -> int:
        """Build every mode reachable from the modes built so far; returns the mode count.

        Raises
        ------
        ValueError
            If more than ``max_modes`` modes would be built.
        """
        # names before _mat_upto are built already: the frequent call on a complete automaton
        # (every access to modes, mode_names, packed) costs nothing
        r = getattr(self, "_mat_upto", 0)
        while r < len(self._res_names):
            name = self._res_names[r]
            if name not in self._index:
                self._build(name)
            r += 1
        self._mat_upto = r
        return len(self._names)

    @property
    def n_built(self) -> int:
        """Number of modes built so far."""
        return len(self._built)

    @property
    def table_bytes(self) -> int:
        """Memory of the packed tables (bytes)."""
        return self._store.nbytes

    @property
    def modes(self) -> Sequence:
        """The modes, in order (their index is the mode code of the kernels).

        Indexing a mode that is built (an index a kernel or :meth:`mode_index` gave) builds
        nothing; its length, iteration or any other index build every reachable mode first
        (:meth:`materialize`). :attr:`built_mode_names` names the modes built so far. The
        guards' resets are read back from the packed tables, where each is stored once.
        """
        return _Modes(self)

    def _slim(self) -> list:
        """The modes built so far, their guards without resets (flows, guard rows, names and
        targets: what an analysis reads besides the packed tables; nothing is built)."""
        return self._built

    def _zeno_reset(self, i, gi) -> np.ndarray:
        """The homogeneous Zeno reset of guard ``gi`` of mode ``i``, packed if it was not."""
        pk = self._store.packed()
        if pk.rz[i, gi] < 0:
            where = f"mode {self._names[i]!r} guard {self._built[i].guards[gi].name!r}"
            self._store.set_zeno(i, gi, reset_matrix(
                f"{where} zeno_reset", self._builder.zeno_reset(
                    self._names[i], self._built[i].guards[gi].name), self._n))
            pk = self._store.packed()
        return pk.Rz[i, gi]

    def _full(self, i) -> Mode:
        """Built mode ``i`` with its guards' resets, from the packed tables."""
        m = self._full_cache.pop(i, None)
        if m is None:
            n = self._n
            pk = self._store.packed()
            guards = []
            for gi, g in enumerate(self._built[i].guards):
                Rh = pk.Rh[i, gi]
                zr = None
                if g.zeno_target is not None:
                    Rz = self._zeno_reset(i, gi)
                    zr = (Rz[:n, :n].copy(), Rz[:n, n].copy())
                guards.append(dataclasses.replace(g, reset=(Rh[:n, :n].copy(), Rh[:n, n].copy()),
                                                  zeno_reset=zr))
            m = dataclasses.replace(self._built[i], guards=tuple(guards))
        self._full_cache[i] = m                 # the most recent few, most recent last
        while len(self._full_cache) > 16:
            self._full_cache.pop(next(iter(self._full_cache)))
        return m

    def _name_of(self, code) -> str:
        """Name of the mode of row or reservation code ``code`` (a run may stop right after
        a jump into a mode not built yet, e.g. on the instant-jump bound)."""
        return self._names[code] if code >= 0 else self._res_names[-2 - int(code)]

    @property
    def built_mode_names(self) -> tuple:
        """Names of the modes built so far, in order (nothing is built)."""
        return tuple(self._names)

    def build_code(self, code: int) -> int:
        """Build the mode a kernel reported as not built (its target code ``< -1``, the
        kernels' return code 6 with ``ic[0] = code``) and return its index."""
        r = -2 - int(code)
        if not 0 <= r < len(self._res_names):
            raise ValueError(f"code must be a reserved mode code (< -1), got {code!r}")
        return self.mode_index(self._res_names[r])

    def guard_names(self) -> tuple:
        """Sorted names of the guards of every mode: declared by the mode builder (its
        ``guard_names`` attribute, when it has one) or found by :meth:`materialize`."""
        declared = getattr(self._builder, "guard_names", None)
        if declared is not None:
            return tuple(sorted(set(declared)))
        self.materialize()
        return tuple(sorted({g.name for m in self._built for g in m.guards}))

    @property
    def mode_names(self) -> tuple:
        self.materialize()
        return tuple(self._names)

    @property
    def n_states(self) -> int:
        return self._n

    @property
    def state_names(self) -> tuple:
        return self._state_names

    @property
    def packed(self) -> PackedAutomaton:
        """Stacked arrays for :func:`run_hybrid` over the modes built so far (read-only by
        convention). A target or Zeno target ``< -1`` names a mode not built yet: the jump
        loop returns code 6 on entering it (:meth:`build_code` builds it; the tables are then
        new arrays). Call :meth:`materialize` first for the tables of every mode."""
        return self._store.packed()

    def _packed_now(self) -> PackedAutomaton:
        """The tables of the modes built so far (targets ``< -1``: reserved modes)."""
        return self._store.packed()

    def mode_index(self, name: str) -> int:
        """Index of the mode called ``name``, built on demand (``ValueError`` if unknown)."""
        i = self._index.get(name) if isinstance(name, str) else None
        if i is None:
            if self._builder is None or not isinstance(name, str):
                raise ValueError(f"unknown mode {name!r}; modes are {tuple(self._names)}")
            i = self._build(name)
        return i

    def mode(self, name: str) -> Mode:
        """The mode called ``name`` (built on demand)."""
        return self._full(self.mode_index(name))

    def simulate(self, x0, mode0: str, t_span, max_jumps: int = 10_000,
                 max_steps: int | None = None, zeno: ZenoOptions | None = None,
                 resolver=None, simtol: float = 1e-12, max_state: float | None = None
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
            Accumulation detection (default the automaton's own, :attr:`zeno`).
        resolver : callable, optional
            ``resolver(mode, guard, t, z) -> (z_post, target, names)`` for a guard of a
            non-zero ``group`` that fires while another of its group is active (see
            :class:`Guard`): ``z`` the pre-jump state (shape ``(n,)``), ``names`` the guard
            names to record (one jump of kind ``'simultaneous'`` each, all at ``t`` with the
            joint post state). It returns ``None`` when the joint jump has no solution: the
            run stops there with ``SIMULTANEOUS``. A guard of the group that fires again at
            one instant is handed over as ``resolver(mode, guard, t, z, refire=k)`` (module
            docstring); the answer may then carry a fourth entry, the kind ``'zeno'`` (an
            accumulation resolved) or ``'simultaneous'``. Without a resolver groups are
            ignored.
        simtol : float
            Guards of a group closing within ``simtol (1 + |t|)`` are simultaneous.
        max_state : float, optional
            Stop with ``DIVERGED`` when a state component exceeds this in magnitude (checked
            at every jump and flow start).

        Returns
        -------
        HybridTrajectory
        """
        x0 = np.asarray(x0, dtype=float)
        if x0.shape != (self._n,):
            raise ValueError(f"x0 must have shape ({self._n},), got {x0.shape}")
        if not np.all(np.isfinite(x0)):
            raise ValueError("x0 must be finite")
        mi = self.mode_index(mode0)
        t0, t1, max_jumps, max_steps, zeno = _check_run_args(
            t_span, max_jumps, max_steps, self.zeno if zeno is None else zeno)
        if max_state is not None and not (float(max_state) > 0):
            raise ValueError(f"max_state must be > 0, got {max_state!r}")
        w = np.append(x0, 1.0)
        fc = np.zeros(8)
        fc[FC_T] = t0
        ic = np.zeros(18, np.int64)
        ic[IC_MODE] = mi
        ic[IC_LAST_GUARD] = -1
        ic[IC_BURST_MODE] = -1
        opts = (zeno, resolver, float(simtol), -1.0 if max_state is None else float(max_state))
        rc, cat = self._run_chunks(t0, t1, max_jumps, max_steps, opts, w, fc, ic)
        traj = self._make_trajectory(t0, rc, cat, w, fc, ic)
        reason = _stop_reason(traj, max_jumps, max_steps, zeno)
        return traj if not reason else dataclasses.replace(traj, reason=reason)

    def _run_chunks(self, t0, t1, max_jumps, max_steps, opts, w, fc, ic):
        """Run the jump loop from the carried state ``(w, fc, ic)`` until it stops.

        Buffers that fill up are resumed with fresh ones, modes not built yet are built when
        entered, joint jumps go to the resolver; a small run is interpreted in chunks (see
        ``_INTERP_MAX_STEPS``). Returns the kernel's code and the concatenated records.
        """
        zeno, resolver, simtol, max_state = opts
        run_opts = zeno.run_options(max_state)
        N1 = self._n + 1
        chunks = []
        cap = min(max_jumps + 4, 2048)
        pk = self._store.packed()
        hmin = float(np.min(pk.h))
        small = (t1 - t0) <= _INTERP_MAX_STEPS * hmin or max_jumps <= _INTERP_JUMPS
        if resolver is None:
            simtol = -1.0
        fired = np.zeros(_FIRED_CAP, np.int64)
        bufs = None
        while True:
            pk = self._store.packed()
            gk = self._store.gkind() if simtol >= 0 else None
            dt_min = (pk.h * 1e-9 if zeno.dt_min is None
                      else np.full(pk.h.shape[0], float(zeno.dt_min)))
            # without groups the plain loop (the same code) is the kernel to compile
            kern = run_hybrid if simtol < 0 else run_hybrid_ex
            extra = () if simtol < 0 else (JointGroups(gk, simtol, self._store.gid(), fired),)
            interp = small and kern.prefer_interpreter()
            steps = min(max_steps, int(ic[IC_STEPS]) + _INTERP_MAX_STEPS) if interp else max_steps
            if interp:
                cap = min(cap, _INTERP_JUMPS + 4)
            if bufs is None or bufs.jt.shape[0] != cap:
                bufs = RunBuffers.empty(cap, N1, w, fc, ic)
            ic[IC_NJ:IC_NZ + 1] = 0
            run = kern.interpret if interp else kern
            rc = run(pk, dt_min, t1, max_jumps, steps, run_opts, bufs, *extra)
            # the records are copied out: the buffers serve the next chunk, and a run that
            # returns often (joint jumps, modes built) holds only what it recorded
            chunks.append(bufs.records())
            if rc == _RC_NEED_MODE:
                if ic[IC_LAZY_MODE]:
                    self._apply_zeno(w, ic, chunks[-1])
                if ic[IC_MODE] < 0:
                    ic[IC_MODE] = self.build_code(int(ic[IC_MODE]))
                continue
            if rc == _RC_SIMULTANEOUS:
                if int(ic[IC_JUMPS]) >= max_jumps:
                    rc = 1
                    break
                rc = self._resolve(resolver, w, fc, ic, chunks, fired, int(zeno.max_instant_jumps))
                if rc is not None:
                    break
                continue
            if rc == _RC_BUFFER_FULL or (rc == _RC_STEP_LIMIT and steps < max_steps):
                cap = min(max(max_jumps - int(ic[IC_JUMPS]), 0) + 4, 65536)
                continue
            break
        names = []
        for c in chunks:
            names.extend(c.pop("jname") if "jname" in c else [None] * len(c["jt"]))
        # one record at a time, each chunk's part let go as it is joined: the peak is the
        # records once and one of them twice, not all twice
        cat = {k: np.concatenate([c.pop(k) for c in chunks]) for k in list(chunks[0])}
        cat["jname"] = names
        return rc, cat

    def _apply_zeno(self, w, ic, chunk) -> None:
        """Apply the Zeno reset the jump loop handed back (``ic[16] = mode + 1``, ``ic[17]``
        the guard) to ``w`` and to the post state of the last jump recorded."""
        Rz = self._zeno_reset(int(ic[IC_LAZY_MODE]) - 1, int(ic[IC_LAZY_GUARD]))
        w[:] = Rz @ w
        w[-1] = 1.0
        chunk["jpost"][-1] = w
        ic[IC_LAZY_MODE] = 0

    def _resolve(self, resolver, w, fc, ic, chunks, fired, max_inst):
        """Apply the resolver's joint jump to the carried state.

        Returns ``None`` to resume the run, else its termination code: ``SIMULTANEOUS`` when
        the resolver has no joint jump, ``ZENO`` past ``max_instant_jumps`` jumps at one
        instant (the joint jumps count like the kernel's own).
        """
        n = self._n
        mode = int(ic[IC_MODE])
        g = int(ic[IC_JOINT_GUARD])
        src = self._names[mode]
        t = float(fc[FC_T])
        gname = self._built[mode].guards[g].name
        if ic[IC_REFIRE]:
            # a guard of the group fires again at this instant: the resolver is told how
            # often this happened, so that it can resolve the contacts' accumulation
            ic[IC_JOINTS] += 1
            out = resolver(src, gname, t, w[:n].copy(), refire=int(ic[IC_JOINTS]))
        else:
            out = resolver(src, gname, t, w[:n].copy())
        if out is None:
            return TerminationCause.SIMULTANEOUS.value
        z_post, target, names, *more = out
        kind = more[0] if more else "simultaneous"
        if kind not in ("simultaneous", "zeno") or not names:
            raise ValueError("resolver must return (z_post, target, names[, kind]) with at "
                             "least one name and kind 'simultaneous' or 'zeno'")
        z_post = np.asarray(z_post, dtype=float)
        tgt = self.mode_index(target)
        k = len(names)
        pre = w.copy()
        post = np.append(z_post, 1.0)
        zeno = kind == "zeno"
        chunks.append({
            "jt": np.full(k, t), "jj": int(ic[IC_JUMPS]) + 1 + np.arange(k, dtype=np.int64),
            "jg": np.full(k, -1, np.int64), "jsrc": np.full(k, mode, np.int64),
            "jdst": np.full(k, tgt, np.int64), "jkind": np.full(k, 3 if zeno else 4, np.int64),
            "jpre": np.tile(pre, (k, 1)), "jpost": np.tile(post, (k, 1)),
            "st0": np.empty(0), "st1": np.empty(0), "smode": np.empty(0, np.int64),
            "sj": np.empty(0, np.int64), "sw": np.empty((0, n + 1)),
            "zt_out": np.full(1 if zeno else 0, t), "jname": list(names)})
        ic[IC_JUMPS] += k
        w[:] = post
        ic[IC_MODE] = tgt
        ic[IC_LAST_GUARD] = -1
        ic[IC_BURST_MODE] = -1
        fc[FC_LOC_ERR] = 0.0
        ids = self._store.guard_ids
        for nm in names:       # the joint jump fires each named guard at this instant
            if nm in ids:
                if ic[IC_FIRED] < fired.shape[0]:
                    fired[ic[IC_FIRED]] = ids[nm]
                ic[IC_FIRED] += 1
        # fc[6]: the start of the flow that ended here; no flow between: one more jump at
        # this instant
        ic[IC_INSTANT] = ic[IC_INSTANT] + 1 if fc[FC_T] == fc[FC_FLOW_START] else 0
        if ic[IC_INSTANT] > max_inst:
            chunks.append({
                "jt": np.empty(0), "jj": np.empty(0, np.int64), "jg": np.empty(0, np.int64),
                "jsrc": np.empty(0, np.int64), "jdst": np.empty(0, np.int64),
                "jkind": np.empty(0, np.int64), "jpre": np.empty((0, n + 1)),
                "jpost": np.empty((0, n + 1)), "st0": np.array([t]), "st1": np.array([t]),
                "smode": np.array([tgt], np.int64), "sj": np.array([ic[IC_JUMPS]], np.int64),
                "sw": post[None, :].copy(), "zt_out": np.array([t]), "jname": []})
            return TerminationCause.ZENO.value
        return None

    def _make_trajectory(self, t0, rc, cat, w, fc, ic) -> HybridTrajectory:
        n = self._n
        mn = self._names
        gnames = [[g.name for g in m.guards] for m in self._built]
        for key in ("jdst", "smode"):
            for code in np.unique(cat[key][cat[key] < 0]):
                if int(code) not in self._code_rows:
                    # the run stopped right after entering it (e.g. on the instant-jump
                    # bound): built now, so that the trajectory's modes all have tables
                    self.build_code(int(code))
                cat[key][cat[key] == code] = self._code_rows[int(code)]
        if ic[IC_MODE] < 0:
            ic[IC_MODE] = self.build_code(int(ic[IC_MODE]))
        jsrc = cat["jsrc"]
        guard = tuple(nm if nm is not None else gnames[s][g]
                      for s, g, nm in zip(jsrc, cat["jg"], cat["jname"]))
        # views, not copies: a long run's records are its largest memory
        jumps = JumpTable(
            t=cat["jt"], j=cat["jj"], guard=guard,
            pre=cat["jpre"][:, :n], post=cat["jpost"][:, :n],
            source=tuple(mn[s] for s in jsrc), target=tuple(mn[d] for d in cat["jdst"]),
            kind=tuple(_KIND_NAMES[int(k)] for k in cat["jkind"]))
        segs = SegmentTable(t_start=cat["st0"], t_end=cat["st1"],
                            mode=tuple(mn[m] for m in cat["smode"]), j=cat["sj"],
                            x_start=cat["sw"][:, :n])
        return HybridTrajectory(
            t0=t0, t_final=float(fc[FC_T]), termination=TerminationCause(int(rc)),
            segments=segs, jumps=jumps, zeno_times=cat["zt_out"].copy(),
            x_final=w[:n].copy(), mode_final=mn[int(ic[IC_MODE])], j_final=int(ic[IC_JUMPS]),
            n_steps=int(ic[IC_STEPS]), state_names=self._state_names, _automaton=self,
            _seg_mode_idx=cat["smode"].copy(), _seg_w=np.ascontiguousarray(cat["sw"]))


class _Modes(Sequence):
    """:attr:`HybridAutomaton.modes`: a built mode by index builds nothing; everything else
    builds every reachable mode first."""

    def __init__(self, automaton):
        self._ha = automaton

    def __getitem__(self, i):
        ha = self._ha
        if isinstance(i, (int, np.integer)) and 0 <= i < len(ha._built):
            return ha._full(int(i))
        n = ha.materialize()
        if isinstance(i, slice):
            return tuple(ha._full(j) for j in range(n)[i])
        return ha._full(range(n)[i])

    def __len__(self):
        return self._ha.materialize()

    def __iter__(self):
        n = self._ha.materialize()
        return (self._ha._full(j) for j in range(n))

    def __repr__(self):
        return f"<modes of an automaton: {len(self._ha._built)} built>"


def _stop_reason(traj, max_jumps, max_steps, zeno) -> str:
    """One line saying why ``traj`` stopped before its end time ("" if it did not)."""
    cause = traj.termination
    t = f"t = {traj.t_final:.12g}"
    jt = traj.jumps
    last = jt.t.size and jt.t[-1] == traj.t_final
    at = f" (last jump: {jt.guard[-1]} in mode {jt.source[-1]!r})" if last else ""
    if cause is TerminationCause.END_TIME:
        return ""
    if cause is TerminationCause.JUMP_LIMIT:
        return f"jump_limit: max_jumps = {max_jumps} jumps reached at {t}{at}"
    if cause is TerminationCause.ZENO:
        n_inst = int(np.sum(jt.t == traj.t_final)) if last else 0
        if n_inst > zeno.max_instant_jumps:
            return (f"zeno: more than max_instant_jumps = {zeno.max_instant_jumps} jumps at "
                    f"the one instant {t}{at}")
        return (f"zeno: jumps accumulate at {traj.zeno_times[-1]:.12g} in mode "
                f"{traj.mode_final!r}, whose guard has no zeno_target (stopped at {t})")
    if cause is TerminationCause.SIMULTANEOUS:
        return (f"simultaneous: the resolver found no joint jump at {t} in mode "
                f"{traj.mode_final!r}")
    if cause is TerminationCause.STEP_LIMIT:
        return f"step_limit: max_steps = {max_steps} flow steps taken by {t}"
    if cause is TerminationCause.NONFINITE:
        return f"nonfinite: the state overflowed or became NaN at {t} in mode {traj.mode_final!r}"
    return f"diverged: a state component exceeded max_state at {t} in mode {traj.mode_final!r}"
