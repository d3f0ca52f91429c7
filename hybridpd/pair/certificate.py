"""Certificates of certified maps: the proof tree in a file, re-checked in ``arb`` alone.

A certified map (:func:`hybridpd.pair.certified.certified_map`) proves a class for every
cell it decides. Its *certificate* is what the proof consists of, cell by cell:

* the map: case, order, swept axes and their cell edges, the fixed parameters, the cells'
  boxes in the scaled parameters the closed forms take (``kpt = kp/m2``, ``kvt = kv/m2``,
  ``mu``, ``e``, ``gam = L/x10``, ``w = omega``) and every cell's class;
* for every proved cell its *leaves*: the boxes the cell was cut into (the cell itself when
  it was proved whole), each with its class and the enclosures that decided it: ``det M``
  and ``C`` or ``S`` (existence), the six Lienard-Chipart quantities (stable), the quantity
  beyond its bound (unstable: which one and its enclosure), the time ``s*`` and the wall of a
  contact (no orbit);
* for every stable or unstable leaf the *pieces* of the flight proved inside the walls, with
  the test that proved each (``inside``, ``first``, ``last``; ``mono`` when on a face of the
  box where the tested quantity is least).

:meth:`Certificate.save` writes it as JSON (gzip-compressed when the name ends in ``.gz``);
:func:`load_certificate` reads it back. :func:`verify_certificate` re-proves it with
:mod:`hybridpd.pair.arbcheck` alone, at ``arb`` precision, without NumPy's interval code:

1. the cells' scaled boxes contain the map's cells (``kp/m2`` and ``kv/m2`` of the cell
   edges, ``L/x10``, ...), and the cells tile the swept rectangle;
2. the leaves of every proved cell lie in it, do not overlap and cover it (their areas sum
   to its area, exactly); the pieces of every orbit leaf cover the flight ``[0, 1]``;
3. every leaf's class is proved again in arb: existence and the stability quantities, or the
   contact at its ``s*``; every piece of an orbit leaf is proved inside the walls. Where a
   box fails arb may halve it (a parameter box up to twice, a piece up to twice): a box is
   proved when all its parts are.

The recorded enclosures are not trusted; those of ``det M`` are compared with arb's own, and
the leaves where the two do not meet are counted (one of them would be wrong). The result is a :class:`CertificateCheck`.
"""
from __future__ import annotations

import gzip
import json
import math
import time
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

import numpy as np

from hybridpd._results import compact_repr

__all__ = ["CLASS_NAMES", "Certificate", "CertificateCheck", "load_certificate",
           "verify_certificate"]

#: Class codes of a certified map (its CF flag values) and their names.
CLASS_NAMES = ("undecided", "proved_stable", "proved_unstable", "proved_no_orbit")
_SCALED = ("kpt", "kvt", "mu", "e", "gam", "w")
_FORMAT = "hybridpd-certificate"
_VERSION = 1
_PIECE_KINDS = ("inside", "first", "last")
_UNSTABLE_KINDS = ("hurwitz", "coeff", "trace")

_LEAF_COLUMNS = ("cell", "cls", "xm_which", "det_lo", "det_hi", "xm_lo", "xm_hi",
                 "hurwitz_lo", "hurwitz_hi", "unstable_kind", "unstable_index", "unstable_lo",
                 "unstable_hi", "witness_s", "witness_wall", "witness_lo", "witness_hi")
_PIECE_COLUMNS = ("leaf", "a", "b", "kind", "mono", "z3_lo", "z3_hi")


def _clean(x):
    """JSON-ready lists: NaN -> None, NumPy scalars -> Python."""
    if isinstance(x, np.ndarray):
        return _clean(x.tolist())
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    if isinstance(x, dict):
        return {k: _clean(v) for k, v in x.items()}
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return None if math.isnan(v) else v
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def _floats(v):
    return np.array([np.nan if x is None else x for x in v], float) if not \
        isinstance(v, np.ndarray) else v.astype(float)


