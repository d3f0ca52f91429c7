"""A controlled mechanical system with contacts as a guard/reset hybrid automaton.

:func:`build_automaton` turns a :class:`~hybridpd.mechanics.loop.MechanicalLoop` and its
:class:`~hybridpd.mechanics.contacts.Contact` list into a
:class:`~hybridpd.hybrid.automaton.HybridAutomaton` (exact LTI flows, guaranteed first-crossing
location, compiled jump loop) plus the metadata an analysis needs (:class:`MechanicalAutomaton`).

Modes
-----
A mode is a pair (compliant configuration, set of held contacts):

* the compliant configuration says, for every compliant contact, whether its spring-damper is
  engaged at ``hi`` (``+1``), at ``lo`` (``-1``) or not (``0``);
* the sticking part ``S`` is a set of ``(k, wall)``: rigid contacts held on a bound (empty:
  free). Several contacts can be held at once (a gear train with every mesh engaged) when
  their normals are independent.

Mode names: ``"free"`` or ``"stick{k}{+|-}..."`` (e.g. ``"stick0+"``, ``"stick0+1-"``),
followed by ``"/c{j}{+|-},..."`` for the engaged compliant contacts (e.g. ``"free/c1+"``).

Flows: the loop's ``z' = A z + b`` plus the engaged Kelvin-Voigt forces; while sticking on
``S`` (normals ``W = [w_k]``) the accelerations ``a`` are projected in the metric of ``M``,
``a_s = a - M^-1 W (W^T M^-1 W)^-1 W^T a``, so that every ``w_k . q`` stays on its bound; the
contact force multipliers are ``lambda = -(W^T M^-1 W)^-1 W^T a`` (generalised force
``W lambda``).

Guards (``g > 0`` admissible, all with ``direction = -1`` except sampling):

* ``contact{k}{+|-}`` (rigid ``k`` at ``hi`` / ``lo``): ``g = hi - w.q`` / ``w.q - lo``; reset
  Newton's law in the metric of ``M`` (:mod:`hybridpd.mechanics.contacts`), and while sticking
  on ``S`` in the constrained metric ``M_S^-1 = M^-1 - M^-1 W (W^T M^-1 W)^-1 W^T M^-1``: the
  held contacts whose reaction impulse pushes stay held, those that would have to pull are
  released first (decided from the geometry, :meth:`_Geometry.impact_held`); target the
  mode holding what stays held (the same mode if all do); accumulating impacts enter the mode
  that also holds ``k`` through the plastic projection onto all of its contacts
  (``zeno_target``; none if the normals are dependent: the run then ends with ``ZENO``).
* ``release{k}{+|-}`` (``k`` in ``S``): ``g = -wall * lambda_k``: the contact force would have
  to pull; reset the plastic projection onto ``S`` (so that rounding accumulated while
  sticking cannot leave the flow outside a gap), target the mode sticking on ``S - {k}``.
* ``enter{j}{+|-}`` / ``leave{j}{+|-}`` (compliant ``j``): the penetration changes sign;
  identity reset, target the configuration with ``j`` engaged / released.
* ``sample`` (sampled-data loops): ``g = s - dt`` with ``direction = +1`` on the clock; reset
  :attr:`MechanicalLoop.sample_reset`; target the same mode.

Priorities for simultaneous events: impacts and compliant switches 2, releases 1, samples 0.

Size: one mode per compliant configuration (``prod_j (1 + number of bounds of j)`` over the
compliant contacts) times one per set of held rigid contacts with independent normals (at
most ``prod_k (1 + number of bounds of k)``); for ``m`` contacts at most ``3^m`` modes, each
an exact LTI flow prepared once.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np

from hybridpd._repr import compact_repr
from hybridpd.hybrid.automaton import Guard, HybridAutomaton, Mode
from hybridpd.mechanics.contacts import Contact
from hybridpd.mechanics.loop import MechanicalLoop

__all__ = ["GuardInfo", "MechanicalAutomaton", "ModeInfo", "build_automaton"]


@dataclass(frozen=True)
class ModeInfo:
    """What a mode means: ``config[j]`` in ``{-1, 0, +1}`` per contact (compliant ones only
    non-zero), ``stick``: tuple of the held ``(k, wall)`` (empty: free)."""

    name: str
    config: tuple
    stick: tuple


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
        ``(k, wall)`` -> ``(R, r)``: Newton's law of rigid contact ``k`` in the free modes
        (``R`` shape ``(N, N)``).
    plastic_resets : dict
        ``(k, wall)`` -> ``(R, r)``: projection onto that one contact (sticking entry).
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
    __repr__ = compact_repr

    @property
    def state_names(self) -> tuple:
        return self.loop.state_names

    @property
    def layout(self) -> dict:
        """Index arrays ``q, v, exo, ctrl, hold`` and the ``clock`` index (see the loop)."""
        return self.loop.layout

    def guard_name(self, contact: int, wall: int, kind: str = "impact") -> str:
        """Name of the guard of ``kind`` (``'impact'``, ``'release'``, ``'enter'``,
        ``'leave'``) for ``contact`` at ``wall`` (the same name in every mode that has it)."""
        prefix = {"impact": "contact", "release": "release", "enter": "enter",
                  "leave": "leave"}.get(kind)
        if prefix is None:
            raise ValueError(f"kind must be 'impact', 'release', 'enter' or 'leave', "
                             f"got {kind!r}")
        name = f"{prefix}{int(contact)}{_sign(wall)}"
        if not any(g == name for _, g in self.guards):
            raise ValueError(f"no guard {name!r} (contact {contact}, wall {wall:+d})")
        return name

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


def _sign(w):
    return "+" if w > 0 else "-"


def _mode_name(config, stick):
    base = "free" if not stick else "stick" + "".join(f"{k}{_sign(w)}" for k, w in stick)
    eng = [f"c{j}{_sign(s)}" for j, s in enumerate(config) if s]
    return base + ("/" + ",".join(eng) if eng else "")


class _Geometry:
    """Normals, bounds and the metric of ``M`` on the closed-loop state."""

    def __init__(self, loop, contacts):
        sysm = loop.system
        self.loop, self.contacts = loop, contacts
        N, lay = loop.n_states, loop.layout
        for k, c in enumerate(contacts):
            if not isinstance(c, Contact):
                raise ValueError(f"contacts[{k}] must be a Contact")
            if c.normal.shape != (sysm.n,):
                raise ValueError(f"contact {k}: normal must have shape ({sysm.n},), got "
                                 f"{c.normal.shape}")
        self.n, self.N = sysm.n, N
        self.iq, self.iv = lay["q"], lay["v"]
        self.gap = np.zeros((len(contacts), N))
        self.Mw = np.zeros((len(contacts), sysm.n))
        for k, c in enumerate(contacts):
            self.gap[k, self.iq] = c.normal
            self.Mw[k] = np.linalg.solve(sysm.M, c.normal)

    def bound(self, k, wall):
        c = self.contacts[k]
        return c.hi if wall > 0 else c.lo

    def held(self, stick):
        """``(W (n, s), M^-1 W, G^-1 = (W^T M^-1 W)^-1, beta)`` or None if dependent."""
        ks = [k for k, _ in stick]
        W = np.array([self.contacts[k].normal for k in ks]).T
        MW = self.Mw[ks].T
        G = W.T @ MW
        if np.linalg.cond(G) > 1e10:
            return None
        beta = np.array([self.bound(k, w) for k, w in stick])
        return W, MW, np.linalg.inv(G), beta

    def projection(self, stick):
        """Plastic projection onto every contact of ``stick``: ``(R, r)`` or None."""
        h = self.held(stick)
        if h is None:
            return None
        W, MW, Gi, beta = h
        P = np.eye(self.n) - MW @ Gi @ W.T
        R = np.eye(self.N)
        r = np.zeros(self.N)
        R[np.ix_(self.iq, self.iq)] = P
        R[np.ix_(self.iv, self.iv)] = P
        r[self.iq] = MW @ (Gi @ beta)
        return R, r

    def impact_held(self, k, wall, stick):
        """The contacts of ``stick`` that stay held through an impact of ``k`` at ``wall``.

        With all of ``stick`` held, the reaction impulses there are ``Lambda = -(W^T M^-1
        W)^-1 W^T M^-1 w_k P`` with the sign of ``P`` fixed by the wall, so whether a held
        contact would have to pull is known from the geometry alone: such contacts are
        released (the worst first, then the rest is re-examined).
        """
        held = list(stick)
        while held:
            W, _, Gi, _ = self.held(tuple(held))
            r = Gi @ (W.T @ self.Mw[k])
            pull = [s_j * wall * r[i] for i, (_, s_j) in enumerate(held)]
            worst = int(np.argmax(pull))
            if pull[worst] <= 1e-12 * (1.0 + float(np.abs(r).max())):
                break
            del held[worst]
        return tuple(held)

    def impact(self, k, stick):
        """Newton's law of contact ``k`` with the contacts of ``stick`` held: ``(R, r)``."""
        c = self.contacts[k]
        mw = self.Mw[k]
        if stick:
            W, MW, Gi, _ = self.held(stick)
            mw = mw - MW @ (Gi @ (W.T @ mw))
        wmw = float(c.normal @ mw)
        if not wmw > 1e-12 * float(c.normal @ self.Mw[k]):
            return None                      # k is held through the others: cannot fire
        R = np.eye(self.N)
        R[np.ix_(self.iv, self.iv)] = (np.eye(self.n)
                                       - (1.0 + c.restitution) * np.outer(mw, c.normal) / wmw)
        return R, np.zeros(self.N)

    def flow(self, config, stick):
        """``(A, b, lam_rows (s, N), lam_b (s,))`` of a mode (``None`` multipliers if free)."""
        A, b = self.loop.A.copy(), self.loop.b.copy()
        iq, iv = self.iq, self.iv
        for j, s in enumerate(config):
            if s == 0:
                continue
            c = self.contacts[j]
            A[np.ix_(iv, iq)] -= c.stiffness * np.outer(self.Mw[j], c.normal)
            A[np.ix_(iv, iv)] -= c.damping * np.outer(self.Mw[j], c.normal)
            b[iv] += c.stiffness * self.bound(j, s) * self.Mw[j]
        if not stick:
            return A, b, None, None
        W, MW, Gi, _ = self.held(stick)
        lam_rows = -Gi @ (W.T @ A[iv])
        lam_b = -Gi @ (W.T @ b[iv])
        A[iv] += MW @ lam_rows
        b[iv] += MW @ lam_b
        return A, b, lam_rows, lam_b


