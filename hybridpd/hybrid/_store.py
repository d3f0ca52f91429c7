"""Growable packed tables of a hybrid automaton's modes (the inputs of the jump loop).

A :class:`ModeStore` holds the stacked arrays of :class:`~hybridpd.hybrid._kernel.PackedAutomaton`
for the modes built so far, one row each. A mode that a guard names but that is not built yet
is *reserved*: the guard's target is the code ``-2 - r`` (``r`` the reservation number),
which the jump loop reports as "mode not built" (code 6) instead of entering it; building the
mode gives it a row and :meth:`ModeStore.patch` replaces the code by the row everywhere. So
only visited modes take table memory. The resets are stored once each, in a table shared by
all modes (a contact's impact law or a projection recurs across modes): a guard holds its
row there. Capacities grow by half, so building ``M`` modes costs ``O(M)`` copies of the
tables.
"""
from __future__ import annotations

import hashlib

import numpy as np

from hybridpd.hybrid._kernel import PackedAutomaton
from hybridpd.hybrid.events import prepare_lti_mode

__all__ = ["ModeStore", "reset_matrix"]


def reset_matrix(where, reset, n):
    """Homogeneous ``[[R, r], [0, 1]]`` of the reset ``(R, r)`` (identity for ``None``)."""
    Rh = np.eye(n + 1)
    if reset is None:
        return Rh
    try:
        R, r = reset
    except (TypeError, ValueError):
        raise ValueError(f"{where} must be a pair (R, r)") from None
    R = np.asarray(R, dtype=float)
    r = np.asarray(r, dtype=float)
    if R.shape != (n, n):
        raise ValueError(f"{where}: R must have shape ({n}, {n}), got {R.shape}")
    if r.shape != (n,):
        raise ValueError(f"{where}: r must have shape ({n},), got {r.shape}")
    if not (np.all(np.isfinite(R)) and np.all(np.isfinite(r))):
        raise ValueError(f"{where} must be finite")
    Rh[:n, :n] = R
    Rh[:n, n] = r
    return Rh


def _empty(cap, GM, Kp1, N1):
    return {
        "h": np.zeros(cap), "Phi": np.zeros((cap, N1, N1)), "Ah": np.zeros((cap, N1, N1)),
        "dinv": np.ones((cap, N1)), "trunc": np.zeros(cap), "G": np.zeros((cap, GM, Kp1, N1)),
        "gabs": np.zeros((cap, GM, Kp1, N1)), "gsum": np.zeros((cap, GM, N1)),
        "cnorm": np.zeros((cap, GM)), "prio": np.zeros((cap, GM), np.int64),
        "ng": np.full(cap, -1, np.int64), "rh": np.zeros((cap, GM), np.int64),
        "target": np.zeros((cap, GM), np.int64), "zt": np.full((cap, GM), -1, np.int64),
        "rz": np.zeros((cap, GM), np.int64), "gkind": np.zeros((cap, GM), np.int64),
        "gid": np.full((cap, GM), -1, np.int64)}


