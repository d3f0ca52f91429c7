"""The basin result's ``.npz`` layout: its arrays, and every other field as JSON in one 0-d
entry (read by :func:`numpy.load` without pickle). :class:`~hybridpd.analysis.basins.BasinResult`
writes and reads it by suffix; the basins of earlier versions are built back there."""
from __future__ import annotations

import json
from dataclasses import fields
from pathlib import Path

import numpy as np

from hybridpd._results import jsonable

_META = "__metadata__"


def write_basin_npz(b, path: Path) -> Path:
    """Write basin ``b`` to ``.npz``: its arrays, and its other fields as JSON."""
    arrays = {f.name: getattr(b, f.name) for f in fields(b)
              if ("dims" in f.metadata or "coord" in f.metadata) and getattr(b, f.name) is not None}
    meta = {f.name: jsonable(getattr(b, f.name)) for f in fields(b) if f.name not in arrays}
    meta["attractors"] = [a.to_dict() for a in b.attractors]
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp.npz")
    np.savez(tmp, **arrays, **{_META: np.array(json.dumps(dict(meta, kind=b.kind)))})
    tmp.replace(path)
    return path


def read_basin_npz(path: Path) -> tuple:
    """``(kind, metadata, arrays)`` of a basin's ``.npz`` file (this version's or an earlier
    one; ``ValueError`` for another kind); the basin result builds itself from them."""
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files if k != _META}
        meta = json.loads(str(z[_META][()])) if _META in z.files else {}
    kind = meta.pop("kind", None)
    if kind not in ("basin", "attractor_basin"):
        raise ValueError(f"{path} does not hold a basin (it holds a {kind!r})")
    return kind, meta, arrays
