"""Basins of attraction of any map, labelled by the attractor each point reaches.

A basin is a thin layer over one question asked of every point of a 2-D slice: where does
iterating the map take it? (Attractors.jl's "initial condition -> label" mapper.) Every grid
point is iterated ``n_iter`` times (:meth:`~hybridpd.analysis.maps.PoincareMap.iterate_many`,
which a map may compile); its tail is then either periodic, of period ``k <= max_period``
(:func:`~hybridpd.analysis.maps.detect_period`), and its cycle is matched against the
attractors found so far (a new one is refined by Newton on ``P^k``,
:func:`~hybridpd.analysis.periodic.find_orbit`, and named by its period and stability), or
one of the outcomes :data:`OUTCOMES`: no convergence within the iterations, divergence
(non-finite, or beyond ``escape``), sticking, the map stopped for another reason
(``unresolved``, its status kept), a start off the map's domain, or (slices of a section with
an admissible set) an inadmissible start. Labels ``0, 1, ...`` are the attractors in the order found; outcomes are
negative.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.analysis.maps import PoincareMap, check_returns, detect_period
from hybridpd.analysis.periodic import find_orbit
from hybridpd.model import check_axis

__all__ = ["DIVERGED", "INADMISSIBLE_LABEL", "NO_CONVERGENCE", "OFF_SECTION_LABEL", "OUTCOMES",
           "STICKING", "UNRESOLVED", "Attractor", "BasinResult", "basin_of_attraction"]

NO_CONVERGENCE = -1
DIVERGED = -2
STICKING = -3
UNRESOLVED = -4
OFF_SECTION_LABEL = -5
INADMISSIBLE_LABEL = -6

#: Negative labels, what a point that reaches no periodic attractor does: ``(kind, name)``.
OUTCOMES = {
    NO_CONVERGENCE: ("no_convergence", "no convergence"),
    DIVERGED: ("diverged", "diverged"),
    STICKING: ("sticking", "sticking"),
    UNRESOLVED: ("unresolved", "unresolved flight"),
    OFF_SECTION_LABEL: ("off_section", "off the section"),
    INADMISSIBLE_LABEL: ("inadmissible", "inadmissible (a gap beyond its bounds)")}


@dataclass(frozen=True, eq=False)
class Attractor:
    """A periodic attractor of a basin (or an outcome, ``label < 0``).

    Attributes
    ----------
    label : int
    name : str
    period : int
        ``k`` (0 for an outcome).
    points : ndarray, shape (k, dim)
        Its cycle's points (Newton-refined), the one with the smallest first coordinate
        first.
    multipliers : ndarray
        Of ``DP^k``.
    spectral_radius : float
    stable : bool
    """

    label: int
    name: str
    period: int = 0
    points: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)), repr=False)
    multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    spectral_radius: float = math.nan
    stable: bool = False
    __repr__ = compact_repr

    @property
    def periodic(self) -> bool:
        """A periodic orbit (not an outcome)."""
        return self.period > 0


@dataclass(frozen=True, eq=False)
class BasinResult:
    """Labels of a 2-D slice (module docstring).

    Attributes
    ----------
    x, y : ndarray
        Grid axes (values of the coordinates ``axes``).
    labels : ndarray of int, shape (len(y), len(x))
    attractors : tuple of Attractor
        The attractors and the outcomes present.
    iterations : ndarray of int, shape (len(y), len(x))
        Iterations run per point.
    axes : tuple of str
        Names of the two coordinates of the grid.
    base : ndarray, shape (dim,)
        The point whose other coordinates the slice holds.
    metadata : dict
    """

    x: np.ndarray
    y: np.ndarray
    labels: np.ndarray
    attractors: tuple
    iterations: np.ndarray = field(repr=False)
    axes: tuple = ()
    base: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    metadata: dict = field(default_factory=dict, repr=False)
    __repr__ = compact_repr

    def fraction(self, label: int) -> float:
        """Share of the grid with ``label``."""
        return float(np.mean(self.labels == label))

    def attractor(self, label: int) -> Attractor:
        """The attractor (or outcome) with ``label``."""
        for a in self.attractors:
            if a.label == label:
                return a
        raise ValueError(f"no attractor with label {label}; labels are "
                         f"{[a.label for a in self.attractors]}")


class _Catalogue:
    """The attractors found so far, matched by their cycle points."""

    def __init__(self, P, k, tol, max_period):
        self.P, self.k, self.tol, self.max_period = P, k, tol, max_period
        self.found = []

    def label(self, tail) -> int:
        p = detect_period(tail, self.P.wrap, self.max_period, self.tol)
        if not p:
            return -1
        cycle = tail[-p:]
        for a in self.found:
            if a.period == p and self._on(cycle[-1], a.points):
                return a.label
        return self._add(cycle, p)

    def _on(self, s, points) -> bool:
        d = np.max(np.abs(self.P.wrap(points - s)), axis=1)
        return bool(np.min(d) <= 1e3 * self.tol * max(1.0, float(np.max(np.abs(s)))))

    def _add(self, cycle, p) -> int:
        po = find_orbit(self.P, cycle[-1], p * self.k, max_iter=30)
        pts = cycle if not po.converged else self.P.iterate(po.s, p - 1, self.k)
        pts = pts[np.argsort(pts[:, 0])]
        label = len(self.found)
        stab = "stable" if po.converged and po.stable else "unstable"
        name = f"period-{p} orbit ({stab})" if po.converged else f"period-{p} cycle"
        self.found.append(Attractor(label, name, p, pts, po.multipliers,
                                    po.spectral_radius, bool(po.converged and po.stable)))
        return label


def _grid(P, x, y, axes, base):
    names = P.names
    if axes is None:
        axes = names[:2]
    if len(axes) != 2:
        raise ValueError(f"axes must name two coordinates of {names}, got {axes!r}")
    idx = []
    for a in axes:
        if isinstance(a, str):
            if a not in names:
                raise ValueError(f"axes: {a!r} is no coordinate; they are {list(names)}")
            idx.append(names.index(a))
        elif isinstance(a, (int, np.integer)) and 0 <= int(a) < P.dim:
            idx.append(int(a))
        else:
            raise ValueError(f"axes: {a!r} must be a coordinate name or index")
    if idx[0] == idx[1]:
        raise ValueError("axes must be two different coordinates")
    if base is None:
        if P.dim > 2:
            raise ValueError(f"base: give the point whose other coordinates the slice holds "
                             f"(the map has {P.dim} coordinates)")
        base = np.zeros(P.dim)
    base = P.check_point(base).copy()
    xs, ys = check_axis("x", x), check_axis("y", y)
    X, Y = np.meshgrid(xs, ys)
    S = np.tile(base, (X.size, 1))
    S[:, idx[0]], S[:, idx[1]] = X.ravel(), Y.ravel()
    return xs, ys, S, tuple(names[i] for i in idx), base


def basin_of_attraction(P: PoincareMap, x, y, *, axes=None, base=None, period: int = 1,
                        n_iter: int = 500, max_period: int = 8, tol: float = 1e-6,
                        escape: float = 1e6) -> BasinResult:
    """Label a 2-D slice of a map's section by the attractor each point reaches.

    Parameters
    ----------
    P : PoincareMap
    x, y : (min, max, num)
        The grid of the two coordinates ``axes``.
    axes : (str or int, str or int), optional
        The coordinates the grid spans (default the first two).
    base : array_like, shape (dim,), optional
        The other coordinates (required when the map has more than two).
    period : int
        ``k``: iterate ``P^k``.
    n_iter : int
        Iterations per point.
    max_period : int
        Largest period of an attractor (in applications of ``P^k``).
    tol : float
        Relative tolerance of the period test.
    escape : float
        Bound on the coordinates (the phase excepted): diverged beyond.

    Returns
    -------
    BasinResult

    Examples
    --------
    A contraction toward the origin: every point reaches it.

    >>> import hybridpd as hp
    >>> class Half(hp.PoincareMap):
    ...     names = ("x", "y")
    ...     def apply(self, s, k=1, jacobian=False):
    ...         return hp.MapResult(np.asarray(s, float) * 0.5 ** k)
    >>> b = hp.basin_of_attraction(Half(), x=(-1, 1, 5), y=(-1, 1, 3), n_iter=80)
    >>> b.labels.tolist(), b.attractors[0].name
    ([[0, 0, 0, 0, 0], [0, 0, 0, 0, 0], [0, 0, 0, 0, 0]], 'period-1 orbit (stable)')
    """
    if not isinstance(P, PoincareMap):
        raise ValueError(f"P must be a PoincareMap, got {type(P).__name__}")
    k = check_returns(period)
    n_iter, max_period = int(n_iter), int(max_period)
    if n_iter < 4 * max_period or max_period < 1:
        raise ValueError(f"n_iter must be >= 4 max_period (got {n_iter}, {max_period})")
    xs, ys, S, names, base = _grid(P, x, y, axes, base)
    tail = 2 * max_period + 1
    tails, status, its = P.iterate_many(S, n_iter, k, tail)
    cat = _Catalogue(P, k, tol, max_period)
    lab = np.full(len(S), -1, np.int64)
    off = 1 if P.period is not None else 0
    for i in range(len(S)):
        st = status[i]
        if st:
            lab[i] = {"off_section": OFF_SECTION_LABEL, "nonfinite": DIVERGED,
                      "sticking": STICKING}.get(st, UNRESOLVED)
        elif np.any(np.abs(tails[i][:, off:]) > escape):
            lab[i] = DIVERGED
        else:
            lab[i] = cat.label(tails[i])
    stops = sorted({status[i] for i in range(len(S)) if lab[i] == UNRESOLVED})
    outcomes = tuple(Attractor(c, OUTCOMES[c][1] + (f" ({', '.join(stops)})"
                                                    if c == UNRESOLVED else ""))
                     for c in sorted(OUTCOMES, reverse=True) if np.any(lab == c))
    shape = (len(ys), len(xs))
    meta = {"n_iter": n_iter, "period": k, "max_period": max_period, "tol": float(tol)}
    return BasinResult(xs, ys, lab.reshape(shape), tuple(cat.found) + outcomes,
                       its.reshape(shape), names, base, meta)
