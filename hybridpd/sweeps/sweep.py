"""Generic parameter-sweep engine: executors, chunks, write-as-you-go, resume.

A *sweep* evaluates one picklable, module-level function over many points
(e.g. a flattened ``(kp, kv, e)`` grid, or the initial conditions of a basin of
attraction). The points are cut into fixed, contiguous *chunks*; each chunk is
one task handed to an executor, and each finished chunk is (optionally)
written to disk at once, so that a sweep interrupted after hours resumes where
it stopped.

Guarantees
----------
* **Determinism.** The chunk layout depends only on the number of points and
  ``chunk_size`` (never on the executor or the worker count), and every chunk
  result is placed by its index. The outputs, and the final ``.npz`` file byte
  for byte, are therefore identical for the serial, process-pool and Dask
  executors, for any worker count, and for an interrupted-then-resumed sweep.
* **Nothing lost.** Each chunk file is written atomically (temporary file,
  then ``os.replace``) as soon as the chunk arrives; a chunk file damaged by
  an OS crash is detected on resume and recomputed (the final file and the
  manifest are also ``fsync``-ed). If a worker raises,
  the error is re-raised in the caller (:class:`ChunkError`, carrying the
  chunk index) and the chunks already finished stay on disk.
* **Never silently mixed.** The store records the sweep's *identity* (hash of
  the points, qualified name of the function, ``func_kwargs``, ``metadata``,
  chunk size). Resuming with a different identity raises ``ValueError``.
* **No home-made scheduler.** Local parallelism is a
  :class:`concurrent.futures.ProcessPoolExecutor`; beyond one machine a Dask
  ``distributed.Client``. Dask is imported only when asked for
  (``pip install 'hybridpd[dask]'``).

The function contract
---------------------
``func(chunk_points, **func_kwargs) -> dict[str, ndarray]`` where
``chunk_points`` maps each point name to a fresh, writable 1-D array of the
chunk's ``m`` points, and each returned array has leading length ``m`` (one
row per point) with any trailing shape and a bool, integer, float or complex
dtype. Every chunk must return the same names, dtypes and trailing shapes.
For the process and Dask executors ``func`` must be importable by name in the
workers (defined at module level, not a lambda or a closure).

On-disk format
--------------
``store="run_dir"`` (a directory)::

    run_dir/manifest.json           identity, chunk layout, status, timing
    run_dir/chunks/chunk-000000.npz one file per finished chunk (removed at the
    ...                             end unless keep_chunks=True)
    run_dir/result.npz              final result (written once, atomically)

``store="result.npz"`` (a path ending in ``.npz``): the final file is that
path and the working files live in ``result.npz.parts/`` (removed at the end
unless ``keep_chunks=True``).

Every ``.npz`` written here (see :func:`save_npz`) is a standard NumPy archive
readable by :func:`numpy.load`, plus a 0-d unicode array ``__metadata__``
holding a JSON document. Zip timestamps are fixed, so equal contents give
equal bytes. The final file holds ``points/<name>`` and ``outputs/<name>``
arrays; its metadata is ``{"hybridpd_sweep": {...identity, layout...},
"metadata": <user metadata>}``. It contains no timing or host information
(that goes to ``manifest.json``), which is what makes it reproducible.
"""

# The project's contract is ValueError for every bad input, type errors included
# (TRY004); the broad excepts are deliberate: each re-raises with context, or
# degrades to recomputing a chunk, or cleans up before re-raising (BLE001).
# ruff: noqa: BLE001

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import dataclasses
import functools
import hashlib
import json
import math
import os
import pickle
import queue
import re
import sys
import time
import uuid
import warnings
import zipfile
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "EXECUTORS",
    "FORMAT",
    "ChunkError",
    "ExecutorSpec",
    "SweepResult",
    "default_chunk_size",
    "grid_points",
    "load_npz",
    "load_sweep",
    "resolve_executor",
    "run_sweep",
    "save_npz",
]

#: Identifier of the on-disk format, stored in every manifest and final file.
FORMAT = "hybridpd.sweeps.sweep/1"

#: Executor names accepted by :func:`run_sweep` (besides executor instances).
EXECUTORS = ("serial", "processes", "dask")

_METADATA_KEY = "__metadata__"
# Fixed zip timestamp (the earliest DOS date): equal contents -> equal bytes.
_ZIP_EPOCH = (1980, 1, 1, 0, 0, 0)
# Default chunking: aim at ~256 chunks (enough for load balancing on a few
# dozen workers, few enough that per-chunk overhead stays negligible), but
# never chunks so small that a vectorised func loses its edge.
_TARGET_CHUNKS = 256
_MIN_CHUNK = 64
_MAX_CHUNK = 1 << 20
_NUMERIC_KINDS = "biufc"
_CHUNK_RE = re.compile(r"^chunk-(\d+)\.npz$")


# --------------------------------------------------------------------------
# Errors and small validators
# --------------------------------------------------------------------------


class ChunkError(RuntimeError):
    """A chunk's function call failed in a worker.

    The original exception is chained as ``__cause__`` (for the process pool it
    carries the remote traceback). Chunks finished before the failure are kept
    in the store, so rerunning with ``resume=True`` only computes the rest.

    Attributes
    ----------
    chunk_index : int
        Index of the failed chunk (0-based).
    start, stop : int
        The chunk covers points ``start:stop`` (original point order).
    """

    def __init__(self, chunk_index: int, start: int, stop: int, cause: BaseException):
        self.chunk_index = chunk_index
        self.start = start
        self.stop = stop
        super().__init__(
            f"sweep chunk {chunk_index} (points {start}:{stop}) failed: "
            f"{type(cause).__name__}: {cause}"
        )


def _check_positive_int(value: Any, name: str) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be a positive integer, got {value!r}")
    if value < 1:
        raise ValueError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def _check_bool(value: Any, name: str) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def _cpu_count() -> int:
    # sched_getaffinity honours CPU pinning (taskset, some containers);
    # os.cpu_count() counts the whole machine.
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


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
# JSON canonicalisation (identity and metadata)
# --------------------------------------------------------------------------

