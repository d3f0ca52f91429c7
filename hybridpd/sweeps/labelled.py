"""Labelled results: xarray Datasets, written and read as netCDF (``.nc``) or Zarr (``.zarr``).

Region maps, basins and sweeps convert to :class:`xarray.Dataset` objects with named
dimensions (``e``, ``kv``, ``kp`` or whichever parameters were swept; ``y1``, ``x1`` for a
basin), coordinates carrying ``units`` and ``long_name``, and the fixed parameters as
attributes, so that e.g. ``rm.to_dataset().stable.sel(e=0.5).plot()`` draws a stability map.
The file format follows the suffix of the path: ``.nc`` (netCDF-4, through the ``netCDF4``
engine) or ``.zarr`` (a Zarr directory); ``.npz`` files of earlier versions stay readable.

Units follow the conventions (CONVENTIONS.md): the model is written in consistent but unspecified
units of length, time and mass (``m2 = 1`` unless given), so the ``units`` attributes name
dimensions (``"length/time"``, ``"mass/time^2"``) rather than SI units; ``"1"`` means
dimensionless.

xarray is imported only inside the functions that build or read a Dataset, so importing
hybridpd stays fast.
"""
from __future__ import annotations

import json
import math
import os
import shutil
import uuid
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["SUFFIXES", "UNITS", "axis_attrs", "check_suffix", "decode_attrs", "encode_attrs",
           "load_result", "read_dataset", "save_result", "write_dataset"]

#: Suffixes of the result files hybridpd writes and reads.
SUFFIXES = (".nc", ".zarr", ".npz")

#: Units and long names of parameters, coordinates and result variables.
UNITS: dict[str, tuple[str, str]] = {
    "kp": ("mass/time^2", "proportional gain"),
    "kv": ("mass/time", "derivative gain"),
    "e": ("1", "coefficient of restitution"),
    "mu": ("1", "mass ratio m1/m2"),
    "L": ("length", "half clearance"),
    "x10": ("length", "amplitude of the desired motion of the primary mass"),
    "gamma": ("1", "clearance ratio L/x10"),
    "m2": ("mass", "secondary mass"),
    "omega": ("rad/time", "angular frequency of the reference"),
    "n": ("1", "impacts per period / 2 (orbit order)"),
    "xm": ("length", "amplitude of the reference xd = xm cos(omega t)"),
    "x1": ("length", "primary-mass position at the impact"),
    "y1": ("length/time", "primary-mass velocity at the impact"),
    "spectral_radius": ("1", "largest modulus of the eigenvalues of DP")}


def axis_attrs(name: str) -> dict[str, str]:
    """``{"units", "long_name"}`` of a known parameter or variable (empty if unknown).

    Examples
    --------
    >>> axis_attrs("kv")
    {'units': 'mass/time', 'long_name': 'derivative gain kv'}
    """
    if name not in UNITS:
        return {}
    units, long_name = UNITS[name]
    return {"units": units, "long_name": f"{long_name} {name}"}


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


_JSON = "json:"


def encode_attrs(values: Mapping[str, Any]) -> dict[str, Any]:
    """Attributes that netCDF and Zarr can both hold: numbers and strings stay as they are;
    anything else (bool, None, lists, dicts) becomes a string ``"json:<JSON text>"``.
    :func:`decode_attrs` reverses it."""
    out: dict[str, Any] = {}
    for k, v in values.items():
        if isinstance(v, np.generic):
            v = v.item()
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


def write_dataset(ds, path: str | os.PathLike) -> Path:
    """Write `ds` to ``.nc`` or ``.zarr`` (by suffix), replacing an earlier result atomically.

    The data go to a temporary name beside `path` first, so a reader never sees half a file.
    An existing `path` is replaced only if it is a file (``.nc``) or a Zarr directory.
    """
    p = Path(path)
    suffix = check_suffix(p, "path", (".nc", ".zarr"))
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
    """Read a ``.nc`` file or ``.zarr`` store into memory as an :class:`xarray.Dataset`."""
    import xarray as xr

    p = Path(path)
    suffix = check_suffix(p, "path", (".nc", ".zarr"))
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


def save_result(result, path: str | os.PathLike, npz=None) -> Path:
    """Write ``result.to_dataset()`` to ``.nc`` or ``.zarr`` by the suffix of `path` (see
    :func:`write_dataset`); with `npz` (a function returning the arrays and metadata that
    :func:`~hybridpd.sweeps.npz.save_npz` takes) ``.npz`` is allowed too."""
    if check_suffix(path, "path", SUFFIXES if npz else SUFFIXES[:2]) != ".npz":
        return write_dataset(result.to_dataset(), path)
    # deferred import: the archives of earlier versions, loaded only when one is written
    from hybridpd.sweeps.npz import save_npz

    return save_npz(path, *npz())


def load_result(cls, path: str | os.PathLike, npz=None):
    """``cls.from_dataset`` of the ``.nc`` file or ``.zarr`` store at `path` (see
    :func:`save_result`); with `npz` (a function of the arrays and metadata that
    :func:`~hybridpd.sweeps.npz.load_npz` returns) an ``.npz`` file is read too."""
    if check_suffix(path, "path", SUFFIXES if npz else SUFFIXES[:2]) != ".npz":
        return cls.from_dataset(read_dataset(path))
    # deferred import: the archives of earlier versions, loaded only when one is read
    from hybridpd.sweeps.npz import load_npz

    return npz(*load_npz(path))


def _zarr2() -> dict:
    import zarr

    return {"zarr_format": 2} if int(zarr.__version__.split(".")[0]) >= 3 else {}
