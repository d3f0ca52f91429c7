"""Basin mappers: one initial condition on a section -> a label, built from any map.

After Attractors.jl: a **mapper** takes a section point to a label of
:data:`~hybridpd.analysis.labels.LABELS` (``converged`` to its orbit, ``not_converged``,
``diverged``, ...); a basin (:func:`hybridpd.sweeps.basins.basin_of_attraction`) is the thin
layer that applies it over a 2-D grid and names the attractors of the points that did not
converge (:class:`Catalogue`).

:class:`Mapper` is the one protocol. Every hook a basin uses is declared on it with its
default: :meth:`~Mapper.labels` (abstract), :meth:`~Mapper.slice` (the grid's section points),
:meth:`~Mapper.admissible` (points never iterated), :meth:`~Mapper.label_tails` (labels plus
the iterates after ``n_iter`` of the unconverged points), :meth:`~Mapper.spec` (a picklable
description that worker processes rebuild), :meth:`~Mapper.catalogue`, :meth:`~Mapper.metric`,
:meth:`~Mapper.metadata`, :attr:`~Mapper.orbit_name` and :attr:`~Mapper.orbit_kind`.

:func:`mapper` builds a :class:`MapMapper` from any map. What the map adds comes from its
:meth:`~hybridpd.analysis.maps.PoincareMap.labeller` hook (a :class:`Labeller`: the impact
pair's compiled labelling, its ``(x1, y1)`` slice and the paper's metric); a section map of
any automaton labels in the compiled section kernel
(:func:`hybridpd.analysis.periodic._label_kernel`), any other map by its own
:meth:`~hybridpd.analysis.maps.PoincareMap.iterate_many`.

**Early exit.** For a stable fixed point, ``Q`` solving the Lyapunov equation of ``DP / rho_t``
defines a norm in which the map contracts; an iterate inside the certified ball
(:func:`hybridpd.analysis.certify.certify_ball`, one ball per cycle point; numerical, sampled)
is labelled ``converged`` at once. ``early_exit=False`` runs every trajectory to the end.
"""
from __future__ import annotations

import abc
import math
import pickle
from dataclasses import dataclass, replace

import numpy as np

from hybridpd.analysis.basins import (
    NO_CONVERGENCE,
    Attractor,
    Slice,
    grid_slice,
    off_section_axis,
)
from hybridpd.analysis.certify import certify_ball
from hybridpd.analysis.hybridmap import SectionMap
from hybridpd.analysis.labels import LABELS, OFF_SECTION
from hybridpd.analysis.maps import PoincareMap, check_returns, detect_period, minimal_period
from hybridpd.analysis.periodic import (
    _CONVERGED,
    _DIVERGED,
    _NOT_CONVERGED,
    _TO_RESOLVER,
    _UNRESOLVED,
    _ZENO_STICKING,
    LabelPoints,
    LabelSpec,
    _dist,
    _label_kernel,
    _n_finite,
    find_orbit,
)
from hybridpd.analysis.strobe import StroboscopicMap
from hybridpd.model import check_int, check_positive

__all__ = ["Catalogue", "Growth", "Labeller", "MapMapper", "Mapper", "Metric", "mapper"]


@dataclass(frozen=True)
class Growth:
    """Window growth of a basin: while the basin of label 0 touches the window's edge, the
    touching sides are pushed out to twice their distance from the orbit's point (at least
    half the span) and the grid relabelled, at most ``max_extensions`` times, with the first
    window's points per axis (so the cells grow) unless ``max_points`` allows more (the first
    window's cell size, up to that bound).

    Examples
    --------
    >>> Growth(2).max_extensions, Growth().max_points is None
    (2, True)
    """

    max_extensions: int = 3
    max_points: int | None = None

    def __post_init__(self):
        n = self.max_extensions
        if isinstance(n, bool) or not (int(n) == n and n >= 0):
            raise ValueError(f"max_extensions must be an integer >= 0, got {n!r}")
        object.__setattr__(self, "max_extensions", int(n))


