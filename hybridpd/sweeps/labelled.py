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

import os
from pathlib import Path

from hybridpd._results import (
    SUFFIXES,
    check_suffix,
    decode_attrs,
    encode_attrs,
    read_dataset,
    write_dataset,
)

__all__ = ["SUFFIXES", "UNITS", "axis_attrs", "check_suffix", "decode_attrs", "encode_attrs",
           "load_result", "read_dataset", "save_result", "write_dataset"]


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
