"""The on-disk store of a sweep: one Zarr group, written as it goes, resumed, never mixed.

Layout of ``store="run.zarr"`` (a directory in Zarr format 2, readable by zarr-python 2 and
3, by ``zarr.open_group`` and by ``xarray.open_zarr``, which shows the points as
coordinates)::

    run.zarr/            group attributes: {"hybridpd_sweep": {format, identity,
                         identity_hash, n_points, chunk_size, n_chunks, point_names,
                         output_names, status}, "metadata": <the caller's metadata>}
    run.zarr/<point>     one 1-D array per point coordinate, dimension "point"
    run.zarr/<output>    one array per output, shape (n_points, *trailing), dimensions
                         ("point", "<output>_dim1", ...)
    run.zarr/_sweep/done one flag per sweep chunk

Every output array is chunked like the sweep (``chunk_size`` points per Zarr chunk), so one
finished sweep chunk is one Zarr chunk file per output, written by Zarr atomically (temporary
file, then rename) from a background thread while the next chunk computes (a chunk is on
disk at most two chunks later, and before the sweep returns or raises). Its ``done`` flag is
written after them: a chunk is either complete on
disk or recomputed on resume, whatever moment the process was killed. A chunk file that
cannot be decoded on resume (disk trouble) is recomputed with a warning. Nothing in the store
depends on timing, host or executor, so equal sweeps give equal files.

The *identity* of a sweep (hash of the points, the function's qualified name, its keyword
arguments, the metadata and the chunk size) is stored in the attributes; resuming a store
with a different identity raises ``ValueError``.
"""

# The broad excepts are deliberate: an unreadable chunk degrades to recomputing it (BLE001).
# ruff: noqa: BLE001

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import dataclasses
import functools
import hashlib
import json
import os
import shutil
import uuid
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["FORMAT", "ZarrStore", "read_store"]

#: Identifier of the store format, stored in every sweep store.
FORMAT = "hybridpd.sweeps.sweep/2"

_NUMERIC_KINDS = "biufc"
_ATTR = "hybridpd_sweep"
_DONE = "_sweep/done"

# --------------------------------------------------------------------------
# Identity (canonical JSON)
# --------------------------------------------------------------------------

_JSON_ALLOWED = ("None, bool, int, float, complex, str, lists/tuples, dicts with str keys, "
                 "numpy scalars and numeric arrays, os.PathLike, dataclass instances")


def _array_digest(a: np.ndarray) -> str:
    a = np.ascontiguousarray(a)
    h = hashlib.sha256()
    h.update(json.dumps([a.dtype.str, list(a.shape)]).encode())
    if a.size:
        h.update(a.reshape(-1).view(np.uint8))
    return h.hexdigest()


def json_value(obj: Any, where: str, *, arrays: str) -> Any:
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
            raise ValueError(f"{where} holds a numpy scalar of dtype {obj.dtype}; allowed: "
                             f"{_JSON_ALLOWED}")
        return json_value(obj.item(), where, arrays=arrays)
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind not in _NUMERIC_KINDS:
            raise ValueError(f"{where} holds an array of dtype {obj.dtype}; allowed: "
                             f"{_JSON_ALLOWED}")
        if arrays == "digest":
            return {"__ndarray__": {"dtype": obj.dtype.str, "shape": list(obj.shape),
                                    "sha256": _array_digest(obj)}}
        return json_value(obj.tolist(), where, arrays=arrays)
    if isinstance(obj, Mapping):
        out = {}
        for k, v in obj.items():
            if not isinstance(k, str):
                raise ValueError(f"{where} has a non-string key {k!r}; JSON needs string keys")
            out[k] = json_value(v, f"{where}[{k!r}]", arrays=arrays)
        return out
    if isinstance(obj, (list, tuple)):
        return [json_value(v, f"{where}[{i}]", arrays=arrays) for i, v in enumerate(obj)]
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        cls = type(obj)
        return {"__dataclass__": f"{cls.__module__}.{cls.__qualname__}",
                "fields": {f.name: json_value(getattr(obj, f.name), f"{where}.{f.name}",
                                            arrays=arrays) for f in dataclasses.fields(obj)}}
    raise ValueError(f"{where} holds an object of type {type(obj).__qualname__} that cannot be "
                     f"recorded as JSON; allowed: {_JSON_ALLOWED}")


def canonical_json(obj: Any) -> str:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=True)


