"""Tests of the sweep store (hybridpd.sweeps.store): resume after errors, interruptions and
kills, recovery from damaged chunks, and refusal to mix sweeps of different identity."""


from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import uuid
from pathlib import Path

import numpy as np
import pytest
from _sweepfuncs import (
    REPO,
    assert_same_outputs,
    calls_by_start,
    chunk_file,
    clear_calls,
    done_chunks,
    model_func,
    pid_alive,
    points_grid,
    slow_model_func,
    store_status,
    sum_func,
    tree_bytes,
    wait_until,
)
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hybridpd.sweeps.store as store_mod
from hybridpd.sweeps.sweep import (
    ChunkError,
    load_sweep,
    run_sweep,
)

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


def _spawn(tmp_path, store, log, executor, workers, sleep):
    mod = model_func.__module__
    code = textwrap.dedent(f"""
        import importlib, signal, sys
        # Ctrl-C as a terminal delivers it: an ignored SIGINT (a disposition the test
        # process may have been left with by a library) would pass to this child
        signal.signal(signal.SIGINT, signal.default_int_handler)
        sys.path[:0] = [{str(REPO)!r}, {str(Path(__file__).parent)!r}]
        m = importlib.import_module({mod!r})
        pts, _ = m.points_grid()
        from hybridpd.sweeps.sweep import run_sweep
        run_sweep(m.slow_model_func, pts, chunk_size=40, executor={executor!r}, max_workers={workers!r},
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
    # slow enough that the signal comes well before the run could end, even on a loaded
    # machine where the start-up and the polling take long
    proc = _spawn(tmp_path, store, log, executor, workers, sleep=0.5)
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
    ida = store_mod.json_value({"w": np.arange(3.0)}, "func_kwargs", arrays="digest")
    idb = store_mod.json_value({"w": np.arange(3.0) + 1e-15 + 1}, "func_kwargs", arrays="digest")
    assert ida != idb
