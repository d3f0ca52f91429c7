"""Result objects: one-line reprs, and one mixin that makes them labelled datasets.

* :func:`compact_repr`: use ``__repr__ = compact_repr`` in a dataclass (the dataclass
  decorator keeps a ``__repr__`` defined in the class body). Fields declared with
  ``field(repr=False)`` are left out, arrays print as ``array(shape=(200, 200),
  dtype=float64)`` (0-d and one-element arrays print their value), floats with 6 significant
  digits, and anything long or multi-line as ``<TypeName>``.
* :class:`Fields`: ``to_dict()`` from a dataclass's fields (below); :class:`Result` extends it.
* :class:`Result`: the one way results become :class:`xarray.Dataset` objects
  (:meth:`~Result.to_dataset`, :meth:`~Result.from_dataset`), files (:meth:`~Result.save`,
  :meth:`~Result.load`: ``.nc`` netCDF-4, a ``.zarr`` store or an ``.npz`` archive, by
  suffix) and JSON (:meth:`~Result.to_dict`), derived from the dataclass's fields: a field
  with ``metadata={"dims": (...)}`` is a data variable, one with ``metadata={"coord": name}``
  the coordinate of a dimension, every other field an attribute (JSON-encoded where netCDF
  cannot hold it). A dimension name ``"@field"`` is the value of that field (e.g. a swept
  parameter's name). In :meth:`~Result.to_dict` a field with ``metadata={"dict_skip": True}``
  is left out and one with ``metadata={"dict_name": name}`` appears under that name.
* :func:`write_npz`, :func:`read_npz`: the one ``.npz`` codec, from and to the dataset (one
  array per variable, the attributes and dimensions as JSON), read by :func:`numpy.load`
  without pickle.

xarray is imported only inside the functions that build or read a Dataset, so importing
hybridpd stays fast.

Examples
--------
>>> from dataclasses import dataclass
>>> import numpy as np
>>> @dataclass
... class Out:
...     x: np.ndarray
...     rho: float
...     __repr__ = compact_repr
>>> Out(np.zeros((3, 4)), 0.123456789)
Out(x=array(shape=(3, 4), dtype=float64), rho=0.123457)
"""
from __future__ import annotations

import dataclasses
import enum
import json
import math
import numbers
import os
import shutil
import uuid
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["SUFFIXES", "Fields", "Result", "WithExtras", "check_suffix", "compact_repr", "decode_attrs",
           "encode_attrs", "jsonable", "read_dataset", "read_npz", "short_repr", "write_dataset",
           "write_npz"]

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


# ----------------------------------------------------------------------------------------
# labelled files
# ----------------------------------------------------------------------------------------
#: Suffixes of the result files hybridpd writes and reads.
SUFFIXES = (".nc", ".zarr", ".npz")
_JSON = "json:"
_NPZ_META = "__metadata__"      # the .npz entry holding the JSON document
_NPZ_FORMAT = "hybridpd.dataset/1"


def check_suffix(path: str | os.PathLike, name: str = "path",
                 allowed: tuple[str, ...] = SUFFIXES) -> str:
    """Return the suffix of `path` if allowed, else raise ValueError naming the choices.

    Examples
    --------
    >>> check_suffix("regions.nc")
    '.nc'
    >>> check_suffix("r.png")
    Traceback (most recent call last):
    ...
    ValueError: path must end in one of .nc, .zarr, .npz; got 'r.png'
    """
    if not isinstance(path, (str, os.PathLike)):
        raise ValueError(f"{name} must be a file path, got {path!r}")
    suffix = Path(path).suffix.lower()
    if suffix not in allowed:
        raise ValueError(f"{name} must end in one of {', '.join(allowed)}; got {str(path)!r}")
    return suffix


def jsonable(v) -> Any:
    """`v` as JSON-ready Python values: arrays and tuples as lists, numpy scalars as Python
    ones, non-finite floats as ``None``, complex numbers as ``[re, im]``, results (anything
    with a ``to_dict`` method) as their :meth:`Result.to_dict`.

    Examples
    --------
    >>> jsonable({"a": np.array([1.0, np.nan]), "b": (1 + 2j, np.int64(3))})
    {'a': [1.0, None], 'b': [[1.0, 2.0], 3]}
    """
    if isinstance(v, Fields):
        return v.to_dict()
    if isinstance(v, Mapping):
        return {str(k): jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple, np.ndarray)):
        return [jsonable(x) for x in (v.tolist() if isinstance(v, np.ndarray) else v)]
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, enum.Enum):
        return v.name
    if isinstance(v, bool) or v is None or isinstance(v, (int, str)):
        return v
    if isinstance(v, complex):
        return [jsonable(v.real), jsonable(v.imag)]
    if isinstance(v, float):
        return v if math.isfinite(v) else None
    if callable(getattr(v, "to_dict", None)):   # results that are not datasets (events)
        return jsonable(v.to_dict())
    return str(v)


