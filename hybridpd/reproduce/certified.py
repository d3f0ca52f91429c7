"""Certified shares of a gain box: the numbers the reproduction's verdicts are decided by.

A grid count says how many grid *points* have a stable orbit; it cannot say whether a change
of a few cells is real. This module encloses the share of the **whole box** (its area)
where the symmetric orbit exists and is stable, by interval proofs
(:func:`hybridpd.pair.proofs.classify`) on an adaptive partition of the box:

* The box ``[lo/m2, hi/m2]^2`` of the scaled gains ``(kp/m2, kv/m2)`` (the paper's gain box
  as printed, read at ``m2``; ``m2 = 1`` is the scaled box itself) is cut into ``grid x grid``
  equal **base cells**. Every cell is classified for each property of
  :data:`PROPERTIES`: proved *in* (the property holds at every point of the cell), proved
  *out* (it fails at every point) or undecided.
* A cell undecided for a property its target asks for is cut into four equal quarters, at
  most ``levels`` times: a leaf of level ``l`` is a cell of the grid with ``grid 2^l``
  cells per axis. The refinement stops when the undecided share of every asked property is
  at most ``width`` (``stop = "width"``) or at the cap (``stop = "levels"``).
* Counted in cells of the **finest grid** (``grid 2^levels`` per axis, ``N`` cells), the
  share of the property lies in ``[in / N, (N - out) / N]``. The cells tile the box exactly
  and are all of one size, so this interval encloses both the share of the box's *area*
  and the share of the finest grid's *cell centres* where the property holds; any two
  enclosures of the same box (another grid, another depth) therefore overlap.

The properties, from the parts of the proof (existence of the solution of (13)-(14), its
viability (18), its multipliers):

* ``"exists_stable"`` (the paper's shaded regions): in when existence, viability and
  stability are proved; out when viability is proved violated (no orbit) or the candidate
  exists and is proved unstable (then it is either no orbit or an unstable one);
* ``"exists"``: in when existence and viability are proved, out when viability is proved
  violated;
* ``"exists_unstable"``: in when existence, viability and instability are proved; out when
  viability is violated or stability is proved.

``"no_orbit"`` is the complement of ``"exists"``.

Examples
--------
>>> from hybridpd.reproduce.certified import ShareTarget, certified_shares
>>> t = ShareTarget("collocated", e=0.5, box=(9.0, 11.0))
>>> (r,) = certified_shares([t], grid=2, levels=0)
>>> r.interval("exists_stable"), r.stop       # the four cells too large for the proofs
((0.0, 1.0), 'levels')
>>> (r,) = certified_shares([t], grid=2, levels=1)
>>> r.interval("exists_stable"), r.stop       # their quarters: the whole box is stable
((1.0, 1.0), 'width')
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.model import Case, check_in_range, check_int, check_odd_order, check_positive

__all__ = ["CLASSES", "GROUPS", "MU_LIMIT", "PROPERTIES", "CertifiedShare", "Leaves",
           "ShareTarget", "certified_shares", "merge_shares", "mu_move_values", "reading_values",
           "reproduction_shares", "study_values"]

#: The properties whose shares are enclosed.
PROPERTIES = ("exists_stable", "exists", "exists_unstable")
#: The classes reported (``no_orbit`` is the complement of ``exists``).
CLASSES = ("exists_stable", "exists_unstable", "exists", "no_orbit")

_IN, _OUT, _UNDECIDED = 1, -1, 0


@dataclass(frozen=True)
class ShareTarget:
    """One box to certify.

    Attributes
    ----------
    case : str
        ``"collocated"`` or ``"noncollocated"``.
    e : float
        Restitution coefficient in ``[0, 1]``.
    mu : float
        Mass ratio ``m1/m2`` (> 0).
    m2 : float
        The reading of the printed box: the scaled box is ``[box[0]/m2, box[1]/m2]`` on both
        axes (``m2 = 1``: the scaled box itself).
    box : (float, float)
        The gain box as printed, the same on ``kp`` and ``kv`` (force/length and
        force·time/length).
    properties : tuple of str
        The properties (:data:`PROPERTIES`) whose undecided share drives the refinement;
        the others are enclosed from the same proofs, as tight as they come.
    key : tuple
        A label for the caller (default ``(case, e, mu, m2)``).
    gamma : float or None
        ``gamma = L/x10`` of this box (> 0); None: the ``gamma`` of the
        :func:`certified_shares` call.
    """

    case: str
    e: float
    mu: float = 0.1
    m2: float = 1.0
    box: tuple = (0.1, 50.0)
    properties: tuple = ("exists_stable", "exists")
    key: tuple = None
    gamma: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "case", Case.parse(self.case).value)
        check_in_range("e", self.e, 0.0, 1.0)
        check_positive("mu", self.mu)
        check_positive("m2", self.m2)
        if self.gamma is not None:
            object.__setattr__(self, "gamma", check_positive("gamma", self.gamma))
        lo, hi = (check_positive("box", v) for v in self.box)
        if not lo < hi:
            raise ValueError(f"box must satisfy 0 < lo < hi, got {self.box!r}")
        object.__setattr__(self, "box", (float(lo), float(hi)))
        bad = [p for p in self.properties if p not in PROPERTIES]
        if bad or not self.properties:
            raise ValueError(f"properties must be a non-empty subset of {PROPERTIES}, "
                             f"got {self.properties!r}")
        if self.key is None:
            object.__setattr__(self, "key", (self.case, float(self.e), float(self.mu),
                                             float(self.m2)))

    @property
    def scaled_box(self) -> tuple:
        """``(lo, hi)`` of ``kp/m2`` and ``kv/m2`` (1/time^2 and 1/time)."""
        return (self.box[0] / self.m2, self.box[1] / self.m2)


@dataclass(frozen=True)
class Leaves:
    """The final partition of one target's box (kept on request, for checks and figures).

    Attributes
    ----------
    kp, kv : ndarray, shape (K, 2)
        ``[lo, hi]`` of each leaf in ``kp/m2`` and ``kv/m2``.
    level : ndarray of int, shape (K,)
        Refinement level of each leaf (0: a base cell).
    state : dict
        ``{property: ndarray of int8 (K,)}``: ``1`` proved in, ``-1`` proved out, ``0``
        undecided.
    """

    kp: np.ndarray
    kv: np.ndarray
    level: np.ndarray
    state: dict
    __repr__ = compact_repr


@dataclass(frozen=True)
class CertifiedShare:
    """The certified shares of one target's box.

    Attributes
    ----------
    target : ShareTarget
    grid : int
        Base cells per axis.
    levels : int
        Refinement levels allowed; :attr:`finest` ``= grid 2^levels`` cells per axis.
    counts : dict
        ``{property: {"in": k, "out": k2, "undecided": u}}`` in cells of the finest grid
        (``k + k2 + u = finest^2``).
    base : dict
        ``{property: {"in", "out", "undecided"}}`` in base cells (a base cell counts as
        proved when the whole cell is, possibly through its parts).
    leaves_evaluated : int
        Boxes classified (base cells and parts).
    stop : str
        ``"width"`` (every asked property's undecided share is at most the width) or
        ``"levels"`` (the cap on the levels was reached first).
    seconds : float
        Wall time of the whole batch this target was certified in.
    leaves : Leaves or None
    """

    target: ShareTarget
    grid: int
    levels: int
    counts: dict
    base: dict
    leaves_evaluated: int
    stop: str
    seconds: float
    leaves: Leaves | None = field(default=None, repr=False)
    __repr__ = compact_repr

    @property
    def finest(self) -> int:
        """Cells per axis of the finest grid."""
        return self.grid * 2 ** self.levels

    @property
    def cells(self) -> int:
        """Cells of the finest grid (the denominator of every share)."""
        return self.finest ** 2

    def interval(self, name) -> tuple:
        """``(lo, hi)`` enclosing the share of the box where ``name`` holds (a property of
        :data:`PROPERTIES` or ``"no_orbit"``)."""
        N = self.cells
        if name == "no_orbit":
            c = self.counts["exists"]
            return (c["out"] / N, (N - c["in"]) / N)
        if name not in self.counts:
            raise ValueError(f"name must be one of {CLASSES}, got {name!r}")
        c = self.counts[name]
        return (c["in"] / N, (N - c["out"]) / N)

    def to_dict(self) -> dict:
        """JSON-ready: each class's ``[lo, hi]``, its cell counts, the grid."""
        t = self.target
        lo, hi = t.scaled_box
        N = self.cells
        out = {name: list(self.interval(name)) for name in CLASSES}
        counts = {}
        for name in CLASSES:
            if name == "no_orbit":
                c = self.counts["exists"]
                counts[name] = {"proved": c["out"], "proved_not": c["in"],
                                "undecided": c["undecided"], "of": N}
            else:
                c = self.counts[name]
                counts[name] = {"proved": c["in"], "proved_not": c["out"],
                                "undecided": c["undecided"], "of": N}
        out.update({
            "cells": counts,
            "grid": [self.finest, self.finest],
            "base_grid": [self.grid, self.grid], "levels": self.levels,
            "base_cells": {p: dict(v, of=self.grid ** 2) for p, v in self.base.items()},
            "box": {"kp/m2": [lo, hi], "kv/m2": [lo, hi]},
            "case": t.case, "e": t.e, "mu": t.mu, "m2": t.m2, "gamma": t.gamma,
            "leaves_evaluated": self.leaves_evaluated, "stop": self.stop})
        return out


def _classify(case, n, kp, kv, mu, e, gamma, omega, chunk):
    """Per box: the states of every property (``1`` in, ``-1`` out, ``0`` undecided)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair import proofs

    N = kp[0].size
    states = {p: np.zeros(N, np.int8) for p in PROPERTIES}
    for s in range(0, N, chunk):
        sl = slice(s, s + chunk)
        boxes, _ = proofs.scaled_boxes(kp=(kp[0][sl], kp[1][sl]), kv=(kv[0][sl], kv[1][sl]),
                                       mu=mu[sl], e=e[sl], gamma=gamma[sl], omega=omega,
                                       m2=1.0)
        _, _, p = proofs.classify(case, n, boxes, details=True)
        ex, v, st, un = p["exists"], p["viable"], p["stable"], p["unstable"]
        real = ex & (v == 1)
        gone = v == -1
        states["exists"][sl] = np.select([real, gone], [_IN, _OUT], _UNDECIDED)
        # an existing candidate proved unstable is no stable orbit, viable or not
        states["exists_stable"][sl] = np.select([real & st, gone | (ex & un)], [_IN, _OUT],
                                                _UNDECIDED)
        states["exists_unstable"][sl] = np.select([real & un, gone | (ex & st)], [_IN, _OUT],
                                                  _UNDECIDED)
    return states


def _certify_case(case, targets, *, grid, levels, width, gamma, omega, n, chunk, keep_leaves):
    """Every target of one feedback case, all boxes of a level in one batch."""
    T = len(targets)
    F = grid * 2 ** levels
    unit = 2 ** levels
    lo = np.array([t.scaled_box[0] for t in targets])
    span = np.array([t.scaled_box[1] - t.scaled_box[0] for t in targets])
    mus = np.array([t.mu for t in targets], float)
    es = np.array([t.e for t in targets], float)
    gams = np.array([gamma if t.gamma is None else t.gamma for t in targets], float)
    asks = {p: np.array([p in t.properties for t in targets]) for p in PROPERTIES}
    # leaves in integer units of the finest grid: [i, i + size) x [j, j + size)
    J, I = np.divmod(np.arange(grid * grid), grid)
    tid = np.repeat(np.arange(T), grid * grid)
    i0, j0 = np.tile(I * unit, T), np.tile(J * unit, T)
    size = np.full(tid.size, unit)
    base = np.tile(np.arange(grid * grid), T)
    counts = {p: np.zeros((T, 3), np.int64) for p in PROPERTIES}   # in, out, undecided
    base_seen = {p: np.zeros((T, grid * grid, 2), bool) for p in PROPERTIES}  # any in / out
    base_open = {p: np.zeros((T, grid * grid), bool) for p in PROPERTIES}
    active = np.ones(T, bool)
    stop = np.array(["levels"] * T, dtype=object)
    evaluated = 0
    kept = []
    inherited = {p: np.zeros(tid.size, np.int8) for p in PROPERTIES}
    for level in range(levels + 1):
        a, b = lo[tid], span[tid]
        kp = (a + b * (i0 / F), a + b * ((i0 + size) / F))
        kv = (a + b * (j0 / F), a + b * ((j0 + size) / F))
        st = _classify(case, n, kp, kv, mus[tid], es[tid], gams[tid], omega, chunk)
        # what was proved on a parent holds on its parts (a smaller box's enclosure may
        # still fail to show it)
        st = {p: np.where(inherited[p] != _UNDECIDED, inherited[p], s) for p, s in st.items()}
        evaluated += tid.size
        w = size.astype(np.int64) ** 2
        for p, s in st.items():
            for col, val in ((0, _IN), (1, _OUT)):
                m = s == val
                np.add.at(counts[p][:, col], tid[m], w[m])
                base_seen[p][tid[m], base[m], col] = True
        und = {p: st[p] == _UNDECIDED for p in PROPERTIES}
        # leaves undecided for an asked property are refined; for the others they stay
        want = np.zeros(tid.size, bool)
        for p in PROPERTIES:
            want |= und[p] & asks[p][tid]
        share = {p: np.bincount(tid[und[p]], weights=w[und[p]], minlength=T) / F ** 2
                 for p in PROPERTIES}
        done_width = np.ones(T, bool)
        for p in PROPERTIES:
            done_width &= ~asks[p] | (share[p] <= width)
        stop[active & done_width] = "width"
        active &= ~done_width
        refine = want & active[tid] & (level < levels)
        keep = ~refine
        for p in PROPERTIES:
            m = keep & und[p]
            np.add.at(counts[p][:, 2], tid[m], w[m])
            base_open[p][tid[m], base[m]] = True
        if keep_leaves:
            kept.append((tid[keep], kp[0][keep], kp[1][keep], kv[0][keep], kv[1][keep],
                         np.full(int(keep.sum()), level), {p: st[p][keep] for p in st}))
        if not refine.any():
            break
        # the refined leaves' decided parts are counted again at the next level
        for p in PROPERTIES:
            for col, val in ((0, _IN), (1, _OUT)):
                m = refine & (st[p] == val)
                np.add.at(counts[p][:, col], tid[m], -w[m])
        tid, i0, j0, size, base = (a[refine] for a in (tid, i0, j0, size, base))
        inherited = {p: np.tile(s[refine], 4) for p, s in st.items()}
        size = size // 2
        tid, base, size = np.tile(tid, 4), np.tile(base, 4), np.tile(size, 4)
        i0 = np.concatenate([i0, i0 + size[: i0.size], i0, i0 + size[: i0.size]])
        j0 = np.concatenate([j0, j0, j0 + size[: j0.size], j0 + size[: j0.size]])
    out = []
    for k in range(T):
        cnt = {p: dict(zip(("in", "out", "undecided"), (int(v) for v in counts[p][k])))
               for p in PROPERTIES}
        bas = {}
        for p in PROPERTIES:
            seen_in, seen_out = base_seen[p][k, :, 0], base_seen[p][k, :, 1]
            op = base_open[p][k]
            proved_in = seen_in & ~seen_out & ~op
            proved_out = seen_out & ~seen_in & ~op
            bas[p] = {"in": int(proved_in.sum()), "out": int(proved_out.sum()),
                      "undecided": int(grid * grid - proved_in.sum() - proved_out.sum())}
        leaves = None
        if keep_leaves:
            parts = [(m := (c[0] == k), c) for c in kept]
            leaves = Leaves(
                kp=np.concatenate([np.stack([c[1][m], c[2][m]], 1) for m, c in parts]),
                kv=np.concatenate([np.stack([c[3][m], c[4][m]], 1) for m, c in parts]),
                level=np.concatenate([c[5][m] for m, c in parts]),
                state={p: np.concatenate([c[6][p][m] for m, c in parts]) for p in PROPERTIES})
        out.append((cnt, bas, str(stop[k]), leaves))
    return out, evaluated


def certified_shares(targets, *, grid=16, levels=3, width=0.02, gamma=0.75, omega=5.0, n=1,
                     chunk=20000, keep_leaves=False) -> list:
    """Certified shares of every target's box (see the module docstring).

    Parameters
    ----------
    targets : sequence of ShareTarget
    grid : int
        Base cells per axis (2 to 512).
    levels : int
        Refinement levels at most (0 to 10); the finest grid has ``grid 2^levels`` cells per
        axis.
    width : float
        Refinement stops for a target once the undecided share of each property it asks for
        is at most this (in ``[0, 1]``).
    gamma, omega, n
        ``gamma = L/x10`` (> 0), the reference frequency (rad/time, > 0) and the odd order.
    chunk : int
        Boxes per vectorised batch.
    keep_leaves : bool
        Keep the final partition of every box (:class:`Leaves`).

    Returns
    -------
    list of CertifiedShare
        In the order of ``targets``.

    Examples
    --------
    >>> from hybridpd.reproduce.certified import ShareTarget, certified_shares
    >>> t = ShareTarget("noncollocated", e=0.5, box=(9.5, 10.5))
    >>> (r,) = certified_shares([t], grid=2, levels=1)
    >>> r.interval("exists_unstable"), r.interval("exists_stable")
    ((1.0, 1.0), (0.0, 0.0))
    """
    targets = list(targets)
    if not targets or not all(isinstance(t, ShareTarget) for t in targets):
        raise ValueError("targets must be a non-empty list of ShareTarget")
    grid = check_int("grid", grid, 2, 512)
    levels = check_int("levels", levels, 0, 10)
    width = check_in_range("width", width, 0.0, 1.0)
    gamma, omega = check_positive("gamma", gamma), check_positive("omega", omega)
    n = check_odd_order(n)
    chunk = check_int("chunk", chunk, 1)
    t0 = time.perf_counter()
    results = [None] * len(targets)
    for case in ("collocated", "noncollocated"):
        idx = [k for k, t in enumerate(targets) if t.case == case]
        if not idx:
            continue
        res, evaluated = _certify_case(case, [targets[k] for k in idx], grid=grid,
                                       levels=levels, width=width, gamma=gamma, omega=omega,
                                       n=n, chunk=chunk, keep_leaves=keep_leaves)
        for k, r in zip(idx, res):
            results[k] = (r, evaluated)
    dt = time.perf_counter() - t0
    return [CertifiedShare(targets[k], grid, levels, cnt, bas, ev, stop, dt, leaves)
            for k, ((cnt, bas, stop, leaves), ev) in enumerate(results)]


#: ``mu`` of the limit ``mu -> 0`` (the point the maps of :mod:`hybridpd.reproduce.params`
#: check the derived limit at).
MU_LIMIT = 1e-4


def reading_values(settings) -> list:
    """The values of ``m2`` at which the printed gain box is read: :attr:`Settings.m2_verdicts`
    log-spaced points of :attr:`Settings.m2_range` (``1`` snapped to exactly 1)."""
    lo, hi = settings.m2_range
    v = np.logspace(np.log10(lo), np.log10(hi), settings.m2_verdicts)
    return [1.0 if abs(x - 1.0) < 1e-9 else float(x) for x in v]


def study_values(settings, name) -> list:
    """The values of the ``mu`` or ``gamma`` study (:attr:`Settings.param_points` log-spaced
    values of its range, as :func:`~hybridpd.reproduce.params.param_study` computes them)."""
    lo, hi = settings.mu_range if name == "mu" else settings.gamma_range
    return [float(v) for v in np.logspace(np.log10(lo), np.log10(hi), settings.param_points)]


def _is_paper_mu(mu) -> bool:
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.settings import PAPER

    return abs(mu / PAPER["mu"] - 1.0) < 1e-9


#: The groups of :func:`reproduction_shares`.
GROUPS = ("main", "limit", "mu_ends", "readings", "mu_moves", "mu_values", "gamma_values")


def _groups(settings, cases) -> dict:
    """``{group: (targets, (grid, levels, width))}`` (see :func:`reproduction_shares`)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.settings import PAPER

    es = [float(e) for e in PAPER["e"]]
    mu0 = PAPER["mu"]
    es_only, ex_only = ("exists_stable",), ("exists",)
    moves = {(c, e): mu_move_values(settings, c, e) for c in cases for e in es}
    every = settings.certify_every_value
    # values certified by another group already: the ends, the paper's mu (the main box,
    # whose cells serve both), the values of the largest sampled move
    taken = lambda c, e, m: (m in settings.mu_range or _is_paper_mu(m) or m in moves[(c, e)])
    return {
        "main": ([ShareTarget(c, e, mu0, properties=PROPERTIES, key=(c, e)) for c in cases
                  for e in es], settings.certified),
        "limit": ([ShareTarget(c, e, MU_LIMIT, properties=es_only, key=(c, e)) for c in cases
                   for e in es], settings.certified_ends),
        "mu_ends": ([ShareTarget(c, e, m, properties=ex_only, key=(c, e, m)) for c in cases
                     for e in es for m in settings.mu_range], settings.certified_ends),
        "readings": ([ShareTarget(c, e, mu0, m2, properties=es_only, key=(c, e, m2))
                      for c in cases for e in es for m2 in reading_values(settings)
                      if m2 != 1.0], settings.certified_readings),
        "mu_moves": ([ShareTarget(c, e, m, properties=ex_only, key=(c, e, m)) for c in cases
                      for e in es for m in moves[(c, e)]
                      if m not in settings.mu_range and not _is_paper_mu(m)],
                     settings.certified_ends),
        "mu_values": ([ShareTarget(c, e, m, properties=ex_only, key=(c, e, m)) for c in cases
                       for e in es for m in study_values(settings, "mu")
                       if every and not taken(c, e, m)], settings.certified_values),
        "gamma_values": ([ShareTarget(c, e, mu0, properties=es_only, key=(c, e, g), gamma=g)
                          for c in cases for e in es for g in study_values(settings, "gamma")
                          if every], settings.certified_values)}


def reproduction_shares(settings, cases=("collocated", "noncollocated"), groups=None) -> dict:
    """Every certified share the reproduction's verdicts need, for ``cases``.

    * ``"main"``: the scaled box (``kp/m2``, ``kv/m2`` in ``[0.1, 50]``) at the paper's
      ``mu``, every ``e``, refined until every class (:data:`PROPERTIES`) is within the
      width (:attr:`Settings.certified`); conclusions 1-3, the ``m2 = 1`` reading, and the
      ``mu`` study at the paper's ``mu``;
    * ``"limit"``: the same box at ``mu = 1e-4`` (the remark ``mu -> 0``;
      :attr:`Settings.certified_ends`);
    * ``"mu_ends"``: existence at both ends of :attr:`Settings.mu_range` (the remark on
      existence against ``mu``; :attr:`Settings.certified_ends`);
    * ``"readings"``: the printed box read at every other value of :func:`reading_values`
      (:attr:`Settings.certified_readings`);
    * ``"mu_moves"``: existence at the two values of ``mu`` between which the sampled share
      rises most (:func:`mu_move_values`; the largest move against the remark's trend,
      certified so that the remark can report it; :attr:`Settings.certified_ends`);
    * ``"mu_values"``, ``"gamma_values"`` (with :attr:`Settings.certify_every_value`):
      existence at every other value of the ``mu`` study, existence and stability at every
      value of the ``gamma`` study (:func:`study_values`; :attr:`Settings.certified_values`).

    ``groups`` (a subset of :data:`GROUPS`, default all) lets the groups run in separate
    processes.

    Returns
    -------
    dict
        ``{group: {key: CertifiedShare}}`` with keys ``(case, e)``, ``(case, e, mu)``,
        ``(case, e, m2)`` and ``(case, e, gamma)``, and ``"seconds"``/``"cpu_seconds"`` per
        group.
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.settings import PAPER

    groups = GROUPS if groups is None else tuple(groups)
    bad = [g for g in groups if g not in GROUPS]
    if bad:
        raise ValueError(f"groups must be a subset of {GROUPS}, got {bad!r}")
    common = dict(gamma=settings.gamma, omega=PAPER["omega"], n=PAPER["n"])
    out = {"seconds": {}, "cpu_seconds": {}}
    for name, (targets, cfg) in _groups(settings, cases).items():
        if name not in groups:
            continue
        t0, c0 = time.perf_counter(), time.process_time()
        cfg = dict(zip(("grid", "levels", "width"), cfg))
        res = certified_shares(targets, **cfg, **common) if targets else []
        out[name] = {t.key: r for t, r in zip(targets, res)}
        out["seconds"][name] = time.perf_counter() - t0
        out["cpu_seconds"][name] = time.process_time() - c0
    return out


def mu_move_values(settings, case, e) -> tuple:
    """The values ``(mu_i, mu_j)``, ``i < j``, of the studied range between which the
    existence share of the scaled box rises most, sampled (:attr:`Settings.param_points`
    values, a :attr:`Settings.param_grid` square grid of gains), or ``()`` where it never
    rises: where the remark "the existence region tends to shrink as mu grows" would be
    contradicted locally, to be certified.

    Examples
    --------
    >>> from dataclasses import replace
    >>> from hybridpd.reproduce import Settings
    >>> from hybridpd.reproduce.certified import mu_move_values
    >>> s = replace(Settings.quick(), param_points=9, param_grid=9)
    >>> m = mu_move_values(s, "noncollocated", 0.5)
    >>> len(m) in (0, 2) and all(s.mu_range[0] <= v <= s.mu_range[1] for v in m)
    True
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.params import param_shares
    from hybridpd.reproduce.settings import PAPER

    lo, hi = settings.mu_range
    vals = np.logspace(np.log10(lo), np.log10(hi), settings.param_points)
    g = settings.param_grid
    fixed = dict(mu=PAPER["mu"], gamma=settings.gamma, x10=settings.x10, m2=1.0,
                 omega=PAPER["omega"], n=PAPER["n"])
    share = param_shares(case, "mu", vals, np.linspace(0.1, settings.gains[0], g),
                         np.linspace(0.1, settings.gains[1], g), e=[e], fixed=fixed)["exists"][0]
    best, pair = 0.0, ()
    for i in range(vals.size):
        j = i + int(np.argmax(share[i:]))
        if share[j] - share[i] > best:
            best, pair = share[j] - share[i], (float(vals[i]), float(vals[j]))
    return pair


def merge_shares(parts) -> dict:
    """One :func:`reproduction_shares` dict from several (e.g. one per case, computed in
    parallel); times add up."""
    out = {"seconds": {}, "cpu_seconds": {}}
    for p in parts:
        for k, v in p.items():
            if k in ("seconds", "cpu_seconds"):
                for g, s in v.items():
                    out[k][g] = out[k].get(g, 0.0) + s
            else:
                out.setdefault(k, {}).update(v)
    return out
