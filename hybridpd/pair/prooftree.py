"""The certified classification with its proof tree: adaptive subdivision, sharper viability.

:func:`prove_cells` classifies many boxes (cells) at once, like
:func:`hybridpd.pair.proofs.classify_bisect`, in the same outward-rounded interval arithmetic
and second-order centred forms, and keeps what it proved: every decided sub-box (*leaf*) of
every proved cell with its class and the enclosures that decided it (:class:`ProofTree`), so
that the proof can be checked again in ``arb`` (:mod:`hybridpd.pair.arbcheck`) and written
to a certificate (:mod:`hybridpd.pair.certificate`). Three things differ from
:mod:`~hybridpd.pair.proofs`:

* **The damped functions.** ``exp(-a t) cosh(sqrt(D) t)`` and ``exp(-a t) sinh(sqrt(D) t) /
  sqrt(D)`` (``a = kv/2``, ``D = kv^2/4 - kp``) are enclosed in the general form (a decaying
  times a growing factor, whose product interval arithmetic overestimates) and, wherever
  ``D > 0`` on the box, in the overdamped form ``exp(-l1 t) (1 + exp(-2 r t)) / 2``
  (``r = sqrt(D)``, ``l1 = (a^2 - D)/(a + r)``), the two centred forms intersected component
  by component. :mod:`~hybridpd.pair.proofs` takes the overdamped form only where ``D`` is
  four of its own widths away from 0; on the coarse cells of the collocated stable region
  (``kv`` of 10 to 20) it is not, and the gap's enclosure is several ``L`` wide.
* **Monotonicity in the viability test.** The stable region's orbits come back to within
  0.3 to 2.5 % of ``L`` of the wall they left (at about a quarter of the flight), and over a
  coarse cell the gap varies by more than that; its enclosure is wide because of the
  *parameters*, not of the time, so cutting the flight into finer pieces cannot help. Where a
  piece fails, the gradient of the tested quantity (``L - z3`` or ``z3 + L``) over the box and
  the piece is looked at: in every direction (parameter or time) where its sign is proved, the
  minimum lies on one face, and the quantity is evaluated again on that face (a box of fewer
  directions, on which ``C``, ``S`` are enclosed anew). The minimum over the face is the
  minimum over the box, so the test stays exact.
* **Adaptive subdivision.** An undecided part is halved along the parameter that makes the
  deciding quantities widest (the failing quantity's gradient times the width, per direction),
  not the widest one; a cell is proved when all its parts are proved in one class, and stops
  as soon as two parts are proved in different classes (``mixed``). The depth and a budget of
  parts per cell bound the work.

What a leaf of each class proved, and what is recorded of it (:class:`ProofTree`):

* every class: existence, ``det M`` and one of ``C``, ``S`` enclosed away from 0;
* ``proved_stable``: the six Lienard-Chipart quantities enclosed above 0, and every piece of
  the flight proved inside the walls (the pieces and the test that proved each);
* ``proved_unstable``: one quantity beyond its bound (a Lienard-Chipart quantity below 0, a
  coefficient ``|c_k| > C(4, k)`` or a power sum ``|tr M^k| > 4``), and the pieces;
* ``proved_no_orbit``: a time ``s*`` of the flight at which ``L - z3 < 0`` or ``z3 + L < 0``.
"""
from __future__ import annotations

import types
from dataclasses import dataclass, field

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.pair import centred as _cf
from hybridpd.pair import intervals as _intervals
from hybridpd.pair import proofs
from hybridpd.pair.centred import INTERVAL_OPS, CForm, CForm2
from hybridpd.pair.interval_kernels import interval_kernel
from hybridpd.pair.intervals import Interval
from hybridpd.pair.proofs import (
    CELL_STOPS,
    NO_ORBIT,
    R_EXIST,
    R_MIXED,
    R_STAB,
    R_STABLE,
    R_UNSTABLE,
    R_VIAB,
    R_VIOLATED,
    SCALED,
    STABLE,
    STOP_BUDGET,
    STOP_DEPTH,
    STOP_MAX_BOXES,
    STOP_MIXED,
    STOP_PROVED,
    UNDECIDED,
    UNSTABLE,
    Boxes,
)


class _NeverRaised(ArithmeticError):
    """Stands for the empty-intersection error of an interval layer without that check."""


EmptyIntersectionError = getattr(_intervals, "EmptyIntersectionError", _NeverRaised)

#: Reason of a box whose enclosures met empty (an arithmetic fault; nothing proved).
R_EMPTY = getattr(proofs, "R_EMPTY", R_EXIST)

__all__ = ["CELL_STOPS", "PIECE_KINDS", "TIGHT_OPS", "UNSTABLE_KINDS", "ProofTree", "classify_record",
           "prove_cells"]