def encode_attrs(values: Mapping[str, Any]) -> dict[str, Any]:
    """Attributes that netCDF and Zarr can both hold: numbers and strings stay as they are;
    anything else (bool, None, lists, dicts) becomes a string ``"json:<JSON text>"``.
    :func:`decode_attrs` reverses it."""
    out: dict[str, Any] = {}
    for k, v in values.items():
        if isinstance(v, np.generic):
            v = v.item()
        if isinstance(v, np.ndarray):
            v = v.tolist()
        text = isinstance(v, str) and not v.startswith(_JSON)
        number = isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
        out[k] = v if text or number else _JSON + json.dumps(v, allow_nan=True)
    return out


def decode_attrs(attrs: Mapping[str, Any]) -> dict[str, Any]:
    """Inverse of :func:`encode_attrs` (numpy scalars read from files become Python ones)."""
    out: dict[str, Any] = {}
    for k, v in attrs.items():
        if isinstance(v, np.generic):
            v = v.item()
        elif isinstance(v, np.ndarray):
            v = v.tolist()
        if isinstance(v, str) and v.startswith(_JSON):
            v = json.loads(v[len(_JSON):])
        out[k] = v
    return out


def _zarr2() -> dict:
    import zarr

    return {"zarr_format": 2} if int(zarr.__version__.split(".")[0]) >= 3 else {}


def write_npz(ds, path: str | os.PathLike) -> Path:
    """Write dataset `ds` to an ``.npz`` archive, replacing an earlier file atomically.

    One array per variable (coordinates too) under its name, and the entry
    ``__metadata__``: a JSON document with the dataset's ``kind``, its attributes and each
    variable's dimensions and attributes (as a netCDF file holds them: numbers, strings and
    lists of numbers; anything else encoded by :func:`encode_attrs`).
    :func:`numpy.load` reads the file without pickle; :func:`read_npz` gives the dataset back.

    Examples
    --------
    >>> import tempfile, xarray as xr
    >>> ds = xr.Dataset({"rho": (("kv",), [0.5, 2.0])}, coords={"kv": [1.0, 2.0]},
    ...                 attrs={"kind": "scan", "fixed": {"e": 0.5}})
    >>> back = read_npz(write_npz(ds, tempfile.mkdtemp() + "/scan.npz"))
    >>> back.rho.dims, back.kv.values.tolist(), decode_attrs(back.attrs)["fixed"]
    (('kv',), [1.0, 2.0], {'e': 0.5})
    """
    p = Path(path)
    check_suffix(p, "path", (".npz",))
    arrays, layout = {}, {}
    for name, v in ds.variables.items():
        a = np.asarray(v.values)
        if a.dtype.hasobject:       # strings held as objects; anything else needs pickle
            a = a.astype(str)
        arrays[str(name)] = a
        layout[str(name)] = {"dims": [str(d) for d in v.dims], "attrs": _plain_attrs(v.attrs),
                             "coord": name in ds.coords}
    if _NPZ_META in arrays:
        raise ValueError(f"a variable of the dataset is named {_NPZ_META!r}, the entry "
                         "holding the metadata")
    attrs = _plain_attrs(ds.attrs)
    meta = {"kind": attrs.get("kind"), "format": _NPZ_FORMAT, "attrs": attrs,
            "variables": layout}
    arrays[_NPZ_META] = np.array(json.dumps(meta, sort_keys=True))
    p.parent.mkdir(parents=True, exist_ok=True)
    tmp = p.with_name(f".{p.name}.{uuid.uuid4().hex[:12]}.tmp.npz")
    try:
        with open(tmp, "wb") as fh:
            np.savez(fh, **arrays)
        os.replace(tmp, p)
    finally:
        if tmp.exists():
            tmp.unlink()
    return p


def _plain_attrs(attrs: Mapping[str, Any]) -> dict[str, Any]:
    """Attributes as JSON holds them: numpy scalars and arrays as numbers and lists; values
    netCDF could not hold either (dicts, None, bools) encoded by :func:`encode_attrs`."""
    out = {}
    for k, v in attrs.items():
        v = v.item() if isinstance(v, np.generic) else v
        v = v.tolist() if isinstance(v, np.ndarray) else v
        plain = isinstance(v, (str, int, float)) and not isinstance(v, bool) or (
            isinstance(v, list) and all(isinstance(x, (int, float, str)) for x in v))
        out[str(k)] = v if plain else encode_attrs({k: v})[k]
    return out


