"""The vectorised proofs behind :mod:`hybridpd.pair.certified`: many parameter boxes at once.

A box gives every scaled parameter ``kpt = kp/m2``, ``kvt = kv/m2``, ``mu``, ``e``,
``gam = L/x10``, ``w = omega`` an interval (``x10 = 1``, ``m2 = 1`` after scaling; the
symmetric orbit depends on nothing else). For one feedback case and odd order ``n`` each box is
classified by three proofs, all in the outward-rounded arithmetic of
:mod:`hybridpd.pair.intervals` on the closed forms of :mod:`hybridpd.pair.interval_kernels`,
through second-order centred forms (:class:`~hybridpd.pair.centred.CForm2`) over the box:

1. **Existence.** ``det M`` of (13)-(14) and ``xm^2 = C^2 + S^2`` are enclosed away from 0.
2. **Viability** (:func:`viability`). The flight ``t = s tau``, ``s`` in ``[0, 1]``, is cut
   into pieces; on a piece the gap ``z3`` and its derivatives are enclosed by first-order
   centred forms in the parameters *and* ``s``. An interior piece is proved when
   ``-L < z3 < L`` on it. The first piece starts at the impact, ``z3(0) = L`` exactly, with
   ``z3'(0) = -e z4- <= 0``: it is proved by ``z3' < 0``, by ``z3'' < 0``, or by the Taylor
   bound ``L - z3(t) >= t (e z4- - max(z3'') t / 2) > 0``; the last piece likewise from
   ``z3(tau) = -L`` and ``z3'(tau) = -z4- < 0``. Pieces that fail are bisected. A
   violation is proved by a time ``s*`` (a piece's midpoint) at which ``|z3| > L`` for
   every parameter of the box.
3. **Stability.** With ``M = diag(1, -1, -1, -1) DP21 DP10`` the Jacobian of the half map,
   ``DP = M^2`` (:func:`hybridpd.pair.interval_kernels.halfmap_exprs`), so ``rho(DP) < 1``
   iff ``rho(M) < 1``. The characteristic polynomial ``p`` of ``M`` is mapped by
   ``lambda = (1 + w)/(1 - w)`` to ``q(w) = (1 - w)^4 p((1 + w)/(1 - w))``; all roots of
   ``p`` lie in the open unit disc iff ``q`` is Hurwitz, i.e. (Lienard-Chipart, degree 4)
   ``q_0, ..., q_4 > 0`` and ``Delta_3 = q_3 q_2 q_1 - q_1^2 q_4 - q_3^2 q_0 > 0``. All six
   enclosed above 0 proves stability. The six are continuous in the coefficients and
   positive on Schur-stable polynomials, hence ``>= 0`` on their closure, the polynomials
   with every root in the closed disc: one of them enclosed below 0 proves a root of
   modulus > 1.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hybridpd.pair.centred import INTERVAL_OPS, Box, CForm2
from hybridpd.pair.interval_kernels import interval_kernel
from hybridpd.pair.intervals import EmptyIntersectionError, Interval, widen_down, widen_up
from hybridpd.pair.selftest import require_libm

__all__ = ["CELL_STOPS", "CLASSES", "REASONS", "SCALED", "Boxes", "classify", "classify_bisect", "viability"]

#: Class codes (CF flag values) and their names.
CLASSES = ("undecided", "proved_stable", "proved_unstable", "proved_no_orbit")
UNDECIDED, STABLE, UNSTABLE, NO_ORBIT = range(4)

#: Reason codes of a classification.
REASONS = (
    "exists, viable and stable on the whole box",
    "exists, viable and unstable on the whole box",
    "viability violated on the whole box: an extra contact between the impacts",
    "undecided: det of (13)-(14) or xm = hypot(C, S) not enclosed away from 0",
    "undecided: viability (the gap's enclosure reaches a wall: grazing nearby)",
    "undecided: stability (a multiplier's modulus may equal 1)",
    "undecided: parts of the box proved in different classes",
    ("undecided: two enclosures of one quantity did not meet (an arithmetic fault; "
    "nothing proved)"),
)
R_STABLE, R_UNSTABLE, R_VIOLATED, R_EXIST, R_VIAB, R_STAB, R_MIXED, R_EMPTY = \
    range(len(REASONS))

#: Why the subdivision of a cell stopped: proved (all its parts in one class), two parts
#: proved in different classes, an undecided part at the depth bound, the cell's budget of
#: parts spent, the round's bound on boxes reached.
CELL_STOPS = ("proved", "mixed", "depth", "budget", "max_boxes")
STOP_PROVED, STOP_MIXED, STOP_DEPTH, STOP_BUDGET, STOP_MAX_BOXES = range(len(CELL_STOPS))

#: The scaled parameters of a box, in the kernels' argument order.
SCALED = ("kpt", "kvt", "mu", "e", "gam", "w")

# q_j = sum_k c_k T[j][k]: coefficient of w^j in (1 + w)^k (1 - w)^(4 - k)
_T = [[int(np.polynomial.polynomial.polymul(
    np.polynomial.polynomial.polypow([1, 1], k),
    np.polynomial.polynomial.polypow([1, -1], 4 - k))[j]) for k in range(5)] for j in range(5)]


@dataclass(frozen=True)
class Boxes:
    """Arrays of parameter boxes: ``lo[name]``, ``hi[name]`` for every name of :data:`SCALED`.

    Every array has the same shape ``(N,)``.
    """

    lo: dict
    hi: dict

    @property
    def size(self) -> int:
        """Number of boxes."""
        return int(np.asarray(self.lo["kpt"]).size)

    def take(self, idx) -> Boxes:
        """The boxes at ``idx``."""
        return Boxes({k: v[idx] for k, v in self.lo.items()},
                     {k: v[idx] for k, v in self.hi.items()})

    def directions(self):
        """The names of the parameters with a positive width in some box."""
        return [k for k in SCALED if np.any(self.hi[k] > self.lo[k])]

    def bisect(self, ref_width) -> Boxes:
        """Halve every box along its widest parameter (width relative to ``ref_width``).

        Returns the ``2 N`` halves, lower halves first.
        """
        rel = np.stack([(self.hi[k] - self.lo[k]) / np.where(ref_width[k] > 0, ref_width[k], 1)
                        for k in SCALED])
        dim = np.argmax(rel, axis=0)
        lo1, hi1 = dict(self.lo), dict(self.hi)
        lo2, hi2 = dict(self.lo), dict(self.hi)
        for j, k in enumerate(SCALED):
            m = np.clip(0.5 * self.lo[k] + 0.5 * self.hi[k], self.lo[k], self.hi[k])
            hi1[k] = np.where(dim == j, m, self.hi[k])
            lo2[k] = np.where(dim == j, m, self.lo[k])
        return Boxes({k: np.concatenate([lo1[k], lo2[k]]) for k in SCALED},
                     {k: np.concatenate([hi1[k], hi2[k]]) for k in SCALED})


def _forms(boxes: Boxes, dirs, order, extra=()):
    """Centred forms of the scaled parameters over the boxes (``extra`` directions after)."""
    box, centres = Box.from_bounds([(boxes.lo[k], boxes.hi[k]) for k in dirs] + list(extra))
    out = {}
    for k in SCALED:
        lo, hi = boxes.lo[k], boxes.hi[k]
        if k in dirs:
            i = dirs.index(k)
            out[k] = box.variable(i, lo, hi, centres[i], order=order)
        else:
            out[k] = box.constant(Interval(lo, hi), order=order)
    return out, box, centres


def _args(P):
    return [P[k] for k in SCALED]


def _charpoly(m):
    """Coefficients ``c0..c3`` of ``det(lambda I - M)`` (monic) from the 16 entries."""
    M = [m[4 * i:4 * i + 4] for i in range(4)]
    c3 = -(M[0][0] + M[1][1] + M[2][2] + M[3][3])
    c2 = None
    for i in range(4):
        for j in range(i + 1, 4):
            t = M[i][i] * M[j][j] - M[i][j] * M[j][i]
            c2 = t if c2 is None else c2 + t
    minor = {}
    for i in range(4):
        for j in range(i + 1, 4):
            for a in range(4):
                for b in range(a + 1, 4):
                    minor[i, j, a, b] = M[i][a] * M[j][b] - M[i][b] * M[j][a]
    c1 = None
    for tri in ((0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)):
        i, j, k = tri
        d = (M[i][i] * minor[j, k, j, k] - M[i][j] * minor[j, k, i, k]
             + M[i][k] * minor[j, k, i, j])
        c1 = -d if c1 is None else c1 - d
    c0 = None
    for a, b in ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)):
        ca, cb = (x for x in range(4) if x not in (a, b))
        sign = (-1) ** (a + b + 1)
        t = minor[0, 1, a, b] * minor[2, 3, ca, cb] * sign
        c0 = t if c0 is None else c0 + t
    return [c0, c1, c2, c3]


def hurwitz_quantities(entries):
    """``q_0..q_4`` and ``Delta_3`` of the bilinear image of ``M``'s characteristic polynomial.

    All positive iff every eigenvalue of ``M`` has modulus < 1 (see the module docstring).

    Parameters
    ----------
    entries : sequence of 16 numbers, intervals or centred forms
        ``M`` row by row.

    Examples
    --------
    >>> import numpy as np
    >>> from hybridpd.pair.intervals import Interval
    >>> from hybridpd.pair.proofs import hurwitz_quantities
    >>> M = np.diag([0.5, -0.9, 0.2, 0.0]) + 0.05
    >>> all(q.lo > 0 for q in hurwitz_quantities([Interval(v) for v in M.ravel()]))
    True
    """
    return _hurwitz(_charpoly(entries))


def _power_sums(c, kmax=8):
    """``p_k = tr(M^k) = sum_i lambda_i^k``, ``k = 1..kmax``, by Newton's identities."""
    p = []
    for k in range(1, kmax + 1):
        acc = c[4 - k] * k if k <= 4 else None
        for j in range(1, min(k, 5)):
            t = c[4 - j] * p[k - j - 1]
            acc = t if acc is None else acc + t
        p.append(-acc)
    return p