# ----------------------------------------------------------------------------------------
# the metric and the catalogue of cycles
# ----------------------------------------------------------------------------------------
class Metric:
    """Distances between section points of a basin: differences with the phase wrapped
    (:meth:`~hybridpd.analysis.maps.PoincareMap.wrap`), the squared Euclidean distance, the
    scale of a tail (``max(1, |s|)`` over the coordinates but the phase) and a cycle's
    canonical order (phase reduced to ``[0, T)``, starting at its smallest first coordinate).
    A map with another metric (the impact pair's criterion) subclasses it.
    """

    def __init__(self, P: PoincareMap):
        self.P = P
        self.T = P.period

    def wrap(self, ds) -> np.ndarray:
        """Differences with the phase wrapped."""
        return self.P.wrap(ds)

    def distance2(self, a, b) -> np.ndarray:
        """Squared distance of points ``a`` and ``b`` (broadcast over leading axes)."""
        d = self.wrap(np.asarray(a, float) - np.asarray(b, float))
        return np.einsum("...i,...i->...", d, d)

    def scale(self, tails) -> np.ndarray:
        """``max(1, |s|)`` of each tail of shape ``(M, K, dim)`` (the phase left out)."""
        off = 0 if self.T is None else 1
        return np.maximum(1.0, np.nanmax(np.abs(tails[:, :, off:]), axis=(1, 2)))

    def canonical(self, orbit) -> np.ndarray:
        """A cycle's points, phase in ``[0, T)``, from its smallest first coordinate."""
        pts = np.array(orbit, float, copy=True)
        if self.T is not None:
            pts[:, 0] %= self.T
        return np.roll(pts, -int(np.argmin(pts[:, 0])), axis=0)


