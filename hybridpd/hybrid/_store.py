"""Growable packed tables of a hybrid automaton's modes (the inputs of the jump loop).

A :class:`ModeStore` holds the stacked arrays of :class:`~hybridpd.hybrid._kernel.PackedAutomaton`
for the modes known so far. A mode is *reserved* (it has an index, because a guard names it
as a target) before it is *built* (its flow and guards prepared and packed): a reserved slot
has ``ng = -1``, which the jump loop reports as "mode not built" (code 6) instead of entering
it. Capacities grow by doubling, so building ``M`` modes costs ``O(M)`` copies of the tables.
"""
from __future__ import annotations

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
        "ng": np.full(cap, -1, np.int64), "Rh": np.zeros((cap, GM, N1, N1)),
        "target": np.zeros((cap, GM), np.int64), "zt": np.full((cap, GM), -1, np.int64),
        "Rz": np.zeros((cap, GM, N1, N1)), "gkind": np.zeros((cap, GM), np.int64)}


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
        self.count = 0                       # slots in use (built or reserved)
        self._pk = _empty(4, 1, self.K + 1, self.n + 1)

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

    def reserve(self) -> int:
        """A new slot (``ng = -1`` until :meth:`build`); returns its index."""
        cap = self._pk["h"].shape[0]
        if self.count >= cap:
            self._grow(2 * cap, 1)
        i = self.count
        self.count += 1
        return i

    def build(self, i, mode, index):
        """Pack ``mode`` into slot ``i``; ``index(name) -> int`` resolves (reserves) targets."""
        n, N1 = self.n, self.n + 1
        ngi = len(mode.guards)
        self._grow(self.count, max(1, ngi))
        targets, zts, Rhs, Rzs = [], [], [], []
        for g in mode.guards:
            where = f"mode {mode.name!r} guard {g.name!r}"
            if g.c.shape != (n,):
                raise ValueError(f"{where}: c must have shape ({n},), got {g.c.shape}")
            targets.append(index(mode.name if g.target is None else g.target, where))
            Rhs.append(reset_matrix(f"{where} reset", g.reset, n))
            if g.zeno_target is not None:
                zts.append(index(g.zeno_target, where + " zeno_target"))
                Rzs.append(reset_matrix(f"{where} zeno_reset", g.zeno_reset, n))
            else:
                zts.append(-1)
                Rzs.append(np.eye(N1))
        md = prepare_lti_mode(mode.A, mode.b, [(g.c, g.d, g.direction) for g in mode.guards],
                              K=self.K, theta=self.theta,
                              priorities=[g.priority for g in mode.guards])
        # targets may have reserved slots (and grown the tables): write after resolving them
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
        pk["Rh"][i] = np.eye(N1)
        pk["Rz"][i] = np.eye(N1)
        for gi, g in enumerate(mode.guards):
            pk["target"][i, gi] = targets[gi]
            pk["zt"][i, gi] = zts[gi]
            pk["Rh"][i, gi] = Rhs[gi]
            pk["Rz"][i, gi] = Rzs[gi]
            pk["gkind"][i, gi] = int(g.group)
        pk["ng"][i] = ngi

    def built(self, i) -> bool:
        return bool(self._pk["ng"][i] >= 0)

    def packed(self) -> PackedAutomaton:
        """Views of the tables over the slots in use (reserved slots have ``ng = -1``)."""
        c = self.count
        return PackedAutomaton(**{k: v[:c] for k, v in self._pk.items() if k != "gkind"})

    def gkind(self) -> np.ndarray:
        """Per-guard simultaneity group (``(count, GM)`` int64, 0: none)."""
        return self._pk["gkind"][:self.count]

    @property
    def nbytes(self) -> int:
        """Memory held by the tables (bytes)."""
        return int(sum(a.nbytes for a in self._pk.values()))
