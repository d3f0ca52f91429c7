"""The impact map ``P`` (paper (21)-(23)), its Jacobian ``DP`` (24)-(26) and stability (27).

Section ``Sigma = {z3 = +L, z4 > 0}`` (pre-impact states at the right wall), coordinates
``s = (phi, z1, z2, z4)`` with ``phi = t mod T``, ``z1 = x2``, ``z2 = y2``, ``z4 = y1 - y2``.
``P(s)`` applies the impact at ``+L`` and simulates until the next pre-impact state at the
right wall, whatever happens in between (on a simple orbit: one impact on the left wall). It
is computed by the simulator (the compiled closed-form engine of :mod:`hybridpd.pair.batch`), so
it is usable from any state, not only near an orbit.

``DP`` (:meth:`ImpactMap.jacobian`, an array like every map's) is the product of the symbolic
blocks ``DP43 DP32 DP21 DP10`` (:mod:`hybridpd.pair.symbolic`, by name from
:meth:`ImpactMap.blocks`) whenever the return has the simple pattern (+L, -L, +L);
:meth:`ImpactMap.jacobian_fd` gives central finite differences of the simulated map as an
independent check.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.analysis.floquet import Stability, stability
from hybridpd.analysis.maps import MapResult, PoincareMap, check_returns, minimal_period
from hybridpd.model import (
    Case,
    ImpactPair,
    Reference,
    as_gains,
    check_array,
    check_int,
    check_positive,
)
from hybridpd.pair import batch as B
from hybridpd.pair import symbolic
from hybridpd.pair.batch import (
    STATUS_IMPACT,
    impact_map,
    iterate_map,
    trace_once,
    turning_margins,
)
from hybridpd.pair.family import _fixed_parameters, _min, pair_family
from hybridpd.pair.params import PairParams

__all__ = ["BatchMapResult", "ImpactMap", "MapResult", "Stability", "stability"]

#: :attr:`MapResult.status` of the engine's codes ``10 + batch.STATUS_*``.
STATUS_NAMES = {0: "returned", 11: "end_time", 12: "sticking", 13: "unresolved",
                14: "nonfinite"}
_KINDS = ("crossing", "grazing", "zeno")


@dataclass(frozen=True)
class BatchMapResult:
    """Result of applying ``P`` to many points at once (:meth:`ImpactMap.apply_batch`).

    Attributes
    ----------
    s : ndarray, shape (N, 4)
        Images ``P(s)`` (``phi`` in ``[0, T)``); meaningless where ``ok`` is False.
    ok : ndarray of bool, shape (N,)
        The trajectory returned to the section.
    status : ndarray of int, shape (N,)
        0 when ``ok``; else ``10 + batch.STATUS_*`` of the flight that failed.
    n_impacts : ndarray of int, shape (N,)
        Impacts taken to return (2 on a simple orbit).
    """

    __repr__ = compact_repr

    s: np.ndarray
    ok: np.ndarray
    status: np.ndarray
    n_impacts: np.ndarray


class ImpactMap(PoincareMap):
    """The impact map of the PD-controlled impact pair: the compiled closed-form engine.

    A named specialisation of the map protocol (:class:`~hybridpd.analysis.maps.PoincareMap`)
    for the PD impact pair: closed-form flights between impacts (:mod:`hybridpd.pair.batch`),
    ``DP`` from the symbolic blocks ``DP43 DP32 DP21 DP10`` on the simple pattern
    ``(+L, -L, +L)`` (finite differences otherwise). It equals the general
    :class:`~hybridpd.analysis.hybridmap.SectionMap` on :func:`~hybridpd.mechanics.sections.
    impact_pair_section` to about ``1e-12`` (``tests/test_specialisations.py``). Measured
    (``benchmarks/bench_specialisations.py``, README parameters, loaded 2-core machine): ``P``
    5 times faster per call and 57-130 times faster in batch (:meth:`apply_batch`) than the
    general path; the symbolic ``DP`` per point is 0.3-0.6 times as fast as the general
    saltation ``DP`` (it is kept for its named blocks and the vectorised orbit grids of
    :mod:`hybridpd.pair.symbolic`, not for speed). Limits: PD controllers only (any LTI
    controller: :meth:`hybridpd.pair.lti.LTIOrbitResult.section_map`); a sticking phase is one
    ``"zeno"`` jump and its release, not the accumulating impacts the general path resolves
    one by one.

    Parameters
    ----------
    pair : ImpactPair
    gains : PDGains or (kp, kv)
    reference : Reference
    case : {"collocated", "noncollocated"}
    tol : float
        Gap tolerance (length) of the contact location.
    max_impacts : int
        Bound on the impacts taken by one application of ``P``.

    Examples
    --------
    >>> from hybridpd import ImpactPair, PDGains, Reference
    >>> from hybridpd.pair.orbits import symmetric_orbit
    >>> orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    >>> P = ImpactMap(orb.pair, orb.gains, orb.reference())
    >>> bool(np.allclose(P(orb.fixed_point), orb.fixed_point, atol=1e-12))
    True
    >>> P.apply(orb.fixed_point).signature
    (('wall+', 'crossing'), ('wall-', 'crossing'))
    >>> B = P.blocks(orb.fixed_point)
    >>> bool(np.allclose(P.jacobian(orb.fixed_point), B.DP43 @ B.DP32 @ B.DP21 @ B.DP10))
    True
    """

    def __init__(self, pair: ImpactPair, gains, reference: Reference, case="collocated", *,
                 tol: float = 1e-13, max_impacts: int = 1000):
        gains = as_gains(gains)
        if not isinstance(pair, ImpactPair):
            raise ValueError(f"pair must be an ImpactPair, got {type(pair).__name__}")
        if not isinstance(reference, Reference):
            raise ValueError(f"reference must be a Reference, got {type(reference).__name__}")
        self.pair, self.gains, self.reference = pair, gains, reference
        self.case = Case.parse(case)
        self.tol = check_positive("tol", tol)
        self.max_impacts = check_int("max_impacts", max_impacts, 1)
        self.params = PairParams.of(pair, gains, reference.omega, xm=reference.xm).packed()
        self._c = 0 if self.case is Case.COLLOCATED else 1

    @property
    def period(self) -> float:
        """``T = 2 pi / omega``."""
        return self.reference.period

    @property
    def dim(self) -> int:
        return 4

    @property
    def names(self) -> tuple:
        return ("phi", "z1", "z2", "z4")

    def _points(self, s) -> np.ndarray:
        s = check_array("s", s, trailing=(4,))
        if np.any(s[..., 3] <= 0):
            raise ValueError("s[..., 3] = z4 must be > 0 (approaching the +L wall)")
        return np.ascontiguousarray(s.reshape(-1, 4))

    def check_point(self, s) -> np.ndarray:
        """``s`` as a section point ``(phi, z1, z2, z4)`` with ``z4 > 0``; ``ValueError``
        naming ``s`` otherwise."""
        return self._points(check_array("s", s, shape=(4,)))[0].copy()

    def _fd_steps(self, S, H):
        H = H.copy()
        H[..., 3] = np.minimum(H[..., 3], 0.5 * S[..., 3])    # stay on the section side z4 > 0
        return H

    def apply(self, s, k: int = 1, jacobian: bool = False) -> MapResult:
        """Apply ``P^k`` to the section point ``s`` (shape ``(4,)``), optionally with ``DP^k``.

        ``DP^k`` is the chain of symbolic blocks when every return has the simple pattern,
        else central differences of the engine's ``P^k``.
        """
        k = check_returns(k)
        cur = self._points(check_array("s", s, shape=(4,)))[0]
        T = self.period
        jumps = [(float(cur[0]), "free", "wall+", "free", "crossing")]
        s0, blocks = cur, []
        t_abs = float(cur[0])
        st = 0
        for i in range(k):
            out, st, _n, rec = trace_once(self.params, self._c, cur, self.tol, self.max_impacts)
            off = t_abs - cur[0]        # engine time (from phi) -> time since t = 0
            for q, r in enumerate(rec):
                t = float(r[B.REC_T] + r[B.REC_TAU] + off)
                g = "wall+" if r[B.REC_WALL] > 0 else "wall-"
                kind = int(r[B.REC_KIND])
                if st == 0 and q == len(rec) - 1:
                    t_abs = t
                    if i < k - 1:
                        jumps.append((t, "free", g, "free", _KINDS[kind]))
                elif kind == B.KIND_STICKING:
                    sm = "stick" + g[-1]
                    jumps += [(t, "free", g, sm, "zeno"),
                              (t + float(r[B.REC_STICK_TIME]), sm, "release" + g[-1], "free",
                               "crossing")]
                else:
                    jumps.append((t, "free", g, "free", _KINDS[kind]))
            if st != 0:
                return MapResult(np.full(4, np.nan), False, STATUS_NAMES.get(int(st),
                                 str(int(st))), float(jumps[0][0]), float(out[0]),
                                 self.state(out, out[0]), "free", tuple(jumps),
                                 any(j[4] == "grazing" for j in jumps))
            blocks.append((cur, rec))
            cur = out
        z = self.state(cur, t_abs)
        grazing = any(j[4] == "grazing" for j in jumps) or cur[3] <= 1e-12 * max(1.0, T)
        DP = self._power_dp(s0, k, blocks) if jacobian else None
        return MapResult(cur.copy(), True, "returned", float(jumps[0][0]), t_abs, z, "free",
                         tuple(jumps), bool(grazing), DP)

    def labeller(self):
        """The pair's basin labelling: compiled, its ``(x1, y1)`` slice and the paper's
        metric (:class:`hybridpd.pair.basins.PairLabeller`)."""
        # deferred import: the basin code loads only when a basin is labelled
        from hybridpd.pair.basins import PairLabeller

        return PairLabeller(self)

    def point_quantities(self, s, k: int, result: MapResult, *, graze_tol: float = 1e-6,
                         margin_samples: int = 256, **options) -> dict:
        """The pair's walls, flight margins and contact pattern along ``s, ..., P^{k-1}(s)``
        (:func:`hybridpd.pair.continuation.trace.orbit_quantities`)."""
        return orbit_quantities(self, s, k, graze_tol=graze_tol,
                                margin_samples=margin_samples)

    def traces(self, s, k: int, margin_samples: int = 256) -> list:
        """:class:`MapTrace` (with flight margins) of ``s, P(s), ..., P^{k-1}(s)``, up to the
        first application that does not return (:func:`trace_orbit`)."""
        return trace_orbit(self, s, k, margin_samples)

    def family(self, parameter: str, *, x10: float | None = None, n: int = 1,
               fd_step: float = 1e-6, graze_tol: float = 1e-6, margin_samples: int = 128):
        """This map's family in one parameter, with the pair's rules of continuation (a
        :class:`~hybridpd.pair.family.PairFamily`: callable, ``p -> ImpactMap``), for
        :func:`~hybridpd.analysis.continuation.continue_orbit`.

        Parameters
        ----------
        parameter : str
            One of ``kp, kv, e, mu, xm, omega, L, m2``; with ``x10`` (the design path: ``xm``
            follows the amplitude of the order-``n`` symmetric orbit realising ``x10``, paper
            (20); the map's own ``xm`` is replaced by the design value) one of ``kp, kv, e,
            mu, omega, L, m2, gamma, x10`` (``gamma`` then means ``L / x10``).
        x10 : float, optional
            The design amplitude (length).
        n : int
            The odd order of the designed symmetric orbit.
        fd_step : float
            Relative step of ``dF/dp`` (central at the current point, one-sided at the edge
            of the parameter's domain).
        graze_tol : float
            Grazing threshold of the event at the end of a branch.
        margin_samples : int
            Grid of the turning-point search per flight (the points' flight margins).

        Returns
        -------
        PairFamily
            Its ``value`` is the parameter's value in this map; calling it at a value out of
            the parameter's range, or where the design has no amplitude, raises
            ``ValueError``.

        Examples
        --------
        >>> from hybridpd import ImpactPair, PDGains
        >>> from hybridpd.pair.orbits import symmetric_orbit
        >>> orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
        >>> P = ImpactMap(orb.pair, orb.gains, orb.reference())
        >>> fam = P.family("kv")
        >>> fam.value, fam(22.0).gains.kv
        (20.0, 22.0)
        """
        return pair_family(self, parameter, x10=x10, n=n, fd_step=fd_step,
                           graze_tol=graze_tol, margin_samples=margin_samples)

    def state(self, s, t: float | None = None) -> np.ndarray:
        """Full state ``[x1, y1, x2, y2, pc, ps]`` of the pre-impact section point ``s`` at time
        ``t`` (default: its phase ``s[0]``)."""
        t = s[0] if t is None else t
        return np.array([s[1] + self.pair.L, s[2] + s[3], s[1], s[2],
                         *self.reference.exo_state(t)])

    def _power_dp(self, s, k, blocks) -> np.ndarray:
        """``DP^k``: the chain of symbolic blocks when every return is simple, else FD."""
        simple = all(len(rec) == 2 and rec[0, B.REC_WALL] < 0 and rec[1, B.REC_WALL] > 0
                     and np.all(rec[:, B.REC_KIND] == B.KIND_IMPACT) for _s, rec in blocks)
        if not simple:
            return self.jacobian_fd(s, k=k, one_sided=True)
        DP = np.eye(4)
        for si, rec in blocks:
            DP = self._symbolic(si, rec[0, B.REC_TAU], rec[1, B.REC_TAU]).DP.reshape(4, 4) @ DP
        return DP

    def _symbolic(self, s, tau1, tau2) -> symbolic.JacobianResult:
        g, p = self.gains, self.pair
        return symbolic.map_jacobian(np.asarray(s, float), tau1, tau2, xm=self.reference.xm,
                                     kp=g.kp, kv=g.kv, m2=p.m2, mu=p.mu, e=p.e, L=p.L,
                                     w=self.reference.omega, case=self.case.value)

    def apply_batch(self, s) -> BatchMapResult:
        """Apply ``P`` to points ``s`` of shape ``(4,)`` or ``(N, 4)`` in the compiled loop."""
        pts = self._points(s)
        out, status, nimp = impact_map(self.params, self._c, pts, self.tol, self.max_impacts)
        return BatchMapResult(out, status == 0, status, nimp)

    def apply_many(self, S, k: int = 1) -> tuple:
        S = np.ascontiguousarray(np.atleast_2d(np.asarray(S, float)))
        img = S.copy()
        ok = np.all(np.isfinite(S), axis=1) & (S[:, 3] > 0)
        for _ in range(check_returns(k)):
            idx = np.flatnonzero(ok)
            if idx.size == 0:
                break
            out, status, _n = impact_map(self.params, self._c, np.ascontiguousarray(img[idx]),
                                         self.tol, self.max_impacts)
            img[idx] = out
            ok[idx] = status == 0
        img[~ok] = np.nan
        return img, ok

    def __call__(self, s, k: int = 1) -> np.ndarray:
        """``P^k(s)`` of points ``(4,)`` or ``(N, 4)``; ``RuntimeError`` where undefined."""
        s_arr = check_array("s", s, trailing=(4,))
        img, ok = self.apply_many(self._points(s_arr), k)
        if not np.all(ok):
            raise RuntimeError(f"P undefined at {int((~ok).sum())} point(s)")
        return img.reshape(s_arr.shape)

    def iterate(self, s0, n: int, k: int = 1) -> np.ndarray:
        """Orbit ``s0, P^k(s0), ..., P^{nk}(s0)``, shape ``(n + 1, 4)`` (NaN rows after a failure)."""
        if k != 1:
            return super().iterate(s0, n, k)
        orbit, _done, _st = iterate_map(self.params, self._c, self._points(s0)[0], int(n),
                                        self.tol, self.max_impacts)
        return orbit

    #: Diagram classes of the engine's statuses (:mod:`hybridpd.analysis.diagrams`).
    status_classes: ClassVar[dict] = {"end_time": "no_impact", "sticking": "sticking",
                                      "unresolved": "unresolved", "nonfinite": "diverged"}

    def iterate_status(self, s0, n: int, k: int = 1) -> tuple:
        """:meth:`iterate` and why it stopped (``""``, or a name of ``STATUS_NAMES``), in the
        compiled loop."""
        if k != 1:
            return super().iterate_status(s0, n, k)
        orbit, _done, st = iterate_map(self.params, self._c, self._points(s0)[0], int(n),
                                       self.tol, self.max_impacts)
        return orbit, "" if st == 0 else STATUS_NAMES.get(int(st), str(int(st)))

    def jacobians(self, S, k: int = 1, h: float = 1e-6) -> np.ndarray:
        """``DP`` at every row of ``S`` (shape ``(N, 4)``): for ``k = 1`` the batch finite
        differences :meth:`jacobians_fd` (one call of the engine, faster than the symbolic
        ``DP`` point by point), else the symbolic ``DP^k``. Shape ``(N, 4, 4)``."""
        if k != 1:
            return super().jacobians(S, k)
        return self.jacobians_fd(S, k, h)

    def flight_times(self, s):
        """Walls and flight times of one application of ``P`` from the section point ``s``.

        Returns a list of ``(wall, tau)`` for the impacts after the initial one.
        """
        _out, st, _n, rec = trace_once(self.params, self._c, self._points(s)[0], self.tol,
                                       self.max_impacts)
        if st != 0 or np.any(rec[:, B.REC_KIND] == B.KIND_STICKING):
            raise RuntimeError(f"no return to the section without sticking: status {st}")
        return [(int(r[B.REC_WALL]), float(r[B.REC_TAU])) for r in rec]

    def blocks(self, s) -> symbolic.JacobianResult:
        """The named blocks of ``DP`` at ``s`` (paper (24)-(25)): ``DP10`` (impact at ``+L``),
        ``DP21`` (flight to ``-L``), ``DP32`` (impact at ``-L``), ``DP43`` (flight back), their
        product ``DP`` and the section points between them. The return from ``s`` must have
        the simple pattern ``(+L, -L, +L)`` (``ValueError`` otherwise: :meth:`jacobian` then
        gives finite differences)."""
        seq = self.flight_times(s)
        if [w for w, _ in seq] != [-1, 1]:
            raise ValueError(
                f"s: the named blocks need the impact pattern (+L, -L, +L); got walls "
                f"{[w for w, _ in seq]} (use jacobian)")
        return self._symbolic(s, seq[0][1], seq[1][1])

    def stability(self, s) -> Stability:
        """Stability of the fixed point ``s`` from ``DP`` (:meth:`jacobian`)."""
        return stability(self.jacobian(s))


def _section_point(s, name, closure=False) -> np.ndarray:
    a = check_array(name, s, shape=(4,))  # (phi, z1, z2, z4)
    if a[3] < 0 or (a[3] == 0 and not closure):
        raise ValueError(f"{name}[3] = z4 must be > 0 (approaching the +L wall), got {a[3]!r}")
    return a


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
    if not isinstance(impact_map_, ImpactMap):
        raise ValueError(f"impact_map_ must be an ImpactMap, got {type(impact_map_).__name__}")
    P = impact_map_
    s = _section_point(s, "s", closure=True)
    nsamp = check_int("margin_samples", margin_samples, 2)
    out, st, _n, rec = trace_once(P.params, P._c, s, P.tol, P.max_impacts)
    kinds = {B.KIND_IMPACT: "impact", B.KIND_GRAZING: "graze", B.KIND_STICKING: "stick"}
    steps = tuple(ImpactStep(int(r[B.REC_WALL]), float(r[B.REC_TAU]), float(r[B.REC_SPEED]),
                             kinds[int(r[B.REC_KIND])], float(r[B.REC_STICK_TIME]))
                  for r in rec)
    marg = np.nan
    if margin:
        # smallest distance / L to the wall approached at interior turning points of z3
        start = slice(B.REC_T, B.REC_Y2 + 1)      # t, x1, y1, x2, y2 where the flight starts
        marg = min([1.0] + [turning_margins(P.params, P._c, B.Flight(*map(float, r[start])),
                                            r[B.REC_TAU], nsamp, True)[0]
                            for r in rec if r[B.REC_TAU] > 0.0])
    speeds = [float(r[B.REC_SPEED]) for r in rec if r[B.REC_KIND] != B.KIND_STICKING]
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
