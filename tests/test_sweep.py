"""Tests of the generic sweep engine (hybridpd.sweeps.sweep).

The functions swept here are module-level so that process-pool and Dask
workers can import them by name. Calls are counted through a side channel:
the function writes one empty file per call into ``log_dir/calls`` (this works
across processes); ``log_dir`` is part of ``func_kwargs``, hence of the sweep
identity, so every run that must be comparable uses the same ``log_dir`` and
clears ``calls/`` in between.
"""

from __future__ import annotations

import concurrent.futures as cf
import doctest
import functools
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
import uuid
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hybridpd.sweeps.store as store_mod
import hybridpd.sweeps.sweep as sweep_mod
from hybridpd.sweeps.progress import Progress
from hybridpd.sweeps.sweep import (
    ChunkError,
    SweepResult,
    default_chunk_size,
    grid_points,
    load_npz,
    load_sweep,
    resolve_executor,
    run_sweep,
    save_npz,
)

REPO = Path(__file__).resolve().parents[1]

# --------------------------------------------------------------------------
# Module-level sweep functions (importable by workers)
# --------------------------------------------------------------------------


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


# --------------------------------------------------------------------------
# Chunking and helpers
# --------------------------------------------------------------------------


def test_default_chunk_size_depends_on_n_only():
    assert default_chunk_size(1) == 1
    assert default_chunk_size(64) == 64
    assert default_chunk_size(65) == 64
    assert default_chunk_size(120_000) == 469  # 200 x 200 x 3 grid -> 256 chunks
    assert -(-120_000 // default_chunk_size(120_000)) == 256
    assert default_chunk_size(10**10) == 1 << 20
    for bad in (0, -3, 2.5, True, None):
        with pytest.raises(ValueError, match="n_points"):
            default_chunk_size(bad)


def test_grid_points_c_order():
    pts, shape = grid_points({"a": [1, 2], "b": [10, 20, 30]})
    assert shape == (2, 3)
    assert pts["a"].tolist() == [1, 1, 1, 2, 2, 2]
    assert pts["b"].tolist() == [10, 20, 30, 10, 20, 30]
    res = run_sweep(sum_func, {"x0": pts["a"], "x1": pts["b"]}, executor="serial")
    np.testing.assert_array_equal(
        res.grid("s", shape), np.add.outer([1, 2], 2 * np.array([10, 20, 30]))
    )
    with pytest.raises(ValueError, match="axes"):
        grid_points({})


def test_save_load_npz_roundtrip_and_deterministic(tmp_path):
    arrays = {
        "b": np.array([True, False, True]),
        "f": np.arange(12.0).reshape(3, 2, 2),
        "i": np.array([-1, 2, 3], dtype=np.int16),
        "c": np.array([1 + 2j]),
        "big": np.arange(3, dtype=">f8"),
    }
    meta = {
        "e": 0.5,
        "n": np.int64(3),
        "v": np.array([1.0, 2.0]),
        "s": "x",
        "nested": {"t": (1, 2)},
    }
    p1 = save_npz(tmp_path / "a.npz", arrays, meta)
    p2 = save_npz(tmp_path / "b.npz", arrays, meta)
    assert p1.read_bytes() == p2.read_bytes()  # fixed zip timestamps
    got, m = load_npz(p1)
    assert list(got) == list(arrays)
    for k, v in arrays.items():
        assert got[k].dtype == v.dtype and np.array_equal(got[k], v)
    assert m == {"e": 0.5, "n": 3, "v": [1.0, 2.0], "s": "x", "nested": {"t": [1, 2]}}
    # Standard numpy archive, readable without pickle.
    with np.load(p1, allow_pickle=False) as z:
        assert json.loads(str(z["__metadata__"][()]))["e"] == 0.5
    # Compressed variant, and no temporary files left behind.
    save_npz(tmp_path / "c.npz", arrays, meta, compress=True)
    assert np.array_equal(load_npz(tmp_path / "c.npz")[0]["f"], arrays["f"])
    assert not list(tmp_path.glob(".*.tmp"))
    # Plain numpy files load with empty metadata.
    np.savez(tmp_path / "plain.npz", x=np.arange(3))
    assert load_npz(tmp_path / "plain.npz")[1] == {}
    with pytest.raises(ValueError, match="__metadata__"):
        save_npz(tmp_path / "d.npz", {"__metadata__": np.zeros(1)})
    with pytest.raises(ValueError, match="object dtype"):
        save_npz(tmp_path / "d.npz", {"o": np.array([object()])})
    with pytest.raises(ValueError, match="metadata"):
        save_npz(tmp_path / "d.npz", {"x": np.zeros(1)}, {"bad": object()})


# --------------------------------------------------------------------------
# Same results whatever the executor
# --------------------------------------------------------------------------


def test_executors_agree_bit_for_bit(tmp_path):
    pts, _ = points_grid()
    n = len(pts["i"])  # 429 points, 9 chunks of 50
    runs = {}
    with cf.ThreadPoolExecutor(max_workers=3) as threads:
        for label, kw in {
            "serial": {"executor": "serial"},
            "proc1": {"executor": "processes", "max_workers": 1},
            "proc2": {"executor": "processes", "max_workers": 2},
            "threads": {"executor": threads},
        }.items():
            runs[label] = run_sweep(
                model_func,
                pts,
                chunk_size=50,
                store=tmp_path / f"{label}.zarr",
                metadata={"case": "test"},
                **kw,
            )
    ref = runs["serial"]
    assert ref.n_chunks == 9 and ref.n_points == n and ref.n_resumed == 0
    assert ref.executor == "serial" and runs["proc2"].executor == "processes[2]"
    assert list(ref.outputs) == sorted(ref.outputs)
    files = {label: tree_bytes(tmp_path / f"{label}.zarr") for label in runs}
    for label, res in runs.items():
        assert_same_outputs(ref, res)
        assert res.identity_hash == ref.identity_hash
        assert files[label] == files["serial"], label  # the whole store, byte for byte
    # The outputs are the function's values, in the original point order.
    direct = model_func({k: v.copy() for k, v in pts.items()})
    for k, v in direct.items():
        np.testing.assert_array_equal(ref.outputs[k], v)
    # Different chunk sizes give the same values (the function is pointwise).
    other = run_sweep(model_func, pts, chunk_size=7, executor="serial")
    assert other.n_chunks == -(-n // 7)
    assert_same_outputs(ref, other)


def test_trailing_shapes_and_mixed_dtypes_survive_the_store(tmp_path):
    pts, _ = points_grid(5, 4)
    res = run_sweep(
        model_func,
        pts,
        chunk_size=8,
        executor="serial",
        store=tmp_path / "s.zarr",
        metadata={"mu": 0.1, "gamma": 0.75},
    )
    expect = {
        "count": (np.int64, ()),
        "disc": (np.float64, ()),
        "eig": (np.complex128, (2,)),
        "mat": (np.float32, (2, 3)),
        "stable": (np.bool_, ()),
        "u8": (np.uint8, ()),
    }
    assert {k: (v.dtype.type, v.shape[1:]) for k, v in res.outputs.items()} == expect
    back = load_sweep(tmp_path / "s.zarr")
    assert_same_outputs(res, back)
    assert back.metadata == {"mu": 0.1, "gamma": 0.75}
    assert back.identity_hash == res.identity_hash
    assert list(back.points) == ["e", "kp", "kv", "i"]
    for k in pts:
        np.testing.assert_array_equal(back.points[k], pts[k])
    # The store is marked complete and carries the identity.
    assert store_status(tmp_path / "s.zarr") == "complete"
    # SweepResult.save to .zarr writes the very same store; .nc and .npz read back equal.
    res.save(tmp_path / "copy.zarr")
    assert tree_bytes(tmp_path / "copy.zarr") == tree_bytes(tmp_path / "s.zarr")
    for name in ("copy.nc", "copy.npz"):
        res.save(tmp_path / name)
        again = load_sweep(tmp_path / name)
        assert_same_outputs(res, again)
        assert again.metadata == res.metadata and again.identity_hash == res.identity_hash


def test_2d_points_and_private_copies():
    a = np.arange(20.0).reshape(10, 2)
    res = run_sweep(sum_func, a, chunk_size=3, executor="serial")
    assert list(res.points) == ["x0", "x1"]
    np.testing.assert_array_equal(res.outputs["s"], a[:, 0] + 2 * a[:, 1])
    res2 = run_sweep(inplace_func, {"x": a[:, 0]}, chunk_size=3, executor="serial")
    np.testing.assert_array_equal(res2.outputs["y"], 2 * a[:, 0])
    np.testing.assert_array_equal(a[:, 0], np.arange(0.0, 20.0, 2))  # caller's data untouched
    assert not res2.points["x"].flags.writeable
    named = run_sweep(sum_func, a, names=["x0", "x1"], executor="serial")
    assert named.identity_hash == run_sweep(sum_func, a, executor="serial").identity_hash


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(n=st.integers(1, 300), cs=st.integers(1, 320), seed=st.integers(0, 2**16))
def test_any_chunking_reproduces_direct_evaluation(n, cs, seed):
    rng = np.random.default_rng(seed)
    pts = {"x0": rng.integers(-50, 50, n), "x1": rng.normal(size=n)}
    res = run_sweep(sum_func, pts, chunk_size=cs, executor="serial")
    assert res.n_chunks == -(-n // cs)
    np.testing.assert_array_equal(res.outputs["s"], pts["x0"] + 2 * pts["x1"])


# --------------------------------------------------------------------------
# Dask
# --------------------------------------------------------------------------


@pytest.fixture(scope="module")
def dask_client():
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    )
    client = distributed.Client(cluster)
    yield client
    client.close()
    cluster.close()


def test_dask_localcluster_matches_serial(tmp_path, dask_client):
    """A real LocalCluster (2 worker processes) -- given as a Client, and created by "dask"."""
    pts, _ = points_grid(9, 7)  # 189 points
    ref = run_sweep(model_func, pts, chunk_size=20, executor="serial", store=tmp_path / "ref.zarr")
    via_client = run_sweep(
        model_func, pts, chunk_size=20, executor=dask_client, store=tmp_path / "c.zarr"
    )
    assert via_client.executor == "Client"
    assert_same_outputs(ref, via_client)
    assert tree_bytes(tmp_path / "c.zarr") == tree_bytes(tmp_path / "ref.zarr")
    assert dask_client.status == "running"  # a supplied client is left open
    t0 = time.perf_counter()
    own = run_sweep(
        model_func, pts, chunk_size=20, executor="dask", max_workers=2, store=tmp_path / "d.zarr"
    )
    assert time.perf_counter() - t0 < 30
    assert own.executor == "dask[2]"
    assert tree_bytes(tmp_path / "d.zarr") == tree_bytes(tmp_path / "ref.zarr")


def test_dask_worker_error_names_chunk(tmp_path, dask_client):
    log = tmp_path / "log"
    log.mkdir()
    (log / "fail_at").write_text("40")
    pts, _ = points_grid(9, 7)
    with pytest.raises(ChunkError, match=r"chunk 2 \(points 40:60\).*boom at point 40") as info:
        run_sweep(
            model_func,
            pts,
            chunk_size=20,
            executor=dask_client,
            store=tmp_path / "s.zarr",
            func_kwargs={"log_dir": str(log)},
        )
    assert info.value.chunk_index == 2
    (log / "fail_at").unlink()
    res = run_sweep(
        model_func,
        pts,
        chunk_size=20,
        executor=dask_client,
        store=tmp_path / "s.zarr",
        func_kwargs={"log_dir": str(log)},
    )
    assert res.n_resumed + res.n_computed == res.n_chunks == 10


# --------------------------------------------------------------------------
# Resume
# --------------------------------------------------------------------------


@pytest.mark.parametrize("executor,workers", [("serial", None), ("processes", 2)])
def test_resume_after_worker_error(tmp_path, executor, workers):
    pts, _ = points_grid()  # 429 points
    log = tmp_path / "log"
    log.mkdir()
    kw = {"chunk_size": 40, "func_kwargs": {"log_dir": str(log)}, "metadata": {"run": 1}}
    ref = run_sweep(model_func, pts, executor="serial", store=tmp_path / "ref.zarr", **kw)
    clear_calls(log)

    store = tmp_path / "run.zarr"
    (log / "fail_at").write_text("200")  # chunk 5 of 11
    with pytest.raises(ChunkError, match=r"chunk 5 \(points 200:240\)") as info:
        run_sweep(model_func, pts, executor=executor, max_workers=workers, store=store, **kw)
    assert info.value.chunk_index == 5 and (info.value.start, info.value.stop) == (200, 240)
    assert "boom at point 200" in repr(info.value.__cause__) or "boom" in str(info.value)
    saved = done_chunks(store)
    assert 5 not in saved
    if executor == "serial":
        assert saved == [0, 1, 2, 3, 4]  # everything before the failure is on disk
    else:
        # Chunks submitted before the failing one were done or running (not
        # cancellable) when it failed: all collected and saved.
        assert set(range(5)) <= set(saved)
    assert store_status(store) == "running"
    (log / "fail_at").unlink()
    clear_calls(log)

    res = run_sweep(model_func, pts, executor=executor, max_workers=workers, store=store, **kw)
    assert res.n_resumed == len(saved)
    computed = calls_by_start(log)
    assert computed == sorted(
        40 * i for i in range(11) if i not in saved
    )  # resumed chunks not recomputed
    assert_same_outputs(ref, res)
    assert tree_bytes(store) == tree_bytes(tmp_path / "ref.zarr")

    # A finished store is returned as is: nothing is recomputed.
    clear_calls(log)
    again = run_sweep(model_func, pts, executor=executor, max_workers=workers, store=store, **kw)
    assert again.n_resumed == again.n_chunks and calls_by_start(log) == []
    assert_same_outputs(ref, again)


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                HealthCheck.function_scoped_fixture])
@given(n=st.integers(1, 90), cs=st.integers(1, 30), fail=st.integers(0, 10**6))
def test_any_interrupted_store_resumes_to_the_uninterrupted_store(tmp_path, n, cs, fail):
    run_dir = tmp_path / uuid.uuid4().hex[:8]
    log = run_dir / "log"
    log.mkdir(parents=True)
    pts = {"i": np.arange(n), "kp": np.linspace(0.5, 30, n), "kv": np.linspace(0.1, 40, n)[::-1],
           "e": np.full(n, 0.5)}
    kw = {"chunk_size": cs, "executor": "serial", "progress": False,
          "func_kwargs": {"log_dir": str(log)}}
    run_sweep(model_func, pts, store=run_dir / "ref.zarr", **kw)
    n_chunks = -(-n // cs)
    k = fail % n_chunks
    (log / "fail_at").write_text(str(k * cs))
    with pytest.raises(ChunkError):
        run_sweep(model_func, pts, store=run_dir / "run.zarr", **kw)
    assert done_chunks(run_dir / "run.zarr") == list(range(k))
    (log / "fail_at").unlink()
    res = run_sweep(model_func, pts, store=run_dir / "run.zarr", **kw)
    assert res.n_resumed == k
    assert tree_bytes(run_dir / "run.zarr") == tree_bytes(run_dir / "ref.zarr")


def slow_model_func(chunk, *, log_dir=None):
    """model_func slowed down by an environment variable (not part of the identity)."""
    time.sleep(float(os.environ.get("SWEEP_TEST_SLEEP", "0")))
    return model_func(chunk, log_dir=log_dir)


def _spawn(tmp_path, store, log, executor, workers, sleep):
    mod = model_func.__module__
    code = textwrap.dedent(f"""
        import importlib, sys
        sys.path[:0] = [{str(REPO)!r}, {str(Path(__file__).parent)!r}]
        m = importlib.import_module({mod!r})
        pts, _ = m.points_grid()
        m.run_sweep(m.slow_model_func, pts, chunk_size=40, executor={executor!r}, max_workers={workers!r},
                    store={str(store)!r}, func_kwargs={{"log_dir": {str(log)!r}}}, metadata={{"run": 1}})
        """)
    return subprocess.Popen(
        [sys.executable, "-c", code],
        cwd=str(tmp_path),
        env={**os.environ, "SWEEP_TEST_SLEEP": str(sleep)},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )


@pytest.mark.parametrize(
    "executor,workers,sig", [("serial", None, signal.SIGKILL), ("processes", 2, signal.SIGINT)]
)
def test_resume_after_kill(tmp_path, executor, workers, sig):
    """Kill a real sweep process mid-run, resume, and get the very same file.

    SIGKILL: a hard crash (no clean-up at all). SIGINT: Ctrl-C, which must
    also stop the pool's worker processes promptly.
    """
    pts, _ = points_grid()
    log = tmp_path / "log"
    log.mkdir()
    kw = {"chunk_size": 40, "func_kwargs": {"log_dir": str(log)}, "metadata": {"run": 1}}
    ref = run_sweep(slow_model_func, pts, executor="serial", store=tmp_path / "ref.zarr", **kw)
    clear_calls(log)

    store = tmp_path / "run.zarr"
    proc = _spawn(tmp_path, store, log, executor, workers, sleep=0.15)
    try:
        wait_until(
            lambda: len(done_chunks(store)) >= 3 or proc.poll() is not None,
            what="three chunks done",
        )
        assert proc.poll() is None, proc.communicate()
        proc.send_signal(sig)
        proc.wait(timeout=15)
    finally:
        if proc.poll() is None:  # pragma: no cover - only on failure
            proc.kill()
            proc.wait()
    _, err = proc.communicate()
    assert proc.returncode != 0
    if sig == signal.SIGINT:
        assert b"KeyboardInterrupt" in err
        worker_pids = {int(p.name.split("-")[1]) for p in (log / "calls").iterdir()} - {proc.pid}
        assert worker_pids
        wait_until(
            lambda: not any(pid_alive(p) for p in worker_pids), timeout=10, what="workers to exit"
        )
    saved = done_chunks(store)
    assert 3 <= len(saved) < 11 and store_status(store) == "running"
    clear_calls(log)

    res = run_sweep(slow_model_func, pts, executor="serial", store=store, **kw)
    assert res.n_resumed == len(saved)
    assert calls_by_start(log) == sorted(40 * i for i in range(11) if i not in saved)
    assert_same_outputs(ref, res)
    assert tree_bytes(store) == tree_bytes(tmp_path / "ref.zarr")


def test_resume_recovers_from_corrupt_chunk_and_stale_temp(tmp_path):
    pts, _ = points_grid(5, 4)  # 60 points
    log = tmp_path / "log"
    log.mkdir()
    kw = {"chunk_size": 10, "executor": "serial", "func_kwargs": {"log_dir": str(log)}}
    ref = run_sweep(model_func, pts, store=tmp_path / "ref.zarr", **kw)
    store = tmp_path / "s.zarr"
    (log / "fail_at").write_text("30")
    with pytest.raises(ChunkError):
        run_sweep(model_func, pts, store=store, **kw)
    (log / "fail_at").unlink()
    chunk_file(store, "disc", 1).write_bytes(b"not a zarr chunk")  # e.g. disk trouble
    stale = chunk_file(store, "eig", 3).with_suffix(".abcdef.partial")
    stale.write_bytes(b"half")  # a write cut by a kill
    clear_calls(log)
    with pytest.warns(RuntimeWarning, match="unreadable chunk 1"):
        res = run_sweep(model_func, pts, store=store, **kw)
    assert res.n_resumed == 2  # chunks 0 and 2
    assert calls_by_start(log) == [10, 30, 40, 50]
    assert_same_outputs(ref, res)
    assert tree_bytes(store) == tree_bytes(tmp_path / "ref.zarr")  # stale temporary gone too


def test_resume_false_recomputes(tmp_path):
    pts, _ = points_grid(5, 4)
    log = tmp_path / "log"
    log.mkdir()
    kw = {"chunk_size": 16, "executor": "serial", "func_kwargs": {"log_dir": str(log)}}
    first = run_sweep(model_func, pts, store=tmp_path / "s.zarr", **kw)
    assert done_chunks(tmp_path / "s.zarr") == [0, 1, 2, 3]
    before = tree_bytes(tmp_path / "s.zarr")
    clear_calls(log)
    res = run_sweep(model_func, pts, store=tmp_path / "s.zarr", resume=False, **kw)
    assert res.n_resumed == 0 and len(calls_by_start(log)) == 4
    assert_same_outputs(first, res)
    assert tree_bytes(tmp_path / "s.zarr") == before


# --------------------------------------------------------------------------
# Identity
# --------------------------------------------------------------------------


def test_identity_mismatch_raises_and_never_mixes(tmp_path):
    pts, _ = points_grid(5, 4)
    log = tmp_path / "log"
    log.mkdir()
    base = {
        "chunk_size": 10,
        "executor": "serial",
        "func_kwargs": {"log_dir": str(log)},
        "metadata": {"e": 0.5},
    }
    # An interrupted store (manifest + some chunks) and a finished one.
    (log / "fail_at").write_text("30")
    with pytest.raises(ChunkError):
        run_sweep(model_func, pts, store=tmp_path / "partial.zarr", **base)
    (log / "fail_at").unlink()
    run_sweep(model_func, pts, store=tmp_path / "done.zarr", **base)

    changed_pts = {k: v.copy() for k, v in pts.items()}
    changed_pts["kp"][7] += 1e-12
    variants = {
        "points": dict(base, points=changed_pts),
        "func": dict(base, func=sum_func),
        "func_kwargs": dict(base, func_kwargs={"log_dir": str(log), "sleep": 0.0}),
        "metadata": dict(base, metadata={"e": 0.9}),
        "chunk_size": dict(base, chunk_size=11),
    }
    for store in ("partial.zarr", "done.zarr"):
        for what, kw in variants.items():
            kw = dict(kw)
            func = kw.pop("func", model_func)
            p = kw.pop("points", pts)
            with pytest.raises(ValueError, match=rf"different sweep.*{what}.*resume=False"):
                run_sweep(func, p, store=tmp_path / store, **kw)
    # Files untouched by the refused attempts: resuming the original still works.
    res = run_sweep(model_func, pts, store=tmp_path / "partial.zarr", **base)
    assert res.n_resumed == 3
    # resume=False overwrites deliberately.
    res = run_sweep(
        model_func,
        pts,
        store=tmp_path / "done.zarr",
        resume=False,
        **dict(base, metadata={"e": 0.9}),
    )
    assert load_sweep(tmp_path / "done.zarr").metadata == {"e": 0.9}


def test_identity_ignores_executor_and_workers_but_sees_array_kwargs():
    pts = {"x0": np.arange(10.0), "x1": np.ones(10)}
    a = run_sweep(sum_func, pts, executor="serial")
    b = run_sweep(sum_func, pts, executor="processes", max_workers=2)
    assert a.identity_hash == b.identity_hash
    ida = store_mod.jsonable({"w": np.arange(3.0)}, "func_kwargs", arrays="digest")
    idb = store_mod.jsonable({"w": np.arange(3.0) + 1e-15 + 1}, "func_kwargs", arrays="digest")
    assert ida != idb


# --------------------------------------------------------------------------
# Validation
# --------------------------------------------------------------------------

_PTS = {"x": np.arange(5.0)}


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"points": {}}, r"points is empty"),
        ({"points": {"x": np.array([])}}, r"points contains no point"),
        (
            {"points": {"x": np.arange(3.0), "y": np.arange(4.0)}},
            r"points arrays must all have the same length",
        ),
        ({"points": {"x": np.array([0.0, np.nan])}}, r"points\['x'\] contains NaN.*allow_nan"),
        ({"points": {"x": np.zeros((2, 2))}}, r"points\['x'\] must be 1-D"),
        ({"points": {"x": np.array(["a", "b"])}}, r"points\['x'\] has dtype"),
        ({"points": np.arange(4.0)}, r"points must be a dict of .* or a 2-D numeric array"),
        ({"points": np.zeros((3, 2)), "names": ["a"]}, r"names must be 2 distinct"),
        ({"names": ["a"]}, r"names applies only"),
        ({"chunk_size": 0}, r"chunk_size must be a positive integer"),
        ({"chunk_size": -2}, r"chunk_size must be a positive integer"),
        ({"chunk_size": 2.5}, r"chunk_size must be a positive integer"),
        ({"chunk_size": True}, r"chunk_size must be a positive integer"),
        ({"executor": "threads"}, r"executor must be one of 'serial', 'processes', 'dask'"),
        ({"executor": "Serial"}, r"executor must be one of"),
        ({"executor": 42}, r"executor must be one of"),
        ({"max_workers": 0}, r"max_workers must be a positive integer"),
        ({"timeout": 0}, r"timeout must be None or a positive number"),
        ({"timeout": float("nan")}, r"timeout must be None or a positive number"),
        ({"resume": "yes"}, r"resume must be True or False"),
        ({"progress": 1}, r"progress must be True or False"),
        ({"label": 3}, r"label must be None or a string"),
        ({"func_kwargs": [1]}, r"func_kwargs must be None or a dict"),
        ({"func_kwargs": {"f": object()}}, r"func_kwargs\['f'\] holds an object of type object"),
        ({"metadata": {"m": {1: 2}}}, r"metadata\['m'\] has a non-string key"),
        ({"metadata": "x"}, r"metadata must be None or a dict"),
        ({"func": 3}, r"func must be callable"),
        (
            {"func": lambda c: {"y": c["x"]}, "executor": "processes"},
            r"func .* cannot be pickled.*module level",
        ),
    ],
)
def test_bad_inputs_raise_value_error_naming_the_parameter(kwargs, match):
    kw = dict(kwargs)
    func = kw.pop("func", sum_func)
    points = kw.pop("points", _PTS)
    kw.setdefault("executor", "serial")
    with pytest.raises(ValueError, match=match):
        run_sweep(func, points, **kw)


