"""Linear mechanical systems ``M q'' + C q' + K q = B u`` with named degrees of freedom.

Conventions
-----------
* ``q`` are generalised coordinates (lengths or angles), ``n = len(dofs)``; the mechanical
  state is interleaved, ``[q_1, v_1, ..., q_n, v_n]`` (``v = q'``), which for the impact pair
  is the impact pair's ``[x1, y1, x2, y2]`` (CONVENTIONS.md).
* ``u`` is one scalar control force (or torque) applied along the input direction ``B``;
  a loop with several controllers (:class:`hybridpd.mechanics.ControlChannel`) gives each its
  own direction (``actuate``), and ``B`` is then only the default of those that give none.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from hybridpd._results import compact_repr

__all__ = ["MechanicalSystem"]


def _matrix(name, value, n, default_zero=False):
    if value is None:
        if default_zero:
            return np.zeros((n, n))
        raise ValueError(f"{name} is required (an {n} x {n} matrix)")
    try:
        A = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be an {n} x {n} matrix of numbers") from None
    if A.shape != (n, n):
        raise ValueError(f"{name} must have shape ({n}, {n}), got {A.shape}")
    if not np.all(np.isfinite(A)):
        raise ValueError(f"{name} must be finite")
    return A


def _input(value, n):
    try:
        B = np.array(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError(f"input must be a list of {n} numbers") from None
    if B.shape != (n,):
        raise ValueError(f"input must have shape ({n},), got {B.shape}")
    if not np.all(np.isfinite(B)) or not np.any(B):
        raise ValueError("input must be finite and not zero")
    return B


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class MechanicalSystem:
    """A linear mechanical system ``M q'' + C q' + K q = B u``.

    Parameters
    ----------
    dofs : sequence of str
        Unique names of the ``n`` degrees of freedom.
    M : array_like, shape (n, n)
        Mass matrix, symmetric positive definite (checked to a relative ``1e-12``).
    C, K : array_like, shape (n, n), optional
        Damping and stiffness (default zero).
    B : array_like, shape (n,), optional
        Direction along which the control force ``u`` acts (e.g. ``[0, 1]``: on the second
        DOF); finite and not zero when given. It may be omitted (``None``) when every
        controller of the loop says where it acts (``ControlChannel.actuate``).

    Examples
    --------
    >>> sysm = MechanicalSystem(["x1", "x2"], M=[[0.1, 0], [0, 1.0]], B=[0, 1])
    >>> sysm.n, sysm.index("x2")
    (2, 1)
    >>> sysm.Minv_B
    array([0., 1.])
    >>> MechanicalSystem(["a", "b"], M=[[1.0, 0], [0, 2.0]]).B is None   # actuated per controller
    True
    """

    dofs: tuple
    M: np.ndarray
    C: np.ndarray | None = None
    K: np.ndarray | None = None
    B: np.ndarray | None = None
    __repr__ = compact_repr

    def __post_init__(self):
        if isinstance(self.dofs, str) or not isinstance(self.dofs, Sequence):
            raise ValueError("dofs must be a list of names")
        dofs = tuple(self.dofs)
        if not dofs:
            raise ValueError("dofs must name at least one degree of freedom")
        for d in dofs:
            if not isinstance(d, str) or not d:
                raise ValueError(f"dofs must be non-empty strings, got {d!r}")
        dup = sorted({d for d in dofs if dofs.count(d) > 1})
        if dup:
            raise ValueError(f"dofs: duplicate names {dup}")
        n = len(dofs)
        M = _matrix("mass", self.M, n)
        if not np.allclose(M, M.T, rtol=1e-12, atol=1e-12 * np.abs(M).max()):
            raise ValueError("mass: M must be symmetric")
        M = 0.5 * (M + M.T)
        try:
            np.linalg.cholesky(M)
        except np.linalg.LinAlgError:
            raise ValueError("mass: M must be positive definite") from None
        C = _matrix("damping", self.C, n, default_zero=True)
        K = _matrix("stiffness", self.K, n, default_zero=True)
        B = None if self.B is None else _input(self.B, n)
        for k, v in (("dofs", dofs), ("M", M), ("C", C), ("K", K), ("B", B)):
            object.__setattr__(self, k, v)

    @property
    def n(self) -> int:
        """Number of degrees of freedom."""
        return len(self.dofs)

    @property
    def Minv(self) -> np.ndarray:
        """``M^-1``, shape ``(n, n)``."""
        return np.linalg.inv(self.M)

    @property
    def Minv_B(self) -> np.ndarray:
        """``M^-1 B``, shape ``(n,)``: acceleration per unit control force (``ValueError``
        when the system has no input direction ``B``)."""
        if self.B is None:
            raise ValueError("input: the system has no input direction B (its controllers "
                             "give their own, ControlChannel.actuate)")
        return np.linalg.solve(self.M, self.B)

    def index(self, dof: str) -> int:
        """Index of the DOF called ``dof`` (``ValueError`` naming the known DOFs)."""
        try:
            return self.dofs.index(dof)
        except ValueError:
            raise ValueError(f"unknown dof {dof!r}; dofs are {list(self.dofs)}") from None

    def state_names(self) -> tuple:
        """Interleaved mechanical state names ``(q_1, v_1, ..., q_n, v_n)``.

        The velocity of DOF ``x`` is called ``x_dot`` (for the impact pair: the
        ``y1, y2`` are ``x1_dot, x2_dot``).
        """
        out = []
        for d in self.dofs:
            out += [d, f"{d}_dot"]
        return tuple(out)

    def kinetic_energy(self, mech_state) -> np.ndarray:
        """``v^T M v / 2`` of state(s) ``[q_1, v_1, ...]``, shape ``(..., 2n)``."""
        x = np.asarray(mech_state, dtype=float)
        v = x[..., 1:2 * self.n:2]
        return 0.5 * np.einsum("...i,ij,...j->...", v, self.M, v)

    def momentum(self, mech_state) -> np.ndarray:
        """Generalised momentum ``M v`` of state(s), shape ``(..., n)``."""
        x = np.asarray(mech_state, dtype=float)
        return x[..., 1:2 * self.n:2] @ self.M.T
