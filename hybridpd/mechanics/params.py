"""Numeric entries of a model file addressed by their dotted TOML paths.

Every number of a model file has a path: table keys joined by dots, array elements by their
0-based index (``controller.kp``, ``contact.0.restitution``, ``system.masses.2``,
``system.stiffness.1.2``, ``reference.omega``; with repeated ``[[controller]]`` tables
``controller.1.kp`` and ``controller.0.reference.omega``). :class:`ModelTemplate` holds the
parsed file and builds the model for any values of such paths; a path that names no numeric
entry is refused before anything runs, with the entries that exist.

One key may set several entries at once: a *pattern* in which each ``*`` stands for one whole
path segment (``controller.*.kp``: every controller's ``kp``; ``system.stiffness.*.*``) and/or
a comma-separated list of paths or patterns (``controller.0.kp,controller.2.kp``). Every
entry it matches gets the value; a key that matches no numeric entry is refused, naming what
exists. Sweep axes and the command line's ``--set KEY VALUE`` take such keys, and a result's
coordinate is named by the key as given.

Only entries present in the file can be set (a default is not an entry: write it in the file
to sweep it), so a path always means what the file says.
"""
from __future__ import annotations

import copy
import difflib
import math
from dataclasses import dataclass, field

from hybridpd._results import compact_repr
from hybridpd.mechanics.modelfile import model_from_dict, read_model_file

__all__ = ["ModelTemplate", "check_path", "get_value", "numeric_paths", "resolve_path",
           "set_values"]


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


def _listing(paths) -> str:
    return ", ".join(list(paths)[:40]) + (" ..." if len(paths) > 40 else "")


def _one(part, paths, key):
    """The paths one element of a key names (a path or a pattern)."""
    if part in paths:
        return [part]
    segs = part.split(".")
    if "*" in part:
        bad = [g for g in segs if "*" in g and g != "*"]
        if bad:
            raise ValueError(f"parameter {key!r}: each '*' stands for one whole path segment, "
                             f"got {bad[0]!r}")
        found = [p for p in paths if len(p.split(".")) == len(segs)
                 and all(g in ("*", q) for g, q in zip(segs, p.split(".")))]
        if found:
            return found
        what = f"pattern {part!r}" if part != key else "it"
        raise ValueError(f"parameter {key!r}: {what} matches no numeric entry of the model "
                         f"file; its numeric entries: {_listing(paths)}")
    close = difflib.get_close_matches(part, list(paths), n=1, cutoff=0.6)
    hint = f" (did you mean {close[0]}?)" if close else ""
    if part == key:
        raise ValueError(f"parameter {key!r} is no numeric entry of the model file{hint}; its "
                         f"numeric entries: {_listing(paths)}")
    raise ValueError(f"parameter {key!r}: {part!r} is no numeric entry of the model file"
                     f"{hint}; its numeric entries: {_listing(paths)}")


def resolve_path(data: dict, key) -> tuple:
    """The paths of the numeric entries that `key` sets, in file order.

    `key` is a dotted path, a pattern (each ``*`` one whole path segment) or a
    comma-separated list of paths and patterns (module docstring). ValueError naming `key`
    (and what exists) when any part of it matches no numeric entry.

    Examples
    --------
    >>> d = {"controller": [{"kp": 1.0, "kv": 0.1}, {"kp": 2.0, "kv": 0.2}]}
    >>> resolve_path(d, "controller.*.kp")
    ('controller.0.kp', 'controller.1.kp')
    >>> resolve_path(d, "controller.1.kv, controller.0.kp")
    ('controller.0.kp', 'controller.1.kv')
    >>> resolve_path(d, "controller.*.kd")
    Traceback (most recent call last):
    ...
    ValueError: parameter 'controller.*.kd': it matches no numeric entry of the model file; its numeric entries: controller.0.kp, controller.0.kv, controller.1.kp, controller.1.kv
    """
    paths = numeric_paths(data)
    if not isinstance(key, str) or not key.strip():
        raise ValueError(f"parameter must be a dotted path (a string), got {key!r}")
    parts = [p.strip() for p in key.split(",")]
    if any(not p for p in parts):
        raise ValueError(f"parameter {key!r}: an empty path in the comma-separated list")
    found = set()
    for part in parts:
        found.update(_one(part, paths, key))
    return tuple(p for p in paths if p in found)


def check_path(data: dict, path) -> str:
    """`path` if it names a numeric entry of `data` (or, as a pattern or list, matches at
    least one: :func:`resolve_path`); ValueError naming it and what exists.

    Examples
    --------
    >>> check_path({"controller": {"kp": 1.0}}, "controller.kd")
    Traceback (most recent call last):
    ...
    ValueError: parameter 'controller.kd' is no numeric entry of the model file (did you mean controller.kp?); its numeric entries: controller.kp
    """
    resolve_path(data, path)
    return path


def get_value(data: dict, path: str) -> float:
    """The number at `path` (checked with :func:`check_path`); for a key that sets several
    entries, their common value (ValueError if they differ)."""
    paths = numeric_paths(data)
    vals = {paths[p] for p in resolve_path(data, path)}
    if len(vals) > 1:
        raise ValueError(f"parameter {path!r} sets entries of different values "
                         f"{sorted(vals)}: no single value to report")
    return vals.pop()


def set_values(data: dict, values: dict) -> dict:
    """A deep copy of `data` with the numeric entries at the given paths replaced.

    Parameters
    ----------
    data : dict
        Parsed model file (:func:`~hybridpd.mechanics.modelfile.read_model_file`).
    values : dict of str to float
        ``{key: value}``; every value finite. A key is a path, a pattern or a list of them
        (:func:`resolve_path`): every entry it matches gets the value.

    Returns
    -------
    dict

    Raises
    ------
    ValueError
        A key that matches no numeric entry, an entry set by two keys, or a non-finite value
        (naming the key).

    Examples
    --------
    >>> d = {"controller": [{"kp": 1.0}, {"kp": 2.0}], "reference": {"omega": 5.0}}
    >>> set_values(d, {"controller.*.kp": 7.5})["controller"]
    [{'kp': 7.5}, {'kp': 7.5}]
    """
    out = copy.deepcopy(_tables(data))
    by = {}
    for key, value in values.items():
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"{key}: must be a number, got {value!r}") from None
        if not math.isfinite(v):
            raise ValueError(f"{key}: must be finite, got {value!r}")
        for path in resolve_path(out, key):
            if path in by:
                raise ValueError(f"{path} is set by both {by[path]!r} and {key!r}")
            by[path] = key
            _set(out, path, v)
    return out


def _set(out, path, v):
    keys = path.split(".")
    node = out
    for k in keys[:-1]:
        node = node[int(k)] if isinstance(node, list) else node[k]
    last = keys[-1]
    if isinstance(node, list):
        node[int(last)] = v
    else:
        node[last] = v


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
        """The paths (or patterns, lists), each checked (:func:`check_path`)."""
        return tuple(check_path(self.data, p) for p in paths)

    def resolve(self, key) -> tuple:
        """The paths of the entries that `key` sets (:func:`resolve_path`)."""
        return resolve_path(self.data, key)

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