def escape_quantities(entries):
    """Quantities whose modulus exceeds a bound only if some eigenvalue has modulus > 1.

    Returns ``[(x, bound)]``: the coefficients ``c_k`` of the characteristic polynomial
    (``|c_k| <= C(4, k)`` when every ``|lambda| <= 1``) and the power sums ``tr(M^k)``,
    ``k = 1..8`` (``<= 4``). With the bilinear test they cover strongly unstable orbits,
    whose widely spread multipliers make ``Delta_3`` nearly cancel.
    """
    c = _charpoly(entries)
    out = [(c[k], float(_BINOM[k])) for k in range(4)]
    return out + [(p, 4.0) for p in _power_sums(c)]


_BINOM = (1, 4, 6, 4)


def _hurwitz(c):
    c = list(c) + [1]
    q = []
    for j in range(5):
        acc = None
        for k in range(5):
            if _T[j][k] == 0:
                continue
            t = c[k] * _T[j][k]
            acc = t if acc is None else acc + t
        q.append(acc)
    d3 = q[3] * q[2] * q[1] - q[1] * q[1] * q[4] - q[3] * q[3] * q[0]
    return q + [d3]


def _orbit_stage(case, n, boxes: Boxes, dirs):
    """Existence and stability verdicts, and the first-order forms of ``C``, ``S``."""
    P, box, _ = _forms(boxes, dirs, 2)
    nI = Interval(float(n))
    C, S, det = interval_kernel("existence", case)(INTERVAL_OPS, *_args(P), nI)
    M = interval_kernel("halfmap", case)(INTERVAL_OPS, C, S, *_args(P), nI)
    c = _charpoly(M)
    apart = lambda x: (x.r.lo > 0) | (x.r.hi < 0)
    exists = apart(det) & (apart(C) | apart(S))
    stable = np.ones(boxes.size, bool)
    unstable = np.zeros(boxes.size, bool)
    for j in _hurwitz(c):
        stable &= j.r.lo > 0
        unstable |= j.r.hi < 0
    for x, bound in [(c[k], float(_BINOM[k])) for k in range(4)] + \
            [(p, 4.0) for p in _power_sums(c)]:
        unstable |= (x.r.lo > bound) | (x.r.hi < -bound)
    return exists, stable, unstable, C, S, box


