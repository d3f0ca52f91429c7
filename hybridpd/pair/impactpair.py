"""The controlled impact pair as a guard/reset hybrid automaton.

Modes
-----
``free``
    Both masses fly; the closed loop of :mod:`hybridpd.loop` (exact LTI flow). Two guards:
    ``wall+`` (``g = L - (x1 - x2) >= 0``, fires when the gap closes on the right wall,
    i.e. ``z3 -> +L`` with ``z4 > 0``) and ``wall-`` (``g = (x1 - x2) + L``), each resetting the
    velocities by Newton's law (2).
``stick+`` / ``stick-``
    Entered when impacts accumulate on a wall (Zeno; e.g. ``e = 0.1`` with ``m1`` pressed
    against a wall). The masses move together, ``(m1 + m2) x'' = U``, starting from the
    plastic (momentum-conserving) contact state. The mode is left when the contact force on
    ``m1`` changes sign: on the right wall the slot can only push ``m1`` to the left, which
    holds while ``U <= 0``; on the left wall while ``U >= 0``.

All timing conventions (hybrid time ``(t, j)``, grazing, post-reset semantics, the Zeno
estimate) are those of :mod:`hybridpd.hybrid.automaton`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.hybrid.automaton import Guard, HybridAutomaton, Mode, TerminationCause
from hybridpd.loop import ClosedLoop, closed_loop
from hybridpd.model import Case, ImpactPair, Reference, check_array, check_int, check_pair

__all__ = ["ControlledImpactPair", "ImpactPairTrajectory"]


@dataclass(frozen=True)
class ImpactPairTrajectory:
    """Result of :meth:`ControlledImpactPair.simulate`.

    Attributes
    ----------
    impact_times : ndarray, shape (k,)
        Times of the impacts (not counting the entries into sticking).
    walls : ndarray of int, shape (k,)
        ``+1`` for the right wall (``z3 = +L``), ``-1`` for the left wall.
    pre, post : ndarray, shape (k, 4)
        Mechanical states ``[x1, y1, x2, y2]`` just before / after each impact.
    grazing : ndarray of bool, shape (k,)
        Impacts located as tangential touches (relative velocity ~ 0).
    sticking : list of (t_start, t_end)
        Intervals in a sticking mode; ``t_end`` is the end of the simulation if still stuck.
        ``t_start`` is the estimated accumulation time of the impacts that led to it.
    sticking_walls : list of int
        Wall (+1/-1) of each sticking interval.
    termination : TerminationCause
        Why the simulation stopped.
    t_final : float
        Time reached.
    hybrid : HybridTrajectory
        The underlying automaton trajectory (segments, all jumps, dense output).
    """

    __repr__ = compact_repr

    impact_times: np.ndarray
    walls: np.ndarray
    pre: np.ndarray
    post: np.ndarray
    grazing: np.ndarray
    sticking: list
    sticking_walls: list
    termination: TerminationCause
    t_final: float
    hybrid: object = field(repr=False)

    @property
    def n_impacts(self) -> int:
        """Number of impacts."""
        return int(self.impact_times.size)

    def __call__(self, t) -> np.ndarray:
        """Full state(s) ``[x1, y1, x2, y2, pc, ps, ...]`` at time(s) ``t`` (right-continuous)."""
        return self.hybrid(t)

    def to_dict(self) -> dict:
        """JSON-ready summary (the CLI's ``simulate --json`` format).

        The same format as a mechanical model's (:mod:`hybridpd.mechanics.simulate`): the
        pair has one contact, number 0.
        """
        return {
            "impacts": [
                {"t": float(t), "contact": 0, "wall": int(w), "pre": [float(v) for v in p],
                 "post": [float(v) for v in q], "grazing": bool(g)}
                for t, w, p, q, g in zip(self.impact_times, self.walls, self.pre, self.post,
                                         self.grazing)],
            "sticking": [[float(a), float(b), 0] for a, b in self.sticking],
            "termination": self.termination.name.lower(),
            "t_final": float(self.t_final)}


class ControlledImpactPair:
    """PD (or any LTI) control of the impact pair, simulated as a hybrid automaton.

    Parameters
    ----------
    plant : ImpactPair
    controller : PDGains, (kp, kv), or python-control LTI system (see :mod:`hybridpd.loop`)
    reference : Reference
    case : {"collocated", "noncollocated"}

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains, Reference
    >>> sysm = ControlledImpactPair(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), Reference(1, 5))
    >>> traj = sysm.simulate([0.3, 0.5, 0.0, 0.0], (0.0, 5.0))
    >>> traj.termination.name
    'END_TIME'
    >>> bool(np.all(np.abs(traj.pre[:, 0] - traj.pre[:, 2]) - 0.75 < 1e-9))
    True
    """

    def __init__(self, plant: ImpactPair, controller, reference: Reference, case="collocated"):
        if not isinstance(plant, ImpactPair):
            raise ValueError(f"plant must be an ImpactPair, got {type(plant).__name__}")
        self.loop: ClosedLoop = closed_loop(plant, controller, reference, Case.parse(case))
        self.plant = plant
        self.reference = reference
        self.case = self.loop.case
        self.automaton = self._build_automaton()

    def _build_automaton(self) -> HybridAutomaton:
        cl, pair = self.loop, self.plant
        n = cl.n_states
        L, mu = pair.L, pair.mu
        E = np.eye(n)
        E[np.ix_([1, 3], [1, 3])] = pair.velocity_jump_matrix()
        zero = np.zeros(n)
        gap = np.zeros(n)
        gap[0], gap[2] = 1.0, -1.0           # z3 = x1 - x2

        def plastic(wall):
            # Project onto the contact: x1 = x2 + wall*L, common velocity conserving momentum.
            R = np.eye(n)
            r = np.zeros(n)
            R[0, :] = 0.0
            R[0, 2] = 1.0
            r[0] = wall * L
            v = np.zeros(n)
            v[1], v[3] = mu / (1 + mu), 1 / (1 + mu)
            R[1, :] = v
            R[3, :] = v
            return R, r

        walls = [Guard(name, c=-wall * gap, d=L, direction=-1, reset=(E, zero), target="free",
                       zeno_target=f"stick{name[-1]}", zeno_reset=plastic(wall))
                 for wall, name in ((+1, "wall+"), (-1, "wall-"))]
        free = Mode("free", cl.A, guards=tuple(walls))
        A_stick = cl.sticking_A()
        # Right wall: stuck while U <= 0 (g = -U >= 0); left wall: while U >= 0. The release
        # projects onto the contact again so that rounding accumulated over a long sticking
        # phase cannot leave the free flow starting off (or through) the wall.
        stick_p = Mode("stick+", A_stick, guards=(
            Guard("release+", c=-cl.force, d=0.0, direction=-1, reset=plastic(+1),
                  target="free"),))
        stick_m = Mode("stick-", A_stick, guards=(
            Guard("release-", c=cl.force.copy(), d=0.0, direction=-1, reset=plastic(-1),
                  target="free"),))
        return HybridAutomaton((free, stick_p, stick_m), state_names=cl.state_names)

    def initial_state(self, x0, t0: float = 0.0, controller_state=None) -> np.ndarray:
        """Full closed-loop state at ``t0`` from ``x0 = [x1, y1, x2, y2]``."""
        return self.loop.initial_state(x0, t0, controller_state)

    def simulate(self, x0, t_span, max_impacts: int = 100_000, controller_state=None,
                 **options) -> ImpactPairTrajectory:
        """Simulate from ``x0 = [x1, y1, x2, y2]`` (with ``|x1 - x2| <= L``) over ``t_span``.

        Parameters
        ----------
        x0 : array_like, shape (4,)
            Initial mechanical state. The exosystem starts at ``xm [cos w t0, sin w t0]``.
        t_span : (float, float)
            Start and end time, ``t0 < t1``.
        max_impacts : int
            Bound on the number of jumps (impacts, sticking entries and releases).
        controller_state : array_like, optional
            Initial states of a dynamic controller (default zero).
        **options
            Passed to :meth:`HybridAutomaton.simulate` (e.g. Zeno options).

        Returns
        -------
        ImpactPairTrajectory
        """
        t0, t1 = check_pair("t_span", t_span)
        if not t1 > t0:
            raise ValueError(f"t_span must be increasing (t0 < t1), got {(t0, t1)!r}")
        max_impacts = check_int("max_impacts", max_impacts, 1)
        x0 = check_array("x0", x0, shape=(4,))
        z0 = self.initial_state(x0, t0, controller_state)
        gap = z0[0] - z0[2]
        L = self.plant.L
        if abs(gap) > L * (1 + 1e-12):
            raise ValueError(
                f"x0 must satisfy |x1 - x2| <= L = {L:g}; got x1 - x2 = {gap:g}")
        traj = self.automaton.simulate(z0, "free", (t0, t1), max_jumps=max_impacts, **options)
        return self._wrap(traj)

    def _wrap(self, traj) -> ImpactPairTrajectory:
        jt = traj.jumps
        guard = np.asarray(jt.guard, dtype=object)
        kind = np.asarray(jt.kind, dtype=object)
        wall_jump = ((guard == "wall+") | (guard == "wall-")) & (kind != "zeno")
        walls = np.where(guard[wall_jump] == "wall+", 1, -1).astype(int)
        # sticking intervals: a 'zeno' jump opens one, the next release closes it
        sticking, sticking_walls = [], []
        opened = None
        for i in np.flatnonzero((kind == "zeno") | np.char.startswith(
                guard.astype(str), "release")):
            if kind[i] == "zeno":
                opened = (float(jt.t[i]), 1 if guard[i] == "wall+" else -1)
            elif opened is not None:
                sticking.append((opened[0], float(jt.t[i])))
                sticking_walls.append(opened[1])
                opened = None
        if opened is not None:
            sticking.append((opened[0], traj.t_final))
            sticking_walls.append(opened[1])
        return ImpactPairTrajectory(
            impact_times=np.asarray(jt.t, float)[wall_jump],
            walls=walls,
            pre=np.asarray(jt.pre, float)[wall_jump, :4].reshape(-1, 4),
            post=np.asarray(jt.post, float)[wall_jump, :4].reshape(-1, 4),
            grazing=(kind[wall_jump] == "grazing").astype(bool),
            sticking=sticking, sticking_walls=sticking_walls,
            termination=traj.termination, t_final=traj.t_final, hybrid=traj)
