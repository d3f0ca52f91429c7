r"""The stroboscopic (period) map of a periodically forced hybrid automaton.

Every periodically forced system has one section that always exists: the state at one phase
``phi0`` of the forcing (:class:`~hybridpd.hybrid.section.StroboscopicSection`), mapped over
one common period ``Tc`` of the reference and of every sampling period. It needs no crossing
of any surface, so impacts, accumulations, sticking phases, releases and samples inside the
period are all just events on the way, and its multipliers are the orbit's Floquet
multipliers. It is the section in which sampled-data control is usually analysed (the state
at a sample instant, here half a sample away from it).

Map
---
``P^k(s)``: the state ``z(s)`` at ``t0 = phi0`` in the section's mode, simulated by the
automaton's simulator (exact flows, located events, its Zeno rules and, for a mechanical
model, its joint-jump resolver) to ``t0 + k Tc``; the image is the state there, which must be
in the section's mode again (status ``"other_mode"`` otherwise).

Jacobian
--------
``DP^k = C Z E``: ``E`` the section's embedding, ``C`` its coordinates and ``Z`` the product of
the flows' exponentials and of the saltation matrix of every jump on the way
(:func:`~hybridpd.analysis.saltation.sensitivity_chain`: impacts, the end of an accumulation
at its estimated limit, releases, sample instants with their held inputs, a crossing forced
at the instant of a reset). No time correction at the end: the end time is fixed. Where a jump
has no saltation matrix (a joint jump of several contacts resolved together, a tangential
touch), :attr:`~hybridpd.analysis.maps.MapResult.DP` is None and the analyses take central
differences of the map (:meth:`~hybridpd.analysis.maps.PoincareMap.jacobian_fd`, relative step
``1e-6``); :meth:`StroboscopicMap.point_quantities` then states the method and an error
estimate (the difference between the steps ``h`` and ``h/2``).

Structural zeros
----------------
Some directions are removed by construction, whatever the parameters: a sampled controller's
held input is overwritten at its next sample, a sticking phase projects the held contact's gap
and normal velocity onto the contact. The chain counts them from the linear parts of the jumps
(:attr:`~hybridpd.analysis.maps.MapResult.structural_zeros`), so the multipliers of an orbit
leave them out instead of reporting them as rounding noise. The count is made where it is
needed, at (near) periodic points (``|P^k(s) - s| <= 1e-6 max(1, |s|)``); elsewhere (Newton's
iterates) ``structural_zeros`` is None.
"""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from hybridpd.analysis.hybridmap import OnSection
from hybridpd.analysis.maps import MapResult, PoincareMap, check_returns
from hybridpd.analysis.saltation import sensitivity_chain
from hybridpd.hybrid.automaton import TerminationCause, ZenoOptions
from hybridpd.hybrid.section import StroboscopicSection

__all__ = ["StroboscopicMap"]

_KINDS = {"crossing": 1, "grazing": 2, "zeno": 3, "simultaneous": 4}
#: Singular values of ``DP`` below this (relative to ``max(1, |DP|)``) are zeros up to
#: rounding: no motion contracts a direction by 1e-13 in one period.
_ROUNDING = 1e-13
#: A point whose image is this close (relative to ``max(1, |s|)``) is (near) periodic: the
#: structural zeros of ``DP`` are counted there
_PERIODIC = 1e-6
#: A state growing past this many times the start's scale is a diverging run.
DIVERGENCE_FACTOR = 1e9


