"""The certified classification's inequalities proved again in python-flint's ``arb`` balls.

The fast layer of :mod:`hybridpd.pair.certified` proves each class in float64 interval
arithmetic (outward rounding, and an error bound assumed of the platform's ``exp``, ``sin``,
...). This module proves the same inequalities again in ``arb``, whose every operation,
elementary functions included, is rigorous at the working precision, on the same closed
forms: the generated kernels of :mod:`hybridpd.pair.interval_kernels` run here on a backend
of arb-valued centred forms. Nothing here imports NumPy's interval code
(:mod:`~hybridpd.pair.intervals`, :mod:`~hybridpd.pair.centred`,
:mod:`~hybridpd.pair.proofs`), so a fault there cannot confirm itself. NumPy serves only as
a container: arrays of ``arb`` objects (``dtype=object``), each operation applied to every
ball by NumPy's object loops.

The balls, centred forms and jets the proofs run on, and the entire functions of the damped
flow, are in :mod:`hybridpd.pair.arbforms`.

The inequalities
----------------
* :func:`orbit_enclosures`: ``det M`` and ``C``, ``S`` of (13)-(14) (existence: ``det`` and
  one of ``C``, ``S`` away from 0), the six Lienard-Chipart quantities of the bilinear image
  of the characteristic polynomial of the half-map Jacobian ``M`` (all > 0: every multiplier
  inside the unit circle; one < 0: one outside), its coefficients ``c_k`` and power sums
  ``tr M^k`` (``|c_k| > C(4, k)`` or ``|tr M^k| > 4``: one outside);
* :func:`witness_enclosures`: ``L - z3(s*)`` and ``z3(s*) + L`` at one time of the flight
  (either below 0: an extra contact, viability violated);
* :func:`piece_proved`: ``-L < z3 < L`` on a piece ``[a, b]`` of the flight (time as one more
  direction of the forms), with the end pieces' tests of the wall they start or end on, and
  the monotone reduction to a face of the box.

The precision is ``ctx.prec`` (callers use :data:`PREC` bits, ``flint.ctx.workprec``).
"""
from __future__ import annotations

import math
import time
import types

import numpy as np

from hybridpd.pair.arbforms import (
    _FORMS,
    PREC,
    SCALED,
    ArbBoxes,
    ArbForms,
    ArbJets,
    _arb,
    _bools,
    _damped,
    _flint,
    _meet,
    _obj,
    _range,
    _u,
    arb_form_ops,
    negative,
    positive,
)

__all__ = ["PREC", "SCALED", "ArbBoxes", "ArbForms", "ArbJets", "arb_form_ops", "check_orbit",
           "orbit_enclosures", "piece_proved", "taylor_bound", "witness_enclosures"]

# ----------------------------------------------------------------------------------------
# The quantities of the proofs
# ----------------------------------------------------------------------------------------


def _kernel(name, case):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.interval_kernels import interval_kernel

    return interval_kernel(name, case)


def charpoly(m):
    """``c0..c3`` of ``det(lambda I - M)`` from the 16 entries (row by row).

    From the 2 x 2 minors of rows ``(0, 1)``, ``(2, 3)`` and of the principal 3 x 3 blocks.
    """
    M = [m[4 * i:4 * i + 4] for i in range(4)]
    minor = {}

    def mn(i, j, a, b):
        key = (i, j, a, b)
        if key not in minor:
            minor[key] = M[i][a] * M[j][b] - M[i][b] * M[j][a]
        return minor[key]

    c3 = -(M[0][0] + M[1][1] + M[2][2] + M[3][3])
    c2 = 0
    for i in range(4):
        for j in range(i + 1, 4):
            c2 = c2 + mn(i, j, i, j)
    c1 = 0
    for i, j, k in ((0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)):
        c1 = c1 - (M[i][i] * mn(j, k, j, k) - M[i][j] * mn(j, k, i, k)
                   + M[i][k] * mn(j, k, i, j))
    c0 = 0
    for a, b in ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)):
        ca, cb = (x for x in range(4) if x not in (a, b))
        c0 = c0 + mn(0, 1, a, b) * mn(2, 3, ca, cb) * (-1) ** (a + b + 1)
    return [c0, c1, c2, c3]


