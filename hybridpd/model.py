"""Impact-pair parameters, validation and Newton's impact law (paper eq. (2)).

Conventions (those of CONVENTIONS.md, stated here once and reused
everywhere):

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
import numbers
from collections.abc import Mapping
from dataclasses import dataclass
from enum import Enum

import numpy as np

from hybridpd._phase import wrap_phase

__all__ = [
    "Case",
    "ImpactPair",
    "PDGains",
    "Reference",
    "as_gains",
    "check_array",
    "check_axis",
    "check_finite",
    "check_in_range",
    "check_int",
    "check_named_axis",
    "check_odd_order",
    "check_pair",
    "check_positive",
    "pd_values",
    "sine_reference",
    "virtual_restitution",
    "wrap_phase",
]


def _show(value) -> str:
    s = repr(value)
    return s if len(s) <= 60 else s[:57] + "..."


def _real(name: str, value, rng: str) -> float:
    """``value`` as a float if it is a real number (not bool, str, None, container), else raise."""
    if isinstance(value, np.ndarray) and value.shape == () and value.dtype.kind in "iuf":
        value = value.item()
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name} must be a real number in {rng}, got {_show(value)}")
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be a finite real number in {rng}, got {_show(value)}")
    return v


def check_finite(name: str, value) -> float:
    """Return ``value`` as a float; ``ValueError`` naming ``name`` unless a finite real number.

    Strings, bools, ``None``, containers and arrays of more than one element are rejected
    (a 0-d array is accepted).
    """
    return _real(name, value, "(-inf, inf)")


def check_positive(name: str, value) -> float:
    """Return ``value`` as a float, requiring a real number with ``0 < value < inf``."""
    v = _real(name, value, "(0, inf)")
    if v <= 0.0:
        raise ValueError(f"{name} must be > 0 (allowed range (0, inf)), got {_show(value)}")
    return v


def check_in_range(name: str, value, lo: float, hi: float) -> float:
    """Return ``value`` as a float, requiring a real number with ``lo <= value <= hi``."""
    rng = f"[{lo:g}, {hi:g}]"
    v = _real(name, value, rng)
    if not (lo <= v <= hi):
        raise ValueError(f"{name} must lie in {rng}, got {_show(value)}")
    return v


def check_int(name: str, value, lo: int | None = None, hi: int | None = None) -> int:
    """Return ``value`` as an int: an integer (or integral float) in ``[lo, hi]``."""
    rng = f"[{'-inf' if lo is None else lo}, {'inf' if hi is None else hi}]"
    if isinstance(value, np.ndarray) and value.shape == () and value.dtype.kind in "iuf":
        value = value.item()
    ok = (isinstance(value, numbers.Integral)
          or (isinstance(value, numbers.Real) and math.isfinite(value) and value == int(value)))
    if isinstance(value, (bool, np.bool_)) or not ok:
        raise ValueError(f"{name} must be an integer in {rng}, got {_show(value)}")
    v = int(value)
    if (lo is not None and v < lo) or (hi is not None and v > hi):
        raise ValueError(f"{name} must be an integer in {rng}, got {_show(value)}")
    return v


def check_array(name: str, value, *, shape: tuple | None = None, trailing: tuple | None = None,
                lo: float | None = None, hi: float | None = None, lo_open: bool = True,
                finite: bool = True) -> np.ndarray:
    """Return ``value`` as a float ndarray after checking its type, shape and range.

    Parameters
    ----------
    name : str
        Parameter name for the error message.
    value : array_like
        Real numbers (bools, strings, ``None``, mappings and ragged or object arrays are
        rejected).
    shape : tuple, optional
        Exact shape required.
    trailing : tuple, optional
        Required trailing dimensions (shape ``(..., *trailing)``).
    lo, hi : float, optional
        Range: ``lo < x`` (``lo <= x`` unless ``lo_open``) and ``x <= hi``.
    finite : bool
        Require every entry finite.
    """
    if value is None or isinstance(value, (str, bytes, dict)) or hasattr(value, "keys"):
        raise ValueError(f"{name} must be an array of real numbers, got {_show(value)}")
    try:
        a = np.asarray(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be an array of real numbers, got {_show(value)}") from None
    if a.dtype.kind not in "iuf":
        raise ValueError(f"{name} must be an array of real numbers, got {_show(value)}")
    a = a.astype(float)
    if shape is not None and a.shape != tuple(shape):
        raise ValueError(f"{name} must have shape {tuple(shape)}, got shape {a.shape}")
    if trailing is not None:
        t = tuple(trailing)
        if a.ndim < len(t) or a.shape[a.ndim - len(t):] != t:
            dims = ", ".join(str(d) for d in t)
            raise ValueError(f"{name} must have shape (..., {dims}), got shape {a.shape}")
    if finite and not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite")
    rng = (f"{'(' if lo_open else '['}{'-inf' if lo is None else format(lo, 'g')}, "
           f"{'inf' if hi is None else format(hi, 'g')}{']' if hi is not None else ')'}")
    if lo is not None:
        bad = a <= lo if lo_open else a < lo
        if np.any(bad):
            raise ValueError(f"{name} must lie in {rng}, got {a[bad].ravel()[0]!r}")
    if hi is not None and np.any(a > hi):
        raise ValueError(f"{name} must lie in {rng}, got {a[a > hi].ravel()[0]!r}")
    return a


def check_pair(name: str, value) -> tuple[float, float]:
    """Return ``(a, b)`` from a sequence of exactly two finite real numbers."""
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__len__") or len(value) != 2:
        raise ValueError(f"{name} must be a pair (start, end) of real numbers, got {_show(value)}")
    return check_finite(f"{name}[0]", value[0]), check_finite(f"{name}[1]", value[1])


def check_odd_order(n) -> int:
    """Return the orbit order ``n`` as an int, requiring a positive odd integer."""
    msg = f"n must be a positive odd integer 1, 3, 5, ... (symmetric orbits), got {_show(n)}"
    try:
        ni = check_int("n", n, 1)
    except ValueError:
        raise ValueError(msg) from None
    if ni % 2 == 0:
        raise ValueError(msg)
    return ni


def check_axis(name: str, spec, *, min_num: int = 1, positive: bool = False) -> np.ndarray:
    """Validate a grid axis ``(MIN, MAX, NUM)`` and return ``linspace(MIN, MAX, NUM)``.

    Requires finite ``MIN < MAX``, an integer ``NUM >= min_num`` and, with ``positive``,
    ``MIN > 0``.
    """
    if isinstance(spec, (str, bytes, dict)) or not hasattr(spec, "__len__") or len(spec) != 3:
        raise ValueError(f"{name} must be (MIN, MAX, NUM), got {_show(spec)}")
    lo = check_finite(f"{name} MIN", spec[0])
    hi = check_finite(f"{name} MAX", spec[1])
    if not hi > lo:
        raise ValueError(f"{name} range must be increasing (MIN < MAX), got {_show(spec)}")
    num = check_int(f"{name} NUM", spec[2], min_num)
    if positive and lo <= 0:
        raise ValueError(f"{name} values must be > 0 (allowed range (0, inf)), got MIN = {lo:g}")
    return np.linspace(lo, hi, num)


def check_named_axis(param: str, spec, names, *, min_num: int = 1, positive: bool = False):
    """Validate ``param = (NAME, MIN, MAX, NUM)`` with ``NAME`` in ``names``.

    Returns ``(NAME, linspace(MIN, MAX, NUM))``; errors name ``param`` (see :func:`check_axis`).
    """
    if isinstance(spec, (str, bytes, dict)) or not hasattr(spec, "__len__") or len(spec) != 4:
        raise ValueError(f"{param} must be (NAME, MIN, MAX, NUM), got {_show(spec)}")
    name = spec[0]
    if not isinstance(name, str) or name not in names:
        raise ValueError(f"{param} axis name must be one of {tuple(names)}, got {_show(name)}")
    try:
        return name, check_axis(name, tuple(spec[1:]), min_num=min_num, positive=positive)
    except ValueError as exc:
        raise ValueError(f"{param}: {exc}") from None


class Case(str, Enum):
    """Which position the PD loop feeds back.

    ``COLLOCATED``: ``x = x2`` (the actuated secondary mass). ``NONCOLLOCATED``: ``x = x1``
    (the primary mass, driven only through impacts). Wherever a case is taken, the strings
    ``"collocated"``, ``"noncollocated"`` and the paper's ``"non-collocated"`` are accepted.

    Examples
    --------
    >>> import hybridpd as hp
    >>> hp.Case.parse("non-collocated")
    <Case.NONCOLLOCATED: 'noncollocated'>
    >>> hp.Case.COLLOCATED.value
    'collocated'
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
    post-impact velocity is ``R`` times its pre-impact velocity.

    Parameters
    ----------
    mu : float or array_like
        Mass ratio ``m1 / m2 > 0``.
    e : float or array_like
        Newton's restitution coefficient in ``[0, 1]``; broadcast against ``mu``.

    Returns
    -------
    ndarray
        ``R``, dimensionless, of the broadcast shape of ``mu`` and ``e``.

    Examples
    --------
    >>> import hybridpd as hp
    >>> round(float(hp.virtual_restitution(0.1, 0.5)), 6)
    0.571429
    >>> hp.virtual_restitution(0.1, [0.0, 1.0]).round(6)
    array([ 0.833333, -1.      ])
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
    >>> round(float(post[1] - post[3]), 12)   # relative velocity reversed and scaled by e
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
        if isinstance(wall, bool) or wall not in (-1, 1):
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
    """PD gains of (3): ``U = m2 xd'' - kv (y - yd) - kp (x - xd)``.

    Parameters
    ----------
    kp : float
        Proportional gain, force per unit length, ``kp > 0``.
    kv : float
        Derivative gain, force per unit velocity, ``kv > 0``.

    Wherever gains are taken, ``(kp, kv)`` and ``{"kp": ..., "kv": ...}`` are accepted too.

    Examples
    --------
    >>> import hybridpd as hp
    >>> hp.PDGains(kp=10, kv=20)
    PDGains(kp=10.0, kv=20.0)
    """

    kp: float
    kv: float

    def __post_init__(self):
        object.__setattr__(self, "kp", check_positive("kp", self.kp))
        object.__setattr__(self, "kv", check_positive("kv", self.kv))


