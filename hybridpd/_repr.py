"""One-line reprs for result objects: shapes instead of array contents.

Use ``__repr__ = compact_repr`` in a dataclass (the dataclass decorator keeps a ``__repr__``
defined in the class body). Fields declared with ``field(repr=False)`` are left out, arrays
print as ``array(shape=(200, 200), dtype=float64)`` (0-d and one-element arrays print their
value), floats with 6 significant digits, and anything long or multi-line as ``<TypeName>``.

Examples
--------
>>> from dataclasses import dataclass
>>> import numpy as np
>>> @dataclass
... class Result:
...     x: np.ndarray
...     rho: float
...     __repr__ = compact_repr
>>> Result(np.zeros((3, 4)), 0.123456789)
Result(x=array(shape=(3, 4), dtype=float64), rho=0.123457)
"""
from __future__ import annotations

import dataclasses
import enum
import numbers

import numpy as np

__all__ = ["compact_repr", "short_repr"]

_MAX_ITEM = 60  # characters of one field's value before it is abbreviated
_MAX_SEQ = 4    # a list/tuple with more items prints as its length


def short_repr(value) -> str:
    """A short one-line representation of ``value`` (see the module docstring)."""
    if value is None or isinstance(value, (bool, np.bool_)):
        return repr(bool(value)) if value is not None else "None"
    if isinstance(value, enum.Enum):
        return f"{type(value).__name__}.{value.name}"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        return format(float(value), ".6g")
    if isinstance(value, numbers.Complex):
        return format(complex(value), ".6g")
    if isinstance(value, np.ndarray):
        if value.size == 1 and value.ndim <= 1 and value.dtype.kind in "biufc":
            return short_repr(value.reshape(()).item())
        return f"array(shape={value.shape}, dtype={value.dtype})"
    if isinstance(value, str):
        s = repr(value)
        return s if len(s) <= _MAX_ITEM else f"str(len={len(value)})"
    if isinstance(value, (list, tuple)):
        if len(value) <= _MAX_SEQ:
            inner = ", ".join(short_repr(v) for v in value)
            comma = "," if len(value) == 1 else ""
            s = f"[{inner}]" if isinstance(value, list) else f"({inner}{comma})"
            if len(s) <= _MAX_ITEM:
                return s
        return f"{type(value).__name__}(len={len(value)})"
    if isinstance(value, dict):
        keys = ", ".join(repr(k) for k in list(value)[:_MAX_SEQ])
        more = ", ..." if len(value) > _MAX_SEQ else ""
        s = f"dict(keys=[{keys}{more}])"
        return s if len(s) <= _MAX_ITEM else f"dict(len={len(value)})"
    try:
        s = repr(value)
    except Exception:  # noqa: BLE001 - a repr must never raise
        s = ""
    if not s or "\n" in s or len(s) > _MAX_ITEM:
        return f"<{type(value).__name__}>"
    return s


def compact_repr(self) -> str:
    """One-line ``TypeName(field=value, ...)`` of a dataclass instance (or any object)."""
    if dataclasses.is_dataclass(self):
        items = [(f.name, getattr(self, f.name)) for f in dataclasses.fields(self) if f.repr]
    else:
        items = [(k, v) for k, v in vars(self).items() if not k.startswith("_")]
    body = ", ".join(f"{k}={short_repr(v)}" for k, v in items)
    return f"{type(self).__name__}({body})"
