"""Certified (computer-assisted) classification of the impact pair's symmetric orbits.

A region map classifies grid *points*; this module proves statements about whole *boxes* of
parameters. For a feedback case, an odd order ``n`` and a box of ``(kp, kv, mu, e,
gamma = L/x10, omega, m2)`` (any of them an interval), one of

* ``proved_stable``: for every parameter in the box the simple symmetric orbit exists
  (conditions (13)-(17) solvable with ``xm > 0``), is viable (18) (``|x1 - x2| < L`` on the
  whole open flight between the two impacts) and every Floquet multiplier (eigenvalue of
  ``DP = DP43 DP32 DP21 DP10``) has modulus < 1;
* ``proved_unstable``: it exists, is viable, and some multiplier has modulus > 1;
* ``proved_no_orbit``: viability fails for every parameter in the box;
* ``undecided``: none of these could be proved (with the reason).

The proofs evaluate the paper's closed forms in outward-rounded interval arithmetic (see
:mod:`hybridpd.pair.proofs` for the three proofs, :mod:`hybridpd.pair.prooftree` for the
adaptive subdivision of undecided boxes and the record of what decided each part, and
:mod:`hybridpd.pair.intervals` for the arithmetic and the assumption made of the platform's
libm); every proved box is then confirmed in python-flint's ``arb``
(:mod:`hybridpd.pair.arbcheck`: existence and the inequality deciding its class) or written
undecided. A certified map can keep its proof as a certificate
(:mod:`hybridpd.pair.certificate`), re-proved in arb alone by
:func:`hybridpd.pair.certificate.verify_certificate`.
Point certificates (:func:`certify_orbit`) add python-flint ``arb`` enclosures of the
section point and of every multiplier's modulus. Region maps (:func:`certified_map`) give
each grid point the box half-way to its neighbours (see :func:`cell_edges`).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from hybridpd._results import Fields, compact_repr
from hybridpd.model import (
    Case,
    check_array,
    check_int,
    check_named_axis,
    check_odd_order,
    check_positive,
)
from hybridpd.pair import proofs
from hybridpd.pair.certified_orbit import OrbitCertificate, _ratio, certify_orbit

__all__ = ["FLAG_MEANINGS", "FLAG_VALUES", "MAP_AXES", "REASONS", "STOPS", "BoxCertificate",
           "CertifiedCells", "CertifiedMap", "OrbitCertificate", "auto_depth", "auto_parts",
           "cell_boxes", "cell_edges", "certified_map", "certify_box", "certify_cells",
           "certify_orbit", "class_shares", "resolve_depth", "resolve_parts"]

#: CF flag values of a certified map and their meanings (``flag_meanings`` is one string).
FLAG_VALUES = (0, 1, 2, 3)
FLAG_MEANINGS = " ".join(proofs.CLASSES)
#: Parameters a certified map can sweep (those of a region map).
MAP_AXES = ("kp", "kv", "mu", "L", "omega", "m2", "x10")
#: Reasons of a certified class: those of :data:`hybridpd.pair.proofs.REASONS` and, last, a
#: cell the interval layer proved but arb did not confirm (written undecided).
REASONS = tuple(proofs.REASONS) + (
    "undecided: proved in float intervals but not confirmed in arb",)
R_ARB = len(proofs.REASONS)

#: Why the subdivision of a cell stopped (:data:`hybridpd.pair.proofs.CELL_STOPS`).
STOPS = proofs.CELL_STOPS

_DOMAIN = {"e": (0.0, 1.0)}  # closed; every other parameter is > 0


def _interval_arg(name, value):
    """``(lo, hi)`` float arrays from a number, an array or a ``(lo, hi)`` pair."""
    if isinstance(value, tuple):
        if len(value) != 2:
            raise ValueError(f"{name} must be a number or a (lo, hi) pair, got {value!r}")
        lo = check_array(f"{name} lo", value[0])
        hi = check_array(f"{name} hi", value[1])
    else:
        lo = hi = check_array(name, value)
    lo, hi = np.broadcast_arrays(lo, hi)
    if np.any(~(lo <= hi)):
        raise ValueError(f"{name}: every lower bound must be <= its upper bound")
    if name in _DOMAIN:
        a, b = _DOMAIN[name]
        if np.any(lo < a) or np.any(hi > b):
            raise ValueError(f"{name} must lie in [{a:g}, {b:g}]")
    elif np.any(lo <= 0):
        raise ValueError(f"{name} must be > 0 (allowed range (0, inf))")
    return lo, hi


@dataclass(frozen=True)
class CertifiedCells:
    """The certified classes of many boxes (:func:`certify_cells`).

    Attributes
    ----------
    flags : ndarray of int8
        :data:`FLAG_VALUES` (``0`` undecided, ``1`` proved stable, ``2`` proved unstable,
        ``3`` proved no orbit), the broadcast shape of the parameters.
    reasons : ndarray of int8
        Indices into :data:`REASONS`.
    boxes_evaluated : int
        Boxes classified, parts included.
    stop : str
        Why the subdivision stopped: ``"decided"`` (no undecided part left), ``"depth"``,
        ``"budget"`` (``max_parts``) or ``"max_boxes"``.
    arb_unconfirmed : int
        Boxes the interval layer proved but arb did not confirm (written undecided, reason
        :data:`R_ARB`); 0 without confirmation.
    tree : ProofTree or None
        The proof (:class:`hybridpd.pair.prooftree.ProofTree`: the leaves and what decided
        them).
    """

    __repr__ = compact_repr

    flags: np.ndarray
    reasons: np.ndarray
    boxes_evaluated: int
    stop: str
    arb_unconfirmed: int = 0
    tree: object = field(default=None, repr=False)

    @property
    def stops(self) -> np.ndarray:
        """Why each box's subdivision stopped, indices into :data:`STOPS` (shape of
        ``flags``): ``proved`` (a box arb did not confirm keeps it; its reason says so),
        ``mixed``, ``depth``, ``budget`` or ``max_boxes``."""
        return np.asarray(self.tree.cell_stop, np.int8).reshape(np.shape(self.flags))


def certify_cells(case="collocated", *, kp, kv, mu, e, omega, m2=1.0, gamma=None, L=None,
                  x10=1.0, n=1, depth=3, max_parts="auto", confirm=True):
    """Classify many boxes at once (vectorised); every parameter a number or ``(lo, hi)``.

    The interval layer proves (:func:`hybridpd.pair.prooftree.prove_cells`: undecided parts
    halved along the parameter that makes the deciding enclosures widest, a box proved when
    all its parts are); with ``confirm`` every proved box is proved again in arb
    (:func:`hybridpd.pair.arbcheck.confirm_map`: existence and the deciding inequality) and
    written undecided where arb cannot.

    Parameters
    ----------
    case : {"collocated", "noncollocated"}
    kp, kv, mu, e, omega, m2 : float, array or (lo, hi) pair of them
        Gains (> 0), mass ratio (> 0), restitution (in [0, 1]), reference frequency (> 0),
        secondary mass (> 0); all broadcast.
    gamma, L, x10 : float, array or (lo, hi)
        ``gamma = L/x10`` (> 0), or ``L`` with ``x10``: give exactly one of ``gamma``, ``L``.
    n : int
        Odd order.
    depth : int
        Bisections of an undecided part at most; ``0`` classifies the boxes as given.
    max_parts : int, None or "auto"
        Parts classified per box at most (``None``: ``depth`` alone bounds the work;
        ``"auto"``, the default: :func:`auto_parts` of ``depth``).
    confirm : bool
        Confirm every proved box in arb.

    Returns
    -------
    CertifiedCells

    Examples
    --------
    >>> import numpy as np
    >>> from hybridpd.pair.certified import certify_cells
    >>> kp = np.array([9.5, 10.0])
    >>> r = certify_cells("collocated", kp=(kp, kp + 0.5), kv=(19.5, 20.0), mu=0.1, e=0.5,
    ...                   gamma=0.75, omega=5.0)
    >>> r.flags.tolist(), r.stop    # 1: proved stable on each whole box
    ([1, 1], 'decided')
    """
    case = Case.parse(case).value
    n = check_odd_order(n)
    depth = check_int("depth", depth, 0, 16)
    max_parts = resolve_parts(max_parts, depth)
    if (gamma is None) == (L is None):
        raise ValueError("give exactly one of gamma or L (gamma = L / x10)")
    gam = _interval_arg("gamma", gamma) if gamma is not None else \
        _ratio(_interval_arg("L", L), _interval_arg("x10", x10))
    boxes, shape = proofs.scaled_boxes(
        kp=_interval_arg("kp", kp), kv=_interval_arg("kv", kv), mu=_interval_arg("mu", mu),
        e=_interval_arg("e", e), gamma=gam, omega=_interval_arg("omega", omega),
        m2=_interval_arg("m2", m2))
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.prooftree import prove_cells

    tree = prove_cells(case, n, boxes, depth=depth, max_parts=max_parts)
    cls, why = tree.cls.copy(), tree.why.copy()
    unconfirmed = 0
    if confirm:
        ok, _ = _arb_confirm(case, n, (1, boxes.size), boxes, tree, blocks=())
        bad = (cls != proofs.UNDECIDED) & ~ok
        cls[bad], why[bad] = proofs.UNDECIDED, R_ARB
        unconfirmed = int(bad.sum())
    return CertifiedCells(cls.astype(np.int8).reshape(shape), why.astype(np.int8).reshape(shape),
                          int(tree.evaluated), tree.stop, unconfirmed, tree)


def _leaf_dict(tree, offset=0):
    """What :func:`hybridpd.pair.arbcheck.confirm_map` reads of a proof tree."""
    r = tree.record
    return {"cell": np.asarray(tree.leaf_cell) + offset, "lo": tree.leaves.lo,
            "hi": tree.leaves.hi, "cls": tree.leaf_cls, "witness_s": r["witness_s"],
            "witness_wall": r["witness_wall"]}


def _arb_confirm(case, n, shape, cells, tree, blocks=(4, 2), leaves=None, flags=None):
    """Confirm the proved cells in arb; returns ``(confirmed, stats)``."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.arbcheck import confirm_map

    return confirm_map(case, n, shape, cells.lo, cells.hi,
                       tree.cls if flags is None else flags,
                       _leaf_dict(tree) if leaves is None else leaves, blocks=blocks)


