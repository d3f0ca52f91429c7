"""Generic parameter-sweep engine: chunks, executors, write-as-you-go, resume.

A *sweep* evaluates one picklable, module-level function over many points
(e.g. a flattened ``(kp, kv, e)`` grid, or the initial conditions of a basin of
attraction). The points are cut into fixed, contiguous *chunks*; each chunk is
one task handed to an executor (:mod:`hybridpd.sweeps.executors`), and each
finished chunk is (optionally) written at once to a Zarr store
(:mod:`hybridpd.sweeps.store`), so that a sweep interrupted after hours resumes
where it stopped. Progress is reported in points (:mod:`hybridpd.sweeps.progress`).

Guarantees
----------
* **Determinism.** The chunk layout depends only on the number of points and
  ``chunk_size`` (never on the executor or the worker count), and every chunk
  result is placed by its index. The outputs, and the store file by file, are
  therefore identical for the serial, process-pool and Dask executors, for any
  worker count, and for an interrupted-then-resumed sweep.
* **Nothing lost.** Each chunk is written as soon as it arrives, atomically (a
  chunk killed mid-write is recomputed on resume; an undecodable one too, with
  a warning). If a worker raises, the error is re-raised in the caller
  (:class:`ChunkError`, carrying the chunk index) and the chunks already
  finished stay on disk.
* **Never silently mixed.** The store records the sweep's *identity* (hash of
  the points, qualified name of the function, ``func_kwargs``, ``metadata``,
  chunk size). Resuming with a different identity raises ``ValueError``.

The function contract
---------------------
``func(chunk_points, **func_kwargs) -> dict[str, ndarray]`` where
``chunk_points`` maps each point name to a fresh, writable 1-D array of the
chunk's ``m`` points, and each returned array has leading length ``m`` (one
row per point) with any trailing shape and a bool, integer, float or complex
dtype. Every chunk must return the same names, dtypes and trailing shapes.
For the process and Dask executors ``func`` must be importable by name in the
workers (defined at module level, not a lambda or a closure).
"""

from __future__ import annotations

import concurrent.futures as cf
import dataclasses
import json
import math
import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from hybridpd._results import Result, check_suffix, decode_attrs, encode_attrs, write_dataset
from hybridpd.sweeps.executors import (
    EXECUTORS,
    ChunkError,
    ExecutorSpec,
    _check_picklable,
    _check_positive_int,
    compute,
    resolve_executor,
)
from hybridpd.sweeps.progress import Progress
from hybridpd.sweeps.store import FORMAT, ZarrStore, check_store_path, read_store, sweep_identity

__all__ = ["EXECUTORS", "FORMAT", "ChunkError", "ExecutorSpec", "SweepResult", "default_chunk_size",
           "grid_points", "load_sweep", "resolve_executor", "run_sweep"]

# Default chunking: aim at ~256 chunks (enough for load balancing on a few
# dozen workers, few enough that per-chunk overhead stays negligible), but
# never chunks so small that a vectorised func loses its edge.
_TARGET_CHUNKS = 256
_MIN_CHUNK = 64
_MAX_CHUNK = 1 << 20
_NUMERIC_KINDS = "biufc"


