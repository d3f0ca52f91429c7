"""The self-test of NumPy's elementary functions that certification runs before it proves anything.

The interval layer (:mod:`hybridpd.pair.intervals`) widens every value of NumPy's ``exp``,
``expm1``, ``cosh``, ``sinh`` by a relative error of :data:`~hybridpd.pair.intervals.LIBM_BOUND`
(``2^-44``), of ``sin`` and ``cos`` by that much absolutely, and takes ``sqrt`` as correctly
rounded (as IEEE 754 requires; the widening of every operation covers one unit in the last
place). NumPy documents no error bound for its elementary functions, and its SIMD routines
change with the version and the CPU (``sin``/``cos`` have had regressions of 2 units in the
last place and more), so the assumption is checked on the machine that certifies:

* every function is evaluated on a fixed set of hard arguments (:func:`hard_arguments`:
  arguments of ``sin``, ``cos`` next to multiples of ``pi/2``, small and up to ``1e22`` and
  the worst case of argument reduction near ``5.3e255``; tiny arguments; arguments near the
  overflow and underflow thresholds; ``sqrt`` near 1 and of subnormals), by every path the
  interval layer may take (one contiguous array, a strided view, element by element);
* each value is compared with python-flint's ``arb`` at 256 bits, and its error with the
  assumed bound (relative plus ``2^-1023`` for the relative ones, whose widening has an
  absolute ``2^-1022`` term; absolute for ``sin``, ``cos``; ``2^-52`` relative for ``sqrt``).

The check runs once per process, lazily, the first time certification needs it
(:func:`hybridpd.pair.proofs.classify`; :func:`libm_check` caches its report), and takes a few
hundredths of a second. If any error exceeds its bound, :func:`require_libm` raises
:class:`LibmSelfTestError` naming the function, the argument and the error: certification
refuses to run rather than prove anything from a wrong enclosure.

Examples
--------
>>> from hybridpd.pair.selftest import libm_check
>>> r = libm_check()
>>> r.ok, sorted(r.worst)[:3]
(True, ['cos', 'cosh', 'exp'])
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.pair.intervals import LIBM_BOUND

__all__ = ["FUNCTIONS", "LibmCheck", "LibmSelfTestError", "hard_arguments", "libm_check",
           "require_libm"]

_PREC = 256
_SUBNORMAL_SLACK = 2.0**-1023   # half the absolute term of the outward step


class LibmSelfTestError(RuntimeError):
    """NumPy's elementary functions miss the error bound the interval layer assumes."""


def _near_multiples_of_half_pi(ks):
    """The floats nearest to ``k pi / 2`` and their two neighbours, for each ``k``."""
    from flint import arb, ctx

    out = []
    with ctx.workprec(_PREC):
        for k in ks:
            x = float((arb.pi() * k / 2).mid())
            out += [math.nextafter(x, -math.inf), x, math.nextafter(x, math.inf)]
    return out


_TRIG_SPECIAL = (0.0, 5e-324, 1e-300, 1e-20, 1e-8, 1e-4, 0.5, 0.7853981633974483, 1.0, 2.0,
                 3.0, 10.0, 100.0, 1e4, 1e6, 2.0**30, 2.0**52, 1e22, 2.0**100,
                 6381956970095103 * 2.0**797,  # the hardest case of argument reduction
                 5.319372648326541e255, 1.0e300, float(np.finfo(float).max))
_TRIG_K = tuple(range(1, 33)) + (100, 1000, 10**5, 10**6, 10**9, 10**12, 10**15)

_ARGUMENTS = {
    "exp": (0.0, 5e-324, 1e-300, 1e-17, -1e-17, 1e-8, 0.5, 1.0, -1.0, 2.0, 10.0, -10.0, 37.5,
            100.0, -100.0, 700.0, 709.78, -700.0, -708.39, -740.0, -745.0, 0.6931471805599453,
            1e-3, 20.0, -20.0),
    "expm1": (5e-324, 1e-300, -1e-300, 1e-17, -1e-17, 1e-10, -1e-10, 1e-5, -1e-5, 0.1, -0.1,
              0.5, -0.5, 1.0, -1.0, 2.0, -2.0, 2.5, -2.5, 10.0, -10.0, 40.0, -40.0, 700.0,
              709.78, -745.0),
    "cosh": (0.0, 1e-300, 1e-8, 0.5, 1.0, 1.5, 2.0, 5.0, 20.0, 36.0, 100.0, 500.0, 700.0,
             710.4, -1.0, -20.0, -710.4),
    "sinh": (5e-324, 1e-300, 1e-17, 1e-8, 1e-4, 0.1, 0.5, 1.0, 1.5, 2.0, 5.0, 20.0, 36.0,
             100.0, 500.0, 700.0, 710.4, -1e-300, -1e-8, -1.0, -20.0, -710.4),
    "sqrt": (0.0, 5e-324, 1e-310, 2.2250738585072014e-308, 1e-300, 0.5, 1.0 - 2.0**-53, 1.0,
             1.0 + 2.0**-52, 2.0, 3.0, 5.0, 10.0, 1e10, 2.0**52 + 1, 1e300,
             float(np.finfo(float).max)),
}


