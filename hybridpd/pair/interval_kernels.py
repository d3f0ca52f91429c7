"""The symmetric orbit's closed forms as backend-neutral code, for interval and ball arithmetic.

The certified classification (:mod:`hybridpd.pair.certified`) evaluates the paper's closed
forms of the simple symmetric orbit, (13)-(16) and the Jacobian blocks of (24)-(26), in
interval arithmetic. This module derives the expressions it needs from the SymPy derivations
of :mod:`hybridpd.pair.symbolic.derive` and prints them as Python source whose every
operation goes through an *arithmetic backend* (``ops``), so the same generated code runs on
floats, on the outward-rounded intervals and centred forms of :mod:`hybridpd.pair.intervals`,
and on python-flint's ``arb`` balls. The source is cached like the package's other generated
code (:mod:`hybridpd._codecache`; the key hashes hybridpd's and SymPy's versions and the
source of this module and of ``derive.py``), so SymPy is imported only on a cache miss.

Scaled parameters
-----------------
With ``mu`` fixed only ``kp/m2`` and ``kv/m2`` matter, and of the lengths only
``gamma = L/x10`` (CONVENTIONS.md). The kernels therefore take ``kpt = kp/m2``,
``kvt = kv/m2``, ``mu``, ``e``, ``gam = gamma``, ``w = omega`` and the odd order ``n``, with
``x10 = 1`` and ``m2 = 1``; lengths scale with ``x10`` and velocities with ``x10``.

Kernels (all per feedback case)
-------------------------------
``existence(kpt, kvt, mu, e, gam, w, n) -> [C, S, det]``
    The solution of the linear system ``M [C, S]^T = b`` of (13)-(14) by Cramer's rule,
    ``C = xm cos(w phi0)``, ``S = xm sin(w phi0)``, and ``det M``.
``gap(s, C, S, kpt, kvt, mu, e, gam, w, n) -> [z3, z3', z3'']``
    The gap ``z3 = x1 - x2`` and its first two time derivatives on the flight after the
    ``+L`` impact, at the normalised time ``s`` (``t = s tau``, ``tau = n pi / w``; ``s`` in
    ``[0, 1]`` covers the flight), from the post-impact state ``(1, -v, 1 - gam, y21, C, S)``.
``halfmap(C, S, kpt, kvt, mu, e, gam, w, n) -> 16 entries of M, row major``
    ``M = diag(1, -1, -1, -1) DP21 DP10`` at the fixed point: the Jacobian of the half map
    (impact at ``+L``, flight to ``-L``, then the symmetry ``(phi, z) -> (phi + n T/2, -z)``),
    with ``DP = M^2`` (see :func:`halfmap_exprs`).

Backends
--------
The generated function is ``kernel(ops, *args)``; ``ops`` provides ``Q(p, q)`` (the rational
``p/q``), ``PI``, ``POW(x, k)`` (``k >= 2``), ``SQRT``, ``EXP``, ``SIN``, ``COS``, the
package's damped functions ``DCH(a, D, t) = exp(-a t) cosh(sqrt(D) t)`` and
``DSH(a, D, t) = exp(-a t) sinh(sqrt(D) t) / sqrt(D)`` (entire in ``D``), and Python's
``+ - * /`` on its numbers (integers appear as Python ``int`` operands).
"""
from __future__ import annotations

import functools
import hashlib
from pathlib import Path

from hybridpd import _codecache
from hybridpd._version import __version__
from hybridpd.model import Case

__all__ = ["KERNEL_ARGS", "existence_exprs", "gap_exprs", "halfmap_exprs", "interval_kernel",
           "interval_kernel_source"]

#: Argument names of each kernel (after the backend ``ops``).
KERNEL_ARGS = {
    "existence": ("kpt", "kvt", "mu", "e", "gam", "w", "n"),
    "gap": ("s", "C", "S", "kpt", "kvt", "mu", "e", "gam", "w", "n"),
    "halfmap": ("C", "S", "kpt", "kvt", "mu", "e", "gam", "w", "n"),
}

