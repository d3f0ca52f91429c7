"""Numeric entries of a model file addressed by their dotted TOML paths.

Every number of a model file has a path: table keys joined by dots, array elements by their
0-based index (``controller.kp``, ``contact.0.restitution``, ``system.masses.2``,
``system.stiffness.1.2``, ``reference.omega``). :class:`ModelTemplate` holds the parsed file
and builds the model for any values of such paths; a path that names no numeric entry is
refused before anything runs, with the entries that exist.

Only entries present in the file can be set (a default is not an entry: write it in the file
to sweep it), so a path always means what the file says.
"""
from __future__ import annotations

import copy
import difflib
import math
from dataclasses import dataclass, field

from hybridpd._repr import compact_repr
from hybridpd.mechanics.modelfile import model_from_dict, read_model_file

__all__ = ["ModelTemplate", "check_path", "get_value", "numeric_paths", "set_values"]


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _walk(node, prefix, out):
    if _is_number(node):
        out[prefix] = float(node)
    elif isinstance(node, dict):
        for k, v in node.items():
            _walk(v, f"{prefix}.{k}" if prefix else str(k), out)
    elif isinstance(node, list):
        for i, v in enumerate(node):
            _walk(v, f"{prefix}.{i}" if prefix else str(i), out)


def _tables(data: dict) -> dict:
    # a single [contact] table is the same as a one-element [[contact]] array
    if isinstance(data.get("contact"), dict):
        data = dict(data, contact=[data["contact"]])
    return data


def numeric_paths(data: dict) -> dict:
    """``{path: value}`` of every numeric entry of a parsed model file, in file order.

    Examples
    --------
    >>> d = {"controller": {"type": "pd", "kp": 10.0, "kv": 2}, "contact": [{"hi": 0.1}]}
    >>> numeric_paths(d)
    {'controller.kp': 10.0, 'controller.kv': 2.0, 'contact.0.hi': 0.1}
    """
    if not isinstance(data, dict):
        raise ValueError("model must be a table")
    out: dict = {}
    _walk(_tables(data), "", out)
    return out


def check_path(data: dict, path) -> str:
    """`path` if it names a numeric entry of `data`; ValueError naming it and what exists.

    Examples
    --------
    >>> check_path({"controller": {"kp": 1.0}}, "controller.kd")
    Traceback (most recent call last):
    ...
    ValueError: parameter 'controller.kd' is no numeric entry of the model file (did you mean controller.kp?); its numeric entries: controller.kp
    """
    paths = numeric_paths(data)
    if isinstance(path, str) and path in paths:
        return path
    close = difflib.get_close_matches(str(path), list(paths), n=1, cutoff=0.6)
    hint = f" (did you mean {close[0]}?)" if close else ""
    listed = ", ".join(list(paths)[:40]) + (" ..." if len(paths) > 40 else "")
    raise ValueError(f"parameter {path!r} is no numeric entry of the model file{hint}; its "
                     f"numeric entries: {listed}")


def get_value(data: dict, path: str) -> float:
    """The number at `path` (checked with :func:`check_path`)."""
    return numeric_paths(data)[check_path(data, path)]


def set_values(data: dict, values: dict) -> dict:
    """A deep copy of `data` with the numeric entries at the given paths replaced.

    Parameters
    ----------
    data : dict
        Parsed model file (:func:`~hybridpd.mechanics.modelfile.read_model_file`).
    values : dict of str to float
        ``{path: value}``; every value finite.

    Returns
    -------
    dict

    Raises
    ------
    ValueError
        A path that names no numeric entry, or a non-finite value (naming the path).
    """
    out = copy.deepcopy(_tables(data))
    for path, value in values.items():
        check_path(out, path)
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"{path}: must be a number, got {value!r}") from None
        if not math.isfinite(v):
            raise ValueError(f"{path}: must be finite, got {value!r}")
        keys = path.split(".")
        node = out
        for k in keys[:-1]:
            node = node[int(k)] if isinstance(node, list) else node[k]
        last = keys[-1]
        if isinstance(node, list):
            node[int(last)] = v
        else:
            node[last] = v
    return out


@dataclass(frozen=True, eq=False)
class ModelTemplate:
    """A parsed model file whose numeric entries can be set by dotted path.

    Attributes
    ----------
    data : dict
        The parsed TOML tables (never modified).
    source : str
        File name (or ``"<dict>"``).

    Examples
    --------
    >>> from pathlib import Path
    >>> import hybridpd
    >>> f = Path(hybridpd.__file__).parents[1] / "examples" / "models" / "drivetrain.toml"
    >>> t = ModelTemplate.load(f) if f.exists() else None
    >>> t is None or t.value("controller.kp")
    20.0
    >>> t is None or t.model({"controller.kp": 35.0}).automaton.loop is not None
    True
    """

    data: dict = field(repr=False)
    source: str = "<dict>"
    __repr__ = compact_repr

    @classmethod
    def load(cls, path) -> ModelTemplate:
        """Parse a TOML model file (checked by building its model once)."""
        data, p = read_model_file(path)
        t = cls(data, str(p))
        t.model()
        return t

    @property
    def paths(self) -> dict:
        """``{path: value}`` of every numeric entry (:func:`numeric_paths`)."""
        return numeric_paths(self.data)

    def check(self, *paths) -> tuple:
        """The paths, each checked (:func:`check_path`)."""
        return tuple(check_path(self.data, p) for p in paths)

    def value(self, path: str) -> float:
        """The file's number at `path`."""
        return get_value(self.data, path)

    def with_values(self, values: dict | None = None) -> dict:
        """The parsed tables with `values` (``{path: value}``) set."""
        return set_values(self.data, dict(values or {}))

    def model(self, values: dict | None = None):
        """The :class:`~hybridpd.mechanics.modelfile.MechanicalModel` at `values`.

        Raises ValueError (naming the key) if the values make the file invalid.
        """
        return model_from_dict(self.with_values(values), source=self.source)