def _impact_speed(boxes: Boxes, n):
    """Enclosures of ``z4- = 2 v (1 + mu)/(1 + e)`` (``v = 2 w/(n pi)``) and ``tau = n pi/w``."""
    e = Interval(boxes.lo["e"], boxes.hi["e"])
    mu = Interval(boxes.lo["mu"], boxes.hi["mu"])
    w = Interval(boxes.lo["w"], boxes.hi["w"])
    pi = INTERVAL_OPS.PI
    v = w * 2 / (pi * float(n))
    z4 = v * 2 * (mu + 1) / (e + 1)
    return z4, e * z4, pi * float(n) / w


def _piece_tests(z3, z3d, z3dd, gam, a, b, z4, ez4, tau):
    """Which pieces ``[a, b]`` of the flight are proved inside the walls."""
    gp = gam - z3
    gm = z3 + gam
    L = Interval(gam.r.lo, gam.r.hi)
    inside = (gp.r.lo > 0) & (gm.r.lo > 0)
    h = tau * b  # longest time from the first impact within the piece
    up = Interval(np.maximum(z3dd.r.hi, 0.0))
    down = Interval(np.minimum(z3dd.r.lo, 0.0))
    first_wall = (z3d.r.hi < 0) | (z3dd.r.hi < 0) | ((ez4 - up * h * 0.5).lo > 0)
    first_far = (gm.r.lo > 0) | ((L * 2 - ez4 * h + down * (h * h) * 0.5).lo > 0)
    sig = tau * (1 - a)  # longest time to the second impact within the piece
    last_wall = (z3d.r.hi < 0) | (z3dd.r.lo > 0) | ((z4 + down * sig * 0.5).lo > 0)
    last_far = (gp.r.lo > 0) | ((L * 2 - z4 * sig - up * (sig * sig) * 0.5).lo > 0)
    first, last = a == 0, b == 1
    return np.where(first, first_wall & first_far, np.where(last, last_wall & last_far, inside))