class Catalogue:
    """Periodic attractors found in tails of trajectories, with integer labels.

    A tail holds iterates ``n, ..., n + K`` of ``P^k`` from one point. It belongs to a known
    cycle when each of its iterates lies within ``criterion`` (squared distance of
    ``metric``) of a point of the cycle. Of the others, the smallest period ``p <=
    max_period`` with which a tail repeats to ``detect_tol`` (relative, the phase wrapped:
    :func:`~hybridpd.analysis.maps.detect_period`) triggers Newton on ``P^(p k)``
    (:func:`~hybridpd.analysis.periodic.find_orbit`, at most ``max_newton`` solves per call);
    a new cycle is kept if the tail lies on it and it is no known one up to a cyclic shift.
    Label 0 is ``orbit`` (an :class:`~hybridpd.analysis.basins.Attractor` as given, or a
    point refined by Newton); others get ``1, 2, ...`` as found.

    Parameters
    ----------
    P : PoincareMap
    metric : Metric, optional
        Default ``Metric(P)``.
    period : int
        ``k``: the tails are iterates of ``P^k``.
    max_period : int
        Largest period searched, in ``[1, 64]``.
    criterion : float
        Squared distance within which a tail iterate is on a cycle.
    detect_tol : float
        Relative repeat tolerance of the period test (a trigger: Newton decides).
    max_newton : int
        Newton solves per :meth:`assign`.
    orbit : Attractor or array_like, optional
        Label 0.
    orbit_name, orbit_kind : str
        Label 0's name and kind when ``orbit`` is a point.

    Examples
    --------
    >>> import hybridpd as hp
    >>> class Logistic(hp.PoincareMap):
    ...     names = ("x",)
    ...     def apply(self, s, k=1, jacobian=False):
    ...         x = np.asarray(s, float)
    ...         for _ in range(k):
    ...             x = 3.2 * x * (1 - x)
    ...         return hp.MapResult(x)
    >>> P = Logistic()
    >>> cat = Catalogue(P, max_period=4)
    >>> cat.assign(P.iterate([0.3], 300)[None, -cat.tail_length:]).tolist()
    [0]
    >>> cat.attractors[0].name, cat.attractors[0].period
    ('period-2 orbit', 2)
    """

    def __init__(self, P: PoincareMap, metric: Metric | None = None, *, period: int = 1,
                 max_period: int = 8, criterion: float = 1e-3, detect_tol: float = 1e-4,
                 max_newton: int = 12, orbit=None, orbit_name: str = "",
                 orbit_kind: str = "periodic"):
        if not (int(max_period) == max_period and 1 <= max_period <= 64):
            raise ValueError(f"max_period must be an integer in [1, 64], got {max_period!r}")
        self.criterion = check_positive("criterion", criterion)
        self.detect_tol = check_positive("detect_tol", detect_tol)
        self.P, self.k = P, check_returns(period)
        self.metric = metric or Metric(P)
        self.max_period, self.max_newton = int(max_period), int(max_newton)
        self.orbit_name = orbit_name or f"period-{self.k} orbit"
        self.orbit_kind = orbit_kind
        self.attractors: list = []
        self._given = orbit is not None
        if isinstance(orbit, Attractor):
            self.attractors.append(orbit)
        elif orbit is not None:
            s = P.check_point(orbit)
            self.attractors.append(self._refine(s, 1, 0, orbit=True) or Attractor(
                0, self.orbit_name, 1, s.reshape(1, -1), kind=orbit_kind))

    @property
    def tail_length(self) -> int:
        """Iterates per tail needed to see ``max_period`` repeat twice: ``max_period + 2``."""
        return self.max_period + 2

    def _name(self, p: int, label: int, orbit: bool) -> str:
        if orbit:
            return self.orbit_name
        same = [a for a in self.attractors if a.period == p and self._found(a)]
        return f"period-{p} orbit" + (f" {chr(ord('A') + len(same))}" if same else "")

    def _refine(self, s0, p: int, label: int, orbit: bool = False) -> Attractor | None:
        """The cycle of period ``p`` (of ``P^k``) through ``s0`` by Newton, or None; the given
        ``orbit`` (label 0) only where it is a fixed point of ``P^k``."""
        try:
            orb = find_orbit(self.P, s0, period=p * self.k, tol=1e-12)
        except (ValueError, RuntimeError, np.linalg.LinAlgError):
            return None
        if not orb.converged:
            return None
        d = int(orb.quantities.get("minimal_period") or minimal_period(self.P, orb.s, p * self.k))
        kmin = d // self.k if d % self.k == 0 else p
        if orbit and kmin != 1:
            return None
        # the orbit's points s, P(s), ..., P^(pk-1)(s) (the map's own where it records them)
        along = orb.quantities.get("orbit")
        if along is None:
            along = self.P.iterate(orb.s, p * self.k - 1)
        pts = self.metric.canonical(along[:kmin * self.k:self.k])
        if kmin != p:   # landed on a cycle of smaller period: its own multipliers
            return self._refine(pts[0], kmin, label, orbit)
        walls = tuple(orb.quantities.get("walls", ()))
        if walls:
            first = np.asarray(along)[:, 0]
            shift = int(np.argmin(first % self.metric.T if self.metric.T else first))
            walls = tuple(walls[shift:]) + tuple(walls[:shift])
        return Attractor(label, self._name(p, label, orbit), p, pts, orb.multipliers,
                         float(orb.spectral_radius), orb.stable,
                         self.orbit_kind if orbit else "periodic", walls,
                         float(orb.residual))

    def _found(self, a: Attractor) -> bool:
        """An attractor found in the tails (not the given orbit)."""
        return a.label > 0 or not self._given

    def _add(self, att: Attractor) -> None:
        same = [i for i, a in enumerate(self.attractors)
                if self._found(a) and a.period == att.period]
        if len(same) == 1:   # a second cycle of this period: the first becomes "A"
            first = self.attractors[same[0]]
            self.attractors[same[0]] = replace(first, name=f"{first.name} A")
        self.attractors.append(att)

    def _known(self, att: Attractor) -> Attractor | None:
        """An attractor already catalogued with the same cycle (up to a cyclic shift)."""
        for a in self.attractors:
            if a.period != att.period:
                continue
            d2 = self.metric.distance2(a.points[:, None, :], att.points[None, :, :])
            if d2.min() <= 1e-12 * (1.0 + float(np.abs(att.points).max()) ** 2):
                return a
        return None

    def _match(self, tails: np.ndarray, att: Attractor) -> np.ndarray:
        # the first iterate rules most tails out; the whole tail only for the rest
        dist = self.metric.distance2
        ok = dist(tails[:, 0, None, :], att.points[None, :, :]).min(axis=1) < self.criterion
        idx = np.flatnonzero(ok)
        d2 = dist(tails[idx, :, None, :], att.points[None, None, :, :])
        ok[idx] = np.all(d2.min(axis=2) < self.criterion, axis=1)
        return ok

    def assign(self, tails) -> np.ndarray:
        """Labels of tails of shape ``(M, K + 1, dim)`` (rows with NaN: on no cycle): an
        attractor's, or ``NO_CONVERGENCE``; new cycles are added to :attr:`attractors`."""
        tails = np.asarray(tails, float)
        if tails.ndim != 3 or tails.shape[2] != self.P.dim:
            raise ValueError(f"tails must have shape (M, K + 1, {self.P.dim}), got "
                             f"{tails.shape}")
        lab = np.full(tails.shape[0], NO_CONVERGENCE, dtype=np.int64)
        finite = np.all(np.isfinite(tails), axis=(1, 2))
        for a in self.attractors:
            free = finite & (lab == NO_CONVERGENCE)
            lab[free] = np.where(self._match(tails[free], a), a.label, NO_CONVERGENCE)
        free = np.flatnonzero(finite & (lab == NO_CONVERGENCE))
        if free.size == 0:
            return lab
        # periods that repeat twice in a tail of K iterates: k <= K - 2
        per, err = detect_period(tails[free], self.metric.wrap,
                                 min(self.max_period, tails.shape[1] - 2), self.detect_tol,
                                 scale=self.metric.scale(tails[free]))
        tried = 0
        for j in np.argsort(err, kind="stable"):   # bounded: one pass over the tails
            i = free[j]
            if per[j] == 0 or tried >= self.max_newton:
                break
            if lab[i] != NO_CONVERGENCE:
                continue
            tried += 1
            att = self._refine(tails[i, -1], int(per[j]), len(self.attractors))
            # keep a new cycle only if the tail that led to it lies on it
            if (att is None or self._known(att) is not None
                    or not self._match(tails[i:i + 1], att)[0]):
                continue
            self._add(att)
            rest = free[lab[free] == NO_CONVERGENCE]
            lab[rest] = np.where(self._match(tails[rest], att), att.label, NO_CONVERGENCE)
        return lab