def _decision(cls, kind, index, wall):
    """The deciding inequality of a leaf, in words."""
    if cls == 1:
        return "q0..q4 > 0 and Delta_3 > 0 (Lienard-Chipart: every multiplier inside)"
    if cls == 2:
        k = _UNSTABLE_KINDS[kind] if kind >= 0 else "?"
        if k == "hurwitz":
            name = ("q0", "q1", "q2", "q3", "q4", "Delta_3")[index]
            return f"{name} < 0 (a multiplier outside the unit circle)"
        if k == "coeff":
            return f"|c_{index}| > C(4, {index}) (a multiplier outside the unit circle)"
        return f"|tr M^{index}| > 4 (a multiplier outside the unit circle)"
    if cls == 3:
        return "L - z3(s*) < 0 (a contact at +L)" if wall == 1 else \
            "z3(s*) + L < 0 (a contact at -L)"
    return ""


@dataclass
class Certificate:
    """The proof of a certified map (see the module), one part per restitution coefficient.

    Attributes
    ----------
    case : str
    n : int
    x_name, y_name : str
    x_edges, y_edges : ndarray
        Cell edges of the swept axes.
    fixed : dict
        The parameters that are not swept (``mu, omega, L, x10, m2``, ...).
    e : ndarray
        Restitution coefficients.
    maps : list of dict
        Per ``e``: ``flags`` (shape ``(ny, nx)``), ``cells`` (``lo``, ``hi``: scaled
        parameter -> array ``(ny * nx,)``), ``leaves`` (columns, ``lo``/``hi`` dicts) and
        ``pieces`` (columns).
    """

    __repr__ = compact_repr

    case: str
    n: int
    x_name: str
    y_name: str
    x_edges: np.ndarray
    y_edges: np.ndarray
    fixed: dict
    e: np.ndarray
    maps: list = field(repr=False)

    @property
    def proved_cells(self) -> int:
        """Number of cells proved in some class (all ``e``)."""
        return int(sum((np.asarray(m["flags"]) != 0).sum() for m in self.maps))

    @property
    def leaves(self) -> int:
        """Number of leaves (all ``e``)."""
        return int(sum(len(m["leaves"]["cell"]) for m in self.maps))

    def to_dict(self) -> dict:
        """JSON-ready form (the file's content)."""
        maps = []
        for m in self.maps:
            lv, pc = m["leaves"], m["pieces"]
            leaves = {k: lv[k] for k in _LEAF_COLUMNS}
            leaves["lo"], leaves["hi"] = lv["lo"], lv["hi"]
            leaves["decision"] = [
                _decision(int(c), int(k), int(i), int(w)) for c, k, i, w in
                zip(lv["cls"], lv["unstable_kind"], lv["unstable_index"], lv["witness_wall"])]
            maps.append({"e": m["e"], "flags": np.asarray(m["flags"]).tolist(),
                         "cells": {"lo": m["cells"]["lo"], "hi": m["cells"]["hi"]},
                         "leaves": leaves,
                         "pieces": {k: pc[k] for k in _PIECE_COLUMNS}})
        return _clean({
            "format": _FORMAT, "version": _VERSION,
            "about": "proof tree of a certified map of hybridpd (see hybridpd.pair.certificate)",
            "case": self.case, "n": self.n, "x_name": self.x_name, "y_name": self.y_name,
            "x_edges": self.x_edges, "y_edges": self.y_edges, "fixed": self.fixed,
            "e": self.e, "class_names": list(CLASS_NAMES), "piece_kinds": list(_PIECE_KINDS),
            "unstable_kinds": list(_UNSTABLE_KINDS), "scaled": list(_SCALED), "maps": maps})

    def save(self, path):
        """Write the certificate as JSON (``.gz``: compressed); returns the path."""
        path = Path(path)
        text = json.dumps(self.to_dict(), separators=(",", ":"))
        if path.suffix == ".gz":
            with gzip.open(path, "wt", encoding="utf-8") as f:
                f.write(text)
        else:
            path.write_text(text, encoding="utf-8")
        return path

    @classmethod
    def from_dict(cls, d) -> Certificate:
        """The certificate from its :meth:`to_dict` form."""
        if d.get("format") != _FORMAT:
            raise ValueError(f"not a hybridpd certificate (format {d.get('format')!r})")
        if d.get("version") != _VERSION:
            raise ValueError(f"certificate version must be {_VERSION}, got {d.get('version')!r}")
        maps = []
        for m in d["maps"]:
            lv, pc = m["leaves"], m["pieces"]
            leaves = {}
            for k in _LEAF_COLUMNS:
                v = lv[k]
                if k in ("hurwitz_lo", "hurwitz_hi"):
                    leaves[k] = np.array([[np.nan if x is None else x for x in row]
                                          for row in v], float).reshape(-1, 6)
                elif k in ("cell", "cls", "xm_which", "unstable_kind", "unstable_index",
                           "witness_wall"):
                    leaves[k] = np.asarray(v, np.int64)
                else:
                    leaves[k] = _floats(v)
            leaves["lo"] = {k: _floats(lv["lo"][k]) for k in _SCALED}
            leaves["hi"] = {k: _floats(lv["hi"][k]) for k in _SCALED}
            pieces = {k: (np.asarray(pc[k], np.int64) if k in ("leaf", "kind") else
                          np.asarray(pc[k], bool) if k == "mono" else _floats(pc[k]))
                      for k in _PIECE_COLUMNS}
            maps.append({"e": float(m["e"]), "flags": np.asarray(m["flags"], np.int64),
                         "cells": {"lo": {k: _floats(m["cells"]["lo"][k]) for k in _SCALED},
                                   "hi": {k: _floats(m["cells"]["hi"][k]) for k in _SCALED}},
                         "leaves": leaves, "pieces": pieces})
        return cls(d["case"], int(d["n"]), d["x_name"], d["y_name"],
                   np.asarray(d["x_edges"], float), np.asarray(d["y_edges"], float),
                   dict(d["fixed"]), np.asarray(d["e"], float), maps)