class StroboscopicMap(OnSection, PoincareMap):
    """The period map of a :class:`~hybridpd.hybrid.section.StroboscopicSection` (module
    docstring).

    Parameters
    ----------
    section : StroboscopicSection
    max_jumps : int
        Bound on the jumps of one application of ``P^k`` (samples, impacts, Zeno switches).
    max_steps : int
        Bound on the exact flow steps of one application.
    zeno : ZenoOptions, optional
        Accumulation rules (default the automaton's own, as its simulations use).
    simtol : float
        Guards of one simultaneity group closing within ``simtol (1 + |t|)`` take one joint
        jump by the section's resolver (a mechanical model's impact law).

    Examples
    --------
    The stroboscopic map of a forced impact oscillator and its stable orbit:

    >>> import numpy as np
    >>> from hybridpd.hybrid.samples import impact_oscillator, oscillator_initial_state
    >>> from hybridpd.hybrid.section import StroboscopicSection
    >>> from hybridpd.analysis.periodic import find_orbit
    >>> ha = impact_oscillator(stop=0.5)
    >>> sec = StroboscopicSection(ha, "free", 0.0, reference=(oscillator_initial_state(0, 0),
    ...                                                         0.0))
    >>> P = StroboscopicMap(sec)
    >>> po = find_orbit(P, P.iterate([0.0, 0.0], 60)[-1])
    >>> po.converged, po.n_periods, bool(po.stable)
    (True, 1, True)
    """

    def __init__(self, section: StroboscopicSection, *, max_jumps: int = 200_000,
                 max_steps: int = 10_000_000, zeno: ZenoOptions | None = None,
                 simtol: float = 1e-12):
        if not isinstance(section, StroboscopicSection):
            raise ValueError(f"section must be a StroboscopicSection, got "
                             f"{type(section).__name__}")
        self.section = section
        for name, v in (("max_jumps", max_jumps), ("max_steps", max_steps)):
            if isinstance(v, bool) or int(v) != v or v < 1:
                raise ValueError(f"{name} must be an int >= 1, got {v!r}")
        self.max_jumps, self.max_steps = int(max_jumps), int(max_steps)
        zeno = section.automaton.zeno if zeno is None else zeno
        if not isinstance(zeno, ZenoOptions):
            raise ValueError("zeno must be a ZenoOptions instance")
        self.zeno = zeno
        if not (math.isfinite(float(simtol)) and float(simtol) >= 0):
            raise ValueError(f"simtol must be finite and >= 0, got {simtol!r}")
        self.simtol = float(simtol)

    @property
    def phase(self) -> float:
        """``phi0``: the section's phase of the reference (time units)."""
        return self.section.phase

    @property
    def common_period(self) -> float:
        """``Tc``: the time of one application of ``P``."""
        return self.section.period

    def _simulate(self, z0, t0, t1):
        sec = self.section
        scale = max(1.0, float(np.max(np.abs(z0))))
        return sec.automaton.simulate(z0, sec.start_mode(z0), (t0, t1), max_jumps=self.max_jumps,
                                      max_steps=self.max_steps, zeno=self.zeno,
                                      resolver=sec.resolver, simtol=self.simtol,
                                      max_state=DIVERGENCE_FACTOR * scale)

    def _on_section(self, tr, z1) -> bool:
        """Whether a run ended in the section's mode (up to what the state decides of it,
        e.g. a compliant contact engaged because its gap is beyond its bound)."""
        sec = self.section
        return tr.mode_final in (sec.mode, sec.start_mode(z1))

    def apply(self, s, k: int = 1, jacobian: bool = False) -> MapResult:
        """Apply ``P^k`` to the section point ``s`` (optionally with ``DP^k``).

        Returns
        -------
        MapResult
            ``t_start = phi0``, ``t_hit = phi0 + k Tc``; status ``"returned"``, or why the
            run stopped (the simulator's termination: ``"diverged"``, ``"jump_limit"``, ...),
            or ``"other_mode"`` (the image is in another mode than the section's).
        """
        k = check_returns(k)
        sec = self.section
        z0, t0 = sec.to_state(sec.check_point(s))
        t1 = t0 + k * sec.period
        nan = np.full(self.dim, np.nan)
        if not self.section.sampling_commensurate:
            return MapResult(nan, False, "sampling_incommensurate", t0, t0, z0, sec.mode)
        try:
            tr = self._simulate(z0, t0, t1)
        except (ValueError, FloatingPointError) as exc:
            return MapResult(nan, False, f"bad_start: {exc}", t0, t0, z0, sec.mode)
        J = tr.jumps
        jumps = tuple((float(J.t[q]), J.source[q], J.guard[q], J.target[q], J.kind[q])
                      for q in range(len(J)))
        grazing = any(j[4] == "grazing" for j in jumps)
        z1 = np.asarray(tr.x_final, float)
        if tr.termination is not TerminationCause.END_TIME:
            return MapResult(nan, False, tr.termination.name.lower(), t0, float(tr.t_final), z1,
                             tr.mode_final, jumps, grazing)
        if not self._on_section(tr, z1):
            return MapResult(nan, False, "other_mode", t0, t1, z1, tr.mode_final, jumps, grazing)
        img = sec.from_state(z1)
        DP, zeros = None, None
        if jacobian and not any(j[4] == "simultaneous" for j in jumps):
            # the structural count (a QR or SVD per jump) is what an orbit's multipliers
            # need: it is made at periodic points, not at Newton's iterates on the way
            x = np.asarray(s, float)
            periodic = float(np.max(np.abs(img - x))) <= _PERIODIC * max(
                1.0, float(np.max(np.abs(x))))
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                DP, tangent, zeros = self._jacobian(s, tr, periodic)
            grazing = grazing or tangent
            if tangent or not np.all(np.isfinite(DP)):
                DP, zeros = None, None    # no saltation matrix somewhere: differences
        return MapResult(img, True, "returned", t0, t1, z1, sec.mode, jumps, grazing, DP,
                         structural_zeros=(None if zeros is None else self.dim - zeros))

    def _jacobian(self, s, tr, structural=True) -> tuple:
        """``(DP, tangent, structural rank)`` of a run (module docstring; the rank None
        without `structural`)."""
        sec = self.section
        ha = sec.automaton
        rec = _records(ha, tr)
        E = sec.embedding(s)
        Z, tangent, rank = sensitivity_chain(rec, len(rec.st0), len(rec.jt), ha._slim(),
                                             ha.packed, E, track=structural)
        if not structural:
            return sec.C @ Z, tangent, None
        C = sec.C
        rank = min(rank, int(np.linalg.matrix_rank(C @ _orth(Z, rank))) if rank else 0)
        DP = C @ Z
        if np.all(np.isfinite(DP)) and DP.size:
            # what the chain makes exactly singular beyond the resets (a crossing pinned
            # to a sample, an accumulation's limit) shows as singular values at rounding
            sv = np.linalg.svd(DP, compute_uv=False)
            rank = min(rank, int(np.sum(sv > _ROUNDING * max(1.0, float(sv[0])))))
        return DP, tangent, rank

    # ---- what an orbit of the map is (hooks of find_orbit)
    def refuse(self, s0, k, **options):
        """``sampling_incommensurate``: the sampling instants never return with the phase."""
        sec = self.section
        if sec.sampling_commensurate:
            return None
        T = sec.reference_period
        near = "; ".join(f"dt = {dt:g} -> {d:.10g} (T / {round(T / d)})"
                         for dt, d in sec.nearest_commensurate_dt().items())
        return "sampling_incommensurate", (
            f"the sampling periods and the reference period T = {T:.10g} have no common "
            f"multiple m T (m <= 64): the sampling instants never return with the phase, so "
            f"no motion repeats. The nearest sampling periods that divide T: {near}")

    def validate(self, s, k: int, result: MapResult, *, verify=True, **options) -> tuple:
        """``(reason, n_periods, detail, return_error)``: an orbit of ``P^k`` lasts ``k Tc``
        (``k Tc / T`` reference periods) by construction; with ``verify``, one independent
        simulation of ``k Tc`` from the section point must return to it (``1e-6``
        relative)."""
        sec = self.section
        m = round(k * sec.period / sec.reference_period)
        if not verify:
            return "converged", m, "", math.nan
        err = self.return_error(s, k)
        if not err <= 1e-6:
            return "not_periodic", m, (f"simulating {k} common period(s) from the section "
                                       f"point does not return to it (relative error "
                                       f"{err:.3g})"), err
        return "converged", m, "", err

    def return_error(self, s, k: int = 1) -> float:
        """Relative distance (``max(1, |z|)``) between the state at the section point and the
        state an independent run of the simulator reaches ``k Tc`` later."""
        sec = self.section
        z0, t0 = sec.to_state(s)
        try:
            tr = sec.automaton.simulate(z0, sec.start_mode(z0), (t0, t0 + k * sec.period),
                                        max_jumps=self.max_jumps, max_steps=self.max_steps,
                                        resolver=sec.resolver, simtol=self.simtol)
        except (ValueError, RuntimeError, FloatingPointError):
            return math.inf
        z1 = np.asarray(tr.x_final, float)
        if tr.termination is not TerminationCause.END_TIME or not self._on_section(tr, z1):
            return math.inf
        return float(np.max(np.abs(z1 - z0))) / max(1.0, float(np.max(np.abs(z0))))

    def point_quantities(self, s, k: int, result: MapResult, **options) -> dict:
        """How ``DP`` was taken at an orbit: ``jacobian`` (``"saltation"`` or ``"central
        differences"``), and for differences the ``jacobian_step`` (relative) and the
        ``jacobian_error`` estimate (largest entry of ``J(h) - J(h/2)``, relative to
        ``max(1, |J|)``)."""
        del options
        if result.DP is not None:
            return {"jacobian": "saltation", "phase": self.phase}
        try:
            J1 = self.jacobian_fd(s, k)
            J2 = self.jacobian_fd(s, k, h=5e-7, scale=np.maximum(1.0, np.abs(s)))
        except RuntimeError:
            return {"jacobian": "central differences", "jacobian_step": 1e-6,
                    "jacobian_error": math.nan, "phase": self.phase}
        err = float(np.max(np.abs(J1 - J2))) / max(1.0, float(np.max(np.abs(J1))))
        return {"jacobian": "central differences", "jacobian_step": 1e-6,
                "jacobian_error": err, "phase": self.phase}