# ----------------------------------------------------------------------------------------
# the mapper protocol
# ----------------------------------------------------------------------------------------
class Mapper(abc.ABC):
    """An initial condition on a section -> a label (:data:`~hybridpd.analysis.labels.LABELS`).

    A subclass gives :meth:`labels` and the attributes below; every other hook a basin uses
    has a default here.

    Attributes
    ----------
    map : PoincareMap
    fixed_point : ndarray, shape (dim,)
        A point of the orbit of label 0.
    period : int
        ``k``: the mapper iterates ``P^k``.
    n_iter : int
        Iterations of ``P^k`` per point.
    criterion : float
        Squared distance to the orbit below which a point has converged.
    escape : float
        Bound on the coordinates beyond which a trajectory diverged.
    orbit : Attractor or None
        Label 0 as an attractor, when known (else the catalogue refines ``fixed_point``).
    """

    map: PoincareMap
    fixed_point: np.ndarray
    period: int = 1
    n_iter: int = 1500
    criterion: float = 1e-3
    escape: float = 1e3
    orbit: Attractor | None = None
    cert_r2: np.ndarray = np.zeros(1)
    #: Kind of label 0 (:attr:`~hybridpd.analysis.basins.Attractor.kind`).
    orbit_kind: str = "periodic"

    @abc.abstractmethod
    def labels(self, S) -> tuple[np.ndarray, np.ndarray]:
        """Labels and iterations run of section points ``S`` of shape ``(N, dim)``."""

    @property
    def orbit_name(self) -> str:
        """Label 0's name as an attractor."""
        return f"period-{self.period} orbit"

    @property
    def converged_name(self) -> str:
        """Label 0's name in a basin without attractor search."""
        return self.orbit_name

    def slice(self, x, y, axes=None) -> Slice:
        """The grid ``x`` times ``y`` over ``axes`` (default the map's first two
        coordinates), the others at :attr:`fixed_point` (:func:`grid_slice`)."""
        return grid_slice(self.map, x, y, axes, self.fixed_point)

    def admissible(self, S) -> np.ndarray:
        """Which points of ``S`` may be iterated (the others are ``inadmissible``)."""
        return np.ones(len(S), bool)

    def label_tails(self, S, tail: int = 0) -> dict:
        """``{"label", "iterations"}`` of ``S`` and, ``tail > 0``, ``"tail"``: iterates
        ``n_iter .. n_iter + tail`` of the points that did not converge (NaN elsewhere)."""
        lab, its = self.labels(S)
        out = {"label": np.asarray(lab, np.int64), "iterations": np.asarray(its, np.int64)}
        if tail:
            tails = np.full((len(S), tail + 1, self.map.dim), np.nan)
            nc = np.flatnonzero(out["label"] == 1)
            if nc.size:
                tails[nc] = self.map.iterate_many(S[nc], int(self.n_iter) + tail, self.period,
                                                  tail + 1)[0]
            out["tail"] = tails
        return out

    def spec(self):
        """A picklable description of the mapper, without compiled objects, rebuilt in
        worker processes: ``spec.label_tails(S, tail)`` is :meth:`label_tails`."""
        return PickledMapper.of(self)

    def metric(self) -> Metric:
        """The metric of the catalogue (:class:`Metric`)."""
        return Metric(self.map)

    def catalogue(self, max_period: int, tol: float | None = None) -> Catalogue:
        """The attractor catalogue, label 0 this mapper's orbit (``tol``: the period
        test's relative tolerance, default the catalogue's)."""
        opts = {} if tol is None else {"detect_tol": tol}
        return Catalogue(self.map, self.metric(), period=self.period,
                         max_period=max(int(max_period), 1), criterion=self.criterion,
                         orbit=self.fixed_point if self.orbit is None else self.orbit,
                         orbit_name=self.orbit_name, orbit_kind=self.orbit_kind, **opts)

    def metadata(self) -> dict:
        """What a basin's metadata records of the mapper."""
        return {"certified_radius": self.certified_radius, "period": self.period}

    @staticmethod
    def label_name(label: int) -> str:
        """Name of an integer label."""
        return LABELS[int(label)]

    @property
    def certified_radius(self) -> float:
        """Radius (``Q``-norm) of the early-exit ball at the fixed point (0 without)."""
        return math.sqrt(float(np.ravel(self.cert_r2)[0]))

    def __call__(self, s) -> int:
        """Label of one section point."""
        return int(self.labels(np.asarray(s, float).reshape(1, -1))[0][0])


