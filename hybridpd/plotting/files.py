"""Draw any result file that hybridpd writes (:func:`plot_file`, ``hybridpd plot``).

The kind of a file is read from the file itself, never from its name:

* ``.nc`` / ``.zarr`` datasets: their ``kind`` attribute (``region_map``, ``basin``);
* ``.npz`` archives: the ``kind`` of their JSON metadata (the same kinds; see
  :func:`hybridpd._results.write_npz`);
* ``.json`` documents: their ``kind`` key (``trajectory``, written by
  ``hybridpd simulate --out``).

Anything else is refused with a ValueError that says why.
"""
from __future__ import annotations

import json
import os
import textwrap
from pathlib import Path

import numpy as np

__all__ = ["KINDS", "OPTIONS", "file_kind", "plot_file"]

#: The kinds of result file :func:`plot_file` draws.
KINDS = ("region_map", "basin", "attractor_basin", "bifurcation_diagram", "branch",
         "trajectory", "model_basin", "model_diagram")

#: The drawing options and the kinds that take them.
OPTIONS = {"title": KINDS, "coordinate": ("bifurcation_diagram", "model_diagram"),
           "quantity": ("branch",)}


def _unreadable(path, why) -> ValueError:
    return ValueError(f"{str(path)!r} is not a result file hybridpd can plot ({why})")


def file_kind(path: str | os.PathLike) -> str:
    """The kind of result held in `path` (one of :data:`KINDS`), read from its metadata.

    Raises
    ------
    ValueError
        The file does not exist, cannot be read, or is not a hybridpd result.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise ValueError(f"path must be a file path, got {path!r}")
    p = Path(path)
    if not p.exists():
        raise ValueError(f"{str(p)!r} does not exist")
    try:
        kind = _read_kind(p)
    except ValueError:
        raise
    except Exception as exc:  # noqa: BLE001 - any reader's failure on a foreign or corrupt
        # file (zip, HDF5, JSON, Zarr errors of many types) becomes one line naming the file
        raise _unreadable(p, f"{type(exc).__name__}: {exc}".splitlines()[0]) from None
    if kind not in KINDS:
        raise _unreadable(p, f"kind {kind!r}" if kind else "no hybridpd metadata")
    return kind


def _read_kind(p: Path):
    if p.is_dir() or _magic(p, b"CDF") or _magic(p, b"\x89HDF"):
        # deferred import: loaded only when this runs, for start-up time
        import xarray as xr

        from hybridpd._results import decode_attrs

        engine = "zarr" if p.is_dir() else "netcdf4"
        with xr.open_dataset(p, engine=engine) as ds:
            return decode_attrs(ds.attrs).get("kind")
    if _magic(p, b"PK"):
        with np.load(p, allow_pickle=False) as z:
            if "__metadata__" in z.files:
                return json.loads(str(z["__metadata__"][()])).get("kind")
        return None
    try:
        with open(p, encoding="utf-8") as fh:
            doc = json.load(fh)
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise _unreadable(p, "neither a netCDF file, a Zarr store, an .npz archive nor a "
                             "JSON document") from None
    return doc.get("kind") if isinstance(doc, dict) else None


def _magic(p: Path, head: bytes) -> bool:
    with open(p, "rb") as fh:
        return fh.read(len(head)) == head


def plot_file(path: str | os.PathLike, **options):
    """Draw the result held in `path` and return the Figure.

    Parameters
    ----------
    path : str or os.PathLike
        A region map, basin, bifurcation diagram or continued branch (``.nc``, ``.zarr``,
        ``.npz``), or a trajectory (``.json`` from
        ``hybridpd simulate --out``).
    **options
        ``title`` (any kind); ``coordinate`` (bifurcation diagrams: ``phi, z1, z2, z4, x1,
        y1, x2, y2``); ``quantity`` (branches: see
        :func:`hybridpd.plotting.branches.plot_branch`). ``None`` means the default.

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.pair.continuation import continue_symmetric
    >>> br = continue_symmetric(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0, "kv", 23.0)
    >>> p = br.save(Path(tempfile.mkdtemp()) / "branch.nc")
    >>> file_kind(p)
    'branch'
    >>> plot_file(p, quantity="margin").axes[0].get_xlabel()
    '$k_v$ (force$\\\\cdot$time/length)'
    """
    kind = file_kind(path)
    options = {k: v for k, v in options.items() if v is not None}
    for k in options:
        if k not in OPTIONS:
            raise ValueError(f"unknown plot option {k!r}; use one of {', '.join(OPTIONS)}")
        if kind not in OPTIONS[k]:
            raise ValueError(f"option {k} does not apply to a {kind.replace('_', ' ')} "
                             f"(only to: {', '.join(OPTIONS[k])})")
    return _DRAW[kind](path, **options)


def _region_map(path, title=None):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.plotting.regions import plot_region_panels
    from hybridpd.sweeps.regions import load_region_map

    return plot_region_panels(load_region_map(path), title=title)


def _basin(path, title=None):
    """Every basin file (the kinds ``attractor_basin`` and ``model_basin`` of earlier
    versions too): the one basin result, drawn by the one basin figure."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.analysis.basins import load_basin
    from hybridpd.plotting.basins import plot_basin

    return plot_basin(load_basin(path), title=title)