def _binom_poly(k, j):
    """Coefficient of ``w^j`` in ``(1 + w)^k (1 - w)^(4 - k)``."""
    return sum(math.comb(k, i) * math.comb(4 - k, j - i) * (-1) ** (j - i)
               for i in range(j + 1) if i <= k and j - i <= 4 - k)


_T = [[_binom_poly(k, j) for k in range(5)] for j in range(5)]
#: Bounds of ``|c_k|`` when every root of a monic quartic is in the closed unit disc.
BINOM = (1, 4, 6, 4)


def hurwitz(c):
    """``q0..q4`` and ``Delta_3`` of the bilinear image ``(1 - w)^4 p((1 + w)/(1 - w))``."""
    c = list(c) + [1]
    q = []
    for j in range(5):
        acc = 0
        for k in range(5):
            if _T[j][k]:
                acc = acc + c[k] * _T[j][k]
        q.append(acc)
    return q + [q[3] * q[2] * q[1] - q[1] * q[1] * q[4] - q[3] * q[3] * q[0]]


def power_sums(c, kmax=8):
    """``tr M^k``, ``k = 1..kmax`` (Newton's identities)."""
    p = []
    for k in range(1, kmax + 1):
        acc = c[4 - k] * k if k <= 4 else 0
        for j in range(1, min(k, 5)):
            acc = acc + c[4 - j] * p[k - j - 1]
        p.append(-acc)
    return p


def _signature(x):
    v = x.c if isinstance(x, _FORMS) else x
    v = v[:3] if isinstance(v, np.ndarray) else [v]
    return tuple(float(e.mid()) for e in v) + (len(x.c) if isinstance(x, _FORMS) else 0,)


def _sharing(ops):
    """``ops`` whose damped functions are computed once per argument: the existence and the
    half-map kernels take them at the same ``(kv/2, kv^2/4 - kp, n pi/w)``."""
    cache = {}

    def shared(which, a, D, t):
        key = (which, _signature(a), _signature(D), _signature(t))
        if key not in cache:
            cache[key] = _damped(a, D, t, which)
        return cache[key]

    out = types.SimpleNamespace(**vars(ops))
    out.DCH = lambda a, D, t: shared("ch", a, D, t)
    out.DSH = lambda a, D, t: shared("sh", a, D, t)
    return out


def orbit_enclosures(case, n, box: ArbBoxes, *, jets=False, ops=None, escape=True):
    """The quantities of existence and stability over the boxes (forms, or jets at the
    centres).

    Returns
    -------
    dict
        ``det``, ``C``, ``S``; ``hurwitz`` (6); ``coeff`` (``c0..c3``); ``trace``
        (``tr M^k``, ``k = 1..8``).
    """
    ops = _sharing(ops or arb_form_ops())
    P = box.params(jets)
    nn = _arb(n)
    C, S, det = _kernel("existence", case)(ops, *P, nn)
    M = _kernel("halfmap", case)(ops, C, S, *P, nn)
    c = charpoly(M)
    return {"det": det, "C": C, "S": S, "hurwitz": hurwitz(c), "coeff": c,
            "trace": power_sums(c) if escape else []}


def witness_enclosures(case, n, box: ArbBoxes, s, *, jets=False, ops=None):
    """``L - z3(s)`` and ``z3(s) + L`` (and ``det``, ``C``, ``S``) at the times ``s``."""
    ops = ops or arb_form_ops()
    P = box.params(jets)
    nn = _arb(n)
    C, S, det = _kernel("existence", case)(ops, *P, nn)
    sa = _obj(_arb(float(x)) for x in np.broadcast_to(np.asarray(s, float), (box.N,)))
    z3 = _kernel("gap", case)(ops, sa, C, S, *P, nn)[0]
    gam = P[SCALED.index("gam")]
    return {"det": det, "C": C, "S": S, "up": gam - z3, "down": z3 + gam}