@dataclass(frozen=True)
class Reference:
    """Desired trajectory ``xd(t) = offset + sum_i xm_i cos(omega_i t)``; the paper's (4) is one sine.

    Generated by an exosystem: for each sine ``pc = xm cos(omega t)``, ``ps = xm sin(omega t)``
    (``pc' = -omega ps``, ``ps' = omega pc``), and a constant state ``r = offset`` when the
    offset is non-zero or there is no sine; so the closed loop between impacts is linear
    time-invariant. One class serves the impact pair (one sine) and every mechanical model.

    Parameters
    ----------
    xm : float or sequence of float
        Amplitude(s) (length), ``xm >= 0``; a sequence for a sum of sines (may be empty for a
        constant set-point).
    omega : float or sequence of float
        Angular frequency(ies) (rad per time unit), ``omega > 0``; as many as ``xm``.
    offset : float
        Constant part of ``xd`` (a set-point), default 0.
    feedforward : float or None
        ``m_ff >= 0``: the loop adds the force ``m_ff xd''``. ``None`` (default) takes the
        loop's own law: ``m2 xd''`` for the impact pair (3), none for a mechanical model.

    Examples
    --------
    >>> import hybridpd as hp
    >>> ref = hp.Reference(xm=1.2, omega=5.0)
    >>> round(ref.period, 6)
    1.256637
    >>> ref.exo_state(0.0)
    array([1.2, 0. ])
    >>> hp.Reference.constant(0.3).exo_names
    ('r',)
    """

    xm: float | tuple
    omega: float | tuple
    offset: float = 0.0
    feedforward: float | None = None

    def __post_init__(self):
        a = tuple(np.atleast_1d(np.asarray(self.xm, dtype=object)).tolist())
        w = tuple(np.atleast_1d(np.asarray(self.omega, dtype=object)).tolist())
        if len(a) != len(w):
            raise ValueError(f"xm and omega must have the same length (one frequency per "
                             f"amplitude), got {len(a)} and {len(w)}")
        a = tuple(check_in_range("xm", x, 0.0, math.inf) for x in a)
        w = tuple(check_positive("omega", x) for x in w)
        set_ = object.__setattr__
        set_(self, "xm", a[0] if len(a) == 1 else a)
        set_(self, "omega", w[0] if len(w) == 1 else w)
        set_(self, "offset", check_finite("offset", self.offset))
        if self.feedforward is not None:
            set_(self, "feedforward", check_in_range("feedforward", self.feedforward, 0.0,
                                                     math.inf))

    @classmethod
    def sine(cls, amplitude, omega, feedforward=None) -> Reference:
        """``xd = amplitude cos(omega t)``."""
        return cls(amplitude, omega, 0.0, feedforward)

    @classmethod
    def constant(cls, value) -> Reference:
        """A set-point ``xd = value``."""
        return cls((), (), value)

    @classmethod
    def sum_of_sines(cls, amplitudes, omegas, feedforward=None) -> Reference:
        """``xd = sum_i amplitudes[i] cos(omegas[i] t)``."""
        return cls(tuple(amplitudes), tuple(omegas), 0.0, feedforward)

    @property
    def amplitudes(self) -> tuple:
        """The sine amplitudes as a tuple (empty for a constant set-point)."""
        return self.xm if isinstance(self.xm, tuple) else (self.xm,)

    @property
    def omegas(self) -> tuple:
        """The sine frequencies as a tuple, rad per time unit."""
        return self.omega if isinstance(self.omega, tuple) else (self.omega,)

    @property
    def is_sine(self) -> bool:
        """True for the paper's reference: one sine, no offset."""
        return not isinstance(self.xm, tuple) and self.offset == 0.0

    @property
    def period(self) -> float:
        """``T = 2 pi / omega`` (one sine only)."""
        if isinstance(self.omega, tuple):
            raise ValueError(f"omega: a period needs one frequency, got {len(self.omega)}")
        return 2.0 * math.pi / self.omega

    @property
    def exo_names(self) -> tuple:
        """Names of the exosystem states: ``pc, ps`` (or ``pc1, ps1, ...``), then ``r``."""
        k = len(self.omegas)
        names = ["pc", "ps"] if k == 1 else [f"{p}{i + 1}" for i in range(k) for p in ("pc", "ps")]
        if self.offset != 0.0 or k == 0:
            names.append("r")
        return tuple(names)

    def exo_matrices(self) -> tuple:
        """``(A, C)``: the exosystem ``p' = A p`` and ``[xd, xd', xd''] = C p``; shapes
        ``(k, k)`` and ``(3, k)``, ``k = len(exo_names)``."""
        m = len(self.exo_names)
        A = np.zeros((m, m))
        C = np.zeros((3, m))
        for i, w in enumerate(self.omegas):
            c, s = 2 * i, 2 * i + 1
            A[c, s], A[s, c] = -w, w
            C[0, c], C[1, s], C[2, c] = 1.0, -w, -w * w
        if m > 2 * len(self.omegas):
            C[0, m - 1] = 1.0
        return A, C

    def exo_state(self, t) -> np.ndarray:
        """Exosystem state at time(s) ``t``; shape ``(..., k)`` in the order of ``exo_names``."""
        t = np.asarray(t, dtype=float)
        cols = []
        for a, w in zip(self.amplitudes, self.omegas):
            cols += [a * np.cos(w * t), a * np.sin(w * t)]
        if len(cols) < len(self.exo_names):
            cols.append(np.full_like(t, self.offset))
        return np.stack(cols, axis=-1)

    def __call__(self, t) -> np.ndarray:
        """``[xd, xd', xd'']`` at time ``t``; shape ``(3,)`` (``(3, ...)`` for an array ``t``)."""
        _, C = self.exo_matrices()
        return np.moveaxis(self.exo_state(t) @ C.T, -1, 0)


