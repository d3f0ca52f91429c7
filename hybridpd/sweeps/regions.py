"""Region maps of any family of maps: where a periodic orbit exists and is stable over a grid
of two parameters.

One result, :class:`RegionMap`, for every family: arrays indexed ``[layer, iy, ix]``, the
layers being the impact pair's restitution coefficients ``e`` (one map each) or, for a model
file, the one restitution of its section contact (NaN for a compliant contact). Beside the
four answers every family gives (``exists``, ``stable``, ``spectral_radius``, ``reason``) a
family records what it knows in :attr:`RegionMap.variables` (the pair's reference amplitude
``xm`` and certified classes ``certified``; a model's statuses, returns per period
``period``, section points and modes of up to two orbits per cell, ...), each also readable
as an attribute (``rm.xm``).

One function, :func:`region_map`, over a family: any object with a ``classify_grid(x, y,
**options) -> RegionMap`` hook. The impact pair's
:class:`~hybridpd.pair.regions.SymmetricFamily` classifies a grid in closed form (vectorised,
and certified with ``certify=True``); a model file's
:class:`~hybridpd.sweeps.model_regions.ModelSearch` searches the orbits of a section cell by
cell by Newton from the neighbours' orbits, seeded by simulation, in tiles on any executor.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from hybridpd._results import Result, WithExtras, compact_repr, decode_attrs, encode_attrs, jsonable

__all__ = ["UNITS", "RegionMap", "axis_attrs", "load_region_map", "region_map"]

#: Units and long names of parameters, coordinates and variables of the datasets. The model is
#: written in consistent but unspecified units (CONVENTIONS.md), so units name dimensions
#: (``"length/time"``); ``"1"`` means dimensionless.
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

#: Names of the trailing dimensions of the variables that have one.
_TRAILING = {"section_point": "coordinate", "section_point2": "coordinate",
             "signature": "jump", "signature2": "jump",
             "section_state": "state", "section_state2": "state"}
_CORE = ("exists", "stable", "spectral_radius", "reason")


@dataclass(frozen=True, eq=False)
class RegionMap(WithExtras, Result):
    """Existence and stability of periodic orbits over a grid of two parameters (module
    docstring). Arrays are indexed ``[layer, iy, ix]``.

    Attributes
    ----------
    case : str
        The impact pair's case, or the model file's name.
    x_name, y_name : str
        Swept parameters (the pair's names, or a model file's dotted paths).
    x, y : ndarray
        Grid axes.
    e : ndarray
        Layers: restitution coefficients (NaN: a compliant contact).
    fixed : dict
        Everything else that defines the map (the pair's parameters; a model's ``model``
        and ``section_*`` settings).
    exists, stable : ndarray of bool, shape (len(e), len(y), len(x))
        An orbit exists; one exists and is stable.
    spectral_radius : ndarray, same shape
        Of the (first, stable first) orbit; NaN where none.
    reason : ndarray of int, same shape
        0 where an orbit exists, else why not (codes of ``metadata["reasons"]``).
    variables : dict of str to ndarray
        Per-cell variables of the family, each ``(len(e), len(y), len(x), ...)``; readable
        as attributes. Classified ones carry their flags in ``metadata["flags"]``.
    metadata : dict
        ``reasons`` (code -> text), ``flags`` (variable -> ``{"values", "meanings"}``) and
        the family's own (a model's ``spec``, ``coords``, ``sig_table``, ...).

    Examples
    --------
    >>> import numpy as np
    >>> rm = RegionMap("collocated", "kp", "kv", np.array([1.0, 2.0]), np.array([3.0]),
    ...                np.array([0.5]), {}, np.ones((1, 1, 2), bool), np.zeros((1, 1, 2), bool),
    ...                np.full((1, 1, 2), 1.5), np.zeros((1, 1, 2), int),
    ...                {"period": np.array([[[1, 2]]])})
    >>> rm.fraction("exists").tolist(), rm.period.tolist()
    ([1.0], [[[1, 2]]])
    """

    kind = "region_map"
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
    reason: np.ndarray
    variables: dict = field(default_factory=dict, repr=False, metadata={"dict_skip": True})
    metadata: dict = field(default_factory=dict, repr=False)
    __repr__ = compact_repr


    @property
    def certified(self):
        """The certified class of every cell (CF flags, ``metadata["flags"]``), or None."""
        return self.variables.get("certified")

    @property
    def source(self) -> str:
        """The model file ('' for the impact pair)."""
        return str(self.fixed.get("model", ""))

    def cell_area(self) -> float:
        """Area of one grid cell in the axes' units."""
        return float((self.x[1] - self.x[0]) * (self.y[1] - self.y[0]))

    def area(self, which: str = "stable") -> np.ndarray:
        """Area per layer of the ``"exists"`` or ``"stable"`` (exists and stable) region."""
        return self._mask(which).sum(axis=(1, 2)) * self.cell_area()

    def fraction(self, which: str = "stable") -> np.ndarray:
        """Share of the grid per layer in the region."""
        return self._mask(which).mean(axis=(1, 2))

    def _mask(self, which):
        if which not in ("exists", "stable"):
            raise ValueError(f"which must be 'exists' or 'stable', got {which!r}")
        return getattr(self, which)

    def returns(self) -> np.ndarray:
        """Returns to the section per period of each cell's orbit (``k``; 1 where the family
        records none and an orbit exists, 0 where none exists)."""
        k = self.variables.get("period")
        return np.where(self.exists, 1 if k is None else np.asarray(k), 0)

    def counts(self) -> dict:
        """``{reason or status name: cells}`` (``"stable"``, ``"unstable"`` for the cells with
        an orbit)."""
        out = {"stable": int(self.stable.sum()),
               "unstable": int((self.exists & ~self.stable).sum())}
        for c, text in sorted((self.metadata.get("reasons") or {}).items(), key=lambda t:
                              int(t[0])):
            if int(c) and text not in out:
                out[text] = int(np.sum(self.reason == int(c)))
        return out

    def signature_of(self, iy: int, ix: int, which: int = 1, layer: int = 0) -> tuple:
        """The impact signature ``((guard, kind), ...)`` of orbit `which` (1 or 2) of a cell
        of a model's map (``metadata["sig_table"]``)."""
        codes = self.variables["signature" if which == 1 else "signature2"][layer, iy, ix]
        table = self.metadata.get("sig_table") or ()
        return tuple(tuple(table[c]) if c >= 0 else ("...", "cut") for c in codes if c != -1)

    def summary(self) -> str:
        """A few lines: grid, share of each class, cells with two orbits or ``k > 1``."""
        n = self.exists[0].size
        lines = [f"{self.case}: {self.x_name} x {self.y_name} = {len(self.x)} x "
                 f"{len(self.y)}" + (f" for e = {', '.join(f'{v:g}' for v in self.e)}"
                                     if len(self.e) > 1 else "")]
        for i, e in enumerate(self.e):
            c = {k: int(np.sum(m)) for k, m in (("stable", self.stable[i]),
                 ("unstable", self.exists[i] & ~self.stable[i]), ("none", ~self.exists[i]))}
            lines.append(("  " if len(self.e) == 1 else f"  e = {e:g}: ")
                         + ", ".join(f"{k} {100 * v / n:.1f}%" for k, v in c.items() if v))
        k = self.returns()
        ks = {int(v): int(np.sum(k[self.exists] == v)) for v in np.unique(k[self.exists])}
        if any(v > 1 for v in ks):
            lines.append("  returns to the section per period (k): " + ", ".join(
                f"k = {v}: {c} cells" for v, c in sorted(ks.items())))
        if "n_orbits" in self.variables:
            lines.append("  cells with two or more orbits: "
                         f"{int(np.sum(self.variables['n_orbits'] > 1))}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-ready form (``regions --json``): every field, arrays ``[layer][iy][ix]``, the
        swept axes also under their names, ``counts``."""
        d = super().to_dict()
        d.update({k: jsonable(v) for k, v in self.variables.items()})
        d.update({self.x_name: d["x"], self.y_name: d["y"], "counts": self.counts()})
        return d

    def to_dataset(self):
        """The map as an :class:`xarray.Dataset` with dimensions ``(e, y_name, x_name)``
        (plus a trailing one for vector variables); coordinates carry ``units`` and
        ``long_name``, classified variables CF ``flag_values``/``flag_meanings``, the fixed
        parameters are attributes. E.g. ``rm.to_dataset().stable.sel(e=0.5).plot()``."""
        # deferred import: loaded only when this runs, for start-up time
        import xarray as xr

        dims = ("e", self.y_name, self.x_name)
        coords = {n: (n, np.asarray(v), axis_attrs(n))
                  for n, v in (("e", self.e), (self.y_name, self.y), (self.x_name, self.x))}
        coords_names = self.metadata.get("coords")
        if coords_names:
            coords["coordinate"] = ("coordinate", [str(c) for c in coords_names])
        flags = dict(self.metadata.get("flags") or {})
        reasons = self.metadata.get("reasons") or {}
        if reasons:
            codes = sorted(int(c) for c in reasons)
            flags["reason"] = {"values": codes, "meanings": " ".join(
                re.sub(r"\W+", "_", reasons[str(c)] if str(c) in reasons else reasons[c])
                .strip("_") for c in codes)}
        data = {}
        for name, a in {**{k: getattr(self, k) for k in _CORE}, **self.variables}.items():
            a = np.asarray(a)
            vd = dims + tuple(_TRAILING.get(name, f"{name}_{j}") for j in range(a.ndim - 3))
            attrs = dict(axis_attrs(name)) if name in ("spectral_radius", "xm") else {}
            if name in flags:
                attrs.update(flag_values=np.asarray(flags[name]["values"], a.dtype),
                             flag_meanings=flags[name]["meanings"])
            data[name] = (vd, a, attrs)
        attrs = {"kind": self.kind, "case": self.case, "x_name": self.x_name,
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
        fixed = {k: a[k] for k in a["fixed_names"].split()}
        var = {k: ds[k].values for k in ds.data_vars if k not in _CORE}
        return cls(a["case"], a["x_name"], a["y_name"], ds[a["x_name"]].values,
                   ds[a["y_name"]].values, ds["e"].values, fixed,
                   ds["exists"].values.astype(bool), ds["stable"].values.astype(bool),
                   ds["spectral_radius"].values, ds["reason"].values.astype(np.int64), var,
                   dict(a.get("metadata") or {}))


def load_region_map(path) -> RegionMap:
    """Read a :class:`RegionMap` written by :meth:`RegionMap.save`.

    Parameters
    ----------
    path : str or path
        A ``.nc``, ``.zarr`` or ``.npz`` file.

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
    >>> from hybridpd.pair.regions import SymmetricFamily
    >>> fam = SymmetricFamily("collocated", e=[0.5], mu=0.1, gamma=0.75, omega=5.0)
    >>> rm = hp.region_map(fam, x=("kp", 1, 40, 4), y=("kv", 1, 40, 3), progress=False)
    >>> back = hp.load_region_map(rm.save(os.path.join(tempfile.mkdtemp(), "regions.nc")))
    >>> back.stable.shape, bool((back.stable == rm.stable).all())
    ((1, 3, 4), True)
    """
    return RegionMap.load(path)


def region_map(family, x=None, y=None, **options) -> RegionMap:
    """Existence and stability of a family's periodic orbits over a grid of two parameters.

    Parameters
    ----------
    family : object
        A family with the hook ``classify_grid(x, y, **options) -> RegionMap``: the impact
        pair's :class:`~hybridpd.pair.regions.SymmetricFamily` (closed form, vectorised,
        ``certify=True`` proves the class of every cell) or a model file's
        :class:`~hybridpd.sweeps.model_regions.ModelSearch` (Newton across the grid from
        the neighbours' orbits, seeded by simulation).
    x, y : (name, MIN, MAX, NUM)
        The swept parameters, each on ``linspace(MIN, MAX, NUM)`` (the family's names: the
        pair's ``kp, kv, mu, L, omega, m2, x10``, a model's dotted paths).
    **options
        The family's options (executor, store, progress, ``certify``, ``tile``, ...).

    Returns
    -------
    RegionMap

    Raises
    ------
    ValueError
        A family without the hook, or bad axes or options (named).

    Examples
    --------
    >>> import hybridpd as hp
    >>> from hybridpd.pair.regions import SymmetricFamily
    >>> fam = SymmetricFamily("collocated", e=[0.5], mu=0.1, omega=5.0, gamma=0.75)
    >>> rm = hp.region_map(fam, x=("kp", 1, 40, 5), y=("kv", 1, 40, 4), progress=False)
    >>> rm.exists.shape
    (1, 4, 5)
    """
    if not callable(getattr(family, "classify_grid", None)):
        raise ValueError("family must offer classify_grid(x, y, **options) (e.g. "
                         "hybridpd.pair.regions.SymmetricFamily or "
                         "hybridpd.sweeps.model_regions.ModelSearch), got "
                         f"{type(family).__name__}")
    if x is None or y is None:
        raise ValueError("give both axes x=(name, MIN, MAX, NUM) and y=(name, MIN, MAX, NUM)")
    return family.classify_grid(x, y, **options)