#: The tests of a piece of the flight: both walls from the gap's range, or the end pieces'.
PIECE_KINDS = ("inside", "first", "last")
#: The quantities that prove a multiplier outside the unit circle.
UNSTABLE_KINDS = ("hurwitz", "coeff", "trace")
_BINOM = (1.0, 4.0, 6.0, 4.0)


# ----------------------------------------------------------------------------------------
# The damped functions, in both forms
# ----------------------------------------------------------------------------------------


def _meet_iv(a, b):
    if a is None or b is None:
        return a if b is None else b
    return a.intersect(b)


def meet_forms(a, b):
    """Component-wise intersection of two enclosures (forms or intervals) of one quantity.

    Every component (value and gradient at the centre, Hessian and gradient over the box,
    range) of each form encloses the same exact quantity, so their intersections do too.
    """
    if isinstance(a, CForm2) and isinstance(b, CForm2):
        return CForm2(_meet_iv(a.c, b.c), tuple(map(_meet_iv, a.gc, b.gc)),
                      tuple(map(_meet_iv, a.H, b.H)), tuple(map(_meet_iv, a.g, b.g)),
                      _meet_iv(a.r, b.r), a.box)
    if isinstance(a, CForm) and isinstance(b, CForm):
        return CForm(_meet_iv(a.c, b.c), tuple(map(_meet_iv, a.g, b.g)), _meet_iv(a.r, b.r),
                     a.box)
    return _meet_iv(_cf._as_iv(a) if not isinstance(a, Interval) else a,
                    _cf._as_iv(b) if not isinstance(b, Interval) else b)


def _damped_both(a, D, t, which):
    """The general and (where ``D > 0``) the overdamped form of a damped function, met."""
    call = _cf._call
    u = D * call("pow", t, 2)
    e = call("exp", -(a * t))
    gen = e * call("cu", u) if which == "ch" else t * e * call("su", u)
    pos = _cf._range(D).lo > 0
    if not np.any(pos):
        return gen
    Ds = _cf.where(pos, D, 4.0)
    r = call("sqrt", Ds)
    l1 = (call("pow", a, 2) - Ds) / (a + r)
    e1 = call("exp", -(l1 * t))
    x = r * t * 2
    alt = e1 * (call("exp", -x) + 1) * 0.5 if which == "ch" else t * e1 * call("emq", x)
    return meet_forms(_cf.where(pos, alt, gen), gen)


#: :data:`hybridpd.pair.centred.INTERVAL_OPS` with the damped functions in both forms.
TIGHT_OPS = types.SimpleNamespace(**{
    **vars(INTERVAL_OPS), "DCH": lambda a, D, t: _damped_both(a, D, t, "ch"),
    "DSH": lambda a, D, t: _damped_both(a, D, t, "sh")})


# ----------------------------------------------------------------------------------------
# One round: classify boxes, record what decided them
# ----------------------------------------------------------------------------------------


def _lohi(x):
    r = x.r if isinstance(x, (CForm, CForm2)) else x
    return np.asarray(r.lo, float), np.asarray(r.hi, float)


def _sens(x, dirs, widths, N):
    """Per-direction share of the width of ``x``'s enclosure, shape ``(N, len(SCALED))``."""
    out = np.zeros((N, len(SCALED)))
    if not isinstance(x, (CForm, CForm2)):
        return out
    lo, hi = _lohi(x)
    with np.errstate(invalid="ignore", divide="ignore"):
        total = hi - lo
        for i, k in enumerate(dirs):
            g = x.g[i]
            if g is None or k not in SCALED:
                continue
            out[:, SCALED.index(k)] = np.nan_to_num(g.mag() * widths[k] / total, nan=0.0,
                                                    posinf=1.0)
    return out