def _pair(lo, hi):
    return (float(lo), float(hi))


@dataclass(frozen=True)
class BoxCertificate(Fields):
    """The certified class of one box of parameters (see the module docstring).

    Attributes
    ----------
    verdict : str
        ``"proved_stable"``, ``"proved_unstable"``, ``"proved_no_orbit"`` or ``"undecided"``.
    flag : int
        Its :data:`FLAG_VALUES` code.
    reason : str
        What was proved, or what could not be.
    case : str
    n : int
    box : dict
        ``name -> (lo, hi)`` of ``kp, kv, mu, e, gamma, omega, m2``.
    depth : int
        Bisections allowed.
    boxes_evaluated : int
        Boxes classified (the box and its parts).
    stop : str
        Why the bisection stopped (``"decided"``, ``"depth"`` or ``"max_boxes"``).
    """

    __repr__ = compact_repr

    verdict: str
    flag: int
    reason: str
    case: str
    n: int
    box: dict
    depth: int
    boxes_evaluated: int
    stop: str


def certify_box(case="collocated", *, kp, kv, mu, e, gamma, omega, m2=1.0, n=1,
                depth=4) -> BoxCertificate:
    """Prove the class of the symmetric orbit on one box of parameters.

    Parameters
    ----------
    case : {"collocated", "noncollocated"}
    kp, kv, mu, e, gamma, omega, m2 : float or (lo, hi)
        The box: gains (> 0), mass ratio (> 0), restitution in [0, 1], ``gamma = L/x10``
        (> 0), reference frequency (> 0, rad/time), secondary mass (> 0).
    n : int
        Odd order.
    depth : int
        Bisections of undecided parts, at most (0 to 12).

    Returns
    -------
    BoxCertificate

    Examples
    --------
    >>> from hybridpd.pair.certified import certify_box
    >>> c = certify_box("noncollocated", kp=(9.5, 10.5), kv=(19.5, 20.5), mu=0.1, e=0.5,
    ...                 gamma=0.75, omega=5.0)
    >>> c.verdict
    'proved_unstable'
    """
    values = dict(kp=kp, kv=kv, mu=mu, e=e, gamma=gamma, omega=omega, m2=m2)
    for k, v in values.items():
        lo, hi = _interval_arg(k, v)
        if lo.ndim or hi.ndim:
            raise ValueError(f"{k} must be a number or a (lo, hi) pair of numbers")
        values[k] = _pair(lo, hi)
    r = certify_cells(case, n=n, depth=depth, **values)
    f = int(r.flags)
    return BoxCertificate(proofs.CLASSES[f], f, REASONS[int(r.reasons)],
                          Case.parse(case).value, int(n), values, int(depth), r.boxes_evaluated,
                          r.stop)