def _gap_forms(case, n, boxes, dirs, C1, S1, idx, s_lo, s_hi, s_point=False):
    """Centred forms of ``z3, z3', z3''`` and ``gam`` on pieces ``[s_lo, s_hi]``."""
    sub = boxes.take(idx)
    extra = [] if s_point else [(s_lo, s_hi)]
    order = 2 if isinstance(C1, CForm2) else 1
    P, box, centres = _forms(sub, dirs, order, extra)
    if s_point:
        s = box.constant(Interval(s_lo), order=order)
    else:
        s = box.variable(len(dirs), s_lo, s_hi, centres[-1], order=order)
    C, S = C1.take(idx).on(box), S1.take(idx).on(box)
    z3, z3d, z3dd = interval_kernel("gap", case)(INTERVAL_OPS, s, C, S, *_args(P), Interval(float(n)))
    return z3, z3d, z3dd, P["gam"]


_SPLIT_SHARE = 0.25
_CHUNK = 16384  # pieces per evaluation: the bound arrays stay in cache


def _witness(case, n, boxes, dirs, C, S, owner, s, verdict):
    """Mark ``verdict = -1`` where ``|z3(s)| > L`` on the whole box (``s`` a point time)."""
    w3, _, _, wg = _gap_forms(case, n, boxes, dirs, C, S, owner, s, s, s_point=True)
    hit = ((wg - w3).r.hi < 0) | ((w3 + wg).r.hi < 0)
    verdict[owner[hit]] = -1


