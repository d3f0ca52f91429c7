"""Existence and stability regions of the symmetric orbit in a parameter plane (Figs 4-5).

A region map evaluates :func:`hybridpd.pair.orbits.symmetric_orbits` over a grid of two parameters
(by default the gains ``kp``, ``kv``) for a list of restitution coefficients. Every grid point
gets exactly the answer :func:`hybridpd.pair.orbits.symmetric_orbit` gives for it (existence with
rigorous viability, multipliers of ``DP``). Arrays are indexed ``[e][y][x]``.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.model import (
    Case,
    check_array,
    check_int,
    check_named_axis,
    check_odd_order,
    check_positive,
)
from hybridpd.pair.orbits import REASONS, symmetric_orbits
from hybridpd.sweeps.labelled import (
    axis_attrs,
    decode_attrs,
    encode_attrs,
    load_result,
    save_result,
)

__all__ = ["AXES", "RegionMap", "load_region_map", "region_map"]

# Each call of the vectorised evaluation costs ~10 ms besides its points (~8 us each):
# chunks of 16384 points keep that overhead near 10%.
_MIN_REGION_CHUNK = 16384

#: Parameters a region map can sweep (any two of them), besides the list of ``e``.
AXES = ("kp", "kv", "mu", "L", "omega", "m2", "x10")


@dataclass(frozen=True)
class RegionMap:
    """Existence/stability over a 2-D parameter grid for several restitution coefficients.

    Attributes
    ----------
    case : str
    x_name, y_name : str
        Swept parameters (e.g. ``"kp"``, ``"kv"``).
    x, y : ndarray
        Grid axes.
    e : ndarray
        Restitution coefficients (first array index).
    fixed : dict
        All other parameters (``mu, L, omega, m2, x10, n`` and the non-swept gains).
    exists, stable : ndarray of bool, shape (len(e), len(y), len(x))
    spectral_radius, xm : ndarray of float, same shape (NaN where no orbit exists / singular)
    reason : ndarray of int, same shape
        Codes of :data:`hybridpd.pair.orbits.REASONS`.
    certified : ndarray of int8, same shape, or None
        The certified class of each grid point's cell (``region_map(certify=True)``; see
        :mod:`hybridpd.pair.certified`): CF flags ``0`` undecided, ``1`` proved stable,
        ``2`` proved unstable, ``3`` proved no orbit. The cell of a point is the box half-way
        to its neighbours, the edge cells ending at the grid's first and last points
        (:func:`hybridpd.pair.certified.cell_edges`).
    """

    case: str
    x_name: str
    y_name: str
    x: np.ndarray
    y: np.ndarray
    e: np.ndarray
    fixed: dict
    exists: np.ndarray
    stable: np.ndarray
    spectral_radius: np.ndarray
    xm: np.ndarray
    reason: np.ndarray
    metadata: dict = field(default_factory=dict)
    certified: np.ndarray | None = None
    __repr__ = compact_repr

    def cell_area(self) -> float:
        """Area of one grid cell in the axes' units."""
        return float((self.x[1] - self.x[0]) * (self.y[1] - self.y[0]))

    def area(self, which: str = "stable") -> np.ndarray:
        """Area per ``e`` of the ``"exists"`` or ``"stable"`` (exists and stable) region."""
        arr = {"exists": self.exists, "stable": self.stable}[which]
        return arr.sum(axis=(1, 2)) * self.cell_area()

    def fraction(self, which: str = "stable") -> np.ndarray:
        """Share of the grid per ``e`` in the region."""
        arr = {"exists": self.exists, "stable": self.stable}[which]
        return arr.mean(axis=(1, 2))

    def certified_shares(self) -> list:
        """Per ``e``, each certified class's count and share interval (see
        :func:`hybridpd.pair.certified.class_shares`); ``[]`` without a certified map."""
        if self.certified is None:
            return []
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.pair.certified import class_shares

        return [class_shares(f) for f in self.certified]

    def to_dict(self) -> dict:
        """JSON-ready form (the CLI's ``regions --json``), arrays indexed ``[e][y][x]``."""
        rho = np.where(self.exists, self.spectral_radius, np.nan)
        extra = {}
        if self.certified is not None:
            # deferred import: loaded only when this runs, for start-up time
            from hybridpd.pair.certified import FLAG_MEANINGS

            extra = {"certified": self.certified.tolist(), "certified_meanings": FLAG_MEANINGS,
                     "certified_shares": [{k: {**v, "share": list(v["share"])}
                                           for k, v in sh.items()}
                                          for sh in self.certified_shares()]}
        return {**extra, 
            "case": self.case, "x_name": self.x_name, "y_name": self.y_name,
            self.x_name: self.x.tolist(), self.y_name: self.y.tolist(), "e": self.e.tolist(),
            "fixed": self.fixed,
            "exists": self.exists.tolist(), "stable": self.stable.tolist(),
            "spectral_radius": [[[None if not np.isfinite(v) else float(v) for v in row]
                                 for row in plane] for plane in rho],
            "reason": self.reason.tolist(), "reasons": {str(k): v for k, v in REASONS.items()},
            **extra}

    def to_dataset(self):
        """The map as an :class:`xarray.Dataset` with dimensions ``(e, y_name, x_name)``.

        Coordinates carry ``units`` and ``long_name``; the fixed parameters are attributes;
        ``reason`` carries CF ``flag_values``/``flag_meanings``. E.g.
        ``rm.to_dataset().stable.sel(e=0.5).plot()`` draws the stability region for e = 0.5.
        """
        # deferred import: loaded only when this runs, for start-up time
        import xarray as xr

        dims = ("e", self.y_name, self.x_name)
        coords = {n: (n, np.asarray(v), axis_attrs(n))
                  for n, v in (("e", self.e), (self.y_name, self.y), (self.x_name, self.x))}
        codes = sorted(REASONS)
        data = {
            "exists": (dims, self.exists, {"long_name": "the symmetric orbit exists (viable)"}),
            "stable": (dims, self.stable, {"long_name": "the symmetric orbit exists, stable"}),
            "spectral_radius": (dims, self.spectral_radius, axis_attrs("spectral_radius")),
            "xm": (dims, self.xm, axis_attrs("xm")),
            "reason": (dims, self.reason, {
                "long_name": "why no orbit exists (0: it exists)", "flag_values": codes,
                "flag_meanings": " ".join(re.sub(r"\W+", "_", REASONS[c]).strip("_")
                                          for c in codes)})}
        if self.certified is not None:
            # deferred import: loaded only when this runs, for start-up time
            from hybridpd.pair.certified import FLAG_MEANINGS, FLAG_VALUES

            data["certified"] = (dims, np.asarray(self.certified, np.int8), {
                "long_name": "certified class of the grid point's cell (interval proofs)",
                "flag_values": np.asarray(FLAG_VALUES, np.int8), "flag_meanings": FLAG_MEANINGS,
                "cells": "half-way to the neighbouring grid points; edge cells end at the "
                         "first and last points"})
        attrs = {"kind": "region_map", "case": self.case, "x_name": self.x_name,
                 "y_name": self.y_name, "fixed_names": " ".join(self.fixed),
                 **encode_attrs(self.fixed)}
        if self.metadata:
            attrs["metadata"] = encode_attrs({"m": self.metadata})["m"]
        return xr.Dataset(data, coords=coords, attrs=attrs)

    @classmethod
    def from_dataset(cls, ds) -> RegionMap:
        """Inverse of :meth:`to_dataset`."""
        a = decode_attrs(ds.attrs)
        if a.get("kind") != "region_map":
            raise ValueError("the dataset does not hold a region map (attribute kind)")
        ds = ds.transpose("e", a["y_name"], a["x_name"], ...)
        names = a["fixed_names"].split()
        return cls(a["case"], a["x_name"], a["y_name"], ds[a["x_name"]].values,
                   ds[a["y_name"]].values, ds["e"].values, {k: a[k] for k in names},
                   ds["exists"].values.astype(bool), ds["stable"].values.astype(bool),
                   ds["spectral_radius"].values, ds["xm"].values,
                   ds["reason"].values.astype(np.int64), dict(a.get("metadata") or {}),
                   ds["certified"].values.astype(np.int8) if "certified" in ds else None)

    def save(self, path) -> Path:
        """Write to ``.nc`` (netCDF) or ``.zarr`` (:meth:`to_dataset`), or ``.npz``, by suffix."""
        return save_result(self, path, lambda: (
            {"x": self.x, "y": self.y, "e": self.e, "exists": self.exists,
             "stable": self.stable, "spectral_radius": self.spectral_radius, "xm": self.xm,
             "reason": self.reason,
             **({} if self.certified is None else {"certified": self.certified})},
            {"kind": "region_map", "case": self.case, "x_name": self.x_name,
             "y_name": self.y_name, "fixed": self.fixed, **self.metadata}))