def load_certificate(path) -> Certificate:
    """Read a certificate written by :meth:`Certificate.save`.

    Parameters
    ----------
    path : str or Path
        A ``.json`` or ``.json.gz`` file.

    Returns
    -------
    Certificate

    Examples
    --------
    >>> import hybridpd as hp
    >>> cm = hp.certified_map("collocated", x=("kp", 9, 11, 2), y=("kv", 19, 21, 2), e=[0.5],
    ...                       mu=0.1, gamma=0.75, omega=5.0, certificate="cert.json")
    >>> cert = hp.load_certificate("cert.json")
    >>> cert.proved_cells, cert.case
    (4, 'collocated')
    """
    path = Path(path)
    if not path.exists():
        raise ValueError(f"certificate file {str(path)!r} does not exist")
    if path.suffix == ".gz":
        with gzip.open(path, "rt", encoding="utf-8") as f:
            d = json.load(f)
    else:
        d = json.loads(path.read_text(encoding="utf-8"))
    return Certificate.from_dict(d)


# ----------------------------------------------------------------------------------------
# Building a certificate from the proofs
# ----------------------------------------------------------------------------------------


def leaves_columns(tree, cell_offset=0):
    """The leaf and piece columns of a :class:`hybridpd.pair.prooftree.ProofTree`."""
    r = tree.record
    leaves = {
        "cell": np.asarray(tree.leaf_cell, np.int64) + cell_offset,
        "cls": np.asarray(tree.leaf_cls, np.int64),
        "xm_which": np.asarray(r["xm_which"], np.int64),
        "det_lo": r["det"][0], "det_hi": r["det"][1], "xm_lo": r["xm"][0], "xm_hi": r["xm"][1],
        "hurwitz_lo": r["hurwitz"][0], "hurwitz_hi": r["hurwitz"][1],
        "unstable_kind": np.asarray(r["unstable_kind"], np.int64),
        "unstable_index": np.asarray(r["unstable_index"], np.int64),
        "unstable_lo": r["unstable_value"][0], "unstable_hi": r["unstable_value"][1],
        "witness_s": r["witness_s"], "witness_wall": np.asarray(r["witness_wall"], np.int64),
        "witness_lo": r["witness_value"][0], "witness_hi": r["witness_value"][1],
        "lo": {k: tree.leaves.lo[k] for k in _SCALED},
        "hi": {k: tree.leaves.hi[k] for k in _SCALED}}
    p = r["pieces"]
    pieces = {"leaf": np.asarray(p["owner"], np.int64), "a": p["a"], "b": p["b"],
              "kind": np.asarray(p["kind"], np.int64), "mono": np.asarray(p["mono"], bool),
              "z3_lo": p["lo"], "z3_hi": p["hi"]}
    return leaves, pieces