# ----------------------------------------------------------------------------------------
# Certified maps
# ----------------------------------------------------------------------------------------


def cell_edges(axis, spacing="linear") -> np.ndarray:
    """Edges of the cells of a grid axis: the cell of each point is half-way to its neighbours.

    Convention: interior edges lie half-way between neighbouring points in the axis's own
    spacing (the arithmetic mean for ``"linear"``, the geometric mean for ``"log"``); the
    first and last edges are the first and last grid points. The cells tile the axis's
    range exactly (no gaps, no overlaps, never outside the swept range, so never outside a
    parameter's domain); the two edge cells are half cells.

    Parameters
    ----------
    axis : array_like, shape (N,)
        Increasing grid values, ``N >= 2`` (``> 0`` for ``"log"``).
    spacing : {"linear", "log"}

    Returns
    -------
    ndarray, shape (N + 1,)

    Examples
    --------
    >>> from hybridpd.pair.certified import cell_edges
    >>> cell_edges([1.0, 2.0, 4.0]).tolist(), cell_edges([1.0, 4.0, 16.0], "log").tolist()
    ([1.0, 1.5, 3.0, 4.0], [1.0, 2.0, 8.0, 16.0])
    """
    x = check_array("axis", axis)
    if x.ndim != 1 or x.size < 2 or not np.all(np.diff(x) > 0):
        raise ValueError("axis must be an increasing 1-D array of at least 2 values")
    if spacing == "linear":
        mid = 0.5 * x[:-1] + 0.5 * x[1:]
    elif spacing == "log":
        if x[0] <= 0:
            raise ValueError("a log-spaced axis must be > 0 (allowed range (0, inf))")
        mid = np.sqrt(x[:-1] * x[1:])
    else:
        raise ValueError(f"spacing must be 'linear' or 'log', got {spacing!r}")
    return np.concatenate([x[:1], mid, x[-1:]])


