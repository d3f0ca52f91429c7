"""A basin of attraction on a 2-D slice of a section: labels on a grid, saved and read back.

The result type of every basin mapper, the impact pair's closed-form one and the general one
on any automaton alike, with its labelled (xarray) form and files (``.nc``, ``.zarr``, and
``.npz`` of earlier versions). Labels are those of :mod:`hybridpd.analysis.labels`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.analysis.labels import LABELS
from hybridpd.sweeps.labelled import (
    axis_attrs,
    decode_attrs,
    encode_attrs,
    load_result,
    save_result,
)

__all__ = ["BasinResult", "load_basin"]


def load_basin(path) -> BasinResult:
    """Read a :class:`BasinResult` written by :meth:`BasinResult.save`.

    Parameters
    ----------
    path : str or path
        A ``.nc``, ``.zarr`` or (earlier versions) ``.npz`` file.

    Returns
    -------
    BasinResult

    Raises
    ------
    ValueError
        If the suffix is unknown or the file holds something else.

    Examples
    --------
    >>> import tempfile, os
    >>> import hybridpd as hp
    >>> orb = hp.symmetric_orbit(hp.ImpactPair(0.1, 0.5, 0.75), hp.PDGains(10, 20), 5.0)
    >>> from hybridpd.pair.basins import basin_of_attraction
    >>> b = basin_of_attraction(hp.ImpactMapper.from_orbit(orb, n_iter=100),
    ...                         (-1, 3, 3), (-1, 5, 2), progress=False)
    >>> path = b.save(os.path.join(tempfile.mkdtemp(), "basin.nc"))
    >>> bool((hp.load_basin(path).labels == b.labels).all())
    True
    """

    def from_npz(a, meta):
        if meta.pop("kind", None) != "basin":
            raise ValueError(f"{path} does not hold a basin")
        frac = float(meta.pop("converged_fraction"))
        meta.pop("label_names", None)
        return BasinResult(a["x1"], a["y1"], a["labels"], a["iterations"], a["fixed_point"],
                           frac, meta)

    return load_result(BasinResult, path, from_npz)


@dataclass(frozen=True)
class BasinResult:
    """A basin of attraction on a 2-D slice of the section.

    Attributes
    ----------
    x1, y1 : ndarray
        Grid axes (primary-mass position and velocity at the impact).
    labels : ndarray of int, shape (len(y1), len(x1))
        Indexed ``[y1][x1]``, values into :data:`LABELS`.
    iterations : ndarray of int, same shape
        Iterations of ``P`` actually run (smaller with early exit).
    fixed_point : ndarray, shape (4,)
        ``(phi*, z1*, z2*, z4*)``; in the slice's coordinates ``x1* = z1* + L``,
        ``y1* = z2* + z4*``.
    converged_fraction : float
        Share of on-section grid points labelled converged.
    metadata : dict
        Parameters, criterion, iterations, certified radius.
    """

    x1: np.ndarray
    y1: np.ndarray
    labels: np.ndarray
    iterations: np.ndarray
    fixed_point: np.ndarray
    converged_fraction: float
    metadata: dict = field(default_factory=dict)
    __repr__ = compact_repr

    @property
    def label_names(self) -> tuple:
        return LABELS

    def to_dataset(self):
        """The basin as an :class:`xarray.Dataset` with dimensions ``(y1, x1)``.

        ``labels`` carries CF ``flag_values``/``flag_meanings`` (the label names); the
        parameters, the fixed point and the converged fraction are attributes. E.g.
        ``(b.to_dataset().labels == 0).plot()`` draws the basin.
        """
        # deferred import: loaded only when this runs, for start-up time
        import xarray as xr

        dims = ("y1", "x1")
        names = list(self.label_names)
        data = {
            "labels": (dims, self.labels, {"long_name": "label of the initial condition",
                                           "flag_values": list(range(len(names))),
                                           "flag_meanings": " ".join(names)}),
            "iterations": (dims, self.iterations,
                           {"long_name": "iterations of the impact map actually run"})}
        coords = {n: (n, np.asarray(getattr(self, n)), axis_attrs(n)) for n in dims}
        attrs = {"kind": "basin", "converged_fraction": self.converged_fraction,
                 "fixed_point": [float(v) for v in self.fixed_point],
                 "fixed_point_coordinates": "phi z1 z2 z4", **encode_attrs(self.metadata)}
        return xr.Dataset(data, coords=coords, attrs=attrs)

    @classmethod
    def from_dataset(cls, ds) -> BasinResult:
        """Inverse of :meth:`to_dataset`."""
        a = decode_attrs(ds.attrs)
        if a.pop("kind", None) != "basin":
            raise ValueError("the dataset does not hold a basin (attribute kind)")
        ds = ds.transpose("y1", "x1")
        frac = float(a.pop("converged_fraction"))
        fp = np.asarray(a.pop("fixed_point"), float)
        a.pop("fixed_point_coordinates", None)
        return cls(ds["x1"].values, ds["y1"].values, ds["labels"].values.astype(np.int64),
                   ds["iterations"].values.astype(np.int64), fp, frac, a)

    def save(self, path):
        """Write to ``.nc`` (netCDF) or ``.zarr`` (:meth:`to_dataset`), or ``.npz``, by suffix
        (see :func:`load_basin`)."""
        return save_result(self, path, lambda: (
            {"x1": self.x1, "y1": self.y1, "labels": self.labels,
             "iterations": self.iterations, "fixed_point": self.fixed_point},
            {"kind": "basin", "converged_fraction": self.converged_fraction,
             "label_names": list(LABELS), **self.metadata}))

    def area(self, label: str = "converged") -> float:
        """Area (in ``x1``-``y1`` units) of the grid cells with ``label``."""
        k = LABELS.index(label)
        dx = (self.x1[-1] - self.x1[0]) / max(len(self.x1) - 1, 1)
        dy = (self.y1[-1] - self.y1[0]) / max(len(self.y1) - 1, 1)
        return float((self.labels == k).sum() * dx * dy)
