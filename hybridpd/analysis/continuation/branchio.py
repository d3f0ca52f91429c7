"""Write and read continued branches (:meth:`Branch.save`, :func:`load_branch`).

A branch is stored as an ``.npz`` archive in the layout of :mod:`hybridpd.sweeps.npz`
(readable by :func:`numpy.load` without pickle): the per-point arrays as NumPy arrays, and
everything else (parameter name, family, case, the fixed parameters, impact patterns,
events) as JSON in the 0-d entry ``__metadata__``, with ``"kind": "branch"``. The layout is
written here directly because analyses do not import the sweeps layer.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from hybridpd.analysis.continuation.events import BifurcationEvent, Branch
from hybridpd.model import Case

__all__ = ["load_branch", "save_branch"]

_ARRAYS = ("parameter", "points", "multipliers", "spectral_radius", "stable", "viable",
           "margin", "min_impact_speed", "xm", "newton_iterations")


def _nan(v):
    return np.nan if v is None else float(v)


def _tuples(obj):
    return tuple(_tuples(o) for o in obj) if isinstance(obj, list) else obj


def save_branch(branch: Branch, path):
    """Write `branch` to an ``.npz`` file (see the module docstring); returns the path."""
    _check_npz(path)
    arrays = {k: np.asarray(getattr(branch, k)) for k in _ARRAYS}
    meta = {"kind": "branch", "parameter_name": branch.parameter_name,
            "period": int(branch.period), "patterns": branch.patterns,
            "events": [ev.to_dict() for ev in branch.events],
            "termination": branch.termination, "family": branch.family,
            "method": branch.method, "case": Case.parse(branch.case).value,
            "fixed": dict(branch.fixed), "n_rejected": int(branch.n_rejected)}
    text = json.dumps(meta, sort_keys=True, default=_plain)
    path = Path(path)
    with open(path, "wb") as fh:  # a file object: numpy would otherwise append .npz
        np.savez_compressed(fh, **arrays, __metadata__=np.array(text))
    return path


def _plain(v):
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    raise TypeError(f"cannot store {type(v).__name__} in the branch metadata")


def _check_npz(path):
    if not isinstance(path, (str, Path)) or Path(path).suffix.lower() != ".npz":
        raise ValueError(f"path must end in .npz, got {path!r}")


def _event(d: dict) -> BifurcationEvent:
    mult = np.array([complex(_nan(re), _nan(im)) for re, im in d["multipliers"]])
    return BifurcationEvent(kind=d["kind"], parameter=float(d["parameter"]),
                            point=np.array([_nan(v) for v in d["point"]]), multipliers=mult,
                            index=int(d["index"]), detail=d["detail"],
                            test_value=_nan(d["test_value"]), located=bool(d["located"]),
                            viable=bool(d["viable"]), xm=_nan(d["xm"]))


def load_branch(path) -> Branch:
    """Read a :class:`Branch` written by :meth:`Branch.save`.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from hybridpd import ImpactPair, PDGains
    >>> from hybridpd.analysis.continuation import continue_symmetric
    >>> br = continue_symmetric(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0, "kv", 23.0)
    >>> p = br.save(Path(tempfile.mkdtemp()) / "kv.npz")
    >>> back = load_branch(p)
    >>> bool((back.spectral_radius == br.spectral_radius).all()), len(back.events)
    (True, 1)
    """
    _check_npz(path)
    with np.load(path, allow_pickle=False) as z:
        a = {k: z[k] for k in z.files}
    meta = json.loads(str(a.pop("__metadata__", np.array("{}"))[()]))
    if meta.get("kind") != "branch":
        raise ValueError(f"{path} does not hold a continued branch")
    return Branch(parameter_name=meta["parameter_name"], parameter=a["parameter"],
                  points=a["points"], multipliers=a["multipliers"],
                  spectral_radius=a["spectral_radius"], stable=a["stable"].astype(bool),
                  viable=a["viable"].astype(bool), margin=a["margin"],
                  min_impact_speed=a["min_impact_speed"], xm=a["xm"],
                  period=int(meta["period"]), patterns=_tuples(meta["patterns"]),
                  events=[_event(d) for d in meta["events"]],
                  termination=meta["termination"], family=meta["family"],
                  method=meta["method"], case=Case.parse(meta["case"]), fixed=meta["fixed"],
                  n_rejected=int(meta["n_rejected"]),
                  newton_iterations=a["newton_iterations"].astype(np.int64))
