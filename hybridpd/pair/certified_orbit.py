"""The certificate of one orbit: the pair's symmetric orbit at one parameter point.

:func:`certify_orbit` proves the orbit's class by the interval proofs of
:mod:`hybridpd.pair.proofs` on the point, and by python-flint ``arb`` enclosures of the
multipliers where they decide; the :class:`OrbitCertificate` carries the enclosures of
``xm``, of the section point and of the multipliers' moduli. The certified maps of many cells
are :mod:`hybridpd.pair.certified`, which re-exports both names.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.model import (
    Case,
    ImpactPair,
    as_gains,
    check_odd_order,
    check_positive,
)
from hybridpd.pair import proofs
from hybridpd.pair.intervals import widen_down, widen_up

__all__ = ["OrbitCertificate", "certify_orbit"]


def _ratio(num, den):
    """Outward enclosure of ``num / den`` for positive interval pairs."""
    (a, b), (c, d) = num, den
    exact = (c == 1.0) & (d == 1.0)
    return np.where(exact, a, widen_down(a / d)), np.where(exact, b, widen_up(b / c))


def _arb_bounds(x):
    """Float bounds ``(lo, hi)`` enclosing the ball ``x`` (NaN if it is not finite)."""
    if not x.is_finite():
        return (math.nan, math.nan)
    m, r = float(x.mid()), float(x.rad())
    return (float(widen_down(m - r * (1 + 2.0**-50))), float(widen_up(m + r * (1 + 2.0**-50))))


@dataclass(frozen=True)
class OrbitCertificate:
    """A certificate of one symmetric orbit (one parameter point).

    Attributes
    ----------
    verdict : str
        ``"proved_stable"``, ``"proved_unstable"``, ``"proved_no_orbit"`` or ``"undecided"``.
    flag : int
        Its :data:`FLAG_VALUES` code.
    reason : str
    case : str
    n : int
    params : dict
        ``kp, kv, mu, e, L, m2, omega, x10``.
    xm : (float, float)
        Enclosure of the reference amplitude (20) (length).
    section_point : dict
        Enclosures ``(lo, hi)`` of the pre-impact section point ``phi0`` (time, in
        ``[0, T)``), ``z1 = x2`` (length), ``z2 = y2`` and ``z4 = y1 - y2`` (velocity).
    multiplier_moduli : tuple of (float, float) or None
        Enclosures of ``|lambda|`` for the four eigenvalues of ``DP``, by decreasing upper
        bound (``None`` where arb could not isolate the eigenvalues, or viability is
        violated).
    spectral_radius : (float, float) or None
    viable : int
        ``+1`` viability proved, ``-1`` violated, ``0`` undecided.
    """

    __repr__ = compact_repr

    verdict: str
    flag: int
    reason: str
    case: str
    n: int
    params: dict = field(repr=False)
    xm: tuple
    section_point: dict = field(repr=False)
    multiplier_moduli: tuple | None = field(repr=False)
    spectral_radius: tuple | None
    viable: int

    def to_dict(self) -> dict:
        """JSON-ready form (bounds as ``[lo, hi]`` lists)."""
        b = lambda p: None if p is None else [p[0], p[1]]
        return {"verdict": self.verdict, "flag": self.flag, "reason": self.reason,
                "case": self.case, "n": self.n, "params": dict(self.params), "xm": b(self.xm),
                "section_point": {k: b(v) for k, v in self.section_point.items()},
                "multiplier_moduli": None if self.multiplier_moduli is None else
                [b(m) for m in self.multiplier_moduli],
                "spectral_radius": b(self.spectral_radius), "viable": self.viable}


def _arb_orbit(case, n, kp, kv, mu, e, L, m2, omega, x10):
    """arb enclosures: ``xm``, the section point, the moduli of the eigenvalues of ``DP``.

    At 106 bits, then 212 and 424 while arb cannot isolate the eigenvalues (they may lie
    far apart, 1e-5 and 1e3, or close together).
    """
    from flint import ctx

    for prec in (106, 212, 424):
        with ctx.workprec(prec):
            xm, section, moduli = _arb_orbit_at(case, n, kp, kv, mu, e, L, m2, omega, x10)
        if moduli is not None:
            break
    return xm, section, moduli


def _arb_orbit_at(case, n, kp, kv, mu, e, L, m2, omega, x10):
    from flint import acb_mat, arb, arb_mat

    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.flowintervals import arb_ops
    from hybridpd.pair.interval_kernels import interval_kernel

    ops = arb_ops()
    a = [arb(kp) / arb(m2), arb(kv) / arb(m2), arb(mu), arb(e), arb(L) / arb(x10), arb(omega),
         arb(n)]
    C, S, _ = interval_kernel("existence", case)(ops, *a)
    X = arb(x10)
    xm = X * (C * C + S * S).sqrt()
    w = arb(omega)
    T = 2 * arb.pi() / w
    ang = arb.atan2(S, C)
    phi0 = (ang + 2 * arb.pi() if ang < 0 else ang) / w
    if not (ang < 0 or ang >= 0):  # the ball straddles the branch cut: any phase in [0, T)
        phi0 = arb(0).union(T)
    v = 2 * X * w / (arb(n) * arb.pi())
    y2m = v * (arb(e) - 2 * arb(mu) - 1) / (1 + arb(e))
    section = {"phi0": phi0, "z1": X - arb(L), "z2": y2m, "z4": v - y2m}
    M = interval_kernel("halfmap", case)(ops, C, S, *a)
    Mm = arb_mat([[M[4 * i + j] for j in range(4)] for i in range(4)])
    moduli = None
    try:
        eig = acb_mat(Mm * Mm).eig()
        moduli = sorted((_arb_bounds(abs(z)) for z in eig), key=lambda p: -p[1])
    except (ValueError, ZeroDivisionError):
        pass  # not isolated at this precision
    return _arb_bounds(xm), {k: _arb_bounds(x) for k, x in section.items()}, moduli


def certify_orbit(pair: ImpactPair, gains, omega: float, *, x10: float = 1.0, n: int = 1,
                  case="collocated") -> OrbitCertificate:
    """Certify the symmetric orbit at one parameter point (signature of
    :func:`hybridpd.pair.orbits.symmetric_orbit`).

    Parameters
    ----------
    pair : ImpactPair
    gains : PDGains, (kp, kv) or {"kp", "kv"}
    omega : float
        Reference frequency (rad/time).
    x10 : float
        Desired primary-mass amplitude (length); ``gamma = L / x10``.
    n : int
        Odd order.
    case : {"collocated", "noncollocated"}

    Returns
    -------
    OrbitCertificate
        The class (proved by the interval proofs of :mod:`hybridpd.pair.proofs` on the
        point, and by the ``arb`` enclosures of the multipliers where they decide), the
        enclosures of ``xm``, of the section point and of the multipliers' moduli.

    Examples
    --------
    >>> import hybridpd as hp
    >>> from hybridpd.pair.certified import certify_orbit
    >>> c = certify_orbit(hp.ImpactPair(mu=0.1, e=0.5, L=0.75), hp.PDGains(10, 20), omega=5.0)
    >>> c.verdict
    'proved_stable'
    >>> lo, hi = c.spectral_radius          # encloses the float path's 0.5238184...
    >>> round(lo, 6), hi - lo < 1e-9
    (0.523818, True)
    """
    if not isinstance(pair, ImpactPair):
        raise ValueError(f"pair must be an ImpactPair, got {type(pair).__name__}")
    g = as_gains(gains)
    omega = check_positive("omega", omega)
    x10 = check_positive("x10", x10)
    n = check_odd_order(n)
    case = Case.parse(case).value
    gam = _ratio((np.array(pair.L), np.array(pair.L)), (np.array(x10), np.array(x10)))
    boxes, _ = proofs.scaled_boxes(kp=g.kp, kv=g.kv, mu=pair.mu, e=pair.e, gamma=gam,
                                   omega=omega, m2=pair.m2)
    cls, why, parts = proofs.classify(case, n, boxes, details=True)
    xm, section, moduli = _arb_orbit(case, n, g.kp, g.kv, pair.mu, pair.e, pair.L, pair.m2,
                                     omega, x10)
    flag, reason = int(cls[0]), proofs.REASONS[int(why[0])]
    viable = int(parts["viable"][0])
    if flag == proofs.UNDECIDED and moduli is not None and bool(parts["exists"][0]) \
            and viable == 1:
        # the rigorous eigenvalue enclosures may decide where the polynomial tests did not
        if max(m[1] for m in moduli) < 1:
            flag, reason = proofs.STABLE, proofs.REASONS[proofs.R_STABLE]
        elif max(m[0] for m in moduli) > 1:
            flag, reason = proofs.UNSTABLE, proofs.REASONS[proofs.R_UNSTABLE]
    if viable == -1:
        moduli = None  # the candidate of (13)-(14) is no orbit: its "multipliers" mean nothing
    rho = None if moduli is None else (max(m[0] for m in moduli), max(m[1] for m in moduli))
    params = {"kp": g.kp, "kv": g.kv, "mu": pair.mu, "e": pair.e, "L": pair.L, "m2": pair.m2,
              "omega": omega, "x10": x10}
    return OrbitCertificate(proofs.CLASSES[flag], flag, reason.replace(" on the whole box", ""),
                            case, n, params, xm, section,
                            None if moduli is None else tuple(moduli), rho, viable)