def class_shares(flags) -> dict:
    """Counts and shares of each class in an array of flags (the last two axes: one map).

    Returns
    -------
    dict
        ``{class name: {"proved": k, "undecided": u, "cells": N, "share": (k/N, (k+u)/N)}}``
        for the three proved classes, where ``k`` counts cells proved in the class and
        ``u`` the undecided ones (which may belong to it): the class's true share of the
        cells lies in ``share``. For ``"undecided"`` itself, ``proved`` is its count.

    Examples
    --------
    >>> from hybridpd.pair.certified import class_shares
    >>> s = class_shares([[1, 1], [0, 3]])
    >>> s["proved_stable"]["share"], s["proved_no_orbit"]["share"]
    ((0.5, 0.75), (0.25, 0.5))
    """
    f = np.asarray(flags)
    N = int(f.size)
    u = int((f == 0).sum())
    out = {}
    for code, name in enumerate(proofs.CLASSES):
        k = int((f == code).sum())
        out[name] = {"proved": k, "undecided": u if code else 0, "cells": N,
                     "share": (k / N, (k + (u if code else 0)) / N) if N else (0.0, 0.0)}
    return out


@dataclass(frozen=True)
class CertifiedMap:
    """A certified classification of a grid of two parameters, per restitution coefficient.

    Attributes
    ----------
    case : str
    n : int
    x_name, y_name : str
    x, y : ndarray
        Grid axes.
    x_edges, y_edges : ndarray
        Cell edges (:func:`cell_edges`), lengths ``len(x) + 1``, ``len(y) + 1``.
    e : ndarray
        Restitution coefficients (first index).
    fixed : dict
        The other parameters.
    flags : ndarray of int8, shape (len(e), len(y), len(x))
        :data:`FLAG_VALUES`.
    reasons : ndarray of int8, same shape
        Indices into :data:`REASONS`.
    depth : int
    seconds : float
        Wall time (the arb confirmation included).
    boxes_evaluated : int
    arb_unconfirmed : ndarray of int, shape (len(e),)
        Cells the interval layer proved but arb did not confirm (written undecided).
    arb_seconds : float
        Wall time of the arb confirmation.
    certificate : Certificate or None
        The proof (:class:`hybridpd.pair.certificate.Certificate`) when asked for.
    stops : ndarray of int8, same shape as ``flags``
        Why each cell's subdivision stopped, indices into :data:`STOPS` (``proved``,
        ``mixed``, ``depth``, ``budget``, ``max_boxes``; a cell arb did not confirm keeps
        ``proved``, its reason says why it is undecided).
    max_parts : int or None
        The budget of parts per cell used.
    """

    __repr__ = compact_repr

    case: str
    n: int
    x_name: str
    y_name: str
    x: np.ndarray
    y: np.ndarray
    x_edges: np.ndarray
    y_edges: np.ndarray
    e: np.ndarray
    fixed: dict
    flags: np.ndarray
    reasons: np.ndarray
    depth: int
    seconds: float
    boxes_evaluated: int
    arb_unconfirmed: np.ndarray = None
    arb_seconds: float = 0.0
    certificate: object = field(default=None, repr=False)
    stops: np.ndarray = field(default=None, repr=False)
    max_parts: int = None

    def save_certificate(self, path):
        """Write the map's certificate (JSON, ``.gz`` compressed); re-check it with
        :func:`hybridpd.pair.certificate.verify_certificate`. Returns the path."""
        if self.certificate is None:
            raise ValueError("certificate: this map kept none (certified_map(..., "
                             "certificate=True or a file name))")
        return self.certificate.save(path)

    def shares(self) -> list:
        """:func:`class_shares` of each ``e``'s map."""
        return [class_shares(f) for f in self.flags]

    def proved_fraction(self) -> np.ndarray:
        """Share of proved cells per ``e``."""
        return (self.flags != 0).mean(axis=(1, 2))

    def summary(self) -> list:
        """One line per ``e``: the proved counts, each class's share interval and why the
        undecided cells' subdivision stopped."""
        lines = []
        for i, (e, sh) in enumerate(zip(self.e, self.shares())):
            N = sh["undecided"]["cells"]
            parts = [f"{name} {d['proved']}/{N} [{100 * d['share'][0]:.1f}, "
                     f"{100 * d['share'][1]:.1f}]%" for name, d in sh.items() if name != "undecided"]
            line = f"e = {e:g}: undecided {sh['undecided']['proved']}/{N}; " + "; ".join(parts)
            if self.stops is not None:
                und = self.flags[i] == 0
                count = np.bincount(self.stops[i][und].astype(np.int64), minlength=len(STOPS))
                # an undecided cell whose subdivision proved it: arb did not confirm it
                names = ("not confirmed in arb",) + STOPS[1:]
                why = [f"{names[k]} {int(c)}" for k, c in enumerate(count) if c]
                if why:
                    line += f" (why undecided: {', '.join(why)})"
            lines.append(line)
        return lines

    def to_dict(self) -> dict:
        """JSON-ready form (flags indexed ``[e][y][x]``)."""
        return {"case": self.case, "n": self.n, "x_name": self.x_name, "y_name": self.y_name,
                self.x_name: self.x.tolist(), self.y_name: self.y.tolist(),
                "x_edges": self.x_edges.tolist(), "y_edges": self.y_edges.tolist(),
                "e": self.e.tolist(), "fixed": dict(self.fixed),
                "flag_values": list(FLAG_VALUES), "flag_meanings": FLAG_MEANINGS,
                "flags": self.flags.tolist(), "reasons": self.reasons.tolist(),
                "reason_texts": list(REASONS), "depth": self.depth,
                "max_parts": self.max_parts,
                "stops": None if self.stops is None else self.stops.tolist(),
                "stop_texts": list(STOPS),
                "seconds": self.seconds, "boxes_evaluated": self.boxes_evaluated,
                "arb_unconfirmed": None if self.arb_unconfirmed is None else
                [int(v) for v in self.arb_unconfirmed], "arb_seconds": self.arb_seconds,
                "shares": [{k: {**v, "share": list(v["share"])} for k, v in sh.items()}
                           for sh in self.shares()]}


