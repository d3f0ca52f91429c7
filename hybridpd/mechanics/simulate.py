"""Simulation of a controlled mechanical system with contacts (:func:`simulate`).

The run is the hybrid automaton of :mod:`hybridpd.mechanics.automaton` (exact flows,
guaranteed first-crossing location); this module only sets it up and reads the jumps back
as impacts, sticking intervals and sampling instants.

Simultaneous contacts
---------------------
When a rigid contact fires while other rigid contacts are active at the same instant (on
their bound within the location tolerance, or closing onto it within ``time_tol (1 + |t|)``,
default ``1e-12``; held contacts always take part), Newton's law is solved for all of them at
once as a linear complementarity problem (:mod:`hybridpd.mechanics.impact`). Each contact
involved gets one impact record with the same ``t``, the same pre-impact state and the joint
post-impact state. Only an LCP without a (non-degenerate) solution ends the run, with
termination ``"simultaneous_contact"`` (``t_final`` its time, the state before it).

Accumulations and divergence
----------------------------
Impacts accumulating on one contact are resolved one by one until the tail extrapolated
from their (verified, geometric) ratios is shorter than ``1e-12 (1 + |t|)``, or a flight is
shorter than ``1e-9`` flow steps; the sticking phase starts at the accumulation time with the
state projected onto the contact (gap at its bound, zero normal velocity):
:attr:`MechanicalTrajectory.accumulations`. Impacts alternating between coupled contacts
(a chain at low restitution) shrink until they follow each other in no time; a contact that
fires again at one instant hands the contacts on their bounds to the resolver, which lets
their impacts follow each other to the end (:func:`~hybridpd.mechanics.impact.impact_cascade`)
or, where they accumulate, takes their plastic limit and holds those whose forces push (the
held set solves the contact-force complementarity problem, so no contact enters a sticking
phase whose force already pulls). Every run reaches its end time or says why not
(:attr:`MechanicalTrajectory.reason`). A run whose state grows past ``max_state``
(default ``1e12 max(1, |z0|, |bounds|)``) stops with termination ``"diverged"``.

Contact tolerance
-----------------
A rigid gap never exceeds its bound by more than the event-location rounding bound
(``~1e-12`` relative to the state scale) plus, during a sticking phase, the drift of the
constrained flow by rounding; the tests check ``1e-9 (1 + |bound|) + 1e-12 ||w||_1 max|q|``
(``max|q|`` over the run). The one exception is the unresolved tail
of an accumulation of impacts, ``[t_k, t_inf]`` (:attr:`MechanicalTrajectory.zeno_tails`):
the infinitely many, geometrically small impacts there are not computed (see
:mod:`hybridpd.hybrid.automaton`), and the state reported inside a tail is the flow of the
mode before the accumulation, which may cross the contact by about the size of the last
resolved rebound (and other contacts are not checked there); the state at ``t_inf`` is
projected back onto the contact, and any other contact then found violated fires at once.
The states recorded between several jumps at one instant are intermediate.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.mechanics.automaton import ZENO_TAIL_TOL, MechanicalAutomaton  # noqa: F401 (old path)

__all__ = ["MechanicalTrajectory", "simulate", "simulate_state"]

_TERMINATIONS = {0: "end_time", 1: "jump_limit", 2: "zeno", 3: "nonfinite", 4: "step_limit",
                 7: "simultaneous_contact", 8: "diverged"}


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class MechanicalTrajectory:
    """Result of :func:`simulate`.

    Attributes
    ----------
    impact_times : ndarray, shape (k,)
        Times of the rigid impacts (not counting sticking entries).
    contacts : ndarray of int, shape (k,)
        0-based contact index of each impact.
    walls : ndarray of int, shape (k,)
        ``+1`` at the contact's ``hi`` bound, ``-1`` at ``lo``.
    pre, post : ndarray, shape (k, 2n)
        Mechanical states ``[q_1, v_1, ..., q_n, v_n]`` just before / after each impact.
    grazing : ndarray of bool, shape (k,)
        Impacts located as tangential touches (closing velocity ~ 0).
    sticking : list of (t_start, t_end, contact)
        Intervals held on a rigid contact (``t_start``: the accumulation time of the impacts
        that led to it; ``t_end``: the release, or ``t_final`` if still held), each of
        positive length: the held set is read after the last jump of every instant, so a
        contact held and set free again among the jumps of one instant (a plastic impact
        in a cascade of impacts there) is not sticking.
    sticking_walls : list of int
        Wall of each sticking interval.
    zeno_tails : list of (t_k, t_inf, contact)
        Unresolved tails of accumulations (see "Contact tolerance" in the module docstring).
    accumulations : list of (t_inf, contact, wall, n_resolved)
        Accumulations of impacts: the accumulation time (the start of sticking), the contact,
        its wall and how many impacts of it were resolved before (consecutive ones).
    samples : ndarray, shape (s,)
        Sampling instants after ``t0`` (sampled-data loops; the sample at ``t0`` is applied
        to the initial state).
    termination : str
        ``"end_time"``, ``"jump_limit"``, ``"zeno"``, ``"nonfinite"``, ``"step_limit"``,
        ``"simultaneous_contact"`` or ``"diverged"``.
    reason : str
        Why the run stopped before the end time, in one line (empty if it did not; see
        :attr:`HybridTrajectory.reason <hybridpd.hybrid.trajectory.HybridTrajectory.reason>`).
    t_final : float
        Time reached.
    n_dofs : int
    hybrid : HybridTrajectory
        The automaton's trajectory (all jumps, segments, dense output).
    """

    impact_times: np.ndarray
    contacts: np.ndarray
    walls: np.ndarray
    pre: np.ndarray
    post: np.ndarray
    grazing: np.ndarray
    sticking: list
    sticking_walls: list
    zeno_tails: list
    samples: np.ndarray
    accumulations: list
    termination: str
    t_final: float
    n_dofs: int
    hybrid: object = field(repr=False)
    reason: str = ""
    __repr__ = compact_repr

    @property
    def n_impacts(self) -> int:
        """Number of impacts."""
        return int(self.impact_times.size)

    def __call__(self, t) -> np.ndarray:
        """Full closed-loop state(s) at time(s) ``t`` in ``[t0, t_final]`` (right-continuous)."""
        t_arr = np.asarray(t, dtype=float)
        if np.any(t_arr > self.t_final):
            raise ValueError(f"t must lie in [t0, t_final], t_final = {self.t_final!r}")
        return self.hybrid(t)

    def mechanical(self, t) -> np.ndarray:
        """Mechanical state(s) ``[q_1, v_1, ..., q_n, v_n]`` at time(s) ``t``."""
        return self(t)[..., :2 * self.n_dofs]

    def to_dict(self) -> dict:
        """JSON-ready summary (the ``simulate --json`` format)."""
        return {
            "impacts": [
                {"t": float(t), "contact": int(k), "wall": int(w),
                 "pre": [float(v) for v in p], "post": [float(v) for v in q],
                 "grazing": bool(g)}
                for t, k, w, p, q, g in zip(self.impact_times, self.contacts, self.walls,
                                            self.pre, self.post, self.grazing)
            ],
            "sticking": [[float(a), float(b), int(k)] for a, b, k in self.sticking],
            "termination": self.termination,
            "t_final": float(self.t_final),
        }


def simulate(model: MechanicalAutomaton, x0, t_span, max_impacts: int = 100_000,
             controller_state=None, time_tol: float = 1e-12, max_state: float | None = None,
             **options) -> MechanicalTrajectory:
    """Simulate a controlled mechanical system with contacts.

    Parameters
    ----------
    model : MechanicalAutomaton
        From :func:`~hybridpd.mechanics.automaton.build_automaton`.
    x0 : array_like, shape (2n,)
        Initial mechanical state ``[q_1, v_1, ..., q_n, v_n]`` inside every contact.
    t_span : (float, float)
        ``(t0, t1)``, ``t0 < t1``; the reference runs in absolute time.
    max_impacts : int
        Bound on the jumps other than sampling instants (impacts, sticking entries and
        releases, compliant engagements), ``>= 1``.
    controller_state : array_like, optional
        Initial controller states (default zero).
    time_tol : float
        Contacts closing within ``time_tol (1 + |t|)`` of each other are simultaneous
        (module docstring).
    max_state : float, optional
        Divergence bound on every state component (module docstring).
    **options
        Passed to :meth:`HybridAutomaton.simulate` (``zeno``, ``max_steps``).

    Returns
    -------
    MechanicalTrajectory

    Examples
    --------
    The impact pair of the paper (collocated PD) as a general mechanical system:

    >>> from hybridpd.mechanics import (Contact, MechanicalSystem, Reference, build_automaton,
    ...                                 mechanical_loop)
    >>> sysm = MechanicalSystem(["x1", "x2"], M=[[0.1, 0], [0, 1.0]], B=[0, 1])
    >>> loop = mechanical_loop(sysm, (10.0, 20.0), Reference.sine(1.0, 5.0, 1.0), "x2")
    >>> model = build_automaton(loop, [Contact([1, -1], -0.75, 0.75, restitution=0.5)])
    >>> traj = simulate(model, [0.3, 0.5, 0.0, 0.0], (0.0, 5.0))
    >>> traj.termination, traj.n_impacts > 0
    ('end_time', True)
    """
    if not isinstance(model, MechanicalAutomaton):
        raise ValueError("model must be a MechanicalAutomaton (see build_automaton)")
    n = model.loop.system.n
    x0 = np.asarray(x0, dtype=float).reshape(-1)
    if x0.shape != (2 * n,):
        raise ValueError(f"x0 must have shape ({2 * n},) = [q_1, v_1, ..., q_n, v_n], "
                         f"got {x0.shape}")
    t0, _ = _check_span(t_span)
    z0 = model.initial_state(x0[0::2], x0[1::2], t0, controller_state)
    return simulate_state(model, z0, t_span, model.initial_mode(z0), max_impacts, time_tol,
                          max_state=max_state, **options)


def simulate_state(model: MechanicalAutomaton, z0, t_span, mode: str | None = None,
                   max_impacts: int = 100_000, time_tol: float = 1e-12,
                   max_state: float | None = None, **options) -> MechanicalTrajectory:
    """Simulate from a full closed-loop state (e.g. a point of a Poincare section).

    Parameters
    ----------
    model : MechanicalAutomaton
    z0 : array_like, shape (N,)
        Closed-loop state in the layout of ``model.layout`` (exosystem, controller, held
        force and clock included; no sample is taken at ``t0``).
    t_span : (float, float)
    mode : str, optional
        Mode to start in (default: checked to lie inside every contact, ``model.free_mode``).
    max_impacts, time_tol, max_state, **options
        As in :func:`simulate`.

    Returns
    -------
    MechanicalTrajectory
    """
    if not isinstance(model, MechanicalAutomaton):
        raise ValueError("model must be a MechanicalAutomaton (see build_automaton)")
    t0, t1 = _check_span(t_span)
    if isinstance(max_impacts, bool) or int(max_impacts) != max_impacts or max_impacts < 1:
        raise ValueError(f"max_impacts must be an int >= 1, got {max_impacts!r}")
    z0 = np.asarray(z0, dtype=float)
    if mode is None:
        mode = model.initial_mode(z0)
    elif mode not in model.modes:
        raise ValueError(f"mode must be a mode name such as 'free' or 'stick0+', got {mode!r}")
    loop = model.loop
    max_jumps = int(max_impacts)
    for _, dt in loop.clocks:        # every sampling instant of every sampled controller
        max_jumps += math.ceil((t1 - t0) / dt) + 2
    if not (isinstance(time_tol, (int, float)) and math.isfinite(time_tol) and time_tol >= 0):
        raise ValueError(f"time_tol must be >= 0, got {time_tol!r}")
    if max_state is None:
        bounds = [abs(b) for c in model.contacts for _, b in c.bounds]
        max_state = 1e12 * max([1.0, float(np.abs(z0).max(initial=0.0))] + bounds)
    # zeno=None: the automaton's own rule (tail below ZENO_TAIL_TOL), the one the maps of its
    # sections use as well
    traj = model.automaton.simulate(z0, mode, (t0, t1), max_jumps=max_jumps,
                                    resolver=model.resolver(time_tol), simtol=time_tol,
                                    max_state=max_state, **options)
    return _wrap(model, traj)


def _check_span(t_span):
    try:
        t0, t1 = (float(v) for v in t_span)
    except (TypeError, ValueError):
        raise ValueError(f"t_span must be a pair (t0, t1), got {t_span!r}") from None
    if not (math.isfinite(t0) and math.isfinite(t1) and t1 > t0):
        raise ValueError(f"t_span must be finite and increasing, got {t_span!r}")
    return t0, t1


def _wrap(model, traj) -> MechanicalTrajectory:
    n = model.loop.system.n
    jt = traj.jumps
    info = [model.guards[(s, g)] for s, g in zip(jt.source, jt.guard)]
    t_final, termination = traj.t_final, _TERMINATIONS[traj.termination.value]
    stop = len(jt)
    imp = [i for i in range(stop) if info[i].kind == "impact" and jt.kind[i] != "zeno"]
    # sticking intervals per contact: opened by a jump into a mode that holds the contact,
    # closed by one into a mode that does not
    spans, opened = [], {}
    held_in = {}                                   # mode name -> {contact: wall}

    def held(mode):
        if mode not in held_in:
            held_in[mode] = dict(model.modes[mode].stick)
        return held_in[mode]

    for k, wall in (held(traj.segments.mode[0]) if len(traj.segments) else {}).items():
        opened[k] = (traj.t0, wall)
    for i in range(stop):
        if i + 1 < stop and jt.t[i + 1] == jt.t[i]:
            continue               # what is held after the last jump of an instant counts
        after = held(jt.target[i])
        t = float(jt.t[i])
        for k in list(opened):
            if after.get(k) != opened[k][1]:
                t_open, wall = opened.pop(k)
                if t > t_open:
                    spans.append((t_open, t, k, wall))
        for k, wall in after.items():
            if k not in opened:
                opened[k] = (t, wall)
    spans += [(t_open, t_final, k, wall) for k, (t_open, wall) in opened.items()
              if t_final > t_open]
    spans.sort()
    sticking = [(a, b, k) for a, b, k, _ in spans]
    sticking_walls = [w for *_, w in spans]
    tails = [(float(jt.t[i - 1]) if i else traj.t0, float(jt.t[i]), info[i].contact)
             for i in range(stop) if jt.kind[i] == "zeno"]
    accum = []
    for i in range(stop):
        if jt.kind[i] != "zeno":
            continue
        c, w, r = info[i].contact, info[i].wall, 0
        q = i - 1
        while q >= 0 and info[q].kind == "impact" and info[q].contact == c and jt.kind[q] != "zeno":
            r += 1
            q -= 1
        accum.append((float(jt.t[i]), c, w, r))
    idx = np.asarray(imp, dtype=int)
    samples = np.asarray([jt.t[i] for i in range(stop) if info[i].kind == "sample"], float)
    return MechanicalTrajectory(
        impact_times=np.asarray(jt.t, float)[idx],
        contacts=np.asarray([info[i].contact for i in imp], dtype=int),
        walls=np.asarray([info[i].wall for i in imp], dtype=int),
        pre=np.asarray(jt.pre, float)[idx, :2 * n].reshape(-1, 2 * n),
        post=np.asarray(jt.post, float)[idx, :2 * n].reshape(-1, 2 * n),
        grazing=np.asarray([jt.kind[i] == "grazing" for i in imp], dtype=bool),
        sticking=sticking, sticking_walls=sticking_walls, zeno_tails=tails, samples=samples,
        accumulations=accum, termination=termination, t_final=float(t_final), n_dofs=n,
        hybrid=traj, reason=traj.reason)
