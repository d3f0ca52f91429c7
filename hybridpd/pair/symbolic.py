"""Closed-form flows, symmetric-orbit existence and impact-map Jacobians, derived with SymPy.

This module reproduces sections 2-4 of the paper symbolically and turns every result into
vectorised NumPy functions. The SymPy derivation runs lazily on first use and is cached per
process (``functools.lru_cache`` on the builders); *importing this module does not import
SymPy*.

Conventions (fixed by the project's SPEC)
-----------------------------------------
* State order ``X = [x1, y1, x2, y2, pc, ps]``: primary mass ``m1 = mu*m2`` (position ``x1``,
  velocity ``y1``), secondary mass ``m2`` (``x2``, ``y2``), exosystem ``pc = xm cos(w t)``,
  ``ps = xm sin(w t)`` with ``pc' = -w ps``, ``ps' = w pc``. Units: any consistent system,
  e.g. positions in m, velocities in m/s, time in s, ``w`` in rad/s, ``m2`` in kg,
  ``kp`` in N/m, ``kv`` in N s/m.
* Reference ``xd = xm cos(w t) = pc``, so ``xd' = -w ps``, ``xd'' = -w^2 pc``.
* Between impacts (8): ``x1' = y1``, ``y1' = 0``, ``x2' = y2``, ``m2 y2' = U`` with
  ``U = m2 xd'' - kv (y - xd') - kp (x - xd)``; collocated ``(x, y) = (x2, y2)``,
  non-collocated ``(x, y) = (x1, y1)``. The closed loop is the autonomous LTI system
  ``X' = A X`` (6x6), whose exact flow ``X(t) = Phi(t) X(0)`` is given in closed form.
* Collocated homogeneous part: the error ``x2 - xd`` obeys ``m2 x'' + kv x' + kp x = 0``.
  With ``alpha = kv/(2 m2)`` and ``D = alpha^2 - kp/m2`` it is written with the *entire*
  functions (analytic in ``D``, valid across under-, critically and over-damped)

      ``DCh(a, D, t) = exp(-a t) cosh(sqrt(D) t)``,
      ``DSh(a, D, t) = exp(-a t) sinh(sqrt(D) t) / sqrt(D)``

  (``cos``/``sin`` for ``D < 0``, ``t exp(-a t)`` limit for ``D = 0``). See :func:`dch`,
  :func:`dsh`. Non-collocated: ``x2`` is a polynomial in ``t`` plus sinusoids (no exponentials).
* Impact law (2) at ``z3 = x1 - x2 = +L`` with ``z4 = y1 - y2 > 0`` (wall ``+1``) or at
  ``z3 = -L`` with ``z4 < 0`` (wall ``-1``): positions unchanged,
  ``y1+ = ((mu - e) y1 + (1 + e) y2)/(1 + mu)``, ``y2+ = ((1 + e) mu y1 + (1 - mu e) y2)/(1 + mu)``,
  hence ``z4+ = -e z4-``.
* Section coordinates ``s = (phi, z1, z2, z4)`` with ``z1 = x2``, ``z2 = y2``, ``z4 = y1 - y2``,
  ``phi = t mod T``, ``T = 2 pi / w``. On wall ``sigma = +-1`` the full state is
  ``X = (z1 + sigma L, z2 + z4, z1, z2, xm cos(w phi), xm sin(w phi))``.
* Symmetric orbit of odd order ``n`` (paper section 3): impacts ``tau = n T / 2`` apart,
  ``v = y10 = 2 x10 w / (n pi)``, ``x20 = x10 - L`` (may be negative), pre-impact velocity of
  ``m2`` ``y2- = v (e - 2 mu - 1)/(1 + e)`` (10), post ``y2+ = R y2-`` (11)-(12),
  ``R = (e + 2 e mu - 1)/(e - 2 mu - 1)``. With unknowns ``C = xm cos(w t0)``,
  ``S = xm sin(w t0)`` the conditions (13)-(14) are linear; ``xm = hypot(C, S)``,
  ``sn = S / xm``, ``cs = C / xm``, ``phi0 = atan2(S, C)/w mod T``.
* Impact map (paper section 4) ``P = P43 o P32 o P21 o P10`` on the pre-impact section
  ``z3 = +L, z4 > 0``; ``DP = DP43 DP32 DP21 DP10`` (24). Flight blocks by implicit
  differentiation: ``g(tau, s) = z3(tau; s) + sigma L = 0`` (target wall ``-sigma``),
  ``dtau/ds = -g_s / g_tau`` and ``DP = f_s + f_tau dtau/ds`` with ``phi_out = phi_in + tau``.

Public API
----------
Flows: :func:`transition_matrix`, :func:`flow`, :func:`gap`, :func:`gap_derivatives`,
:func:`system_matrix`, :func:`dch`, :func:`dsh`.
Section: :func:`state_from_section`, :func:`section_from_state`.
Symmetric orbit: :func:`virtual_restitution`, :func:`symmetric_velocities`,
:func:`symmetric_orbit` (-> :class:`SymmetricOrbit`).
Impact map: :func:`impact_section_map`, :func:`impact_block`, :func:`flight_section_map`,
:func:`flight_block`, :func:`flight_time`, :func:`impact_map` (-> :class:`ImpactMapResult`),
:func:`map_jacobian`, :func:`orbit_jacobian` (-> :class:`JacobianResult`).
SymPy objects: :func:`derivation` (-> :class:`Derivation`), :func:`sympy_functions`.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from hybridpd.model import Case

__all__ = [
    "Derivation",
    "ImpactMapResult",
    "JacobianResult",
    "SymmetricOrbit",
    "dch",
    "derivation",
    "dsh",
    "flight_block",
    "flight_section_map",
    "flight_time",
    "flow",
    "gap",
    "gap_derivatives",
    "impact_block",
    "impact_map",
    "impact_section_map",
    "map_jacobian",
    "orbit_jacobian",
    "section_from_state",
    "state_from_section",
    "symmetric_orbit",
    "symmetric_velocities",
    "sympy_functions",
    "system_matrix",
    "transition_matrix",
    "virtual_restitution",
]


# ----------------------------------------------------------------------------------------
# Numerical implementation of the entire functions DCh, DSh
# ----------------------------------------------------------------------------------------

_SERIES_U = 1.0  # use the power series in u = D t^2 for |u| <= _SERIES_U
_NTERMS = 16  # 1/(2*16)! ~ 4e-36: series exact to rounding for |u| <= 1
_CH_COEF = tuple(1.0 / math.factorial(2 * k) for k in range(_NTERMS))
_SH_COEF = tuple(1.0 / math.factorial(2 * k + 1) for k in range(_NTERMS))


def _horner(u, coef):
    acc = np.full_like(u, coef[-1])
    for c in coef[-2::-1]:
        acc = acc * u + c
    return acc


def _damped_pair(a, D, t):
    """Return ``(DCh, DSh)`` arrays for broadcast float inputs (see :func:`dch`)."""
    a, D, t = np.broadcast_arrays(
        np.asarray(a, dtype=float), np.asarray(D, dtype=float), np.asarray(t, dtype=float)
    )
    with np.errstate(all="ignore"):
        u = D * t * t
        small = np.abs(u) <= _SERIES_U
        ea = np.exp(-a * t)
        us = np.where(small, u, 0.0)
        ch_s = _horner(us, _CH_COEF) * ea
        sh_s = t * _horner(us, _SH_COEF) * ea
        neg = D < 0.0
        b = np.sqrt(np.where(neg & ~small, -D, 1.0))
        ch_o = np.cos(b * t) * ea
        sh_o = np.sin(b * t) / b * ea
        r = np.sqrt(np.where(~neg & ~small, D, 1.0))
        ep = np.exp((r - a) * t)
        em = np.exp(-(r + a) * t)
        ch_h = 0.5 * (ep + em)
        sh_h = 0.5 * (ep - em) / r
        ch = np.where(small, ch_s, np.where(neg, ch_o, ch_h))
        sh = np.where(small, sh_s, np.where(neg, sh_o, sh_h))
    return ch, sh


def dch(a, D, t):
    """Damped hyperbolic cosine ``exp(-a t) cosh(sqrt(D) t)``, entire in ``D``.

    Parameters
    ----------
    a : array_like
        Decay rate (1/time), e.g. ``alpha = kv / (2 m2)``.
    D : array_like
        Discriminant (1/time^2), e.g. ``alpha^2 - kp/m2``; any sign. ``D < 0`` gives
        ``exp(-a t) cos(sqrt(-D) t)``; ``D = 0`` gives ``exp(-a t)``.
    t : array_like
        Time. All inputs broadcast.

    Returns
    -------
    ndarray
        Broadcast shape of the inputs. For ``|D t^2| <= 1`` a power series in ``D t^2`` is
        used (no branch at ``D = 0``); elsewhere ``cos`` (``D < 0``) or a product of decaying
        exponentials ``(exp((r - a) t) + exp(-(r + a) t))/2`` (``D > 0``, no overflow of
        ``cosh`` when ``exp(-a t)`` is small). ``d/dt dch = -a dch + D dsh``.
    """
    return _damped_pair(a, D, t)[0][()]


def dsh(a, D, t):
    """Damped scaled hyperbolic sine ``exp(-a t) sinh(sqrt(D) t)/sqrt(D)``, entire in ``D``.

    ``D < 0``: ``exp(-a t) sin(sqrt(-D) t)/sqrt(-D)``; ``D = 0``: ``t exp(-a t)``.
    Same parameters, shapes and numerics as :func:`dch`. ``d/dt dsh = dch - a dsh``.
    """
    return _damped_pair(a, D, t)[1][()]


_NUMERIC_MODULES = [{"DCh": dch, "DSh": dsh}, "numpy"]


# ----------------------------------------------------------------------------------------
# SymPy side (lazy)
# ----------------------------------------------------------------------------------------


@functools.cache
def sympy_functions():
    """Return the SymPy function classes ``(DCh, DSh)`` (built once, on first call).

    ``DCh(a, D, t) = exp(-a t) cosh(sqrt(D) t)`` and ``DSh(a, D, t) = exp(-a t)
    sinh(sqrt(D) t)/sqrt(D)`` are entire in ``D``. Derivative rules:
    ``d/dt DCh = -a DCh + D DSh``, ``d/dt DSh = DCh - a DSh``, ``d/da DCh = -t DCh``,
    ``d/da DSh = -t DSh``, ``d/dD DCh = (t/2) DSh``, ``d/dD DSh = (t DCh - DSh)/(2 D)``
    (removable singularity at ``D = 0``). ``DCh(a, D, 0) = 1``, ``DSh(a, D, 0) = 0``.
    They lambdify to :func:`dch`, :func:`dsh` (pass ``modules=[{"DCh": dch, "DSh": dsh},
    "numpy"]``).
    """
    import sympy as sp
    from sympy.core.evalf import prec_to_dps
    from sympy.core.function import ArgumentIndexError

    def _numeric_value(a, D, t, which, prec):
        dps = prec_to_dps(prec)
        a, D, t = (sp.sympify(x).evalf(dps) for x in (a, D, t))
        if D == 0:
            val = sp.exp(-a * t) * (1 if which == "ch" else t)
        elif D < 0:
            b = sp.sqrt(-D)
            val = sp.exp(-a * t) * (sp.cos(b * t) if which == "ch" else sp.sin(b * t) / b)
        else:
            r = sp.sqrt(D)
            val = sp.exp(-a * t) * (sp.cosh(r * t) if which == "ch" else sp.sinh(r * t) / r)
        return val.evalf(dps)

    class DCh(sp.Function):
        """``exp(-a t) cosh(sqrt(D) t)`` (entire in ``D``); arguments ``(a, D, t)``."""

        nargs = 3
        is_real = True

        @classmethod
        def eval(cls, a, D, t):
            if t.is_zero:
                return sp.S.One
            return None

        def fdiff(self, argindex=1):
            a, D, t = self.args
            if argindex == 1:
                return -t * self
            if argindex == 2:
                return t / 2 * DSh(a, D, t)
            if argindex == 3:
                return -a * self + D * DSh(a, D, t)
            raise ArgumentIndexError(self, argindex)

        def _eval_evalf(self, prec):
            if all(x.is_number for x in self.args):
                return _numeric_value(*self.args, "ch", prec)
            return None

        def _eval_rewrite_as_cosh(self, a, D, t, **kwargs):
            return sp.exp(-a * t) * sp.cosh(sp.sqrt(D) * t)

        def _latex(self, printer, exp=None):
            # %-formatting: LaTeX braces would need doubling with str.format / f-strings
            a, D, t = (printer._print(x) for x in self.args)
            s = r"\operatorname{Ch}_{%s}\left(%s, %s\right)" % (a, D, t)  # noqa: UP031
            return s if exp is None else r"%s^{%s}" % (s, exp)  # noqa: UP031

    class DSh(sp.Function):
        """``exp(-a t) sinh(sqrt(D) t)/sqrt(D)`` (entire in ``D``); arguments ``(a, D, t)``."""

        nargs = 3
        is_real = True

        @classmethod
        def eval(cls, a, D, t):
            if t.is_zero:
                return sp.S.Zero
            return None

        def fdiff(self, argindex=1):
            a, D, t = self.args
            if argindex == 1:
                return -t * self
            if argindex == 2:
                return (t * DCh(a, D, t) - self) / (2 * D)
            if argindex == 3:
                return DCh(a, D, t) - a * self
            raise ArgumentIndexError(self, argindex)

        def _eval_evalf(self, prec):
            if all(x.is_number for x in self.args):
                return _numeric_value(*self.args, "sh", prec)
            return None

        def _eval_rewrite_as_sinh(self, a, D, t, **kwargs):
            return sp.exp(-a * t) * sp.sinh(sp.sqrt(D) * t) / sp.sqrt(D)

        def _latex(self, printer, exp=None):
            a, D, t = (printer._print(x) for x in self.args)
            s = r"\operatorname{Sh}_{%s}\left(%s, %s\right)" % (a, D, t)  # noqa: UP031
            return s if exp is None else r"%s^{%s}" % (s, exp)  # noqa: UP031

    return DCh, DSh


@functools.cache
def _symbols():
    import sympy as sp

    pos = dict(positive=True)
    d = dict(
        kp=sp.Symbol("k_p", **pos),
        kv=sp.Symbol("k_v", **pos),
        m2=sp.Symbol("m_2", **pos),
        w=sp.Symbol("omega", **pos),
        mu=sp.Symbol("mu", **pos),
        e=sp.Symbol("e", nonnegative=True),
        L=sp.Symbol("L", **pos),
        x10=sp.Symbol("x_10", **pos),
        n=sp.Symbol("n", odd=True, positive=True),
        t=sp.Symbol("t", real=True),
        tau=sp.Symbol("tau", positive=True),
        alpha=sp.Symbol("alpha", real=True),
        D=sp.Symbol("D", real=True),
        X0=sp.symbols("x1_0 y1_0 x2_0 y2_0 pc_0 ps_0", real=True),
        # existence
        C=sp.Symbol("C", real=True),
        S=sp.Symbol("S", real=True),
        v=sp.Symbol("y_10", positive=True),
        x20=sp.Symbol("x_20", real=True),
        y2m=sp.Symbol("y_20", real=True),
        y2p=sp.Symbol("y_21", real=True),
        # section
        phi=sp.Symbol("phi", real=True),
        z1=sp.Symbol("z_1", real=True),
        z2=sp.Symbol("z_2", real=True),
        z4=sp.Symbol("z_4", real=True),
        xm=sp.Symbol("x_m", positive=True),
        sig=sp.Symbol("sigma", real=True),
    )
    return d


@dataclass(frozen=True)
class Derivation:
    """The SymPy objects of one feedback case (see module docstring for conventions).

    Attributes
    ----------
    case : str
        ``"collocated"`` or ``"noncollocated"``.
    symbols : dict
        Name -> SymPy symbol (``kp, kv, m2, w, mu, e, L, x10, n, t, tau, alpha, D, X0, C, S,
        v (=y10), x20, y2m (=y20), y2p (=y21), phi, z1, z2, z4, xm, sig``).
    param_subs : dict
        ``{alpha: kv/(2 m2), D: alpha^2 - kp/m2}`` (substituted before lambdifying).
    A : sympy.Matrix
        6x6 closed-loop system matrix, ``X' = A X``.
    flow : sympy.Matrix
        6x1 closed-form ``X(t)`` in terms of ``X0`` (symbols ``x1_0 ... ps_0``), ``t``,
        parameters (and ``alpha``, ``D`` in the collocated case).
    Phi : sympy.Matrix
        6x6 state-transition matrix ``Phi(t) = d flow / d X0``.
    gap : list of sympy.Expr
        ``[z3, z3', z3'', z3''']`` at time ``t`` (``z3^(k) = c A^k X(t)``, ``c = e1 - e3``).
    R, y2_pre, y2_post : sympy.Expr
        (12), (10), (11) in terms of ``mu, e, v``.
    existence_conditions : list of sympy.Expr
        (13)-(14) as ``[x2(tau) + x20, y2(tau) + y20]`` with ``cos(w tau) = -1``,
        ``sin(w tau) = 0`` (``tau = n T/2``), in terms of ``C, S, x20, y20, y21, v, tau``.
    M, b : sympy.Matrix
        The linear system ``M [C, S]^T = b`` equivalent to the conditions.
    det : sympy.Expr
        ``det M`` (never zero for ``kv > 0``: collocated ``det M = -w (1 + 2 E cosh + E^2)``
        with ``E cosh = DCh(alpha, D, tau)``, non-collocated
        ``-(4/w^3) ((kp/m2 - w^2)^2 + (kv/m2)^2 w^2)``).
    C, S, xm, sn, cs : sympy.Expr
        Solution by Cramer's rule; ``xm = sqrt(C^2 + S^2)``, ``sn = S/xm``, ``cs = C/xm``.
    impact_block : sympy.Matrix
        4x4 ``DP10 = DP32`` (section coordinates; identical on both walls).
    flight_state0 : sympy.Matrix
        6x1 state on wall ``sigma`` from section coordinates ``(phi, z1, z2, z4)``.
    flight_out : sympy.Matrix
        4x1 ``(phi + tau, x2(tau), y2(tau), y1(tau) - y2(tau))``.
    flight_gap : sympy.Expr
        ``g = z3(tau) + sigma L`` (zero at the opposite wall).
    flight_parts : dict
        ``Fs`` (4x4), ``Ftau`` (4x1), ``Gs`` (1x4), ``Gtau`` (scalar, ``= z4(tau)``).
    flight_block : sympy.Matrix
        4x4 ``DP21`` (``sigma = +1``) / ``DP43`` (``sigma = -1``) = ``Fs - Ftau Gs / Gtau``,
        a function of the block's input ``(phi, z1, z2, z4)``, ``tau``, ``xm`` and parameters.
    """

    case: str
    symbols: dict
    param_subs: dict
    A: Any
    flow: Any
    Phi: Any
    gap: list
    R: Any
    y2_pre: Any
    y2_post: Any
    existence_conditions: list
    M: Any
    b: Any
    det: Any
    C: Any
    S: Any
    xm: Any
    sn: Any
    cs: Any
    impact_block: Any
    flight_state0: Any
    flight_out: Any
    flight_gap: Any
    flight_parts: dict
    flight_block: Any


def _case(case) -> str:
    return Case.parse(case).value


@functools.cache
def _flow_derivation(case: str):
    import sympy as sp

    DCh, DSh = sympy_functions()
    y = _symbols()
    kp, kv, m2, w, t = y["kp"], y["kv"], y["m2"], y["w"], y["t"]
    alpha, D = y["alpha"], y["D"]
    x10_, y10_, x20_, y20_, pc0, ps0 = y["X0"]
    cwt, swt = sp.cos(w * t), sp.sin(w * t)
    pc_t = pc0 * cwt - ps0 * swt
    ps_t = ps0 * cwt + pc0 * swt
    x1_t = x10_ + y10_ * t
    y1_t = y10_
    if case == "collocated":
        e0 = x20_ - pc0  # tracking error x2 - xd at t = 0
        de0 = y20_ + w * ps0  # its derivative y2 - xd'
        ch, sh = DCh(alpha, D, t), DSh(alpha, D, t)
        err = e0 * (ch + alpha * sh) + de0 * sh
        derr = de0 * (ch - alpha * sh) - (kp / m2) * e0 * sh
        x2_t = pc_t + err
        y2_t = -w * ps_t + derr
        A_y2 = [0, 0, -kp / m2, -kv / m2, kp / m2 - w**2, -kv * w / m2]
    else:
        # x2'' = -w^2 pc - (kv/m2)(y1 + w ps) - (kp/m2)(x1 - pc), integrated twice exactly.
        I1pc = (ps_t - ps0) / w  # int_0^t pc
        I1ps = (pc0 - pc_t) / w  # int_0^t ps
        I2pc = (I1ps - ps0 * t) / w  # int_0^t int_0^s pc
        I2ps = (pc0 * t - I1pc) / w  # int_0^t int_0^s ps
        a = kp / m2 - w**2
        k = kv / m2
        y2_t = (y20_ + a * I1pc - k * w * I1ps - k * y10_ * t
                - (kp / m2) * (x10_ * t + y10_ * t**2 / 2))
        x2_t = (x20_ + y20_ * t + a * I2pc - k * w * I2ps - k * y10_ * t**2 / 2
                - (kp / m2) * (x10_ * t**2 / 2 + y10_ * t**3 / 6))
        A_y2 = [-kp / m2, -kv / m2, 0, 0, kp / m2 - w**2, -kv * w / m2]
    flow = sp.Matrix([x1_t, y1_t, x2_t, y2_t, pc_t, ps_t])
    A = sp.Matrix([
        [0, 1, 0, 0, 0, 0],
        [0, 0, 0, 0, 0, 0],
        [0, 0, 0, 1, 0, 0],
        A_y2,
        [0, 0, 0, 0, 0, -w],
        [0, 0, 0, 0, w, 0],
    ])
    Phi = flow.jacobian(sp.Matrix(y["X0"]))
    c = sp.Matrix([[1, 0, -1, 0, 0, 0]])
    gaps = []
    row = c
    for _ in range(4):
        gaps.append(sp.expand((row * flow)[0]))
        row = row * A
    param_subs = {alpha: kv / (2 * m2), D: kv**2 / (4 * m2**2) - kp / m2}
    return dict(flow=flow, A=A, Phi=Phi, gap=gaps, param_subs=param_subs)


@functools.cache
def _existence_derivation(case: str):
    import sympy as sp

    y = _symbols()
    fd = _flow_derivation(case)
    mu, e, w, t, tau, L = y["mu"], y["e"], y["w"], y["t"], y["tau"], y["L"]
    C, S, v, x20, y2m, y2p = y["C"], y["S"], y["v"], y["x20"], y["y2m"], y["y2p"]
    R = (e + 2 * e * mu - 1) / (e - 2 * mu - 1)
    y2_pre = v * (e - 2 * mu - 1) / (1 + e)
    y2_post = v * (e + 2 * e * mu - 1) / (1 + e)
    # post-impact state at t0 on wall +1 (x1 = x10 = x20 + L, y1+ = -v)
    X0 = dict(zip(y["X0"], [x20 + L, -v, x20, y2p, C, S]))
    Xt = fd["flow"].subs(t, tau).xreplace(X0)
    wsub = {sp.cos(w * tau): -1, sp.sin(w * tau): 0}
    conds = [sp.expand(Xt[2].subs(wsub) + x20), sp.expand(Xt[3].subs(wsub) + y2m)]
    M, b = sp.linear_eq_to_matrix(conds, [C, S])
    det = M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]
    Csol = (b[0] * M[1, 1] - M[0, 1] * b[1]) / det
    Ssol = (M[0, 0] * b[1] - M[1, 0] * b[0]) / det
    xm = sp.sqrt(Csol**2 + Ssol**2)
    return dict(R=R, y2_pre=y2_pre, y2_post=y2_post, conds=conds, M=M, b=b, det=det,
                C=Csol, S=Ssol, xm=xm, sn=Ssol / xm, cs=Csol / xm)


@functools.cache
def _impact_block_derivation():
    import sympy as sp

    y = _symbols()
    mu, e = y["mu"], y["e"]
    z1, z2, z4, phi = y["z1"], y["z2"], y["z4"], y["phi"]
    # velocities from section coordinates, impact law (2), back to section coordinates
    y1, y2 = z2 + z4, z2
    y1p = ((mu - e) * y1 + (1 + e) * y2) / (1 + mu)
    y2p = ((1 + e) * mu * y1 + (1 - mu * e) * y2) / (1 + mu)
    out = sp.Matrix([phi, z1, y2p, y1p - y2p])
    return out.jacobian([phi, z1, z2, z4]).applyfunc(sp.factor)


@functools.cache
def _flight_derivation(case: str):
    import sympy as sp

    y = _symbols()
    fd = _flow_derivation(case)
    t, tau, w, L = y["t"], y["tau"], y["w"], y["L"]
    phi, z1, z2, z4, xm, sig = y["phi"], y["z1"], y["z2"], y["z4"], y["xm"], y["sig"]
    svars = [phi, z1, z2, z4]
    X0s = sp.Matrix([z1 + sig * L, z2 + z4, z1, z2, xm * sp.cos(w * phi), xm * sp.sin(w * phi)])
    Phi = fd["Phi"].subs(t, tau)
    A = fd["A"]
    Xtau = Phi * X0s
    J = X0s.jacobian(svars)  # 6x4
    PJ = Phi * J  # d X(tau) / d s at fixed tau
    AX = A * Xtau  # d X(tau) / d tau
    Mz = sp.Matrix([[0, 0, 1, 0, 0, 0], [0, 0, 0, 1, 0, 0], [0, 1, 0, -1, 0, 0]])
    c = sp.Matrix([[1, 0, -1, 0, 0, 0]])
    Fs = sp.Matrix.vstack(sp.Matrix([[1, 0, 0, 0]]), Mz * PJ)
    Ftau = sp.Matrix.vstack(sp.Matrix([[1]]), Mz * AX)
    Gs = c * PJ
    Gtau = (c * AX)[0]
    block = Fs - Ftau * Gs / Gtau
    out = sp.Matrix.vstack(sp.Matrix([[phi + tau]]), Mz * Xtau)
    g = (c * Xtau)[0] + sig * L
    return dict(X0s=X0s, out=out, g=g, parts=dict(Fs=Fs, Ftau=Ftau, Gs=Gs, Gtau=Gtau),
                block=block)


def derivation(case="collocated") -> Derivation:
    """All SymPy derivations of one feedback case (cached; first call takes ~1 s).

    Parameters
    ----------
    case : {"collocated", "noncollocated"} or hybridpd.Case

    Returns
    -------
    Derivation
        Dataclass of SymPy objects; see its docstring.
    """
    case = _case(case)
    return _derivation(case)


@functools.cache
def _derivation(case: str) -> Derivation:
    fd = _flow_derivation(case)
    ex = _existence_derivation(case)
    fl = _flight_derivation(case)
    return Derivation(
        case=case, symbols=dict(_symbols()), param_subs=fd["param_subs"], A=fd["A"],
        flow=fd["flow"], Phi=fd["Phi"], gap=list(fd["gap"]), R=ex["R"], y2_pre=ex["y2_pre"],
        y2_post=ex["y2_post"], existence_conditions=list(ex["conds"]), M=ex["M"], b=ex["b"],
        det=ex["det"], C=ex["C"], S=ex["S"], xm=ex["xm"], sn=ex["sn"], cs=ex["cs"],
        impact_block=_impact_block_derivation(), flight_state0=fl["X0s"], flight_out=fl["out"],
        flight_gap=fl["g"], flight_parts=dict(fl["parts"]), flight_block=fl["block"],
    )


# ----------------------------------------------------------------------------------------
# Lambdified numerics (cached)
# ----------------------------------------------------------------------------------------


def _lambdify(args, exprs, subs):
    import sympy as sp

    exprs = [sp.sympify(ex).xreplace(subs) for ex in exprs]
    return sp.lambdify(args, exprs, modules=_NUMERIC_MODULES, cse=True)


def _as_float_arrays(*xs):
    return [np.asarray(x, dtype=float) for x in xs]


def _stack(values, shape, axis=-1):
    """Broadcast lambdify outputs (scalars or arrays) to ``shape`` and stack on a new last axis."""
    return np.stack([np.broadcast_to(np.asarray(v, dtype=float), shape) for v in values],
                    axis=axis)


@functools.cache
def _flow_numeric(case: str):
    fd = _flow_derivation(case)
    y = _symbols()
    par = [y["kp"], y["kv"], y["m2"], y["w"]]
    args = [y["t"], *y["X0"], *par]
    subs = fd["param_subs"]
    f_flow = _lambdify(args, list(fd["flow"]), subs)
    f_phi = _lambdify([y["t"], *par], list(fd["Phi"]), subs)
    f_gap = _lambdify(args, list(fd["gap"]), subs)
    return f_flow, f_phi, f_gap


def _flow_args(t, X0, kp, kv, m2, w):
    t, X0, kp, kv, m2, w = _as_float_arrays(t, X0, kp, kv, m2, w)
    if X0.shape[-1:] != (6,):
        raise ValueError(f"X0 must have shape (..., 6) [x1, y1, x2, y2, pc, ps], got {X0.shape}")
    shape = np.broadcast_shapes(t.shape, X0.shape[:-1], kp.shape, kv.shape, m2.shape, w.shape)
    return t, X0, kp, kv, m2, w, shape


def system_matrix(*, kp, kv, m2=1.0, w, case="collocated") -> np.ndarray:
    """Closed-loop 6x6 matrix ``A`` of ``X' = A X``, ``X = [x1, y1, x2, y2, pc, ps]``.

    Parameters
    ----------
    kp, kv, m2, w : array_like
        Gains (N/m, N s/m), secondary mass (kg), reference frequency (rad/s); broadcast.
    case : {"collocated", "noncollocated"}

    Returns
    -------
    ndarray, shape (..., 6, 6)
        Row ``y2'``: collocated ``[0, 0, -kp/m2, -kv/m2, kp/m2 - w^2, -kv w/m2]``;
        non-collocated ``[-kp/m2, -kv/m2, 0, 0, kp/m2 - w^2, -kv w/m2]``.
    """
    case = _case(case)
    kp, kv, m2, w = _as_float_arrays(kp, kv, m2, w)
    shape = np.broadcast_shapes(kp.shape, kv.shape, m2.shape, w.shape)
    A = np.zeros(shape + (6, 6))
    A[..., 0, 1] = 1.0
    A[..., 2, 3] = 1.0
    i, j = (2, 3) if case == "collocated" else (0, 1)
    A[..., 3, i] = -kp / m2
    A[..., 3, j] = -kv / m2
    A[..., 3, 4] = kp / m2 - w**2
    A[..., 3, 5] = -kv * w / m2
    A[..., 4, 5] = -w
    A[..., 5, 4] = w
    return A


def transition_matrix(t, *, kp, kv, m2=1.0, w, case="collocated") -> np.ndarray:
    """Closed-form state-transition matrix ``Phi(t) = expm(A t)``.

    Parameters
    ----------
    t : array_like
        Time since the initial state (any sign).
    kp, kv, m2, w : array_like
        Parameters (see :func:`system_matrix`); all broadcast with ``t``.
    case : {"collocated", "noncollocated"}

    Returns
    -------
    ndarray, shape (..., 6, 6)
        ``X(t) = Phi(t) @ X(0)``. Continuous across critical damping ``kv^2 = 4 kp m2``.
    """
    case = _case(case)
    t, kp, kv, m2, w = _as_float_arrays(t, kp, kv, m2, w)
    shape = np.broadcast_shapes(t.shape, kp.shape, kv.shape, m2.shape, w.shape)
    vals = _flow_numeric(case)[1](t, kp, kv, m2, w)
    return _stack(vals, shape).reshape(shape + (6, 6))


def flow(t, X0, *, kp, kv, m2=1.0, w, case="collocated") -> np.ndarray:
    """State at time ``t`` from the state ``X0`` at time 0 (closed form).

    Parameters
    ----------
    t : array_like
        Elapsed time.
    X0 : array_like, shape (..., 6)
        ``[x1, y1, x2, y2, pc, ps]`` at time 0 (``pc = xm cos(w t0)``, ``ps = xm sin(w t0)``).
    kp, kv, m2, w : array_like
        Parameters; broadcast with ``t`` and ``X0[..., 0]``.
    case : {"collocated", "noncollocated"}

    Returns
    -------
    ndarray, shape (..., 6)
        ``X(t)``, no impacts taken into account.
    """
    case = _case(case)
    t, X0, kp, kv, m2, w, shape = _flow_args(t, X0, kp, kv, m2, w)
    vals = _flow_numeric(case)[0](t, *np.moveaxis(X0, -1, 0), kp, kv, m2, w)
    return _stack(vals, shape)


def gap_derivatives(t, X0, *, kp, kv, m2=1.0, w, case="collocated", order=3) -> np.ndarray:
    """Gap ``z3 = x1 - x2`` and its time derivatives at time ``t`` (closed form).

    Parameters
    ----------
    t, X0, kp, kv, m2, w, case
        As in :func:`flow`.
    order : int, 0..3
        Highest derivative returned.

    Returns
    -------
    ndarray, shape (..., order + 1)
        ``[z3, z3', z3'', z3''']`` truncated to ``order + 1`` entries
        (``z3' = z4 = y1 - y2``; ``z3^(k) = c A^k X(t)``).
    """
    case = _case(case)
    if not 0 <= int(order) <= 3:
        raise ValueError(f"order must be in 0..3, got {order!r}")
    t, X0, kp, kv, m2, w, shape = _flow_args(t, X0, kp, kv, m2, w)
    vals = _flow_numeric(case)[2](t, *np.moveaxis(X0, -1, 0), kp, kv, m2, w)
    return _stack(vals[: int(order) + 1], shape)


def gap(t, X0, *, kp, kv, m2=1.0, w, case="collocated", order=0) -> np.ndarray:
    """The ``order``-th time derivative (0..3) of ``z3 = x1 - x2`` at time ``t``; shape ``(...)``.

    See :func:`gap_derivatives`.
    """
    return gap_derivatives(t, X0, kp=kp, kv=kv, m2=m2, w=w, case=case, order=order)[..., -1]


# ----------------------------------------------------------------------------------------
# Section coordinates
# ----------------------------------------------------------------------------------------


def state_from_section(s, *, xm, L, w, wall=1) -> np.ndarray:
    """Full state on wall ``wall`` from section coordinates.

    Parameters
    ----------
    s : array_like, shape (..., 4)
        ``(phi, z1, z2, z4)``: phase (time mod T), ``x2``, ``y2``, ``y1 - y2``.
    xm, L, w : array_like
        Reference amplitude, half clearance, reference frequency.
    wall : {+1, -1}
        The state lies on ``z3 = wall * L``.

    Returns
    -------
    ndarray, shape (..., 6)
        ``(z1 + wall L, z2 + z4, z1, z2, xm cos(w phi), xm sin(w phi))``.
    """
    s, xm, L, w, wall = _as_float_arrays(s, xm, L, w, wall)
    phi, z1, z2, z4 = np.moveaxis(s, -1, 0)
    shape = np.broadcast_shapes(phi.shape, xm.shape, L.shape, w.shape, wall.shape)
    return _stack([z1 + wall * L, z2 + z4, z1, z2, xm * np.cos(w * phi), xm * np.sin(w * phi)],
                  shape)


def section_from_state(X, *, w) -> np.ndarray:
    """Section coordinates ``(phi, z1, z2, z4)`` of a full state (shape (..., 6) -> (..., 4)).

    ``phi = atan2(ps, pc)/w mod T``; the wall (``z3``) is not checked.
    """
    X, w = _as_float_arrays(X, w)
    T = 2.0 * np.pi / w
    phi = np.mod(np.arctan2(X[..., 5], X[..., 4]) / w, T)
    shape = np.broadcast_shapes(phi.shape, X.shape[:-1])
    return _stack([phi, X[..., 2], X[..., 3], X[..., 1] - X[..., 3]], shape)


# ----------------------------------------------------------------------------------------
# Symmetric orbit (paper section 3)
# ----------------------------------------------------------------------------------------


def virtual_restitution(mu, e):
    """Virtual restitution coefficient (12): ``R = (e + 2 e mu - 1)/(e - 2 mu - 1)``."""
    mu, e = _as_float_arrays(mu, e)
    return ((e + 2 * e * mu - 1) / (e - 2 * mu - 1))[()]


def symmetric_velocities(*, mu, e, w, x10, n=1):
    """Impact velocities of the symmetric orbit of order ``n``, (9)-(11).

    Returns
    -------
    v, y2_pre, y2_post : ndarray
        ``v = y10 = 2 x10 w / (n pi)`` (primary-mass speed; pre-impact ``y1- = +v``,
        post ``y1+ = -v`` at the ``+L`` wall), ``y2_pre = v (e - 2 mu - 1)/(1 + e)`` (10),
        ``y2_post = v (e + 2 e mu - 1)/(1 + e) = R y2_pre`` (11).
    """
    mu, e, w, x10, n = _as_float_arrays(mu, e, w, x10, n)
    v = 2.0 * x10 * w / (n * np.pi)
    return (v[()], (v * (e - 2 * mu - 1) / (1 + e))[()],
            (v * (e + 2 * e * mu - 1) / (1 + e))[()])


@functools.cache
def _existence_numeric(case: str):
    import sympy as sp

    y = _symbols()
    fd = _flow_derivation(case)
    ex = _existence_derivation(case)
    kp, kv, m2, mu, e, L, w, x10, n = (y[k] for k in
                                       ("kp", "kv", "m2", "mu", "e", "L", "w", "x10", "n"))
    v = 2 * x10 * w / (n * sp.pi)
    subs = dict(fd["param_subs"])
    subs.update({y["tau"]: n * sp.pi / w, y["v"]: v, y["x20"]: x10 - L,
                 y["y2m"]: v * (e - 2 * mu - 1) / (1 + e),
                 y["y2p"]: v * (e + 2 * e * mu - 1) / (1 + e)})
    M, b = ex["M"], ex["b"]
    exprs = [M[0, 0], M[0, 1], M[1, 0], M[1, 1], b[0], b[1]]
    return _lambdify([kp, kv, m2, mu, e, L, w, x10, n], exprs, subs)


def _check_odd(n):
    n = np.asarray(n)
    nf = np.asarray(n, dtype=float)
    if not np.all((nf == np.round(nf)) & (nf >= 1) & (np.mod(nf, 2) == 1)):
        raise ValueError(f"n must be a positive odd integer (or array of them), got {n!r}")
    return nf


@dataclass(frozen=True)
class SymmetricOrbit:
    """Simple symmetric periodic orbit of order ``n`` (paper section 3).

    All array fields share the broadcast shape of the inputs of :func:`symmetric_orbit`.
    The orbit is only *candidate*: viability (18) (no extra impact in between) is not
    checked here.

    Attributes
    ----------
    case : str
        ``"collocated"`` or ``"noncollocated"``.
    kp, kv, m2, mu, e, L, w, x10, n : ndarray
        The inputs, broadcast.
    C, S : ndarray
        ``xm cos(w t0)``, ``xm sin(w t0)`` at the ``+L`` impact (length).
    xm : ndarray
        Reference amplitude ``hypot(C, S)`` (20) (length).
    sn, cs : ndarray
        ``sin(w phi0) = S/xm``, ``cos(w phi0) = C/xm`` (15)-(16).
    phi0 : ndarray
        Phase of the ``+L`` impact, ``atan2(S, C)/w mod T``, in ``[0, T)`` (time).
    T, tau : ndarray
        ``2 pi / w`` and the flight time ``n T / 2`` between impacts (time).
    x20 : ndarray
        ``x10 - L``: secondary-mass position at the ``+L`` impact (may be negative).
    v : ndarray
        ``y10 = 2 x10 w/(n pi)``; ``y1- = +v``, ``y1+ = -v`` at the ``+L`` impact.
    y2_pre, y2_post : ndarray
        Secondary-mass velocity before (10) and after (11) the ``+L`` impact.
    R : ndarray
        Virtual restitution coefficient (12).
    det : ndarray
        Determinant of the 2x2 linear system for ``(C, S)``.
    singular : ndarray of bool
        ``|det|`` below ``1e-13`` times the product of the row norms (then ``C``, ``S`` are
        unreliable or NaN). Never true for ``kv > 0`` (see :class:`Derivation`).
    """

    case: str
    kp: np.ndarray
    kv: np.ndarray
    m2: np.ndarray
    mu: np.ndarray
    e: np.ndarray
    L: np.ndarray
    w: np.ndarray
    x10: np.ndarray
    n: np.ndarray
    C: np.ndarray
    S: np.ndarray
    xm: np.ndarray
    sn: np.ndarray
    cs: np.ndarray
    phi0: np.ndarray
    T: np.ndarray
    tau: np.ndarray
    x20: np.ndarray
    v: np.ndarray
    y2_pre: np.ndarray
    y2_post: np.ndarray
    R: np.ndarray
    det: np.ndarray
    singular: np.ndarray

    @property
    def section_point(self) -> np.ndarray:
        """Pre-impact point on the section, ``(phi0, x20, y2_pre, v - y2_pre)``, shape (..., 4)."""
        return np.stack(np.broadcast_arrays(self.phi0, self.x20, self.y2_pre,
                                            self.v - self.y2_pre), axis=-1)

    @property
    def post_impact_state(self) -> np.ndarray:
        """Full state right after the ``+L`` impact, ``(x10, -v, x20, y2_post, C, S)``; (..., 6)."""
        return np.stack(np.broadcast_arrays(self.x10, -self.v, self.x20, self.y2_post,
                                            self.C, self.S), axis=-1)


def symmetric_orbit(*, kp, kv, m2=1.0, mu, e, L, w, x10, n=1,
                    case="collocated") -> SymmetricOrbit:
    """Solve the existence conditions (13)-(14) of the symmetric orbit; vectorised.

    Parameters
    ----------
    kp, kv : array_like
        PD gains (> 0).
    m2 : array_like
        Secondary mass (> 0), default 1.
    mu : array_like
        Mass ratio ``m1/m2`` (> 0).
    e : array_like
        Restitution coefficient in [0, 1].
    L : array_like
        Half clearance (> 0).
    w : array_like
        Reference frequency (rad/time, > 0).
    x10 : array_like
        Desired amplitude of the primary mass (> 0); ``x20 = x10 - L``.
    n : int or array_like of odd int
        Orbit order (period ``n T``).
    case : {"collocated", "noncollocated"}

    Returns
    -------
    SymmetricOrbit
        All fields broadcast to the common shape (e.g. a 200x200x3 grid of (kp, kv, e)
        evaluates in a few tens of ms).

    Raises
    ------
    ValueError
        If ``n`` is not a positive odd integer, a parameter is out of range (``kp, kv, m2,
        mu, L, w, x10 > 0``, ``0 <= e <= 1``) or ``case`` is unknown.

    Notes
    -----
    ``x20 = x10 - L`` may be negative (allowed). Existence in the paper's sense also needs
    viability (18), which is not checked here. The determinant of the 2x2 system is
    ``-w (1 + 2 DCh(alpha, D, tau) + exp(-2 alpha tau)) <= -w (1 - exp(-alpha tau))^2 < 0``
    (collocated) and ``-(4/w^3)((kp/m2 - w^2)^2 + (kv w/m2)^2) < 0`` (non-collocated), so
    for ``kv > 0`` the system is never singular; ``singular`` flags numerical trouble only.
    """
    case = _case(case)
    nf = _check_odd(n)
    kp, kv, m2, mu, e, L, w, x10 = _as_float_arrays(kp, kv, m2, mu, e, L, w, x10)
    for name, val in (("kp", kp), ("kv", kv), ("m2", m2), ("mu", mu), ("L", L), ("w", w),
                      ("x10", x10)):
        if not np.all(np.isfinite(val) & (val > 0)):
            raise ValueError(f"{name} must be finite and > 0 everywhere")
    if not np.all((e >= 0) & (e <= 1)):
        raise ValueError("e must lie in [0, 1] everywhere")
    shape = np.broadcast_shapes(kp.shape, kv.shape, m2.shape, mu.shape, e.shape, L.shape,
                                w.shape, x10.shape, nf.shape)
    f = _existence_numeric(case)
    m00, m01, m10, m11, b0, b1 = (np.broadcast_to(np.asarray(q, dtype=float), shape)
                                  for q in f(kp, kv, m2, mu, e, L, w, x10, nf))
    with np.errstate(all="ignore"):
        det = m00 * m11 - m01 * m10
        scale = np.hypot(m00, m01) * np.hypot(m10, m11)
        singular = ~(np.abs(det) > 1e-13 * scale)
        C = (b0 * m11 - m01 * b1) / det
        S = (m00 * b1 - m10 * b0) / det
        C = np.where(singular, np.nan, C)
        S = np.where(singular, np.nan, S)
        xm = np.hypot(C, S)
        sn = S / xm
        cs = C / xm
        T = 2.0 * np.pi / w
        phi0 = np.mod(np.arctan2(S, C) / w, T)
    v, y2m, y2p = symmetric_velocities(mu=mu, e=e, w=w, x10=x10, n=nf)
    b = lambda a: np.broadcast_to(np.asarray(a, dtype=float), shape)[()]
    return SymmetricOrbit(
        case=case, kp=b(kp), kv=b(kv), m2=b(m2), mu=b(mu), e=b(e), L=b(L), w=b(w), x10=b(x10),
        n=b(nf), C=b(C), S=b(S), xm=b(xm), sn=b(sn), cs=b(cs), phi0=b(phi0), T=b(T),
        tau=b(nf * T / 2), x20=b(x10 - L), v=b(v), y2_pre=b(y2m), y2_post=b(y2p),
        R=b(virtual_restitution(mu, e)), det=b(det), singular=b(singular),
    )


# ----------------------------------------------------------------------------------------
# Impact map (paper section 4)
# ----------------------------------------------------------------------------------------


def impact_section_map(s, *, mu, e) -> np.ndarray:
    """Impact (P10 or P32) in section coordinates: ``(phi, z1, z2 + (1+e) mu z4/(1+mu), -e z4)``.

    ``s`` has shape (..., 4) (pre-impact); the law is the same on both walls.
    """
    s, mu, e = _as_float_arrays(s, mu, e)
    phi, z1, z2, z4 = np.moveaxis(s, -1, 0)
    shape = np.broadcast_shapes(phi.shape, mu.shape, e.shape)
    return _stack([phi, z1, z2 + (1 + e) * mu / (1 + mu) * z4, -e * z4], shape)


def impact_block(*, mu, e) -> np.ndarray:
    """Jacobian ``DP10 = DP32`` of the impact in section coordinates, shape (..., 4, 4).

    ``[[1,0,0,0],[0,1,0,0],[0,0,1,(1+e) mu/(1+mu)],[0,0,0,-e]]`` (independent of the state).
    """
    mu, e = _as_float_arrays(mu, e)
    shape = np.broadcast_shapes(mu.shape, e.shape)
    B = np.zeros(shape + (4, 4))
    B[..., 0, 0] = B[..., 1, 1] = B[..., 2, 2] = 1.0
    B[..., 2, 3] = (1 + e) * mu / (1 + mu)
    B[..., 3, 3] = -e
    return B


@functools.cache
def _flight_numeric(case: str):
    fl = _flight_derivation(case)
    fd = _flow_derivation(case)
    y = _symbols()
    args = [y["phi"], y["z1"], y["z2"], y["z4"], y["tau"], y["xm"],
            y["kp"], y["kv"], y["m2"], y["w"], y["L"], y["sig"]]
    subs = fd["param_subs"]
    f_out = _lambdify(args, list(fl["out"]) + [fl["g"]], subs)
    # block and output together: the common subexpressions (Phi(tau), X(tau)) are shared
    f_both = _lambdify(args, list(fl["block"]) + list(fl["out"]) + [fl["g"]], subs)
    return f_both, f_out


def _flight_args(s, tau, xm, kp, kv, m2, w, L, wall):
    s, tau, xm, kp, kv, m2, w, L, wall = _as_float_arrays(s, tau, xm, kp, kv, m2, w, L, wall)
    if s.shape[-1:] != (4,):
        raise ValueError(f"s must have shape (..., 4) (phi, z1, z2, z4), got {s.shape}")
    if not np.all(np.abs(wall) == 1):
        raise ValueError("wall must be +1 or -1")
    shape = np.broadcast_shapes(s.shape[:-1], tau.shape, xm.shape, kp.shape, kv.shape,
                                m2.shape, w.shape, L.shape, wall.shape)
    return [*np.moveaxis(s, -1, 0), tau, xm, kp, kv, m2, w, L, wall], shape


def flight_section_map(s, tau, *, xm, kp, kv, m2=1.0, w, L, wall=1,
                       case="collocated", return_gap=False):
    """Flight from wall ``wall`` lasting ``tau``, in section coordinates (closed form).

    Parameters
    ----------
    s : array_like, shape (..., 4)
        Post-impact ``(phi, z1, z2, z4)`` on ``z3 = wall * L``.
    tau : array_like
        Flight time (the caller supplies it, e.g. from :func:`flight_time`).
    xm, kp, kv, m2, w, L : array_like
        Reference amplitude and parameters.
    wall : {+1, -1}
        Departure wall; the flight is meant to end on ``z3 = -wall * L``.
    case : {"collocated", "noncollocated"}
    return_gap : bool
        Also return ``g = z3(tau) + wall L`` (zero when ``tau`` is the flight time).

    Returns
    -------
    s_out : ndarray, shape (..., 4)
        ``(phi + tau, x2(tau), y2(tau), y1(tau) - y2(tau))`` (``phi`` not reduced mod T).
    g : ndarray, shape (...)
        Only with ``return_gap``.
    """
    case = _case(case)
    args, shape = _flight_args(s, tau, xm, kp, kv, m2, w, L, wall)
    vals = _flight_numeric(case)[1](*args)
    out = _stack(vals[:4], shape)
    if return_gap:
        return out, np.broadcast_to(np.asarray(vals[4], dtype=float), shape)[()]
    return out


def flight_block(s, tau, *, xm, kp, kv, m2=1.0, w, L, wall=1, case="collocated") -> np.ndarray:
    """Jacobian of a flight block, ``DP21`` (``wall=+1``) or ``DP43`` (``wall=-1``).

    Implicit differentiation (26): ``DP = Fs - Ftau (Gs / Gtau)`` with
    ``F = (phi + tau, x2, y2, y1 - y2)(tau)``, ``G = z3(tau) + wall L``,
    ``Gtau = z4(tau)`` (the pre-impact relative velocity; must be non-zero).

    Parameters
    ----------
    s : array_like, shape (..., 4)
        The block's input: post-impact ``(phi, z1, z2, z4)`` on ``z3 = wall L``.
    tau : array_like
        The flight time to ``z3 = -wall L``.
    xm, kp, kv, m2, w, L, wall, case
        As in :func:`flight_section_map`.

    Returns
    -------
    ndarray, shape (..., 4, 4)
        ``d(phi, z1, z2, z4)_out / d(phi, z1, z2, z4)_in``.
    """
    case = _case(case)
    return _flight_block_and_map(s, tau, xm, kp, kv, m2, w, L, wall, case)[0]


def _flight_block_and_map(s, tau, xm, kp, kv, m2, w, L, wall, case):
    """(block (..., 4, 4), s_out (..., 4), gap (...)) in one lambdified call."""
    args, shape = _flight_args(s, tau, xm, kp, kv, m2, w, L, wall)
    vals = _flight_numeric(case)[0](*args)
    block = _stack(vals[:16], shape).reshape(shape + (4, 4))
    out = _stack(vals[16:20], shape)
    g = np.broadcast_to(np.asarray(vals[20], dtype=float), shape)[()]
    return block, out, g


def flight_time(s, *, xm, kp, kv, m2=1.0, w, L, wall=1, case="collocated",
                tmax=None, return_wall=False):
    """First time a flight from wall ``wall`` hits a wall (closed-form gap + root finding).

    Scalar (one section point). The gap ``z3(t)`` and ``z3'(t)`` are sampled on a grid
    whose step resolves the fastest time scale (``T/64``, ``1/(8 omega_n)``, ``1/(8 alpha)``);
    a root is bracketed by a sign change, and on intervals where ``z3'`` changes sign the
    extremum is located first so that a pair of crossings within one step (near grazing) is
    not missed (assumes at most one extremum of ``z3`` per step). Roots are refined by
    ``brentq`` to full precision.

    Parameters
    ----------
    s : array_like, shape (4,)
        Post-impact ``(phi, z1, z2, z4)`` on ``z3 = wall L``; ``wall * z4 < 0`` (leaving).
    xm, kp, kv, m2, w, L, wall, case
        As in :func:`flight_section_map`.
    tmax : float, optional
        Search horizon; default ``50 T``.
    return_wall : bool
        Also return the wall hit (``-wall`` normally; ``+wall`` if the masses meet the
        departure wall again first).

    Returns
    -------
    tau : float
        First impact time (``nan`` if none before ``tmax`` or if ``wall * z4 >= 0``).
    hit : int
        Only with ``return_wall``: the wall hit (0 if none).
    """
    case = _case(case)
    s = np.asarray(s, dtype=float)
    kp, kv, m2, w, L, xm = (float(q) for q in (kp, kv, m2, w, L, xm))
    wall = int(wall)
    X0 = state_from_section(s, xm=xm, L=L, w=w, wall=wall)
    T = 2 * np.pi / w

    def zz(t):
        return gap_derivatives(t, X0, kp=kp, kv=kv, m2=m2, w=w, case=case, order=1)

    res = (np.nan, 0)
    if not wall * s[3] < 0:
        return res if return_wall else res[0]
    if tmax is None:
        tmax = 50 * T
    rate = max(math.sqrt(abs(kp / m2)), abs(kv / (2 * m2)), 1e-300)
    h = min(T / 64, 1 / (8 * rate))
    nchunk = 256
    t0 = 0.0
    while t0 < tmax:
        tt = t0 + h * np.arange(nchunk + 1)
        zd = zz(tt)
        events = []
        for target in (-wall, wall):
            tr = _first_root(lambda t, tg=target: float(zz(t)[0]) - tg * L,
                             lambda t: float(zz(t)[1]), tt, zd[:, 0] - target * L, zd[:, 1],
                             departing=(target == wall and t0 == 0.0))
            if tr is not None:
                events.append((tr, target))
        if events:
            res = min(events)
            break
        t0 = tt[-1]
    return res if return_wall else res[0]


def _first_root(g, gd, tt, gv, gdv, departing=False):
    """First root of ``g`` on the grid ``tt`` (values ``gv``, slopes ``gdv``).

    ``departing``: ``g(tt[0]) = 0`` is the departure itself and is not a root; in the first
    interval only a return after an extremum counts.
    """
    from scipy.optimize import brentq

    def root(a, b):
        ga, gb = g(a), g(b)
        if ga * gb > 0:  # grid and scalar evaluations differ in the last bit at an endpoint
            return a if abs(ga) < abs(gb) else b
        return brentq(g, a, b, xtol=1e-15, rtol=1e-15, maxiter=200)

    for k in range(len(tt) - 1):
        a, b = tt[k], tt[k + 1]
        ga, gb = gv[k], gv[k + 1]
        da, db = gdv[k], gdv[k + 1]
        first = departing and k == 0
        if ga == 0.0 and not first:
            return a
        if da * db < 0:  # an extremum inside: split there
            dA, dB = gd(a), gd(b)
            tm = (brentq(gd, a, b, xtol=1e-15, rtol=1e-15, maxiter=200) if dA * dB < 0
                  else (a if abs(dA) < abs(dB) else b))
            gm = g(tm)
            if not first and ga * gm < 0:
                return root(a, tm)
            if gm == 0.0:
                return tm
            if gm * gb < 0:
                return root(tm, b)
        elif not first and ga * gb < 0:
            return root(a, b)
        if gb == 0.0:
            return b
    return None


@dataclass(frozen=True)
class ImpactMapResult:
    """One application of the impact map ``P`` (numerical: closed-form flows + root finding).

    Attributes
    ----------
    s0, s1, s2, s3, s4 : ndarray, shape (4,)
        Pre-impact at ``+L``, post-impact, pre-impact at ``-L``, post-impact, pre-impact at
        ``+L`` (``phi`` accumulates: ``s4[0] = s0[0] + tau1 + tau2``, not reduced mod T).
    tau1, tau2 : float
        Flight times ``+L -> -L`` and ``-L -> +L``.
    ok : bool
        Both flights ended on the opposite wall (otherwise later entries are ``nan``).
    """

    s0: np.ndarray
    s1: np.ndarray
    s2: np.ndarray
    s3: np.ndarray
    s4: np.ndarray
    tau1: float
    tau2: float
    ok: bool


def impact_map(s0, *, xm, kp, kv, m2=1.0, mu, e, L, w, case="collocated",
               tmax=None) -> ImpactMapResult:
    """Apply ``P = P43 o P32 o P21 o P10`` to one pre-impact section point (scalar).

    Parameters
    ----------
    s0 : array_like, shape (4,)
        ``(phi, z1, z2, z4)`` on ``z3 = +L`` with ``z4 > 0``.
    xm, kp, kv, m2, mu, e, L, w : float
        Reference amplitude and parameters.
    case : {"collocated", "noncollocated"}
    tmax : float, optional
        Horizon of each flight-time search (default ``50 T``).

    Returns
    -------
    ImpactMapResult
    """
    case = _case(case)
    kw = dict(xm=xm, kp=kp, kv=kv, m2=m2, w=w, L=L, case=case)
    s0 = np.asarray(s0, dtype=float)
    nan4 = np.full(4, np.nan)
    s1 = impact_section_map(s0, mu=mu, e=e)
    tau1, hit1 = flight_time(s1, wall=1, tmax=tmax, return_wall=True, **kw)
    if hit1 != -1:
        return ImpactMapResult(s0, s1, nan4, nan4, nan4, tau1, np.nan, False)
    s2 = flight_section_map(s1, tau1, wall=1, **kw)
    s3 = impact_section_map(s2, mu=mu, e=e)
    tau2, hit2 = flight_time(s3, wall=-1, tmax=tmax, return_wall=True, **kw)
    if hit2 != 1:
        return ImpactMapResult(s0, s1, s2, s3, nan4, tau1, tau2, False)
    s4 = flight_section_map(s3, tau2, wall=-1, **kw)
    return ImpactMapResult(s0, s1, s2, s3, s4, tau1, tau2, True)


@dataclass(frozen=True)
class JacobianResult:
    """Jacobian of the impact map and its four blocks (24)-(25), vectorised.

    Attributes
    ----------
    DP : ndarray, shape (..., 4, 4)
        ``DP43 @ DP32 @ DP21 @ DP10`` in coordinates ``(phi, z1, z2, z4)``.
    DP10, DP21, DP32, DP43 : ndarray, shape (..., 4, 4)
        Impact at ``+L``, flight ``+L -> -L``, impact at ``-L``, flight ``-L -> +L``.
    s0, s1, s2, s3, s4 : ndarray, shape (..., 4)
        Section points along the map (``s2``, ``s4`` from the closed-form flow with the given
        flight times; ``phi`` not reduced mod T).
    tau1, tau2 : ndarray
        The flight times used.
    gap2, gap4 : ndarray
        Residuals ``z3 + L`` at ``s2`` and ``z3 - L`` at ``s4`` (zero if the flight times are
        the true ones).
    """

    DP: np.ndarray
    DP10: np.ndarray
    DP21: np.ndarray
    DP32: np.ndarray
    DP43: np.ndarray
    s0: np.ndarray
    s1: np.ndarray
    s2: np.ndarray
    s3: np.ndarray
    s4: np.ndarray
    tau1: np.ndarray
    tau2: np.ndarray
    gap2: np.ndarray
    gap4: np.ndarray

    def eigenvalues(self) -> np.ndarray:
        """Eigenvalues of ``DP`` (Floquet multipliers), shape (..., 4), complex."""
        return np.linalg.eigvals(self.DP)

    def spectral_radius(self) -> np.ndarray:
        """Largest eigenvalue modulus of ``DP``, shape (...)."""
        return np.max(np.abs(self.eigenvalues()), axis=-1)


def map_jacobian(s0, tau1, tau2, *, xm, kp, kv, m2=1.0, mu, e, L, w,
                 case="collocated") -> JacobianResult:
    """``DP`` and its blocks at a general pre-impact section point, given the flight times.

    Parameters
    ----------
    s0 : array_like, shape (..., 4)
        Pre-impact ``(phi, z1, z2, z4)`` on ``z3 = +L`` (``z4 > 0``).
    tau1, tau2 : array_like
        Flight times ``+L -> -L`` and ``-L -> +L`` (e.g. from :func:`impact_map`).
    xm, kp, kv, m2, mu, e, L, w : array_like
        Reference amplitude and parameters; everything broadcasts.
    case : {"collocated", "noncollocated"}

    Returns
    -------
    JacobianResult
    """
    case = _case(case)
    s1 = impact_section_map(s0, mu=mu, e=e)
    F21, s2, g2 = _flight_block_and_map(s1, tau1, xm, kp, kv, m2, w, L, 1.0, case)
    s3 = impact_section_map(s2, mu=mu, e=e)
    F43, s4, g4 = _flight_block_and_map(s3, tau2, xm, kp, kv, m2, w, L, -1.0, case)
    B = impact_block(mu=mu, e=e)
    shape = F21.shape[:-2]
    B = np.broadcast_to(B, shape + (4, 4))
    DP = F43 @ B @ F21 @ B
    s0 = np.broadcast_to(np.asarray(s0, dtype=float), shape + (4,))
    return JacobianResult(DP=DP, DP10=B, DP21=F21, DP32=B, DP43=F43, s0=s0, s1=s1, s2=s2,
                          s3=s3, s4=s4, tau1=np.broadcast_to(np.asarray(tau1, float), shape),
                          tau2=np.broadcast_to(np.asarray(tau2, float), shape), gap2=g2,
                          gap4=g4)


def orbit_jacobian(orbit: SymmetricOrbit) -> JacobianResult:
    """``DP`` and its blocks at the fixed point of a :class:`SymmetricOrbit` (vectorised).

    Both flights last ``tau = n T/2``; the section point is ``orbit.section_point``.
    """
    return map_jacobian(orbit.section_point, orbit.tau, orbit.tau, xm=orbit.xm, kp=orbit.kp,
                        kv=orbit.kv, m2=orbit.m2, mu=orbit.mu, e=orbit.e, L=orbit.L, w=orbit.w,
                        case=orbit.case)
