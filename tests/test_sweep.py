"""Tests of the generic sweep engine (hybridpd.sweeps.sweep): chunking, executors, Dask,
validation, time-outs and progress (the store's resume and identity: test_sweep_store.py)."""


from __future__ import annotations

import concurrent.futures as cf
import doctest
import functools
import subprocess
import sys
import time
import warnings

import numpy as np
import pytest
from _sweepfuncs import (
    REPO,
    assert_same_outputs,
    dtype_switch_func,
    inplace_func,
    model_func,
    not_dict_func,
    object_func,
    pid_alive,
    points_grid,
    sleepy_func,
    store_status,
    sum_func,
    tree_bytes,
    wait_until,
    wrong_length_func,
)
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hybridpd.sweeps.sweep as sweep_mod
from hybridpd.sweeps.progress import Progress
from hybridpd.sweeps.sweep import (
    ChunkError,
    default_chunk_size,
    grid_points,
    load_sweep,
    resolve_executor,
    run_sweep,
)

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


def test_a_callable_progress_gets_the_points_done_and_nothing_on_stderr(capfd):
    calls = []
    pts = {"x0": np.arange(100.0), "x1": np.ones(100)}
    r = run_sweep(sum_func, pts, chunk_size=30, executor="serial",
                  progress=lambda done, total: calls.append((done, total)))
    assert calls == [(0, 100), (30, 100), (60, 100), (90, 100), (100, 100)]
    assert np.array_equal(r.outputs["s"], pts["x0"] + 2 * pts["x1"])
    assert capfd.readouterr() == ("", "")
    with pytest.raises(ValueError, match="progress"):
        run_sweep(sum_func, pts, progress="yes")


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
