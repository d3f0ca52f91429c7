"""The sections of a model file: which one, where its phase is, and what a simulation shows.

:class:`SectionSpec` names a section of a :class:`~hybridpd.mechanics.modelfile.MechanicalModel`
and the orbits sought on it: by default (``event="auto"``) the stroboscopic section of a
model with a periodic reference (:class:`~hybridpd.analysis.strobe.StroboscopicMap`: the
state at the phase ``phi0``, one common period of the reference and the sampling later), the
event section that the simulated motion crosses otherwise, or a contact's impacts or
releases (:class:`~hybridpd.analysis.hybridmap.SectionMap`). :func:`simulated_returns` reads
a simulation of the model: the section's mode, its phase (:func:`choose_phase`: where no
jump other than a sample happens near it) and the candidate numbers of returns per orbit.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from hybridpd.analysis.hybridmap import SectionMap
from hybridpd.analysis.strobe import StroboscopicMap
from hybridpd.mechanics.sections import mechanical_section, stroboscopic_section

__all__ = ["EVENTS", "DivergedRun", "SectionSpec", "SimulatedReturns", "choose_phase",
           "default_phase", "fix_section", "section_words", "simulated_returns"]

#: The sections of a model: ``"auto"`` (the stroboscopic one for a periodic reference, else
#: the event section the simulated motion crosses), ``"stroboscopic"`` (the state at one
#: phase of the reference, one common period later), ``"impact"`` and ``"release"`` (a
#: contact's impacts, or the ends of its sticking phases).
EVENTS = ("auto", "stroboscopic", "impact", "release")


@dataclass(frozen=True)
class SectionSpec:
    """Which section and which orbits.

    ``event`` (:data:`EVENTS`): ``"auto"`` (default) is the stroboscopic section for a model
    with a periodic reference and otherwise the event section its simulated motion crosses
    (:func:`fix_section`); ``"stroboscopic"``: the state at the phase ``phase`` of the
    reference, one common period later (``phase`` None: chosen from a simulation where no
    jump other than a sample happens near it, :func:`choose_phase`; :func:`fix_section`
    fixes it once for a sweep); ``"impact"``/``"release"``: contact ``contact`` (0-based) at
    its bound ``wall`` (``+1`` hi, ``-1`` lo, None: hi if it has one). ``mode``: the mode of
    the section's states, or in which its guard fires (None: the one a simulation of the
    model shows, e.g. ``"stick0+1+"`` when contact 0 releases while contact 1 is held).
    ``period``: the returns per orbit (``k`` of ``P^k``), or ``"auto"``: the neighbours'
    ``k``, then ``k = 1`` and every ``k <= max_period`` after which the simulated motion
    returns (whole reference periods for an event section); ``periods`` reference periods
    per orbit (None: any); Newton's ``tol`` and ``max_iter``; the seeding simulation's
    ``transient`` (reference periods); the bound ``t_max`` on one application of an event
    map (reference periods per return); the ``jacobian`` of Newton and of the multipliers
    (``"fd"``: central differences of the simulated map, ``"exact"``: the saltation chain).
    """

    contact: int = 0
    wall: int | None = None
    event: str = "auto"
    period: int | str = "auto"
    periods: int | None = None
    tol: float = 1e-10
    max_iter: int = 25
    transient: float = 30.0
    t_max: float = 20.0
    jacobian: str = "exact"
    mode: str | None = None
    max_period: int = 4
    phase: float | None = None

    def __post_init__(self):
        if self.event not in EVENTS:
            raise ValueError(f"event must be one of {', '.join(EVENTS)}, got {self.event!r}")
        if self.phase is not None and (isinstance(self.phase, bool) or not
                                       math.isfinite(float(self.phase))
                                       or float(self.phase) < 0):
            raise ValueError(f"phase must be None or a finite number >= 0, got "
                             f"{self.phase!r}")
        if self.period != "auto" and (isinstance(self.period, (bool, str))
                                      or int(self.period) != self.period or self.period < 1):
            raise ValueError(f"period must be an int >= 1 or 'auto', got {self.period!r}")
        if isinstance(self.max_period, bool) or int(self.max_period) != self.max_period or \
                not 1 <= self.max_period <= 64:
            raise ValueError(f"max_period must be an int in [1, 64], got {self.max_period!r}")
        if self.periods is not None and (int(self.periods) != self.periods or self.periods < 1):
            raise ValueError(f"periods must be None or an int >= 1, got {self.periods!r}")
        if self.jacobian not in ("exact", "fd"):
            raise ValueError(f"jacobian must be 'exact' or 'fd', got {self.jacobian!r}")
        if self.wall not in (None, 1, -1):
            raise ValueError(f"wall must be +1, -1 or None, got {self.wall!r}")
        if self.mode is not None and not isinstance(self.mode, str):
            raise ValueError(f"mode must be a mode name or None, got {self.mode!r}")
        for name in ("tol", "transient", "t_max"):
            v = getattr(self, name)
            if not (math.isfinite(float(v)) and float(v) > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v!r}")

    def _where(self, model) -> tuple:
        """``(contact, wall)`` checked against the model."""
        ma = model.automaton
        n = len(ma.contacts)
        if isinstance(self.contact, bool) or int(self.contact) != self.contact or \
                not 0 <= int(self.contact) < n:
            raise ValueError(f"contact must be an index in [0, {n}), got {self.contact!r}")
        walls = [w for w, _ in ma.contacts[int(self.contact)].bounds]
        wall = self.wall if self.wall is not None else (1 if 1 in walls else -1)
        if wall not in walls:
            raise ValueError(f"wall must be one of {walls} for contact {self.contact}, got "
                             f"{wall!r}")
        return int(self.contact), wall

    def stroboscopic(self, model) -> bool:
        """Whether this is the stroboscopic section of `model` (``"auto"`` with a periodic
        reference)."""
        if self.event == "auto":
            return model.automaton.loop.reference_period is not None
        return self.event == "stroboscopic"

    def guard(self, model) -> str:
        """Name of the section's guard (``contact0+``, ``release1-``, ``enter2+``; None for
        the stroboscopic section)."""
        if self.stroboscopic(model):
            return None
        k, wall = self._where(model)
        c = model.automaton.contacts[k]
        if self.event == "release":
            if not c.rigid:
                raise ValueError(f"event 'release': contact {k} is compliant (no sticking)")
            return model.automaton.guard_name(k, wall, "release")
        return model.automaton.guard_name(k, wall, "impact" if c.rigid else "enter")

    def section_map(self, model, mode: str | None = None) -> SectionMap | StroboscopicMap:
        """The map ``P`` of this section of `model` in `mode` (default ``self.mode``, else
        the free mode for impacts and the mode holding the contact alone for releases);
        ValueError for a bad contact, wall or mode. The stroboscopic section is taken at
        ``phase`` (None: half a sample after the start of a sampled loop, else 0)."""
        if self.stroboscopic(model):
            phase = default_phase(model) if self.phase is None else float(self.phase)
            sec = stroboscopic_section(model.automaton, _wrap_phase(model, phase),
                                       mode=mode or self.mode, sample_time=model.t0)
            return StroboscopicMap(sec)
        k, wall = self._where(model)
        sec = mechanical_section(model.automaton, k, wall, event=self.event,
                                 mode=mode or self.mode, sample_time=model.t0)
        T = sec.reference_period if sec.has_phase else 1.0
        kmax = self.max_period if self.period == "auto" else int(self.period)
        t_max = self.t_max * kmax * T
        if sec.has_phase:
            t_max = max(t_max, 2.0 * kmax * sec.period)
        return SectionMap(sec, t_max=t_max, max_jumps=5000)

    def sampling_period(self, model):
        dt = float(getattr(model.automaton.loop, "dt", 0.0) or 0.0)
        return dt if dt > 0 else None


@dataclass(frozen=True)
class SimulatedReturns:
    """What a simulation shows of a section: where to start Newton, and with which ``k``.

    Attributes
    ----------
    mode : str
        The mode of the last crossing of the section's guard that starts a burst.
    candidates : tuple of (int, ndarray)
        ``(k, section point)`` to try, in order.
    text : str
        What the simulation showed, in words (for messages).
    """

    mode: str
    candidates: tuple
    text: str
    phase: float | None = None


class DivergedRun(ValueError):
    """The simulation of a model that seeds its section (its phase, mode and orbit guesses)
    diverged: it stopped as ``diverged`` or ``nonfinite``, or its positions and velocities
    grew past :data:`~hybridpd.analysis.periodic.DIVERGENCE_BOUND` times the scale of its
    start, ``max(1, |z0|, |bounds|)`` (the scale of the simulator's own bound)."""


def _check_run(model, h, what: str) -> None:
    """Raise :class:`DivergedRun` where the hybrid trajectory `h` of `model` (`what`, in
    the message) diverged, whatever else stopped it there."""
    # deferred import: periodic imports the maps this module builds
    from hybridpd.analysis.periodic import DIVERGENCE_BOUND

    ma = model.automaton
    z0 = ma.initial_state(model.x0[0::2], model.x0[1::2], model.t0)
    scale = max([1.0, float(np.max(np.abs(z0)))]
                + [abs(b) for c in ma.contacts for _, b in c.bounds])
    lay = ma.layout
    z = np.asarray(h.x_final, float)
    mech = z[np.concatenate([np.ravel(lay["q"]), np.ravel(lay["v"])]).astype(int)]
    name = h.termination.name.lower()
    if name in ("diverged", "nonfinite") or not np.all(np.isfinite(mech)):
        raise DivergedRun(f"{what} diverged: it stopped at t = {h.t_final:.6g} "
                          f"({getattr(h, 'reason', '') or name})")
    big = float(np.max(np.abs(mech), initial=0.0))
    if big > DIVERGENCE_BOUND * scale:
        raise DivergedRun(f"{what} diverged: its positions and velocities reached {big:.3g} "
                          f"at t = {h.t_final:.6g}, past {DIVERGENCE_BOUND:g} times the scale "
                          f"of its start ({scale:.3g})")


def _crossings(tr, guard):
    """Indices of the jumps of `guard` (any mode) that start a burst: a crossing after a jump
    of another guard (rebounds of one burst return within it)."""
    J = tr.jumps
    return [i for i in range(len(J)) if J.guard[i] == guard and J.kind[i] == "crossing"
            and (i == 0 or J.guard[i - 1] != guard)]


def simulated_returns(model, spec: SectionSpec, transient: float | None = None
                      ) -> SimulatedReturns:
    """Simulate `model` from its initial state and read the section's crossings.

    The section's mode is ``spec.mode`` or the mode of the last crossing; with
    ``spec.period = "auto"`` the candidates are every ``k <= spec.max_period`` after which the
    last crossing comes a whole number of reference periods after an earlier one (within
    ``1e-3 T``), the ones that also return close to the same state (``1e-3`` relative) first,
    then ``k = 1``; otherwise ``spec.period`` alone.

    Raises
    ------
    ValueError
        No crossing of the guard within the transient (the message says what the simulation
        did cross).
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.mechanics.simulate import simulate

    if spec.stroboscopic(model):
        return _strobe_returns(model, spec, transient)
    guard = spec.guard(model)
    P0 = spec.section_map(model)
    T = P0.section.reference_period if P0.section.has_phase else 1.0
    span = float(spec.transient * T if transient is None else transient)
    if not (span > 0 and math.isfinite(span)):
        raise ValueError(f"transient must be finite and > 0, got {transient!r}")
    tr = simulate(model.automaton, model.x0, (model.t0, model.t0 + span)).hybrid
    _check_run(model, tr, "the transient simulation from the file's initial state")
    J = tr.jumps
    hits = _crossings(tr, guard)
    hits = [i for i in hits if spec.mode is None or J.source[i] == spec.mode]
    if not hits:
        seen = {}
        for i in range(len(J)):
            if J.kind[i] == "crossing":
                seen[(J.guard[i], J.source[i])] = seen.get((J.guard[i], J.source[i]), 0) + 1
        top = ", ".join(f"{g} in {m} x {c}" for (g, m), c in
                        sorted(seen.items(), key=lambda t: -t[1])[:6]) or "no jump"
        where = f" in mode {spec.mode}" if spec.mode else ""
        raise ValueError(f"guess: the motion does not cross the section ({guard}{where}) within "
                         f"the transient of {span:g} (simulated from the file's initial state; "
                         f"its crossings: {top}); choose another contact or event, a longer "
                         "--transient, or give --guess")
    mode = J.source[hits[-1]]
    hits = [i for i in hits if J.source[i] == mode]
    P = spec.section_map(model, mode)
    pts = [P.section.from_state(J.pre[i], J.t[i]) for i in hits]
    text = (f"the simulation ({span:g} time units from the file's initial state) crosses "
            f"{guard} in mode {mode} {len(hits)} times") + _at_samples(J, hits)
    if spec.period != "auto":
        return SimulatedReturns(mode, ((int(spec.period), pts[-1]),), text)
    scale = max(1.0, float(np.max(np.abs(pts[-1]))))
    close, whole, notes = [], [], []
    for k in range(1, min(spec.max_period, len(hits) - 1) + 1):
        gap = J.t[hits[-1]] - J.t[hits[-1 - k]]
        m = round(gap / T)
        dist = float(np.max(np.abs(P.section.wrap(pts[-1] - pts[-1 - k])))) / scale
        notes.append(f"after {k}: {gap / T:.4g} T, distance {dist:.2g}")
        if m >= 1 and abs(gap - m * T) <= 1e-3 * T:
            (close if dist <= 1e-3 else whole).append((dist, k))
    order = sorted(k for _, k in close) + [1] + [k for _, k in sorted(whole)]
    ks = list(dict.fromkeys(order))[:3]
    if notes:
        text += "; returns " + "; ".join(notes)
    return SimulatedReturns(mode, tuple((k, pts[-1]) for k in ks), text)


def _at_samples(J, hits) -> str:
    """What to say when crossings of an event section come at sample instants.

    A sampled controller's held input steps there, and the step itself carries the state
    across the guard (a contact released by the new input): the flow never crosses the
    guard, so the event section's map is not defined at such points.
    """
    samples = {float(J.t[j]) for j in range(len(J)) if J.guard[j] == "sample"}
    n = sum(float(J.t[i]) in samples for i in hits)
    if not n:
        return ""
    return (f", {n} of them at a sample instant (the held input's step moves the state "
            "across the guard, where this section's map is not defined; the stroboscopic "
            "section is)")


def _default_transient(model, spec):
    T = model.automaton.loop.reference_period
    return 50.0 * T if T else 200.0


# ----------------------------------------------------------------------------------------
# the stroboscopic section of a model: its phase, and what a simulation shows of it
# ----------------------------------------------------------------------------------------
def _common_period(model) -> float:
    return stroboscopic_section(model.automaton, 0.0, sample_time=model.t0).period


def _wrap_phase(model, phase) -> float:
    """``phase`` reduced to ``[0, Tc)``."""
    Tc = _common_period(model)
    p = float(phase) % Tc
    return 0.0 if p >= Tc else p


def _sample_grid(model, Tc) -> np.ndarray:
    """Every sampling instant of every sampled controller in ``[0, Tc)`` (phases)."""
    clocks = getattr(model.automaton.loop, "clocks", ()) or ()
    pts = [((model.t0 + j * dt) % Tc) for _, dt in clocks for j in range(round(Tc / dt))]
    return np.unique(np.round(np.asarray(pts, float), 15)) if pts else np.zeros(0)


def default_phase(model) -> float:
    """The phase of the stroboscopic section when no simulation chose one: half the
    shortest sampling period after the start of a sampled loop (never on a sample), else 0."""
    clocks = getattr(model.automaton.loop, "clocks", ()) or ()
    if not clocks:
        return 0.0
    return _wrap_phase(model, model.t0 + 0.5 * min(dt for _, dt in clocks))


def choose_phase(model, tr, t_end: float) -> tuple:
    """``(phase, margin)``: where to cut the motion of the trajectory `tr` over its last
    common period before `t_end`: among the candidates at least half as far (in time, modulo
    ``Tc``) from every jump of that period other than a sample as the farthest one, the
    farthest in the free mode if there is one, else the farthest. The candidates are
    the midpoints between consecutive sampling instants of a sampled loop, else 256 phases
    across ``Tc``. ``margin``: the distance to the nearest such jump."""
    Tc = _common_period(model)
    samples = {ch.guard for ch in model.automaton.loop.channels if ch.sampled}
    J = tr.jumps
    ev = np.array([J.t[i] % Tc for i in range(len(J)) if J.t[i] >= t_end - Tc
                   and J.guard[i] not in samples], float)
    grid = _sample_grid(model, Tc)
    if grid.size:
        nxt = np.append(grid[1:], grid[0] + Tc)
        cand = (0.5 * (grid + nxt)) % Tc
    else:
        cand = (np.arange(256) + 0.5) * Tc / 256
    if ev.size:
        d = np.abs(cand[:, None] - ev[None, :])
        margin = np.min(np.minimum(d, Tc - d), axis=1)
    else:
        margin = np.full(cand.size, Tc)
    free = model.automaton.free_mode
    t_c = t_end - Tc + ((cand - (t_end - Tc)) % Tc)
    is_free = np.array([_mode_at(tr, t) == free for t in t_c])
    # the free mode (its chart holds every state) where its margin is at least half the
    # largest: a phase half a sample after a release would put neighbouring parameter values
    # on either side of it
    wide = margin >= 0.5 * float(margin.max())
    best = int(np.lexsort((-margin, ~(is_free & wide), ~wide))[0])
    return float(cand[best]), float(margin[best])


def _mode_at(tr, t) -> str:
    """The mode of a hybrid trajectory at time `t` (the segment holding it)."""
    S = tr.segments
    i = int(np.searchsorted(np.asarray(S.t_start), t, side="right")) - 1
    return S.mode[max(i, 0)]


def _strobe_returns(model, spec, transient) -> SimulatedReturns:
    """:func:`simulated_returns` on the stroboscopic section: the motion simulated for the
    transient, the phase chosen (:func:`choose_phase`, unless given), then the states at
    that phase over ``max_period`` further common periods; the candidates ``k`` are those
    after which the state returns (``1e-3`` relative), closest first, then 1."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.mechanics.simulate import simulate, simulate_state

    ma = model.automaton
    T = ma.loop.reference_period
    Tc = _common_period(model)
    span = float(spec.transient * T if transient is None else transient)
    if not (span > 0 and math.isfinite(span)):
        raise ValueError(f"transient must be finite and > 0, got {transient!r}")
    n = max(1, math.ceil(span / Tc - 1e-9))
    t1 = model.t0 + n * Tc
    tr = simulate(ma, model.x0, (model.t0, t1))
    _check_run(model, tr.hybrid, "the transient simulation from the file's initial state")
    if tr.termination != "end_time":
        raise ValueError(f"guess: the transient simulation from the file's initial state "
                         f"stopped at t = {tr.t_final:.6g}: {tr.reason or tr.termination}")
    if spec.phase is None:
        phase, margin = choose_phase(model, tr.hybrid, t1)
        how = f"phase phi0 = {phase:.6g} (the nearest jump other than a sample {margin:.3g} away)"
    else:
        phase, how = _wrap_phase(model, spec.phase), f"phase phi0 = {float(spec.phase):.6g}"
    ta = t1 + ((phase - t1) % Tc)
    z, mode, t = tr.hybrid.x_final, tr.hybrid.mode_final, t1
    states = []
    for j in range(spec.max_period + 1):
        t_next = ta + j * Tc
        if t_next > t:
            h = simulate_state(ma, z, (t, t_next), mode).hybrid
            _check_run(model, h, "the simulation after the transient")
            if h.termination.name != "END_TIME":
                raise ValueError(f"guess: the simulation stopped at t = {h.t_final:.6g}: "
                                 f"{h.reason or h.termination.name.lower()}")
            z, mode, t = h.x_final, h.mode_final, t_next
        states.append((z.copy(), mode))
    mode = spec.mode or states[-1][1]
    P = spec.section_map(model, mode) if spec.phase is not None else \
        replace(spec, phase=phase).section_map(model, mode)
    sec = P.section
    text = (f"the simulation ({span:g} time units from the file's initial state) is at the "
            f"{how} in mode {states[-1][1]}")
    last = sec.from_state(states[-1][0])
    if spec.period != "auto":
        return SimulatedReturns(mode, ((int(spec.period), last),), text, phase)
    scale = max(1.0, float(np.max(np.abs(last))))
    close, notes = [], []
    for k in range(1, spec.max_period + 1):
        zk, mk = states[-1 - k]
        dist = float(np.max(np.abs(sec.from_state(zk) - last))) / scale if mk == mode \
            else math.inf
        notes.append(f"after {k}: distance {dist:.2g}")
        if dist <= 1e-3:
            close.append((dist, k))
    order = [k for _, k in sorted(close)] + [1]
    ks = list(dict.fromkeys(order))[:3]
    text += "; returns " + "; ".join(notes)
    return SimulatedReturns(mode, tuple((k, last) for k in ks), text, phase)


def _event_section(model, spec, transient) -> tuple:
    """``(spec, text)``: the event section of a model without a periodic reference that its
    simulated motion crosses: the contact and wall whose impacts (or entries into a
    compliant contact) come most often in the second half of the transient; its releases
    when that contact also sticks there (one crossing per burst of impacts)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.mechanics.simulate import simulate

    ma = model.automaton
    span = float(200.0 if transient is None else transient)
    tr = simulate(ma, model.x0, (model.t0, model.t0 + span))
    _check_run(model, tr.hybrid, "the simulation from the file's initial state")
    J = tr.hybrid.jumps
    half = model.t0 + 0.5 * (tr.t_final - model.t0)
    counts: dict = {}
    for k, c in enumerate(ma.contacts):
        for wall, _ in c.bounds:
            hit = ma.guard_name(k, wall, "impact" if c.rigid else "enter")
            rel = ma.guard_name(k, wall, "release") if c.rigid else None
            n_hit = sum(1 for i in range(len(J)) if J.t[i] >= half and J.guard[i] == hit)
            n_rel = sum(1 for i in range(len(J)) if J.t[i] >= half and J.guard[i] == rel)
            if n_hit:
                counts[(k, wall)] = (n_hit, n_rel)
    if not counts:
        raise ValueError("the model has no periodic reference (no stroboscopic section) and "
                         f"its simulated motion ({span:g} time units) crosses no contact in "
                         "its second half: no section to choose; give --event and --contact")
    (k, wall), (n_hit, n_rel) = max(counts.items(), key=lambda kv: kv[1][0])
    event = "release" if n_rel else "impact"
    text = (f"no periodic reference: the event section chosen is the {event} of contact {k} "
            f"at wall {wall:+d} ({n_hit} impacts, {n_rel} releases in the second half of a "
            f"{span:g}-long simulation)")
    return replace(spec, event=event, contact=k, wall=wall), text


def section_words(event, contact=0, wall=None, phase=None) -> str:
    """A section in words, for titles and reports.

    Parameters
    ----------
    event : str
        ``"stroboscopic"``, ``"impact"``, ``"release"`` (or ``"auto"``: a section not yet
        fixed, see :func:`fix_section`).
    contact : int
        The contact of an event section (0-based).
    wall : {+1, -1, None}
        Its bound (``+1`` hi, ``-1`` lo; None: not stated).
    phase : float or None
        The phase ``phi0`` of the stroboscopic section (time units).

    Examples
    --------
    >>> section_words("stroboscopic", phase=0.6525)
    'stroboscopic section at phi0 = 0.6525'
    >>> section_words("release", contact=1, wall=-1)
    'release section of contact 1 (lower bound)'
    """
    if event == "stroboscopic":
        return ("stroboscopic section" if phase is None else
                f"stroboscopic section at phi0 = {float(phase):.4g}")
    if event == "auto":
        return "section chosen from a simulation"
    side = {1: " (upper bound)", -1: " (lower bound)"}.get(wall, "")
    return f"{event} section of contact {int(contact)}{side}"


def fix_section(model, spec: SectionSpec, transient: float | None = None) -> tuple:
    """``(spec, mode, text)``: what every cell of a sweep over `model`'s parameters keeps.

    ``event="auto"`` is made concrete (the stroboscopic section for a periodic reference,
    else the event section the simulated motion crosses), the stroboscopic section's phase
    is chosen from a simulation at the file's values (:func:`choose_phase`) unless given,
    and ``mode`` is the section's mode there (the map's chart; empty where the simulation
    shows no section point). ``text`` says what was chosen and why.

    Raises
    ------
    ValueError
        A model without periodic reference whose motion crosses no contact (``"auto"``).
    """
    text = ""
    if model.automaton.contacts:
        spec._where(model)      # a contact or wall the model does not have is refused
    if not spec.stroboscopic(model) and spec.event == "auto":
        spec, text = _event_section(model, spec, transient)
    strobe = spec.stroboscopic(model)
    if strobe:
        spec = replace(spec, event="stroboscopic")
    try:
        sim = simulated_returns(model, spec, transient)
    except ValueError as exc:
        return spec, spec.mode or "", "; ".join(t for t in (text, str(exc)) if t)
    if strobe:
        spec = replace(spec, phase=sim.phase)
    return spec, sim.mode, "; ".join(t for t in (text, sim.text) if t)