def func_identity(func: Callable) -> Any:
    """Name `func` by module and qualified name (plus partial arguments)."""
    if isinstance(func, functools.partial):
        return {"partial": func_identity(func.func),
                "args": json_value(list(func.args), "func (partial args)", arrays="digest"),
                "keywords": json_value(dict(func.keywords), "func (partial keywords)",
                                     arrays="digest")}
    qualname = getattr(func, "__qualname__", None)
    module = getattr(func, "__module__", None)
    if qualname is None:  # a callable instance: name its class
        cls = type(func)
        name = f"{cls.__module__}.{cls.__qualname__}"
        if dataclasses.is_dataclass(func):
            return {"callable": name, "state": json_value(func, "func", arrays="digest")}
        return name
    return f"{module}.{qualname}"

def points_identity(cols: Mapping[str, np.ndarray]) -> dict[str, Any]:
    h = hashlib.sha256()
    for k in sorted(cols):
        h.update(k.encode())
        h.update(_array_digest(cols[k]).encode())
    first = next(iter(cols.values()))
    return {"n": int(first.shape[0]), "names": list(cols),
            "dtypes": [cols[k].dtype.str for k in cols], "sha256": h.hexdigest()}


def sweep_identity(func, func_kwargs, metadata, cols, chunk_size) -> tuple[dict, str]:
    """The identity of a sweep and its SHA-256 (see the module docstring)."""
    identity = {"format": FORMAT, "func": func_identity(func),
                "func_kwargs": json_value(func_kwargs, "func_kwargs", arrays="digest"),
                "metadata": json_value(dict(metadata or {}), "metadata", arrays="list"),
                "points": points_identity(cols), "chunk_size": chunk_size}
    # Round-trip through JSON so the in-memory identity equals the stored one
    # (e.g. tuples become lists) and comparisons are exact.
    identity = json.loads(canonical_json(identity))
    return identity, hashlib.sha256(canonical_json(identity).encode()).hexdigest()


def raise_mismatch(where: Path, stored: Any, current: dict) -> None:
    """Refuse to mix two sweeps, naming the parts of the identity that differ."""
    if isinstance(stored, dict):
        keys = sorted(k for k in set(stored) | set(current) if stored.get(k) != current.get(k))
    else:
        keys = ["?"]
    raise ValueError(f"store {where} holds a different sweep (identity differs in: "
                     f"{', '.join(keys) or '?'}); refusing to mix results. Pass resume=False to "
                     "overwrite it, or use another store")


# --------------------------------------------------------------------------
# Zarr store
# --------------------------------------------------------------------------


def _create_array(group, name, shape, chunks, dtype, dims, attrs=None):
    # Zarr format 2 (written by zarr-python 2 and 3, read by every Zarr implementation);
    # "_ARRAY_DIMENSIONS" names the dimensions for xarray.
    attrs = {"_ARRAY_DIMENSIONS": list(dims), **(attrs or {})}
    if hasattr(group, "create_array"):  # zarr-python >= 3
        return group.create_array(name, shape=shape, chunks=chunks, dtype=dtype, fill_value=0,
                                  attributes=attrs, overwrite=True)
    arr = group.create_dataset(name, shape=shape, chunks=chunks, dtype=dtype, fill_value=0,
                               overwrite=True)
    arr.attrs.update(attrs)
    return arr


def _open_new_group(path: Path):
    import zarr

    if int(zarr.__version__.split(".")[0]) >= 3:
        return zarr.open_group(str(path), mode="w", zarr_format=2)
    return zarr.open_group(str(path), mode="w")


def _write_in_order(*stages) -> None:
    """``arr[sel] = value`` for every ``(arr, sel, value)`` of each stage, stage after stage.

    With zarr-python 3 the writes of one stage run concurrently and all stages take a single
    round trip to Zarr's I/O thread (each synchronous write would be one), which keeps the
    store's cost per chunk near that of writing its files.
    """
    if hasattr(stages[0][0][0], "async_array"):
        import asyncio

        from zarr.core.sync import sync

        async def write():
            for stage in stages:
                await asyncio.gather(*(a.async_array.setitem(sel, v) for a, sel, v in stage))

        sync(write())
    else:  # zarr-python 2
        for stage in stages:
            for a, sel, v in stage:
                a[sel] = v


def _is_zarr_group(path: Path) -> bool:
    return (path / ".zgroup").is_file() or (path / "zarr.json").is_file()