_SOURCES = (Path(__file__), Path(__file__).with_name("symbolic") / "derive.py")


@functools.cache
def _syms():
    """The SymPy symbols of the scaled kernels, by argument name."""
    import sympy as sp

    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.symbolic.derive import _symbols

    y = _symbols()
    return {"s": sp.Symbol("s", nonnegative=True), "C": y["C"], "S": y["S"],
            "kpt": sp.Symbol("kpt", positive=True), "kvt": sp.Symbol("kvt", positive=True),
            "mu": y["mu"], "e": y["e"], "gam": sp.Symbol("gam", positive=True), "w": y["w"],
            "n": y["n"]}


def _scaling(case: str) -> dict:
    """Substitutions to the scaled parameters (``alpha``, ``D``, ``kp``, ``kv``, ``m2``,
    ``L``, ``x10``) and the orbit's velocities (``tau``, ``v``, ``x20``, ``y20``, ``y21``)."""
    import sympy as sp

    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.symbolic.derive import _symbols

    y, z = _symbols(), _syms()
    kpt, kvt, mu, e, gam, w, n = (z[k] for k in ("kpt", "kvt", "mu", "e", "gam", "w", "n"))
    v = 2 * w / (n * sp.pi)
    return {y["alpha"]: kvt / 2, y["D"]: kvt**2 / 4 - kpt, y["kp"]: kpt, y["kv"]: kvt,
            y["m2"]: sp.S.One, y["L"]: gam, y["x10"]: sp.S.One, y["tau"]: sp.pi * n / w,
            y["v"]: v, y["x20"]: 1 - gam, y["y2m"]: v * (e - 2 * mu - 1) / (1 + e),
            y["y2p"]: v * (e + 2 * e * mu - 1) / (1 + e)}


def _check_free(exprs, name):
    allowed = set(_syms().values())
    for ex in exprs:
        extra = ex.free_symbols - allowed
        if extra:
            raise RuntimeError(f"kernel {name}: unexpected symbols {sorted(map(str, extra))}")
    return exprs