def hard_arguments(name) -> tuple:
    """The fixed arguments of the self-test of the function ``name`` (see the module).

    For ``sin`` and ``cos``: the floats nearest to ``k pi/2`` (``k = 1..32`` and up to
    ``1e15``) and their neighbours, and special values up to the largest float, both signs.
    """
    if name in ("sin", "cos"):
        xs = _near_multiples_of_half_pi(_TRIG_K)
        return tuple(xs + list(_TRIG_SPECIAL) + [-x for x in _TRIG_SPECIAL[1:]]
                     + [-x for x in xs[::7]])
    return _ARGUMENTS[name]


#: ``name -> (NumPy function, kind of bound, bound)``: every function the layer uses.
FUNCTIONS = {
    "exp": (np.exp, "relative", LIBM_BOUND),
    "expm1": (np.expm1, "relative", LIBM_BOUND),
    "cosh": (np.cosh, "relative", LIBM_BOUND),
    "sinh": (np.sinh, "relative", LIBM_BOUND),
    "sin": (np.sin, "absolute", LIBM_BOUND),
    "cos": (np.cos, "absolute", LIBM_BOUND),
    "sqrt": (np.sqrt, "relative", 2.0**-52),
}


def _evaluate(name, args):
    """NumPy's values of ``name`` at ``args`` by each path: contiguous, strided, one by one.

    Returns
    -------
    list of ndarray
        One array of values per path, each in the order of ``args``.
    """
    fn = FUNCTIONS[name][0]
    a = np.ascontiguousarray(args, dtype=float)
    wide = np.repeat(a, 2)[::2]     # a strided view (no SIMD fast path)
    with np.errstate(all="ignore"):
        return [fn(a), fn(wide), np.array([fn(np.float64(v)) for v in a])]


@dataclass(frozen=True)
class LibmCheck:
    """The report of the self-test (:func:`libm_check`).

    Attributes
    ----------
    ok : bool
        Every value within its bound.
    worst : dict
        ``name -> (argument, error, used, kind)``: where each function comes nearest to its
        bound, its error there (absolute or relative, as ``kind`` says) and the share of the
        bound it uses (``> 1``: beyond; the relative bounds include the absolute
        ``2^-1023`` of subnormal results).
    failures : tuple of str
        One line per function beyond its bound.
    """

    __repr__ = compact_repr

    ok: bool
    worst: dict
    failures: tuple

    def message(self) -> str:
        """Why certification refuses to run (empty when :attr:`ok`)."""
        if self.ok:
            return ""
        return ("certification refused: NumPy's elementary functions miss the error bound "
                "the interval layer assumes (hybridpd.pair.selftest): "
                + "; ".join(self.failures))


def _error(name, x, y, kind, bound):
    """The error of the value ``y`` of ``name`` at ``x`` (a float) and whether it is within."""
    from flint import arb

    if not math.isfinite(y):
        return math.inf, math.inf, False
    ref = _FLINT[name](arb(x))
    err = abs(arb(y) - ref)
    allowed = arb(bound)
    if kind == "relative":
        allowed = allowed * abs(ref) + arb(_SUBNORMAL_SLACK)
    size = err / abs(ref) if kind == "relative" and ref != 0 else err
    return float(size.mid()), float((err / allowed).mid()), bool(err <= allowed)


_FLINT = {"exp": lambda x: x.exp(), "expm1": lambda x: x.expm1(), "cosh": lambda x: x.cosh(),
          "sinh": lambda x: x.sinh(), "sin": lambda x: x.sin(), "cos": lambda x: x.cos(),
          "sqrt": lambda x: x.sqrt()}


@functools.lru_cache(maxsize=1)
def libm_check() -> LibmCheck:
    """Run the self-test (once per process: the report is cached) and report.

    Returns
    -------
    LibmCheck
    """
    from flint import ctx

    worst, failures = {}, []
    with ctx.workprec(_PREC):
        for name, (_, kind, bound) in FUNCTIONS.items():
            args = hard_arguments(name)
            top, first_bad = (math.nan, math.nan, -1.0), None
            for values in _evaluate(name, args):
                for x, y in zip(args, np.asarray(values, dtype=float).ravel()):
                    size, used, ok = _error(name, x, float(y), kind, bound)
                    if used > top[2]:
                        top = (x, size, used)
                    if not ok and first_bad is None:
                        first_bad = (x, float(y), size)
            worst[name] = (top[0], top[1], top[2], kind)
            if first_bad is not None:
                x, y, size = first_bad
                failures.append(f"{name}({x!r}) = {y!r}: {kind} error {size:.3g} exceeds the "
                                f"assumed {bound:.3g}")
    return LibmCheck(not failures, worst, tuple(failures))


def require_libm() -> None:
    """Raise :class:`LibmSelfTestError` unless the self-test (:func:`libm_check`) passed.

    Raises
    ------
    LibmSelfTestError
        Naming each function beyond its bound, the argument and the error.
    """
    r = libm_check()
    if not r.ok:
        raise LibmSelfTestError(r.message())