def load_region_map(path) -> RegionMap:
    """Read a :class:`RegionMap` written by :meth:`RegionMap.save`.

    Parameters
    ----------
    path : str or path
        A ``.nc``, ``.zarr`` or (earlier versions) ``.npz`` file.

    Returns
    -------
    RegionMap

    Raises
    ------
    ValueError
        If the suffix is unknown or the file holds something else.

    Examples
    --------
    >>> import tempfile, os
    >>> import hybridpd as hp
    >>> rm = hp.region_map("collocated", x=("kp", 1, 40, 4), y=("kv", 1, 40, 3), e=[0.5],
    ...                    mu=0.1, gamma=0.75, omega=5.0, progress=False)
    >>> back = hp.load_region_map(rm.save(os.path.join(tempfile.mkdtemp(), "regions.nc")))
    >>> back.stable.shape, bool((back.stable == rm.stable).all())
    ((1, 3, 4), True)
    """

    def from_npz(a, meta):
        if meta.get("kind") != "region_map":
            raise ValueError(f"{path} does not hold a region map")
        extra = {k: v for k, v in meta.items()
                 if k not in ("kind", "case", "x_name", "y_name", "fixed")}
        return RegionMap(meta["case"], meta["x_name"], meta["y_name"], a["x"], a["y"], a["e"],
                         meta["fixed"], a["exists"].astype(bool), a["stable"].astype(bool),
                         a["spectral_radius"], a["xm"], a["reason"], extra,
                         a["certified"].astype(np.int8) if "certified" in a else None)

    return load_result(RegionMap, path, from_npz)