def existence_exprs(case: str):
    """``[C, S, det]`` of (13)-(14) in the scaled parameters (SymPy expressions)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.symbolic.derive import _existence_derivation

    ex = _existence_derivation(case)
    sub = _scaling(case)
    # alpha and D first (they contain kp, kv), then everything else
    first = {k: v for k, v in sub.items() if str(k) in ("alpha", "D")}
    rest = {k: v for k, v in sub.items() if k not in first}
    out = [ex[k].xreplace(first).xreplace(rest) for k in ("C", "S", "det")]
    return _check_free(out, "existence")


def gap_exprs(case: str):
    """``[z3, z3', z3'']`` after the ``+L`` impact at ``t = s n pi / w`` (SymPy)."""
    import sympy as sp

    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.symbolic.derive import _flow_derivation, _symbols

    y, z = _symbols(), _syms()
    fd = _flow_derivation(case)
    sub = _scaling(case)
    v, y2p = sub[y["v"]], sub[y["y2p"]]
    X0 = dict(zip(y["X0"], [sp.S.One, -v, 1 - z["gam"], y2p, z["C"], z["S"]]))
    t = z["s"] * sp.pi * z["n"] / z["w"]
    first = {k: val for k, val in sub.items() if str(k) in ("alpha", "D")}
    rest = {k: val for k, val in sub.items() if k not in first}
    out = [g.xreplace(first).xreplace(rest).xreplace(X0).subs(y["t"], t) for g in fd["gap"][:3]]
    return _check_free(out, "gap")


def halfmap_exprs(case: str):
    """The 16 entries of ``M = diag(1, -1, -1, -1) DP21 DP10`` at the fixed point (SymPy).

    ``DP21 = Fs - Ftau Gs / Gtau`` is the flight block (26) from the post-impact point
    ``(phi0, 1 - gam, y21, -e z4-)`` on ``+L``; ``DP10`` the impact block. The state at the
    end of the flight is *the exact mirror* of the pre-impact state at ``+L``,
    ``(-1, -v, -(1 - gam), -y20, -C, -S)``, by (13)-(14) and the symmetry, and is written in
    that form (so ``Gtau = z4(tau) = -(v - y20)`` exactly), which is valid wherever ``C, S``
    solve (13)-(14). The symmetry ``R: (phi, z) -> (phi + n T/2, -z)`` conjugates the two
    halves of the impact map, ``P43 o P32 = R o P21 o P10 o R^-1``, so ``DP = (S DP21 DP10)^2``
    with ``S = DR = diag(1, -1, -1, -1)``.
    """
    import sympy as sp

    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.symbolic.derive import (
        _flow_derivation,
        _impact_block_derivation,
        _symbols,
    )

    y, z = _symbols(), _syms()
    fd = _flow_derivation(case)
    sub = _scaling(case)
    v, y2m = sub[y["v"]], sub[y["y2m"]]
    gam, w, C, S = z["gam"], z["w"], z["C"], z["S"]
    tau = y["tau"]
    Phi = fd["Phi"].subs(y["t"], tau).subs({sp.cos(w * tau): -1, sp.sin(w * tau): 0})
    z1 = 1 - gam
    # d X0 / d(phi, z1, z2, z4) with X0 = (z1 + L, z2 + z4, z1, z2, xm cos w phi, xm sin w phi)
    J = sp.Matrix([[0, 1, 0, 0], [0, 0, 1, 1], [0, 1, 0, 0], [0, 0, 1, 0],
                   [-w * S, 0, 0, 0], [w * C, 0, 0, 0]])
    Xtau = sp.Matrix([-1, -v, -z1, -y2m, -C, -S])
    A = fd["A"]
    PJ = Phi * J
    AX = A * Xtau
    Mz = sp.Matrix([[0, 0, 1, 0, 0, 0], [0, 0, 0, 1, 0, 0], [0, 1, 0, -1, 0, 0]])
    c = sp.Matrix([[1, 0, -1, 0, 0, 0]])
    Fs = sp.Matrix.vstack(sp.Matrix([[1, 0, 0, 0]]), Mz * PJ)
    Ftau = sp.Matrix.vstack(sp.Matrix([[1]]), Mz * AX)
    Gs = c * PJ
    Gtau = (c * AX)[0]
    F = Fs - Ftau * Gs / Gtau
    B = _impact_block_derivation()
    M = sp.diag(1, -1, -1, -1) * F * B
    first = {k: val for k, val in sub.items() if str(k) in ("alpha", "D")}
    rest = {k: val for k, val in sub.items() if k not in first}
    # the post-impact section point enters the flight block only through z1 (the state at
    # tau is the mirror point) and the impact block B is constant
    out = [sp.sympify(m).xreplace(first).xreplace(rest) for m in M]
    return _check_free(out, "halfmap")


_EXPRS = {"existence": existence_exprs, "gap": gap_exprs, "halfmap": halfmap_exprs}


# ----------------------------------------------------------------------------------------
# Printing
# ----------------------------------------------------------------------------------------


class _Printer:
    """Python source of a SymPy expression whose operations go through the backend names."""

    def __init__(self, names):
        self.names = names  # Symbol -> Python identifier

    def __call__(self, ex) -> str:
        import sympy as sp

        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.pair.symbolic.derive import sympy_functions

        DCh, DSh = sympy_functions()
        if ex in self.names:
            return self.names[ex]
        if ex is sp.pi:
            return "PI"
        if isinstance(ex, sp.Integer):
            return f"({int(ex)})"
        if isinstance(ex, sp.Rational):
            return f"Q({int(ex.p)}, {int(ex.q)})"
        if isinstance(ex, sp.Add):
            return "(" + " + ".join(self(a) for a in ex.args) + ")"
        if isinstance(ex, sp.Mul):
            return self._mul(ex)
        if isinstance(ex, sp.Pow):
            b, k = ex.args
            if k == sp.S.Half:
                return f"SQRT({self(b)})"
            if k.is_Integer and k >= 2:
                return f"POW({self(b)}, {int(k)})"
            if k.is_Integer and k <= -1:
                return f"(1 / {self(b ** -k)})"
            raise RuntimeError(f"cannot print the power {ex}")
        for fn, name in ((sp.exp, "EXP"), (sp.sin, "SIN"), (sp.cos, "COS")):
            if isinstance(ex, fn):
                return f"{name}({self(ex.args[0])})"
        if isinstance(ex, (DCh, DSh)):
            a, D, t = (self(x) for x in ex.args)
            return f"{'DCH' if isinstance(ex, DCh) else 'DSH'}({a}, {D}, {t})"
        raise RuntimeError(f"cannot print {type(ex).__name__}: {ex}")

    def _mul(self, ex) -> str:
        import sympy as sp

        num, den = [], []
        sign = ""
        for a in ex.args:
            if a == -1:
                sign = "-"
            elif isinstance(a, sp.Pow) and a.args[1].is_Integer and a.args[1] < 0:
                den.append(a.args[0] ** -a.args[1])
            elif isinstance(a, sp.Rational) and not isinstance(a, sp.Integer) and a.p == 1:
                den.append(sp.Integer(a.q))
            else:
                num.append(a)
        top = " * ".join(self(a) for a in num) if num else "(1)"
        if den:
            top = f"{top} / ({' * '.join(self(a) for a in den)})"
        return f"({sign}{top})"


def _generate(name: str, case: str) -> str:
    import sympy as sp

    exprs = _EXPRS[name](case)
    args = KERNEL_ARGS[name]
    syms = _syms()
    names = {syms[a]: a for a in args}
    reps, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("x"))
    lines = [f"def kernel(ops, {', '.join(args)}):"]
    for fn in ("Q", "PI", "POW", "SQRT", "EXP", "SIN", "COS", "DCH", "DSH"):
        lines.append(f"    {fn} = ops.{fn}")
    pr = _Printer(names)
    for sym, ex in reps:
        lines.append(f"    {sym} = {pr(ex)}")
        names[sym] = str(sym)
    lines.append("    return [")
    lines.extend(f"        {pr(ex)}," for ex in reduced)
    lines.append("    ]")
    return "\n".join(lines) + "\n"