def concat_columns(parts):
    """Leaf and piece columns of several trees (``(leaves, pieces)`` pairs) as one."""
    if not parts:
        return _empty_columns()
    leaves, pieces = {}, {}
    offset = 0
    for lv, pc in parts:
        for k, v in lv.items():
            if isinstance(v, dict):
                leaves.setdefault(k, {kk: [] for kk in v})
                for kk, vv in v.items():
                    leaves[k][kk].append(vv)
            else:
                leaves.setdefault(k, []).append(v)
        for k, v in pc.items():
            pieces.setdefault(k, []).append(v + offset if k == "leaf" else v)
        offset += len(lv["cell"])
    cat = lambda xs: np.concatenate(xs) if xs else np.zeros(0)
    leaves = {k: ({kk: cat(vv) for kk, vv in v.items()} if isinstance(v, dict) else
                  (np.concatenate(v, axis=0) if v[0].ndim > 1 else cat(v)))
              for k, v in leaves.items()}
    pieces = {k: cat(v) for k, v in pieces.items()}
    return leaves, pieces


def _empty_columns():
    z, zi = np.zeros(0), np.zeros(0, np.int64)
    leaves = {k: zi if k in ("cell", "cls", "xm_which", "unstable_kind", "unstable_index",
                             "witness_wall") else z for k in _LEAF_COLUMNS}
    leaves["hurwitz_lo"] = leaves["hurwitz_hi"] = np.zeros((0, 6))
    leaves["lo"] = {k: z for k in _SCALED}
    leaves["hi"] = {k: z for k in _SCALED}
    pieces = {k: zi if k in ("leaf", "kind") else np.zeros(0, bool) if k == "mono" else z
              for k in _PIECE_COLUMNS}
    return leaves, pieces


def restrict(leaves, pieces, keep_cells):
    """The leaves (and their pieces) of the cells where ``keep_cells``; leaf indices renumbered."""
    keep = np.asarray(keep_cells, bool)[leaves["cell"]] if len(leaves["cell"]) else \
        np.zeros(0, bool)
    idx = np.flatnonzero(keep)
    renum = np.full(len(leaves["cell"]), -1, np.int64)
    renum[idx] = np.arange(idx.size)
    lv = {k: ({kk: vv[idx] for kk, vv in v.items()} if isinstance(v, dict) else v[idx])
          for k, v in leaves.items()}
    ps = keep[pieces["leaf"]] if len(pieces["leaf"]) else np.zeros(0, bool)
    pc = {k: (renum[v[ps]] if k == "leaf" else v[ps]) for k, v in pieces.items()}
    return lv, pc


# ----------------------------------------------------------------------------------------
# Verification in arb
# ----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class CertificateCheck:
    """The outcome of :func:`verify_certificate`.

    Attributes
    ----------
    ok : bool
        Every claim of the certificate was re-proved (and nothing failed).
    cells : int
        Cells the certificate claims proved (all ``e``).
    reproved : int
        Of those, cells re-proved in arb (structure, every leaf's class and, with
        ``viability``, every piece of the flight).
    failed : list of dict
        One entry per failed cell: ``e``, ``ix``, ``iy``, ``claimed`` (class name) and
        ``why`` (what could not be proved), at most ``max_failures`` of them.
    structure_errors : list of str
        Faults of the file's structure (cells that do not cover the map, leaves that do not
        tile their cell, pieces that do not cover the flight, ...).
    disagreements : int
        Leaves whose recorded enclosure of ``det M`` arb's enclosure does not meet
        (reported; neither is trusted for the verdict).
    leaves, pieces : int
        Leaves and pieces checked.
    viability : bool
        Whether the pieces of the flight were checked.
    precision : int
        arb's working precision (bits).
    seconds : float
    """

    __repr__ = compact_repr

    ok: bool
    cells: int
    reproved: int
    failed: list = field(repr=False)
    structure_errors: list = field(repr=False)
    disagreements: int
    leaves: int
    pieces: int
    viability: bool
    precision: int
    seconds: float

    def summary(self) -> str:
        """One line."""
        s = (f"{'OK' if self.ok else 'FAILED'}: {self.reproved}/{self.cells} proved cells "
             f"re-proved in arb ({self.leaves} leaves, {self.pieces} pieces, "
             f"{self.precision} bits, {self.seconds:.1f} s)")
        if self.failed:
            s += f"; {len(self.failed)} failed"
        if self.structure_errors:
            s += f"; {len(self.structure_errors)} structure errors"
        return s


