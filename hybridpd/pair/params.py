"""The impact pair's parameters as one object, and the packed array the compiled engine reads.

:class:`PairParams` holds every parameter of the PD-controlled impact pair by name, validated
once. The compiled kernels of :mod:`hybridpd.pair.batch` take the parameters as one float64
array (:meth:`PairParams.packed`); its entries are read through the named index constants
below (``params[KP]``, never ``params[0]``), which numba folds into the machine code like
literals.

The layout of the packed array (length :data:`N_PACKED`) is

=============  =====  ==================================
constant       index  entry
=============  =====  ==================================
:data:`KP`     0      proportional gain ``kp``
:data:`KV`     1      derivative gain ``kv``
:data:`M2`     2      secondary mass ``m2``
:data:`MU`     3      mass ratio ``mu = m1 / m2``
:data:`E`      4      restitution coefficient ``e``
:data:`L`      5      half clearance ``L = gamma x10``
:data:`OMEGA`  6      reference frequency ``omega``
:data:`XM`     7      reference amplitude ``xm``
=============  =====  ==================================

Conventions (CONVENTIONS.md): ``m1 = mu m2``, clearance ``2 L``, ``gamma = L / x10``,
reference ``xd = xm cos(omega t)``.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from hybridpd.model import check_finite, check_in_range, check_positive

__all__ = ["KP", "KV", "M2", "MU", "NAMES", "N_PACKED", "OMEGA", "PACKED_NAMES", "XM", "E", "L",
           "PairParams"]

# Index of each parameter in the packed array. The compiled kernels fold these in and are
# cached on disk under a stamp of the source files that mention njit (hybridpd._jit): this
# comment names njit so that a change of the layout here recompiles them.
KP = 0
KV = 1
M2 = 2
MU = 3
E = 4
L = 5
OMEGA = 6
XM = 7
#: Length of the packed array.
N_PACKED = 8
#: The entries of the packed array, in order.
PACKED_NAMES = ("kp", "kv", "m2", "mu", "e", "L", "omega", "xm")
#: The fields of :class:`PairParams`, in order.
NAMES = ("kp", "kv", "mu", "gamma", "omega", "e", "m2", "x10", "xm")


@dataclass(frozen=True)
class PairParams:
    """Every parameter of the PD-controlled impact pair, by name.

    Parameters
    ----------
    kp : float
        Proportional gain, force per unit length, ``0 < kp < inf``.
    kv : float
        Derivative gain, force per unit velocity, ``0 < kv < inf``.
    mu : float
        Mass ratio ``m1 / m2`` (dimensionless), ``0 < mu < inf``.
    gamma : float
        Clearance ratio ``L / x10`` (dimensionless), ``0 < gamma < inf``.
    omega : float
        Reference frequency, rad per time unit, ``0 < omega < inf``.
    e : float
        Newton's coefficient of restitution (dimensionless), ``0 <= e <= 1``.
    m2 : float, optional
        Secondary (actuated) mass, ``0 < m2 < inf``; default 1.
    x10 : float, optional
        Amplitude of the primary mass's desired motion (length), ``0 < x10 < inf``;
        default 1. With `gamma` it fixes the half clearance ``L = gamma x10``.
    xm : float or None, optional
        Reference amplitude of ``xd = xm cos(omega t)`` (length), finite; None (default)
        until it is chosen, e.g. as the amplitude that realises a symmetric orbit. The
        packed array needs it.

    Raises
    ------
    ValueError
        A parameter outside its range, naming it and the range.

    Examples
    --------
    >>> from hybridpd.pair.params import KP, L, PairParams
    >>> p = PairParams(kp=10, kv=20, mu=0.1, gamma=0.75, omega=5, e=0.5)
    >>> p.L
    0.75
    >>> p.replace(e=0.9).e
    0.9
    >>> a = p.replace(xm=1.2).packed()
    >>> float(a[KP]), float(a[L])
    (10.0, 0.75)
    >>> PairParams(kp=10, kv=20, mu=0.1, gamma=0.75, omega=5, e=1.5)
    Traceback (most recent call last):
    ...
    ValueError: e must lie in [0, 1], got 1.5
    """

    kp: float
    kv: float
    mu: float
    gamma: float
    omega: float
    e: float
    m2: float = 1.0
    x10: float = 1.0
    xm: float | None = None

    def __post_init__(self):
        checked = {name: check_positive(name, getattr(self, name))
                   for name in ("kp", "kv", "mu", "gamma", "omega", "m2", "x10")}
        checked["e"] = check_in_range("e", self.e, 0.0, 1.0)
        if self.xm is not None:
            checked["xm"] = check_finite("xm", self.xm)
        for name, value in checked.items():
            object.__setattr__(self, name, value)
        if not math.isfinite(self.L):
            raise ValueError(f"gamma * x10 must be finite (the half clearance L), got "
                             f"gamma = {self.gamma!r}, x10 = {self.x10!r}")

    @property
    def L(self) -> float:
        """Half clearance ``L = gamma x10`` (length)."""
        return self.gamma * self.x10

    @property
    def m1(self) -> float:
        """Primary mass ``m1 = mu m2``."""
        return self.mu * self.m2

    @property
    def period(self) -> float:
        """Reference period ``T = 2 pi / omega``."""
        return 2.0 * math.pi / self.omega

    def replace(self, **changes) -> PairParams:
        """A copy with the named parameters changed (validated again).

        Besides the fields (:data:`NAMES`), ``L`` may be given: it sets ``gamma = L / x10``
        (with the new ``x10`` if that changes too), so ``replace(x10=v, L=p.L)`` moves the
        amplitude at a fixed clearance while ``replace(x10=v)`` keeps ``gamma``.

        Examples
        --------
        >>> from hybridpd.pair.params import PairParams
        >>> p = PairParams(10, 20, 0.1, 0.75, 5, 0.5)
        >>> p.replace(kv=30).kv
        30.0
        >>> p.replace(L=1.5).gamma, p.replace(x10=2.0).L, p.replace(x10=2.0, L=p.L).gamma
        (1.5, 1.5, 0.375)
        """
        unknown = sorted(set(changes) - set(NAMES) - {"L"})
        if unknown:
            raise ValueError(f"replace: unknown parameter(s) {', '.join(unknown)}; the "
                             f"parameters are {', '.join(NAMES)} (and L)")
        if "L" in changes:
            if "gamma" in changes:
                raise ValueError("replace: give L or gamma, not both (gamma = L / x10)")
            x10 = check_positive("x10", changes.get("x10", self.x10))
            changes["gamma"] = check_positive("L", changes.pop("L")) / x10
        return dataclasses.replace(self, **changes)

    def as_dict(self) -> dict:
        """``{name: value}`` of every field (:data:`NAMES`), ``xm`` included (None if not
        chosen).

        Examples
        --------
        >>> from hybridpd.pair.params import PairParams
        >>> PairParams(10, 20, 0.1, 0.75, 5, 0.5).as_dict()["gamma"]
        0.75
        """
        return {name: getattr(self, name) for name in NAMES}

    def packed(self) -> np.ndarray:
        """The float64 array of length :data:`N_PACKED` the kernels of
        :mod:`hybridpd.pair.batch` take, laid out by the index constants (:data:`KP`, ...).

        Raises
        ------
        ValueError
            ``xm`` is None.

        Examples
        --------
        >>> from hybridpd.pair.params import OMEGA, PairParams
        >>> float(PairParams(10, 20, 0.1, 0.75, 5, 0.5, xm=1.0).packed()[OMEGA])
        5.0
        """
        if self.xm is None:
            raise ValueError("xm must be a finite number to pack the parameters, got None "
                             "(choose it with replace(xm=...))")
        out = np.empty(N_PACKED, dtype=np.float64)
        out[KP], out[KV], out[M2], out[MU] = self.kp, self.kv, self.m2, self.mu
        out[E], out[L], out[OMEGA], out[XM] = self.e, self.L, self.omega, self.xm
        return out

    @classmethod
    def from_packed(cls, array, x10: float = 1.0) -> PairParams:
        """The parameters of a packed array (:meth:`packed`); ``x10`` (not stored in it)
        turns its ``L`` into ``gamma = L / x10``.

        Raises
        ------
        ValueError
            `array` is not of length :data:`N_PACKED`, or an entry is out of its range.

        Examples
        --------
        >>> from hybridpd.pair.params import PairParams
        >>> p = PairParams(10, 20, 0.1, 0.75, 5, 0.5, xm=1.0)
        >>> PairParams.from_packed(p.packed()) == p
        True
        """
        a = np.asarray(array, dtype=float)
        if a.shape != (N_PACKED,):
            raise ValueError(f"array must have shape ({N_PACKED},) "
                             f"({', '.join(PACKED_NAMES)}), got shape {a.shape}")
        x10 = check_positive("x10", x10)
        return cls(kp=float(a[KP]), kv=float(a[KV]), mu=float(a[MU]),
                   gamma=check_positive("L", float(a[L])) / x10, omega=float(a[OMEGA]),
                   e=float(a[E]), m2=float(a[M2]), x10=x10, xm=float(a[XM]))

    @classmethod
    def of(cls, pair, gains, omega: float, *, xm: float | None = None,
           x10: float = 1.0) -> PairParams:
        """The parameters of an :class:`~hybridpd.model.ImpactPair`, its
        :class:`~hybridpd.model.PDGains` and a reference frequency (``gamma = pair.L /
        x10``).

        Examples
        --------
        >>> from hybridpd import ImpactPair, PDGains
        >>> from hybridpd.pair.params import PairParams
        >>> PairParams.of(ImpactPair(0.1, 0.5, 1.5), PDGains(10, 20), 5.0, x10=2.0).gamma
        0.75
        """
        x10 = check_positive("x10", x10)
        return cls(kp=gains.kp, kv=gains.kv, mu=pair.mu, gamma=pair.L / x10, omega=omega,
                   e=pair.e, m2=pair.m2, x10=x10, xm=xm)
