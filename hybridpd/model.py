"""Impact-pair parameters, validation and Newton's impact law (paper eq. (2)).

Conventions (fixed by the project's SPEC, stated here once and reused everywhere):

* State order ``[x1, y1, x2, y2]`` (positions in length units, velocities in length/time)
  for the mechanical part; the closed loop appends the reference exosystem
  ``[pc, ps] = xm * [cos(w t), sin(w t)]`` and any controller states.
* The primary mass ``m1 = mu * m2`` moves freely inside a slot of the secondary mass ``m2``;
  the clearance is ``2 L``. With ``z3 = x1 - x2`` and ``z4 = y1 - y2`` an impact happens at
  ``z3 = +L`` with ``z4 > 0`` ("wall +1") or at ``z3 = -L`` with ``z4 < 0`` ("wall -1").
* ``m2 = 1`` unless given.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

__all__ = [
    "Case",
    "ImpactPair",
    "PDGains",
    "Reference",
    "check_axis",
    "check_finite",
    "check_in_range",
    "check_odd_order",
    "check_positive",
    "virtual_restitution",
]


def check_finite(name: str, value) -> float:
    """Return ``value`` as a float, raising ``ValueError`` naming ``name`` if it is not finite."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite real number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be a finite real number, got {value!r}")
    return v


def check_positive(name: str, value) -> float:
    """Return ``value`` as a float, requiring ``0 < value < inf``."""
    v = check_finite(name, value)
    if v <= 0.0:
        raise ValueError(f"{name} must be > 0 (allowed range (0, inf)), got {value!r}")
    return v


def check_in_range(name: str, value, lo: float, hi: float) -> float:
    """Return ``value`` as a float, requiring ``lo <= value <= hi``."""
    v = check_finite(name, value)
    if not (lo <= v <= hi):
        raise ValueError(f"{name} must lie in [{lo:g}, {hi:g}], got {value!r}")
    return v


def check_odd_order(n) -> int:
    """Return the orbit order ``n`` as an int, requiring a positive odd integer."""
    try:
        ni = int(n)
    except (TypeError, ValueError):
        raise ValueError(f"n must be a positive odd integer, got {n!r}") from None
    if ni != n or ni < 1 or ni % 2 == 0:
        raise ValueError(
            f"n must be a positive odd integer (symmetric orbits need odd n), got {n!r}"
        )
    return ni


def check_axis(name: str, spec, *, min_num: int = 1, positive: bool = False) -> np.ndarray:
    """Validate a grid axis ``(MIN, MAX, NUM)`` and return ``linspace(MIN, MAX, NUM)``.

    Requires finite ``MIN < MAX``, an integer ``NUM >= min_num`` and, with ``positive``,
    ``MIN > 0``.
    """
    try:
        lo, hi, num = spec
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be (MIN, MAX, NUM), got {spec!r}") from None
    lo, hi = float(lo), float(hi)
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ValueError(f"{name} range must be finite, got {spec!r}")
    if not hi > lo:
        raise ValueError(f"{name} range must be increasing (MIN < MAX), got {spec!r}")
    if not (float(num) == int(num) and int(num) >= min_num):
        raise ValueError(f"{name} NUM must be an integer >= {min_num}, got {num!r}")
    if positive and lo <= 0:
        raise ValueError(f"{name} values must be > 0 (allowed range (0, inf)), got MIN = {lo:g}")
    return np.linspace(lo, hi, int(num))


class Case(str, Enum):
    """Which position the PD loop feeds back.

    ``COLLOCATED``: ``x = x2`` (the actuated secondary mass). ``NONCOLLOCATED``: ``x = x1``
    (the primary mass, driven only through impacts).
    """

    COLLOCATED = "collocated"
    NONCOLLOCATED = "noncollocated"

    @classmethod
    def parse(cls, value) -> Case:
        """Accept a ``Case`` or one of the strings ``"collocated"``, ``"noncollocated"``."""
        if isinstance(value, Case):
            return value
        key = str(value).strip().lower().replace("-", "").replace("_", "")
        for c in cls:
            if c.value == key:
                return c
        raise ValueError(
            f"case must be 'collocated' or 'noncollocated', got {value!r}"
        )


def virtual_restitution(mu, e):
    """Virtual restitution coefficient ``R`` of the secondary mass, paper eq. (12).

    ``R = (e + 2 e mu - 1) / (e - 2 mu - 1)``: on the symmetric orbit the secondary mass's
    post-impact velocity is ``R`` times its pre-impact velocity. Vectorised over arrays.
    """
    mu = np.asarray(mu, dtype=float)
    e = np.asarray(e, dtype=float)
    return (e + 2.0 * e * mu - 1.0) / (e - 2.0 * mu - 1.0)