def _add(stick, k, wall):
    return tuple(sorted(set(stick) | {(k, wall)}))


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
    geo = _Geometry(loop, contacts)
    impact = {(k, w): geo.impact(k, ()) for k, c in enumerate(contacts) if c.rigid
              for w, _ in c.bounds}
    plastic = {(k, w): geo.projection(((k, w),)) for k, c in enumerate(contacts) if c.rigid
               for w, _ in c.bounds}
    choices = [(0,) + tuple(w for w, _ in c.bounds) if not c.rigid else (0,) for c in contacts]
    held = [((0, None),) if not c.rigid else ((0, None),) + tuple((1, w) for w, _ in c.bounds)
            for c in contacts]
    sticks = []
    for combo in itertools.product(*held):
        stick = tuple((k, w) for k, (on, w) in enumerate(combo) if on)
        if not stick or geo.held(stick) is not None:
            sticks.append(stick)
    modes, minfo, ginfo = [], {}, {}
    for config in itertools.product(*choices):
        for stick in sticks:
            name = _mode_name(config, stick)
            minfo[name] = ModeInfo(name, tuple(config), stick)
            A, b, lam_rows, lam_b = geo.flow(config, stick)
            guards = _guards(geo, config, stick, lam_rows, lam_b, name, ginfo, set(sticks))
            modes.append(Mode(name, A, b=b, guards=tuple(guards)))
    ha = HybridAutomaton(modes, state_names=loop.state_names)
    return MechanicalAutomaton(automaton=ha, loop=loop, contacts=contacts, modes=minfo,
                               guards=ginfo, gap_rows=geo.gap, impact_resets=impact,
                               plastic_resets=plastic,
                               free_mode=_mode_name((0,) * len(contacts), ()))


