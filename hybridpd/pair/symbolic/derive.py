"""The SymPy derivations of the closed forms (paper sections 2-4) and the numeric kernels.

Everything here runs only when SymPy is needed: on a cache miss of the generated code (see
:mod:`hybridpd.pair.symbolic._numeric`) or when the SymPy objects themselves are asked for
(:func:`derivation`). The numeric kernels are the lists of expressions :func:`kernel_spec`
names; :func:`kernel_source` turns one into Python source with SymPy's ``lambdify`` (common
subexpressions eliminated). The hash of this file is part of the key of the generated code,
so editing a derivation regenerates it.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

from hybridpd._results import compact_repr
from hybridpd.model import Case
from hybridpd.pair.symbolic.damped import dch, dsh

__all__ = ["KERNELS", "Derivation", "derivation", "kernel_source", "kernel_spec",
           "lambdify_kernel", "sympy_functions"]

_NUMERIC_MODULES = [{"DCh": dch, "DSh": dsh}, "numpy"]

#: Names of the numeric kernels (each exists for both feedback cases).
KERNELS = ("flow", "transition", "gap", "existence", "flight", "flight_out")


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

    class _Damped(sp.Function):
        # what DCh and DSh share: three arguments, a value at t = 0, numeric values, LaTeX
        nargs = 3
        is_real = True

        @classmethod
        def eval(cls, a, D, t):
            if t.is_zero:
                return cls._at_zero
            return None

        def _eval_evalf(self, prec):
            if all(x.is_number for x in self.args):
                return _numeric_value(*self.args, self._which, prec)
            return None

        def _latex(self, printer, exp=None):
            # %-formatting: LaTeX braces would need doubling with str.format / f-strings
            a, D, t = (printer._print(x) for x in self.args)
            s = r"\operatorname{%s}_{%s}\left(%s, %s\right)" % (  # noqa: UP031
                self._which.title(), a, D, t)
            return s if exp is None else r"%s^{%s}" % (s, exp)  # noqa: UP031

    class DCh(_Damped):
        """``exp(-a t) cosh(sqrt(D) t)`` (entire in ``D``); arguments ``(a, D, t)``."""

        nargs = 3
        _at_zero = sp.S.One
        _which = "ch"

        def fdiff(self, argindex=1):
            a, D, t = self.args
            if argindex == 1:
                return -t * self
            if argindex == 2:
                return t / 2 * DSh(a, D, t)
            if argindex == 3:
                return -a * self + D * DSh(a, D, t)
            raise ArgumentIndexError(self, argindex)

        def _eval_rewrite_as_cosh(self, a, D, t, **kwargs):
            return sp.exp(-a * t) * sp.cosh(sp.sqrt(D) * t)

    class DSh(_Damped):
        """``exp(-a t) sinh(sqrt(D) t)/sqrt(D)`` (entire in ``D``); arguments ``(a, D, t)``."""

        nargs = 3
        _at_zero = sp.S.Zero
        _which = "sh"

        def fdiff(self, argindex=1):
            a, D, t = self.args
            if argindex == 1:
                return -t * self
            if argindex == 2:
                return (t * DCh(a, D, t) - self) / (2 * D)
            if argindex == 3:
                return DCh(a, D, t) - a * self
            raise ArgumentIndexError(self, argindex)

        def _eval_rewrite_as_sinh(self, a, D, t, **kwargs):
            return sp.exp(-a * t) * sp.sinh(sp.sqrt(D) * t) / sp.sqrt(D)

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
        sig=sp.Symbol("sigma", real=True))
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

    __repr__ = compact_repr

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
# Numeric kernels: argument lists and expressions
# ----------------------------------------------------------------------------------------


def kernel_spec(name: str, case: str):
    """``(args, exprs, subs)`` of the numeric kernel ``name`` for ``case`` (see :data:`KERNELS`).

    ``flow(t, X0..., kp, kv, m2, w)`` -> the 6 states; ``transition(t, kp, kv, m2, w)`` -> the
    36 entries of ``Phi(t)`` (row major); ``gap(t, X0..., kp, kv, m2, w)`` -> ``z3`` and its
    first three time derivatives; ``existence(kp, kv, m2, mu, e, L, w, x10, n)`` -> ``M00,
    M01, M10, M11, b0, b1``; ``flight(phi, z1, z2, z4, tau, xm, kp, kv, m2, w, L, sig)`` ->
    the 16 block entries, the 4 outputs and the gap; ``flight_out`` (same arguments) -> the 4
    outputs and the gap.
    """
    import sympy as sp

    case = _case(case)
    y = _symbols()
    fd = _flow_derivation(case)
    subs = dict(fd["param_subs"])
    par = [y["kp"], y["kv"], y["m2"], y["w"]]
    if name in ("flow", "gap"):
        return [y["t"], *y["X0"], *par], list(fd[name]), subs
    if name == "transition":
        return [y["t"], *par], list(fd["Phi"]), subs
    if name == "existence":
        ex = _existence_derivation(case)
        kp, kv, m2, mu, e, L, w, x10, n = (y[k] for k in
                                           ("kp", "kv", "m2", "mu", "e", "L", "w", "x10", "n"))
        v = 2 * x10 * w / (n * sp.pi)
        subs.update({y["tau"]: n * sp.pi / w, y["v"]: v, y["x20"]: x10 - L,
                     y["y2m"]: v * (e - 2 * mu - 1) / (1 + e),
                     y["y2p"]: v * (e + 2 * e * mu - 1) / (1 + e)})
        M, b = ex["M"], ex["b"]
        exprs = [M[0, 0], M[0, 1], M[1, 0], M[1, 1], b[0], b[1]]
        return [kp, kv, m2, mu, e, L, w, x10, n], exprs, subs
    if name in ("flight", "flight_out"):
        fl = _flight_derivation(case)
        args = [y["phi"], y["z1"], y["z2"], y["z4"], y["tau"], y["xm"],
                y["kp"], y["kv"], y["m2"], y["w"], y["L"], y["sig"]]
        # block and output together: the common subexpressions (Phi(tau), X(tau)) are shared
        exprs = list(fl["out"]) + [fl["g"]]
        if name == "flight":
            exprs = list(fl["block"]) + exprs
        return args, exprs, subs
    raise ValueError(f"kernel name must be one of {KERNELS}, got {name!r}")


def lambdify_kernel(name: str, case: str):
    """A fresh ``lambdify`` of :func:`kernel_spec` (no cache); the function returns a list."""
    import sympy as sp

    args, exprs, subs = kernel_spec(name, case)
    exprs = [sp.sympify(ex).xreplace(subs) for ex in exprs]
    return sp.lambdify(args, exprs, modules=_NUMERIC_MODULES, cse=True)


def kernel_source(name: str, case: str, func_name: str = "kernel") -> str:
    """Self-contained Python source defining ``func_name``, the kernel :func:`lambdify_kernel`.

    The source imports what it uses from NumPy and ``DCh``/``DSh`` from
    :mod:`hybridpd.pair.symbolic.damped`; ``RuntimeError`` if the generated code refers to
    anything else.
    """
    import inspect

    import numpy as np

    f = lambdify_kernel(name, case)
    src = inspect.getsource(f)
    head, rest = src.split("(", 1)
    if not head.startswith("def "):
        raise RuntimeError(f"unexpected lambdify output for {name}/{case}: {head!r}")
    from_numpy = set()
    for ident in f.__code__.co_names:
        if ident not in f.__globals__ or ident in ("DCh", "DSh"):
            continue  # attribute names, and our own functions imported below
        obj = f.__globals__[ident]
        if getattr(np, ident, None) is not obj:
            raise RuntimeError(f"generated code of {name}/{case} uses {ident!r} ({obj!r})")
        from_numpy.add(ident)
    lines = ["from hybridpd.pair.symbolic.damped import dch as DCh",
             "from hybridpd.pair.symbolic.damped import dsh as DSh"]
    if from_numpy:
        lines.insert(0, f"from numpy import {', '.join(sorted(from_numpy))}")
    return "\n".join(lines) + "\n\n\n" + f"def {func_name}(" + rest
