"""Periodic orbits of a model file at given parameter values, seeded from neighbours.

The building block of region maps, diagrams and basins of general models
(:mod:`hybridpd.sweeps.model_regions`): :func:`solve_at` looks for the periodic orbits of one
section of a :class:`~hybridpd.mechanics.modelfile.MechanicalModel` by Newton's method
(:func:`~hybridpd.analysis.periodic.find_orbit`, every answer checked: whole number of
reference periods, transversal, confirmed by a simulated period; on the stroboscopic
section an orbit continued from a seed is confirmed by its Newton residual, itself a
simulated period from the point) from a list of seeds (the
solutions at neighbouring parameter values) and, where none of them gives an orbit or only
unstable ones, from a simulation of the model from its initial state. Distinct orbits found
from different seeds are all returned, never silently one.

Status codes (:data:`STATUS`) say per parameter point what was found, or why nothing was.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.analysis.basins import Attractor
from hybridpd.analysis.hybridmap import SectionMap
from hybridpd.analysis.mappers import Mapper, mapper
from hybridpd.analysis.maps import minimal_period
from hybridpd.analysis.model_sections import (
    EVENTS,
    DivergedRun,
    SectionSpec,
    SimulatedReturns,
    _crossings,
    _default_transient,
    _event_section,
    fix_section,
    simulated_returns,
)
from hybridpd.analysis.periodic import PeriodicOrbit, find_orbit
from hybridpd.analysis.strobe import StroboscopicMap
from hybridpd.mechanics.params import ModelTemplate

__all__ = [
    "DEFAULT_NUM",
    "EVENTS",
    "FAMILY_DISTANCE",
    "STATUS",
    "ModelSection",
    "OrbitSearch",
    "SectionSpec",
    "Seed",
    "SimulatedReturns",
    "default_axes",
    "model_map",
    "orbit_from_model",
    "orbit_record",
    "orbit_status",
    "other_family",
    "signature_codes",
    "signature_table",
    "simulated_returns",
    "solve_at",
]

#: Status of a parameter point: an orbit found (stable / unstable) or why none was.
STATUS = {0: "stable", 1: "unstable", 2: "not_converged", 3: "degenerate_return",
          4: "grazing", 5: "not_periodic", 6: "fast_return", 7: "map_undefined",
          8: "sampling_incommensurate", 9: "no_section_crossing", 10: "invalid_parameters",
          11: "diverged"}
_CODE = {v: k for k, v in STATUS.items()}
_KINDS = ("crossing", "grazing", "zeno")
def orbit_status(po: PeriodicOrbit) -> int:
    """Status code (:data:`STATUS`) of a :func:`find_orbit` result."""
    if po.converged:
        return 0 if po.stable else 1
    r = po.reason
    if r in _CODE:
        return _CODE[r]
    if r.startswith("map undefined"):
        return _CODE["map_undefined"]
    return _CODE["not_converged"]


def signature_table(automaton) -> tuple:
    """All ``(guard, kind)`` pairs a signature of `automaton` can hold, in a fixed order.

    The guard names are those its mode builder declares, so no mode is built (a mechanical
    automaton's hybrid automaton is read through its ``automaton`` attribute).
    """
    hybrid = getattr(automaton, "automaton", automaton)
    return tuple((g, k) for g in hybrid.guard_names() for k in _KINDS)


def signature_codes(signature, table, length: int) -> np.ndarray:
    """A signature as ``length`` int16 codes into `table` (``-1`` padding; ``-2`` marks a
    signature longer than ``length``, cut there)."""
    index = {p: i for i, p in enumerate(table)}
    out = np.full(length, -1, np.int16)
    for i, p in enumerate(signature):
        if i == length - 1 and len(signature) > length:
            out[i] = -2
            break
        out[i] = index.get(tuple(p), -1)
    return out


@dataclass(frozen=True, eq=False)
class OrbitSearch:
    """The outcome of :func:`solve_at` at one parameter point.

    Attributes
    ----------
    status : int
        :data:`STATUS` code: of the best orbit (stable first) if one was found, else of the
        last attempt.
    orbits : tuple of PeriodicOrbit
        The distinct accepted orbits, stable ones first.
    attempts : int
        Newton runs made.
    detail : str
        Why no orbit was found (empty if one was).
    origins : tuple of (Seed or None)
        Per orbit, the seed (one of the ``seeds`` given) whose Newton run found it, or None
        (found from a simulation): a sweep's record of which neighbour's orbit it continues.
    matched : tuple of (Seed or None, int)
        Seeds whose Newton run (or chord steps, :func:`_lands_on`) landed on an orbit
        already ``known`` (its index): they continue that orbit's family.
    also : tuple of (Seed or None, int)
        Further seeds whose Newton run or chord steps landed on orbit ``orbits[i]`` (found
        from another seed first): they continue its family too.
    """

    status: int
    orbits: tuple = field(repr=False)
    attempts: int
    detail: str = ""
    origins: tuple = field(default=(), repr=False)
    matched: tuple = field(default=(), repr=False)
    also: tuple = field(default=(), repr=False)
    __repr__ = compact_repr


def _same_orbit(P, a: PeriodicOrbit, s) -> bool:
    """Whether section point `s` lies on the cycle of orbit `a` (within 1e-6 relative)."""
    pts = P.iterate(a.s, a.period - 1)
    for p in pts[np.all(np.isfinite(pts), axis=1)]:
        d = P.section.wrap(np.asarray(s) - p)
        if np.max(np.abs(d)) <= 1e-6 * max(1.0, float(np.max(np.abs(p)))):
            return True
    return False


#: A seed farther than this (relative, section coordinates) from an orbit with the same
#: signature is taken for another family and tried.
FAMILY_DISTANCE = 0.25


def other_family(s, sig, s_ref, sig_ref, wrap=None) -> bool:
    """Whether the orbit seed ``(s, sig)`` looks like another family than ``(s_ref,
    sig_ref)``: another impact signature, or farther than :data:`FAMILY_DISTANCE`."""
    if tuple(sig) != tuple(sig_ref):
        return True
    d = np.asarray(s, float) - np.asarray(s_ref, float)
    d = wrap(d) if wrap is not None else d
    return float(np.max(np.abs(d))) > FAMILY_DISTANCE * max(1.0, float(np.max(np.abs(s_ref))))


@dataclass(frozen=True, eq=False)
class Seed:
    """A starting point for Newton: an orbit's full pre-jump state ``z`` (shape ``(n,)``) at
    time ``t`` on the section, its impact ``signature``, returns per period ``period``, the
    section's ``mode`` (empty: the spec's) and whether it was ``stable``. Full states serve
    every section mode's chart. ``jacobian``: ``DP^k`` of the orbit in its mode's chart
    (None if unknown), with which :func:`solve_at` tests cheaply whether another seed lands
    on this orbit."""

    z: np.ndarray
    t: float
    signature: tuple = ()
    period: int = 1
    mode: str = ""
    stable: bool = True
    jacobian: np.ndarray | None = field(default=None, repr=False)

    @classmethod
    def of(cls, po: PeriodicOrbit, P) -> Seed:
        """The seed of an orbit found on the map `P`."""
        t = P.section.to_state(po.s)[1]
        DP = np.asarray(getattr(po, "DP", None), float)
        return cls(np.asarray(po.z, float).copy(), t, tuple(po.signature), int(po.period),
                   P.section.mode, bool(po.stable),
                   DP.copy() if DP.shape == (P.dim, P.dim) and np.all(np.isfinite(DP))
                   else None)

    def point(self, P) -> np.ndarray:
        """The seed in `P`'s section coordinates."""
        return P.section.from_state(self.z, self.t)

    def distance(self, ref: Seed, period: float | None = None) -> float:
        """Largest difference of the full states and of the times (wrapped to
        ``[-period/2, period/2)`` when the section has a phase of that period), relative to
        ``max(1, |ref.z|)``."""
        dt = self.t - ref.t
        if period:
            dt = (dt + 0.5 * period) % period - 0.5 * period
        d = np.append(self.z - ref.z, dt)
        return float(np.max(np.abs(d))) / max(1.0, float(np.max(np.abs(ref.z))))

    def other_family(self, ref: Seed, period: float | None = None) -> bool:
        """Another family than `ref`: another mode, period or signature (their common part:
        a stored signature may be cut), or more than :data:`FAMILY_DISTANCE` away (full
        states, times)."""
        n = min(len(self.signature), len(ref.signature))
        if (self.mode, self.period, tuple(self.signature[:n])) != \
                (ref.mode, ref.period, tuple(ref.signature[:n])):
            return True
        return self.distance(ref, period) > FAMILY_DISTANCE