def _region_chunk(chunk, case, n, fixed):
    """Evaluate one chunk of flattened grid points (module-level: runs in worker processes)."""
    kw = dict(fixed)
    kw.update({k: v for k, v in chunk.items()})
    kp, kv = kw.pop("kp"), kw.pop("kv")
    r = symmetric_orbits(kp, kv, case=case, n=n, **kw)
    return {"exists": r.exists, "stable": r.stable, "spectral_radius": r.spectral_radius,
            "xm": r.xm, "reason": r.reason}


def _certify_chunk(chunk, case, n, fixed, depth, xname, yname):
    """Certify one chunk of grid cells (module-level: runs in worker processes)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.certified import certify_cells

    kw = dict(fixed)
    kw[xname] = (chunk["x_lo"], chunk["x_hi"])
    kw[yname] = (chunk["y_lo"], chunk["y_hi"])
    r = certify_cells(case, n=n, depth=depth, e=chunk["e"], **kw)
    return {"certified": r.flags, "certified_reason": r.reasons}


def _certify(case, n, fixed, depth, xname, xs, yname, ys, es, *, executor, max_workers, store,
             progress):
    """The certified flags of every cell of the grid, shape ``(len(e), len(y), len(x))``."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.certified import cell_boxes, cell_edges
    from hybridpd.sweeps.sweep import run_sweep

    cells = cell_boxes(xname, cell_edges(xs), yname, cell_edges(ys))
    (xl, xh), (yl, yh) = cells[xname], cells[yname]
    shape = (es.size,) + xl.shape
    rep = lambda a: np.broadcast_to(a, shape).ravel()
    points = {"e": np.repeat(es, xl.size), "x_lo": rep(xl), "x_hi": rep(xh), "y_lo": rep(yl),
              "y_hi": rep(yh)}
    if store is not None:
        p = Path(store)
        store = p.with_name(f"{p.stem}.certified{p.suffix}")
    out = run_sweep(_certify_chunk, points, chunk_size=min(points["e"].size, 4096),
                    executor=executor, max_workers=max_workers, store=store, progress=progress,
                    label=f"certify {case} e={','.join(f'{v:g}' for v in es)}",
                    func_kwargs={"case": case, "n": n, "fixed": fixed, "depth": depth,
                                 "xname": xname, "yname": yname},
                    metadata={"kind": "certified_region_sweep", "version": 1}).outputs
    return np.asarray(out["certified"]).reshape(shape).astype(np.int8)