def read_npz(path: str | os.PathLike):
    """The :class:`xarray.Dataset` of an ``.npz`` archive written by :func:`write_npz`
    (``ValueError`` for any other archive)."""
    import xarray as xr

    p = Path(path)
    check_suffix(p, "path", (".npz",))
    if not p.exists():
        raise ValueError(f"path {str(p)!r} does not exist")
    with np.load(p, allow_pickle=False) as z:
        meta = json.loads(str(z[_NPZ_META][()])) if _NPZ_META in z.files else {}
        if meta.get("format") != _NPZ_FORMAT:
            raise ValueError(f"{str(p)!r} is not a result archive of this version of hybridpd "
                             f"(no {_NPZ_FORMAT!r} metadata)")
        data, coords = {}, {}
        for name, v in meta["variables"].items():
            (coords if v["coord"] else data)[name] = (tuple(v["dims"]), z[name], v["attrs"])
    return xr.Dataset(data, coords=coords, attrs=meta["attrs"])


def write_dataset(ds, path: str | os.PathLike) -> Path:
    """Write `ds` to ``.nc``, ``.zarr`` or ``.npz`` (by suffix; :func:`write_npz`), replacing
    an earlier result atomically.

    The data go to a temporary name beside `path` first, so a reader never sees half a file.
    An existing `path` is replaced only if it is a file (``.nc``, ``.npz``) or a Zarr
    directory.
    """
    p = Path(path)
    suffix = check_suffix(p, "path")
    if suffix == ".npz":
        return write_npz(ds, p)
    p.parent.mkdir(parents=True, exist_ok=True)
    tmp = p.with_name(f".{p.name}.{uuid.uuid4().hex[:12]}.tmp{suffix}")
    try:
        if suffix == ".nc":
            # complex variables need netCDF4 >= 1.7's compound-type support, asked for only
            # when needed so that real-valued results write with any netCDF4 version
            cplx = any(v.dtype.kind == "c" for v in ds.variables.values())
            ds.to_netcdf(tmp, engine="netcdf4", **({"auto_complex": True} if cplx else {}))
            os.replace(tmp, p)
        else:
            # Zarr format 2 with consolidated metadata: read by zarr-python 2 and 3 and by
            # xarray.open_zarr without warnings
            ds.to_zarr(tmp, mode="w", consolidated=True, **_zarr2())
            if p.exists():
                if not ((p / "zarr.json").is_file() or (p / ".zgroup").is_file()):
                    raise ValueError(f"path {str(p)!r} exists and is not a Zarr store; "
                                     "refusing to replace it")
                shutil.rmtree(p)
            os.replace(tmp, p)
    finally:
        if tmp.is_dir():
            shutil.rmtree(tmp, ignore_errors=True)
        elif tmp.exists():
            tmp.unlink()
    return p


def read_dataset(path: str | os.PathLike):
    """Read a ``.nc`` file, ``.zarr`` store or ``.npz`` archive (:func:`read_npz`) into
    memory as an :class:`xarray.Dataset`."""
    import xarray as xr

    p = Path(path)
    suffix = check_suffix(p, "path")
    if suffix == ".npz":
        return read_npz(p)
    if not p.exists():
        raise ValueError(f"path {str(p)!r} does not exist")
    if suffix == ".nc":
        try:
            ds = xr.open_dataset(p, engine="netcdf4", auto_complex=True)
        except TypeError:  # xarray or netCDF4 without complex support
            ds = xr.open_dataset(p, engine="netcdf4")
        with ds:
            return ds.load()
    consolidated = (p / ".zmetadata").is_file()
    with xr.open_dataset(p, engine="zarr", consolidated=consolidated) as ds:
        return ds.load()


# ----------------------------------------------------------------------------------------
# the mixin
# ----------------------------------------------------------------------------------------
class Fields:
    """Mixin of a dataclass whose JSON form is its fields: :meth:`to_dict`. :class:`Result`
    adds datasets and files; a value that is not saved alone (an end point, a certificate)
    takes only this.

    Examples
    --------
    >>> from dataclasses import dataclass, field
    >>> @dataclass(frozen=True)
    ... class End(Fields):
    ...     m2: float
    ...     residual: float = field(metadata={"dict_name": "rho_minus_1"})
    ...     seconds: float = field(default=0.0, metadata={"dict_skip": True})
    >>> End(0.5, float("nan"), 1.5).to_dict()
    {'m2': 0.5, 'rho_minus_1': None}
    """

    def to_dict(self) -> dict:
        """JSON-ready values of the fields (:func:`jsonable`), in their order: a field with
        ``metadata={"dict_skip": True}`` is left out, one with ``metadata={"dict_name":
        name}`` appears under that name."""
        return {f.metadata.get("dict_name", f.name): jsonable(getattr(self, f.name))
                for f in dataclasses.fields(self) if not f.metadata.get("dict_skip")}