_JSON_ALLOWED = (
    "None, bool, int, float, complex, str, lists/tuples, dicts with str keys, "
    "numpy scalars and numeric arrays, os.PathLike, dataclass instances"
)


def _array_digest(a: np.ndarray) -> str:
    a = np.ascontiguousarray(a)
    h = hashlib.sha256()
    h.update(json.dumps([a.dtype.str, list(a.shape)]).encode())
    if a.size:
        h.update(a.reshape(-1).view(np.uint8))
    return h.hexdigest()


def _jsonable(obj: Any, where: str, *, arrays: str) -> Any:
    """Convert `obj` to plain JSON types, deterministically.

    ``arrays="digest"`` replaces numpy arrays by dtype/shape/sha256 (for the
    identity: arrays may be large); ``arrays="list"`` stores them as nested
    lists (for metadata that must be readable back).
    """
    if obj is None or isinstance(obj, (bool, str)):
        return obj
    if isinstance(obj, int):
        return int(obj)
    if isinstance(obj, float):
        return float(obj)
    if isinstance(obj, complex):
        return {"__complex__": [obj.real, obj.imag]}
    if isinstance(obj, np.generic):
        if obj.dtype.kind not in _NUMERIC_KINDS:
            raise ValueError(
                f"{where} holds a numpy scalar of dtype {obj.dtype}; allowed: {_JSON_ALLOWED}"
            )
        return _jsonable(obj.item(), where, arrays=arrays)
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind not in _NUMERIC_KINDS:
            raise ValueError(
                f"{where} holds an array of dtype {obj.dtype}; allowed: {_JSON_ALLOWED}"
            )
        if arrays == "digest":
            return {
                "__ndarray__": {
                    "dtype": obj.dtype.str,
                    "shape": list(obj.shape),
                    "sha256": _array_digest(obj),
                }
            }
        return _jsonable(obj.tolist(), where, arrays=arrays)
    if isinstance(obj, Mapping):
        out = {}
        for k, v in obj.items():
            if not isinstance(k, str):
                raise ValueError(f"{where} has a non-string key {k!r}; JSON needs string keys")
            out[k] = _jsonable(v, f"{where}[{k!r}]", arrays=arrays)
        return out
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v, f"{where}[{i}]", arrays=arrays) for i, v in enumerate(obj)]
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        cls = type(obj)
        return {
            "__dataclass__": f"{cls.__module__}.{cls.__qualname__}",
            "fields": {
                f.name: _jsonable(getattr(obj, f.name), f"{where}.{f.name}", arrays=arrays)
                for f in dataclasses.fields(obj)
            },
        }
    raise ValueError(
        f"{where} holds an object of type {type(obj).__qualname__} that cannot be "
        f"recorded as JSON; allowed: {_JSON_ALLOWED}"
    )


def _canonical_json(obj: Any) -> str:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=True)


def _func_identity(func: Callable) -> Any:
    """Name `func` by module and qualified name (plus partial arguments)."""
    if isinstance(func, functools.partial):
        return {
            "partial": _func_identity(func.func),
            "args": _jsonable(list(func.args), "func (partial args)", arrays="digest"),
            "keywords": _jsonable(dict(func.keywords), "func (partial keywords)", arrays="digest"),
        }
    qualname = getattr(func, "__qualname__", None)
    module = getattr(func, "__module__", None)
    if qualname is None:  # a callable instance: name its class
        cls = type(func)
        name = f"{cls.__module__}.{cls.__qualname__}"
        if dataclasses.is_dataclass(func):
            return {"callable": name, "state": _jsonable(func, "func", arrays="digest")}
        return name
    return f"{module}.{qualname}"


# --------------------------------------------------------------------------
# .npz helpers
# --------------------------------------------------------------------------


