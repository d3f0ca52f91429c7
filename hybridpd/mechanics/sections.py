"""The sections of a mechanical automaton's contacts (:mod:`hybridpd.hybrid.section`).

:func:`mechanical_section`: a contact's impacts (or the ends of its sticking phases) of a
mechanical automaton of :mod:`hybridpd.mechanics`, with the constraints of the contacts held
in its mode and the bounds of every contact's gap.

"""
from __future__ import annotations

import numpy as np

from hybridpd.hybrid.section import Section, StroboscopicSection

__all__ = ["contact_bounds", "held_constraints", "mechanical_section",
           "mode_code", "mode_name", "stroboscopic_section"]


def mechanical_section(model, contact: int = 0, wall: int = 1, *, period=None,
                       mode: str | None = None, event: str = "impact",
                       sample_time: float = 0.0) -> Section:
    """The section of a contact of a mechanical automaton (:mod:`hybridpd.mechanics`).

    ``event="impact"``: pre-impact states of rigid contact ``contact`` on its ``wall`` bound
    (``+1``: ``hi``), or the entry into a compliant contact, in the free mode (or ``mode``).
    ``event="release"``: the end of sticking on that bound (mode ``stick{k}{+|-}``), a
    section crossed once per sticking phase, however many impacts precede it (the contact
    reopens tangentially there, so finite differences across it may see an immediate
    re-sticking; the multipliers equal those of the impact section). Coordinates: the
    reference phase ``phi = t mod T`` (sine references; ``period`` is required for a sum of
    sines) and the non-exosystem states except the pivot of the gap (module docstring).

    Parameters
    ----------
    model : MechanicalAutomaton
    contact : int
        0-based contact index (file order).
    wall : {+1, -1}
    period : float, optional
        Period of the phase (default: the common period of every sine of every controller's
        reference, :attr:`~hybridpd.mechanics.loop.MechanicalLoop.reference_period`).
    mode : str, optional
        Mode of the section (default the free mode).
    sample_time : float
        A sampling instant of a sampled-data loop (the run's start time ``t0``: the first
        sample is taken there). The sampling clocks are then set from the phase, which has the
        common period of the reference and the sampling periods (see
        :class:`~hybridpd.analysis.hybridmap.Section`).
    """
    if wall not in (1, -1):
        raise ValueError(f"wall must be +1 or -1, got {wall!r}")
    contacts = model.contacts
    if isinstance(contact, bool) or int(contact) != contact or not 0 <= contact < len(contacts):
        raise ValueError(f"contact must be an index in [0, {len(contacts)}), got {contact!r}")
    contact = int(contact)
    sign = "+" if wall > 0 else "-"
    if event not in ("impact", "release"):
        raise ValueError(f"event must be 'impact' or 'release', got {event!r}")
    if event == "release":
        if not contacts[contact].rigid:
            raise ValueError(f"event 'release': contact {contact} is compliant (no sticking)")
        name = f"release{contact}{sign}"
        mode = f"stick{contact}{sign}" if mode is None else mode
    else:
        name = f"contact{contact}{sign}" if contacts[contact].rigid else f"enter{contact}{sign}"
    mode = model.free_mode if mode is None else mode
    loop = model.loop
    exo = tuple(int(i) for i in model.layout["exo"])
    if period is None:
        period = loop.reference_period      # every sine of every controller's reference
    clocks = getattr(loop, "clocks", ())
    return Section(model.automaton, mode, name, exo=exo, period=period,
                   exo_state=loop.exo_state(0.0), clocks=clocks or None, sample_time=sample_time,
                   constraints=held_constraints(model, mode), bounds=contact_bounds(model),
                   resolver=model.resolver())