def sine_reference(reference, name: str = "reference", m2: float | None = None) -> Reference:
    """``reference`` if it is the impact pair's (one sine, no offset), else ``ValueError``.

    ``m2`` given: a set ``feedforward`` must be the pair's ``m2`` (law (3)).

    Examples
    --------
    >>> sine_reference(Reference(1.0, 5.0)).period == Reference(1.0, 5.0).period
    True
    >>> sine_reference(Reference.constant(0.2))
    Traceback (most recent call last):
    ...
    ValueError: reference: the impact pair takes one sine xm cos(omega t) with no offset, got Reference(xm=(), omega=(), offset=0.2, feedforward=None)
    """
    if not isinstance(reference, Reference):
        raise ValueError(f"{name} must be a Reference, got {type(reference).__name__}")
    if not reference.is_sine:
        raise ValueError(f"{name}: the impact pair takes one sine xm cos(omega t) with no "
                         f"offset, got {reference!r}")
    ff = reference.feedforward
    if m2 is not None and ff is not None and not math.isclose(ff, m2, rel_tol=1e-12):
        raise ValueError(f"{name}.feedforward: the impact pair's law adds m2 xd'' (m2 = {m2:g}); "
                         f"leave it None, got {ff!r}")
    return reference


def _is_pd_form(value) -> bool:
    return isinstance(value, (PDGains, Mapping, tuple, list)) or (
        isinstance(value, np.ndarray) and value.ndim == 1)


