"""Contacts: clearances, stops and general linear gaps, rigid or compliant.

A contact constrains one linear gap ``s = w . q`` (``w`` the *normal*, shape ``(n,)``) to
``lo <= s <= hi`` (either bound may be absent, not both):

* a clearance between DOFs ``i`` and ``j``: ``w = e_i - e_j``;
* a stop on DOF ``i``: ``w = e_i``;
* a gear mesh with ratio ``r`` (motor ``i``, load ``j``): ``w = r e_i - e_j``; any ``w``.

Contact laws
------------
*Rigid* (``restitution = e`` in ``[0, 1]``): at ``s = hi`` with ``s' = w . v > 0`` (or at
``lo`` with ``s' < 0``) the velocity jumps by an impulse ``P w`` (a generalised force along the
normal) chosen so that ``w . v+ = -e w . v-`` (Newton's law). Hence

``v+ = v- - (1 + e) (w . v-) M^-1 w / (w . M^-1 w)``,

the impulse in the metric of ``M``: it moves every DOF that ``M`` couples to the contact, the
generalised momentum changes only along ``w`` (``M v+ - M v- = P w``), and the kinetic energy
lost is ``(1 - e^2) (w . v-)^2 / (2 w . M^-1 w)``. For the impact pair this is the
paper's law (2). Accumulating impacts (Zeno) end in a *sticking* phase on the constraint
``s = bound`` (see :mod:`hybridpd.mechanics.automaton`).

*Compliant* (``stiffness = k > 0``, ``damping = c >= 0``): a Kelvin-Voigt spring-damper acting
only while the gap is closed, i.e. the generalised force ``-(k (s - hi) + c s') w`` while
``s > hi`` (and ``-(k (s - lo) + c s') w`` while ``s < lo``): piecewise-linear modes. For an
isolated contact of effective mass ``m* = 1 / (w . M^-1 w)`` the apparent restitution is
``e = exp(-zeta pi / sqrt(1 - zeta^2))``, ``zeta = c / (2 sqrt(k m*))``
(:meth:`Contact.equivalent_restitution`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hybridpd.model import check_finite

__all__ = ["Contact"]


def _opt_float(name, v):
    return None if v is None else check_finite(name, v)


@dataclass(frozen=True, eq=False)  # array field: identity semantics
class Contact:
    """One contact ``lo <= w·q <= hi``, rigid or compliant (see the module docstring).

    Parameters
    ----------
    normal : array_like, shape (n,)
        The gap direction ``w`` (not zero).
    lo, hi : float or None
        Bounds of the gap (length units of ``w . q``); at least one given; ``lo < hi``.
    restitution : float, optional
        Newton's ``e`` in ``[0, 1]`` (rigid contact). Default 0 (plastic) when neither law
        is given.
    stiffness, damping : float, optional
        Kelvin-Voigt ``k > 0`` (force per length) and ``c >= 0`` (force per velocity):
        compliant contact. Not together with ``restitution``.
    name : str, optional
        Label used in messages and plots.

    Examples
    --------
    >>> c = Contact([1.0, -1.0], lo=-0.75, hi=0.75, restitution=0.5)
    >>> c.rigid, c.bounds
    (True, ((-1, -0.75), (1, 0.75)))
    >>> bool(abs(Contact([1.0], hi=0, stiffness=1e4, damping=0.0)
    ...          .equivalent_restitution([[1.0]]) - 1.0) < 1e-15)
    True
    """

    normal: np.ndarray
    lo: float | None = None
    hi: float | None = None
    restitution: float | None = None
    stiffness: float | None = None
    damping: float | None = None
    name: str = ""

    def __post_init__(self):
        pre = f"contact {self.name!r}: " if self.name else ""
        try:
            w = np.array(self.normal, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise ValueError(f"{pre}normal must be a list of numbers") from None
        if not np.all(np.isfinite(w)) or not np.any(w):
            raise ValueError(f"{pre}normal must be finite and not zero")
        lo = _opt_float(pre + "lo", self.lo)
        hi = _opt_float(pre + "hi", self.hi)
        if lo is None and hi is None:
            raise ValueError(f"{pre}lo/hi: give at least one bound")
        if lo is not None and hi is not None and not lo < hi:
            raise ValueError(f"{pre}lo must be < hi, got lo = {lo!r}, hi = {hi!r}")
        e = _opt_float(pre + "restitution", self.restitution)
        k = _opt_float(pre + "stiffness", self.stiffness)
        c = _opt_float(pre + "damping", self.damping)
        if e is not None and (k is not None or c is not None):
            raise ValueError(f"{pre}restitution: give either restitution (rigid) or "
                             "stiffness/damping (compliant), not both")
        if c is not None and k is None:
            raise ValueError(f"{pre}stiffness: a compliant contact needs stiffness > 0")
        if k is not None:
            if not k > 0:
                raise ValueError(f"{pre}stiffness must be > 0, got {k!r}")
            c = 0.0 if c is None else c
            if c < 0:
                raise ValueError(f"{pre}damping must be >= 0, got {c!r}")
        else:
            e = 0.0 if e is None else e
            if not 0.0 <= e <= 1.0:
                raise ValueError(f"{pre}restitution must be in [0, 1], got {e!r}")
        for key, v in (("normal", w), ("lo", lo), ("hi", hi), ("restitution", e),
                       ("stiffness", k), ("damping", c), ("name", str(self.name))):
            object.__setattr__(self, key, v)

    @property
    def rigid(self) -> bool:
        """True for a Newton (rigid) contact, False for a Kelvin-Voigt one."""
        return self.stiffness is None

    @property
    def bounds(self) -> tuple:
        """``((wall, bound), ...)``: the bounds present (``wall`` -1 at ``lo``, +1 at ``hi``)."""
        out = []
        if self.lo is not None:
            out.append((-1, self.lo))
        if self.hi is not None:
            out.append((1, self.hi))
        return tuple(out)

    def gap(self, q) -> np.ndarray:
        """``w . q`` for position(s) ``q`` of shape ``(..., n)``."""
        return np.asarray(q, dtype=float) @ self.normal

    def effective_mass(self, M) -> float:
        """``m* = 1 / (w . M^-1 w)``: the mass the contact sees."""
        return 1.0 / float(self.normal @ np.linalg.solve(np.asarray(M, float), self.normal))

    def equivalent_restitution(self, M) -> float:
        """Apparent restitution of a compliant contact with effective mass ``m*`` (rigid: ``e``).

        ``e = exp(-zeta pi / sqrt(1 - zeta^2))`` with ``zeta = c / (2 sqrt(k m*))`` (0 when
        overdamped, ``zeta >= 1``): the exit-to-entry velocity ratio of a free mass ``m*``
        meeting the spring-damper, which is left when the penetration returns to zero.
        """
        if self.rigid:
            return float(self.restitution)
        zeta = self.damping / (2.0 * math.sqrt(self.stiffness * self.effective_mass(M)))
        if zeta >= 1.0:
            return 0.0
        return math.exp(-zeta * math.pi / math.sqrt(1.0 - zeta * zeta))