class ModeStore:
    """Packed tables of the built modes, with reserved slots for modes not built yet.

    Parameters
    ----------
    n : int
        State dimension.
    K : int
        Taylor order.
    theta : float
        Normalised flow step.
    """

    def __init__(self, n, K, theta):
        self.n, self.K, self.theta = int(n), int(K), float(theta)
        self.count = 0                       # rows in use (built modes)
        self.version = 0                     # changes whenever the tables do
        self.guard_ids = {}                  # guard name -> id, the same in every mode
        self._pk = _empty(4, 1, self.K + 1, self.n + 1)
        # the distinct resets: row 0 the identity; a mode's guards share them with other
        # modes' (a contact's impact law, a projection), so each is stored once
        self._R = np.zeros((4, self.n + 1, self.n + 1))
        self._n_resets = 0
        self._reset_row = {}
        self._reset(np.eye(self.n + 1))

    def _reset(self, Rh) -> int:
        """Row of the homogeneous reset ``Rh`` in the shared table (added if new)."""
        key = hashlib.blake2b(np.ascontiguousarray(Rh).view(np.uint8), digest_size=16).digest()
        row = self._reset_row.get(key)
        if row is not None and not np.array_equal(self._R[row], Rh):
            raise RuntimeError("two resets with one 128-bit digest")    # pragma: no cover
        if row is None:
            row = self._n_resets
            if row >= self._R.shape[0]:
                R = np.zeros((_grown(row), self.n + 1, self.n + 1))
                R[:row] = self._R[:row]
                self._R = R
            self._R[row] = Rh
            self._n_resets += 1
            self.version += 1
            self._reset_row[key] = row
        return row

    def _grow(self, cap, GM):
        old = self._pk
        ocap, oGM = old["h"].shape[0], old["G"].shape[1]
        if cap <= ocap and GM <= oGM:
            return
        cap, GM = max(cap, ocap), max(GM, oGM)
        new = _empty(cap, GM, self.K + 1, self.n + 1)
        c = self.count
        for k, a in old.items():
            if a.ndim == 1:
                new[k][:c] = a[:c]
            else:
                new[k][:c, :a.shape[1]] = a[:c]
        self._pk = new

    def add(self, mode, resolve, lazy_zeno=False) -> int:
        """Pack ``mode`` into a new row and return it; ``resolve(name, where) -> int`` gives
        the row (or reservation code) of each target. With ``lazy_zeno`` the Zeno resets are
        not packed (row ``-1``: the jump loop hands such a switch back, :meth:`set_zeno`)."""
        n, N1 = self.n, self.n + 1
        ngi = len(mode.guards)
        targets, zts, Rhs, Rzs = [], [], [], []
        for g in mode.guards:
            where = f"mode {mode.name!r} guard {g.name!r}"
            if g.c.shape != (n,):
                raise ValueError(f"{where}: c must have shape ({n},), got {g.c.shape}")
            targets.append(resolve(mode.name if g.target is None else g.target, where))
            Rhs.append(reset_matrix(f"{where} reset", g.reset, n))
            if g.zeno_target is not None:
                zts.append(resolve(g.zeno_target, where + " zeno_target"))
                Rzs.append(None if lazy_zeno else
                           reset_matrix(f"{where} zeno_reset", g.zeno_reset, n))
            else:
                zts.append(-1)
                Rzs.append(np.eye(N1))
        md = prepare_lti_mode(mode.A, mode.b, [(g.c, g.d, g.direction) for g in mode.guards],
                              K=self.K, theta=self.theta,
                              priorities=[g.priority for g in mode.guards])
        i = self.count
        cap = self._pk["h"].shape[0]
        self._grow(_grown(cap) if i >= cap else cap, max(1, ngi))
        self.count += 1
        pk = self._pk
        pk["h"][i] = md.h
        pk["Phi"][i] = md.Phi
        pk["Ah"][i] = md.Ah
        pk["dinv"][i] = md.dinv
        pk["trunc"][i] = md.trunc
        pk["G"][i, :ngi] = md.G
        pk["gabs"][i, :ngi] = md.gabs
        pk["gsum"][i, :ngi] = md.gsum
        pk["cnorm"][i, :ngi] = md.cnorm
        pk["prio"][i, :ngi] = md.prio
        pk["rh"][i] = 0
        pk["rz"][i] = 0
        for gi, g in enumerate(mode.guards):
            pk["target"][i, gi] = targets[gi]
            pk["zt"][i, gi] = zts[gi]
            pk["rh"][i, gi] = self._reset(Rhs[gi])
            pk["rz"][i, gi] = -1 if Rzs[gi] is None else self._reset(Rzs[gi])
            pk["gkind"][i, gi] = int(g.group)
            pk["gid"][i, gi] = self.guard_ids.setdefault(g.name, len(self.guard_ids))
        pk["ng"][i] = ngi
        self.version += 1
        return i

    def set_zeno(self, row, g, Rh) -> None:
        """Pack the homogeneous Zeno reset ``Rh`` of guard ``g`` of mode ``row``."""
        self._pk["rz"][row, g] = self._reset(Rh)
        self.version += 1

    def patch(self, code, row):
        """Replace the reservation ``code`` by ``row`` in the target tables."""
        c = self.count
        for key in ("target", "zt"):
            t = self._pk[key][:c]
            t[t == code] = row
        self.version += 1

    def packed(self) -> PackedAutomaton:
        """Views of the tables over the built rows (targets ``< -1``: reserved modes)."""
        c = self.count
        return PackedAutomaton(R=self._R[:self._n_resets],
                               **{k: v[:c] for k, v in self._pk.items()
                                  if k not in ("gkind", "gid")})

    def gkind(self) -> np.ndarray:
        """Per-guard simultaneity group (``(count, GM)`` int64, 0: none)."""
        return self._pk["gkind"][:self.count]

    def gid(self) -> np.ndarray:
        """Per-guard identity (``(count, GM)`` int64): guards of one name share it in every
        mode (:attr:`guard_ids`), so that a guard firing again after a mode change is seen."""
        return self._pk["gid"][:self.count]

    @property
    def nbytes(self) -> int:
        """Memory held by the tables (bytes)."""
        return int(sum(a.nbytes for a in self._pk.values())) + int(self._R.nbytes)


def _grown(cap) -> int:
    """The next capacity: half as large again (a doubling would hold up to twice the memory
    the modes need, and copy as much while it grows)."""
    return max(4, cap + cap // 2)
