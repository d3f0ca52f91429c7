"""The numeric closed-form kernels, loaded from the generated-code cache.

Each kernel (:data:`~hybridpd.pair.symbolic.derive.KERNELS`, per feedback case) is the
``lambdify`` source of a SymPy derivation, generated once per installation and version and
kept by :mod:`hybridpd._codecache`. The key hashes the versions of hybridpd and SymPy and the
source of :mod:`hybridpd.pair.symbolic.derive`; SymPy is imported only on a cache miss.
"""
from __future__ import annotations

import functools
import hashlib
import importlib.util
import re
from pathlib import Path

import numpy as np

from hybridpd import _codecache
from hybridpd._version import __version__
from hybridpd.model import Case, check_array

_DERIVE_SOURCE = Path(__file__).with_name("derive.py")


def _case(case) -> str:
    return Case.parse(case).value


def _as_float_arrays(**named):
    """The values as float arrays (any shape, NaN allowed), rejecting non-numeric input."""
    return [check_array(name, x, finite=False) for name, x in named.items()]


def _stack(values, shape, axis=-1):
    """Broadcast kernel outputs (scalars or arrays) to ``shape`` and stack on a new last axis."""
    return np.stack([np.broadcast_to(np.asarray(v, dtype=float), shape) for v in values],
                    axis=axis)


@functools.cache
def sympy_version() -> str:
    """SymPy's version, read from its ``release.py`` (importing SymPy takes a quarter second)."""
    spec = importlib.util.find_spec("sympy")
    if spec is not None and spec.origin:
        try:
            text = Path(spec.origin).with_name("release.py").read_text(encoding="utf-8")
            m = re.search(r"""__version__\s*=\s*["']([^"']+)["']""", text)
            if m:
                return m.group(1)
        except OSError:
            pass
    import sympy

    return sympy.__version__


@functools.cache
def derivation_key() -> str:
    """Key of the generated code: hybridpd and SymPy versions, hash of the derivation source."""
    src = hashlib.sha256(_DERIVE_SOURCE.read_bytes()).hexdigest()
    return _codecache.make_key("hybridpd", __version__, "sympy", sympy_version(), "derive", src)


def _generate(name: str, case: str) -> str:
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.symbolic.derive import kernel_source

    return kernel_source(name, case, func_name="kernel")


def load_kernel(name: str, case: str, key: str | None = None):
    """The kernel ``name`` for ``case`` from the cache (generated on a miss); no memoisation."""
    case = _case(case)
    key = derivation_key() if key is None else key
    ns = _codecache.load(f"closed_form.{name}.{case}", key, lambda: _generate(name, case))
    return ns["kernel"]


@functools.cache
def kernel(name: str, case: str):
    """The kernel ``name`` for ``case`` (``case`` already normalised), memoised per process."""
    return load_kernel(name, case)