def pd_values(value, name: str = "gains") -> tuple:
    """``(kp, kv)`` as finite floats from ``PDGains``, a pair or a mapping with keys exactly
    ``kp, kv``; ``ValueError`` naming ``name`` otherwise. Signs are not checked here (a
    mechanical loop may use ``kv = 0``; :class:`PDGains` requires both positive).

    Examples
    --------
    >>> pd_values({"kp": 10, "kv": 0})
    (10.0, 0.0)
    """
    if isinstance(value, PDGains):
        return value.kp, value.kv
    if isinstance(value, Mapping):
        keys = set(value)
        if keys != {"kp", "kv"}:
            raise ValueError(f"{name} as a mapping must have exactly the keys kp, kv, got "
                             f"{sorted(map(str, keys))}")
        kp, kv = value["kp"], value["kv"]
    elif _is_pd_form(value):
        if len(value) != 2:
            raise ValueError(f"{name} must be a pair (kp, kv), got {_show(value)}")
        kp, kv = value
    else:
        raise ValueError(f"{name} must be PDGains, a pair (kp, kv) or a mapping with keys kp, "
                         f"kv; got {type(value).__name__}")
    return check_finite(f"{name}: kp", kp), check_finite(f"{name}: kv", kv)


def as_gains(value, name: str = "gains", *, strict: bool = True) -> PDGains | None:
    """PD gains from ``PDGains``, a pair ``(kp, kv)`` or a mapping with keys exactly ``kp, kv``.

    With ``strict=False`` anything else returns ``None`` (the caller may accept other
    controllers); a malformed pair or mapping always raises ``ValueError`` naming ``name``.
    """
    if isinstance(value, PDGains):
        return value
    if not strict and not _is_pd_form(value):
        return None
    kp, kv = pd_values(value, name)
    try:
        return PDGains(kp, kv)
    except ValueError as exc:
        raise ValueError(f"{name}: {exc}") from None