@dataclass(frozen=True, eq=False)
class PickledMapper:
    """A mapper as bytes (a sweep records its arguments by digest and ships them to the
    worker processes)."""

    blob: np.ndarray

    @classmethod
    def of(cls, m: Mapper) -> PickledMapper:
        return cls(np.frombuffer(pickle.dumps(m), dtype=np.uint8))

    def label_tails(self, S, tail: int = 0) -> dict:
        return pickle.loads(self.blob.tobytes()).label_tails(S, tail)


class Labeller(abc.ABC):
    """What a map adds to :class:`MapMapper`: how it labels many points at once and what
    only it has (its slice, metric, names and metadata). A map returns one from its
    :meth:`~hybridpd.analysis.maps.PoincareMap.labeller` hook.

    :meth:`run` labels points under a :class:`~hybridpd.analysis.periodic.LabelSpec`;
    :meth:`certify` gives the early-exit ball at one cycle point.
    """

    #: Label 0's name as an attractor, and in a basin without search (None: the defaults).
    orbit_name: str | None = None
    converged_name: str | None = None
    orbit_kind: str = "periodic"

    def __init__(self, P: PoincareMap):
        self.map = P

    @abc.abstractmethod
    def run(self, S, spec: LabelSpec) -> tuple:
        """``(labels, iterations, last iterates)`` of section points ``S``."""

    def certify(self, m: MapMapper, fp) -> tuple:
        """``(Q, r2)`` of the early-exit ball at cycle point ``fp`` (``r2 = 0``: none)."""
        P = self.map
        try:
            DP = P.jacobian(fp, m.period)
        except RuntimeError:
            return np.eye(P.dim), 0.0
        one = replace_spec(m.spec_of(), FP=fp[None], n_iter=1, QS=np.eye(P.dim)[None],
                           R2=np.zeros(1))

        def images(pts):
            lab, _, img = self.run(pts, one)
            return img, (lab != OFF_SECTION) & np.all(np.isfinite(img), axis=1)

        return certify_ball(DP, fp, m.criterion, images, P.wrap)

    def criterion_matrix(self) -> np.ndarray:
        """``C``: the criterion's coordinates of a deviation ``d`` are ``C d``."""
        return np.eye(self.map.dim)

    def slice(self, m: MapMapper, x, y, axes) -> Slice:
        return grid_slice(self.map, x, y, axes, m.fixed_point)

    def label_tails(self, m: MapMapper, S, tail: int) -> dict:
        return Mapper.label_tails(m, S, tail)

    def admissible(self, S) -> np.ndarray:
        return np.ones(len(S), bool)

    def metric(self) -> Metric:
        return Metric(self.map)

    def metadata(self, m: MapMapper) -> dict:
        return {"certified_radius": m.certified_radius, "period": m.period}

    def spec(self, m: MapMapper):
        return PickledMapper.of(m)


def replace_spec(spec: LabelSpec, **fields) -> LabelSpec:
    """``spec`` with ``fields`` replaced (contiguous arrays, as the kernels take them)."""
    return spec._replace(**{k: np.ascontiguousarray(v) if isinstance(v, np.ndarray) else v
                            for k, v in fields.items()})