def _check_bool(value: Any, name: str) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def default_chunk_size(n_points: int) -> int:
    """Default number of points per chunk for a sweep of `n_points` points.

    Depends on `n_points` only -- never on the executor or the number of
    workers -- so that the chunk layout, hence every result, is the same
    whatever runs the sweep. About 256 chunks, each of at least 64 points
    (or all points if fewer) and at most 2**20 points.

    Parameters
    ----------
    n_points : int
        Number of points in the sweep (positive).

    Returns
    -------
    int
        Chunk size, ``1 <= chunk_size <= n_points``.

    Examples
    --------
    >>> default_chunk_size(10), default_chunk_size(1000), default_chunk_size(120_000)
    (10, 64, 469)
    """
    n = _check_positive_int(n_points, "n_points")
    return min(n, min(_MAX_CHUNK, max(_MIN_CHUNK, -(-n // _TARGET_CHUNKS))))


# --------------------------------------------------------------------------
# Points
# --------------------------------------------------------------------------


def grid_points(axes: Mapping[str, Any]) -> tuple[dict[str, np.ndarray], tuple[int, ...]]:
    """Flatten a Cartesian grid into sweep points.

    Parameters
    ----------
    axes : mapping of str to 1-D array_like
        Grid axes, in order. The first axis varies slowest (C order,
        ``numpy.meshgrid(..., indexing="ij")``).

    Returns
    -------
    points : dict of str to ndarray
        One flattened coordinate array per axis, each of length
        ``prod(shape)``, ready for :func:`run_sweep`.
    shape : tuple of int
        Grid shape; ``outputs[name].reshape(shape + trailing)`` restores it
        (see :meth:`SweepResult.grid`).

    Examples
    --------
    >>> pts, shape = grid_points({"e": [0.1, 0.9], "kp": [1.0, 2.0, 3.0]})
    >>> shape, pts["e"].tolist(), pts["kp"].tolist()
    ((2, 3), [0.1, 0.1, 0.1, 0.9, 0.9, 0.9], [1.0, 2.0, 3.0, 1.0, 2.0, 3.0])
    """
    if not isinstance(axes, Mapping) or not axes:
        raise ValueError("axes must be a non-empty mapping of names to 1-D arrays")
    arrs = []
    for k, v in axes.items():
        a = np.asarray(v)
        if a.ndim != 1 or a.size == 0:
            raise ValueError(f"axes[{k!r}] must be a non-empty 1-D array, got shape {a.shape}")
        arrs.append(a)
    mesh = np.meshgrid(*arrs, indexing="ij")
    return {k: m.reshape(-1) for k, m in zip(axes, mesh)}, tuple(a.size for a in arrs)


def _normalize_points(points: Any, names: Sequence[str] | None,
                      allow_nan: bool) -> dict[str, np.ndarray]:
    allowed = "a dict of equally long 1-D numeric arrays, or a 2-D numeric array of shape (N, d)"
    if isinstance(points, Mapping):
        if names is not None:
            raise ValueError("names applies only when points is a 2-D array; dict keys already "
                             "name the points")
        if not points:
            raise ValueError(f"points is empty; expected {allowed}")
        cols = {}
        for k, v in points.items():
            if not isinstance(k, str) or not k:
                raise ValueError(f"points keys must be non-empty strings, got {k!r}")
            a = np.asarray(v)
            if a.ndim != 1:
                raise ValueError(f"points[{k!r}] must be 1-D, got shape {a.shape}; expected "
                                 f"{allowed}")
            cols[k] = a
    else:
        try:
            a = np.asarray(points)
        except (TypeError, ValueError) as exc:  # ragged nested lists, ...
            raise ValueError(f"points could not be converted to an array ({exc}); expected "
                             f"{allowed}") from None
        if a.ndim != 2:
            raise ValueError(f"points must be {allowed}; got an array of shape {a.shape}")
        if a.shape[1] == 0:
            raise ValueError(f"points has no coordinates (shape {a.shape}); expected {allowed}")
        if names is None:
            names = [f"x{j}" for j in range(a.shape[1])]
        names = list(names)
        if (len(names) != a.shape[1] or len(set(names)) != len(names)
                or not all(isinstance(n, str) and n for n in names)):
            raise ValueError(f"names must be {a.shape[1]} distinct non-empty strings (one per "
                             f"column of points), got {names!r}")
        cols = {n: a[:, j] for j, n in enumerate(names)}
    lengths = {k: len(v) for k, v in cols.items()}
    if len(set(lengths.values())) != 1:
        raise ValueError(f"points arrays must all have the same length, got lengths {lengths}")
    if next(iter(lengths.values())) == 0:
        raise ValueError("points contains no point (length 0); a sweep needs at least one point")
    out = {}
    for k, a in cols.items():
        if a.dtype.kind not in _NUMERIC_KINDS:
            raise ValueError(f"points[{k!r}] has dtype {a.dtype}; allowed: bool, integer, "
                             "float, complex")
        if not allow_nan and a.dtype.kind in "fc" and np.isnan(a).any():
            raise ValueError(f"points[{k!r}] contains NaN at index "
                             f"{int(np.flatnonzero(np.isnan(a))[0])}; pass allow_nan=True if "
                             "that is intended")
        if not a.dtype.isnative:
            a = a.astype(a.dtype.newbyteorder("="))
        # A private read-only copy: the sweep must not see later changes made
        # by the caller, and the identity hash must describe what was computed.
        a = np.array(a, order="C", copy=True)
        a.flags.writeable = False
        out[k] = a
    return out


class _Assembler:
    """Places chunk outputs into preallocated arrays, checking consistency."""

    def __init__(self, n_points: int, chunk_size: int, n_chunks: int):
        self.n_points, self.chunk_size, self.n_chunks = n_points, chunk_size, n_chunks
        self.schema: dict[str, tuple[np.dtype, tuple[int, ...]]] | None = None
        self.arrays: dict[str, np.ndarray] = {}
        self.done: set[int] = set()

    def bounds(self, i: int) -> tuple[int, int]:
        start = i * self.chunk_size
        return start, min(self.n_points, start + self.chunk_size)

    def add(self, i: int, out: Any, source: str) -> dict[str, np.ndarray]:
        start, stop = self.bounds(i)
        m = stop - start
        if not isinstance(out, Mapping):
            raise ValueError(f"func must return a dict of arrays; {source} for chunk {i} gave "
                             f"{type(out).__qualname__}")
        if not out:
            raise ValueError(f"func returned no outputs for chunk {i} ({source}); it must return "
                             "at least one array")
        checked = {}
        for k in sorted(out, key=str):
            if not isinstance(k, str) or not k:
                raise ValueError(f"func output names must be non-empty strings; chunk {i} "
                                 f"returned {k!r}")
            a = np.asarray(out[k])
            if a.dtype.kind not in _NUMERIC_KINDS:
                raise ValueError(f"output {k!r} of chunk {i} ({source}) has dtype {a.dtype}; "
                                 "allowed: bool, integer, float, complex")
            if a.ndim == 0 or a.shape[0] != m:
                raise ValueError(f"output {k!r} of chunk {i} ({source}) has shape {a.shape}; "
                                 f"expected leading length {m} (one row per point of the chunk)")
            if not a.dtype.isnative:
                a = a.astype(a.dtype.newbyteorder("="))
            checked[k] = a
        schema = {k: (a.dtype, a.shape[1:]) for k, a in checked.items()}
        if self.schema is None:
            self.schema = schema
            self.arrays = {k: np.empty((self.n_points, *tr), dtype=dt)
                           for k, (dt, tr) in schema.items()}
        elif schema != self.schema:

            def fmt(s):
                return ", ".join(f"{k}: {dt} {tuple(tr)}" for k, (dt, tr) in s.items())

            raise ValueError(f"chunk {i} ({source}) returned outputs {{{fmt(schema)}}} but earlier "
                             f"chunks returned {{{fmt(self.schema)}}}; every chunk must return the "
                             "same names, dtypes and trailing shapes")
        for k, a in checked.items():
            self.arrays[k][start:stop] = a
        self.done.add(i)
        return checked


@dataclass
class SweepResult(Result):
    """Outcome of :func:`run_sweep`; a result (:class:`~hybridpd._results.Result`) whose
    dataset lays the points along one dimension ``point`` (or a grid, see :meth:`to_dataset`).

    Attributes
    ----------
    outputs : dict of str to ndarray
        One array per output of `func` (names sorted), shape
        ``(n_points, *trailing)``, in the original point order.
    points : dict of str to ndarray
        The (read-only) points, in the given order, shape ``(n_points,)``.
    metadata : dict
        The caller's metadata (JSON form).
    n_chunks : int
        Number of chunks; chunk ``i`` covers points
        ``i*chunk_size : min((i+1)*chunk_size, n_points)``.
    n_resumed : int
        Chunks loaded from the store instead of computed in this call.
    chunk_size : int
        Points per chunk.
    identity_hash : str
        SHA-256 of the sweep identity (points, func, func_kwargs, metadata,
        chunk_size).
    identity : dict
        The identity itself.
    path : pathlib.Path or None
        The Zarr store (or the file read by :func:`load_sweep`), or None without a store.
    wall_time : float
        Seconds spent in :func:`run_sweep` (0 for :func:`load_sweep`).
    compute_time : float
        Sum over chunks computed in this call of the seconds spent inside
        `func` in the workers; ``wall_time * workers - compute_time`` is the
        engine overhead (start-up, transfer, writing).
    executor : str
        Which executor computed this call's chunks, e.g. ``"processes[4]"``.
    """

    outputs: dict[str, np.ndarray]
    points: dict[str, np.ndarray]
    metadata: dict[str, Any]
    n_chunks: int
    n_resumed: int
    chunk_size: int
    identity_hash: str
    identity: dict[str, Any] = field(default_factory=dict, repr=False)
    path: Path | None = None
    wall_time: float = 0.0
    compute_time: float = 0.0
    executor: str = ""
    kind = "sweep"

    @property
    def n_points(self) -> int:
        """Number of points."""
        return int(next(iter(self.points.values())).shape[0])

    @property
    def n_computed(self) -> int:
        """Chunks computed (not resumed) in this call."""
        return self.n_chunks - self.n_resumed

    def grid(self, name: str, shape: Sequence[int]) -> np.ndarray:
        """Output `name` reshaped to a grid: ``shape + trailing`` (see :func:`grid_points`)."""
        a = self.outputs[name]
        return a.reshape(tuple(shape) + a.shape[1:])

    def __repr__(self) -> str:
        outs = ", ".join(f"{k}{tuple(v.shape)}:{v.dtype}" for k, v in self.outputs.items())
        return (f"SweepResult(n_points={self.n_points}, n_chunks={self.n_chunks}, "
                f"n_resumed={self.n_resumed}, outputs=[{outs}], "
                f"identity_hash={self.identity_hash[:12]!r}, path={self.path!r})")

    def to_dataset(self, grid: Mapping[str, Any] | None = None):
        """The result as an :class:`xarray.Dataset` (xarray is imported here, not before).

        Parameters
        ----------
        grid : mapping of str to 1-D array_like, optional
            The axes the points were built from with :func:`grid_points`; the outputs are
            then laid out on those dimensions (``"e", "kp", ...``) instead of ``"point"``.

        Returns
        -------
        xarray.Dataset
            One variable per output (trailing dimensions ``"<name>_dim1", ...``), the points
            as coordinates, the metadata and the sweep's identity as attributes.
        """
        # deferred import: loaded only when this runs, for start-up time
        import xarray as xr

        from hybridpd.sweeps.store import canonical_json

        if grid is None:
            dims: tuple[str, ...] = ("point",)
            shape: tuple[int, ...] = (self.n_points,)
            coords = {k: ("point", v) for k, v in self.points.items()}
        else:
            pts, shape = grid_points(grid)
            if set(pts) - set(self.points) or any(
                    not np.array_equal(pts[k], self.points[k]) for k in pts):
                raise ValueError("grid does not generate this sweep's points (see grid_points)")
            dims = tuple(pts)
            coords = {k: np.asarray(v) for k, v in grid.items()}
        data = {}
        for k, v in self.outputs.items():
            tr = v.shape[1:]
            data[k] = (dims + tuple(f"{k}_dim{j + 1}" for j in range(len(tr))),
                       v.reshape(shape + tr))
        info = {"identity": self.identity, "identity_hash": self.identity_hash,
                "chunk_size": self.chunk_size, "n_chunks": self.n_chunks}
        attrs = {"kind": "sweep", **encode_attrs(self.metadata),
                 "hybridpd_sweep": canonical_json(info)}
        return xr.Dataset(data, coords=coords, attrs=attrs)

    @classmethod
    def from_dataset(cls, ds) -> SweepResult:
        """Inverse of :meth:`to_dataset` (without `grid`); ``ValueError`` for another dataset."""
        if ds.attrs.get("kind") != cls.kind or "hybridpd_sweep" not in ds.attrs \
                or "point" not in ds.dims:
            raise ValueError("the dataset does not hold a hybridpd sweep result laid out by "
                             "point (attributes kind and hybridpd_sweep)")
        info = json.loads(ds.attrs["hybridpd_sweep"])
        points = {k: ds[k].values for k in info["identity"]["points"]["names"]}
        meta = decode_attrs({k: v for k, v in ds.attrs.items()
                             if k not in ("kind", "hybridpd_sweep")})
        return _loaded(points, {k: ds[k].values for k in ds.data_vars}, info, meta, None)

    def save(self, path: str | os.PathLike) -> Path:
        """Write this result; the format follows the suffix of `path`.

        ``.zarr``: a complete sweep store (the layout :func:`run_sweep` writes); ``.nc`` and
        ``.npz``: :meth:`to_dataset` (the one writer of results). All three are read back by
        :func:`load_sweep`.
        """
        p = Path(path)
        if check_suffix(p, "path") != ".zarr":
            return write_dataset(self.to_dataset(), p)
        if p.exists():
            raise ValueError(f"path {str(p)!r} exists; remove it or choose another name")
        st = ZarrStore(p, self.identity, self.identity_hash, self.n_points, self.chunk_size,
                       self.n_chunks)
        st.open(self.points, resume=False)
        for i in range(self.n_chunks):
            a, b = st.bounds(i)
            st.write_chunk(i, {k: v[a:b] for k, v in self.outputs.items()})
        st.finish()
        return p


def _loaded(points, outputs, info, meta, path) -> SweepResult:
    for a in points.values():
        a.flags.writeable = False
    return SweepResult(outputs=outputs, points=points, metadata=meta,
                       n_chunks=int(info["n_chunks"]), n_resumed=int(info["n_chunks"]),
                       chunk_size=int(info["chunk_size"]), identity_hash=info["identity_hash"],
                       identity=info["identity"], path=path, executor="")


def load_sweep(path: str | os.PathLike) -> SweepResult:
    """Load a finished sweep: a Zarr store, or a ``.nc`` or ``.npz`` file.

    Parameters
    ----------
    path : str or os.PathLike
        A store written by :func:`run_sweep` (or :meth:`SweepResult.save` to ``.zarr``), or
        a ``.nc`` or ``.npz`` file written by :meth:`SweepResult.save`.

    Returns
    -------
    SweepResult
        With ``n_resumed == n_chunks`` and zero timings.
    """
    p = Path(path)
    if p.suffix in (".nc", ".npz"):
        return dataclasses.replace(SweepResult.load(p), path=p)
    return _loaded(*read_store(p), p)


def run_sweep(func: Callable[..., Mapping[str, Any]], points: Mapping[str, Any] | np.ndarray, *,
              chunk_size: int | None = None, executor: Any = "processes",
              max_workers: int | None = None, store: str | os.PathLike | None = None,
              resume: bool = True, progress: bool = True, label: str | None = None,
              metadata: Mapping[str, Any] | None = None,
              func_kwargs: Mapping[str, Any] | None = None, names: Sequence[str] | None = None,
              allow_nan: bool = False, timeout: float | None = None) -> SweepResult:
    """Evaluate `func` over all points, chunk by chunk, optionally on disk.

    Parameters
    ----------
    func : callable
        ``func(chunk_points, **func_kwargs) -> dict[str, array_like]``.
        `chunk_points` maps each point name to a fresh writable 1-D array of
        the chunk's ``m`` points; every returned array must have leading
        length ``m`` (any trailing shape; bool, integer, float or complex),
        and all chunks must return the same names, dtypes and trailing
        shapes. Must be a module-level (picklable) function for the process
        and Dask executors. Its identity is its module and qualified name:
        changing its code does not change the identity, so put a version
        string in `metadata` when results of an edited function must not be
        resumed.
    points : dict of str to 1-D array_like, or 2-D array_like of shape (N, d)
        The points, e.g. a flattened grid (see :func:`grid_points`). A 2-D
        array's columns are named by `names` (default ``"x0", "x1", ...``).
        Copied (the sweep does not see later changes).
    chunk_size : int, optional
        Points per chunk; default :func:`default_chunk_size` (a function of
        N only). Part of the identity: it fixes the chunk layout.
    executor : {"processes", "serial", "dask"}, scheduler address, Executor or distributed.Client
        See :func:`resolve_executor` (``"tcp://host:8786"``: an existing Dask
        cluster). Never changes the results.
    max_workers : int, optional
        Workers for pools created here (default: all usable cores, capped at
        the number of chunks left).
    store : str or os.PathLike, optional
        Directory of a Zarr store (e.g. ``"run.zarr"``), written as the sweep
        goes: one Zarr chunk per sweep chunk and output, the identity in its
        attributes (see :mod:`hybridpd.sweeps.store`). Without a store nothing
        is written.
    resume : bool, default True
        Reuse a matching store: a complete store is returned as is, finished
        chunks are loaded instead of recomputed. A store holding a different
        sweep raises ``ValueError``. With False, the store is deleted first
        and everything is recomputed.
    progress : bool or callable, default True
        Report progress on stderr in points (a tqdm bar on a terminal, a
        plain line every ~10 s otherwise; nothing for runs under ~2 s); see
        :class:`hybridpd.sweeps.progress.Progress`. Never writes to stdout. A callable
        ``progress(done, total)`` is called instead (no report on stderr) with the points
        done so far and in all, once before the first chunk and after each chunk, in the
        calling process (a page's progress bar).
    label : str, optional
        What runs, shown by the progress report (default: the function's name).
    metadata : dict, optional
        JSON-compatible data stored in the store's attributes and part of the
        identity (e.g. the fixed model parameters, a code version).
    func_kwargs : dict, optional
        Extra keyword arguments of `func`, part of the identity (numpy arrays
        by content hash). Must be JSON-describable (see the error message)
        and picklable for the process/Dask executors.
    names : sequence of str, optional
        Column names when `points` is a 2-D array.
    allow_nan : bool, default False
        Accept NaN coordinates (refused by default: usually a bug upstream).
    timeout : float, optional
        Seconds to wait for the *next* chunk to finish before raising
        ``TimeoutError`` (so a hung worker cannot hang the sweep); pools the
        sweep created are then terminated. Ignored by ``"serial"``.

    Returns
    -------
    SweepResult
        Outputs in original point order, identical for every executor,
        worker count and resume history.

    Raises
    ------
    ValueError
        Invalid parameters (the message names the parameter and the allowed
        values), invalid func outputs (naming the chunk), or a store holding
        a different sweep.
    ChunkError
        `func` raised for a chunk (original exception chained). Chunks
        finished before are saved; rerun to resume.
    TimeoutError
        No chunk finished within `timeout` seconds.

    Notes
    -----
    Results are identical across executors as long as `func` itself is
    deterministic for a given chunk. Dask workers run with one BLAS thread;
    elementwise numpy code is unaffected, large BLAS products may differ in
    the last bit between executors.

    Examples
    --------
    The process and Dask executors need `func` importable by name (a
    module-level function); the in-process ``"serial"`` executor does not:

    >>> import numpy as np
    >>> def norm(chunk, *, p=2.0):
    ...     r = (np.abs(chunk["x"]) ** p + np.abs(chunk["y"]) ** p) ** (1 / p)
    ...     return {"r": r, "inside": r < 1.0, "xy": np.stack([chunk["x"], chunk["y"]], axis=1)}
    >>> pts, shape = grid_points({"x": np.linspace(-1, 1, 5), "y": np.linspace(-1, 1, 4)})
    >>> res = run_sweep(norm, pts, executor="serial", chunk_size=6, func_kwargs={"p": 2.0})
    >>> res.n_chunks, res.outputs["xy"].shape, int(res.grid("inside", shape).sum())
    (4, (20, 2), 6)

    With a store, the sweep writes as it goes and a second call resumes
    (here: finds the complete store and computes nothing):

    >>> import tempfile
    >>> d = tempfile.mkdtemp() + "/norm.zarr"
    >>> a = run_sweep(norm, pts, executor="serial", chunk_size=6, store=d)
    >>> b = run_sweep(norm, pts, executor="serial", chunk_size=6, store=d)
    >>> b.n_resumed == b.n_chunks, np.array_equal(a.outputs["r"], b.outputs["r"])
    (True, True)
    """
    t0 = time.perf_counter()
    if not callable(func):
        raise ValueError(f"func must be callable, got {type(func).__qualname__}")
    resume = _check_bool(resume, "resume")
    report = progress if callable(progress) else None
    progress = False if report is not None else _check_bool(progress, "progress")
    allow_nan = _check_bool(allow_nan, "allow_nan")
    if label is not None and not isinstance(label, str):
        raise ValueError(f"label must be None or a string, got {label!r}")
    if timeout is not None:
        if (isinstance(timeout, bool)
                or not isinstance(timeout, (int, float, np.integer, np.floating))
                or not (math.isfinite(timeout) and timeout > 0)):
            raise ValueError(f"timeout must be None or a positive number of seconds, got "
                             f"{timeout!r}")
        timeout = float(timeout)
    cols = _normalize_points(points, names, allow_nan)
    n_points = len(next(iter(cols.values())))
    cs = (default_chunk_size(n_points) if chunk_size is None
          else _check_positive_int(chunk_size, "chunk_size"))
    n_chunks = -(-n_points // cs)
    if func_kwargs is None:
        func_kwargs = {}
    if not isinstance(func_kwargs, Mapping) or not all(isinstance(k, str) for k in func_kwargs):
        raise ValueError(f"func_kwargs must be None or a dict with string keys, got "
                         f"{func_kwargs!r}")
    func_kwargs = dict(func_kwargs)
    if metadata is not None and not isinstance(metadata, Mapping):
        raise ValueError(f"metadata must be None or a dict, got {type(metadata).__qualname__}")
    spec = resolve_executor(executor, max_workers)
    if spec.kind in ("processes", "scheduler") or isinstance(spec.instance,
                                                             cf.ProcessPoolExecutor):
        _check_picklable(func, func_kwargs)
    identity, identity_hash = sweep_identity(func, func_kwargs, metadata, cols, cs)

    st = None
    if store is not None:
        st = ZarrStore(check_store_path(store), identity, identity_hash, n_points, cs, n_chunks)
        if st.open(cols, resume) == "complete":
            done = load_sweep(st.path)
            done.wall_time = time.perf_counter() - t0
            done.executor = spec.label
            return done
    asm = _Assembler(n_points, cs, n_chunks)
    n_resumed = st.load_chunks(asm.add) if st is not None else 0
    pending = [i for i in range(n_chunks) if i not in asm.done]
    compute_time = 0.0
    if label is None:
        label = f"sweep {getattr(func, '__name__', type(func).__name__)}"
    with Progress(n_points, label, enabled=progress,
                  initial=sum(b - a for a, b in map(asm.bounds, asm.done))) as bar:
        if report is not None:
            report(bar.n, n_points)

        def on_result(i: int, out: Any, seconds: float) -> None:
            nonlocal compute_time
            checked = asm.add(i, out, "func")
            if st is not None:
                st.write_chunk(i, checked)
            compute_time += seconds
            start, stop = asm.bounds(i)
            bar.update(stop - start)
            if report is not None:
                report(bar.n, n_points)

        try:
            compute(spec, func, cols, func_kwargs, pending, asm.bounds, on_result, timeout)
        finally:
            if st is not None:  # chunks finished before an error or Ctrl-C reach the disk
                st.flush()
    if st is not None:
        st.finish()
    return SweepResult(outputs=asm.arrays, points=cols, metadata=identity["metadata"],
                       n_chunks=n_chunks, n_resumed=n_resumed, chunk_size=cs,
                       identity_hash=identity_hash, identity=identity,
                       path=st.path if st is not None else None,
                       wall_time=time.perf_counter() - t0, compute_time=compute_time,
                       executor=spec.label)