def _orbit_stage(case, n, boxes: Boxes, dirs):
    """Existence and stability on every box, with the enclosures that decided them."""
    P, _, _ = proofs._forms(boxes, dirs, 2)
    nI = Interval(float(n))
    args = proofs._args(P)
    C, S, det = interval_kernel("existence", case)(TIGHT_OPS, *args, nI)
    M = interval_kernel("halfmap", case)(TIGHT_OPS, C, S, *args, nI)
    c = proofs._charpoly(M)
    N = boxes.size
    apart = lambda x: (x.r.lo > 0) | (x.r.hi < 0)
    margin = lambda x: np.maximum(x.r.lo, -x.r.hi) / np.maximum(x.r.hi - x.r.lo, 1e-300)
    aC, aS = apart(C), apart(S)
    exists = apart(det) & (aC | aS)
    with np.errstate(invalid="ignore"):
        use_S = aS & (~aC | (margin(S) > margin(C)))
    rec = {"det": _lohi(det), "xm_which": np.where(use_S, 1, 0),
           "xm": tuple(np.where(use_S, s, c_) for s, c_ in zip(_lohi(S), _lohi(C)))}
    H = proofs._hurwitz(c)
    hlo = np.stack([_lohi(h)[0] for h in H], axis=1)
    hhi = np.stack([_lohi(h)[1] for h in H], axis=1)
    stable = np.all(hlo > 0, axis=1)
    kind = np.full(N, -1, np.int64)
    idx = np.full(N, -1, np.int64)
    ulo = np.full(N, np.nan)
    uhi = np.full(N, np.nan)

    def mark(hit, k, j, lo, hi):
        new = hit & (kind < 0)
        kind[new], idx[new], ulo[new], uhi[new] = k, j, lo[new], hi[new]

    for j in range(6):
        mark(hhi[:, j] < 0, 0, j, hlo[:, j], hhi[:, j])
    for k in range(4):
        lo, hi = _lohi(c[k])
        mark((lo > _BINOM[k]) | (hi < -_BINOM[k]), 1, k, lo, hi)
    for k, p in enumerate(proofs._power_sums(c)):
        lo, hi = _lohi(p)
        mark((lo > 4.0) | (hi < -4.0), 2, k + 1, lo, hi)
    unstable = kind >= 0
    rec.update(hurwitz=(hlo, hhi), unstable_kind=kind, unstable_index=idx,
               unstable_value=(ulo, uhi))
    widths = {k: boxes.hi[k] - boxes.lo[k] for k in SCALED}
    sens = np.zeros((N, len(SCALED)))
    no_exist = ~exists
    if np.any(no_exist):
        s = _sens(det, dirs, widths, N) + _sens(C, dirs, widths, N) + _sens(S, dirs, widths, N)
        sens[no_exist] += s[no_exist]
    open_stab = exists & ~stable & ~unstable
    if np.any(open_stab):
        s = sum(_sens(h, dirs, widths, N) for h in H)
        sens[open_stab] += s[open_stab]
    return exists, stable, unstable, C, S, rec, sens


# -- viability ------------------------------------------------------------------------------


def _gap_forms(case, n, boxes, dirs, C1, S1, idx, s_lo, s_hi, s_point=False):
    """Centred forms of ``z3, z3', z3''`` and ``gam`` on pieces ``[s_lo, s_hi]``."""
    sub = boxes.take(idx)
    extra = [] if s_point else [(s_lo, s_hi)]
    order = 2 if isinstance(C1, CForm2) else 1
    P, box, centres = proofs._forms(sub, dirs, order, extra)
    if s_point:
        s = box.constant(Interval(s_lo), order=order)
    else:
        s = box.variable(len(dirs), s_lo, s_hi, centres[-1], order=order)
    C, S = C1.take(idx).on(box), S1.take(idx).on(box)
    z3, z3d, z3dd = interval_kernel("gap", case)(TIGHT_OPS, s, C, S, *proofs._args(P),
                                                 Interval(float(n)))
    return z3, z3d, z3dd, P["gam"]