class MapMapper(Mapper):
    """The mapper of any map (module docstring): labels by the map's
    :meth:`~hybridpd.analysis.maps.PoincareMap.labeller`, the compiled section kernel of a
    section map, or the map's own iterations.

    Labels: ``converged`` when, after ``n_iter`` iterations of ``P^k``, the squared distance
    (the labeller's criterion coordinates, phase wrapped) to a cycle point is below
    ``criterion`` (the ``k`` points ``P^j(fixed_point)`` are all fixed points of ``P^k``);
    ``diverged`` (non-finite, beyond ``escape``, no further return); ``zeno_sticking``;
    ``unresolved`` (a jump or step bound); ``off_section`` (not a point of the section).

    Parameters
    ----------
    P : PoincareMap
    fixed_point : array_like, shape (dim,)
    period : int
        ``k``: the mapper iterates ``P^k``.
    n_iter : int
    criterion : float
    early_exit : bool
        The certified contraction ball (and, where the labeller has it, the cycle test).
    escape : float
        Bound on ``|s_i|`` (the phase excepted where the labeller says).
    orbit : Attractor, optional
        Label 0 as an attractor when it is known (its name and multipliers in the basin).
    metadata : dict, optional
        More entries of a basin's metadata (e.g. the conventions of the orbit).

    Examples
    --------
    >>> import hybridpd as hp
    >>> from hybridpd.pair.section import impact_pair_section
    >>> orb = hp.symmetric_orbit(hp.ImpactPair(0.1, 0.5, 0.75), hp.PDGains(10, 20), 5.0)
    >>> m = mapper(hp.SectionMap(impact_pair_section(orb.system())), orb.fixed_point)
    >>> m.label_name(m(orb.fixed_point + [0, 0.01, 0, 0]))
    'converged'
    """

    def __init__(self, P: PoincareMap, fixed_point, *, period: int = 1, n_iter: int = 1500,
                 criterion: float = 1e-3, early_exit: bool = True, escape: float = 1e3,
                 orbit: Attractor | None = None, metadata: dict | None = None):
        if not isinstance(P, PoincareMap):
            raise ValueError(f"P must be a PoincareMap, got {type(P).__name__}")
        self.map = P
        lab = P.labeller()
        if lab is None:
            # the section kernel lives above the section map's module (it calls its run
            # kernel), so the section maps cannot return it from their hook without a cycle
            lab = (SectionLabeller(P) if isinstance(P, (SectionMap, StroboscopicMap))
                   else IterateLabeller(P))
        self.labeller = lab
        try:
            self.fixed_point = P.check_point(fixed_point).copy()
        except ValueError as exc:
            raise ValueError(f"fixed_point: {exc}") from None
        if isinstance(period, bool) or int(period) != period or period < 1:
            raise ValueError(f"period must be an int >= 1, got {period!r}")
        self.period = int(period)
        self.n_iter = check_int("n_iter", n_iter, 1)
        self.criterion = check_positive("criterion", criterion)
        self.escape = check_positive("escape", escape)
        self.early_exit = bool(early_exit)
        self.orbit = orbit
        self.extra = dict(metadata or {})
        # the cycle's points on the section: P^k fixes each of them (k returns per period)
        cyc = P.iterate(self.fixed_point, self.period - 1) if self.period > 1 \
            else self.fixed_point[None]
        self.cycle = np.ascontiguousarray(cyc[:_n_finite(cyc)])
        K = len(cyc)
        self.cert_Q = np.tile(np.eye(P.dim), (K, 1, 1))
        self.cert_r2 = np.zeros(K)
        if self.early_exit:
            for c in range(K):
                self.cert_Q[c], self.cert_r2[c] = lab.certify(self, self.cycle[c])

    def spec_of(self) -> LabelSpec:
        """The labelling's options by name (:class:`~hybridpd.analysis.periodic.LabelSpec`)."""
        # the kernels' types: float and int scalars, contiguous float arrays
        return LabelSpec(np.ascontiguousarray(self.labeller.criterion_matrix(), float),
                         float(self.map.period or 0.0), np.ascontiguousarray(self.cycle, float),
                         int(self.period), int(self.n_iter), float(self.criterion),
                         np.ascontiguousarray(self.cert_Q, float),
                         np.ascontiguousarray(self.cert_r2, float), float(self.escape),
                         1e-12 if self.early_exit else 0.0)

    def labels(self, S) -> tuple:
        """Labels and iterations run of section points ``S`` of shape ``(N, dim)``."""
        lab, its, _ = self.labeller.run(S, self.spec_of())
        return lab, its

    @property
    def orbit_name(self) -> str:
        return self.labeller.orbit_name or f"period-{self.period} orbit"

    @property
    def converged_name(self) -> str:
        return self.labeller.converged_name or self.orbit_name

    @property
    def orbit_kind(self) -> str:
        return self.labeller.orbit_kind

    def slice(self, x, y, axes=None) -> Slice:
        return self.labeller.slice(self, x, y, axes)

    def admissible(self, S) -> np.ndarray:
        return self.labeller.admissible(S)

    def label_tails(self, S, tail: int = 0) -> dict:
        return self.labeller.label_tails(self, S, tail)

    def spec(self):
        return self.labeller.spec(self)

    def metric(self) -> Metric:
        return self.labeller.metric()

    def metadata(self) -> dict:
        return {**self.labeller.metadata(self), **self.extra}