def taylor_bound(jet, H, box: ArbBoxes):
    """``f(p0) + grad f(p0) . delta + sum H_ij q_ij``: the Taylor enclosure of ``f`` over the
    boxes from its jets at their centres and a Hessian enclosure ``H`` over boxes containing
    them (``H`` a tuple of arrays in the order of ``box.pairs``)."""
    v = jet.c
    for x, d in zip(jet.gc, box.delta):
        v = v + x * d
    for h, q in zip(H, box.quad):
        v = v + h * q
    return v


# ----------------------------------------------------------------------------------------
# Decisions
# ----------------------------------------------------------------------------------------


def exists(q, which=None) -> np.ndarray:
    """``det`` and ``C`` (``which == 0``), ``S`` (1) or either (``None``) away from 0."""
    apart = lambda x: positive(x) | negative(x)
    ok = apart(q["det"])
    if which is None:
        return ok & (apart(q["C"]) | apart(q["S"]))
    which = np.broadcast_to(np.asarray(which), ok.shape)
    return ok & np.where(which == 1, apart(q["S"]), apart(q["C"]))


def is_stable(q) -> np.ndarray:
    """All six Lienard-Chipart quantities above 0."""
    out = None
    for h in q["hurwitz"]:
        p = positive(h)
        out = p if out is None else out & p
    return out


def is_unstable(q) -> np.ndarray:
    """One Lienard-Chipart quantity below 0, or an escape bound exceeded."""
    out = None
    for h in q["hurwitz"]:
        x = negative(h)
        out = x if out is None else out | x
    for x, bound in list(zip(q["coeff"], BINOM)) + [(p, 4) for p in q["trace"]]:
        out = out | positive(_range(x) - bound) | negative(_range(x) + bound)
    return out


def is_violated(q, wall=None) -> np.ndarray:
    """``L - z3 < 0`` (``wall = 1``), ``z3 + L < 0`` (``-1``) or either (``None``)."""
    up, down = negative(q["up"]), negative(q["down"])
    if wall is None:
        return up | down
    wall = np.broadcast_to(np.asarray(wall), up.shape)
    return np.where(wall == 1, up, down)


def check_orbit(case, n, box: ArbBoxes, cls, *, which=None):
    """Whether existence and the class ``cls`` (1 stable, 2 unstable; arrays) are proved on
    the boxes by :class:`ArbForms` over each box."""
    q = orbit_enclosures(case, n, box)
    cls = np.broadcast_to(np.asarray(cls), (box.N,))
    return exists(q, which) & np.where(cls == 1, is_stable(q), is_unstable(q))


# ----------------------------------------------------------------------------------------
# Pieces of the flight
# ----------------------------------------------------------------------------------------


def _piece_box(box: ArbBoxes, a, b):
    names = box.names + ("s",)
    lo = {**box.lo, "s": np.asarray(a, float)}
    hi = {**box.hi, "s": np.asarray(b, float)}
    return ArbBoxes(lo, hi, names)


def _gap(case, n, pb: ArbBoxes, ops):
    """``z3, z3', z3''`` and ``gam`` over boxes with time (all directions of ``pb``)."""
    P = pb.params()
    nn = _arb(n)
    C, S, _ = _kernel("existence", case)(ops, *P, nn)
    z = _kernel("gap", case)(ops, pb.value("s"), C, S, *P, nn)
    return z[0], z[1], z[2], P[SCALED.index("gam")]