class _Viability:
    """The viability proof of many boxes, with the record of its pieces and witnesses."""

    def __init__(self, case, n, boxes: Boxes, dirs, C, S, *, pieces, depth, witness_only):
        self.case, self.n, self.boxes, self.dirs, self.C, self.S = case, n, boxes, dirs, C, S
        self.C1, self.S1 = C.first_order(), S.first_order()
        N = boxes.size
        self.verdict = np.zeros(N, np.int64)
        self.failed = np.zeros(N, bool)
        self.z4, self.ez4, self.tau = proofs._impact_speed(boxes, n)
        self.pieces, self.depth = pieces, depth
        self.witness_only = witness_only
        self.w_s = np.full(N, np.nan)
        self.w_wall = np.zeros(N, np.int64)
        self.w_val = (np.full(N, np.nan), np.full(N, np.nan))
        self.rec = {k: [] for k in ("owner", "a", "b", "kind", "mono", "lo", "hi")}
        self.sens = np.zeros((N, len(SCALED)))
        self.widths = {k: boxes.hi[k] - boxes.lo[k] for k in SCALED}

    # witnesses
    def witness(self, owner, s, order2):
        """Mark a violation where ``|z3(s)| > L`` on the whole box (``s`` point times)."""
        C, S = (self.C, self.S) if order2 else (self.C1, self.S1)
        w3, _, _, wg = _gap_forms(self.case, self.n, self.boxes, self.dirs, C, S, owner, s, s,
                                  s_point=True)
        up, down = wg - w3, w3 + wg
        hit_up = up.r.hi < 0
        hit_dn = (down.r.hi < 0) & ~hit_up
        for hit, q, wall in ((hit_up, up, 1), (hit_dn, down, -1)):
            new = hit & (self.verdict[owner] != -1)
            if not np.any(new):
                continue
            o = owner[new]
            o, first = np.unique(o, return_index=True)
            sel = np.flatnonzero(new)[first]
            self.verdict[o] = -1
            self.w_s[o] = s[sel]
            self.w_wall[o] = wall
            lo, hi = _lohi(q)
            self.w_val[0][o], self.w_val[1][o] = lo[sel], hi[sel]

    def _tests(self, z3, z3d, z3dd, gam, a, b, sel):
        ends = (self.z4.take(sel), self.ez4.take(sel), self.tau.take(sel))
        return proofs._piece_tests(z3, z3d, z3dd, gam, a, b, *ends)

    def _record(self, owner, a, b, ok, z3, mono=False):
        if not np.any(ok):
            return
        kind = np.where(a == 0, 1, np.where(b == 1, 2, 0))
        lo, hi = _lohi(z3)
        for key, v in (("owner", owner), ("a", a), ("b", b), ("kind", kind),
                       ("mono", np.full(owner.size, mono)), ("lo", lo), ("hi", hi)):
            self.rec[key].append(np.asarray(v)[ok])

    def _monotone(self, owner, a, b, z3, gam):
        """Re-test failing interior pieces on the face where the tested quantity is least."""
        sides = [(q, q.r.lo > 0) for q in (gam - z3, z3 + gam)]
        proved = [s[1].copy() for s in sides]
        for side, (q, done) in enumerate(sides):
            need = np.flatnonzero(~done)
            if need.size == 0:
                continue
            sub_lo = {k: self.boxes.lo[k][owner[need]].copy() for k in SCALED}
            sub_hi = {k: self.boxes.hi[k][owner[need]].copy() for k in SCALED}
            s_lo, s_hi = a[need].copy(), b[need].copy()
            useful = np.zeros(need.size, bool)
            for i, k in enumerate(list(self.dirs) + ["s"]):
                g = q.g[i]
                if g is None:
                    continue
                up = g.lo[need] >= 0      # increasing: least at the lower end
                down = g.hi[need] <= 0
                if k == "s":
                    s_hi = np.where(up, s_lo, s_hi)
                    s_lo = np.where(down, s_hi, s_lo)
                else:
                    sub_hi[k] = np.where(up, sub_lo[k], sub_hi[k])
                    sub_lo[k] = np.where(down, sub_hi[k], sub_lo[k])
                useful |= up | down
            if not np.any(useful):
                continue
            need = need[useful]
            face = Boxes({k: v[useful] for k, v in sub_lo.items()},
                         {k: v[useful] for k, v in sub_hi.items()})
            s_lo, s_hi = s_lo[useful], s_hi[useful]
            fdirs = face.directions()
            P, _, _ = proofs._forms(face, fdirs, 2)
            nI = Interval(float(self.n))
            Cf, Sf, _ = interval_kernel("existence", self.case)(TIGHT_OPS, *proofs._args(P), nI)
            point = s_hi <= s_lo
            res = np.zeros(need.size, bool)
            for pt in (True, False):
                sel = np.flatnonzero(point == pt)
                if sel.size == 0:
                    continue
                z3f, _, _, gf = _gap_forms(self.case, self.n, face, fdirs, Cf, Sf, sel,
                                           s_lo[sel], s_hi[sel], s_point=pt)
                qf = gf - z3f if side == 0 else z3f + gf
                res[sel] = qf.r.lo > 0
            proved[side][need] = res
        return proved[0] & proved[1]

    def _round_chunk(self, owner, a, b):
        """Test one chunk of pieces (first- then second-order forms, then a face)."""
        inner = (a > 0) & (b < 1)
        z3, z3d, z3dd, gam = _gap_forms(self.case, self.n, self.boxes, self.dirs, self.C1,
                                        self.S1, owner, a, b)
        sel = owner
        ok = self._tests(z3, z3d, z3dd, gam, a, b, sel)
        self._record(owner, a, b, ok, z3)
        share = np.ones(owner.size)
        look = ~ok & inner & (self.verdict[owner] != -1)
        if np.any(look):
            self.witness(owner[look], 0.5 * (a[look] + b[look]), False)
        bad = np.flatnonzero(~ok & (self.verdict[owner] != -1))
        if bad.size:
            o, lo, hi = owner[bad], a[bad], b[bad]
            z3, z3d, z3dd, gam = _gap_forms(self.case, self.n, self.boxes, self.dirs, self.C,
                                            self.S, o, lo, hi)
            ok2 = self._tests(z3, z3d, z3dd, gam, lo, hi, o)
            self._record(o, lo, hi, ok2, z3)
            ok[bad] = ok2
            share[bad] = proofs._time_share(z3)
            mono = np.flatnonzero(~ok2 & (lo > 0) & (hi < 1))
            if mono.size:
                sub = _take_form(z3, mono), _take_form(gam, mono)
                okm = self._monotone(o[mono], lo[mono], hi[mono], *sub)
                self._record(o[mono], lo[mono], hi[mono], okm, sub[0], mono=True)
                ok[bad[mono]] = okm
            still = ~ok2
            if np.any(still):
                s = _sens(z3, self.dirs + ["s"], {**self.widths_of(o), "s": hi - lo}, o.size)
                np.add.at(self.sens, o[still], s[still])
        look = ~ok & inner & (self.verdict[owner] != -1)
        if np.any(look):
            self.witness(owner[look], 0.5 * (a[look] + b[look]), True)
        return ok, share

    def widths_of(self, owner):
        return {k: v[owner] for k, v in self.widths.items()}

    def run(self, idx):
        """Prove viability of the boxes ``idx``; witnesses only where ``witness_only``."""
        pieces, depth = self.pieces, self.depth
        if idx.size == 0:
            return
        wo = self.witness_only[idx]
        if np.any(wo):
            # boxes whose stability is undecided can only be proved without an orbit
            o = idx[wo]
            m = 4 * pieces
            s = (np.arange(m) + 0.5) / m
            owner = np.repeat(o, m)
            ss = np.tile(s, o.size)
            for order2 in (False, True):
                left = self.verdict[owner] != -1
                if np.any(left):
                    self.witness(owner[left], ss[left], order2)
            self.failed[o] = True
            idx = idx[~wo]
        owner = np.repeat(idx, pieces)
        j = np.tile(np.arange(pieces), idx.size)
        a, b = j / pieces, (j + 1) / pieces
        level = np.zeros(owner.size, np.int64)
        for _round in range(depth + 1):
            if owner.size == 0:
                break
            ok = np.empty(owner.size, bool)
            share = np.empty(owner.size)
            for c in range(0, owner.size, proofs._CHUNK):
                sl = slice(c, c + proofs._CHUNK)
                ok[sl], share[sl] = self._round_chunk(owner[sl], a[sl], b[sl])
            bad = ~ok
            ends = (a == 0) | (b == 1)
            alive = self.verdict[owner] != -1
            keep = bad & alive & (ends | (share > proofs._SPLIT_SHARE))
            self.failed[owner[bad & ~keep & alive]] = True
            exhausted = keep & (level >= depth)
            self.failed[owner[exhausted]] = True
            keep &= ~exhausted & ~self.failed[owner]
            o, lo, hi, lv = owner[keep], a[keep], b[keep], level[keep]
            mid = 0.5 * (lo + hi)
            owner = np.concatenate([o, o])
            a, b = np.concatenate([lo, mid]), np.concatenate([mid, hi])
            level = np.concatenate([lv, lv]) + 1
        self.failed[owner] = True

    def result(self):
        v = self.verdict.copy()
        v[(v == 0) & ~self.failed] = 1
        return v

    def pieces_of(self, keep):
        """The recorded pieces of the boxes where ``keep``; owners renumbered by ``keep``."""
        if not self.rec["owner"]:
            return {k: np.zeros(0, np.int64 if k in ("owner", "kind") else
                                bool if k == "mono" else float) for k in self.rec}
        r = {k: np.concatenate(v) for k, v in self.rec.items()}
        sel = keep[r["owner"]]
        return {k: v[sel] for k, v in r.items()}