@dataclass(frozen=True)
class ImpactPair:
    """The mechanical plant: two masses with clearance ``2 L`` and Newton restitution ``e``.

    Parameters
    ----------
    mu : float
        Mass ratio ``m1 / m2``, ``0 < mu < inf``.
    e : float
        Newton's coefficient of restitution, ``0 <= e <= 1`` (0 plastic, 1 elastic).
    L : float
        Half clearance (length), ``L > 0``. Contact when ``|x1 - x2| = L``.
    m2 : float, optional
        Secondary (actuated) mass, ``m2 > 0``; default 1.

    Examples
    --------
    >>> pair = ImpactPair(mu=0.1, e=0.5, L=0.75)
    >>> post = pair.impact([0.75, 1.0, 0.0, -1.0], wall=+1)
    >>> float(post[1] - post[3])          # relative velocity reversed and scaled by e
    -1.0
    """

    mu: float
    e: float
    L: float
    m2: float = 1.0

    def __post_init__(self):
        object.__setattr__(self, "mu", check_positive("mu", self.mu))
        object.__setattr__(self, "e", check_in_range("e", self.e, 0.0, 1.0))
        object.__setattr__(self, "L", check_positive("L", self.L))
        object.__setattr__(self, "m2", check_positive("m2", self.m2))

    @property
    def m1(self) -> float:
        """Primary mass ``mu * m2``."""
        return self.mu * self.m2

    @property
    def R(self) -> float:
        """Virtual restitution coefficient (12)."""
        return float(virtual_restitution(self.mu, self.e))

    def velocity_jump_matrix(self) -> np.ndarray:
        """The 2x2 block of (2) acting on ``[y1, y2]``: ``[y1+, y2+] = E @ [y1-, y2-]``."""
        mu, e = self.mu, self.e
        return np.array(
            [[(mu - e) / (1 + mu), (1 + e) / (1 + mu)],
             [(1 + e) * mu / (1 + mu), (1 - mu * e) / (1 + mu)]]
        )

    def impact_matrix(self) -> np.ndarray:
        """Newton's impact law (2) as a 4x4 matrix on ``[x1, y1, x2, y2]`` (positions kept)."""
        E = np.eye(4)
        Ev = self.velocity_jump_matrix()
        E[np.ix_([1, 3], [1, 3])] = Ev
        return E

    def impact(self, state, wall: int = +1) -> np.ndarray:
        """Apply the impact law to a pre-impact state ``[x1, y1, x2, y2, ...]``.

        Extra trailing entries (exosystem, controller states) pass unchanged; leading
        dimensions broadcast (shape ``(..., n)`` with ``n >= 4``). ``wall`` is accepted for
        symmetry with the trajectory records: the law (2) is the same on both walls.
        """
        if wall not in (-1, 1):
            raise ValueError(f"wall must be +1 or -1, got {wall!r}")
        x = np.array(state, dtype=float, copy=True)
        if x.shape[-1] < 4:
            raise ValueError(f"state must have at least 4 entries [x1, y1, x2, y2], got shape {x.shape}")
        Ev = self.velocity_jump_matrix()
        y1, y2 = x[..., 1].copy(), x[..., 3].copy()
        x[..., 1] = Ev[0, 0] * y1 + Ev[0, 1] * y2
        x[..., 3] = Ev[1, 0] * y1 + Ev[1, 1] * y2
        return x

    def kinetic_energy(self, state) -> np.ndarray:
        """Kinetic energy ``(m1 y1^2 + m2 y2^2) / 2`` of state(s) ``(..., >=4)``."""
        x = np.asarray(state, dtype=float)
        return 0.5 * (self.m1 * x[..., 1] ** 2 + self.m2 * x[..., 3] ** 2)

    def energy_loss(self, relative_velocity) -> np.ndarray:
        """Kinetic energy lost in one impact, ``(1 - e^2) m1 m2 / (2 (m1 + m2)) * z4^2``."""
        z4 = np.asarray(relative_velocity, dtype=float)
        mred = self.m1 * self.m2 / (self.m1 + self.m2)
        return 0.5 * (1.0 - self.e ** 2) * mred * z4 ** 2

    def plastic_velocity(self, state) -> np.ndarray:
        """Common velocity after a perfectly plastic contact: ``(m1 y1 + m2 y2) / (m1 + m2)``."""
        x = np.asarray(state, dtype=float)
        return (self.mu * x[..., 1] + x[..., 3]) / (1.0 + self.mu)


@dataclass(frozen=True)
class PDGains:
    """PD gains of (3): ``U = m2 xd'' - kv (y - yd) - kp (x - xd)``, ``kp > 0``, ``kv > 0``."""

    kp: float
    kv: float

    def __post_init__(self):
        object.__setattr__(self, "kp", check_positive("kp", self.kp))
        object.__setattr__(self, "kv", check_positive("kv", self.kv))


@dataclass(frozen=True)
class Reference:
    """Desired trajectory ``xd(t) = xm cos(omega t)`` (4).

    ``xm >= 0`` (length), ``omega > 0`` (rad/time). Generated by the exosystem
    ``pc = xm cos(omega t)``, ``ps = xm sin(omega t)``.
    """

    xm: float
    omega: float

    def __post_init__(self):
        xm = check_finite("xm", self.xm)
        if xm < 0:
            raise ValueError(f"xm must be >= 0 (allowed range [0, inf)), got {self.xm!r}")
        object.__setattr__(self, "xm", xm)
        object.__setattr__(self, "omega", check_positive("omega", self.omega))

    @property
    def period(self) -> float:
        """``T = 2 pi / omega``."""
        return 2.0 * math.pi / self.omega

    def exo_state(self, t) -> np.ndarray:
        """Exosystem state ``[pc, ps]`` at time(s) ``t``; shape ``(..., 2)``."""
        t = np.asarray(t, dtype=float)
        wt = self.omega * t
        return np.stack([self.xm * np.cos(wt), self.xm * np.sin(wt)], axis=-1)