def piece_proved(case, n, box: ArbBoxes, a, b, kind, *, ops=None, monotone=True):
    """Whether ``-L < z3 < L`` is proved on the pieces ``[a, b]`` of the flight.

    ``kind`` (per box): 0 ``inside`` (both walls from the gap's range), 1 ``first`` (the
    piece starts at the ``+L`` impact, ``a = 0``: ``z3' < 0``, ``z3'' < 0`` or the Taylor bound
    ``L - z3(t) >= t (e z4- - max(z3'') t / 2) > 0``, and the far wall), 2 ``last`` (ends at
    the ``-L`` impact, ``b = 1``). An inside piece that fails is tried again on the face of
    its box (time included) where the tested quantity is least, wherever the sign of its
    gradient is proved (``monotone``).
    """
    ops = ops or arb_form_ops()
    arb = _flint().arb
    a, b = np.asarray(a, float), np.asarray(b, float)
    kind = np.broadcast_to(np.asarray(kind), a.shape)
    pb = _piece_box(box, a, b)
    z3, z3d, z3dd, gam = _gap(case, n, pb, ops)
    up_q, dn_q = gam - z3, z3 + gam
    gp, gm = _range(up_q), _range(dn_q)
    ok_up, ok_dn = positive(gp), positive(gm)
    out = ok_up & ok_dn
    ends = np.flatnonzero(kind != 0)
    if ends.size:
        pi = arb.pi()
        for i in ends:
            e, mu, w = pb.ball["e"][i], pb.ball["mu"][i], pb.ball["w"][i]
            v = 2 * w / (pi * n)
            z4 = 2 * v * (1 + mu) / (1 + e)
            ez4 = e * z4
            tau = pi * n / w
            L = pb.ball["gam"][i]
            zd, zdd = _range(z3d)[i], _range(z3dd)[i]
            up = zdd.upper() if zdd.upper() > 0 else arb(0)
            down = zdd.lower() if zdd.lower() < 0 else arb(0)
            if kind[i] == 1:
                h = tau * float(b[i])
                wall = zd < 0 or zdd < 0 or (ez4 - up * h / 2) > 0
                far = gm[i] > 0 or (2 * L - ez4 * h + down * h * h / 2) > 0
            else:
                sig = tau * (1 - float(a[i]))
                wall = zd < 0 or zdd > 0 or (z4 + down * sig / 2) > 0
                far = gp[i] > 0 or (2 * L - z4 * sig - up * sig * sig / 2) > 0
            out[i] = bool(wall and far)
    if monotone:
        for side, (q, ok) in enumerate(((up_q, ok_up), (dn_q, ok_dn))):
            need = np.flatnonzero((kind == 0) & ~ok & ~out)
            if need.size == 0 or not isinstance(q, ArbForms):
                continue
            face = _face(pb, q, need)
            if face is None:
                continue
            idx, fb = face
            z3f, _, _, gf = _gap(case, n, fb, ops)
            qf = gf - z3f if side == 0 else z3f + gf
            okf = positive(qf)
            if side == 0:
                ok_up[idx] = okf
            else:
                ok_dn[idx] = okf
        out = np.where(kind == 0, ok_up & ok_dn, out)
    return out


def _face(pb: ArbBoxes, q: ArbForms, need):
    """The faces of the boxes ``need`` where ``q`` is least, in every direction where the
    sign of its gradient over the box is proved; ``None`` if no direction is."""
    lo = {k: pb.lo[k][need].copy() for k in pb.names}
    hi = {k: pb.hi[k][need].copy() for k in pb.names}
    useful = np.zeros(need.size, bool)
    for i, k in enumerate(pb.dirs):
        g = q.g[i][need]
        incr = _bools(_u(lambda x: bool(x >= 0))(g))
        decr = _bools(_u(lambda x: bool(x <= 0))(g))
        hi[k] = np.where(incr, lo[k], hi[k])
        lo[k] = np.where(decr & ~incr, hi[k], lo[k])
        useful |= incr | decr
    if not np.any(useful):
        return None
    sel = np.flatnonzero(useful)
    return need[sel], ArbBoxes({k: v[sel] for k, v in lo.items()},
                               {k: v[sel] for k, v in hi.items()}, pb.names)


# ----------------------------------------------------------------------------------------
# Confirming a map: blocks of cells, cells, leaves, halves
# ----------------------------------------------------------------------------------------


