"""Periodic orbits of a model file at given parameter values, seeded from neighbours.

The building block of region maps, diagrams and basins of general models
(:mod:`hybridpd.sweeps.model_regions`): :func:`solve_at` looks for the periodic orbits of one
section of a :class:`~hybridpd.mechanics.modelfile.MechanicalModel` by Newton's method
(:func:`~hybridpd.analysis.periodic.find_orbit`, every answer checked: whole number of
reference periods, transversal, confirmed by a simulated period) from a list of seeds (the
solutions at neighbouring parameter values) and, where none of them gives an orbit or only
unstable ones, from a simulation of the model from its initial state. Distinct orbits found
from different seeds are all returned, never silently one.

Status codes (:data:`STATUS`) say per parameter point what was found, or why nothing was.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hybridpd._repr import compact_repr
from hybridpd.analysis.hybridmap import SectionMap
from hybridpd.analysis.periodic import PeriodicOrbit, find_orbit
from hybridpd.analysis.sections import mechanical_section

__all__ = ["FAMILY_DISTANCE", "STATUS", "OrbitSearch", "SectionSpec", "orbit_from_model",
           "orbit_status", "other_family", "signature_codes", "signature_table", "solve_at"]

#: Status of a parameter point: an orbit found (stable / unstable) or why none was.
STATUS = {0: "stable", 1: "unstable", 2: "not_converged", 3: "degenerate_return",
          4: "grazing", 5: "not_periodic", 6: "fast_return", 7: "map_undefined",
          8: "sampling_incommensurate", 9: "no_section_crossing", 10: "invalid_parameters"}
_CODE = {v: k for k, v in STATUS.items()}
_KINDS = ("crossing", "grazing", "zeno")


@dataclass(frozen=True)
class SectionSpec:
    """Which section and which orbits: contact ``contact`` (0-based), bound ``wall`` (``+1``
    hi, ``-1`` lo, None: hi if it has one), ``event`` (``"impact"`` or ``"release"``),
    ``period`` returns per orbit (``k`` of ``P^k``), ``periods`` reference periods per orbit
    (None: any), Newton's ``tol`` and ``max_iter``, the seeding simulation's ``transient``
    (reference periods), the bound ``t_max`` on one map application (reference periods
    per return) and the ``jacobian`` of Newton and of the multipliers (``"fd"``: central
    differences of the simulated map, ``"exact"``: the saltation chain)."""

    contact: int = 0
    wall: int | None = None
    event: str = "impact"
    period: int = 1
    periods: int | None = None
    tol: float = 1e-10
    max_iter: int = 25
    transient: float = 30.0
    t_max: float = 20.0
    jacobian: str = "exact"

    def __post_init__(self):
        if self.event not in ("impact", "release"):
            raise ValueError(f"event must be 'impact' or 'release', got {self.event!r}")
        if isinstance(self.period, bool) or int(self.period) != self.period or self.period < 1:
            raise ValueError(f"period must be an int >= 1, got {self.period!r}")
        if self.periods is not None and (int(self.periods) != self.periods or self.periods < 1):
            raise ValueError(f"periods must be None or an int >= 1, got {self.periods!r}")
        if self.jacobian not in ("exact", "fd"):
            raise ValueError(f"jacobian must be 'exact' or 'fd', got {self.jacobian!r}")
        if self.wall not in (None, 1, -1):
            raise ValueError(f"wall must be +1, -1 or None, got {self.wall!r}")
        for name in ("tol", "transient", "t_max"):
            v = getattr(self, name)
            if not (math.isfinite(float(v)) and float(v) > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v!r}")

    def section_map(self, model) -> SectionMap:
        """The map ``P`` of this section of `model` (ValueError for a bad contact/wall)."""
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
        sec = mechanical_section(ma, int(self.contact), wall, event=self.event)
        T = sec.period if sec.has_phase else 1.0
        return SectionMap(sec, t_max=self.t_max * self.period * T, max_jumps=5000)

    def sampling_period(self, model):
        dt = float(getattr(model.automaton.loop, "dt", 0.0) or 0.0)
        return dt if dt > 0 else None


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
    """All ``(guard, kind)`` pairs a signature of `automaton` can hold, in a fixed order."""
    names = automaton.guard_names()       # declared by a mode builder: no mode is built
    return tuple((g, k) for g in names for k in _KINDS)


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
    """

    status: int
    orbits: tuple = field(repr=False)
    attempts: int
    detail: str = ""
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


def _far(P, orbit, seed) -> bool:
    return other_family(seed[0], seed[1], orbit.s, orbit.signature, P.section.wrap)