def _map_axis(param, spec, spacing):
    """``(name, values)`` from ``(NAME, MIN, MAX, NUM)`` or ``(NAME, values)``."""
    if isinstance(spec, (tuple, list)) and len(spec) == 2 and not isinstance(spec[1], (int, float)):
        name = spec[0]
        if not isinstance(name, str) or name not in MAP_AXES:
            raise ValueError(f"{param} axis name must be one of {MAP_AXES}, got {name!r}")
        values = check_array(param, spec[1], lo=0.0)
        cell_edges(values, spacing)  # validates
        return name, values
    name, values = check_named_axis(param, spec, MAP_AXES, min_num=2, positive=True)
    if spacing == "log":
        values = np.geomspace(values[0], values[-1], values.size)
    return name, values


def cell_boxes(x_name, x_edges, y_name, y_edges):
    """The cells of a grid as ``{name: (lo, hi)}``, arrays of shape ``(ny, nx)``.

    Parameters
    ----------
    x_name, y_name : str
    x_edges, y_edges : ndarray
        Cell edges (:func:`cell_edges`), lengths ``nx + 1`` and ``ny + 1``.

    Examples
    --------
    >>> from hybridpd.pair.certified import cell_boxes
    >>> c = cell_boxes("kp", [1.0, 1.5, 2.0], "kv", [3.0, 4.0])
    >>> c["kp"][0].tolist(), c["kp"][1].tolist(), c["kv"][0].tolist()
    ([[1.0, 1.5]], [[1.5, 2.0]], [[3.0, 3.0]])
    """
    XL, YL = np.meshgrid(x_edges[:-1], y_edges[:-1])
    XH, YH = np.meshgrid(x_edges[1:], y_edges[1:])
    return {x_name: (XL, XH), y_name: (YL, YH)}