def _fsync_dir(path: Path) -> None:
    # Makes the rename itself durable; not supported everywhere (Windows).
    with contextlib.suppress(OSError, AttributeError):
        fd = os.open(path, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _atomic_write(path: Path, writer: Callable[[Any], None], *, fsync: bool = True) -> None:
    """Write via a temporary file in the same directory, then ``os.replace``.

    Readers (including a resumed sweep) therefore see either the old file or
    the complete new one, never a truncated file -- even if the process is
    killed mid-write. The temporary name starts with '.' and ends in '.tmp'.
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex[:12]}.tmp")
    try:
        with open(tmp, "wb") as fh:
            writer(fh)
            fh.flush()
            if fsync:
                os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise
    if fsync:
        _fsync_dir(path.parent)


def save_npz(
    path: str | os.PathLike,
    arrays: Mapping[str, Any],
    metadata: Mapping[str, Any] | None = None,
    *,
    compress: bool = False,
    fsync: bool = True,
) -> Path:
    """Write arrays plus JSON metadata to an ``.npz`` file, atomically.

    The file is a standard NumPy archive (:func:`numpy.load` reads it without
    pickle) with one extra entry, ``__metadata__``: a 0-d unicode array holding
    the JSON text of `metadata` (keys sorted). Zip timestamps are fixed, so the
    same arrays and metadata always produce the same bytes.

    Parameters
    ----------
    path : str or os.PathLike
        Destination, used verbatim (no ``.npz`` suffix is appended).
    arrays : mapping of str to array_like
        Arrays to store, in this order. Names must be non-empty and differ
        from ``"__metadata__"``; object dtypes are refused (they need pickle).
    metadata : mapping, optional
        JSON-compatible data (numpy scalars/arrays are converted to numbers
        and nested lists, complex numbers to ``{"__complex__": [re, im]}``).
    compress : bool, default False
        Deflate the entries (worth it for large boolean/integer maps).
    fsync : bool, default True
        Flush the file and its directory to stable storage before returning.

    Returns
    -------
    pathlib.Path
        The written path.

    Examples
    --------
    >>> import tempfile, numpy as np
    >>> from pathlib import Path
    >>> d = Path(tempfile.mkdtemp())
    >>> _ = save_npz(d / "r.npz", {"stable": np.array([True, False])}, {"e": 0.5})
    >>> arrays, meta = load_npz(d / "r.npz")
    >>> arrays["stable"], meta
    (array([ True, False]), {'e': 0.5})
    """
    path = Path(path)
    if not isinstance(arrays, Mapping):
        raise ValueError(
            f"arrays must be a mapping of names to arrays, got {type(arrays).__qualname__}"
        )
    items: list[tuple[str, np.ndarray]] = []
    for k, v in arrays.items():
        if not isinstance(k, str) or not k or k == _METADATA_KEY:
            raise ValueError(
                f"arrays keys must be non-empty strings other than {_METADATA_KEY!r}, got {k!r}"
            )
        a = np.asarray(v)
        if a.dtype.hasobject:
            raise ValueError(
                f"arrays[{k!r}] has object dtype; only plain numpy dtypes can be stored without pickle"
            )
        items.append((k, a))
    meta = _jsonable(dict(metadata or {}), "metadata", arrays="list")
    items.append((_METADATA_KEY, np.array(_canonical_json(meta))))
    method = zipfile.ZIP_DEFLATED if compress else zipfile.ZIP_STORED

    def write(fh: Any) -> None:
        with zipfile.ZipFile(fh, "w", compression=method, allowZip64=True) as zf:
            for name, a in items:
                info = zipfile.ZipInfo(name + ".npy", date_time=_ZIP_EPOCH)
                info.compress_type = method
                info.external_attr = 0o644 << 16
                # force_zip64: the entry size is unknown while streaming (as numpy does).
                with zf.open(info, "w", force_zip64=True) as out:
                    np.lib.format.write_array(out, a, allow_pickle=False)

    _atomic_write(path, write, fsync=fsync)
    return path


def load_npz(path: str | os.PathLike) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Read an ``.npz`` written by :func:`save_npz`.

    Parameters
    ----------
    path : str or os.PathLike
        The file. Plain ``numpy.savez`` files load too (empty metadata).

    Returns
    -------
    arrays : dict of str to ndarray
        The arrays, in stored order, fully loaded in memory.
    metadata : dict
        The decoded JSON metadata.
    """
    with np.load(Path(path), allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files if k != _METADATA_KEY}
        meta = json.loads(str(z[_METADATA_KEY][()])) if _METADATA_KEY in z.files else {}
    return arrays, meta


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


def _normalize_points(
    points: Any, names: Sequence[str] | None, allow_nan: bool
) -> dict[str, np.ndarray]:
    allowed = "a dict of equally long 1-D numeric arrays, or a 2-D numeric array of shape (N, d)"
    if isinstance(points, Mapping):
        if names is not None:
            raise ValueError(
                "names applies only when points is a 2-D array; dict keys already name the points"
            )
        if not points:
            raise ValueError(f"points is empty; expected {allowed}")
        cols = {}
        for k, v in points.items():
            if not isinstance(k, str) or not k:
                raise ValueError(f"points keys must be non-empty strings, got {k!r}")
            a = np.asarray(v)
            if a.ndim != 1:
                raise ValueError(
                    f"points[{k!r}] must be 1-D, got shape {a.shape}; expected {allowed}"
                )
            cols[k] = a
    else:
        try:
            a = np.asarray(points)
        except Exception as exc:  # ragged nested lists, ...
            raise ValueError(
                f"points could not be converted to an array ({exc}); expected {allowed}"
            ) from None
        if a.ndim != 2:
            raise ValueError(f"points must be {allowed}; got an array of shape {a.shape}")
        if a.shape[1] == 0:
            raise ValueError(f"points has no coordinates (shape {a.shape}); expected {allowed}")
        if names is None:
            names = [f"x{j}" for j in range(a.shape[1])]
        names = list(names)
        if (
            len(names) != a.shape[1]
            or len(set(names)) != len(names)
            or not all(isinstance(n, str) and n for n in names)
        ):
            raise ValueError(
                f"names must be {a.shape[1]} distinct non-empty strings (one per column of points), got {names!r}"
            )
        cols = {n: a[:, j] for j, n in enumerate(names)}
    lengths = {k: len(v) for k, v in cols.items()}
    if len(set(lengths.values())) != 1:
        raise ValueError(f"points arrays must all have the same length, got lengths {lengths}")
    if next(iter(lengths.values())) == 0:
        raise ValueError("points contains no point (length 0); a sweep needs at least one point")
    out = {}
    for k, a in cols.items():
        if a.dtype.kind not in _NUMERIC_KINDS:
            raise ValueError(
                f"points[{k!r}] has dtype {a.dtype}; allowed: bool, integer, float, complex"
            )
        if not allow_nan and a.dtype.kind in "fc" and np.isnan(a).any():
            raise ValueError(
                f"points[{k!r}] contains NaN at index {int(np.flatnonzero(np.isnan(a))[0])}; "
                "pass allow_nan=True if that is intended"
            )
        if not a.dtype.isnative:
            a = a.astype(a.dtype.newbyteorder("="))
        # A private read-only copy: the sweep must not see later changes made
        # by the caller, and the identity hash must describe what was computed.
        a = np.array(a, order="C", copy=True)
        a.flags.writeable = False
        out[k] = a
    return out


def _points_identity(cols: Mapping[str, np.ndarray]) -> dict[str, Any]:
    h = hashlib.sha256()
    for k in sorted(cols):
        h.update(k.encode())
        h.update(_array_digest(cols[k]).encode())
    first = next(iter(cols.values()))
    return {
        "n": int(first.shape[0]),
        "names": list(cols),
        "dtypes": [cols[k].dtype.str for k in cols],
        "sha256": h.hexdigest(),
    }


def _slice(cols: Mapping[str, np.ndarray], start: int, stop: int) -> dict[str, np.ndarray]:
    # Copies, so every executor hands func fresh writable arrays (identical
    # behaviour in-process and across process boundaries).
    return {k: v[start:stop].copy() for k, v in cols.items()}


# --------------------------------------------------------------------------
# Executors
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class ExecutorSpec:
    """A validated executor choice (nothing is started by creating it).

    Attributes
    ----------
    kind : {"serial", "processes", "dask", "executor", "client"}
        ``"executor"`` is a user-supplied :class:`concurrent.futures.Executor`,
        ``"client"`` a user-supplied ``distributed.Client``.
    instance : object or None
        The user-supplied executor or client (never closed by the sweep).
    max_workers : int
        Workers of a pool the sweep creates (all usable cores by default);
        1 for ``"serial"``; informational for supplied instances.
    """

    kind: str
    instance: Any = None
    max_workers: int = 1

    @property
    def label(self) -> str:
        """Short description, e.g. ``"processes[4]"``."""
        if self.kind in ("executor", "client"):
            return type(self.instance).__qualname__
        return self.kind if self.kind == "serial" else f"{self.kind}[{self.max_workers}]"


def _is_dask_client(obj: Any) -> bool:
    # If a Client exists, distributed is already imported: no import needed.
    mod = sys.modules.get("distributed")
    return mod is not None and isinstance(obj, getattr(mod, "Client", ()))


def resolve_executor(executor: Any = "processes", max_workers: int | None = None) -> ExecutorSpec:
    """Validate an executor choice for :func:`run_sweep`.

    Parameters
    ----------
    executor : {"processes", "serial", "dask"}, concurrent.futures.Executor or distributed.Client
        ``"processes"`` (default; ``None`` means the same): a
        ``ProcessPoolExecutor`` created and closed by the sweep.
        ``"serial"``: in the calling process, no pickling. ``"dask"``: a
        ``distributed.LocalCluster`` (processes, one thread each) created and
        closed by the sweep. An ``Executor`` or ``Client`` instance is used
        as is and left open.
    max_workers : int, optional
        Worker count for pools the sweep creates; default: all usable cores.
        Ignored for ``"serial"`` and supplied instances. Never affects results.

    Returns
    -------
    ExecutorSpec

    Raises
    ------
    ValueError
        Unknown executor name or type, or non-positive `max_workers`.
    ImportError
        ``"dask"`` without the optional ``distributed`` package.

    Examples
    --------
    >>> resolve_executor("processes", 2).label
    'processes[2]'
    >>> resolve_executor("threads")
    Traceback (most recent call last):
    ...
    ValueError: executor must be one of 'serial', 'processes', 'dask', a concurrent.futures.Executor or a distributed.Client; got 'threads'
    """
    workers = (
        _cpu_count() if max_workers is None else _check_positive_int(max_workers, "max_workers")
    )
    if executor is None:
        executor = "processes"
    if isinstance(executor, str):
        if executor == "serial":
            return ExecutorSpec("serial", None, 1)
        if executor == "processes":
            return ExecutorSpec("processes", None, workers)
        if executor == "dask":
            import importlib.util

            if importlib.util.find_spec("distributed") is None:
                raise ImportError(
                    "executor='dask' needs the optional dependency: pip install 'hybridpd[dask]'"
                )
            return ExecutorSpec("dask", None, workers)
    elif isinstance(executor, cf.Executor):
        return ExecutorSpec("executor", executor, getattr(executor, "_max_workers", workers))
    elif _is_dask_client(executor):
        return ExecutorSpec("client", executor, workers)
    raise ValueError(
        "executor must be one of 'serial', 'processes', 'dask', a concurrent.futures.Executor "
        f"or a distributed.Client; got {executor!r}"
    )


def _run_chunk(
    func: Callable, chunk: dict[str, np.ndarray], kwargs: Mapping[str, Any]
) -> tuple[dict, float]:
    """Worker side: call func on one chunk; return (outputs, seconds)."""
    t0 = time.perf_counter()
    out = func(chunk, **kwargs)
    dt = time.perf_counter() - t0
    if isinstance(out, Mapping):
        # Plain arrays pickle compactly; validation happens in the caller,
        # where the chunk index can be reported.
        out = {k: np.asarray(v) for k, v in out.items()}
    return out, dt


def _run_chunk_slice(
    func: Callable, cols: Mapping[str, np.ndarray], start: int, stop: int, kwargs: Mapping[str, Any]
):
    """Dask worker side: the full points are scattered once; slice here."""
    return _run_chunk(func, _slice(cols, start, stop), kwargs)


def _terminate_process_pool(pool: cf.ProcessPoolExecutor) -> None:
    """Stop a pool we own now, including chunks still running.

    ``shutdown(cancel_futures=True)`` only drops queued work; a running chunk
    would keep the interpreter alive until it finishes (exit joins the
    workers). On timeout or Ctrl-C we terminate the workers instead.
    """
    terminate = getattr(pool, "terminate_workers", None)  # Python >= 3.14
    if terminate is not None:
        with contextlib.suppress(Exception):
            terminate()
        return
    procs = list(
        (getattr(pool, "_processes", None) or {}).values()
    )  # read before shutdown clears it
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        with contextlib.suppress(Exception):
            p.terminate()
    for p in procs:
        with contextlib.suppress(Exception):
            p.join(timeout=5)


class _PoolBackend:
    """A concurrent.futures executor: chunks are sliced here and pickled."""

    def __init__(
        self, executor: cf.Executor, owned: bool, func: Callable, cols: dict, kwargs: dict
    ):
        self.executor, self.owned = executor, owned
        self.func, self.cols, self.kwargs = func, cols, kwargs

    def submit(self, tasks: Sequence[tuple[int, int, int]]) -> list[cf.Future]:
        """Submit chunks ``(index, start, stop)``; one future per chunk."""
        return [
            self.executor.submit(_run_chunk, self.func, _slice(self.cols, start, stop), self.kwargs)
            for _, start, stop in tasks
        ]

    def cancel(self, futures) -> set:
        # Queued chunks are dropped; running ones cannot be, so they are
        # returned for the caller to collect (and save) before re-raising.
        return {f for f in futures if not f.cancel()}

    def close(self, abort: bool, futures=()) -> None:
        for f in futures:
            f.cancel()
        if self.owned:
            if abort and isinstance(self.executor, cf.ProcessPoolExecutor):
                _terminate_process_pool(self.executor)
            else:
                self.executor.shutdown(wait=not abort, cancel_futures=True)


class _DaskBackend:
    """A distributed.Client: points are scattered once, workers slice them."""

    def __init__(self, client: Any, owned_cluster: Any, func: Callable, cols: dict, kwargs: dict):
        self.client, self.cluster = client, owned_cluster
        self.func, self.kwargs = func, kwargs
        self.token = uuid.uuid4().hex[:12]  # unique task keys per run on a shared client
        self.cols_future = client.scatter([cols], hash=False)[0]

    def submit(self, tasks: Sequence[tuple[int, int, int]]) -> list:
        """Submit chunks ``(index, start, stop)``; one future per chunk."""
        if not tasks:
            return []
        index, start, stop = (list(t) for t in zip(*tasks))
        # One client.map call instead of a submit per chunk: a single message
        # to the scheduler, which matters with thousands of chunks.
        n = len(tasks)
        return self.client.map(
            _run_chunk_slice,
            [self.func] * n,
            [self.cols_future] * n,
            start,
            stop,
            [self.kwargs] * n,
            key=[f"hybridpd-sweep-{self.token}-{i}" for i in index],
            pure=False,
            retries=0,
        )

    def cancel(self, futures) -> set:
        futures = list(futures)
        if futures:
            with contextlib.suppress(Exception):
                self.client.cancel(futures)
        return set()  # dask cancels running tasks too: nothing left to collect

    def close(self, abort: bool, futures=()) -> None:
        if abort:
            self.cancel(futures)
        with contextlib.suppress(Exception):
            self.client.cancel([self.cols_future])
        if self.cluster is not None:  # we created both: close both
            with contextlib.suppress(Exception):
                self.client.close()
            with contextlib.suppress(Exception):
                self.cluster.close()


def _open_backend(spec: ExecutorSpec, n_tasks: int, func: Callable, cols: dict, kwargs: dict):
    # Never start more workers than there are chunks left (saves start-up
    # time on short or mostly-resumed sweeps; results are unaffected).
    n = max(1, min(spec.max_workers, n_tasks))
    if spec.kind == "processes":
        return _PoolBackend(cf.ProcessPoolExecutor(max_workers=n), True, func, cols, kwargs)
    if spec.kind == "executor":
        return _PoolBackend(spec.instance, False, func, cols, kwargs)
    if spec.kind == "client":
        return _DaskBackend(spec.instance, None, func, cols, kwargs)
    if spec.kind == "dask":
        try:
            from distributed import Client, LocalCluster
        except ImportError as exc:  # pragma: no cover - checked by resolve_executor
            raise ImportError(
                "executor='dask' needs the optional dependency: pip install 'hybridpd[dask]'"
            ) from exc
        cluster = LocalCluster(
            n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0"
        )
        try:
            client = Client(cluster)
        except BaseException:
            cluster.close()
            raise
        try:
            return _DaskBackend(client, cluster, func, cols, kwargs)
        except BaseException:
            client.close()
            cluster.close()
            raise
    raise AssertionError(spec.kind)  # pragma: no cover


def _check_picklable(func: Callable, kwargs: Mapping[str, Any]) -> None:
    try:
        pickle.dumps(func)
    except Exception as exc:
        raise ValueError(
            f"func {getattr(func, '__qualname__', func)!r} cannot be pickled for a process pool ({exc}); "
            "define it at module level (not a lambda or nested function) or use executor='serial'"
        ) from None
    try:
        pickle.dumps(dict(kwargs))
    except Exception as exc:
        raise ValueError(f"func_kwargs cannot be pickled for a process pool ({exc})") from None


# --------------------------------------------------------------------------
# Results
# --------------------------------------------------------------------------


@dataclass
class SweepResult:
    """Outcome of :func:`run_sweep`.

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
        The final ``.npz`` file, or None without a store.
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

    def save(self, path: str | os.PathLike, *, compress: bool = False) -> Path:
        """Write this result in the final-file format (readable by :func:`load_sweep`)."""
        return save_npz(
            path,
            *_final_payload(
                self.points,
                self.outputs,
                self.identity,
                self.identity_hash,
                self.n_chunks,
                self.chunk_size,
            ),
            compress=compress,
        )


def _final_payload(points, outputs, identity, identity_hash, n_chunks, chunk_size):
    arrays = {f"points/{k}": v for k, v in points.items()}
    arrays.update({f"outputs/{k}": v for k, v in outputs.items()})
    meta = {
        "hybridpd_sweep": {
            "format": FORMAT,
            "identity": identity,
            "identity_hash": identity_hash,
            "n_points": int(next(iter(points.values())).shape[0]),
            "n_chunks": n_chunks,
            "chunk_size": chunk_size,
            "point_names": list(points),
            "output_names": list(outputs),
        },
        "metadata": identity.get("metadata", {}),
    }
    return arrays, meta


def load_sweep(path: str | os.PathLike) -> SweepResult:
    """Load a finished sweep from its final ``.npz`` (or its store directory).

    Parameters
    ----------
    path : str or os.PathLike
        The final file, or a store directory (its ``result.npz`` is read).

    Returns
    -------
    SweepResult
        With ``n_resumed == n_chunks`` and zero timings.
    """
    p = Path(path)
    if p.is_dir():
        p = p / "result.npz"
    arrays, meta = load_npz(p)
    info = meta.get("hybridpd_sweep")
    if not isinstance(info, dict) or info.get("format") != FORMAT:
        raise ValueError(f"{p} is not a hybridpd sweep result (format {FORMAT!r})")
    points = {k: arrays[f"points/{k}"] for k in info["point_names"]}
    for a in points.values():
        a.flags.writeable = False
    outputs = {k: arrays[f"outputs/{k}"] for k in info["output_names"]}
    return SweepResult(
        outputs=outputs,
        points=points,
        metadata=meta.get("metadata", {}),
        n_chunks=int(info["n_chunks"]),
        n_resumed=int(info["n_chunks"]),
        chunk_size=int(info["chunk_size"]),
        identity_hash=info["identity_hash"],
        identity=info["identity"],
        path=p,
        executor="",
    )


# --------------------------------------------------------------------------
# Assembly and store
# --------------------------------------------------------------------------


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
            raise ValueError(
                f"func must return a dict of arrays; {source} for chunk {i} gave {type(out).__qualname__}"
            )
        if not out:
            raise ValueError(
                f"func returned no outputs for chunk {i} ({source}); it must return at least one array"
            )
        checked = {}
        for k in sorted(out, key=str):
            if not isinstance(k, str) or not k:
                raise ValueError(
                    f"func output names must be non-empty strings; chunk {i} returned {k!r}"
                )
            a = np.asarray(out[k])
            if a.dtype.kind not in _NUMERIC_KINDS:
                raise ValueError(
                    f"output {k!r} of chunk {i} ({source}) has dtype {a.dtype}; allowed: bool, integer, float, complex"
                )
            if a.ndim == 0 or a.shape[0] != m:
                raise ValueError(
                    f"output {k!r} of chunk {i} ({source}) has shape {a.shape}; expected leading length {m} "
                    "(one row per point of the chunk)"
                )
            if not a.dtype.isnative:
                a = a.astype(a.dtype.newbyteorder("="))
            checked[k] = a
        schema = {k: (a.dtype, a.shape[1:]) for k, a in checked.items()}
        if self.schema is None:
            self.schema = schema
            self.arrays = {
                k: np.empty((self.n_points, *tr), dtype=dt) for k, (dt, tr) in schema.items()
            }
        elif schema != self.schema:

            def fmt(s):
                return ", ".join(f"{k}: {dt} {tuple(tr)}" for k, (dt, tr) in s.items())

            raise ValueError(
                f"chunk {i} ({source}) returned outputs {{{fmt(schema)}}} but earlier chunks returned "
                f"{{{fmt(self.schema)}}}; every chunk must return the same names, dtypes and trailing shapes"
            )
        for k, a in checked.items():
            self.arrays[k][start:stop] = a
        self.done.add(i)
        return checked


class _Store:
    """Paths and file operations of one sweep store (see module docstring)."""

    def __init__(self, store: str | os.PathLike, n_chunks: int):
        p = Path(store)
        if p.suffix == ".npz":
            if p.is_dir():
                raise ValueError(
                    f"store {str(p)!r} ends in .npz but is a directory; pass a directory or a file path"
                )
            self.final, self.workdir, self.single_file = p, p.with_name(p.name + ".parts"), True
        else:
            if p.exists() and not p.is_dir():
                raise ValueError(
                    f"store {str(p)!r} exists and is not a directory; pass a directory or a path ending in .npz"
                )
            self.final, self.workdir, self.single_file = p / "result.npz", p, False
        self.manifest = self.workdir / "manifest.json"
        self.chunk_dir = self.workdir / "chunks"
        self.width = max(6, len(str(n_chunks - 1)))

    def chunk_path(self, i: int) -> Path:
        return self.chunk_dir / f"chunk-{i:0{self.width}d}.npz"

    def _chunk_files(self) -> list[tuple[int, Path]]:
        if not self.chunk_dir.is_dir():
            return []
        found = []
        for p in self.chunk_dir.iterdir():
            m = _CHUNK_RE.match(p.name)
            if m:
                found.append((int(m.group(1)), p))
        return sorted(found)

    def _remove_tmp(self) -> None:
        # Leftovers of writes interrupted by a kill (see _atomic_write).
        for d in (self.workdir, self.chunk_dir, self.final.parent):
            if d.is_dir():
                for p in d.glob(".*.tmp"):
                    with contextlib.suppress(OSError):
                        p.unlink()

    def clear(self) -> None:
        """Remove this store's own files (resume=False); nothing else."""
        for _, p in self._chunk_files():
            p.unlink()
        self._remove_tmp()
        for p in (self.final, self.manifest):
            with contextlib.suppress(FileNotFoundError):
                p.unlink()
        self._rmdirs()

    def _rmdirs(self) -> None:
        with contextlib.suppress(OSError):
            self.chunk_dir.rmdir()  # only if empty
        if self.single_file:
            with contextlib.suppress(OSError):
                self.workdir.rmdir()

    def check_manifest(self, identity: dict, identity_hash: str) -> None:
        if not self.manifest.exists():
            return
        try:
            stored = json.loads(self.manifest.read_text())
            stored_hash, stored_identity = stored["identity_hash"], stored["identity"]
        except Exception as exc:
            raise ValueError(
                f"cannot read the sweep manifest {self.manifest} ({exc}); pass resume=False to start afresh"
            ) from None
        if stored_hash != identity_hash:
            _raise_mismatch(self.manifest, stored_identity, identity)

    def write_manifest(self, content: dict) -> None:
        text = json.dumps(content, indent=2, sort_keys=True, allow_nan=True) + "\n"
        _atomic_write(self.manifest, lambda fh: fh.write(text.encode()))

    def load_chunks(self, asm: _Assembler, identity_hash: str) -> int:
        n = 0
        for i, p in self._chunk_files():
            if i >= asm.n_chunks:
                raise ValueError(
                    f"chunk file {p} has index {i} beyond the sweep's {asm.n_chunks} chunks; "
                    "pass resume=False to start afresh"
                )
            try:
                arrays, meta = load_npz(p)
            except Exception as exc:  # corrupt file: recompute rather than fail
                warnings.warn(
                    f"ignoring unreadable chunk file {p} ({exc}); the chunk will be recomputed",
                    RuntimeWarning,
                    stacklevel=3,
                )
                continue
            if meta.get("identity_hash") != identity_hash:
                raise ValueError(
                    f"chunk file {p} belongs to a different sweep (identity "
                    f"{str(meta.get('identity_hash'))[:12]}..., expected {identity_hash[:12]}...); "
                    "pass resume=False to start afresh or use another store"
                )
            if (meta.get("chunk"), meta.get("start"), meta.get("stop")) != (i, *asm.bounds(i)):
                warnings.warn(
                    f"ignoring chunk file {p} with inconsistent layout; the chunk will be recomputed",
                    RuntimeWarning,
                    stacklevel=3,
                )
                continue
            asm.add(i, arrays, f"chunk file {p.name}")
            n += 1
        return n

    def write_chunk(
        self, i: int, start: int, stop: int, out: dict, seconds: float, identity_hash: str
    ) -> None:
        # No fsync here (it costs several ms per chunk on a real disk): the
        # write is still atomic against a killed process, and after an OS
        # crash a missing or torn chunk file is detected on load (zip CRC,
        # identity, layout) and merely recomputed. The final file and the
        # manifest, which nothing can recompute silently, are fsynced.
        save_npz(
            self.chunk_path(i),
            out,
            {
                "chunk": i,
                "start": start,
                "stop": stop,
                "identity_hash": identity_hash,
                "compute_seconds": seconds,
            },
            fsync=False,
        )

    def remove_work_files(self) -> None:
        """Delete chunk files (and, for a single-file store, the manifest)."""
        for _, p in self._chunk_files():
            with contextlib.suppress(OSError):
                p.unlink()
        if self.single_file:
            # The final file carries the identity; the working folder goes.
            with contextlib.suppress(FileNotFoundError):
                self.manifest.unlink()
        self._rmdirs()

    def finish(self, keep_chunks: bool, manifest: dict) -> None:
        if keep_chunks or not self.single_file:
            self.write_manifest(manifest)
        if not keep_chunks:
            self.remove_work_files()


def _raise_mismatch(where: Path, stored: Any, current: dict) -> None:
    if isinstance(stored, dict):
        keys = sorted(k for k in set(stored) | set(current) if stored.get(k) != current.get(k))
    else:
        keys = ["?"]
    raise ValueError(
        f"store {where} holds a different sweep (identity differs in: {', '.join(keys) or '?'}); "
        "refusing to mix results. Pass resume=False to overwrite it, or use another store"
    )


# --------------------------------------------------------------------------
# The engine
# --------------------------------------------------------------------------


def _compute_serial(func, cols, kwargs, asm, pending, on_result) -> None:
    for i in pending:
        start, stop = asm.bounds(i)
        try:
            out, dt = _run_chunk(func, _slice(cols, start, stop), kwargs)
        except Exception as exc:
            raise ChunkError(i, start, stop, exc) from exc
        on_result(i, out, dt)


def _compute_futures(backend, asm, pending, on_result, timeout) -> None:
    # Completion order is collected through done-callbacks into a queue rather
    # than with as_completed(): as_completed's timeout bounds the *whole*
    # sweep, while here `timeout` bounds the wait for the *next* chunk, which
    # with busy workers is at most the longest chunk's run time. Scheduling
    # itself stays entirely with the executor.
    done: queue.SimpleQueue = queue.SimpleQueue()
    index_of: dict[Any, int] = {}
    failed = True
    try:
        futures = backend.submit([(i, *asm.bounds(i)) for i in pending])
        for i, f in zip(pending, futures):
            index_of[f] = i
        for f in futures:
            f.add_done_callback(done.put)
        first_error: ChunkError | None = None
        while index_of:
            try:
                f = done.get(timeout=timeout)
            except queue.Empty:
                if first_error is not None:
                    break  # draining after a failure: report the failure itself
                left = sorted(index_of.values())
                more = f" (+{len(left) - 10} more)" if len(left) > 10 else ""
                raise TimeoutError(
                    f"no sweep chunk finished within timeout={timeout} s; pending chunks {left[:10]}{more}. "
                    "Finished chunks are saved; increase timeout or use smaller chunks"
                ) from None
            i = index_of.pop(f, None)
            if i is None or f.cancelled():
                continue
            try:
                out, dt = f.result()
            except Exception as exc:
                if first_error is None:
                    first_error = ChunkError(i, *asm.bounds(i), exc)
                    first_error.__cause__ = exc
                    # Drop queued chunks; keep collecting the running ones so
                    # their results are saved before the error propagates.
                    keep = backend.cancel(list(index_of))
                    index_of = {g: j for g, j in index_of.items() if g in keep}
                continue
            on_result(i, out, dt)
        if first_error is not None:
            raise first_error
        failed = False
    finally:
        backend.close(abort=failed, futures=list(index_of))


def run_sweep(
    func: Callable[..., Mapping[str, Any]],
    points: Mapping[str, Any] | np.ndarray,
    *,
    chunk_size: int | None = None,
    executor: Any = "processes",
    max_workers: int | None = None,
    store: str | os.PathLike | None = None,
    resume: bool = True,
    keep_chunks: bool = False,
    progress: bool = False,
    metadata: Mapping[str, Any] | None = None,
    func_kwargs: Mapping[str, Any] | None = None,
    names: Sequence[str] | None = None,
    allow_nan: bool = False,
    timeout: float | None = None,
) -> SweepResult:
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
    executor : {"processes", "serial", "dask"}, Executor or distributed.Client
        See :func:`resolve_executor`. Never changes the results.
    max_workers : int, optional
        Workers for pools created here (default: all usable cores, capped at
        the number of chunks left).
    store : str or os.PathLike, optional
        Directory, or final file path ending in ``.npz``; see the module
        docstring for the layout. Each chunk is saved as soon as it is done.
        Without a store nothing is written.
    resume : bool, default True
        Reuse a matching store: a finished final file is returned as is,
        finished chunks are loaded instead of recomputed. A store holding a
        different sweep raises ``ValueError``. With False, this store's files
        are deleted first and everything is recomputed.
    keep_chunks : bool, default False
        Keep the per-chunk files (and manifest) after the final file exists.
    progress : bool, default False
        Show a tqdm progress bar (chunks) on stderr -- never stdout.
    metadata : dict, optional
        JSON-compatible data stored in the final file and part of the
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
    (here: finds the finished file and computes nothing):

    >>> import tempfile
    >>> d = tempfile.mkdtemp()
    >>> a = run_sweep(norm, pts, executor="serial", chunk_size=6, store=d)
    >>> b = run_sweep(norm, pts, executor="serial", chunk_size=6, store=d)
    >>> b.n_resumed == b.n_chunks, np.array_equal(a.outputs["r"], b.outputs["r"])
    (True, True)
    """
    t0 = time.perf_counter()
    if not callable(func):
        raise ValueError(f"func must be callable, got {type(func).__qualname__}")
    resume = _check_bool(resume, "resume")
    keep_chunks = _check_bool(keep_chunks, "keep_chunks")
    progress = _check_bool(progress, "progress")
    allow_nan = _check_bool(allow_nan, "allow_nan")
    if timeout is not None:
        if (
            isinstance(timeout, bool)
            or not isinstance(timeout, (int, float, np.integer, np.floating))
            or not (math.isfinite(timeout) and timeout > 0)
        ):
            raise ValueError(
                f"timeout must be None or a positive number of seconds, got {timeout!r}"
            )
        timeout = float(timeout)
    cols = _normalize_points(points, names, allow_nan)
    n_points = len(next(iter(cols.values())))
    cs = (
        default_chunk_size(n_points)
        if chunk_size is None
        else _check_positive_int(chunk_size, "chunk_size")
    )
    n_chunks = -(-n_points // cs)
    if func_kwargs is None:
        func_kwargs = {}
    if not isinstance(func_kwargs, Mapping) or not all(isinstance(k, str) for k in func_kwargs):
        raise ValueError(
            f"func_kwargs must be None or a dict with string keys, got {func_kwargs!r}"
        )
    func_kwargs = dict(func_kwargs)
    if metadata is not None and not isinstance(metadata, Mapping):
        raise ValueError(f"metadata must be None or a dict, got {type(metadata).__qualname__}")
    spec = resolve_executor(executor, max_workers)
    if spec.kind == "processes" or isinstance(spec.instance, cf.ProcessPoolExecutor):
        _check_picklable(func, func_kwargs)

    identity = {
        "format": FORMAT,
        "func": _func_identity(func),
        "func_kwargs": _jsonable(func_kwargs, "func_kwargs", arrays="digest"),
        "metadata": _jsonable(dict(metadata or {}), "metadata", arrays="list"),
        "points": _points_identity(cols),
        "chunk_size": cs,
    }
    # Round-trip through JSON so the in-memory identity equals the stored one
    # (e.g. tuples become lists) and comparisons are exact.
    identity = json.loads(_canonical_json(identity))
    identity_hash = hashlib.sha256(_canonical_json(identity).encode()).hexdigest()

    st: _Store | None = _Store(store, n_chunks) if store is not None else None
    if st is not None:
        if not resume:
            st.clear()
        elif st.final.exists():
            try:
                done = load_sweep(st.final)
            except Exception as exc:
                warnings.warn(
                    f"ignoring unreadable final file {st.final} ({exc}); recomputing",
                    RuntimeWarning,
                    stacklevel=2,
                )
            else:
                if done.identity_hash != identity_hash:
                    _raise_mismatch(st.final, done.identity, identity)
                if not keep_chunks:  # a kill between the final write and the clean-up
                    st.remove_work_files()
                done.wall_time = time.perf_counter() - t0
                done.executor = spec.label
                return done
        if resume:
            st.check_manifest(identity, identity_hash)
        st._remove_tmp()
        manifest = {
            "format": FORMAT,
            "identity": identity,
            "identity_hash": identity_hash,
            "n_points": n_points,
            "chunk_size": cs,
            "n_chunks": n_chunks,
            "chunk_files": f"chunks/chunk-<index:0{st.width}d>.npz",
            "final": os.path.relpath(st.final, st.workdir),
            "status": "running",
        }
        st.write_manifest(manifest)

    asm = _Assembler(n_points, cs, n_chunks)
    n_resumed = st.load_chunks(asm, identity_hash) if st is not None else 0
    pending = [i for i in range(n_chunks) if i not in asm.done]

    bar = None
    if progress:
        try:
            from tqdm.auto import tqdm
        except ImportError:  # pragma: no cover - tqdm is a core dependency
            warnings.warn(
                "progress=True needs tqdm; continuing without a progress bar",
                RuntimeWarning,
                stacklevel=2,
            )
        else:
            bar = tqdm(
                total=n_chunks,
                initial=n_resumed,
                unit="chunk",
                file=sys.stderr,
                desc=f"sweep {identity_hash[:8]}",
                dynamic_ncols=True,
            )
    compute_time = 0.0

    def on_result(i: int, out: Any, seconds: float) -> None:
        nonlocal compute_time
        checked = asm.add(i, out, "func")
        if st is not None:
            st.write_chunk(i, *asm.bounds(i), checked, seconds, identity_hash)
        compute_time += seconds
        if bar is not None:
            bar.update(1)

    try:
        if pending:
            if spec.kind == "serial":
                _compute_serial(func, cols, func_kwargs, asm, pending, on_result)
            else:
                backend = _open_backend(spec, len(pending), func, cols, func_kwargs)
                _compute_futures(backend, asm, pending, on_result, timeout)
    finally:
        if bar is not None:
            bar.close()

    outputs = asm.arrays
    result = SweepResult(
        outputs=outputs,
        points=cols,
        metadata=identity["metadata"],
        n_chunks=n_chunks,
        n_resumed=n_resumed,
        chunk_size=cs,
        identity_hash=identity_hash,
        identity=identity,
        path=st.final if st is not None else None,
        compute_time=compute_time,
        executor=spec.label,
    )
    if st is not None:
        save_npz(st.final, *_final_payload(cols, outputs, identity, identity_hash, n_chunks, cs))
        result.wall_time = time.perf_counter() - t0
        manifest.update(
            status="complete",
            last_run={
                "executor": spec.label,
                "n_computed": n_chunks - n_resumed,
                "n_resumed": n_resumed,
                "wall_time": result.wall_time,
                "compute_time": compute_time,
            },
        )
        st.finish(keep_chunks, manifest)
    result.wall_time = time.perf_counter() - t0
    return result