def _guess_from_simulation(model, sec, transient):
    """The section point of the last crossing of `sec`'s guard in its mode (a simulation of
    ``transient`` time units from the file's initial state)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.mechanics.simulate import simulate

    if transient is None:
        transient = 50.0 * sec.reference_period if sec.has_phase else 200.0
    if not (float(transient) > 0 and math.isfinite(float(transient))):
        raise ValueError(f"transient must be finite and > 0, got {transient!r}")
    tr = simulate(model.automaton, model.x0, (model.t0, model.t0 + float(transient))).hybrid
    J = tr.jumps
    hits = [i for i in _crossings(tr, sec.guard) if J.source[i] == sec.mode]
    if not hits:
        raise ValueError(f"guess: no crossing of the section ({sec.guard} in mode {sec.mode}) "
                         f"within the transient of {float(transient):g}; give --guess")
    i = hits[-1]
    return sec.from_state(J.pre[i], J.t[i])


def _minimal(P, po, options):
    """`po` as an orbit of its minimal period: a search on ``P^k`` may land on a fixed point
    of ``P^d`` with ``d`` dividing ``k``."""
    if not po.converged or po.period == 1:
        return po
    d = minimal_period(P, po.s, po.period)
    if d == po.period:
        return po
    short = find_orbit(P, po.s, d, **options)
    return short if short.converged else po


class _Search:
    """Newton runs of one :func:`solve_at` call: maps per mode, orbits found, what was tried."""

    def __init__(self, model, spec):
        self.model, self.spec = model, spec
        self.maps, self.found, self.tried, self.origins, self.again = {}, [], [], [], []
        self.attempts, self.last = 0, None
        self.dt = spec.sampling_period(model)

    def map(self, mode=""):
        mode = mode or self.spec.mode or ""
        if mode not in self.maps:
            self.maps[mode] = self.spec.section_map(self.model, mode or None)
        return self.maps[mode]

    def attempt(self, P, s0, k, why, seed=None):
        self.attempts += 1
        sp = self.spec
        # on the stroboscopic map Newton's residual is itself a simulation of the period
        # from the point: a neighbour's orbit continued there needs no second one
        verify = seed is None or not isinstance(P, StroboscopicMap)
        # a neighbour's orbit is a close start: a step damped below SEED_DAMPING is no
        # continuation of it (a jump of the map between the two points, e.g. an impact
        # crossing a sample instant), and halving on costs a map run per halving
        po = _minimal(P, find_orbit(P, s0, k, tol=sp.tol, max_iter=sp.max_iter,
                                    periods=sp.periods, sampling_period=self.dt,
                                    jacobian=sp.jacobian, verify=verify,
                                    **({} if seed is None else
                                       {"min_lambda": SEED_DAMPING})),
                      dict(tol=sp.tol, max_iter=sp.max_iter, sampling_period=self.dt,
                           jacobian=sp.jacobian))
        self.last = po
        self.tried.append(f"{why}: period {k} in mode {P.section.mode}: "
                          f"{po.reason if not po.converged else 'orbit'}")
        if not po.converged:
            return po
        same = [j for j, (o, _) in enumerate(self.found) if o.mode == po.mode and
                o.period == po.period and _same_orbit(self.maps[o.mode], o, po.s)]
        if same:
            self.again.append((seed, same[0]))     # the seed continues that orbit too
        else:
            self.found.append((po, Seed.of(po, P)))
            self.origins.append(seed)
        return po


#: Smallest damping factor of Newton's line search from a seed (a neighbour's orbit); a
#: simulation's candidates get find_orbit's default.
SEED_DAMPING = 2.0 ** -10
#: Chord iterations of :func:`_lands_on` (each one application of the map).
CHORD_STEPS = 8
#: Where the chord iterate is this close to the orbit (relative, section coordinates), the
#: seed lands on it: Newton converges quadratically from there.
_LANDED = 1e-8


def _lands_on(P, s0, k, orbit: Seed) -> bool:
    """Whether chord iterations from `s0` (Newton's method with the orbit's own ``DP^k``
    held fixed) converge onto `orbit`: within :data:`_LANDED` of it, each step at least
    halving the distance, in at most :data:`CHORD_STEPS` applications of ``P^k``.

    A seed that lands on an orbit known at this point is of its family: Newton from it
    would find that orbit again, at the cost of a Jacobian at the start and one at the end.
    Undefined or refused images, a distance that does not halve, or the bound reached:
    False (the seed gets its own Newton run).
    """
    if orbit.jacobian is None or orbit.period != k or orbit.mode != P.section.mode:
        return False
    ref = orbit.point(P)
    scale = max(1.0, float(np.max(np.abs(ref))))
    x = np.asarray(s0, float).copy()
    try:
        J = orbit.jacobian - np.eye(P.dim)
        dist = float(np.max(np.abs(P.wrap(x - ref)))) / scale
        for _ in range(CHORD_STEPS):
            r = P.apply(x, k)
            if not r.ok or not np.all(np.isfinite(r.s)):
                return False
            x = x - np.linalg.solve(J, P.wrap(r.s - x))
            new = float(np.max(np.abs(P.wrap(x - ref)))) / scale
            if new <= _LANDED:
                return True
            if not new <= 0.5 * dist:
                return False
            dist = new
    except (ValueError, RuntimeError, FloatingPointError, np.linalg.LinAlgError):
        return False
    return False


def _landing(run, P, s0, k, known) -> tuple | None:
    """``("found", j)`` or ``("known", i)``: the orbit found here, or known, that a seed at
    `s0` lands on (:func:`_lands_on`), else None."""
    for j, (_, sd) in enumerate(run.found):
        if _lands_on(P, s0, k, sd):
            return "found", j
    for i, sd in enumerate(known):
        if _lands_on(P, s0, k, sd):
            return "known", i
    return None


def _as_seed(seed) -> Seed:
    if isinstance(seed, Seed):
        return seed
    raise ValueError(f"seeds must be Seed instances, got {type(seed).__name__}")


def solve_at(model, spec: SectionSpec, seeds=(), *, simulate: bool = True,
             known=(), families=None) -> OrbitSearch:
    """The periodic orbits of `spec`'s section of `model`, from `seeds` and a simulation.

    Parameters
    ----------
    model : MechanicalModel
    spec : SectionSpec
    seeds : sequence of Seed
        Orbits at neighbouring parameter values (:meth:`Seed.of`). The first is tried (with
        its own ``k`` and section mode when ``spec.period`` is ``"auto"``); each further one
        only if it is no seed of an orbit found already (:meth:`Seed.other_family`): so a
        connected family costs one Newton run per point, and two families meeting are both
        reported. Newton from a seed damps its steps down to :data:`SEED_DAMPING` only (a
        neighbour's orbit is a close start). Before its Newton run, a further seed is
        tested by chord steps with the
        ``DP`` of each orbit found or known here (:func:`_lands_on`): one it lands on is
        not searched again (a few map applications instead of two Jacobians).
    simulate : bool
        Also seed from a simulation of the model (``spec.transient`` reference periods from
        its initial state) where the seeds give no orbit, or only unstable ones although a
        seed was stable (a stable orbit may then exist elsewhere): the section's mode and
        the candidate ``k`` come from it (:func:`simulated_returns`). A family continued
        from unstable neighbours costs no simulation.
    known : sequence of Seed
        Orbits already known here: seeds of their families are skipped and only new orbits
        are returned.
    families : sequence, optional
        One label per seed: the family the caller knows it to be of (e.g. a sweep's orbits
        joined by continuation). Once a seed gave an orbit, the other seeds of its family
        are skipped, however far apart their states are.

    Returns
    -------
    OrbitSearch
        Never raises for a valid model and section: failures are statuses, and ``detail``
        says what was tried and what the simulation showed.
    """
    if spec.stroboscopic(model) and spec.phase is None:
        spec = fix_section(model, spec)[0]      # one phase for the seeds and the maps
    run = _Search(model, spec)
    known = [_as_seed(k) for k in known]
    seeds = [_as_seed(sd) for sd in seeds]
    if families is not None and len(families) != len(seeds):
        raise ValueError(f"families must have one label per seed ({len(seeds)}), got "
                         f"{len(families)}")
    labels = list(families) if families is not None else [None] * len(seeds)
    done = set()        # the families that gave an orbit
    landed = []         # (seed, i): seeds whose chord steps landed on known[i]
    for seed, label in zip(seeds, labels):
        P = run.map(seed.mode)
        T = P.section.period
        if label is not None and label in done:
            continue
        if run.found and not all(seed.other_family(sd, T) for _, sd in run.found):
            continue
        if any(not seed.other_family(k, T) for k in known):
            continue
        s0 = seed.point(P)
        if not np.all(np.isfinite(s0)):
            continue
        k = seed.period if spec.period == "auto" else int(spec.period)
        # a seed of another look may still land on an orbit found or known here: a few
        # chord steps tell, where a Newton run would cost two Jacobians
        hit = _landing(run, P, s0, k, known) if run.found or known else None
        if hit is not None:
            (run.again if hit[0] == "found" else landed).append((seed, hit[1]))
        elif not run.attempt(P, s0, k, "a neighbour's orbit", seed).converged:
            continue
        if label is not None:
            done.add(label)
    detail = ""
    lost = not run.found or (not any(po.stable for po, _ in run.found)
                             and any(sd.stable for sd in seeds))
    if simulate and lost:
        try:
            sim = simulated_returns(model, spec)
        except ValueError as exc:
            detail = str(exc)
            if not run.found and run.last is None:
                code = "diverged" if isinstance(exc, DivergedRun) else "no_section_crossing"
                return OrbitSearch(_CODE[code], (), run.attempts, detail)
        else:
            P = run.map(sim.mode)
            for k, s0 in sim.candidates:
                po = run.attempt(P, s0, k, "the simulation")
                if po.converged and po.stable:
                    break
            detail = sim.text
    found, matched = [], list(landed)
    for j, ((po, sd), origin) in enumerate(zip(run.found, run.origins)):
        T = run.map(sd.mode).section.period
        same = [i for i, k in enumerate(known) if sd.distance(k, T) <= 1e-6]
        seeds_of = [origin] + [sd2 for sd2, jj in run.again if jj == j]
        if same:
            matched += [(o, same[0]) for o in seeds_of]
        else:
            found.append((po, origin, seeds_of[1:]))
    found.sort(key=lambda f: (not f[0].stable, f[0].spectral_radius))
    if found:
        return OrbitSearch(orbit_status(found[0][0]), tuple(f[0] for f in found),
                           run.attempts, origins=tuple(f[1] for f in found),
                           matched=tuple(matched),
                           also=tuple((o, i) for i, f in enumerate(found) for o in f[2]))
    tried = "; ".join(run.tried) or "nothing (no seed)"
    if run.last is None:
        return OrbitSearch(_CODE["not_converged"], (), run.attempts,
                           f"tried {tried}" + (f"; {detail}" if detail else ""),
                           matched=tuple(matched))
    why = run.last.detail or run.last.reason
    return OrbitSearch(orbit_status(run.last), (), run.attempts,
                       f"{why} (tried {tried}" + (f"; {detail})" if detail else ")"),
                       matched=tuple(matched))


def orbit_from_model(model, contact: int = 0, wall: int | None = None, period="auto", *,
                     guess=None, transient: float | None = None, tol: float = 1e-11,
                     event: str = "auto", map_options: dict | None = None,
                     periods: int | None = None, min_return: float | None = None,
                     mode: str | None = None, max_period: int = 4,
                     phase: float | None = None) -> tuple:
    """A periodic orbit of a mechanical model, by default on its stroboscopic section.

    Parameters
    ----------
    model : MechanicalModel
        A loaded model file (:func:`hybridpd.mechanics.modelfile.load_model`).
    contact : int
        0-based contact index (file order) of an event section.
    wall : {+1, -1}, optional
        Bound of the contact (default ``hi`` if the contact has one, else ``lo``).
    period : int or "auto"
        Number of returns to the section per period (``k`` of ``P^k``); ``"auto"``: ``k = 1``
        and every ``k <= max_period`` after which a simulation of the model returns with whole
        reference periods (see :func:`simulated_returns`); the orbit's ``period`` says which.
    guess : array_like, optional
        Section point (coordinates of :func:`~hybridpd.mechanics.sections.mechanical_section`
        in `mode`). Default: simulate from the file's initial state for ``transient`` and take
        the last crossing of the section (in whichever mode it happens).
    transient : float, optional
        Time of that simulation (default 50 reference periods, or 200 time units).
    tol : float
        Newton tolerance.
    event : {"auto", "stroboscopic", "impact", "release"}
        ``"auto"`` (default): the stroboscopic section (the state at the phase ``phase`` of
        the reference, one common period of the reference and the sampling later) for a
        model with a periodic reference, else the event section that the simulated motion
        crosses (reported in the orbit's ``detail``); ``"impact"``: the contact's impacts;
        ``"release"``: the ends of its sticking phases (one crossing per phase however many
        impacts precede the sticking).
    map_options : dict, optional
        Keyword arguments of :class:`~hybridpd.analysis.hybridmap.SectionMap`.
    periods, min_return : optional
        As in :func:`find_orbit`. A sampled-data controller's ``dt`` is checked against the
        reference period (``sampling_incommensurate``).
    mode : str, optional
        The mode in which the section's guard fires (default: where the simulation crosses
        it; with a ``guess``, the free mode for impacts and the mode holding the contact alone
        for releases).
    max_period : int
        Largest ``k`` that ``period="auto"`` tries.
    phase : float, optional
        ``phi0`` of the stroboscopic section (default: chosen from the simulation where no
        jump other than a sample happens near it, in the free mode where the motion has one;
        :func:`choose_phase`).

    Returns
    -------
    (PeriodicOrbit, SectionMap)
        The orbit (``converged = False`` with the reason, and what was tried in ``detail``,
        where there is none) and the map of its section.

    Examples
    --------
    >>> from pathlib import Path
    >>> import hybridpd
    >>> f = Path(hybridpd.__file__).parents[1] / "examples" / "models" / "gear_train.toml"
    >>> po, P = orbit_from_model(hybridpd.load_model(f), 0, event="release")
    >>> po.converged, po.mode, po.period
    (True, 'stick0+1+', 1)
    >>> po, P = orbit_from_model(hybridpd.load_model(f))     # the stroboscopic section
    >>> po.converged, po.n_periods, round(po.spectral_radius, 4)
    (True, 1, 0.5605)
    """
    spec = SectionSpec(contact=contact, wall=wall, event=event, period=period,
                       periods=periods, tol=tol, mode=mode, max_period=max_period, phase=phase)
    chosen = ""
    if model.automaton.contacts:
        spec._where(model)      # a contact or wall the model does not have is refused
    if not spec.stroboscopic(model) and spec.event == "auto":
        spec, chosen = _event_section(model, spec, transient)
    if guess is None:
        sim = simulated_returns(model, spec, transient if transient is not None else
                                _default_transient(model, spec))
        cands, sec_mode, text = sim.candidates, sim.mode, sim.text
        spec = replace(spec, phase=sim.phase)
    else:
        ks = (1, *range(2, spec.max_period + 1)) if period == "auto" else (int(period),)
        cands, sec_mode, text = tuple((k, guess) for k in ks[:3]), mode, ""
    text = "; ".join(t for t in (chosen, text) if t)
    s0 = cands[0][1]
    sec = spec.section_map(model, sec_mode).section
    P = (StroboscopicMap if spec.stroboscopic(model) else SectionMap)(
        sec, **dict(map_options or {}))
    s0 = np.asarray(s0, float)
    if s0.shape != (sec.dim,):
        raise ValueError(f"guess must have {sec.dim} numbers {sec.names}, got {s0.size}")
    dt = spec.sampling_period(model)
    tried, po = [], None
    for k, s in cands:
        po = _minimal(P, find_orbit(P, np.asarray(s, float), k, tol=tol, periods=periods,
                                    min_return=min_return, sampling_period=dt),
                      dict(tol=tol, min_return=min_return, sampling_period=dt))
        tried.append(f"period {k}: {'orbit' if po.converged else po.reason}")
        if po.converged:
            if chosen:      # the section chosen for a model without periodic reference
                po = replace(po, quantities={**po.quantities, "section_choice": chosen})
            return po, P
        if po.reason in ("sampling_incommensurate",):
            break
    if len(tried) > 1 or text:
        po = replace(po, detail=(po.detail + "; " if po.detail else "") +
                     f"tried {', '.join(tried)}" + (f"; {text}" if text else ""))
    return po, P


def orbit_record(model, orb, P) -> dict:
    """The JSON object of a model's orbit (``hybridpd orbit --model --json``).

    The orbit's own fields (:meth:`PeriodicOrbit.to_dict`), its section (``event``
    ``stroboscopic``/``impact``/``release``, ``contact`` and ``wall`` of an event section,
    ``section_mode``, the period ``T``, the phase ``phi0``, the start time ``t0``), ``n``
    returns per period, the count of structural zeros of ``DP``, how ``DP`` was obtained, and
    the pre- and post-jump mechanical states ``[q_1, v_1, ..., q_n, v_n]`` at the section.

    Parameters
    ----------
    model : MechanicalModel
    orb, P : PeriodicOrbit, SectionMap
        As :func:`orbit_from_model` returns them.

    Examples
    --------
    >>> from pathlib import Path
    >>> import hybridpd
    >>> f = Path(hybridpd.__file__).parents[1] / "examples" / "models" / "robot_joint_pd.toml"
    >>> m = hybridpd.load_model(f)
    >>> d = orbit_record(m, *orbit_from_model(m, 0))
    >>> d["event"], d["exists"], len(d["pre"]) == 2 * m.system.n
    ('stroboscopic', True, True)
    """
    sec = P.section
    d = orb.to_dict()
    n = model.system.n
    lay = model.automaton.layout
    z = orb.z
    strobe = sec.guard is None
    reset = None if strobe else sec.automaton.mode(sec.mode).guards[sec.guard_index].reset
    zp = z if reset is None else reset[0] @ z + reset[1]

    def mech(x):      # [q_1, v_1, ..., q_n, v_n]
        return [float(x[lay["q"][i]]) if j == 0 else float(x[lay["v"][i]])
                for i in range(n) for j in (0, 1)]

    t0 = sec.to_state(orb.s)[1] if np.all(np.isfinite(orb.s)) else None
    zeros = len(orb.s) - len(orb.multipliers) if orb.converged else None
    event = "stroboscopic" if strobe else ("release" if sec.guard.startswith("release")
                                           else "impact")
    contact = None if strobe else int("".join(c for c in sec.guard if c.isdigit()))
    d.update({"model": model.source, "contact": contact,
              "wall": None if strobe else (1 if sec.guard.endswith("+") else -1),
              "event": event, "section_mode": sec.mode, "T": sec.period,
              "phi0": sec.phase if strobe else (float(orb.s[0]) if sec.has_phase else None),
              "t0": t0, "n": orb.period, "structural_zeros": zeros,
              "jacobian": orb.quantities.get("jacobian"),
              "section_choice": orb.quantities.get("section_choice"),
              "jacobian_error": orb.quantities.get("jacobian_error"),
              "pre": mech(z), "post": mech(zp)})
    return d


#: Points per axis of a model basin's default slice (a run of the section map each).
DEFAULT_NUM = 21


def default_axes(s, names, num: int = DEFAULT_NUM) -> tuple:
    """The default slice of a basin through the section point ``s``: its first two section
    coordinates, each over ``s_i +- r`` with ``r = max(|s_0|, |s_1|)`` (at least 1e-6),
    ``num`` points each, as ``((name, min, max, num), (name, min, max, num))``.

    Examples
    --------
    >>> default_axes([0.5, -2.0, 7.0], ("link", "link_dot", "h0"), 5)
    (('link', -1.5, 2.5, 5), ('link_dot', -4.0, 0.0, 5))
    """
    r = max(float(abs(s[0])), float(abs(s[1])), 1e-6)
    return tuple((names[i], float(s[i]) - r, float(s[i]) + r, int(num)) for i in (0, 1))


@dataclass(frozen=True, eq=False)
class ModelSection:
    """A model file's section map with a periodic orbit on it (:func:`model_map`).

    Attributes
    ----------
    map : SectionMap or StroboscopicMap
    orbit : PeriodicOrbit
    metadata : dict
        The file, the values set, the section and its mode (for a basin's metadata).
    """

    map: object
    orbit: PeriodicOrbit
    metadata: dict
    __repr__ = compact_repr

    @property
    def fixed_point(self) -> np.ndarray:
        """The orbit's section point."""
        return self.orbit.s

    def entry(self) -> Attractor:
        """The orbit as a basin's attractor 0 (named by its period and reference periods)."""
        po = self.orbit
        return Attractor(0, f"the period-{po.period} orbit ({po.n_periods} T)", int(po.period),
                         np.asarray(po.s, float).reshape(1, -1), po.multipliers,
                         float(po.spectral_radius), bool(po.stable))

    def mapper(self, *, n_iter: int = 300, criterion: float = 1e-3, **options) -> Mapper:
        """The basin mapper of the orbit (:func:`hybridpd.analysis.mappers.mapper`; its
        ``n_iter`` iterations of ``P^k``)."""
        return mapper(self.map, self.orbit.s, period=self.orbit.period, n_iter=n_iter,
                      criterion=criterion, orbit=self.entry(), metadata=self.metadata,
                      **options)


def model_map(model, *, values: dict | None = None, contact: int = 0, wall: int | None = None,
              event: str = "auto", period="auto", periods: int | None = None,
              mode: str | None = None, phase: float | None = None) -> ModelSection:
    """The section map of a model file and a periodic orbit on it (the first found, as
    :class:`~hybridpd.sweeps.model_regions.ModelSearch` finds one per cell): what a model
    file's basin is taken of.

    Parameters
    ----------
    model : str, Path, dict or ModelTemplate
    values : dict, optional
        ``{dotted path: value}`` set in the file first (e.g. ``{"controller.kp": 30}``).
    contact, wall, event, period, periods, mode, phase
        The section and the orbit (:class:`~hybridpd.analysis.model_sections.SectionSpec`).

    Returns
    -------
    ModelSection

    Raises
    ------
    ValueError
        Bad paths or section, or no periodic orbit found (:class:`DivergedRun` where the
        motion diverges).
    """
    if isinstance(model, (str, Path)):
        template = ModelTemplate.load(model)
    elif isinstance(model, (dict, ModelTemplate)):
        template = model if isinstance(model, ModelTemplate) else ModelTemplate(model)
    else:
        raise ValueError(f"model must be a model file path, a parsed dict or a ModelTemplate, "
                         f"got {type(model).__name__}")
    m = template.model(values)
    spec = SectionSpec(contact=contact, wall=wall, event=event, period=period, periods=periods,
                       mode=mode, phase=phase)
    spec = fix_section(m, spec)[0]
    res = solve_at(m, spec)
    if not res.orbits:
        # a motion that diverges is said to (DivergedRun), not only that no orbit was found
        err = DivergedRun if STATUS[res.status] == "diverged" else ValueError
        raise err(f"no periodic orbit of this section to take the basin of ({res.detail})")
    po = res.orbits[0]
    meta = {"values": dict(values or {}),
            "spec": {f: getattr(spec, f) for f in ("contact", "wall", "event", "period",
                                                    "periods", "phase")},
            "section_mode": po.mode, "model": str(template.source)}
    return ModelSection(spec.section_map(m, po.mode), po, meta)