#: The grid whose cells ``depth = 3`` suits (the benchmark's 101 x 101)
_DENSE_CELLS = 101 * 101
#: The largest depth :func:`auto_depth` chooses and the parts per cell :func:`auto_parts`
#: allows at most (twice the 255 parts of the former largest automatic depth, 7).
MAX_AUTO_DEPTH = 12
MAX_AUTO_PARTS = 512


def auto_depth(n_cells: int) -> int:
    """Bisections per undecided part for a grid of `n_cells` cells: 3 for a 101 x 101 grid,
    one more for every factor 2 fewer cells, at most :data:`MAX_AUTO_DEPTH`.

    A coarse cell holding ``4^k`` dense ones is cut to their size by ``k`` halvings along
    each of the two axes, ``2 k`` in all: its parts are then as fine as the dense grid's
    cells, and below them as finely subdivided.

    Examples
    --------
    >>> from hybridpd.pair.certified import auto_depth
    >>> auto_depth(101 * 101), auto_depth(51 * 51), auto_depth(81), auto_depth(1)
    (3, 5, 10, 12)
    """
    n_cells = check_int("n_cells", n_cells, 1)
    more = max(0, math.ceil(math.log2(_DENSE_CELLS / n_cells) - 1e-9))
    return int(min(MAX_AUTO_DEPTH, 3 + more))


def auto_parts(depth: int) -> int:
    """Parts classified per cell at most with bisection depth `depth`: all ``2^(depth+1) - 1``
    parts of the full tree, at most :data:`MAX_AUTO_PARTS`.

    A cell proved in one class is seldom a full tree: it is cut finely only along the
    boundaries of its enclosures' failure, and a cell that a class boundary crosses stops
    when two of its parts are proved in different classes. The budget bounds the work of a
    cell whose parts stay undecided along a long curve.

    Examples
    --------
    >>> from hybridpd.pair.certified import auto_parts
    >>> auto_parts(3), auto_parts(10)
    (15, 512)
    """
    depth = check_int("depth", depth, 0, 16)
    return int(min(2 ** (depth + 1) - 1, MAX_AUTO_PARTS))


def resolve_depth(depth, n_cells: int) -> int:
    """``depth`` as an int: ``"auto"`` is :func:`auto_depth` of the grid, else an int in
    ``[0, 16]`` (``ValueError`` naming it)."""
    if isinstance(depth, str):
        if depth != "auto":
            raise ValueError(f"depth must be 'auto' or an int in [0, 16], got {depth!r}")
        return auto_depth(n_cells)
    return check_int("depth", depth, 0, 16)


def resolve_parts(max_parts, depth: int):
    """``max_parts`` as an int or ``None``: ``"auto"`` is :func:`auto_parts` of ``depth``,
    ``None`` no budget, else an int >= 1 (``ValueError`` naming it)."""
    if isinstance(max_parts, str):
        if max_parts != "auto":
            raise ValueError(f"max_parts must be 'auto', None or an int >= 1, got "
                             f"{max_parts!r}")
        return auto_parts(depth)
    return None if max_parts is None else check_int("max_parts", max_parts, 1)