def _groups(shape, pending, B):
    """The pending cells sorted by their aligned ``B x B`` block, and each one's block index;
    for ``B > 1`` blocks with a single pending cell are left out (``B = 1`` takes them)."""
    nx = shape[1]
    cells = np.flatnonzero(pending)
    iy, ix = np.divmod(cells, nx)
    key = (iy // B) * ((nx + B - 1) // B) + ix // B
    order = np.argsort(key, kind="stable")
    cells, key = cells[order], key[order]
    _, count = np.unique(key, return_counts=True)
    many = np.repeat(count > (1 if B > 1 else 0), count)
    cells, key = cells[many], key[many]
    _, gi = np.unique(key, return_inverse=True)
    return cells, gi


def _block_bounds(lo, hi, cells, gi):
    nb = int(gi.max()) + 1 if gi.size else 0
    blo, bhi = {}, {}
    for k in lo:
        a = np.full(nb, np.inf)
        b = np.full(nb, -np.inf)
        np.minimum.at(a, gi, lo[k][cells])
        np.maximum.at(b, gi, hi[k][cells])
        blo[k], bhi[k] = a, b
    return blo, bhi


def _finish(q):
    """``Delta_3`` also from the enclosures of ``q0..q4`` (when they are balls): both enclose it."""
    h = list(q["hurwitz"])
    r = [_range(x) for x in h]
    if all(isinstance(x, np.ndarray) for x in r):
        naive = r[3] * r[2] * r[1] - r[1] * r[1] * r[4] - r[3] * r[3] * r[0]
        h[5] = _meet(r[5], naive)
        q = dict(q, hurwitz=h)
    return q


def _ranges(q):
    out = {}
    for k, v in q.items():
        out[k] = [_range(x) for x in v] if isinstance(v, list) else _range(v)
    return out


def _take_ranges(q, idx):
    out = {}
    for k, v in q.items():
        out[k] = [x[idx] for x in v] if isinstance(v, list) else v[idx]
    return out


def _decide(q, cls):
    """Existence and the class (1 stable, 2 unstable, per box) from ball arrays."""
    q = _finish(q)
    cls = np.asarray(cls)
    return exists(q) & np.where(cls == 1, is_stable(q), is_unstable(q))


def _from_block(qpt, qb, gi, cbox: ArbBoxes, bbox: ArbBoxes):
    """Enclosures over the cells from their point values and their blocks' forms.

    ``f(p) = f(c) + grad f(c) . (p - c) + (p - c)^T H (p - c) / 2`` with
    ``grad f(c) in grad f(c_B) + H_B (c - c_B)`` and ``H`` in the block's Hessian ``H_B``.
    """
    offs = [cbox.centre[k] - bbox.centre[k][gi] for k in cbox.dirs]
    pairs = cbox.pairs

    def one(v, f):
        if not isinstance(f, ArbForms):
            return v
        H = [h[gi] for h in f.H]
        out = v
        for i in range(cbox.k):
            G = f.gc[i][gi]
            for (a, b), h in zip(pairs, H):
                if a == i:
                    G = G + h * offs[b]
                elif b == i:
                    G = G + h * offs[a]
            out = out + G * cbox.delta[i]
        for h, q in zip(H, cbox.quad):
            out = out + h * q
        return _meet(out, f.r[gi])

    res = {}
    for k, v in qpt.items():
        f = qb[k]
        res[k] = [one(a, b) for a, b in zip(v, f)] if isinstance(v, list) else one(v, f)
    return res


def _taylor_from_block(qjet, sel, qb, gi, cbox: ArbBoxes):
    """``f(c) + grad f(c) . delta + sum H_B q``: jets at the cells' centres, the Hessians of
    their blocks' forms (met with the blocks' ranges)."""

    def one(j, f):
        if not isinstance(f, ArbForms) or not isinstance(j, ArbJets):
            return _range(f)[gi] if isinstance(_range(f), np.ndarray) else _range(j)[sel]
        v = taylor_bound(j.take(sel), tuple(h[gi] for h in f.H), cbox)
        return _meet(v, f.r[gi])

    res = {}
    for k, f in qb.items():
        j = qjet[k]
        res[k] = [one(a, b) for a, b in zip(j, f)] if isinstance(f, list) else one(j, f)
    return res


def _halves(lo, hi, names=SCALED):
    """Each box halved along its widest (relative to the others' widths) direction."""
    w = np.stack([hi[k] - lo[k] for k in names], axis=1)
    scale = np.where(w.max(axis=0) > 0, w.max(axis=0), 1.0)
    dim = np.argmax(w / scale, axis=1)
    lo1, hi1, lo2, hi2 = dict(lo), dict(hi), dict(lo), dict(hi)
    for j, k in enumerate(names):
        m = np.clip(0.5 * lo[k] + 0.5 * hi[k], lo[k], hi[k])
        hi1[k] = np.where(dim == j, m, hi[k])
        lo2[k] = np.where(dim == j, m, lo[k])
    return ({k: np.concatenate([lo1[k], lo2[k]]) for k in names},
            {k: np.concatenate([hi1[k], hi2[k]]) for k in names})


def confirm_boxes(case, n, lo, hi, cls, *, witness_s=None, witness_wall=None, split=2,
                  ops=None):
    """Prove existence and the class of every box in arb, halving a box that fails.

    Parameters
    ----------
    lo, hi : dict
        ``name -> array`` of the scaled parameters (:data:`SCALED`).
    cls : ndarray of int
        1 stable, 2 unstable, 3 no orbit (needs ``witness_s``, ``witness_wall``).
    split : int
        Times a failing box is halved (into up to ``2^split`` parts, all to be proved).

    Returns
    -------
    ndarray of bool
    """
    ops = ops or arb_form_ops()
    cls = np.asarray(cls)
    N = cls.size
    owner = np.arange(N)
    ok_all = np.ones(N, bool)
    cur_lo, cur_hi = {k: np.asarray(lo[k], float) for k in SCALED}, \
        {k: np.asarray(hi[k], float) for k in SCALED}
    s = None if witness_s is None else np.asarray(witness_s, float)
    wall = None if witness_wall is None else np.asarray(witness_wall)
    for level in range(split + 1):
        if owner.size == 0:
            break
        box = ArbBoxes(cur_lo, cur_hi)
        c = cls[owner]
        ok = np.zeros(owner.size, bool)
        orb = c != 3
        if np.any(orb):
            sub = box.take(np.flatnonzero(orb))
            esc = bool(np.any(c[orb] == 2))
            q = _ranges(orbit_enclosures(case, n, sub, ops=ops, escape=esc))
            ok[orb] = _decide(q, c[orb])
        wit = ~orb
        if np.any(wit):
            sub = box.take(np.flatnonzero(wit))
            q = _ranges(witness_enclosures(case, n, sub, s[owner[wit]], ops=ops))
            ok[wit] = exists(q) & is_violated(q, wall[owner[wit]])
        bad = ~ok
        if not np.any(bad) or level == split:
            ok_all[owner[bad]] = False
            break
        # halves of the failing boxes; a box is proved when all its parts are
        blo = {k: v[bad] for k, v in cur_lo.items()}
        bhi = {k: v[bad] for k, v in cur_hi.items()}
        cur_lo, cur_hi = _halves(blo, bhi)
        owner = np.concatenate([owner[bad], owner[bad]])
    return ok_all


def confirm_map(case, n, shape, cell_lo, cell_hi, flags, leaves, *, blocks=(4, 2), split=2,
                prec=PREC, jets=True):
    """Confirm in arb every proved cell of one map: existence and the deciding inequality.

    A cell is confirmed when every one of its leaves (the boxes the interval layer proved it
    on; the cell itself when it was proved whole) is proved in arb in the cell's class.
    Stages, each for the leaves the previous ones left:

    1. blocks of ``B x B`` cells (for each ``B`` of ``blocks``): the forms over the block; its
       ranges decide all its leaves at once, else each leaf from its value at its centre with
       the block's gradient and Hessian, else (``jets``) from its value and gradient at its
       centre with the block's Hessian (:func:`taylor_bound`);
    2. each leaf's own forms, the leaf halved up to ``split`` times where it fails.

    A contact (no orbit) is proved at the time ``s*`` of the block's middle cell (blocks) or
    of the leaf.

    Parameters
    ----------
    case : str
    n : int
    shape : (ny, nx)
        The grid; cells are numbered row by row.
    cell_lo, cell_hi : dict
        ``name -> array (ny * nx,)`` of the cells' scaled parameters (:data:`SCALED`).
    flags : ndarray of int, shape (ny * nx,)
        The classes the interval layer proved (0 undecided, 1 stable, 2 unstable, 3 no orbit).
    leaves : dict
        The proof's leaves: ``cell`` (owner cell), ``lo``, ``hi`` (dicts of arrays), ``cls``,
        ``witness_s``, ``witness_wall``.
    blocks : tuple of int
        Block sizes tried first (largest first; ``()``: leaves only).
    split : int
        Halvings of a failing leaf.
    prec : int
        Working precision (bits).
    jets : bool
        Use the gradients at the leaves' centres (stage 1).

    Returns
    -------
    confirmed : ndarray of bool, shape (ny * nx,)
        Proved cells confirmed (the others ``False``).
    stats : dict
        Leaves confirmed by each stage (``"block B"``, ``"point B"``, ``"jets B"``,
        ``"leaves"``), the seconds each took (``"seconds ..."``) and the boxes evaluated.
    """
    flint = _flint()
    flags = np.asarray(flags).ravel()
    lo = {k: np.asarray(cell_lo[k], float).ravel() for k in SCALED}
    hi = {k: np.asarray(cell_hi[k], float).ravel() for k in SCALED}
    cell = np.asarray(leaves["cell"], np.int64)
    llo = {k: np.asarray(leaves["lo"][k], float) for k in SCALED}
    lhi = {k: np.asarray(leaves["hi"][k], float) for k in SCALED}
    ws = np.nan_to_num(np.asarray(leaves["witness_s"], float), nan=0.5)
    ww = np.asarray(leaves["witness_wall"], np.int64)
    ww = np.where(ww != 0, ww, 1)
    proved = flags != 0
    use = proved[cell] if cell.size else np.zeros(0, bool)
    done = np.zeros(cell.size, bool)          # leaves confirmed
    lcls = flags[cell] if cell.size else np.zeros(0, np.int64)
    stats = {"boxes": 0}
    with flint.ctx.workprec(prec):
        ops = arb_form_ops()
        first = _first_leaf(leaves, flags.size)
        s_cell = np.where(first >= 0, ws[np.maximum(first, 0)] if cell.size else 0.5, 0.5)
        qpt = qjet = None
        leaf_pos = np.full(cell.size, -1, np.int64)
        orbit_leaf = use & ((lcls == 1) | (lcls == 2))
        for B in blocks:
            for kind in ("orbit", "witness"):
                t_stage = time.perf_counter()
                target = (flags == 3) if kind == "witness" else ((flags == 1) | (flags == 2))
                lt = use & (lcls == 3) if kind == "witness" else orbit_leaf
                open_cells = np.zeros(flags.size, bool)
                open_cells[cell[lt & ~done]] = True
                pending = target & open_cells
                if not np.any(pending):
                    continue
                cells, gi = _groups(shape, pending, B)
                if cells.size == 0:
                    continue
                blo, bhi = _block_bounds(lo, hi, cells, gi)
                bbox = ArbBoxes(blo, bhi)
                stats["boxes"] += bbox.N
                block_of = np.full(flags.size, -1, np.int64)
                block_of[cells] = gi
                sel = np.flatnonzero(lt & ~done & (block_of[cell] >= 0))
                g = block_of[cell[sel]]
                if kind == "witness":
                    counts = np.bincount(gi)
                    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
                    mid = cells[starts + counts // 2]
                    q = _ranges(witness_enclosures(case, n, bbox, s_cell[mid], ops=ops))
                    okb = exists(q) & is_violated(q)
                    hit = okb[g]
                    done[sel[hit]] = True
                    stats[f"block {B}"] = stats.get(f"block {B}", 0) + int(hit.sum())
                    stats[f"seconds witness {B}"] = time.perf_counter() - t_stage
                    continue
                esc = bool(np.any(flags[cells] == 2))
                qb = orbit_enclosures(case, n, bbox, ops=ops, escape=esc)
                hit = _decide(_take_ranges(_ranges(qb), g), lcls[sel])
                done[sel[hit]] = True
                stats[f"block {B}"] = stats.get(f"block {B}", 0) + int(hit.sum())
                sel, g = sel[~hit], g[~hit]
                if sel.size == 0:
                    continue
                if qpt is None:
                    todo = np.flatnonzero(orbit_leaf & ~done)
                    leaf_pos[todo] = np.arange(todo.size)
                    mid_ = {k: (llo[k][todo] + lhi[k][todo]) * 0.5 for k in SCALED}
                    qpt = _ranges(orbit_enclosures(case, n, ArbBoxes(mid_, mid_), ops=ops,
                                                   escape=bool(np.any(lcls[todo] == 2))))
                have = leaf_pos[sel] >= 0
                sel, g = sel[have], g[have]
                lbox = ArbBoxes({k: llo[k][sel] for k in SCALED},
                                {k: lhi[k][sel] for k in SCALED})
                q = _from_block(_take_ranges(qpt, leaf_pos[sel]), qb, g, lbox, bbox)
                ok = _decide(q, lcls[sel])
                done[sel[ok]] = True
                stats[f"point {B}"] = stats.get(f"point {B}", 0) + int(ok.sum())
                sel, g = sel[~ok], g[~ok]
                if not jets or sel.size == 0:
                    continue
                if qjet is None:
                    todo = np.flatnonzero(orbit_leaf & ~done)
                    jet_pos = np.full(cell.size, -1, np.int64)
                    jet_pos[todo] = np.arange(todo.size)
                    qjet = orbit_enclosures(case, n, ArbBoxes({k: llo[k][todo] for k in SCALED},
                                                              {k: lhi[k][todo] for k in SCALED}),
                                            jets=True, ops=ops,
                                            escape=bool(np.any(lcls[todo] == 2)))
                have = jet_pos[sel] >= 0
                sel, g = sel[have], g[have]
                lbox = ArbBoxes({k: llo[k][sel] for k in SCALED},
                                {k: lhi[k][sel] for k in SCALED})
                q = _taylor_from_block(qjet, jet_pos[sel], qb, g, lbox)
                ok = _decide(q, lcls[sel])
                done[sel[ok]] = True
                stats[f"jets {B}"] = stats.get(f"jets {B}", 0) + int(ok.sum())
                stats[f"seconds orbit {B}"] = time.perf_counter() - t_stage
        # each leaf's own forms, halved where it fails
        rest = np.flatnonzero(use & ~done)
        t_stage = time.perf_counter()
        if rest.size:
            stats["leaves orbit/witness"] = (int((lcls[rest] != 3).sum()),
                                             int((lcls[rest] == 3).sum()))
            ok = confirm_boxes(case, n, {k: llo[k][rest] for k in SCALED},
                               {k: lhi[k][rest] for k in SCALED}, lcls[rest],
                               witness_s=ws[rest], witness_wall=ww[rest], split=split, ops=ops)
            done[rest[ok]] = True
            stats["boxes"] += rest.size
            stats["leaves"] = int(ok.sum())
        stats["seconds leaves"] = time.perf_counter() - t_stage
    bad = np.zeros(flags.size, bool)
    bad[cell[use & ~done]] = True
    has = np.zeros(flags.size, bool)
    has[cell[use]] = True
    confirmed = proved & has & ~bad
    return confirmed, stats


def _first_leaf(leaves, N):
    """Index of the first leaf of each cell (-1 if none)."""
    first = np.full(N, -1, np.int64)
    cell = np.asarray(leaves["cell"], np.int64)
    if cell.size:
        first[cell[::-1]] = np.arange(cell.size)[::-1]
    return first