def _round_chunk(case, n, boxes, dirs, C, S, owner, a, b, z4, ez4, tau, verdict):
    """Test one chunk of pieces; record proved violations in ``verdict`` (-1).

    First-order forms first (cheap, enough for most pieces), second-order forms for the
    pieces they leave; a failed interior piece looks for a violation at its midpoint, with
    first- and then second-order forms. Returns the pieces' verdicts (proved inside the
    walls) and the share of the width of ``z3``'s enclosure due to time (the split
    criterion).
    """
    ends = (z4.take(owner), ez4.take(owner), tau.take(owner))
    inner = (a > 0) & (b < 1)
    C1, S1 = C.first_order(), S.first_order()
    z3, z3d, z3dd, gam = _gap_forms(case, n, boxes, dirs, C1, S1, owner, a, b)
    ok = _piece_tests(z3, z3d, z3dd, gam, a, b, *ends)
    share = np.ones(owner.size)
    for order2 in (False, True):
        look = ~ok & inner & (verdict[owner] != -1)
        if np.any(look):
            _witness(case, n, boxes, dirs, C if order2 else C1, S if order2 else S1,
                     owner[look], 0.5 * (a[look] + b[look]), verdict)
        if order2:
            break
        bad = np.flatnonzero(~ok & (verdict[owner] != -1))
        if bad.size:
            o, lo, hi = owner[bad], a[bad], b[bad]
            z3, z3d, z3dd, gam = _gap_forms(case, n, boxes, dirs, C, S, o, lo, hi)
            ok[bad] = _piece_tests(z3, z3d, z3dd, gam, lo, hi, *(x.take(bad) for x in ends))
            share[bad] = _time_share(z3)
    return ok, share


def _time_share(z3):
    """Share of the width of ``z3``'s enclosure due to the time direction (the last one)."""
    gs = z3.g[-1]
    if gs is None:
        return np.zeros(z3.r.lo.shape)
    ds = z3.box.delta[-1]
    with np.errstate(invalid="ignore", divide="ignore"):
        share = gs.mag() * (ds.hi - ds.lo) / (z3.r.hi - z3.r.lo)
    return np.nan_to_num(share, nan=1.0)


def viability(case, n, boxes: Boxes, dirs, C1, S1, *, pieces=8, depth=10):
    """Prove or refute viability (18) on every box; ``+1`` viable, ``-1`` violated, ``0``.

    Parameters
    ----------
    case : str
    n : int
    boxes : Boxes
    dirs : list of str
        The directions of the centred forms ``C1``, ``S1``.
    C1, S1 : CForm2
        Second-order forms of ``C``, ``S`` over the boxes.
    pieces : int
        Initial number of pieces of the flight.
    depth : int
        Bisections of a piece at most (the smallest piece is ``2^-depth / pieces``).

    Returns
    -------
    verdict : ndarray of int, shape (N,)
    pieces_used : int
        Number of piece evaluations (the work done).
    """
    N = boxes.size
    verdict = np.zeros(N, np.int64)
    failed = np.zeros(N, bool)
    z4, ez4, tau = _impact_speed(boxes, n)
    owner = np.repeat(np.arange(N), pieces)
    j = np.tile(np.arange(pieces), N)
    a, b = j / pieces, (j + 1) / pieces
    level = np.zeros(owner.size, np.int64)
    used = 0
    for _round in range(depth + 1):
        if owner.size == 0:
            break
        used += owner.size
        ok = np.empty(owner.size, bool)
        share = np.empty(owner.size)
        for c in range(0, owner.size, _CHUNK):
            sl = slice(c, c + _CHUNK)
            ok[sl], share[sl] = _round_chunk(case, n, boxes, dirs, C1, S1, owner[sl], a[sl],
                                             b[sl], z4, ez4, tau, verdict)
        bad = ~ok
        # splitting a piece helps only where time, not the parameters, makes the enclosure wide
        ends = (a == 0) | (b == 1)
        keep = bad & (verdict[owner] != -1) & (ends | (share > _SPLIT_SHARE))
        failed[owner[bad & ~keep & (verdict[owner] != -1)]] = True
        exhausted = keep & (level >= depth)
        failed[owner[exhausted]] = True
        keep &= ~exhausted & ~failed[owner]
        o, lo, hi, lv = owner[keep], a[keep], b[keep], level[keep]
        mid = 0.5 * (lo + hi)
        owner = np.concatenate([o, o])
        a, b = np.concatenate([lo, mid]), np.concatenate([mid, hi])
        level = np.concatenate([lv, lv]) + 1
    failed[owner] = True  # pieces left when the rounds ran out
    verdict[(verdict == 0) & ~failed] = 1
    return verdict, used