def _physical_cells(cert: Certificate):
    """The swept rectangle's cells as physical ``(lo, hi)`` per parameter, row by row."""
    xe, ye = cert.x_edges, cert.y_edges
    XL, YL = np.meshgrid(xe[:-1], ye[:-1])
    XH, YH = np.meshgrid(xe[1:], ye[1:])
    out = {cert.x_name: (XL.ravel(), XH.ravel()), cert.y_name: (YL.ravel(), YH.ravel())}
    for k, v in cert.fixed.items():
        if k in ("n",):
            continue
        out.setdefault(k, (np.full(XL.size, float(v)), np.full(XL.size, float(v))))
    return out


def _check_scaling(cert: Certificate, m, errors):
    """The scaled boxes of the cells contain the physical cells (in arb)."""
    from flint import arb

    phys = _physical_cells(cert)
    need = {"kp", "kv", "mu", "L", "x10", "m2", "omega"}
    missing = [k for k in need if k not in phys]
    if missing:
        errors.append(f"e = {m['e']:g}: the map does not give {sorted(missing)}")
        return np.zeros(len(m["flags"].ravel()), bool)
    lo, hi = m["cells"]["lo"], m["cells"]["hi"]
    N = m["flags"].size
    ok = np.ones(N, bool)
    a = lambda k, i: arb(float(phys[k][0][i]))
    b = lambda k, i: arb(float(phys[k][1][i]))
    for i in range(N):
        # the exact ranges of the scaled parameters over the cell (quotients are monotone)
        want = {"kpt": (a("kp", i) / b("m2", i), b("kp", i) / a("m2", i)),
                "kvt": (a("kv", i) / b("m2", i), b("kv", i) / a("m2", i)),
                "mu": (a("mu", i), b("mu", i)), "e": (arb(m["e"]), arb(m["e"])),
                "gam": (a("L", i) / b("x10", i), b("L", i) / a("x10", i)),
                "w": (a("omega", i), b("omega", i))}
        for k in _SCALED:
            w_lo, w_hi = want[k]
            if not (arb(float(lo[k][i])) <= w_lo and w_hi <= arb(float(hi[k][i]))):
                ok[i] = False
                break
    if not ok.all():
        errors.append(f"e = {m['e']:g}: {int((~ok).sum())} cells' scaled boxes do not contain "
                      "the map's cells")
    return ok


def _area(lo, hi, k):
    a = Fraction(1)
    for name in _SCALED:
        w = Fraction(float(hi[name][k])) - Fraction(float(lo[name][k]))
        if w != 0:
            a *= w
    return a


def _check_tiling(m, errors):
    """Leaves inside their cell, pairwise disjoint, areas summing to the cell's; pieces cover
    ``[0, 1]``. Returns per cell (structure ok) and per leaf (pieces ok) flags."""
    flags = m["flags"].ravel()
    cl, ch = m["cells"]["lo"], m["cells"]["hi"]
    lv, pc = m["leaves"], m["pieces"]
    L = len(lv["cell"])
    cell_ok = np.ones(flags.size, bool)
    by_cell = {}
    for j, c in enumerate(lv["cell"]):
        by_cell.setdefault(int(c), []).append(j)
    for c in np.flatnonzero(flags != 0):
        js = by_cell.get(int(c), [])
        if not js:
            cell_ok[c] = False
            continue
        good = all(int(lv["cls"][j]) == int(flags[c]) for j in js)
        for j in js:
            for k in _SCALED:
                if not (cl[k][c] <= lv["lo"][k][j] <= lv["hi"][k][j] <= ch[k][c]):
                    good = False
        # disjoint interiors and total area: the parts cover the cell
        if good and len(js) > 1:
            total = sum((_area(lv["lo"], lv["hi"], j) for j in js), Fraction(0))
            cell_area = _area(cl, ch, c)
            good = total == cell_area and _disjoint(lv, js)
        elif good:
            good = all(lv["lo"][k][js[0]] == cl[k][c] and lv["hi"][k][js[0]] == ch[k][c]
                       for k in _SCALED)
        cell_ok[c] = good
    bad_cells = np.flatnonzero((flags != 0) & ~cell_ok)
    if bad_cells.size:
        errors.append(f"e = {m['e']:g}: {bad_cells.size} proved cells whose leaves do not tile "
                      "them in their class")
    leaf_ok = np.ones(L, bool)
    by_leaf = {}
    for i, j in enumerate(pc["leaf"]):
        by_leaf.setdefault(int(j), []).append(i)
    for j in range(L):
        if int(lv["cls"][j]) not in (1, 2):
            continue
        ps = sorted(by_leaf.get(j, []), key=lambda i: pc["a"][i])
        edge = 0.0
        good = bool(ps)
        for i in ps:
            if pc["a"][i] != edge or not pc["b"][i] > pc["a"][i]:
                good = False
                break
            kind = int(pc["kind"][i])
            if (kind == 1) != (pc["a"][i] == 0.0) or (kind == 2) != (pc["b"][i] == 1.0):
                good = False
                break
            edge = pc["b"][i]
        leaf_ok[j] = good and edge == 1.0
    if not leaf_ok.all():
        errors.append(f"e = {m['e']:g}: {int((~leaf_ok).sum())} orbit leaves whose pieces do not "
                      "cover the flight [0, 1]")
    return cell_ok, leaf_ok