class Result(Fields):
    """Mixin of a dataclass result: datasets, files and JSON from its fields (module
    docstring).

    A subclass names its ``kind`` (the dataset's ``kind`` attribute, checked on reading) and
    declares its array fields' dimensions; it overrides :meth:`to_dataset` /
    :meth:`from_dataset` only for what the fields cannot say (then ``save``, ``load`` and
    ``to_dict`` still come from here).

    Examples
    --------
    >>> import tempfile
    >>> from dataclasses import dataclass, field
    >>> @dataclass(frozen=True, eq=False)
    ... class Scan(Result):
    ...     kind = "scan"
    ...     name: str
    ...     p: np.ndarray = field(metadata={"coord": "@name"})
    ...     rho: np.ndarray = field(metadata={"dims": ("@name",), "dict_name": "radius"})
    ...     note: dict = field(default_factory=dict)
    ...     seconds: float = field(default=0.0, metadata={"dict_skip": True})
    >>> r = Scan("kv", np.array([1.0, 2.0]), np.array([0.5, np.nan]), {"k": (1, 2)})
    >>> r.to_dict()
    {'name': 'kv', 'p': [1.0, 2.0], 'radius': [0.5, None], 'note': {'k': [1, 2]}}
    >>> list(r.to_dataset().rho.dims)
    ['kv']
    >>> back = Scan.load(r.save(tempfile.mkdtemp() + "/scan.nc"))
    >>> back.name, back.note, np.isnan(back.rho[1])
    ('kv', {'k': [1, 2]}, np.True_)
    """

    kind = ""

    def _dim(self, name: str) -> str:
        return str(getattr(self, name[1:])) if name.startswith("@") else name


    def to_dataset(self):
        """The result as an :class:`xarray.Dataset` (module docstring)."""
        import xarray as xr

        data, coords, attrs = {}, {}, {"kind": self.kind}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if "dims" in f.metadata and v is not None:
                data[f.name] = (tuple(self._dim(d) for d in f.metadata["dims"]), np.asarray(v),
                                {k: w for k, w in f.metadata.items() if k == "long_name"})
            elif "coord" in f.metadata:
                coords[self._dim(f.metadata["coord"])] = np.asarray(v)
            else:
                attrs[f.name] = jsonable(v)
        return xr.Dataset(data, coords=coords, attrs=encode_attrs(attrs))

    @classmethod
    def from_dataset(cls, ds):
        """Inverse of :meth:`to_dataset`; ``ValueError`` for a dataset of another kind."""
        attrs = decode_attrs(ds.attrs)
        if attrs.get("kind") != cls.kind:
            raise ValueError(f"the dataset holds a {attrs.get('kind')!r}, not a {cls.kind!r}")
        fields = dataclasses.fields(cls)
        kw = {f.name: attrs[f.name] for f in fields
              if "dims" not in f.metadata and "coord" not in f.metadata and f.name in attrs}
        dim = lambda d: str(kw[d[1:]]) if d.startswith("@") else d
        for f in fields:
            if "dims" in f.metadata and f.name in ds:
                kw[f.name] = ds[f.name].transpose(*map(dim, f.metadata["dims"])).values
            elif "coord" in f.metadata:
                kw[f.name] = ds[dim(f.metadata["coord"])].values
        return cls(**kw)

    def save(self, path: str | os.PathLike) -> Path:
        """Write to ``.nc``, ``.zarr`` or ``.npz`` (by suffix); returns the path."""
        return write_dataset(self.to_dataset(), path)

    @classmethod
    def load(cls, path: str | os.PathLike):
        """Read a result written by :meth:`save`."""
        return cls.from_dataset(read_dataset(path))


class WithExtras:
    """Mixin of results whose ``variables`` and ``metadata`` dicts hold optional entries
    (a family's extra variables, a run's settings): each reads as an attribute
    (``rm.xm``, ``d.keep``)."""

    def __getattr__(self, name):
        # the guard keeps copy/pickle, which probe before the fields exist, from recursing
        if not name.startswith("_"):
            for where in ("variables", "metadata"):
                table = self.__dict__.get(where) or {}
                if name in table:
                    return table[name]
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
