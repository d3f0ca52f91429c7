"""Stored results the pair must keep while its engines are replaced by the general ones.

A golden file ``tests/data/golden_<area>.npz`` holds named arrays computed by an earlier
version, with the fingerprint of the machine and libraries that computed them. On a machine
with the same fingerprint the current code must give the same bits (the replacement changed no
arithmetic); elsewhere the last digits may move (NumPy dispatches other SIMD kernels on other
CPUs, other versions round differently), so floats are compared to a relative tolerance and
discrete arrays (labels, counts) must agree at a stated share of their entries.

Record: ``save(path, arrays)``; compare: ``check(path, arrays)`` (every array of the file must
be given).
"""
from __future__ import annotations

import json
import os
import platform
from pathlib import Path

import numpy as np

DATA = Path(__file__).parent / "data"

#: Relative tolerance of floats and least share of equal entries of discrete arrays, used
#: when the fingerprint differs from the recording machine's.
RTOL, ATOL, SHARE = 1e-8, 1e-12, 0.99


def fingerprint() -> dict:
    """What decides the last bits of a float result: library versions, CPU features in use."""
    import numba
    import scipy
    from numpy._core._multiarray_umath import __cpu_features__

    return {"numpy": np.__version__, "scipy": scipy.__version__, "numba": numba.__version__,
            "python": platform.python_version(), "machine": platform.machine(),
            "cpu_features": sorted(k for k, v in __cpu_features__.items() if v),
            "npy_disable": os.environ.get("NPY_DISABLE_CPU_FEATURES", "")}


def save(path, arrays: dict) -> None:
    """Write ``arrays`` (name -> array) and this machine's fingerprint to ``path`` (.npz)."""
    path = Path(path)
    arrays = {k: np.asarray(v) for k, v in arrays.items()}
    np.savez_compressed(path, __fingerprint__=np.array(json.dumps(fingerprint())), **arrays)


def load(path) -> tuple[dict, dict]:
    """``(arrays, fingerprint)`` stored in ``path``."""
    with np.load(Path(path), allow_pickle=False) as f:
        arrays = {k: f[k] for k in f.files if k != "__fingerprint__"}
        fp = json.loads(str(f["__fingerprint__"]))
    return arrays, fp


def check(path, arrays: dict, atol: dict | None = None) -> bool:
    """Assert that ``arrays`` reproduce the stored ones; return whether bitwise was required.

    Bitwise (``np.array_equal`` with NaN equal to NaN, same dtype and shape) where this
    machine's fingerprint equals the recording one; otherwise floats to ``RTOL``/``ATOL`` and
    integer, boolean and string arrays equal at ``SHARE`` of their entries at least.
    ``atol`` (name -> absolute tolerance) replaces that rule for arrays whose entries are
    ill-conditioned, stated by the caller with the reason (e.g. the eigenvalues of a double
    root move like the square root of a change in the last digits: 1e-16 -> 1e-8).
    """
    atol = dict(atol or {})
    stored, fp = load(path)
    missing = sorted(set(stored) - set(arrays))
    assert not missing, f"not recomputed: {missing}"
    exact = fp == fingerprint()
    for name, old in stored.items():
        new = np.asarray(arrays[name])
        assert new.shape == old.shape, f"{name}: shape {new.shape} != stored {old.shape}"
        if exact:
            assert new.dtype == old.dtype, f"{name}: dtype {new.dtype} != stored {old.dtype}"
            same = np.array_equal(new, old, equal_nan=new.dtype.kind in "fc")
            if not same:
                bad = np.flatnonzero(~((new == old) | (np.isnan(new) & np.isnan(old))
                                       if new.dtype.kind in "fc" else new == old))
                raise AssertionError(f"{name}: {bad.size} of {new.size} entries differ "
                                     f"bitwise from the stored ones (first at {bad[:5]})")
        elif old.dtype.kind == "U" and old.size == 1 and _json(str(old)) is not None:
            _same_json(_json(str(new)), _json(str(old)), name)
        elif name in atol:
            np.testing.assert_allclose(new, old, rtol=0, atol=atol[name], equal_nan=True,
                                       err_msg=name)
        elif old.dtype.kind in "fc":
            np.testing.assert_allclose(new, old, rtol=RTOL, atol=ATOL, equal_nan=True,
                                       err_msg=name)
        else:
            share = float(np.mean(new == old)) if old.size else 1.0
            assert share >= SHARE, f"{name}: {share:.4f} of entries equal, < {SHARE}"
    return exact


def _json(text):
    try:
        return json.loads(text)
    except ValueError:
        return None


def _same_json(new, old, where):
    """A stored JSON object (metadata): the same keys and strings, numbers to ``RTOL``."""
    if isinstance(old, dict):
        assert isinstance(new, dict) and set(new) == set(old), f"{where}: keys differ"
        for k in old:
            _same_json(new[k], old[k], f"{where}.{k}")
    elif isinstance(old, list):
        assert isinstance(new, list) and len(new) == len(old), f"{where}: lengths differ"
        for i, (a, b) in enumerate(zip(new, old)):
            _same_json(a, b, f"{where}[{i}]")
    elif isinstance(old, float) or isinstance(new, float):
        np.testing.assert_allclose(new, old, rtol=RTOL, atol=ATOL, err_msg=where)
    else:
        assert new == old, f"{where}: {new!r} != stored {old!r}"