def _take_form(x, idx):
    return x.take(idx) if isinstance(x, (CForm, CForm2)) else Interval(x.lo[idx], x.hi[idx])


def classify_record(case, n, boxes: Boxes, *, pieces=8, flight_depth=10):
    """Classify every box and keep what decided it.

    Returns
    -------
    cls, why : ndarray of int, shape (N,)
        :data:`hybridpd.pair.proofs.CLASSES` and :data:`~hybridpd.pair.proofs.REASONS` indices.
    rec : dict
        Per box: ``det``, ``xm`` (``(lo, hi)`` arrays), ``xm_which`` (0: ``C``, 1: ``S``),
        ``hurwitz`` (``(lo, hi)`` arrays of shape ``(N, 6)``), ``unstable_kind``
        (:data:`UNSTABLE_KINDS` index or -1), ``unstable_index``, ``unstable_value``,
        ``witness_s``, ``witness_wall`` (+1: ``L - z3 < 0``, -1: ``z3 + L < 0``),
        ``witness_value``, ``pieces`` (dict of arrays ``owner, a, b, kind, mono, lo, hi``:
        the pieces proved inside the walls), ``sens`` (per box and scaled parameter, the
        share of the failing enclosures due to it).
    """
    require = getattr(proofs, "require_libm", None)   # the libm self-test, where present
    if require is not None:
        require()
    try:
        return _classify(case, n, boxes, pieces, flight_depth)
    except EmptyIntersectionError:
        return _classify_apart(case, n, boxes, pieces, flight_depth)


