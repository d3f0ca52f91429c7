"""Test functions of the symmetric-orbit boundaries in a parameter plane.

The simple symmetric orbit of odd order ``n`` (:mod:`hybridpd.pair.orbits`) is known in
closed form at every parameter point, so each boundary of its existence/stability regions is
the zero set of one scalar *test function* ``F(p1, p2)`` of the two swept parameters:

===================  ========================================================================
kind                 test function (zero on the boundary)
===================  ========================================================================
``existence``        post-impact separation of a plastic impact (only when ``e = 0`` is
                     fixed): the gap acceleration ``g''(t0+) / (x10 omega^2)``; ``<= 0``
                     means the masses stick after the impact and the orbit is not admissible
``grazing``          the viability margin ``min (L - |z3|) / L`` over the interior turning
                     points of the flight (paper (19)); ``< 0``: an extra contact
``fold``             ``(1 - lambda_a)(1 - lambda_b) / (1 + |1 - lambda_b|)`` for the
                     multiplier ``lambda_a`` of ``DP`` nearest ``+1`` and its partner (the
                     conjugate, or the next real one): ``~ 1 - lambda_a`` away from a 1:1
                     resonance and smooth through it (sign of ``det(I - DP)``)
``period_doubling``  the same with ``1 + lambda`` (sign of ``det(I + DP)``)
``neimark_sacker``   ``1 - lambda_i lambda_j`` for the pair of multipliers with real product
                     nearest 1 (sign of the bialternate-product determinant
                     ``prod_{i<j} (1 - lambda_i lambda_j) = det(I - DP (.) DP)``); a
                     Neimark-Sacker point when the pair is complex, a neutral saddle (not a
                     bifurcation) when it is real
===================  ========================================================================

The "sign" versions (:meth:`TestValues.sign_test`) are globally defined and change sign
exactly on the boundary; they seed the curves. The "local" versions
(:meth:`TestValues.local_test`) are the vanishing factor alone (dimensionless, O(1)), smooth
near the boundary, and are what the curve points satisfy to ``1e-10``.

Why the other conditions of (13)-(14) give no curves: their determinant is never zero for
``kv > 0`` (see :func:`hybridpd.pair.symbolic.solve_symmetric_orbit`), and ``xm = hypot(C, S)``
vanishes only where ``C = S = 0`` (two equations: isolated points of a plane). The impact
speed ``z4 = 2 v (1 + mu) / (1 + e)`` is fixed and positive, and for ``e > 0`` the rebound
always separates the masses; with a plastic impact (``e = 0``) they may stick, which is the
``existence`` boundary.

Symmetry: the orbit is a fixed point of the half map ``G = S o H`` (flight plus impact to the
other wall, then the symmetry ``S: (phi, z) -> (phi + n T / 2, -z)``), and ``P = G o G``,
hence ``DP = M^2`` with ``M = S DP21 DP10`` (``S = diag(1, -1, -1, -1)`` in section
coordinates). The multipliers are computed as ``lambda = mu^2`` from the eigenvalues ``mu``
of ``M``. Consequences: ``det(I + DP) = |det(M - i I)|^2 >= 0``, so a real multiplier at
``-1`` is always double and never a sign change: the symmetric family has no
period-doubling *curves*; ``-1`` is reached only at isolated points of the Neimark-Sacker
curves (``mu = +-i``, reported as ``resonance_1_2``).

Parameters of the plane: any two of :data:`PARAMETERS` with the others fixed;
``gamma = L / x10`` with ``x10`` fixed (so sweeping ``gamma`` moves the clearance ``L``), and
``m2`` is the secondary mass (the gains are absolute, so changing ``m2`` rescales the
closed-loop natural frequency ``sqrt(kp / m2)`` and damping ``kv / m2``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hybridpd._jit import njit
from hybridpd.model import Case, check_finite, check_odd_order, check_positive
from hybridpd.pair import symbolic
from hybridpd.pair.batch import Flights, _eval, flight_at, pack_params, turning_margins

__all__ = ["KINDS", "PARAMETERS", "Axis", "Plane", "TestValues", "make_plane"]

#: Parameters a boundary plane can sweep (any two; the others fixed).
PARAMETERS = ("kp", "kv", "e", "mu", "gamma", "omega", "m2")
#: Boundary kinds.
KINDS = ("existence", "grazing", "fold", "period_doubling", "neimark_sacker")

_DOMAIN = {"e": (0.0, 1.0, False)}  # name -> (lo, hi, lo_open); the others: (0, inf)
_S = np.diag([1.0, -1.0, -1.0, -1.0])


def _domain(name):
    return _DOMAIN.get(name, (0.0, math.inf, True))


def _in_domain(name, v):
    lo, hi, lo_open = _domain(name)
    v = np.asarray(v, float)
    ok = (v > lo) if lo_open else (v >= lo)
    return ok & (v <= hi) & np.isfinite(v)


def _range_text(name):
    lo, hi, lo_open = _domain(name)
    return f"{'(' if lo_open else '['}{lo:g}, {hi:g}{')' if math.isinf(hi) else ']'}"


@dataclass(frozen=True)
class Axis:
    """One swept parameter of the plane: ``name`` on ``[lo, hi]``.

    Attributes
    ----------
    name : str
        One of :data:`PARAMETERS`.
    lo, hi : float
        The box edges (``lo < hi``, both inside the parameter's domain).
    """

    name: str
    lo: float
    hi: float

    @classmethod
    def parse(cls, spec, which="x") -> Axis:
        """Validate ``(name, lo, hi)``; ValueError naming the problem otherwise."""
        try:
            name, lo, hi = spec
        except (TypeError, ValueError):
            raise ValueError(f"{which} must be (NAME, MIN, MAX), got {spec!r}") from None
        name = str(name)
        if name not in PARAMETERS:
            raise ValueError(f"{which} axis name must be one of {PARAMETERS}, got {name!r}")
        lo = check_finite(f"{which} MIN ({name})", lo)
        hi = check_finite(f"{which} MAX ({name})", hi)
        if not lo < hi:
            raise ValueError(f"{which} axis {name}: MIN must be < MAX, got MIN = {lo:g}, "
                             f"MAX = {hi:g}")
        for v, what in ((lo, "MIN"), (hi, "MAX")):
            if not _in_domain(name, v):
                raise ValueError(f"{which} axis {name}: {what} must lie in {_range_text(name)}, "
                                 f"got {v:g}")
        return cls(name, lo, hi)

    def to_unit(self, v):
        """Parameter value(s) -> unit coordinate(s) (0 at ``lo``, 1 at ``hi``)."""
        return (np.asarray(v, float) - self.lo) / (self.hi - self.lo)

    def from_unit(self, u):
        """Unit coordinate(s) -> parameter value(s)."""
        return self.lo + np.asarray(u, float) * (self.hi - self.lo)

    def unit_domain(self):
        """The parameter's domain in unit coordinates (for finite-difference stencils)."""
        lo, hi, _ = _domain(self.name)
        return float(self.to_unit(lo)), (math.inf if math.isinf(hi) else float(self.to_unit(hi)))


@njit(cache=True)
def _margin_kernel(P, case, fl, nsamp):
    """Per point: (margin, second margin, post-impact gap acceleration) of the half-period
    flights ``fl`` (:class:`~hybridpd.pair.batch.Flights`).

    ``margin`` is ``min (L - |z3|)/L`` over the interior turning points of ``z3`` on
    ``(0, tau)`` (1 without any), ``second`` the next smallest value (1 without one): where
    both vanish two turning points graze at once (a corner of the existence region).
    """
    N = P.shape[0]
    marg = np.full(N, np.nan)
    marg2 = np.full(N, np.nan)
    acc = np.full(N, np.nan)
    for i in range(N):
        p = P[i]
        # x2'' at the start of the flight
        f = flight_at(fl, i)
        _x1, _y1, _x2, _y2, a2, _a3, _M2, _M3 = _eval(p, case, f, 0.0, 0.0)
        acc[i] = a2
        marg[i], marg2[i] = turning_margins(p, case, f, fl.tau[i], nsamp)
    return marg, marg2, acc


def _nearest_pair(lam, target):
    """Indices ``(i, j)`` per row of the eigenvalue nearest ``target`` and its partner.

    The partner is the conjugate of a complex eigenvalue, or the next real eigenvalue nearest
    ``target`` (a real 4x4 matrix has 0, 2 or 4 real eigenvalues), so ``(i, j)`` is the
    quadratic factor that stays smooth when the two collide.
    """
    N = lam.shape[0]
    rows = np.arange(N)
    d = np.abs(lam - target)
    d = np.where(np.isfinite(d), d, np.inf)
    i = np.argmin(d, axis=-1)
    li = lam[rows, i]
    real = lam.imag == 0.0
    # partner of a complex eigenvalue: its conjugate
    dc = np.abs(lam - np.conj(li)[:, None])
    dc[rows, i] = np.inf
    jc = np.argmin(dc, axis=-1)
    # partner of a real one: the next nearest real eigenvalue
    dr = np.where(real, d, np.inf)
    dr[rows, i] = np.inf
    jr = np.argmin(dr, axis=-1)
    j = np.where(li.imag == 0.0, jr, jc)
    return i, j


_II, _JJ = np.triu_indices(4, 1)


@dataclass(frozen=True)
class TestValues:
    """Everything the test functions need at a batch of parameter points.

    Attributes
    ----------
    formal : ndarray of bool, shape (N,)
        Conditions (13)-(14) solvable with ``xm > 0`` (all values below are NaN elsewhere).
    margin, margin2 : ndarray, shape (N,)
        Viability margin and the second-smallest turning-point margin (dimensionless).
    admissible : ndarray, shape (N,)
        The ``existence`` test (``+1`` when ``e > 0``: the rebound always separates).
    mu : ndarray, shape (N, 4), complex
        Eigenvalues of the half-map Jacobian ``M = S DP21 DP10``.
    lam : ndarray, shape (N, 4), complex
        Multipliers of ``DP = M^2`` (``lam = mu^2``).
    xm : ndarray, shape (N,)
        Reference amplitude of the orbit.
    """

    formal: np.ndarray
    margin: np.ndarray
    margin2: np.ndarray
    admissible: np.ndarray
    mu: np.ndarray
    lam: np.ndarray
    xm: np.ndarray

    @property
    def exists(self) -> np.ndarray:
        """The orbit exists (admissible and viable: margin > 0)."""
        with np.errstate(invalid="ignore"):
            return self.formal & (self.margin > 0) & (self.admissible > 0)

    @property
    def n_unstable(self) -> np.ndarray:
        """Number of multipliers outside the unit circle (-1 where not formal)."""
        n = np.sum(np.abs(self.lam) > 1.0, axis=-1)
        return np.where(self.formal, n, -1)

    def status(self) -> np.ndarray:
        """Region label: ``-1`` no orbit, else the number of unstable multipliers."""
        return np.where(self.exists, self.n_unstable, -1)

    def sign_test(self, kind: str) -> np.ndarray:
        """Globally defined test function of ``kind`` whose sign changes on the boundary."""
        lam = self.lam
        with np.errstate(all="ignore"):
            if kind == "grazing":
                out = self.margin.copy()
            elif kind == "existence":
                out = self.admissible.copy()
            elif kind == "fold":
                out = np.prod(1.0 - lam, axis=-1).real
            elif kind == "period_doubling":
                out = np.prod(1.0 + lam, axis=-1).real
            elif kind == "neimark_sacker":
                out = np.prod(1.0 - lam[:, _II] * lam[:, _JJ], axis=-1).real
            else:
                raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
        return np.where(self.formal, out, np.nan)

    def local_test(self, kind: str) -> np.ndarray:
        """The vanishing factor of :meth:`sign_test` (smooth near the boundary, O(1))."""
        if kind in ("grazing", "existence"):
            return self.sign_test(kind)
        lam = self.lam
        N = lam.shape[0]
        rows = np.arange(N)
        with np.errstate(all="ignore"):
            if kind in ("fold", "period_doubling"):
                # the factor of the real-or-conjugate pair nearest the critical value: smooth
                # where the pair collides (1:1 / 1:2 points lie on these curves)
                sgn = 1.0 if kind == "fold" else -1.0
                fac = 1.0 - sgn * lam
                i, j = _nearest_pair(lam, sgn)
                # divided by 1 + |partner factor|: O(1) when the partner is far (a
                # multiplier of 1e3 would otherwise scale the test function by 1e3)
                crit = (fac[rows, i] * fac[rows, j]).real / (1.0 + np.abs(fac[rows, j]))
                mask = (np.arange(4)[None, :] == i[:, None]) | (np.arange(4)[None, :] == j[:, None])
                rest = np.prod(np.where(mask, 1.0, fac), axis=-1).real
                out = crit * np.sign(rest)
            elif kind == "neimark_sacker":
                prod = lam[:, _II] * lam[:, _JJ]
                fac = 1.0 - prod
                realp = np.abs(prod.imag) <= 1e-12 * np.maximum(1.0, np.abs(prod))
                d = np.where(realp, np.abs(fac), np.inf)
                k = np.argmin(d, axis=-1)
                crit = fac[rows, k].real
                rest = np.prod(np.where(np.arange(6)[None, :] == k[:, None], 1.0, fac),
                               axis=-1).real
                out = crit * np.sign(rest)
            else:
                raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
        return np.where(self.formal, out, np.nan)

    def critical_pair(self):
        """For the Neimark-Sacker test: ``(complex, sum, re_mu)`` of the critical pair.

        ``complex``: the pair is a complex-conjugate pair (a Neimark-Sacker point when on the
        curve) rather than two real multipliers (a neutral saddle); ``sum``: ``lam_i + lam_j``
        (``2 cos theta`` on the unit circle; crosses 2 at a 1:1 resonance); ``re_mu``: real
        part of the corresponding half-map eigenvalue (changes sign where the pair passes
        ``-1``, the 1:2 resonance).
        """
        lam, mu = self.lam, self.mu
        prod = lam[:, _II] * lam[:, _JJ]
        realp = np.abs(prod.imag) <= 1e-12 * np.maximum(1.0, np.abs(prod))
        d = np.where(realp, np.abs(1.0 - prod), np.inf)
        k = np.argmin(d, axis=-1)
        i, j = _II[k], _JJ[k]
        rows = np.arange(lam.shape[0])
        mi, mj = mu[rows, i], mu[rows, j]
        cplx = (mi.imag != 0.0) & (mj.imag != 0.0)
        s = (lam[rows, i] + lam[rows, j]).real
        return cplx, s, np.where(cplx, mi.real, np.nan)


def _half_map_jacobian(c, idx, N):
    """``M = S DP21 DP10`` at the points ``idx`` of the candidate orbits ``c``, (k, 4, 4)."""
    b = lambda a: np.broadcast_to(np.asarray(a, float), (N,))[idx]
    s0 = np.broadcast_to(c.section_point, (N, 4))[idx]
    s1 = symbolic.impact_section_map(s0, mu=b(c.mu), e=b(c.e))
    DP21 = symbolic.flight_block(s1, b(c.tau), xm=b(c.xm), kp=b(c.kp), kv=b(c.kv), m2=b(c.m2),
                                 w=b(c.w), L=b(c.L), wall=1, case=c.case)
    return _S @ (DP21 @ symbolic.impact_block(mu=b(c.mu), e=b(c.e)))


@dataclass(frozen=True)
class Plane:
    """A parameter plane of the symmetric-orbit family: two axes and the fixed parameters.

    Attributes
    ----------
    case : Case
    n : int
        Odd orbit order.
    x, y : Axis
        The swept parameters.
    fixed : dict
        Values of the other parameters of :data:`PARAMETERS` and ``x10``.
    """

    case: Case
    n: int
    x: Axis
    y: Axis
    fixed: dict

    def params(self, xv, yv) -> dict:
        """All parameters (arrays, shape of ``xv``) at plane points ``(xv, yv)``."""
        xv = np.asarray(xv, float)
        p = {k: np.full(xv.shape, v, float) for k, v in self.fixed.items()}
        p[self.x.name] = xv
        p[self.y.name] = np.broadcast_to(np.asarray(yv, float), xv.shape).copy()
        return p

    def evaluate(self, xv, yv, margin_samples: int = 256) -> TestValues:
        """:class:`TestValues` at the points ``(xv[i], yv[i])`` (1-D arrays, same length)."""
        xv = np.atleast_1d(np.asarray(xv, float)).ravel()
        yv = np.atleast_1d(np.asarray(yv, float)).ravel()
        p = self.params(xv, yv)
        N = xv.size
        ok = np.ones(N, bool)
        for name in (self.x.name, self.y.name):
            ok &= _in_domain(name, p[name])
        safe = dict(p)
        for a in (self.x, self.y):   # keep the closed forms away from invalid values
            safe[a.name] = np.where(ok, p[a.name], a.lo)
        L = safe["gamma"] * safe["x10"]
        c = symbolic.solve_symmetric_orbit(kp=safe["kp"], kv=safe["kv"], m2=safe["m2"], mu=safe["mu"],
                                     e=safe["e"], L=L, w=safe["omega"], x10=safe["x10"],
                                     n=self.n, case=self.case.value)
        b = lambda a: np.broadcast_to(np.asarray(a, float), (N,))
        xm = b(c.xm)
        formal = ok & ~np.broadcast_to(np.asarray(c.singular, bool), (N,)) & np.isfinite(xm) \
            & (xm > 0)
        marg = np.full(N, np.nan)
        marg2 = np.full(N, np.nan)
        acc = np.full(N, np.nan)
        idx = np.flatnonzero(formal)
        lam = np.full((N, 4), np.nan + 0j)
        mu = np.full((N, 4), np.nan + 0j)
        if idx.size:
            P = pack_params(kp=b(safe["kp"]), kv=b(safe["kv"]), m2=b(safe["m2"]),
                            mu=b(safe["mu"]), e=b(safe["e"]), L=b(L), w=b(safe["omega"]),
                            xm=xm)[idx]
            sub = lambda a: np.ascontiguousarray(b(a)[idx])
            fl = Flights(sub(c.phi0), sub(c.x10), -sub(c.v), sub(c.x20), sub(c.y2_post),
                         sub(c.tau))
            marg[idx], marg2[idx], acc[idx] = _margin_kernel(
                np.ascontiguousarray(P), 0 if self.case is Case.COLLOCATED else 1, fl,
                int(margin_samples))
            M = _half_map_jacobian(c, idx, N)
            good = np.all(np.isfinite(M), axis=(1, 2))
            ev = np.full((idx.size, 4), np.nan + 0j)
            if np.any(good):
                ev[good] = np.linalg.eigvals(M[good])
            formal[idx[~good]] = False
            mu[idx] = ev
            lam[idx] = ev * ev
        if self.x.name != "e" and self.y.name != "e" and self.fixed["e"] == 0.0:
            scale = safe["x10"] * safe["omega"] ** 2
            adm = acc / scale
        else:
            adm = np.where(formal, 1.0, np.nan)
        return TestValues(formal=formal, margin=marg, margin2=marg2, admissible=adm, mu=mu,
                          lam=lam, xm=np.where(formal, xm, np.nan))


def make_plane(case, x, y, *, kp=None, kv=None, e=None, mu=None, gamma=None, omega=None,
               m2=None, x10=1.0, n=1) -> Plane:
    """Validate a parameter plane: axes ``x``, ``y`` = ``(name, lo, hi)`` and fixed values.

    A fixed value given for a swept name is ignored when it lies in the axis range and
    rejected (ValueError) otherwise, so a contradictory input is never silently dropped.
    Every parameter not swept must be given (``m2``, unless swept, and ``x10`` default to 1).

    Raises
    ------
    ValueError
        Unknown axis name, the same name twice, ``MIN >= MAX``, a range outside the
        parameter's domain, a missing or out-of-domain fixed value, an inconsistent fixed
        value of a swept name, an even or non-positive ``n``.
    """
    case = Case.parse(case)
    n = check_odd_order(n)
    ax = Axis.parse(x, "x")
    ay = Axis.parse(y, "y")
    if ax.name == ay.name:
        raise ValueError(f"the x and y axes must be different parameters, got {ax.name!r} twice")
    if m2 is None and "m2" not in (ax.name, ay.name):
        m2 = 1.0
    given = {"kp": kp, "kv": kv, "e": e, "mu": mu, "gamma": gamma, "omega": omega, "m2": m2}
    fixed = {"x10": check_positive("x10", x10)}
    for name, val in given.items():
        if name in (ax.name, ay.name):
            a = ax if name == ax.name else ay
            if val is not None:
                v = check_finite(name, val)
                if not a.lo <= v <= a.hi:
                    raise ValueError(f"{name} is swept on [{a.lo:g}, {a.hi:g}] but also fixed "
                                     f"at {v:g}: drop the fixed value or widen the range")
            continue
        if val is None:
            raise ValueError(f"{name} must be given (it is not a swept axis)")
        v = check_finite(name, val)
        if not _in_domain(name, v):
            raise ValueError(f"{name} must lie in {_range_text(name)}, got {v:g}")
        fixed[name] = v
    return Plane(case=case, n=n, x=ax, y=ay, fixed=fixed)