def mapper(P: PoincareMap, fixed_point, *, period: int = 1, n_iter: int = 1500,
           criterion: float = 1e-3, early_exit: bool = True, escape: float = 1e3,
           orbit: Attractor | None = None, metadata: dict | None = None) -> Mapper:
    """The mapper of map ``P`` about the orbit through ``fixed_point`` (:class:`MapMapper`).

    Examples
    --------
    >>> import hybridpd as hp
    >>> orb = hp.symmetric_orbit(hp.ImpactPair(0.1, 0.5, 0.75), hp.PDGains(10, 20), 5.0)
    >>> from hybridpd.pair.impactmap import ImpactMap
    >>> m = hp.mapper(ImpactMap(orb.pair, orb.gains, orb.reference()), orb.fixed_point)
    >>> m.label_name(m(orb.fixed_point + [0, 0.01, 0, 0])), m.orbit_kind
    ('converged', 'symmetric')
    """
    return MapMapper(P, fixed_point, period=period, n_iter=n_iter, criterion=criterion,
                     early_exit=early_exit, escape=escape, orbit=orbit, metadata=metadata)


# ----------------------------------------------------------------------------------------
# labellers: a section map's compiled kernel, any map's own iterations
# ----------------------------------------------------------------------------------------
class SectionLabeller(Labeller):
    """Labels on a section of any automaton: one compiled loop
    (:func:`~hybridpd.analysis.periodic._label_kernel`) for a :class:`SectionMap`, the
    map's own applications for a :class:`StroboscopicMap` (and for runs the kernel hands to
    the section's resolver). Slices over section coordinates (one the section fixes is
    refused by name); states outside the admissible set are never iterated."""

    def criterion_matrix(self) -> np.ndarray:
        return np.ascontiguousarray(self.map.section.C)

    def slice(self, m: MapMapper, x, y, axes) -> Slice:
        sec = self.map.section
        return grid_slice(self.map, x, y, axes, m.fixed_point,
                          refuse=lambda a: off_section_axis("axes", a, sec))

    def admissible(self, S) -> np.ndarray:
        sec = self.map.section
        if not sec.bounds:
            return np.ones(len(S), bool)
        return np.array([not sec.violations(sec.to_state(p)[0]) for p in S], bool)

    def metadata(self, m: MapMapper) -> dict:
        # "inadmissible": the basin counts the points outside the admissible set
        return {"certified_radius": m.certified_radius, "period": m.period, "inadmissible": 0}

    def run(self, S, spec: LabelSpec) -> tuple:
        P = self.map
        sec = P.section
        S = np.asarray(S, float).reshape(-1, P.dim)
        N = S.shape[0]
        n = sec.automaton.n_states
        lab = np.full(N, OFF_SECTION, np.int64)
        its = np.zeros(N, np.int64)
        out = np.full((N, P.dim), np.nan)
        W0 = np.zeros((N, n + 1))
        T0 = np.zeros(N)
        valid = np.zeros(N, bool)
        for i in range(N):
            if not np.all(np.isfinite(S[i])):
                continue
            z, t = sec.to_state(S[i])
            if sec.fires(z) > 0:
                W0[i, :n], W0[i, n], T0[i], valid[i] = z, 1.0, t, True
        if np.any(valid):
            lab[valid], its[valid], out[valid] = self._label(
                np.ascontiguousarray(W0[valid]), T0[valid], spec)
        return lab, its, out

    def _label(self, W0, T0, spec: LabelSpec):
        """Labels, iterations and last section points of the valid start states ``W0``.

        Modes on demand: where a point's run enters a mode not built yet, the kernel hands
        back; the mode is built and the labelling resumes at that point's iterate (each
        mode is built once, so this repeats at most ``max_modes`` times).
        """
        P = self.map
        sec = P.section
        N = W0.shape[0]
        lab = np.empty(N, np.int64)
        its = np.zeros(N, np.int64)
        sub = np.full((N, P.dim), np.nan)
        if not isinstance(P, SectionMap):
            # a map without compiled labeller (the stroboscopic map): its own applications,
            # under the same rules; each step counts an iteration, so n_iter bounds the loop
            for p in range(N):
                while not self._resolved_step(p, W0, T0, its, lab, sub, spec):
                    pass
            return lab, its, sub
        bufs = P._buffers()
        pts = LabelPoints(W0, T0, sub, lab, its)
        p = 0
        while p < N:   # bounded: each pass labels a point or builds one of max_modes modes
            p, code = _label_kernel(P._return_run(spec.period), spec, pts, p,
                                    sec.resolver is not None, bufs)
            if p < N and code == _TO_RESOLVER:
                if self._resolved_step(p, W0, T0, its, lab, sub, spec):
                    p += 1
            elif p < N and not P._complete(bufs.ic):
                lab[p] = _UNRESOLVED        # its run needs a mode beyond the tables' bound
                its[p] += 1
                p += 1
        return lab, its, sub

    def _resolved_step(self, p, W0, T0, its, lab, sub, spec: LabelSpec) -> bool:
        """One application of ``P^k`` to point ``p``'s iterate by the map's own ``apply``
        (the compiled run stopped at contacts refiring at one instant: ``apply`` hands it to
        the section's resolver, as a simulation does). Labels ``p`` and returns True where
        this ends its run (the same rules as the compiled labeller); otherwise leaves the
        image as its iterate for the compiled labeller to resume."""
        P = self.map
        sec = P.section
        n = sec.automaton.n_states
        its[p] += 1
        try:
            # apply repeats the compiled run that stopped (a tenth of the resolver's cost on
            # the arm), so that the labeller follows the map's one rule for joint jumps
            r = P.apply(sec.from_state(W0[p, :n], float(T0[p])), spec.period)
        except ValueError:            # the iterate is no longer a point of the section
            lab[p] = _UNRESOLVED
            return True
        if not r.ok:
            lab[p] = {"zeno": _ZENO_STICKING, "nonfinite": _DIVERGED,
                      "diverged": _DIVERGED}.get(r.status, _UNRESOLVED)
            if r.status == "end_time":
                lab[p] = _ZENO_STICKING if r.mode_final != sec.mode else _DIVERGED
            return True
        sub[p] = r.s
        targets = spec.FP
        dist = [_dist(r.s, targets[c], spec.T, spec.QS[c]) for c in range(len(targets))]
        if not np.all(np.abs(r.s) <= spec.escape):
            lab[p] = _DIVERGED
        elif any(q < spec.R2[c] for c, (q, _e) in enumerate(dist)):
            lab[p] = _CONVERGED
        elif its[p] >= spec.n_iter:
            lab[p] = _CONVERGED if min(e for _q, e in dist) < spec.criterion \
                else _NOT_CONVERGED
        else:
            W0[p, :n], W0[p, n], T0[p] = r.z_hit, 1.0, r.t_hit
            return False
        return True


class IterateLabeller(Labeller):
    """Labels of any map by its own iterations
    (:meth:`~hybridpd.analysis.maps.PoincareMap.iterate_many`), without early exits: the
    criterion is read at iterate ``n_iter``."""

    def run(self, S, spec: LabelSpec) -> tuple:
        P = self.map
        S = np.asarray(S, float).reshape(-1, P.dim)
        tails, status, its = P.iterate_many(S, int(spec.n_iter), spec.period, 1)
        last = tails[:, -1]
        lab = np.full(len(S), _NOT_CONVERGED, np.int64)
        for i, st in enumerate(status):
            if st:
                lab[i] = {"off_section": OFF_SECTION, "nonfinite": _DIVERGED,
                          "sticking": _ZENO_STICKING}.get(st, _UNRESOLVED)
            elif not np.all(np.abs(last[i]) <= spec.escape):
                lab[i] = _DIVERGED
            else:
                d = P.wrap(last[i][None, :] - spec.FP)
                if np.min(np.einsum("ij,ij->i", d, d)) < spec.criterion:
                    lab[i] = _CONVERGED
        return lab, np.asarray(its, np.int64), last
