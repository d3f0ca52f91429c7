"""Lazily compiled kernels: numba is imported only when a kernel is compiled.

``from hybridpd._jit import njit`` replaces ``from numba import njit`` in the package. The
decorator returns a :class:`Kernel`; calling it compiles the function with numba on first
use (loading numba's on-disk cache when there is one), exactly as ``numba.njit`` would.
Compiled kernels call each other as numba dispatchers.

Why: importing numba and loading even cached kernels costs about half a second per process
(numba initialises its whole CPU target on the first dispatch). A single symmetric orbit or
a short simulation needs a few milliseconds of kernel work, so for them the plain Python
function is faster than the compiler's start-up. :meth:`Kernel.interpret` runs the Python
function (nested kernel calls are interpreted too, unless already compiled in this process),
and :meth:`Kernel.prefer_interpreter` says whether that is the better choice: the kernel is
not compiled yet and the time already spent interpreting it is below a budget (the
"ski rental" rule: at most about twice the cost of the better choice made in hindsight).
Callers with a known small amount of work use ``kernel.interpret`` when
``prefer_interpreter()`` says so; every other call compiles.

The budget is ``HYBRIDPD_INTERPRET_SECONDS`` (default 0.5 s per kernel; ``0`` always
compiles). Interpreted and compiled kernels run the same code in IEEE double precision; they
may differ in the last bits where NumPy's and the C library's elementary functions differ.
"""
from __future__ import annotations

import contextvars
import functools
import os
import time

__all__ = ["Kernel", "njit"]

#: True while an interpreted kernel runs: nested kernel calls then interpret as well.
_INTERPRETING = contextvars.ContextVar("hybridpd_interpreting", default=False)


@functools.cache
def _interpret_budget() -> float:
    raw = os.environ.get("HYBRIDPD_INTERPRET_SECONDS", "0.5")
    try:
        v = float(raw)
    except ValueError:
        raise ValueError(
            f"HYBRIDPD_INTERPRET_SECONDS must be a number of seconds >= 0, got {raw!r}"
        ) from None
    return max(0.0, v)  # nan and negatives: always compile


@functools.cache
def _register_numba_type() -> None:
    """Let numba type a :class:`Kernel` found in a global as its dispatcher."""
    from numba.core import types
    from numba.extending import typeof_impl

    @typeof_impl.register(Kernel)
    def _typeof_kernel(val, c):
        return types.Dispatcher(val.dispatcher)


class Kernel:
    """A function that numba compiles on first compiled call (see the module docstring).

    Attributes
    ----------
    py_func : callable
        The Python function.
    options : dict
        Keyword arguments for ``numba.njit``.
    interpreted_seconds : float
        Time spent in :meth:`interpret` so far (this process).
    """

    def __init__(self, func, options):
        self.py_func = func
        self.options = dict(options)
        self.interpreted_seconds = 0.0
        self._dispatcher = None
        functools.update_wrapper(self, func)

    def __repr__(self) -> str:
        state = "compiled" if self._dispatcher is not None else "not compiled"
        return f"<Kernel {self.__qualname__} ({state})>"

    @property
    def compiled(self) -> bool:
        """Whether the numba dispatcher exists in this process."""
        return self._dispatcher is not None

    @property
    def dispatcher(self):
        """The numba dispatcher (imports numba and creates it on first access)."""
        if self._dispatcher is None:
            import numba

            _register_numba_type()
            self._dispatcher = numba.njit(**self.options)(self.py_func)
        return self._dispatcher

    def __call__(self, *args, **kwargs):
        d = self._dispatcher
        if d is not None:
            return d(*args, **kwargs)
        if _INTERPRETING.get():
            return self.py_func(*args, **kwargs)
        return self.dispatcher(*args, **kwargs)

    def __reduce__(self):
        # pickled by reference (the module attribute), like a plain function
        return _import_kernel, (self.__module__, self.__qualname__)

    def prefer_interpreter(self) -> bool:
        """True when interpreting a small call beats compiling (see the module docstring)."""
        return self._dispatcher is None and self.interpreted_seconds < _interpret_budget()

    def interpret(self, *args, **kwargs):
        """Run the Python function; nested kernels not yet compiled are interpreted too."""
        token = _INTERPRETING.set(True)
        t0 = time.perf_counter()
        try:
            return self.py_func(*args, **kwargs)
        finally:
            self.interpreted_seconds += time.perf_counter() - t0
            _INTERPRETING.reset(token)

    def call(self, small: bool, *args, **kwargs):
        """``interpret`` when ``small`` and :meth:`prefer_interpreter`, else the compiled call."""
        if small and self.prefer_interpreter():
            return self.interpret(*args, **kwargs)
        return self(*args, **kwargs)


def _import_kernel(module: str, qualname: str) -> Kernel:
    import importlib

    obj = importlib.import_module(module)
    for part in qualname.split("."):
        obj = getattr(obj, part)
    return obj


def njit(*args, **options):
    """Drop-in for ``numba.njit`` (with or without options) returning a lazy :class:`Kernel`."""
    if args and callable(args[0]) and not options:
        return Kernel(args[0], {})
    if args:
        raise ValueError("njit takes the function or keyword options only")
    return lambda func: Kernel(func, options)