def region_map(case="collocated", *, x=("kp", 0.1, 50.0, 200), y=("kv", 0.1, 50.0, 200),
               e=(0.1, 0.5, 0.9), mu=None, omega=None, L=None, gamma=None, x10=1.0,
               m2=1.0, n=1,
               kp=None, kv=None, executor="serial", max_workers=None, chunk_size=None,
               store=None, progress=True, certify=False, certify_depth=3) -> RegionMap:
    """Existence and stability of the symmetric orbit over a grid of two parameters.

    Parameters
    ----------
    case : {"collocated", "noncollocated"}
    x, y : (name, MIN, MAX, NUM)
        The swept parameters (names from :data:`AXES`), each on ``linspace(MIN, MAX, NUM)``.
    e : sequence of float
        Restitution coefficients in [0, 1] (one map each).
    mu, omega, L or gamma, x10, m2, n, kp, kv
        The fixed parameters (``L = gamma * x10`` when ``gamma`` is given). ``kp``/``kv`` are
        needed only when they are not swept.
    executor, max_workers, chunk_size, store, progress
        See :func:`hybridpd.sweeps.sweep.run_sweep`. ``"serial"`` is the default because the
        evaluation is vectorised (a 200 x 200 x 3 map takes about a second), which beats
        starting worker processes; a ``store`` (a ``.zarr`` directory) makes the sweep write
        as it goes and resume. Progress is labelled e.g. ``regions collocated e=0.1,0.5``.
        The default ``chunk_size`` is at least 16384 points (a function of the grid size
        only): the evaluation is vectorised, and smaller chunks lose to per-call overhead.
    certify : bool
        Also prove the class of every grid point's cell (the box half-way to its
        neighbours; edge cells end at the first and last points) with the interval proofs of
        :mod:`hybridpd.pair.certified`, into :attr:`RegionMap.certified` (CF flags: 0
        undecided, 1 proved stable, 2 proved unstable, 3 proved no orbit). About a second
        per thousand cells; with ``store`` it writes and resumes ``NAME.certified.zarr``
        beside it.
    certify_depth : int
        Bisections of an undecided cell (0 to 12).

    Returns
    -------
    RegionMap

    Examples
    --------
    >>> rm = region_map("collocated", x=("kp", 1, 40, 5), y=("kv", 1, 40, 4), e=[0.5],
    ...                 mu=0.1, omega=5.0, gamma=0.75)
    >>> rm.exists.shape
    (1, 4, 5)
    >>> rm = region_map("collocated", x=("kp", 9, 11, 3), y=("kv", 19, 21, 2), e=[0.5],
    ...                 mu=0.1, omega=5.0, gamma=0.75, certify=True, progress=False)
    >>> rm.certified.tolist()            # every cell proved stable
    [[[1, 1, 1], [1, 1, 1]]]
    """
    case = Case.parse(case).value
    n = check_odd_order(n)
    xname, xs = check_named_axis("x", x, AXES, min_num=2, positive=True)
    yname, ys = check_named_axis("y", y, AXES, min_num=2, positive=True)
    if xname == yname:
        raise ValueError(f"x and y must sweep different parameters, got {xname!r} twice")
    es = np.atleast_1d(check_array("e", e, lo=0.0, lo_open=False, hi=1.0))
    if es.size == 0 or es.ndim != 1:
        raise ValueError("e must be a non-empty list of restitution coefficients")
    if not np.all(np.isfinite(es)) or np.any((es < 0) | (es > 1)):
        raise ValueError(f"e must lie in [0, 1], got {es.tolist()}")
    swept = (xname, yname)
    if "x10" not in swept:
        x10 = check_positive("x10", x10)
    if "L" in swept:
        if gamma is not None or L is not None:
            raise ValueError("L is a swept axis: do not give L or gamma as well")
    elif (L is None) == (gamma is None):
        raise ValueError("give exactly one of L or gamma (L = gamma * x10)")
    elif L is None and "x10" in swept:
        raise ValueError("with x10 swept give L, not gamma (L would change along the axis)")
    else:
        L = check_positive("L", L) if L is not None else check_positive("gamma", gamma) * x10
    given = {"mu": mu, "omega": omega, "L": L, "x10": x10, "m2": m2, "kp": kp, "kv": kv}
    fixed = {}
    for nm, val in given.items():
        if nm in swept:
            continue
        if val is None:
            raise ValueError(f"{nm} must be given when it is not a swept axis")
        fixed[nm] = check_positive(nm, val)

    E, Y, X = np.meshgrid(es, ys, xs, indexing="ij")
    points = {"e": E.ravel(), yname: Y.ravel(), xname: X.ravel()}
    shape = E.shape
    kwargs = {"case": case, "n": n, "fixed": fixed}
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.sweeps.sweep import default_chunk_size, run_sweep

    label = f"regions {case} e={','.join(f'{v:g}' for v in es)}"
    if chunk_size is None:
        size = E.size
        chunk_size = min(size, max(default_chunk_size(size), _MIN_REGION_CHUNK))
    out = run_sweep(_region_chunk, points, chunk_size=chunk_size, executor=executor,
                    max_workers=max_workers, store=store, progress=progress, label=label,
                    func_kwargs=kwargs, metadata={"kind": "region_sweep", "version": 1}).outputs
    get = lambda k: np.asarray(out[k]).reshape(shape)
    certified = None
    if certify:
        certified = _certify(case, n, fixed, check_int("certify_depth", certify_depth, 0, 12),
                             xname, xs, yname, ys, es, executor=executor,
                             max_workers=max_workers, store=store, progress=progress)
    return RegionMap(case, xname, yname, xs, ys, es, {**fixed, "n": n},
                     get("exists").astype(bool), get("stable").astype(bool),
                     get("spectral_radius").astype(float), get("xm").astype(float),
                     get("reason").astype(np.int64), certified=certified)