def _disjoint(lv, js):
    for a in range(len(js)):
        for b in range(a + 1, len(js)):
            i, j = js[a], js[b]
            if all(min(lv["hi"][k][i], lv["hi"][k][j]) > max(lv["lo"][k][i], lv["lo"][k][j])
                   for k in _SCALED if lv["hi"][k][i] > lv["lo"][k][i]):
                return False
    return True


def _prove_pieces(case, n, lv, pc, leaves_idx, ops, split=2):
    """Every piece of the given leaves proved inside the walls (halved up to ``split``
    times in time where it fails); returns per piece."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair import arbcheck as ac

    sel = np.flatnonzero(np.isin(pc["leaf"], leaves_idx))
    ok_all = np.ones(len(pc["leaf"]), bool)
    if sel.size == 0:
        return ok_all
    owner = sel
    a, b = pc["a"][sel].astype(float), pc["b"][sel].astype(float)
    kind = pc["kind"][sel].astype(np.int64)
    for level in range(split + 1):
        leaf = pc["leaf"][owner]
        box = ac.ArbBoxes({k: lv["lo"][k][leaf] for k in _SCALED},
                          {k: lv["hi"][k][leaf] for k in _SCALED})
        ok = ac.piece_proved(case, n, box, a, b, kind, ops=ops)
        bad = ~ok
        if not np.any(bad) or level == split:
            ok_all[owner[bad]] = False
            break
        o, lo_, hi_, kd = owner[bad], a[bad], b[bad], kind[bad]
        mid = 0.5 * (lo_ + hi_)
        owner = np.concatenate([o, o])
        a = np.concatenate([lo_, mid])
        b = np.concatenate([mid, hi_])
        # the halves keep the end tests only at the flight's ends
        kind = np.concatenate([np.where(kd == 2, 0, kd), np.where(kd == 1, 0, kd)])
    return ok_all


def verify_certificate(certificate, *, viability=True, prec=None, max_failures=100):
    """Re-prove a certificate of a certified map in ``arb`` alone (see the module).

    Parameters
    ----------
    certificate : str, Path or Certificate
        A certificate file (``.json``, ``.json.gz``) or a loaded certificate.
    viability : bool
        Also re-prove every piece of the flight of every stable and unstable leaf (the
        largest part of the work).
    prec : int or None
        arb's working precision in bits (default :data:`hybridpd.pair.arbcheck.PREC`).
    max_failures : int
        Failed cells listed at most.

    Returns
    -------
    CertificateCheck

    Examples
    --------
    >>> import hybridpd as hp
    >>> from hybridpd.pair.certified import certified_map
    >>> cm = certified_map("noncollocated", x=("kp", 10, 13, 3), y=("kv", 19.5, 23.5, 3),
    ...                    e=[0.5], mu=0.1, gamma=0.75, omega=5.0, certificate=True)
    >>> chk = hp.verify_certificate(cm.certificate)
    >>> chk.ok, chk.reproved == chk.cells
    (True, True)
    """
    from flint import ctx

    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair import arbcheck as ac

    t0 = time.perf_counter()
    cert = certificate if isinstance(certificate, Certificate) else \
        load_certificate(certificate)
    prec = ac.PREC if prec is None else int(prec)
    errors, failed = [], []
    cells = reproved = disagreements = n_leaves = n_pieces = 0
    xe, ye = np.asarray(cert.x_edges), np.asarray(cert.y_edges)
    if not (np.all(np.diff(xe) > 0) and np.all(np.diff(ye) > 0)):
        errors.append("the cell edges are not increasing")
    with ctx.workprec(prec):
        ops = ac.arb_form_ops()
        for m in cert.maps:
            flags = np.asarray(m["flags"]).ravel()
            ny, nx = ye.size - 1, xe.size - 1
            if flags.size != nx * ny:
                errors.append(f"e = {m['e']:g}: {flags.size} flags for {ny} x {nx} cells")
                continue
            scaled_ok = _check_scaling(cert, m, errors)
            cell_ok, leaf_ok = _check_tiling(m, errors)
            lv, pc = m["leaves"], m["pieces"]
            L = len(lv["cell"])
            n_leaves += L
            why = {}
            # every leaf's class
            leaf_proved = np.zeros(L, bool)
            if L:
                leaf_proved = ac.confirm_boxes(cert.case, cert.n, lv["lo"], lv["hi"], lv["cls"],
                                               witness_s=np.nan_to_num(lv["witness_s"], nan=0.5),
                                               witness_wall=np.where(lv["witness_wall"] != 0,
                                                                     lv["witness_wall"], 1),
                                               split=2, ops=ops)
                disagreements += _disagreements(cert.case, cert.n, lv, ops)
            piece_ok = np.ones(len(pc["leaf"]), bool)
            if viability and L:
                orbit_leaves = np.flatnonzero((lv["cls"] == 1) | (lv["cls"] == 2))
                piece_ok = _prove_pieces(cert.case, cert.n, lv, pc, orbit_leaves, ops)
                n_pieces += int(np.isin(pc["leaf"], orbit_leaves).sum())
            pieces_good = np.ones(L, bool)
            if len(pc["leaf"]):
                bad = np.zeros(L, bool)
                bad[pc["leaf"][~piece_ok]] = True
                pieces_good = ~bad
            for c in np.flatnonzero(flags != 0):
                cells += 1
                js = np.flatnonzero(lv["cell"] == c)
                problems = []
                if not scaled_ok[c]:
                    problems.append("the cell's scaled box does not contain the map's cell")
                if not cell_ok[c]:
                    problems.append("its leaves do not tile it in its class")
                if js.size and not leaf_proved[js].all():
                    problems.append(f"{int((~leaf_proved[js]).sum())} of {js.size} leaves not "
                                    "proved in their class")
                if js.size and not leaf_ok[js].all():
                    problems.append("the pieces of a leaf do not cover the flight")
                if viability and js.size and not pieces_good[js].all():
                    problems.append("a piece of the flight not proved inside the walls")
                if problems:
                    iy, ix = divmod(int(c), nx)
                    if len(failed) < max_failures:
                        failed.append({"e": float(m["e"]), "ix": ix, "iy": iy,
                                       "claimed": CLASS_NAMES[int(flags[c])],
                                       "why": "; ".join(problems)})
                    why[c] = problems
                else:
                    reproved += 1
    ok = not errors and reproved == cells
    return CertificateCheck(ok, cells, reproved, failed, errors, disagreements, n_leaves,
                            n_pieces, bool(viability), prec, time.perf_counter() - t0)


def _disagreements(case, n, lv, ops):
    """Leaves whose recorded enclosure of ``det M`` arb's enclosure over the leaf misses."""
    from flint import arb

    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair import arbcheck as ac

    L = len(lv["cell"])
    if L == 0:
        return 0
    box = ac.ArbBoxes(lv["lo"], lv["hi"])
    nn = arb(n)
    det = ac._range(ac._kernel("existence", case)(ops, *box.params(), nn)[2])
    count = 0
    for d, lo, hi in zip(det, lv["det_lo"], lv["det_hi"]):
        if math.isnan(lo) or math.isnan(hi) or not d.is_finite():
            continue
        if not d.overlaps(arb(lo).union(arb(hi))):
            count += 1
    return count