def test_nan_allowed_on_request():
    res = run_sweep(inplace_func, {"x": np.array([1.0, np.nan])}, executor="serial", allow_nan=True)
    assert np.isnan(res.outputs["y"][1])


@pytest.mark.parametrize(
    "func,match",
    [
        (wrong_length_func, r"output 'y' of chunk 0 .* expected leading length 3"),
        (object_func, r"output 'y' of chunk 0 .* dtype object"),
        (not_dict_func, r"func must return a dict of arrays; func for chunk 0"),
        (
            dtype_switch_func,
            r"chunk 1 .* returned outputs \{y: float64 \(\)\} but earlier chunks returned \{y: int64",
        ),
    ],
)
def test_bad_outputs_raise_value_error_naming_the_chunk(func, match):
    with pytest.raises(ValueError, match=match):
        run_sweep(func, {"x": np.arange(6.0)}, chunk_size=3, executor="serial")


def test_bad_store_paths(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(ValueError, match="store .* is not a directory"):
        run_sweep(
            sum_func,
            {"x0": np.ones(2), "x1": np.ones(2)},
            executor="serial",
            store=tmp_path / "file",
        )
    pts = {"x0": np.ones(2), "x1": np.ones(2)}
    for name in ("d.npz", "d.nc"):
        with pytest.raises(ValueError, match=r"store .* names a \.(npz|nc) file.*\.zarr"):
            run_sweep(sum_func, pts, executor="serial", store=tmp_path / name)
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("x")  # never deleted by a sweep
    for resume in (True, False):
        with pytest.raises(ValueError, match="not a Zarr sweep store"):
            run_sweep(sum_func, pts, executor="serial", store=tmp_path / "mine", resume=resume)
    assert (tmp_path / "mine" / "notes.txt").exists()
    # A Zarr dataset that is not a sweep store (e.g. a saved result) is never overwritten.
    import xarray as xr

    xr.Dataset({"a": ("x", np.arange(3))}).to_zarr(tmp_path / "other.zarr", consolidated=False)
    before = tree_bytes(tmp_path / "other.zarr")
    for resume in (True, False):
        with pytest.raises(ValueError, match="not a Zarr sweep store"):
            run_sweep(sum_func, pts, executor="serial", store=tmp_path / "other.zarr",
                      resume=resume)
    assert tree_bytes(tmp_path / "other.zarr") == before
    with pytest.raises(ValueError, match="clash with point names"):
        run_sweep(inplace_func, {"x": np.ones(2), "y": np.ones(2)}, executor="serial",
                  store=tmp_path / "c.zarr")


def test_resolve_executor():
    assert resolve_executor("serial").kind == "serial"
    assert resolve_executor(None, 3).label == "processes[3]"
    assert resolve_executor("processes").max_workers >= 1
    with cf.ThreadPoolExecutor(2) as ex:
        assert resolve_executor(ex).kind == "executor"
    with pytest.raises(ValueError, match="max_workers"):
        resolve_executor("processes", -1)


# --------------------------------------------------------------------------
# Never hang; progress; light import; docs
# --------------------------------------------------------------------------


def test_timeout_stops_a_hung_pool(tmp_path):
    log = tmp_path / "log"
    log.mkdir()
    t0 = time.perf_counter()
    with pytest.raises(TimeoutError, match=r"timeout=0.5 s; pending chunks \[0, 1, 2, 3\]"):
        run_sweep(
            sleepy_func,
            {"x": np.arange(8.0)},
            chunk_size=2,
            executor="processes",
            max_workers=2,
            timeout=0.5,
            func_kwargs={"log_dir": str(log)},
        )
    assert time.perf_counter() - t0 < 10
    pids = [int(p.name[4:]) for p in log.glob("pid-*")]
    assert pids
    wait_until(lambda: not any(pid_alive(p) for p in pids), timeout=10, what="workers terminated")


def test_progress_counts_points_on_stderr_only(capfd, monkeypatch):
    # Report at every chunk (no interval, no delay) to see the lines of a short sweep.
    monkeypatch.setattr(sweep_mod, "Progress", functools.partial(Progress, interval=0, delay=0))
    pts = {"x0": np.arange(100.0), "x1": np.ones(100)}
    run_sweep(sum_func, pts, chunk_size=30, executor="serial", label="demo sweep")
    out, err = capfd.readouterr()
    assert out == ""
    lines = err.splitlines()
    assert [ln.split(":")[1].split()[0] for ln in lines] == ["30/100", "60/100", "90/100",
                                                             "100/100", "100/100"]
    assert lines[0].startswith("demo sweep: 30/100 points (30%)") and "done" in lines[-1]
    run_sweep(sum_func, pts, chunk_size=30, executor="serial", progress=False)
    assert capfd.readouterr() == ("", "")


def test_import_is_light():
    code = (
        "import sys; import hybridpd; before = set(sys.modules); import hybridpd.sweeps.sweep; "
        "new = set(sys.modules) - before; "
        "print(sorted(m for m in new if m.split('.')[0] in "
        "('dask', 'distributed', 'tqdm', 'zarr', 'xarray', 'netCDF4')))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=str(REPO), capture_output=True, text=True, check=True
    )
    assert out.stdout.strip() == "[]"


def test_docstring_examples_run():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        failures, tried = doctest.testmod(sweep_mod, optionflags=doctest.ELLIPSIS)
    assert tried > 5 and failures == 0
