"""Module-level sweep functions and helpers shared by the sweep tests.

The functions swept are module-level so that process-pool and Dask workers can import them
by name. Calls are counted through a side channel: the function writes one empty file per
call into ``log_dir/calls`` (this works across processes); ``log_dir`` is part of
``func_kwargs``, hence of the sweep identity, so every run that must be comparable uses the
same ``log_dir`` and clears ``calls/`` in between.
"""


from __future__ import annotations

import os
import time
import uuid
from pathlib import Path

import numpy as np

from hybridpd.sweeps.sweep import (
    SweepResult,
    grid_points,
)

REPO = Path(__file__).resolve().parents[1]


def model_func(chunk, *, log_dir=None, sleep=0.0, slow_at=None):
    """Mixed dtypes and trailing shapes; optional call log, failure, delay.

    A file ``log_dir/fail_at`` holding a point index makes the chunk starting
    there raise (the trigger is outside func_kwargs so the identity does not
    change between the failing and the resumed run).
    """
    i = chunk["i"]
    start = int(i[0])
    if log_dir is not None:
        calls = Path(log_dir) / "calls"
        calls.mkdir(exist_ok=True)
        (calls / f"{start}-{os.getpid()}-{uuid.uuid4().hex[:6]}").touch()
        fail = Path(log_dir) / "fail_at"
        if fail.exists() and int(fail.read_text()) == start:
            raise RuntimeError(f"boom at point {start}")
    if sleep:
        time.sleep(sleep)
    if slow_at is not None and start == slow_at:
        time.sleep(60)
    kp, kv, e = chunk["kp"], chunk["kv"], chunk["e"]
    disc = kv**2 - 4.0 * kp
    root = np.sqrt(disc.astype(complex))
    return {
        "disc": disc,
        "stable": disc < e * kp,
        "count": (np.floor(kp * 7) % 5).astype(np.int64),
        "eig": np.stack([(-kv + root) / 2, (-kv - root) / 2], axis=1),  # (m, 2) complex
        "mat": np.stack([np.outer(a, [1, 2, 3]) for a in np.stack([kp, kv], axis=1)]).astype(
            np.float32
        ),
        "u8": (i % 256).astype(np.uint8),
    }


def sum_func(chunk):
    return {"s": chunk["x0"] + 2 * chunk["x1"]}


def wrong_length_func(chunk):
    return {"y": chunk["x"][:-1]}


def object_func(chunk):
    return {"y": np.array([object()] * len(chunk["x"]))}


def not_dict_func(chunk):
    return chunk["x"]


def dtype_switch_func(chunk):
    x = chunk["x"]
    return {"y": x.astype(np.int64) if x[0] == 0 else x}


def inplace_func(chunk):
    chunk["x"] *= 2  # modifies its input: must be allowed, and harmless
    return {"y": chunk["x"]}


def sleepy_func(chunk, *, log_dir):
    (Path(log_dir) / f"pid-{os.getpid()}").touch()
    time.sleep(30)
    return {"y": chunk["x"]}


def points_grid(n_kp=13, n_kv=11, es=(0.1, 0.5, 0.9)):
    axes = {
        "e": np.asarray(es),
        "kp": np.linspace(0.5, 30.0, n_kp),
        "kv": np.linspace(0.1, 40.0, n_kv),
    }
    pts, shape = grid_points(axes)
    pts["i"] = np.arange(len(pts["e"]))
    return pts, shape


def assert_same_outputs(a: SweepResult, b: SweepResult):
    assert list(a.outputs) == list(b.outputs)
    for k in a.outputs:
        assert a.outputs[k].dtype == b.outputs[k].dtype, k
        assert a.outputs[k].shape == b.outputs[k].shape, k
        np.testing.assert_array_equal(a.outputs[k], b.outputs[k], err_msg=k)


def calls_by_start(log_dir: Path) -> list[int]:
    d = log_dir / "calls"
    return sorted(int(p.name.split("-")[0]) for p in d.iterdir()) if d.exists() else []


def clear_calls(log_dir: Path):
    d = log_dir / "calls"
    if d.exists():
        for p in d.iterdir():
            p.unlink()


def pid_alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/status") as fh:
            return "\nState:\tZ" not in fh.read()
    except FileNotFoundError:
        return False
    except OSError:  # pragma: no cover - non-Linux
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return False
        return True


def tree_bytes(root: Path) -> dict[str, bytes]:
    """Every file of a store, by relative path (the store's full on-disk content)."""
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


def store_status(store: Path) -> str:
    import zarr

    return zarr.open_group(str(store), mode="r").attrs["hybridpd_sweep"]["status"]


def done_chunks(store: Path) -> list[int]:
    """Chunks flagged done in a store (read by Zarr, possibly while another process writes)."""
    import zarr

    try:
        flags = zarr.open_group(str(store), mode="r")["_sweep/done"][:]
    except Exception:  # noqa: BLE001 - not created yet
        return []
    return np.flatnonzero(flags).tolist()


def chunk_file(store: Path, name: str, i: int) -> Path:
    """The Zarr chunk file of sweep chunk `i` of output `name` (Zarr format 2 key)."""
    import zarr

    ndim = zarr.open_group(str(store), mode="r")[name].ndim
    return store / name / ".".join([str(i)] + ["0"] * (ndim - 1))


def wait_until(cond, timeout=20.0, what="condition"):
    t_end = time.monotonic() + timeout
    while time.monotonic() < t_end:
        if cond():
            return
        time.sleep(0.02)
    raise AssertionError(f"timed out waiting for {what}")


def slow_model_func(chunk, *, log_dir=None):
    """model_func slowed down by an environment variable (not part of the identity)."""
    time.sleep(float(os.environ.get("SWEEP_TEST_SLEEP", "0")))
    return model_func(chunk, log_dir=log_dir)