def _diagram(path, title=None, coordinate=None):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.analysis.diagrams import load_diagram
    from hybridpd.plotting.bifurcation import plot_bifurcation

    return plot_bifurcation(load_diagram(path), coordinate=coordinate, title=title)


_BRANCH_UNITS = {"spectral_radius": "(1)", "multipliers": "(1)", "margin": "(length)",
                 "xm": "(length)", "min_impact_speed": "(length/time)", 0: "(time)",
                 1: "(length)", 2: "(length/time)", 3: "(length/time)"}


def _branch(path, title=None, quantity="spectral_radius"):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.analysis.continuation import load_branch
    from hybridpd.plotting.branches import plot_branch
    from hybridpd.plotting.style import DOUBLE, axis_label, house_figure, house_style

    br = load_branch(path)
    with house_style():
        fig = house_figure(DOUBLE, 3.8)
        ax = fig.add_subplot(1, 1, 1)
        plot_branch(br, ax=ax, quantity=quantity)
        ax.set_xlabel(axis_label(br.parameter_name))
        unit = _BRANCH_UNITS.get(quantity)
        if unit and not ax.get_ylabel().endswith(")"):
            ax.set_ylabel(f"{ax.get_ylabel()} {unit}".strip())
        # the termination names why and where it stopped (the corrector's failure at the
        # smallest step, say): shortened to one line under the title, whole in the file
        family = " ".join(filter(None, (br.metadata.get("case"), br.metadata.get("family"))))
        ax.set_title(title if title is not None else
                     f"{family} branch in {br.parameter_name} ({len(br)} points)\nstopped: "
                     + textwrap.shorten(str(br.termination), 100, placeholder=" ..."))
    return fig


def _trajectory(path, title=None):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.plotting.trajectory import plot_trajectory_samples

    with open(path, encoding="utf-8") as fh:
        doc = json.load(fh)
    try:
        s = doc["samples"]
        imp = doc.get("impacts", [])
        return plot_trajectory_samples(
            s["t"], s["q"], s["v"], dofs=doc["dofs"], contacts=doc.get("contacts", ()),
            impact_times=[d["t"] for d in imp], impact_contacts=[d["contact"] for d in imp],
            impact_states=[d["pre"] for d in imp] if imp else None,
            sticking=doc.get("sticking", ()),
            title=title if title is not None else doc.get("title"))
    except (KeyError, TypeError) as exc:
        raise _unreadable(path, f"trajectory without {exc}") from None


_DRAW = {"region_map": _region_map, "basin": _basin, "attractor_basin": _basin,
         "bifurcation_diagram": _diagram, "branch": _branch, "trajectory": _trajectory,
         "model_basin": _basin, "model_diagram": _diagram}
