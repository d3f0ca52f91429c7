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
  the held contacts and ``k`` form one multi-contact impact (:mod:`hybridpd.mechanics.impact`):
  since the held contacts have zero normal velocity, which of them keep pushing (stay held)
  and which are released is the same for every closing speed, so it is solved once when the
  mode is built (:meth:`_Geometry.impact_held`); target the mode holding what stays held (the
  same mode if all do); accumulating impacts enter the mode that also holds ``k`` through the
  plastic projection onto all of its contacts (``zeno_target``; none if the normals are
  dependent: the run then ends with ``ZENO``; the projection is the mode builder's
  ``zeno_reset``, packed the first time an accumulation uses it). Impact guards form
  simultaneity group 1: when
  another rigid contact is on its bound or closing onto it at the same instant, the joint
  impact is solved by :func:`~hybridpd.mechanics.impact.multi_impact` at run time
  (:meth:`MechanicalAutomaton.resolver`); the contacts it leaves at rest are held if their
  forces push (a complementarity problem in the contact forces, so that no contact enters a
  sticking phase whose force already pulls). A contact that fires again at one instant (its
  impacts alternating with a neighbour's faster than time resolves them) goes to the
  resolver as well, with every contact on its bound: their impacts follow each other to the
  end (:func:`~hybridpd.mechanics.impact.impact_cascade`), or where they accumulate to their
  plastic limit, the contacts then at rest held as above (kind ``'zeno'``).
* ``release{k}{+|-}`` (``k`` in ``S``): ``g = -wall * lambda_k + delta_k``: the contact force
  pulls by the margin ``delta_k = RELEASE_MARGIN (|c_k|_1 max(1, |bounds|) + |d_k|)`` (``c_k,
  d_k`` the affine force row), so that the free flow entered at the release separates
  clearly; a force that only touches zero within rounding (and would be undone by a
  re-impact at zero relative velocity, a sticking interval of zero length) releases nothing;
  reset the plastic projection onto ``S`` (so that rounding accumulated while
  sticking cannot leave the flow outside a gap), target the mode sticking on ``S - {k}``.
* ``enter{j}{+|-}`` / ``leave{j}{+|-}`` (compliant ``j``): the penetration changes sign;
  identity reset, target the configuration with ``j`` engaged / released.
* ``sample`` (sampled-data loops; ``sample{i}`` per sampled controller ``i`` when several
  are sampled): ``g = s - dt`` with ``direction = +1`` on that controller's clock; reset its
  own sampling jump (:attr:`LoopChannel.sample_reset
  <hybridpd.mechanics.loop.LoopChannel.sample_reset>`); target the same mode.

Priorities for simultaneous events: impacts and compliant switches 2, releases 1, samples 0.

Modes on demand: there is one mode per compliant configuration (``prod_j (1 + number of
bounds of j)`` over the compliant contacts) times one per set of held rigid contacts with
independent normals, up to ``3^m`` for ``m`` contacts. Only the free mode is built with the
model (``O(m)`` work besides its own tables); every other mode is built, compiled into the
kernel's tables and cached the first time a run enters it, so cost and memory grow with the
modes visited. An analysis that needs every mode calls
:meth:`HybridAutomaton.materialize <hybridpd.hybrid.automaton.HybridAutomaton.materialize>`
(implicitly through ``automaton.modes`` or ``automaton.packed``), bounded by ``max_modes``.
"""
from __future__ import annotations

import functools
import re
from dataclasses import dataclass, field

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.hybrid.automaton import Guard, HybridAutomaton, Mode, ZenoOptions
from hybridpd.mechanics.contacts import Contact
from hybridpd.mechanics.impact import impact_cascade, multi_impact, solve_lcp
from hybridpd.mechanics.loop import MechanicalLoop
from hybridpd.mechanics.tables import (
    _GUARD_RE,
    _GuardTable,
    _ModeTable,
    _ResetTable,
)

__all__ = ["MechanicalAutomaton", "build_automaton"]

_STICK_RE = re.compile(r"(\d+)([+-])")
#: relative margin by which a held contact's force must pull before it is released
RELEASE_MARGIN = 1e-9
#: resolve an accumulation until its extrapolated tail is this short (relative to 1 + |t|)
ZENO_TAIL_TOL = 1e-12
_EPS = float(np.finfo(float).eps)
#: contacts within this (relative) of their bounds take part in an accumulation's limit
_TOUCH_RTOL = 1e-12
_CACHE_SIZE = 512              # impact laws and projections kept for the next modes built


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class MechanicalAutomaton:
    """The hybrid automaton of a controlled mechanical system, with its metadata.

    Attributes
    ----------
    automaton : HybridAutomaton
    loop : MechanicalLoop
        Closed loop (state layout in ``loop.layout``, names in ``loop.state_names``).
    contacts : tuple of Contact
    modes : Mapping
        Mode name -> :class:`ModeInfo` (any valid mode name can be looked up; iteration
        and ``len`` cover the modes built or named so far).
    guards : Mapping
        ``(mode name, guard name)`` -> :class:`GuardInfo` (looked up from the names).
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
    _geometry: object = field(default=None, repr=False)
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
        k = int(contact)
        ok = 0 <= k < len(self.contacts) and any(w == wall for w, _ in self.contacts[k].bounds)
        if ok:
            rigid = self.contacts[k].rigid
            ok = rigid if kind in ("impact", "release") else not rigid
        if not ok:
            raise ValueError(f"no guard {name!r} (contact {contact}, wall {wall:+d})")
        return name

    def resolver(self, time_tol: float = 1e-12):
        """The joint-impact resolver for :meth:`HybridAutomaton.simulate` (module docstring).

        ``resolver(mode, guard, t, z)`` collects the active rigid contacts at ``z`` (the
        firing one, those on a bound within the location tolerance or closing onto it within
        ``time_tol (1 + |t|)``, and every held one), solves their joint impact
        (:func:`~hybridpd.mechanics.impact.multi_impact`) and returns ``(z_post, target
        mode, impact guard names)``, or ``None`` when the LCP has no non-degenerate solution.
        ``resolver(..., refire=k)`` (a contact firing again at one instant, the ``k``-th time
        there) resolves the contacts on their bounds together (module docstring) and may
        return a fourth entry, the kind ``'zeno'``.
        """
        # a partial, not a closure: sections that carry it go to worker processes
        return functools.partial(_resolve, self, time_tol)

    def initial_state(self, q0, v0, t0: float = 0.0, controller_state=None) -> np.ndarray:
        """Full state at ``t0`` (see :meth:`MechanicalLoop.initial_state`)."""
        return self.loop.initial_state(q0, v0, t0, controller_state)

    def initial_mode(self, z0, rtol: float = 1e-12) -> str:
        """Mode to start in from ``z0``; ``ValueError`` naming the violated contact.

        Every rigid contact's gap must lie in its bounds (to ``rtol`` relative to
        ``1 + |bound|``); a compliant contact whose gap is beyond a bound starts engaged
        there (its spring compressed), else disengaged (:meth:`mode_at`).
        """
        z0 = np.asarray(z0, dtype=float)
        for k, c in enumerate(self.contacts):
            if not c.rigid:
                continue
            s = float(self.gap_rows[k] @ z0)
            for wall, bound in c.bounds:
                if wall * (s - bound) > rtol * (1.0 + abs(bound)):
                    side = "hi" if wall > 0 else "lo"
                    raise ValueError(
                        f"initial: the state is outside contact {k}{_label(c)}: gap {s:.12g} "
                        f"beyond {side} = {bound:g}")
        return self.mode_at(z0, self.free_mode)

    def mode_at(self, z, mode: str) -> str:
        """``mode`` with its compliant configuration read from the state ``z``.

        A compliant contact is engaged at a bound exactly when its gap is beyond it (its
        spring acts while the gap is closed) and disengaged when the gap is strictly inside;
        on the bound itself ``mode`` decides. The held (rigid) contacts are ``mode``'s.

        Examples
        --------
        >>> from hybridpd.mechanics.modelfile import model_from_dict
        >>> m = model_from_dict({"system": {"dofs": ["x"], "masses": [1.0], "input": [1.0]},
        ...     "contact": [{"dof": "x", "hi": 0.1, "stiffness": 1e4}],
        ...     "controller": {"type": "pd", "kp": 1.0, "kv": 1.0, "measure": "x"},
        ...     "initial": {"q": [0.0], "v": [0.0]}})
        >>> ha = m.automaton
        >>> z = np.zeros(ha.automaton.n_states); z[ha.layout["q"][0]] = 0.12
        >>> ha.mode_at(z, "free"), ha.mode_at(0 * z, "free/c0+")
        ('free/c0+', 'free')
        """
        if all(c.rigid for c in self.contacts):
            return mode
        config, stick = _parse_mode(mode, self.contacts, self._geometry)
        config = list(config)
        z = np.asarray(z, dtype=float)
        for k, c in enumerate(self.contacts):
            if c.rigid:
                continue
            s = float(self.gap_rows[k] @ z)
            beyond = [w for w, b in c.bounds if w * (s - b) > 0]
            inside = all(w * (s - b) < 0 for w, b in c.bounds)
            if beyond:
                config[k] = beyond[0]
            elif inside:
                config[k] = 0
        return _mode_name(tuple(config), stick)


def _active(model, z, t, time_tol, stick, fired, touching=False):
    """Rigid contacts on a bound (or closing onto it within the tolerance) at state ``z``:
    ``(k, wall, held)``. With ``touching`` a contact on its bound takes part even while it
    separates (the contacts of an accumulation, which must not close again)."""
    iv = model.layout["v"]
    v = z[iv]
    held = dict(stick)
    tau = time_tol * (1.0 + abs(t))
    out = []
    for k, c in enumerate(model.contacts):
        if not c.rigid:
            continue
        if k in held:
            out.append((k, held[k], True))
            continue
        if k == fired[0]:
            out.append((k, fired[1], False))
            continue
        row = model.gap_rows[k]
        s = float(row @ z)
        scale = float(np.abs(row * z).sum())
        sd = float(c.normal @ v)
        sdscale = float(np.abs(c.normal * v).sum())
        for wall, bound in c.bounds:
            dist = wall * (bound - s)               # > 0 inside
            closing = wall * sd
            if closing < -64 * _EPS * sdscale and not touching:
                continue
            # an accumulation's contacts are on their bounds to the precision of the event
            # location (the guard's rounding bound, ~1e-13 relative), not to a few ulps
            rtol = _TOUCH_RTOL if touching else 64 * _EPS
            if dist <= rtol * (scale + abs(bound)) + max(closing, 0) * tau:
                out.append((k, wall, False))
    return out


def _resolve(model, time_tol, mode, guard, t, z, refire=0):
    """The joint jump of the active contacts (``refire = 0``), or of every contact on its
    bound when a contact fires again at one instant (``refire`` times so far).

    The first time the impacts of those contacts follow each other to their end
    (:func:`~hybridpd.mechanics.impact.impact_cascade`: one at a time, with the held ones,
    to the plastic limit where they accumulate); after that the contacts are at rest on
    their bounds and pushed in, and their limit is the plastic joint impact. Contacts left
    at zero relative velocity whose forces push are held (:func:`_hold`); where impacts
    accumulated the jump has kind ``'zeno'``, one record per newly held contact, and the
    state is projected onto the held contacts (as the plastic projection of a single
    contact's accumulation).
    """
    info = model.modes[mode]
    gi = model.guards[(mode, guard)]
    geo = model._geometry
    fired = (gi.contact, gi.wall)
    act = _active(model, z, t, time_tol, info.stick, fired, refire > 0)
    iv = model.layout["v"]
    W = np.array([-wall * model.contacts[k].normal for k, wall, _ in act])
    e = np.array([model.contacts[k].restitution for k, _, _ in act])
    held = np.array([h for *_, h in act])
    if refire == 1:
        cas = impact_cascade(geo.Minv, W, z[iv], e, held)
        if cas is None:
            return None
        v1, still, limit = cas.v, cas.held, cas.accumulated
        hit = sorted(set(cas.hits))
    else:
        limit = refire >= 2
        out = multi_impact(geo.Minv, W, z[iv], np.zeros_like(e) if limit else e, held)
        if out is None:
            return None
        v1 = out.v
        # at zero relative velocity, relative to the velocities that make it up (as the
        # jump loop judges it)
        vscale = np.abs(W) @ (np.abs(z[iv]) + np.abs(v1))
        still = np.abs(out.u_post) <= 1e-10 * (
            vscale + float(np.abs(out.u_pre).max(initial=0.0)))
        scale = float(out.impulses.max(initial=0.0))
        hit = [i for i, (k, _, h) in enumerate(act) if not h and (
            k == gi.contact or out.u_pre[i] < 0.0 or out.impulses[i] > 1e-12 * scale)]
    z1 = np.array(z, dtype=float)
    z1[iv] = v1
    cand = [(k, wall) for (k, wall, _), s in zip(act, still) if s]
    # the contact that keeps firing is held at last, whatever the forces say: the jump loop
    # sees it at rest on its bound and pushed in (their judgements differ by rounding)
    forced = (fired,) if refire >= 3 and fired in cand else ()
    keep = _hold(geo, info.config, z1, cand, forced)
    if keep and geo.held(keep) is None:
        return None
    target = _mode_name(info.config, keep)
    new = sorted(set(keep) - set(info.stick))
    if limit and new:
        R, r = geo.projection(keep)
        return R @ z1 + r, target, [f"contact{k}{_sign(w)}" for k, w in new], "zeno"
    names = [f"contact{act[i][0]}{_sign(act[i][1])}" for i in hit if not act[i][2]]
    return z1, target, names or [f"contact{fired[0]}{_sign(fired[1])}"]


def _hold(geo, config, z, cand, always=()):
    """The contacts of ``cand`` (on their bounds at zero relative velocity) that stay held.

    Their forces ``f >= 0`` solve the LCP of the separating accelerations
    ``a = W a0 + W M^-1 W^T f >= 0``, ``f . a = 0`` (``a0``: the accelerations without the
    contacts, ``W`` the oriented normals): a contact that pushes, or whose acceleration
    apart is zero to a relative ``RELEASE_MARGIN``, stays held; one that accelerates apart
    is free. The set is then checked against the release guards of the mode that holds it
    (the same forces, with their margin): a contact they would release at once is dropped,
    so no contact enters a sticking phase whose force already pulls (a sticking interval of
    zero length). The contacts of ``always`` stay held whatever their forces.
    """
    if not cand:
        return ()
    A, b, _, _ = geo.flow(config, ())
    a0 = (A @ z + b)[geo.iv]
    W = np.array([-wall * geo.contacts[k].normal for k, wall in cand])
    Aw = W @ geo.Minv @ W.T
    q = W @ a0
    f = solve_lcp(Aw, q)
    if f is None:
        keep = list(cand)
    else:
        acc = Aw @ f + q
        # relative to the terms that make up the accelerations, as the release margin is
        # relative to the force's terms: near rest both vanish, and a contact the jump loop
        # sees at rest and pushed in must not be judged free on rounding
        terms = np.abs(A[geo.iv]) @ np.abs(z) + np.abs(b[geo.iv])
        tol = RELEASE_MARGIN * (np.abs(W) @ terms + np.abs(Aw) @ f)
        keep = [c for c, a, tl in zip(cand, acc, tol) if a <= tl or c in always]
    for _ in range(len(keep)):
        keep.sort()
        if not keep or geo.held(tuple(keep)) is None:
            break
        _, _, lam_rows, lam_b = geo.flow(config, tuple(keep))
        pull = np.array([w for _, w in keep]) * (lam_rows @ z + lam_b)
        margin = RELEASE_MARGIN * (np.abs(lam_rows).sum(axis=1) * geo.scale + np.abs(lam_b))
        excess = np.where([c in always for c in keep], -np.inf, pull - margin)
        worst = int(np.argmax(excess))
        if not excess[worst] > 0.0:
            break
        keep.pop(worst)
    return tuple(sorted(keep))


def _label(c):
    return f" ({c.name})" if c.name else ""


def _sign(w):
    return "+" if w > 0 else "-"


def _mode_name(config, stick):
    base = "free" if not stick else "stick" + "".join(f"{k}{_sign(w)}" for k, w in stick)
    eng = [f"c{j}{_sign(s)}" for j, s in enumerate(config) if s]
    return base + ("/" + ",".join(eng) if eng else "")


class _LoopData:
    """The parts of a :class:`MechanicalLoop` that building a mode reads.

    ``samplers``: per sampled controller ``(guard name, controller index, clock index, dt,
    reset)``; ``sample_guards``: guard name -> controller index.
    """

    def __init__(self, loop):
        self.system, self.A, self.b = loop.system, loop.A, loop.b
        self.layout, self.n_states = loop.layout, loop.n_states
        self.samplers = tuple((ch.guard, ch.index, ch.clock, ch.dt, ch.sample_reset)
                              for ch in loop.channels if ch.sampled)
        self.sample_guards = {g: i for g, i, *_ in self.samplers}


class _Geometry:
    """Normals, bounds and the metric of ``M`` on the closed-loop state."""

    def __init__(self, loop, contacts):
        sysm = loop.system
        # the numbers the modes need, without python-control objects (automata pickle)
        self.loop = _LoopData(loop)
        self.contacts = contacts
        N, lay = loop.n_states, loop.layout
        for k, c in enumerate(contacts):
            if not isinstance(c, Contact):
                raise ValueError(f"contacts[{k}] must be a Contact")
            if c.normal.shape != (sysm.n,):
                raise ValueError(f"contact {k}: normal must have shape ({sysm.n},), got "
                                 f"{c.normal.shape}")
        self.n, self.N = sysm.n, N
        self.iq, self.iv = lay["q"], lay["v"]
        self.Minv = np.linalg.inv(sysm.M)
        self._held = {}
        self._cache = {}
        self.scale = max([1.0] + [abs(b) for c in contacts for _, b in c.bounds])
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
        key = tuple(stick)
        if key not in self._held:
            self._held[key] = self._held_uncached(key)
        return self._held[key]

    def _held_uncached(self, stick):
        ks = [k for k, _ in stick]
        W = np.array([self.contacts[k].normal for k in ks]).T
        MW = self.Mw[ks].T
        G = W.T @ MW
        if np.linalg.cond(G) > 1e10:
            return None
        beta = np.array([self.bound(k, w) for k, w in stick])
        return W, MW, np.linalg.inv(G), beta

    def _cached(self, key, fn, *args):
        # a contact's impact law and a projection recur in the modes built one after the
        # other: the last few are kept (the packed tables keep every one, once)
        out = self._cache.pop(key, self)
        if out is self:
            out = fn(*args)
        self._cache[key] = out
        while len(self._cache) > _CACHE_SIZE:
            self._cache.pop(next(iter(self._cache)))
        return out

    def projection(self, stick):
        """Plastic projection onto every contact of ``stick``: ``(R, r)`` or None."""
        return self._cached(("projection", tuple(stick)), self._projection, tuple(stick))

    def impact_held(self, k, wall, stick):
        """The contacts of ``stick`` that stay held through an impact of ``k`` at ``wall``
        (:meth:`_impact_held`)."""
        return self._cached(("held", k, wall, tuple(stick)), self._impact_held, k, wall,
                            tuple(stick))

    def impact(self, k, stick):
        """Newton's law of contact ``k`` with the contacts of ``stick`` held: ``(R, r)``, or
        None when the others hold ``k`` too (:meth:`_impact`)."""
        return self._cached(("impact", k, tuple(stick)), self._impact, k, tuple(stick))

    def _projection(self, stick):
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

    def _impact_held(self, k, wall, stick):
        """The contacts of ``stick`` that stay held through an impact of ``k`` at ``wall``.

        The joint impact of ``k`` and the held contacts (zero normal velocity) is an LCP
        whose ``q`` is ``-(1 + e) |u_k|`` times a unit vector, so its solution scales with the
        closing speed: it is solved once here (:func:`solve_lcp`); the held contacts that
        leave with a positive separating velocity are released, the others stay held.
        """
        if not stick:
            return ()
        rows = [self.contacts[j].normal * -s_j for j, s_j in stick]
        rows.append(self.contacts[k].normal * -wall)
        W = np.array(rows)
        A = W @ np.linalg.solve(self.loop.system.M, W.T)
        q = np.zeros(len(rows))
        q[-1] = -1.0
        lam = solve_lcp(A, q)
        if lam is None:
            return ()
        # released: only the held contacts that the impact sets moving apart (u+ > 0); one
        # that neither pushes nor moves stays held, its force decides its release
        u = A @ lam + q
        return tuple(s for i, s in enumerate(stick) if u[i] <= 1e-12 * float(lam.max()))

    def _impact(self, k, stick):
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


def build_automaton(loop: MechanicalLoop, contacts, max_modes: int = 4096
                    ) -> MechanicalAutomaton:
    """Build the hybrid automaton of ``loop`` with ``contacts`` (see the module docstring).

    Only the free mode is built here; the others are built the first time a run enters them.

    Parameters
    ----------
    loop : MechanicalLoop
    contacts : sequence of Contact
        Normals of shape ``(n,)``; the index in this sequence is the contact number.
    max_modes : int
        Bound on the modes an analysis of every mode may build (``automaton.materialize``).

    Returns
    -------
    MechanicalAutomaton

    Examples
    --------
    >>> from hybridpd.mechanics import Contact, MechanicalSystem, Reference, mechanical_loop
    >>> sysm = MechanicalSystem(["x1", "x2"], M=[[0.1, 0], [0, 1.0]], B=[0, 1])
    >>> loop = mechanical_loop(sysm, (10.0, 20.0), Reference.sine(1.0, 5.0, 1.0), "x2")
    >>> ma = build_automaton(loop, [Contact([1, -1], -0.75, 0.75, restitution=0.5)])
    >>> ma.automaton.n_built
    1
    >>> ma.automaton.mode_names
    ('free', 'stick0-', 'stick0+')
    >>> ma.guards[("free", "contact0+")]
    GuardInfo(kind='impact', contact=0, wall=1)
    """
    if not isinstance(loop, MechanicalLoop):
        raise ValueError("loop must be a MechanicalLoop")
    contacts = tuple(contacts)
    geo = _Geometry(loop, contacts)

    builder = _ModeBuilder(geo)
    free = _mode_name((0,) * len(contacts), ())
    # the automaton's own accumulation rule, so that its simulations and the maps of its
    # sections end an accumulation at the same (resolved) point
    ha = HybridAutomaton([builder(free)], state_names=loop.state_names, mode_builder=builder,
                         max_modes=max_modes, zeno=ZenoOptions(tail_tol=ZENO_TAIL_TOL))
    return MechanicalAutomaton(automaton=ha, loop=loop, contacts=contacts,
                               modes=_ModeTable(ha, functools.partial(
                                   _parse_mode, contacts=contacts, geo=geo)),
                               guards=_GuardTable(ha, geo.loop.sample_guards),
                               gap_rows=geo.gap, impact_resets=_ResetTable(geo, "impact"),
                               plastic_resets=_ResetTable(geo, "plastic"), free_mode=free,
                               _geometry=geo)


class _ModeBuilder:
    """Builds the mode called ``name`` (a module-level class: automata pickle for workers)."""

    def __init__(self, geo):
        self.geo = geo
        # the guards of every mode, known without building them (signature tables)
        names = [g for g, *_ in geo.loop.samplers]
        for k, c in enumerate(geo.contacts):
            for wall, _ in c.bounds:
                kinds = ("contact", "release") if c.rigid else ("enter", "leave")
                names += [f"{kind}{k}{_sign(wall)}" for kind in kinds]
        self.guard_names = tuple(sorted(names))

    def zeno_reset(self, mode, guard):
        """The Zeno reset ``(R, r)`` of the impact guard ``guard`` of ``mode``: the plastic
        projection onto the contacts held after the accumulation."""
        geo = self.geo
        _, stick = _parse_mode(mode, geo.contacts, geo)
        m = _GUARD_RE.match(guard)
        if m is None or m.group(1) != "contact":
            raise ValueError(f"guard {guard!r} of mode {mode!r} has no Zeno reset")
        k, wall = int(m.group(2)), 1 if m.group(3) == "+" else -1
        return geo.projection(_add(geo.impact_held(k, wall, stick), k, wall))

    def __call__(self, name):
        geo = self.geo
        config, stick = _parse_mode(name, geo.contacts, geo)
        A, b, lam_rows, lam_b = geo.flow(config, stick)
        guards = _guards(geo, config, stick, lam_rows, lam_b)
        return Mode(name, A, b=b, guards=tuple(guards))


def _parse_mode(name, contacts, geo):
    """``(config, stick)`` of a mode name; ``ValueError`` if it names no mode."""
    if not isinstance(name, str):
        raise ValueError(f"mode name must be a string, got {name!r}")
    base, _, eng = name.partition("/")
    config = [0] * len(contacts)
    stick = []
    if base.startswith("stick"):
        if re.fullmatch(r"(?:\d+[+-])+", base[5:]) is None:
            raise ValueError(f"unknown mode {name!r}")
        stick = [(int(k), 1 if sg == "+" else -1) for k, sg in _STICK_RE.findall(base[5:])]
    elif base != "free":
        raise ValueError(f"unknown mode {name!r}")
    for part in eng.split(",") if eng else ():
        m = re.fullmatch(r"c(\d+)([+-])", part)
        if m is None:
            raise ValueError(f"unknown mode {name!r}")
        j = int(m.group(1))
        if j >= len(contacts) or contacts[j].rigid or config[j]:
            raise ValueError(f"unknown mode {name!r}")
        config[j] = 1 if m.group(2) == "+" else -1
    for k, w in stick:
        if k >= len(contacts) or not contacts[k].rigid:
            raise ValueError(f"unknown mode {name!r}")
    for j, w in list(enumerate(config)) + stick:
        if w and not any(b == w for b, _ in contacts[j].bounds):
            raise ValueError(f"unknown mode {name!r}: contact {j} has no bound on that side")
    stick = tuple(stick)
    if list(stick) != sorted(set(stick)) or len({k for k, _ in stick}) != len(stick):
        raise ValueError(f"unknown mode {name!r}")
    if stick and geo.held(stick) is None:
        raise ValueError(f"unknown mode {name!r}: the held contacts have dependent normals")
    if _mode_name(tuple(config), stick) != name:
        raise ValueError(f"unknown mode {name!r}")
    return tuple(config), stick


def _guards(geo, config, stick, lam_rows, lam_b):
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
                # its Zeno reset, the projection onto `to`, is asked for when first used
                # (_ModeBuilder.zeno_reset): most accumulations never happen in most modes
                zt = ({"zeno_target": _mode_name(config, to)}
                      if geo.held(to) is not None else {})
                out.append(Guard(gname, c=-wall * gap[k], d=wall * bound, direction=-1,
                                 reset=reset, target=_mode_name(config, kept), priority=2,
                                 group=1, **zt))
            elif config[k] == 0:
                cfg = list(config)
                cfg[k] = wall
                gname = f"enter{k}{_sign(wall)}"
                out.append(Guard(gname, c=-wall * gap[k], d=wall * bound, direction=-1,
                                 target=_mode_name(tuple(cfg), stick), priority=2))
            elif config[k] == wall:
                cfg = list(config)
                cfg[k] = 0
                gname = f"leave{k}{_sign(wall)}"
                out.append(Guard(gname, c=wall * gap[k], d=-wall * bound, direction=-1,
                                 target=_mode_name(tuple(cfg), stick), priority=2))
    for i, (k, wall) in enumerate(stick):
        gname = f"release{k}{_sign(wall)}"
        rest = tuple(s for s in stick if s[0] != k)
        margin = RELEASE_MARGIN * (float(np.abs(lam_rows[i]).sum()) * geo.scale
                                   + abs(float(lam_b[i])))
        out.append(Guard(gname, c=-wall * lam_rows[i], d=-wall * float(lam_b[i]) + margin,
                         direction=-1, reset=geo.projection(stick),
                         target=_mode_name(config, rest), priority=1))
    for gname, _, clock, dt, reset in loop.samplers:
        cl = np.zeros(loop.n_states)
        cl[clock] = 1.0
        out.append(Guard(gname, c=cl, d=-dt, direction=+1, reset=reset, priority=0))
    return out