def _orth(Z, rank):
    """An orthonormal basis of the ``rank`` leading directions of the columns of ``Z``."""
    U = np.linalg.svd(Z, full_matrices=False)[0]
    return U[:, :rank]


def _records(ha, tr) -> SimpleNamespace:
    """A trajectory's jumps and segments as the index records of
    :func:`~hybridpd.analysis.saltation.sensitivity_chain`."""
    J, S = tr.jumps, tr.segments
    index = {name: i for i, name in enumerate(ha.built_mode_names)}
    gidx = {}
    slim = ha._slim()
    for i, m in enumerate(slim):
        for g, guard in enumerate(m.guards):
            gidx[(i, guard.name)] = g
    n1 = ha.n_states + 1
    jsrc = np.array([index[m] for m in J.source], np.int64)
    jdst = np.array([index[m] for m in J.target], np.int64)
    jg = np.array([gidx.get((s, g), -1) for s, g in zip(jsrc, J.guard)], np.int64)
    pad = np.ones((len(J.t), 1))
    return SimpleNamespace(
        jt=np.asarray(J.t, float), jg=jg, jsrc=jsrc, jdst=jdst,
        jkind=np.array([_KINDS[k] for k in J.kind], np.int64),
        jpre=np.hstack([J.pre, pad]).reshape(-1, n1), jpost=np.hstack([J.post, pad])
        .reshape(-1, n1), st0=np.asarray(S.t_start, float), st1=np.asarray(S.t_end, float),
        smode=np.array([index[m] for m in S.mode], np.int64), sj=np.asarray(S.j, np.int64))