def certified_map(case="collocated", *, x=("kp", 0.1, 50.0, 101), y=("kv", 0.1, 50.0, 101),
                  e=(0.1, 0.5, 0.9), mu=None, omega=None, L=None, gamma=None, x10=1.0,
                  m2=1.0, n=1, kp=None, kv=None, spacing="linear", depth="auto",
                  chunk_size=4096, max_parts="auto", confirm=True,
                  certificate=None) -> CertifiedMap:
    """Certified classification of every cell of a grid (see the module docstring).

    Each cell is proved in float interval arithmetic (undecided parts halved adaptively,
    :func:`hybridpd.pair.prooftree.prove_cells`), then, with ``confirm``, every proved cell
    is proved again in arb (:func:`hybridpd.pair.arbcheck.confirm_map`: existence and the
    inequality deciding its class) before it is written; a cell arb cannot confirm is
    written undecided (reason :data:`R_ARB`) and counted in ``arb_unconfirmed``.

    Parameters
    ----------
    case : {"collocated", "noncollocated"}
    x, y : (NAME, MIN, MAX, NUM) or (NAME, values)
        Swept parameters (names from :data:`MAP_AXES`); ``linspace`` (or ``geomspace`` with
        ``spacing="log"``) or the given increasing values.
    e : sequence of float
        Restitution coefficients in [0, 1], one map each.
    mu, omega, L or gamma, x10, m2, n, kp, kv
        The fixed parameters (as for :class:`hybridpd.pair.regions.SymmetricFamily`).
    spacing : {"linear", "log"} or (x_spacing, y_spacing)
        The cells' convention of :func:`cell_edges`.
    depth : int or "auto"
        Bisections of an undecided part of a cell at most; ``"auto"`` (default): 3 for a
        101 x 101 grid and one more for every factor 2 fewer cells (:func:`auto_depth`),
        so that coarse cells are subdivided as finely as a dense grid's.
    chunk_size : int
        Cells classified per vectorised batch.
    max_parts : int, None or "auto"
        Parts classified per cell at most (``None``: ``depth`` alone bounds the work;
        ``"auto"``, the default: :func:`auto_parts` of the depth, at most 512).
    confirm : bool
        Confirm every proved cell in arb.
    certificate : None, True, str or Path
        Keep the proof as the map's ``certificate``
        (:class:`hybridpd.pair.certificate.Certificate`); a file name also writes it there
        (JSON; ``.gz`` compressed). :func:`hybridpd.pair.certificate.verify_certificate`
        re-proves it in arb alone.

    Returns
    -------
    CertifiedMap

    Examples
    --------
    >>> from hybridpd.pair.certified import certified_map
    >>> cm = certified_map("collocated", x=("kp", 9, 11, 3), y=("kv", 19, 21, 3), e=[0.5],
    ...                    mu=0.1, gamma=0.75, omega=5.0)
    >>> cm.flags.tolist()                    # every cell proved stable
    [[[1, 1, 1], [1, 1, 1], [1, 1, 1]]]
    >>> cm.shares()[0]["proved_stable"]["share"]
    (1.0, 1.0)
    """
    t0 = time.perf_counter()
    case = Case.parse(case).value
    n = check_odd_order(n)
    sx, sy = (spacing, spacing) if isinstance(spacing, str) else tuple(spacing)
    xname, xs = _map_axis("x", x, sx)
    yname, ys = _map_axis("y", y, sy)
    if xname == yname:
        raise ValueError(f"x and y must sweep different parameters, got {xname!r} twice")
    es = np.atleast_1d(check_array("e", e, lo=0.0, lo_open=False, hi=1.0))
    if es.ndim != 1 or es.size == 0:
        raise ValueError("e must be a non-empty list of restitution coefficients")
    chunk_size = check_int("chunk_size", chunk_size, 1)
    if certificate is not None and certificate is not True and \
            not isinstance(certificate, (str, bytes)) and not hasattr(certificate, "__fspath__"):
        raise ValueError(f"certificate must be None, True or a file name, got {certificate!r}")
    fixed = _fixed_params(xname, yname, mu=mu, omega=omega, L=L, gamma=gamma, x10=x10, m2=m2,
                          kp=kp, kv=kv)
    depth = resolve_depth(depth, xs.size * ys.size)
    max_parts = resolve_parts(max_parts, depth)
    xe, ye = cell_edges(xs, sx), cell_edges(ys, sy)
    cells = cell_boxes(xname, xe, yname, ye)
    flags = np.zeros((es.size, ys.size, xs.size), np.int8)
    reasons = np.zeros_like(flags)
    stops = np.zeros_like(flags)
    evaluated = 0
    unconfirmed = np.zeros(es.size, np.int64)
    arb_seconds = 0.0
    maps = []
    flat = {k: (lo.ravel(), hi.ravel()) for k, (lo, hi) in cells.items()}
    for i, ev in enumerate(es):
        f_out, r_out, s_out = (a[i].reshape(-1) for a in (flags, reasons, stops))
        trees = []
        for c in range(0, xs.size * ys.size, chunk_size):
            sl = slice(c, c + chunk_size)
            part = {k: (lo[sl], hi[sl]) for k, (lo, hi) in flat.items()}
            r = certify_cells(case, n=n, depth=depth, e=ev, max_parts=max_parts, confirm=False,
                              **fixed, **part)
            f_out[sl], r_out[sl], s_out[sl] = r.flags, r.reasons, r.stops
            evaluated += r.boxes_evaluated
            trees.append((c, r.tree))
        if confirm or certificate is not None:
            grid, leaves, columns = _merge_trees(trees)
        if confirm:
            t1 = time.perf_counter()
            ok, _ = _arb_confirm(case, n, (ys.size, xs.size), grid, None, leaves=leaves,
                                 flags=f_out.astype(np.int64))
            arb_seconds += time.perf_counter() - t1
            bad = (f_out != 0) & ~ok
            f_out[bad], r_out[bad] = 0, R_ARB
            unconfirmed[i] = int(bad.sum())
        if certificate is not None:
            maps.append(_certificate_map(ev, f_out, grid, columns, (ys.size, xs.size)))
    cert = None
    if certificate is not None:
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.pair.certificate import Certificate

        cert = Certificate(case, n, xname, yname, xe, ye, {**fixed, "n": n}, es, maps)
        if certificate is not True:
            cert.save(certificate)
    return CertifiedMap(case, n, xname, yname, xs, ys, xe, ye, es, {**fixed, "n": n}, flags,
                        reasons, int(depth), time.perf_counter() - t0, evaluated, unconfirmed,
                        arb_seconds, cert, stops, max_parts)