def classify(case, n, boxes: Boxes, *, pieces=8, depth=10, details=False):
    """Class (:data:`CLASSES` index) and reason (:data:`REASONS` index) of every box.

    With ``details`` also a dict of the parts of the proof per box: ``exists`` (bool),
    ``viable`` (+1 proved, -1 violated, 0 undecided; 0 where existence is not proved),
    ``stable`` and ``unstable`` (bool).

    Examples
    --------
    >>> from hybridpd.pair.proofs import CLASSES, classify, scaled_boxes
    >>> boxes, _ = scaled_boxes(kp=(9.9, 10.1), kv=(19.9, 20.1), mu=0.1, e=0.5, gamma=0.75,
    ...                         omega=5.0, m2=1.0)
    >>> cls, why = classify("noncollocated", 1, boxes)
    >>> CLASSES[int(cls[0])]
    'proved_unstable'

    Certification first runs the self-test of NumPy's elementary functions
    (:func:`hybridpd.pair.selftest.require_libm`, once per process) and refuses to run
    (:class:`~hybridpd.pair.selftest.LibmSelfTestError`) where it fails. Boxes whose
    evaluation meets an empty intersection of two enclosures
    (:class:`~hybridpd.pair.intervals.EmptyIntersectionError`) are undecided (reason
    :data:`R_EMPTY`); the batch is halved until they are isolated.
    """
    require_libm()
    try:
        cls, why, parts = _classify(case, n, boxes, pieces, depth)
    except EmptyIntersectionError:
        cls, why, parts = _classify_apart(case, n, boxes, pieces, depth)
    if details:
        return cls, why, parts
    return cls, why