def _guards(geo, config, stick, lam_rows, lam_b, name, ginfo, sticks):
    loop, contacts, gap = geo.loop, geo.contacts, geo.gap
    held = {k for k, _ in stick}
    out = []
    for k, c in enumerate(contacts):
        if k in held:
            continue
        for wall, bound in c.bounds:
            if c.rigid:
                if geo.impact(k, stick) is None:
                    continue                 # k cannot move while the others are held
                kept = geo.impact_held(k, wall, stick)
                reset = geo.impact(k, kept)
                gname = f"contact{k}{_sign(wall)}"
                to = _add(kept, k, wall)
                zt = (dict(zeno_target=_mode_name(config, to), zeno_reset=geo.projection(to))
                      if to in sticks else {})
                out.append(Guard(gname, c=-wall * gap[k], d=wall * bound, direction=-1,
                                 reset=reset, target=_mode_name(config, kept), priority=2,
                                 **zt))
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
    for i, (k, wall) in enumerate(stick):
        gname = f"release{k}{_sign(wall)}"
        rest = tuple(s for s in stick if s[0] != k)
        out.append(Guard(gname, c=-wall * lam_rows[i], d=-wall * float(lam_b[i]), direction=-1,
                         reset=geo.projection(stick), target=_mode_name(config, rest),
                         priority=1))
        ginfo[(name, gname)] = GuardInfo("release", k, wall)
    if loop.sampled:
        cl = np.zeros(loop.n_states)
        cl[loop.layout["clock"]] = 1.0
        out.append(Guard("sample", c=cl, d=-loop.dt, direction=+1, reset=loop.sample_reset,
                         priority=0))
        ginfo[(name, "sample")] = GuardInfo("sample", -1, 0)
    return out