def check_store_path(store: Any) -> Path:
    """Validate a store path: a directory path, not a file (contents checked by open)."""
    if not isinstance(store, (str, os.PathLike)):
        raise ValueError(f"store must be None or a directory path, got {store!r}")
    p = Path(store)
    if p.suffix in (".npz", ".nc"):
        raise ValueError(f"store {str(p)!r} names a {p.suffix} file; a sweep store is a Zarr "
                         "directory written as it goes, e.g. 'run.zarr' (write other formats "
                         "afterwards with save)")
    if p.exists() and not p.is_dir():
        raise ValueError(f"store {str(p)!r} exists and is not a directory; pass a directory path")
    return p


def _stored_info(path: Path) -> tuple[dict | None, dict]:
    """The sweep attributes of the store at `path` (None if it holds none), and all attrs."""
    import zarr

    if not _is_zarr_group(path):
        return None, {}
    try:
        attrs = dict(zarr.open_group(str(path), mode="r").attrs)
    except Exception:
        return None, {}
    info = attrs.get(_ATTR)
    return (info if isinstance(info, dict) else None), attrs


class ZarrStore:
    """Read and write one sweep store (see the module docstring)."""

    def __init__(self, path: Path, identity: dict, identity_hash: str, n_points: int,
                 chunk_size: int, n_chunks: int):
        self.path, self.identity, self.identity_hash = path, identity, identity_hash
        self.n_points, self.chunk_size, self.n_chunks = n_points, chunk_size, n_chunks
        self.group: Any = None
        self.arrays: dict[str, Any] = {}
        self.done_flags: Any = None
        self.info: dict = {}
        self._writer: cf.ThreadPoolExecutor | None = None
        self._pending: list[cf.Future] = []

    def bounds(self, i: int) -> tuple[int, int]:
        start = i * self.chunk_size
        return start, min(self.n_points, start + self.chunk_size)

    def open(self, cols: Mapping[str, np.ndarray], resume: bool) -> str:
        """Open or create the store: ``"complete"``, ``"partial"`` or ``"new"``.

        A store holding a different sweep raises ValueError (unless `resume` is False, in
        which case it is deleted first).
        """
        import zarr

        info, _ = _stored_info(self.path)
        if info is None and self.path.is_dir() and any(self.path.iterdir()):
            # never delete what a sweep did not write (a saved dataset, an older store, ...)
            raise ValueError(
                f"store {str(self.path)!r} is a non-empty directory that is not a Zarr sweep "
                "store; pass a new path (e.g. 'run.zarr')")
        if info is not None and resume:
            if info.get("identity_hash") != self.identity_hash:
                raise_mismatch(self.path, info.get("identity"), self.identity)
            self.group = zarr.open_group(str(self.path), mode="r+")
            self.done_flags = self.group[_DONE]
            self.info = info
            for p in self.path.rglob("*.partial"):  # leftovers of writes cut by a kill
                p.unlink(missing_ok=True)
            self.arrays = {k: self.group[k] for k in info.get("output_names", [])}
            return "complete" if info.get("status") == "complete" else "partial"
        # Built beside and renamed into place: a store exists only with its identity.
        tmp = self.path.with_name(f".{self.path.name}.{uuid.uuid4().hex[:12]}.tmp")
        try:
            self.group = _open_new_group(tmp)
            self.info = {"format": FORMAT, "identity": self.identity,
                         "identity_hash": self.identity_hash, "n_points": self.n_points,
                         "chunk_size": self.chunk_size, "n_chunks": self.n_chunks,
                         "point_names": list(cols), "output_names": [], "status": "running"}
            for k, v in cols.items():  # written once: one Zarr chunk each
                _create_array(self.group, k, (self.n_points,), (self.n_points,), v.dtype,
                              ["point"])[:] = v
            _create_array(self.group, _DONE, (self.n_chunks,), (1,), bool, ["chunk"])
            self._write_attrs()
            if self.path.exists():
                shutil.rmtree(self.path)  # a sweep store or an empty directory
            os.replace(tmp, self.path)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        self.group = zarr.open_group(str(self.path), mode="r+")
        self.done_flags = self.group[_DONE]
        return "new"

    def _write_attrs(self) -> None:
        self.group.attrs.put({_ATTR: self.info, "metadata": self.identity["metadata"]})

    def done(self) -> np.ndarray:
        """Flags of the chunks finished on disk (unreadable flags count as not done)."""
        arr = self.done_flags
        try:
            return np.asarray(arr[:], bool)
        except Exception:
            flags = np.zeros(self.n_chunks, bool)
            for i in range(self.n_chunks):
                with contextlib.suppress(Exception):
                    flags[i] = bool(arr[i])
            return flags

    def load_chunks(self, add: Callable[[int, dict, str], Any]) -> int:
        """Hand every finished chunk to ``add(i, outputs, source)``; return how many."""
        done = np.flatnonzero(self.done())
        if not self.arrays or done.size == 0:
            self.arrays = {}  # recreated from the first chunk computed now
            return 0
        try:
            full = {k: a[:] for k, a in self.arrays.items()}
        except Exception:
            full = None  # some chunk file is damaged: find which, chunk by chunk
        n = 0
        for i in done.tolist():
            start, stop = self.bounds(i)
            try:
                if full is not None:
                    out = {k: v[start:stop] for k, v in full.items()}
                else:
                    out = {k: a[start:stop] for k, a in self.arrays.items()}
            except Exception as exc:
                warnings.warn(f"ignoring unreadable chunk {i} of {self.path} ({exc}); the "
                              "chunk will be recomputed", RuntimeWarning, stacklevel=3)
                continue
            add(i, out, f"store chunk {i}")
            n += 1
        return n

    def write_chunk(self, i: int, outputs: Mapping[str, np.ndarray]) -> None:
        """Write one finished chunk's outputs, then its done flag."""
        if not self.arrays:  # the first chunk fixes the outputs' dtypes and trailing shapes
            clash = sorted(set(outputs) & set(self.info["point_names"]) | {"_sweep"} & set(outputs))
            if clash:
                raise ValueError(f"func output names {clash} clash with point names (or the "
                                 "reserved '_sweep'); a store holds both in one Zarr group")
            for k, a in outputs.items():
                tr = a.shape[1:]
                dims = ["point", *(f"{k}_dim{j + 1}" for j in range(len(tr)))]
                # "coordinates": xarray.open_zarr shows the points as coordinates
                self.arrays[k] = _create_array(
                    self.group, k, (self.n_points, *tr), (self.chunk_size, *tr), a.dtype, dims,
                    {"coordinates": " ".join(self.info["point_names"])})
            self.info["output_names"] = list(outputs)
            self._write_attrs()
        start, stop = self.bounds(i)
        stages = ([(self.arrays[k], slice(start, stop), a) for k, a in outputs.items()],
                  [(self.done_flags, slice(i, i + 1), np.ones(1, bool))])  # the flag last
        # Written by one background thread while the next chunk computes; at most two chunks
        # wait, and a failed write is re-raised here or by flush().
        if self._writer is None:
            self._writer = cf.ThreadPoolExecutor(1, thread_name_prefix="hybridpd-store")
        self._pending.append(self._writer.submit(_write_in_order, *stages))
        while len(self._pending) > 2:
            self._pending.pop(0).result()

    def flush(self) -> None:
        """Wait until every chunk handed to :meth:`write_chunk` is on disk (errors re-raised)."""
        try:
            while self._pending:
                self._pending.pop(0).result()
        finally:
            if self._writer is not None:
                self._writer.shutdown(wait=True)
                self._writer = None

    def finish(self) -> None:
        """Mark the store complete (after every chunk is on disk)."""
        import zarr

        self.flush()
        self.info["status"] = "complete"
        self._write_attrs()
        # Consolidated metadata: xarray.open_zarr reads the finished store in one go.
        zarr.consolidate_metadata(str(self.path))


def read_store(path: Path) -> tuple[dict, dict, dict, dict]:
    """Read a complete sweep store: ``(points, outputs, info, metadata)``."""
    import zarr

    info, attrs = _stored_info(path)
    if info is None or info.get("format") != FORMAT:
        raise ValueError(f"{path} is not a hybridpd sweep store (format {FORMAT!r})")
    group = zarr.open_group(str(path), mode="r")
    if info.get("status") != "complete":
        n_done = int(np.asarray(group[_DONE][:], bool).sum())
        raise ValueError(f"sweep store {path} is incomplete ({n_done} of {info['n_chunks']} "
                         "chunks done); rerun run_sweep with the same arguments to finish it")
    points = {k: np.asarray(group[k][:]) for k in info["point_names"]}
    outputs = {k: np.asarray(group[k][:]) for k in info["output_names"]}
    return points, outputs, info, attrs.get("metadata", {})