def _classify_apart(case, n, boxes: Boxes, pieces, depth):
    """:func:`_classify` on halves of the batch; a single failing box is undecided."""
    N = boxes.size
    if N == 1:
        no = np.zeros(1, bool)
        return (np.full(1, UNDECIDED, np.int64), np.full(1, R_EMPTY, np.int64),
                {"exists": no, "viable": np.zeros(1, np.int64), "stable": no.copy(),
                 "unstable": no.copy()})
    out = []
    for idx in (np.arange(N // 2), np.arange(N // 2, N)):
        part = boxes.take(idx)
        try:
            out.append(_classify(case, n, part, pieces, depth))
        except EmptyIntersectionError:
            out.append(_classify_apart(case, n, part, pieces, depth))
    (c1, w1, p1), (c2, w2, p2) = out
    return (np.concatenate([c1, c2]), np.concatenate([w1, w2]),
            {k: np.concatenate([p1[k], p2[k]]) for k in p1})


def _classify(case, n, boxes: Boxes, pieces, depth):
    """The classes, reasons and parts of :func:`classify` (may raise an empty intersection)."""
    dirs = boxes.directions()
    exists, stable, unstable, C, S, _ = _orbit_stage(case, n, boxes, dirs)
    cls = np.zeros(boxes.size, np.int64)
    why = np.full(boxes.size, R_EXIST, np.int64)
    viable = np.zeros(boxes.size, np.int64)
    idx = np.flatnonzero(exists)
    if idx.size:
        v, _ = viability(case, n, boxes.take(idx), dirs, C.take(idx), S.take(idx),
                         pieces=pieces, depth=depth)
        viable[idx] = v
        st, un = stable[idx], unstable[idx]
        cls[idx] = np.select([v < 0, v == 0, st, un], [NO_ORBIT, UNDECIDED, STABLE, UNSTABLE],
                             UNDECIDED)
        why[idx] = np.select([v < 0, v == 0, st, un], [R_VIOLATED, R_VIAB, R_STABLE, R_UNSTABLE],
                             R_STAB)
    return cls, why, {"exists": exists, "viable": viable, "stable": stable,
                      "unstable": unstable}


def classify_bisect(case, n, boxes: Boxes, *, depth=4, pieces=8, flight_depth=10,
                    max_boxes=200_000):
    """:func:`classify`, then bisect undecided boxes (widest relative parameter) ``depth`` times.

    A box is proved in a class when all its parts are; parts proved in different classes make
    it undecided (reason "parts ... in different classes").

    Returns
    -------
    cls, why : ndarray of int, shape (N,)
    evaluated : int
        Number of boxes classified (the original ones and all their parts).
    stop : str
        ``"decided"`` (nothing left to bisect), ``"depth"`` or ``"max_boxes"``.
    """
    N = boxes.size
    ref = {k: boxes.hi[k] - boxes.lo[k] for k in SCALED}
    cls = np.zeros(N, np.int64)
    why = np.zeros(N, np.int64)
    agreed = np.full(N, -1, np.int64)   # the class every decided part has so far (-1: none)
    mixed = np.zeros(N, bool)
    open_ = np.zeros(N, bool)           # some part still undecided
    owner = np.arange(N)
    cur = boxes
    evaluated = 0
    stop = "decided"
    for level in range(depth + 1):
        c, w = classify(case, n, cur, pieces=pieces, depth=flight_depth)
        evaluated += cur.size
        if level == 0:
            cls, why = c.copy(), w.copy()
        dec = c != UNDECIDED
        for o, cc in zip(owner[dec], c[dec]):
            if agreed[o] == -1:
                agreed[o] = cc
            elif agreed[o] != cc:
                mixed[o] = True
        und = ~dec & ~mixed[owner]
        open_[:] = False
        open_[owner[und]] = True
        last_why = np.full(N, -1, np.int64)
        last_why[owner[und]] = w[und]
        if not np.any(und):
            break
        if level == depth:
            stop = "depth"
            break
        if 2 * int(und.sum()) > max_boxes:
            stop = "max_boxes"
            break
        sub = cur.take(np.flatnonzero(und))
        owner = np.concatenate([owner[und], owner[und]])
        cur = sub.bisect({k: ref[k][owner[: sub.size]] for k in SCALED})
    done = (agreed >= 0) & ~mixed & ~open_
    cls = np.where(done, agreed, UNDECIDED)
    why = np.where(done, np.select([agreed == STABLE, agreed == UNSTABLE], [R_STABLE, R_UNSTABLE],
                                   R_VIOLATED),
                   np.where(mixed, R_MIXED, np.where(last_why >= 0, last_why, why)))
    return cls, why, evaluated, stop


def scaled_boxes(*, kp, kv, mu, e, gamma, omega, m2):
    """:class:`Boxes` from ``(lo, hi)`` pairs (or floats) of the physical parameters.

    ``kpt = kp/m2`` and ``kvt = kv/m2`` are enclosed with outward rounding; arrays broadcast.
    """
    pairs = {}
    for name, v in (("kp", kp), ("kv", kv), ("mu", mu), ("e", e), ("gamma", gamma),
                    ("omega", omega), ("m2", m2)):
        lo, hi = (v if isinstance(v, tuple) else (v, v))
        pairs[name] = (np.asarray(lo, float), np.asarray(hi, float))
    shape = np.broadcast_shapes(*(np.shape(x) for p in pairs.values() for x in p))
    b = {k: (np.broadcast_to(lo, shape).ravel().copy(), np.broadcast_to(hi, shape).ravel().copy())
         for k, (lo, hi) in pairs.items()}
    m2lo, m2hi = b["m2"]
    lo, hi = {}, {}
    for name, src in (("kpt", "kp"), ("kvt", "kv")):
        a, c = b[src]
        point = (m2lo == 1.0) & (m2hi == 1.0)
        lo[name] = np.where(point, a, widen_down(a / m2hi))
        hi[name] = np.where(point, c, widen_up(c / m2lo))
    for name, src in (("mu", "mu"), ("e", "e"), ("gam", "gamma"), ("w", "omega")):
        lo[name], hi[name] = b[src]
    return Boxes(lo, hi), shape
