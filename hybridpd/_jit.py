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

Compiled code is cached once per installation: kernels declared with ``cache=True`` keep
numba's machine code in a per-user directory keyed by the versions of hybridpd, numba and
Python and a stamp of the package's kernel source files (:func:`numba_cache_dir`:
``$HYBRIDPD_NUMBA_CACHE_DIR`` if set, else ``numba-<versions>-<stamp>`` under
``$XDG_CACHE_HOME/hybridpd`` or ``~/.cache/hybridpd``), so a fresh
process on a machine that has run hybridpd before loads it instead of compiling. Compiled
code is only ever loaded from a directory owned by the current user and writable by no one
else (checked for the directory and its parent); otherwise the kernels compile in memory for
the process. A kernel whose cache entry is missing logs once (logger ``hybridpd``, level
INFO, and a WARNING the very first time, when the cache directory is new) that it compiles.
"""
from __future__ import annotations

import contextvars
import functools
import logging
import os
import sys
import time
from pathlib import Path

__all__ = ["Kernel", "njit", "numba_cache_dir"]

_LOG = logging.getLogger("hybridpd")

#: True while an interpreted kernel runs: nested kernel calls then interpret as well.
_INTERPRETING = contextvars.ContextVar("hybridpd_interpreting", default=False)


@functools.cache
def _interpret_budget() -> float:
    raw = os.environ.get("HYBRIDPD_INTERPRET_SECONDS", "0.5")
    try:
        v = float(raw)
    except ValueError:
        raise ValueError(
            f"HYBRIDPD_INTERPRET_SECONDS must be a number of seconds >= 0, got {raw!r}") from None
    return max(0.0, v)  # nan and negatives: always compile


def _private(d: Path) -> bool:
    """``d`` is a directory owned by this user and writable by no one else."""
    try:
        st = d.stat()
    except OSError:
        return False
    if not hasattr(os, "getuid"):  # pragma: no cover (not POSIX: rely on the user profile)
        return d.is_dir()
    return d.is_dir() and st.st_uid == os.getuid() and not st.st_mode & 0o022


@functools.cache
def numba_cache_dir() -> Path | None:
    """The private directory of numba's compiled code for this version, or ``None``.

    Created (mode 0700) if needed; ``None`` when it cannot be created or is not private
    (owned by this user and writable by no one else, in a parent that is private too or
    sticky): the kernels then compile in memory.
    """
    # deferred import: loaded only when this runs, for start-up time
    import numba

    from hybridpd._version import __version__

    key = (f"numba-{__version__}-nb{numba.__version__}-py{sys.version_info[0]}"
           f"{sys.version_info[1]}-{_source_stamp()}")
    env = os.environ.get("HYBRIDPD_NUMBA_CACHE_DIR")
    if env:
        d = Path(env).expanduser()
    else:
        xdg = os.environ.get("XDG_CACHE_HOME")
        d = (Path(xdg).expanduser() if xdg else Path.home() / ".cache") / "hybridpd" / key
    try:
        d.mkdir(mode=0o700, parents=True, exist_ok=True)
    except OSError:
        return None
    # in a shared parent only its sticky bit stops others from replacing our directory
    parent_ok = _private(d.parent) or bool(d.parent.stat().st_mode & 0o1000)
    if not (_private(d) and parent_ok):
        _LOG.warning("hybridpd: %s is not private to this user; numba kernels are compiled in "
                     "memory, not cached", d)
        return None
    return d


def _source_stamp() -> str:
    """Short hash of the package's kernel sources (paths, sizes, modification times).

    numba checks only a kernel's own file when it loads cached code, not the files of the
    kernels it calls; keying the directory by every file that defines kernels means an
    edited or upgraded installation never runs stale compiled callees.
    """
    import hashlib

    root = str(Path(__file__).resolve().parent)
    h = hashlib.sha256(root.encode())
    entries = []
    for d, subdirs, files in os.walk(root):
        subdirs[:] = [s for s in subdirs if s != "__pycache__"]
        for f in files:
            if f.endswith(".py"):
                path = os.path.join(d, f)
                try:
                    st = os.stat(path)
                    with open(path, "rb") as fh:
                        if b"njit" not in fh.read():
                            continue         # no kernel: its edits cannot stale compiled code
                except OSError:
                    continue
                entries.append(f"{os.path.relpath(os.path.join(d, f), root)}:{st.st_size}:"
                               f"{st.st_mtime_ns};")
    for e in sorted(entries):
        h.update(e.encode())
    return h.hexdigest()[:12]


def _announce(dispatcher, name) -> None:
    """Log that ``name`` compiles when its cache index is missing (the first run ever)."""
    cache_file = getattr(getattr(dispatcher, "_cache", None), "_cache_file", None)
    index = getattr(cache_file, "_index_path", None)
    if index is None or os.path.exists(index):
        return
    if not _announce.done:
        _announce.done = True
        _LOG.warning("hybridpd: compiling the numba kernels (once per installation; cached "
                     "in %s)", numba_cache_dir())
    else:
        _LOG.info("hybridpd: compiling %s", name)


_announce.done = False


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
            opts = dict(self.options)
            where = numba_cache_dir() if opts.get("cache") else None
            if where is None:
                opts.pop("cache", None)
                self._dispatcher = numba.njit(**opts)(self.py_func)
            else:
                # numba reads its cache location when the dispatcher is made: point it at
                # the private directory for this one call only
                saved = numba.config.CACHE_DIR
                numba.config.CACHE_DIR = str(where)
                try:
                    self._dispatcher = numba.njit(**opts)(self.py_func)
                finally:
                    numba.config.CACHE_DIR = saved
                _announce(self._dispatcher, self.__qualname__)
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
