"""A controlled mechanical system with contacts as a guard/reset hybrid automaton.

:func:`build_automaton` turns a :class:`~hybridpd.mechanics.loop.MechanicalLoop` and its
:class:`~hybridpd.mechanics.contacts.Contact` list into a
:class:`~hybridpd.hybrid.automaton.HybridAutomaton` (exact LTI flows, guaranteed first-crossing
location, compiled jump loop) plus the metadata an analysis needs (:class:`MechanicalAutomaton`).

Modes
-----
A mode is a pair (compliant configuration, sticking contact):

* the compliant configuration says, for every compliant contact, whether its spring-damper is
  engaged at ``hi`` (``+1``), at ``lo`` (``-1``) or not (``0``);
* the sticking part is ``None`` (free) or ``(k, wall)``: rigid contact ``k`` held on that bound.

Mode names: ``"free"`` or ``"stick{k}{+|-}"``, followed by ``"/c{j}{+|-},..."`` for the engaged
compliant contacts (e.g. ``"free"``, ``"free/c1+"``, ``"stick0-/c1+"``).

Flows: the loop's ``z' = A z + b`` plus the engaged Kelvin-Voigt forces; while sticking on
contact ``k`` (normal ``w``) the accelerations ``a`` are projected in the metric of ``M``,
``a_s = a - M^-1 w (w . a) / (w . M^-1 w)``, so that ``w . q`` stays on its bound; the
contact force multiplier is ``lambda = -(w . a) / (w . M^-1 w)`` (generalised force
``lambda w``).

Guards (``g > 0`` admissible, all with ``direction = -1`` except sampling):

* ``contact{k}{+|-}`` (rigid ``k`` at ``hi`` / ``lo``): ``g = hi - w.q`` / ``w.q - lo``; reset
  Newton's law in the metric of ``M`` (:mod:`hybridpd.mechanics.contacts`); target the same
  mode (from a sticking mode: the free mode of the same configuration); accumulating impacts
  enter ``stick{k}{+|-}`` through the plastic projection (``zeno_target``).
* ``release{k}{+|-}``: ``g = -wall * lambda``: the contact force would have to pull; reset
  the plastic projection (so that rounding accumulated while sticking cannot leave the free
  flow outside the gap), target the free mode of the configuration.
* ``enter{j}{+|-}`` / ``leave{j}{+|-}`` (compliant ``j``): the penetration changes sign;
  identity reset, target the configuration with ``j`` engaged / released.
* ``sample`` (sampled-data loops): ``g = s - dt`` with ``direction = +1`` on the clock; reset
  :attr:`MechanicalLoop.sample_reset`; target the same mode.

Priorities for simultaneous events: impacts and compliant switches 2, releases 1, samples 0.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np

from hybridpd.hybrid.automaton import Guard, HybridAutomaton, Mode
from hybridpd.mechanics.contacts import Contact
from hybridpd.mechanics.loop import MechanicalLoop

__all__ = ["GuardInfo", "MechanicalAutomaton", "ModeInfo", "build_automaton"]


@dataclass(frozen=True)
class ModeInfo:
    """What a mode means: ``config[j]`` in ``{-1, 0, +1}`` per contact (compliant ones only
    non-zero), ``stick = (k, wall)`` or ``None``."""

    name: str
    config: tuple
    stick: tuple | None


@dataclass(frozen=True)
class GuardInfo:
    """What a guard means.

    ``kind`` is ``'impact'``, ``'release'``, ``'enter'``, ``'leave'`` or ``'sample'``;
    ``contact`` the 0-based contact index (``-1`` for ``'sample'``); ``wall`` ``+1`` at ``hi``,
    ``-1`` at ``lo`` (0 for ``'sample'``).
    """

    kind: str
    contact: int
    wall: int


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class MechanicalAutomaton:
    """The hybrid automaton of a controlled mechanical system, with its metadata.

    Attributes
    ----------
    automaton : HybridAutomaton
    loop : MechanicalLoop
        Closed loop (state layout in ``loop.layout``, names in ``loop.state_names``).
    contacts : tuple of Contact
    modes : dict
        Mode name -> :class:`ModeInfo`.
    guards : dict
        ``(mode name, guard name)`` -> :class:`GuardInfo`.
    gap_rows : ndarray, shape (m, N)
        ``w_k . q = gap_rows[k] @ z``.
    impact_resets : dict
        ``(k, wall)`` -> ``(R, r)``: Newton's law of rigid contact ``k`` (``R`` shape ``(N, N)``).
    plastic_resets : dict
        ``(k, wall)`` -> ``(R, r)``: projection onto the contact (sticking entry, release).
    free_mode : str
        The mode without engaged contacts (``"free"``).
    """

    automaton: HybridAutomaton = field(repr=False)
    loop: MechanicalLoop = field(repr=False)
    contacts: tuple
    modes: dict = field(repr=False)
    guards: dict = field(repr=False)
    gap_rows: np.ndarray = field(repr=False)
    impact_resets: dict = field(repr=False)
    plastic_resets: dict = field(repr=False)
    free_mode: str = "free"

    @property
    def state_names(self) -> tuple:
        return self.loop.state_names

    @property
    def layout(self) -> dict:
        """Index arrays ``q, v, exo, ctrl, hold`` and the ``clock`` index (see the loop)."""
        return self.loop.layout

    def initial_state(self, q0, v0, t0: float = 0.0, controller_state=None) -> np.ndarray:
        """Full state at ``t0`` (see :meth:`MechanicalLoop.initial_state`)."""
        return self.loop.initial_state(q0, v0, t0, controller_state)

    def initial_mode(self, z0, rtol: float = 1e-12) -> str:
        """Mode to start in from ``z0``; ``ValueError`` naming the violated contact.

        Every gap must lie in its bounds (to ``rtol`` relative to ``1 + |bound|``); compliant
        contacts start disengaged.
        """
        z0 = np.asarray(z0, dtype=float)
        for k, c in enumerate(self.contacts):
            s = float(self.gap_rows[k] @ z0)
            for wall, bound in c.bounds:
                if wall * (s - bound) > rtol * (1.0 + abs(bound)):
                    side = "hi" if wall > 0 else "lo"
                    raise ValueError(
                        f"initial: the state is outside contact {k}{_label(c)}: gap {s:.12g} "
                        f"beyond {side} = {bound:g}")
        return self.free_mode


def _label(c):
    return f" ({c.name})" if c.name else ""


def _mode_name(config, stick):
    base = "free" if stick is None else f"stick{stick[0]}{'+' if stick[1] > 0 else '-'}"
    eng = [f"c{j}{'+' if s > 0 else '-'}" for j, s in enumerate(config) if s]
    return base + ("/" + ",".join(eng) if eng else "")


def _contact_geometry(loop, contacts):
    sysm = loop.system
    N, lay = loop.n_states, loop.layout
    for k, c in enumerate(contacts):
        if not isinstance(c, Contact):
            raise ValueError(f"contacts[{k}] must be a Contact")
        if c.normal.shape != (sysm.n,):
            raise ValueError(f"contact {k}: normal must have shape ({sysm.n},), got "
                             f"{c.normal.shape}")
    gap = np.zeros((len(contacts), N))
    Mw = np.zeros((len(contacts), sysm.n))
    for k, c in enumerate(contacts):
        gap[k, lay["q"]] = c.normal
        Mw[k] = np.linalg.solve(sysm.M, c.normal)
    return gap, Mw


def _resets(loop, contacts, Mw):
    lay = loop.layout
    N = loop.n_states
    iq, iv = lay["q"], lay["v"]
    impact, plastic = {}, {}
    for k, c in enumerate(contacts):
        w, mw = c.normal, Mw[k]
        wmw = float(w @ mw)
        P = np.eye(len(w)) - np.outer(mw, w) / wmw
        for wall, bound in c.bounds:
            if c.rigid:
                R = np.eye(N)
                R[np.ix_(iv, iv)] = np.eye(len(w)) - (1.0 + c.restitution) * np.outer(mw, w) / wmw
                impact[(k, wall)] = (R, np.zeros(N))
            R = np.eye(N)
            r = np.zeros(N)
            R[np.ix_(iq, iq)] = P
            R[np.ix_(iv, iv)] = P
            r[iq] = mw * (bound / wmw)
            plastic[(k, wall)] = (R, r)
    return impact, plastic


def _flow(loop, contacts, Mw, config, stick):
    """``(A, b, lambda_row, lambda_const)`` of a mode."""
    A, b = loop.A.copy(), loop.b.copy()
    lay = loop.layout
    iq, iv = lay["q"], lay["v"]
    for j, s in enumerate(config):
        if s == 0:
            continue
        c = contacts[j]
        bound = c.hi if s > 0 else c.lo
        A[np.ix_(iv, iq)] -= c.stiffness * np.outer(Mw[j], c.normal)
        A[np.ix_(iv, iv)] -= c.damping * np.outer(Mw[j], c.normal)
        b[iv] += c.stiffness * bound * Mw[j]
    if stick is None:
        return A, b, None, None
    k = stick[0]
    w, mw = contacts[k].normal, Mw[k]
    wmw = float(w @ mw)
    lam_row = -(w @ A[iv]) / wmw
    lam_b = -float(w @ b[iv]) / wmw
    A[iv] += np.outer(mw, lam_row)
    b[iv] += mw * lam_b
    return A, b, lam_row, lam_b


def build_automaton(loop: MechanicalLoop, contacts) -> MechanicalAutomaton:
    """Build the hybrid automaton of ``loop`` with ``contacts`` (see the module docstring).

    Parameters
    ----------
    loop : MechanicalLoop
    contacts : sequence of Contact
        Normals of shape ``(n,)``; the index in this sequence is the contact number.

    Returns
    -------
    MechanicalAutomaton

    Examples
    --------
    >>> from hybridpd.mechanics import Contact, MechanicalSystem, Reference, mechanical_loop
    >>> sysm = MechanicalSystem(["x1", "x2"], M=[[0.1, 0], [0, 1.0]], B=[0, 1])
    >>> loop = mechanical_loop(sysm, (10.0, 20.0), Reference.sine(1.0, 5.0, 1.0), "x2")
    >>> ma = build_automaton(loop, [Contact([1, -1], -0.75, 0.75, restitution=0.5)])
    >>> ma.automaton.mode_names
    ('free', 'stick0-', 'stick0+')
    >>> ma.guards[("free", "contact0+")]
    GuardInfo(kind='impact', contact=0, wall=1)
    """
    if not isinstance(loop, MechanicalLoop):
        raise ValueError("loop must be a MechanicalLoop")
    contacts = tuple(contacts)
    gap, Mw = _contact_geometry(loop, contacts)
    impact, plastic = _resets(loop, contacts, Mw)
    choices = [(0,) + tuple(w for w, _ in c.bounds) if not c.rigid else (0,) for c in contacts]
    sticks = [None] + [(k, w) for k, c in enumerate(contacts) if c.rigid for w, _ in c.bounds]
    modes, minfo, ginfo = [], {}, {}
    for config in itertools.product(*choices):
        for stick in sticks:
            name = _mode_name(config, stick)
            minfo[name] = ModeInfo(name, tuple(config), stick)
            A, b, lam_row, lam_b = _flow(loop, contacts, Mw, config, stick)
            guards = _guards(loop, contacts, gap, impact, plastic, config, stick, lam_row,
                             lam_b, name, ginfo)
            modes.append(Mode(name, A, b=b, guards=tuple(guards)))
    ha = HybridAutomaton(modes, state_names=loop.state_names)
    return MechanicalAutomaton(automaton=ha, loop=loop, contacts=contacts, modes=minfo,
                               guards=ginfo, gap_rows=gap, impact_resets=impact,
                               plastic_resets=plastic, free_mode=_mode_name(
                                   (0,) * len(contacts), None))


def _sign(w):
    return "+" if w > 0 else "-"


def _guards(loop, contacts, gap, impact, plastic, config, stick, lam_row, lam_b, name,
            ginfo):
    free_same = _mode_name(config, None)
    out = []
    for k, c in enumerate(contacts):
        for wall, bound in c.bounds:
            gname = None
            if c.rigid:
                if stick is not None and stick[0] == k:
                    continue
                gname = f"contact{k}{_sign(wall)}"
                out.append(Guard(gname, c=-wall * gap[k], d=wall * bound, direction=-1,
                                 reset=impact[(k, wall)], target=free_same, priority=2,
                                 zeno_target=_mode_name(config, (k, wall)),
                                 zeno_reset=plastic[(k, wall)]))
                ginfo[(name, gname)] = GuardInfo("impact", k, wall)
            elif config[k] == 0:
                cfg = list(config)
                cfg[k] = wall
                gname = f"enter{k}{_sign(wall)}"
                out.append(Guard(gname, c=-wall * gap[k], d=wall * bound, direction=-1,
                                 target=_mode_name(tuple(cfg), stick), priority=2))
                ginfo[(name, gname)] = GuardInfo("enter", k, wall)
            elif config[k] == wall:
                cfg = list(config)
                cfg[k] = 0
                gname = f"leave{k}{_sign(wall)}"
                out.append(Guard(gname, c=wall * gap[k], d=-wall * bound, direction=-1,
                                 target=_mode_name(tuple(cfg), stick), priority=2))
                ginfo[(name, gname)] = GuardInfo("leave", k, wall)
    if stick is not None:
        k, wall = stick
        gname = f"release{k}{_sign(wall)}"
        out.append(Guard(gname, c=-wall * lam_row, d=-wall * lam_b, direction=-1,
                         reset=plastic[(k, wall)], target=free_same, priority=1))
        ginfo[(name, gname)] = GuardInfo("release", k, wall)
    if loop.sampled:
        cl = np.zeros(loop.n_states)
        cl[loop.layout["clock"]] = 1.0
        out.append(Guard("sample", c=cl, d=-loop.dt, direction=+1, reset=loop.sample_reset,
                         priority=0))
        ginfo[(name, "sample")] = GuardInfo("sample", -1, 0)
    return out