def interval_kernel_source(name: str, case="collocated") -> str:
    """Python source of the kernel ``name`` (see the module docstring) for ``case``."""
    if name not in KERNEL_ARGS:
        raise ValueError(f"name must be one of {tuple(KERNEL_ARGS)}, got {name!r}")
    return _generate(name, Case.parse(case).value)


@functools.cache
def _key() -> str:
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.symbolic._numeric import sympy_version

    srcs = [hashlib.sha256(p.read_bytes()).hexdigest() for p in _SOURCES]
    return _codecache.make_key("hybridpd", __version__, "sympy", sympy_version(),
                               "interval_kernels", *srcs)


@functools.cache
def interval_kernel(name: str, case: str):
    """The cached kernel ``name`` for ``case`` (``"collocated"``/``"noncollocated"``).

    Returns
    -------
    callable
        ``kernel(ops, *args)`` with the arguments :data:`KERNEL_ARGS` ``[name]``; returns a
        list of backend numbers.

    Examples
    --------
    >>> from hybridpd.pair.interval_kernels import interval_kernel
    >>> from hybridpd.pair.flowintervals import FLOAT_OPS
    >>> C, S, det = interval_kernel("existence", "collocated")(FLOAT_OPS, 10.0, 20.0, 0.1, 0.5,
    ...                                               0.75, 5.0, 1)
    >>> round((C * C + S * S) ** 0.5, 6)    # xm of the paper's collocated orbit
    0.398584
    """
    if name not in KERNEL_ARGS:
        raise ValueError(f"name must be one of {tuple(KERNEL_ARGS)}, got {name!r}")
    case = Case.parse(case).value
    ns = _codecache.load(f"interval_kernels.{name}.{case}", _key(),
                         lambda: _generate(name, case))
    return ns["kernel"]