def solve_at(model, spec: SectionSpec, seeds=(), *, simulate: bool = True,
             known=()) -> OrbitSearch:
    """The periodic orbits of `spec`'s section of `model`, from `seeds` and a simulation.

    Parameters
    ----------
    model : MechanicalModel
    spec : SectionSpec
    seeds : sequence of (s, signature)
        Section points (and impact signatures) of orbits at neighbouring parameter values.
        The first is tried; each further one only if it is no seed of an orbit found already
        (another signature, or more than 5 % away): so a connected family costs one Newton
        run per point, and two families meeting are both reported.
    simulate : bool
        Also seed from a simulation of the model (``spec.transient`` reference periods from
        its initial state) when the seeds give no orbit or only unstable ones.
    known : sequence of (s, signature)
        Orbits already known here: seeds of their families are skipped and only new orbits
        are returned.

    Returns
    -------
    OrbitSearch
        Never raises for a valid model and section: failures are statuses.
    """
    P = spec.section_map(model)
    dt = spec.sampling_period(model)
    found: list[PeriodicOrbit] = []
    attempts = 0
    last = None

    def attempt(s0):
        nonlocal attempts, last
        attempts += 1
        po = find_orbit(P, s0, spec.period, tol=spec.tol, max_iter=spec.max_iter,
                        periods=spec.periods, sampling_period=dt, jacobian=spec.jacobian)
        last = po
        if po.converged and not any(_same_orbit(P, o, po.s) for o in found):
            found.append(po)
        return po

    wrap = P.section.wrap
    for s, sig in seeds:
        if found and not all(_far(P, o, (s, sig)) for o in found):
            continue
        if any(not other_family(s, sig, ks, ksig, wrap) for ks, ksig in known):
            continue
        if np.asarray(s).shape != (P.dim,) or not np.all(np.isfinite(s)):
            continue
        attempt(np.asarray(s, float))
    detail = ""
    if simulate and not any(o.stable for o in found):
        T = P.section.period if P.section.has_phase else 1.0
        try:
            g = _guess_from_simulation(model, P.section, spec.transient * T)
        except ValueError as exc:
            detail = str(exc)
            if not found and last is None:
                return OrbitSearch(_CODE["no_section_crossing"], (), attempts, detail)
        else:
            attempt(g)
    found = [o for o in found
             if all(np.max(np.abs(wrap(o.s - np.asarray(ks)))) >
                    1e-6 * max(1.0, float(np.max(np.abs(o.s)))) for ks, _ in known)]
    found.sort(key=lambda o: (not o.stable, o.spectral_radius))
    if found:
        return OrbitSearch(orbit_status(found[0]), tuple(found), attempts)
    if last is None:
        return OrbitSearch(_CODE["not_converged"], (), attempts, detail or "no seed")
    return OrbitSearch(orbit_status(last), (), attempts, last.detail or last.reason)


def orbit_from_model(model, contact: int = 0, wall: int | None = None, period: int = 1, *,
                     guess=None, transient: float | None = None, tol: float = 1e-11,
                     event: str = "impact", map_options: dict | None = None,
                     periods: int | None = None, min_return: float | None = None) -> tuple:
    """A periodic orbit of a mechanical model on the section of one of its contacts.

    Parameters
    ----------
    model : MechanicalModel
        A loaded model file (:func:`hybridpd.mechanics.modelfile.load_model`).
    contact : int
        0-based contact index (file order).
    wall : {+1, -1}, optional
        Bound of the contact (default ``hi`` if the contact has one, else ``lo``).
    period : int
        Number of returns to the section per period (``k`` of ``P^k``).
    guess : array_like, optional
        Section point (coordinates of :func:`~hybridpd.analysis.sections.mechanical_section`).
        Default: simulate from the file's initial state for ``transient`` and take the last
        pre-impact state on the section.
    transient : float, optional
        Time of that simulation (default 50 reference periods, or 200 time units).
    tol : float
        Newton tolerance.
    event : {"impact", "release"}
        Section on the impacts, or on the ends of sticking phases (one crossing per phase
        however many impacts precede the sticking).
    map_options : dict, optional
        Keyword arguments of :class:`~hybridpd.analysis.hybridmap.SectionMap`.
    periods, min_return : optional
        As in :func:`find_orbit`. A sampled-data controller's ``dt`` is checked against the
        reference period (``sampling_incommensurate``).

    Returns
    -------
    (PeriodicOrbit, SectionMap)
        The orbit (``converged = False`` with the reason where there is none) and the map.
    """
    ma = model.automaton
    if isinstance(contact, bool) or int(contact) != contact or \
            not 0 <= int(contact) < len(ma.contacts):
        raise ValueError(f"contact must be an index in [0, {len(ma.contacts)}), got {contact!r}")
    c = ma.contacts[int(contact)]
    walls = [w for w, _ in c.bounds]
    if wall is None:
        wall = 1 if 1 in walls else -1
    if wall not in walls:
        raise ValueError(f"wall must be one of {walls} for contact {contact} (its bounds), "
                         f"got {wall!r}")
    sec = mechanical_section(ma, int(contact), wall, event=event)
    P = SectionMap(sec, **dict(map_options or {}))
    if guess is None:
        guess = _guess_from_simulation(model, sec, transient)
    s0 = np.asarray(guess, float)
    if s0.shape != (sec.dim,):
        raise ValueError(f"guess must have {sec.dim} numbers {sec.names}, got {s0.size}")
    dt = float(getattr(ma.loop, "dt", 0.0) or 0.0)
    return find_orbit(P, s0, period, tol=tol, periods=periods, min_return=min_return,
                      sampling_period=dt if dt > 0 else None), P


def _guess_from_simulation(model, sec, transient):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.mechanics.simulate import simulate

    if transient is None:
        transient = 50.0 * sec.period if sec.has_phase else 200.0
    if not (float(transient) > 0 and math.isfinite(float(transient))):
        raise ValueError(f"transient must be finite and > 0, got {transient!r}")
    tr = simulate(model.automaton, model.x0, (model.t0, model.t0 + float(transient)))
    J = tr.hybrid.jumps
    # the first firing of a burst (after a jump of another guard): the start of a pattern
    hits = [i for i in range(len(J)) if J.source[i] == sec.mode and J.guard[i] == sec.guard
            and J.kind[i] == "crossing" and (i == 0 or J.guard[i - 1] != sec.guard)]
    if not hits:
        raise ValueError(f"guess: no impact on the section ({sec.guard} in mode {sec.mode}) "
                         f"within the transient of {float(transient):g}; give --guess")
    i = hits[-1]
    return sec.from_state(J.pre[i], J.t[i])