def _merge_trees(trees):
    """The cells (scaled boxes), the leaves for arb and the certificate's columns of one map
    from the proof trees of its chunks (``(first cell, tree)`` pairs)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.certificate import concat_columns, leaves_columns

    cells = proofs.Boxes({k: np.concatenate([t.cells.lo[k] for _, t in trees])
                          for k in proofs.SCALED},
                         {k: np.concatenate([t.cells.hi[k] for _, t in trees])
                          for k in proofs.SCALED})
    columns = concat_columns([leaves_columns(t, c) for c, t in trees])
    lv = columns[0]
    leaves = {"cell": lv["cell"], "lo": lv["lo"], "hi": lv["hi"], "cls": lv["cls"],
              "witness_s": lv["witness_s"], "witness_wall": lv["witness_wall"]}
    return cells, leaves, columns


def _certificate_map(e, flags, cells, columns, shape):
    """One ``e``'s part of a certificate: the cells, and the leaves of the proved ones."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.certificate import restrict

    flags = np.asarray(flags, np.int64)
    lv, pc = restrict(*columns, flags != 0)
    return {"e": float(e), "flags": flags.reshape(shape),
            "cells": {"lo": dict(cells.lo), "hi": dict(cells.hi)}, "leaves": lv, "pieces": pc}


def _fixed_params(xname, yname, *, mu, omega, L, gamma, x10, m2, kp, kv) -> dict:
    """The parameters that are not swept, validated (``L = gamma x10`` when ``gamma`` given)."""
    swept = (xname, yname)
    if "L" in swept:
        if gamma is not None or L is not None:
            raise ValueError("L is a swept axis: do not give L or gamma as well")
    elif (L is None) == (gamma is None):
        raise ValueError("give exactly one of L or gamma (L = gamma * x10)")
    elif L is None and "x10" in swept:
        raise ValueError("with x10 swept give L, not gamma (L would change along the axis)")
    elif L is None:
        L = check_positive("gamma", gamma) * check_positive("x10", x10)
    given = {"mu": mu, "omega": omega, "L": L, "x10": x10, "m2": m2, "kp": kp, "kv": kv}
    fixed = {}
    for name, val in given.items():
        if name in swept:
            continue
        if val is None:
            raise ValueError(f"{name} must be given when it is not a swept axis")
        fixed[name] = check_positive(name, val)
    return fixed
