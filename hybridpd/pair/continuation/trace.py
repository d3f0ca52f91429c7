"""One application of the impact map with its impact pattern (walls, flight times, grazing
touches, sticking) and the flight margins."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.model import check_int
from hybridpd.pair.batch import STATUS_IMPACT, trace_once, turning_margins
from hybridpd.pair.continuation._common import (
    _fixed_parameters,
    _impact_map,
    _min,
    _section_point,
)
from hybridpd.pair.impactmap import ImpactMap


@dataclass(frozen=True)
class ImpactStep:
    """One wall contact met by an application of ``P``.

    Attributes
    ----------
    wall : int
        +1 (``z3 = +L``) or -1 (``z3 = -L``).
    tau : float
        Flight time (time units) from the previous contact (or release) to this one.
    speed : float
        Approach speed ``wall * z4`` just before the contact (length/time, >= 0).
    kind : str
        ``"impact"`` (Newton's law applied), ``"graze"`` (tangential touch: the approach speed
        is below the engine's velocity tolerance, no velocity jump) or ``"stick"`` (impacts
        accumulated; the masses then moved together for ``stick_time``).
    stick_time : float
        Duration of the sticking phase (time units), 0 unless ``kind == "stick"``.
    """

    wall: int
    tau: float
    speed: float
    kind: str
    stick_time: float = 0.0
    __repr__ = compact_repr


@dataclass(frozen=True)
class MapTrace:
    """One application of ``P`` with its impact pattern and flight diagnostics.

    Attributes
    ----------
    s : ndarray, shape (4,)
        ``P(s0)`` (``phi`` in ``[0, T)``); NaN unless ``ok``.
    ok : bool
        The trajectory returned to the section.
    status : int
        0 when ``ok``, else ``10 + batch.STATUS_*`` (as :class:`~hybridpd.pair.impactmap.MapResult`).
    steps : tuple of ImpactStep
        Contacts after the initial ``+L`` impact; the last one is the return to ``+L``.
    margin : float
        Smallest interior distance of a flight to the wall it turns towards, divided by ``L``
        (dimensionless): at every interior turning point of ``z3`` a maximum is measured to
        ``+L`` and a minimum to ``-L``; 1 if ``z3`` has no interior turning point. It tends to
        0 at grazing (paper (19)). NaN if not computed.
    min_speed : float
        Smallest approach speed over the impacts and grazing touches (length/time).
    """

    s: np.ndarray
    ok: bool
    status: int
    steps: tuple
    margin: float
    min_speed: float
    __repr__ = compact_repr

    @property
    def walls(self) -> tuple:
        """Walls of the contacts, e.g. ``(-1, 1)`` for the simple pattern."""
        return tuple(st.wall for st in self.steps)

    @property
    def signature(self) -> tuple:
        """``((wall, kind), ...)``: what a pattern change (grazing) is detected on."""
        return tuple((st.wall, st.kind) for st in self.steps)

    @property
    def simple(self) -> bool:
        """The pattern ``(+L, -L, +L)`` with two genuine impacts (symbolic ``DP`` applies)."""
        return self.signature == ((-1, "impact"), (1, "impact"))


def trace_map(impact_map_: ImpactMap, s, *, margin: bool = True,
              margin_samples: int = 256) -> MapTrace:
    """Apply ``P`` once from ``s`` and record every contact (the impact pattern).

    This is the compiled engine's own run with its record
    (:func:`hybridpd.pair.batch.trace_once`), so ``trace_map(P, s).s`` equals ``P(s)``; it
    additionally gives walls, flight times, approach speeds, grazing touches and sticking phases, and measures how close every
    flight comes to a wall in its interior.

    Parameters
    ----------
    impact_map_ : ImpactMap
    s : array_like, shape (4,)
        Section point ``(phi, z1, z2, z4)`` with ``z4 >= 0`` (``z4 = 0``: a grazing arrival,
        as returned by ``P`` after a tangential touch).
    margin : bool
        Compute :attr:`MapTrace.margin` (``margin_samples`` flow evaluations per flight).
    margin_samples : int
        Grid size of the turning-point search in each flight.

    Returns
    -------
    MapTrace

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.pair.orbits import symmetric_orbit
    >>> orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    >>> P = ImpactMap(orb.pair, orb.gains, orb.reference())
    >>> tr = trace_map(P, orb.fixed_point)
    >>> tr.walls, tr.simple
    ((-1, 1), True)
    """
    # z4 = 0 (the closure of the section) is accepted: P itself returns it after a
    # tangential touch of the right wall
    P = _impact_map(impact_map_)
    s = _section_point(s, "s", closure=True)
    nsamp = check_int("margin_samples", margin_samples, 2)
    out, st, _n, rec = trace_once(P.params, P._c, s, P.tol, P.max_impacts)
    kinds = ("impact", "graze", "stick")
    steps = tuple(ImpactStep(int(r[0]), float(r[1]), float(r[2]), kinds[int(r[3])],
                             float(r[4])) for r in rec)
    marg = np.nan
    if margin:
        # smallest distance / L to the wall approached at interior turning points of z3
        marg = min([1.0] + [turning_margins(P.params, P._c, *r[5:10], r[1], nsamp, True)[0]
                            for r in rec if r[1] > 0.0])
    speeds = [float(r[2]) for r in rec if r[3] != 2]
    ok = st == STATUS_IMPACT
    return MapTrace(out if ok else np.full(4, np.nan), bool(ok), int(st), steps, marg,
                    _min(speeds))


def trace_orbit(P: ImpactMap, s, k: int, margin_samples: int = 256) -> list:
    """:func:`trace_map` (with margins) of ``s, P(s), ..., P^{k-1}(s)``, up to the first
    application that does not return."""
    traces, cur = [], np.asarray(s, float)
    for _ in range(k):
        tr = trace_map(P, cur, margin=True, margin_samples=margin_samples)
        traces.append(tr)
        if not tr.ok:
            break
        cur = tr.s
    return traces


def orbit_quantities(P: ImpactMap, s, k: int, *, graze_tol: float = 1e-6,
                     margin_samples: int = 256) -> dict:
    """The pair's quantities of the segment ``s, P(s), ..., P^{k-1}(s)`` (the hook
    :meth:`ImpactMap.point_quantities`).

    Returns a dict with ``orbit`` (shape ``(k, 4)``, the iterates as far as ``P`` is defined),
    ``pattern`` (the :class:`ImpactStep` of each application), ``walls``, ``n_impacts``,
    ``margin`` (smallest flight margin over ``L``, see :class:`MapTrace`),
    ``min_impact_speed`` (length/time), ``sticking``, ``grazing`` (a grazing touch, a
    margin below ``graze_tol`` or an approach speed below ``graze_tol`` times the largest),
    ``minimal_period`` (smallest ``d`` dividing ``k`` with ``P^d(s) = s`` to ``1e-7``) and
    ``symbolic_dp`` (every application has the simple pattern: the map's ``DP`` is the chain
    of its named blocks, :meth:`ImpactMap.blocks`; finite differences otherwise) and
    ``parameters`` (the map's ``kp, kv, e, mu, L, m2, xm, omega, case``).
    """
    from hybridpd.analysis.maps import minimal_period

    traces = trace_orbit(P, s, k, margin_samples)
    steps = [st for tr in traces for st in tr.steps]
    margin = _min([tr.margin for tr in traces])
    speeds = [st.speed for st in steps if st.kind != "stick"]
    vmax, vmin = max(speeds, default=0.0), _min(speeds)
    grazing = (any(st.kind == "graze" for st in steps)
               or (np.isfinite(margin) and margin < graze_tol)
               or (vmax > 0 and vmin < graze_tol * vmax))
    pattern = tuple(tr.steps for tr in traces)
    ok = all(tr.ok for tr in traces)
    return {"orbit": np.array([s] + [tr.s for tr in traces[:-1]]), "pattern": pattern,
            "walls": tuple(tuple(st.wall for st in p) for p in pattern),
            "n_impacts": len(steps), "margin": margin, "min_impact_speed": vmin,
            "sticking": any(st.kind == "stick" for st in steps), "grazing": bool(grazing),
            "minimal_period": minimal_period(P, s, k) if ok else k,
            "symbolic_dp": ok and all(tr.simple for tr in traces),
            "parameters": _fixed_parameters(P)}