def _classify_apart(case, n, boxes, pieces, flight_depth):
    N = boxes.size
    if N == 1:
        rec = _empty_record(1)
        return np.zeros(1, np.int64), np.full(1, R_EMPTY, np.int64), rec
    out = []
    for idx in (np.arange(N // 2), np.arange(N // 2, N)):
        part = boxes.take(idx)
        try:
            out.append(_classify(case, n, part, pieces, flight_depth))
        except EmptyIntersectionError:
            out.append(_classify_apart(case, n, part, pieces, flight_depth))
    (c1, w1, r1), (c2, w2, r2) = out
    return np.concatenate([c1, c2]), np.concatenate([w1, w2]), _concat_records(r1, r2, N // 2)


def _empty_record(N):
    nan = lambda: np.full(N, np.nan)
    return {"det": (nan(), nan()), "xm": (nan(), nan()), "xm_which": np.zeros(N, np.int64),
            "hurwitz": (np.full((N, 6), np.nan), np.full((N, 6), np.nan)),
            "unstable_kind": np.full(N, -1, np.int64), "unstable_index": np.full(N, -1, np.int64),
            "unstable_value": (nan(), nan()), "witness_s": nan(),
            "witness_wall": np.zeros(N, np.int64), "witness_value": (nan(), nan()),
            "pieces": {k: np.zeros(0, np.int64 if k in ("owner", "kind") else
                                   bool if k == "mono" else float)
                       for k in ("owner", "a", "b", "kind", "mono", "lo", "hi")},
            "sens": np.zeros((N, len(SCALED)))}


def _concat_records(r1, r2, offset):
    out = {}
    for k, v in r1.items():
        w = r2[k]
        if k == "pieces":
            out[k] = {p: np.concatenate([v[p], w[p] + (offset if p == "owner" else 0)])
                      for p in v}
        elif isinstance(v, tuple):
            out[k] = tuple(np.concatenate([x, y]) for x, y in zip(v, w))
        else:
            out[k] = np.concatenate([v, w])
    return out


def _classify(case, n, boxes: Boxes, pieces, flight_depth):
    N = boxes.size
    dirs = boxes.directions()
    exists, stable, unstable, C, S, rec, sens = _orbit_stage(case, n, boxes, dirs)
    cls = np.zeros(N, np.int64)
    why = np.full(N, R_EXIST, np.int64)
    idx = np.flatnonzero(exists)
    via = _Viability(case, n, boxes, dirs, C, S, pieces=pieces, depth=flight_depth,
                     witness_only=~(stable | unstable))
    via.run(idx)
    v = via.result()
    v[~exists] = 0
    st, un = stable, unstable
    e = exists
    cls = np.select([~e, v < 0, v == 0, st, un], [UNDECIDED, NO_ORBIT, UNDECIDED, STABLE,
                                                  UNSTABLE], UNDECIDED)
    why = np.select([~e, v < 0, v == 0, st, un], [R_EXIST, R_VIOLATED, R_VIAB, R_STABLE,
                                                  R_UNSTABLE], R_STAB)
    # a box whose stability is open was only searched for a contact
    why = np.where((cls == UNDECIDED) & e & ~st & ~un, R_STAB, why)
    sens = sens + via.sens
    rec.update(witness_s=via.w_s, witness_wall=via.w_wall, witness_value=via.w_val,
               pieces=via.pieces_of((cls == STABLE) | (cls == UNSTABLE)), sens=sens)
    return cls, why, rec


# ----------------------------------------------------------------------------------------
# Cells: adaptive subdivision
# ----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ProofTree:
    """The proof of many cells: their classes and every decided part (leaf) of the proved ones.

    Attributes
    ----------
    cls, why : ndarray of int, shape (N,)
        Class and reason of each cell.
    cells : Boxes
        The cells (scaled parameters).
    leaf_cell : ndarray of int, shape (L,)
        The cell of each leaf (only proved cells have leaves; their leaves tile them).
    leaves : Boxes
        The leaves' bounds.
    leaf_cls : ndarray of int, shape (L,)
    record : dict
        What decided each leaf (see :func:`classify_record`; the pieces' ``owner`` indexes
        the leaves).
    evaluated : int
        Boxes classified (cells and parts).
    stop : str
        ``"decided"``, ``"depth"``, ``"budget"`` or ``"max_boxes"``.
    cell_stop : ndarray of int, shape (N,)
        Why each cell's subdivision stopped, an index into :data:`CELL_STOPS`.
    """

    __repr__ = compact_repr

    cls: np.ndarray
    why: np.ndarray
    cells: Boxes = field(repr=False)
    leaf_cell: np.ndarray = field(repr=False)
    leaves: Boxes = field(repr=False)
    leaf_cls: np.ndarray = field(repr=False)
    record: dict = field(repr=False)
    evaluated: int
    stop: str
    cell_stop: np.ndarray = field(default=None, repr=False)

    def leaves_of(self, cell: int) -> np.ndarray:
        """Indices of the leaves of one cell."""
        return np.flatnonzero(self.leaf_cell == cell)


def _bisect_along(boxes: Boxes, dim):
    """Halve every box along the scaled parameter ``SCALED[dim[i]]``; lower halves first."""
    lo1, hi1 = dict(boxes.lo), dict(boxes.hi)
    lo2, hi2 = dict(boxes.lo), dict(boxes.hi)
    for j, k in enumerate(SCALED):
        m = np.clip(0.5 * boxes.lo[k] + 0.5 * boxes.hi[k], boxes.lo[k], boxes.hi[k])
        hi1[k] = np.where(dim == j, m, boxes.hi[k])
        lo2[k] = np.where(dim == j, m, boxes.lo[k])
    return Boxes({k: np.concatenate([lo1[k], lo2[k]]) for k in SCALED},
                 {k: np.concatenate([hi1[k], hi2[k]]) for k in SCALED})


def _split_dims(boxes: Boxes, ref, sens):
    """The direction to halve: the most sensitive one, unless it is already 16 times
    narrower (relative to the cell) than the widest one; the widest relative one otherwise."""
    rel = np.stack([(boxes.hi[k] - boxes.lo[k]) / np.where(ref[k] > 0, ref[k], 1)
                    for k in SCALED], axis=1)
    widest = np.argmax(rel, axis=1)
    s = np.where(rel > 0, sens, 0.0)
    best = np.argmax(s, axis=1)
    rows = np.arange(boxes.size)
    ok = (s[rows, best] > 0) & (rel[rows, best] * 16 >= rel[rows, widest])
    return np.where(ok, best, widest)


def prove_cells(case, n, boxes: Boxes, *, depth=3, max_parts=None, pieces=8, flight_depth=10,
                max_boxes=400_000, adaptive=True):
    """Classify cells, subdividing undecided parts; keep the proof tree.

    Parameters
    ----------
    case : str
    n : int
        Odd order.
    boxes : Boxes
        The cells.
    depth : int
        Bisections of a part at most (``0`` classifies the cells as given).
    max_parts : int or None
        Parts classified per cell at most (``None``: only ``depth`` bounds them).
    pieces, flight_depth : int
        Initial pieces of the flight and their bisections in the viability test.
    max_boxes : int
        Boxes classified in one round at most.
    adaptive : bool
        Halve along the most sensitive parameter (else the widest relative one).

    Returns
    -------
    ProofTree
    """
    N = boxes.size
    ref = {k: boxes.hi[k] - boxes.lo[k] for k in SCALED}
    agreed = np.full(N, -1, np.int64)
    mixed = np.zeros(N, bool)
    open_ = np.zeros(N, bool)
    used = np.zeros(N, np.int64)
    halted = np.full(N, -1, np.int64)   # why a cell with undecided parts stopped
    first_why = None
    last_why = np.full(N, -1, np.int64)
    owner = np.arange(N)
    cur = boxes
    evaluated = 0
    stop = "decided"
    kept = []          # (owner, boxes, cls, record) of decided parts per round
    for level in range(depth + 1):
        c, w, rec = classify_record(case, n, cur, pieces=pieces, flight_depth=flight_depth)
        evaluated += cur.size
        np.add.at(used, owner, 1)
        if first_why is None:
            first_why = w.copy()
        dec = c != UNDECIDED
        if np.any(dec):
            d_own, d_cls = owner[dec], c[dec]
            for o, cc in zip(d_own, d_cls):
                if agreed[o] == -1:
                    agreed[o] = cc
                elif agreed[o] != cc:
                    mixed[o] = True
            kept.append((owner[dec], cur.take(np.flatnonzero(dec)), c[dec],
                         _select_record(rec, dec)))
        und = ~dec & ~mixed[owner]
        # a cell whose undecided parts the budget dropped stays open: those parts are no
        # longer classified, but they are not proved either
        dropped = halted == STOP_BUDGET
        open_[:] = dropped
        open_[owner[und]] = True
        last_why[~dropped] = -1
        last_why[owner[und]] = w[und]
        if not np.any(und):
            break
        if level == depth:
            stop = "depth"
            halted[open_] = STOP_DEPTH
            break
        cand = np.flatnonzero(und)
        if max_parts is not None:
            # a cell's undecided parts are halved only while its budget allows all of them
            n_open = np.bincount(owner[cand], minlength=N)
            allowed = used + 2 * n_open <= max_parts
            over = cand[~allowed[owner[cand]]]
            if over.size:
                stop = "budget"
                halted[owner[over]] = STOP_BUDGET
            cand = cand[allowed[owner[cand]]]
            if cand.size == 0:
                break
        if 2 * cand.size > max_boxes:
            stop = "max_boxes"
            halted[open_ & (halted < 0)] = STOP_MAX_BOXES
            break
        sub = cur.take(cand)
        sub_owner = owner[cand]
        if adaptive:
            dims = _split_dims(sub, {k: ref[k][sub_owner] for k in SCALED}, rec["sens"][cand])
        else:
            dims = _split_dims(sub, {k: ref[k][sub_owner] for k in SCALED},
                               np.zeros((cand.size, len(SCALED))))
        cur = _bisect_along(sub, dims)
        owner = np.concatenate([sub_owner, sub_owner])
    done = (agreed >= 0) & ~mixed & ~open_
    cls = np.where(done, agreed, UNDECIDED)
    why = np.where(done, np.select([agreed == STABLE, agreed == UNSTABLE], [R_STABLE, R_UNSTABLE],
                                   R_VIOLATED),
                   np.where(mixed, R_MIXED, np.where(last_why >= 0, last_why, first_why)))
    cell_stop = np.where(done, STOP_PROVED, np.where(mixed, STOP_MIXED, halted))
    return _tree(cls, why, boxes, kept, done, evaluated, stop, cell_stop)


def _select_record(rec, mask):
    idx = np.flatnonzero(mask)
    renum = np.full(mask.size, -1, np.int64)
    renum[idx] = np.arange(idx.size)
    out = {}
    for k, v in rec.items():
        if k == "pieces":
            sel = mask[v["owner"]]
            out[k] = {p: (renum[x[sel]] if p == "owner" else x[sel]) for p, x in v.items()}
        elif k == "sens":
            continue
        elif isinstance(v, tuple):
            out[k] = tuple(x[idx] for x in v)
        else:
            out[k] = v[idx]
    return out


def _tree(cls, why, cells, kept, done, evaluated, stop, cell_stop):
    owners, boxes, classes, recs = [], [], [], []
    offset = 0
    for o, b, c, r in kept:
        sel = done[o]
        if not np.any(sel):
            continue
        idx = np.flatnonzero(sel)
        owners.append(o[idx])
        boxes.append(b.take(idx))
        classes.append(c[idx])
        r = _select_record(r, sel)
        r["pieces"]["owner"] = r["pieces"]["owner"] + offset
        recs.append(r)
        offset += idx.size
    if owners:
        leaf_cell = np.concatenate(owners)
        leaves = Boxes({k: np.concatenate([b.lo[k] for b in boxes]) for k in SCALED},
                       {k: np.concatenate([b.hi[k] for b in boxes]) for k in SCALED})
        leaf_cls = np.concatenate(classes)
        record = recs[0]
        for r in recs[1:]:
            record = _concat_records(record, r, 0)
    else:
        leaf_cell = np.zeros(0, np.int64)
        leaves = Boxes({k: np.zeros(0) for k in SCALED}, {k: np.zeros(0) for k in SCALED})
        leaf_cls = np.zeros(0, np.int64)
        record = _select_record(_empty_record(0), np.zeros(0, bool))
    order = np.argsort(leaf_cell, kind="stable")
    leaf_cell, leaf_cls = leaf_cell[order], leaf_cls[order]
    leaves = leaves.take(order)
    inv = np.empty_like(order)
    inv[order] = np.arange(order.size)
    rec2 = {}
    for k, v in record.items():
        if k == "pieces":
            p = dict(v)
            p["owner"] = inv[p["owner"]]
            po = np.argsort(p["owner"], kind="stable")
            rec2[k] = {q: x[po] for q, x in p.items()}
        elif isinstance(v, tuple):
            rec2[k] = tuple(x[order] for x in v)
        else:
            rec2[k] = v[order]
    return ProofTree(cls.astype(np.int64), why.astype(np.int64), cells, leaf_cell, leaves,
                     leaf_cls, rec2, int(evaluated), stop, cell_stop.astype(np.int64))