def stroboscopic_section(model, phase: float, *, mode: str | None = None, period=None,
                         sample_time: float = 0.0) -> StroboscopicSection:
    """The stroboscopic section of a mechanical automaton: its states at the phase `phase`
    of the common period of its reference and sampling periods.

    Parameters
    ----------
    model : MechanicalAutomaton
    phase : float
        ``phi0`` in ``[0, Tc)`` (time units; ``t = phi0 + j Tc``).
    mode : str, optional
        The mode of the section's states (default the free mode); the gaps and normal
        velocities of the contacts it holds are constraints, not coordinates.
    period : float, optional
        Period of the reference (default: the common period of every sine of every
        controller's reference).
    sample_time : float
        A sampling instant (the run's start ``t0``), from which the clocks are set.

    Raises
    ------
    ValueError
        The model has no periodic reference (a constant set-point), or a bad mode or phase.
    """
    mode = model.free_mode if mode is None else mode
    loop = model.loop
    exo = tuple(int(i) for i in model.layout["exo"])
    if period is None:
        period = loop.reference_period
    if period is None:
        raise ValueError("the model has no periodic reference (a constant set-point): it "
                         "has no stroboscopic section; use an event section (impact or "
                         "release)")
    clocks = getattr(loop, "clocks", ())
    return StroboscopicSection(model.automaton, mode, phase, exo=exo, period=period,
                               exo_state=loop.exo_state(0.0), clocks=clocks or None,
                               sample_time=sample_time,
                               constraints=held_constraints(model, mode),
                               bounds=contact_bounds(model), resolver=model.resolver(),
                               mode_of=model.mode_at)


def _contact_label(model, k) -> str:
    c = model.contacts[k]
    return f"contact {k}" + (f" ({c.name})" if c.name else "")


def held_constraints(model, mode: str) -> tuple:
    """``((row, value, name), ...)``: the equalities of the contacts held in `mode`, gap at
    its bound and zero normal velocity (see :class:`~hybridpd.analysis.hybridmap.Section`)."""
    try:
        info = model.modes[mode]
    except KeyError:
        raise ValueError(f"mode {mode!r} is no mode of the model") from None
    lay = model.layout
    out = []
    for k, wall in info.stick:
        c = model.contacts[k]
        bound = c.hi if wall > 0 else c.lo
        vrow = np.zeros(model.gap_rows.shape[1])
        vrow[lay["v"]] = c.normal
        what = _contact_label(model, k)
        out.append((model.gap_rows[k].copy(), float(bound),
                    f"{what} held: gap = {'hi' if wall > 0 else 'lo'} = {bound:g}"))
        out.append((vrow, 0.0, f"{what} held: no relative velocity"))
    return tuple(out)


def contact_bounds(model) -> tuple:
    """``((row, lo, hi, name), ...)``: every rigid contact's gap within its bounds (the
    admissible states of a mechanical model; a compliant contact's gap beyond its bound is
    a state of its engaged mode, :meth:`MechanicalAutomaton.mode_at`)."""
    out = []
    for k, c in enumerate(model.contacts):
        if not c.rigid:
            continue
        lo = "" if c.lo is None else f"{c.lo:g} <= "
        hi = "" if c.hi is None else f" <= {c.hi:g}"
        out.append((model.gap_rows[k].copy(), c.lo, c.hi,
                    f"{_contact_label(model, k)}: {lo}gap{hi}"))
    return tuple(out)


def mode_code(model, mode: str) -> int:
    """A mechanical automaton's mode as an integer: one base-3 digit per contact (0 free,
    1 held or engaged at ``hi``, 2 at ``lo``), contact 0 the least significant; ``-1`` for
    more than 39 contacts (the code would not fit in 64 bits)."""
    if len(model.contacts) > 39:
        return -1
    info = model.modes[mode]
    digits = [0] * len(model.contacts)
    for j, w in enumerate(info.config):
        digits[j] = 0 if w == 0 else (1 if w > 0 else 2)
    for k, w in info.stick:
        digits[k] = 1 if w > 0 else 2
    return int(sum(d * 3 ** j for j, d in enumerate(digits)))


def mode_name(model, code: int) -> str:
    """Inverse of :func:`mode_code` (``""`` for ``-1``)."""
    code = int(code)
    if code < 0:
        return ""
    stick, config = [], [0] * len(model.contacts)
    for j, c in enumerate(model.contacts):
        d = code % 3
        code //= 3
        if d:
            w = 1 if d == 1 else -1
            if c.rigid:
                stick.append((j, w))
            else:
                config[j] = w
    base = "free" if not stick else "stick" + "".join(
        f"{k}{'+' if w > 0 else '-'}" for k, w in stick)
    eng = [f"c{j}{'+' if w > 0 else '-'}" for j, w in enumerate(config) if w]
    name = base + ("/" + ",".join(eng) if eng else "")
    model.modes[name]            # KeyError for a code that names no mode
    return name
