"""``.npz`` archives with JSON metadata: the format of files written by earlier versions.

Region maps, basins and sweeps are now written as netCDF or Zarr (see
:mod:`hybridpd.sweeps.labelled`); this module keeps reading (and, for those who want it,
writing) the ``.npz`` files of earlier versions: a standard NumPy archive readable by
:func:`numpy.load` without pickle, plus a 0-d unicode array ``__metadata__`` holding a JSON
document. Zip timestamps are fixed, so equal contents give equal bytes.
"""

from __future__ import annotations

import contextlib
import json
import os
import uuid
import zipfile
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from hybridpd.sweeps.store import canonical_json, json_value

__all__ = ["load_npz", "save_npz"]

_METADATA_KEY = "__metadata__"
# Fixed zip timestamp (the earliest DOS date): equal contents -> equal bytes.
_ZIP_EPOCH = (1980, 1, 1, 0, 0, 0)


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


def save_npz(path: str | os.PathLike, arrays: Mapping[str, Any],
             metadata: Mapping[str, Any] | None = None, *, compress: bool = False,
             fsync: bool = True) -> Path:
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
        raise ValueError(f"arrays must be a mapping of names to arrays, got "
                         f"{type(arrays).__qualname__}")
    items: list[tuple[str, np.ndarray]] = []
    for k, v in arrays.items():
        if not isinstance(k, str) or not k or k == _METADATA_KEY:
            raise ValueError(f"arrays keys must be non-empty strings other than "
                             f"{_METADATA_KEY!r}, got {k!r}")
        a = np.asarray(v)
        if a.dtype.hasobject:
            raise ValueError(f"arrays[{k!r}] has object dtype; only plain numpy dtypes can be "
                             "stored without pickle")
        items.append((k, a))
    meta = json_value(dict(metadata or {}), "metadata", arrays="list")
    items.append((_METADATA_KEY, np.array(canonical_json(meta))))
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
