"""Sweeps on an existing dask.distributed cluster: a real ``dask scheduler`` and ``dask worker``
processes on 127.0.0.1 (free ports), one worker killed mid-sweep, results identical to serial,
an interrupted client resumed from the Zarr store, and the command line's ``--scheduler``."""
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("distributed")

from _sweepfuncs import model_func

from hybridpd.cli import main
from hybridpd.sweeps.sweep import ChunkError, grid_points, run_sweep

ROOT = Path(__file__).resolve().parents[1]
DASK = shutil.which("dask", path=os.path.dirname(sys.executable)) or shutil.which("dask")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _stop(proc):
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=10)


@pytest.fixture(scope="module")
def cluster():
    if DASK is None:
        pytest.skip("the dask command is not installed")
    from distributed import Client

    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), str(ROOT / "tests")]),
               OPENBLAS_NUM_THREADS="1", DASK_DISTRIBUTED__WORKER__DAEMON="False")
    env.pop("DASK_SCHEDULER_ADDRESS", None)
    port = _free_port()
    addr = f"tcp://127.0.0.1:{port}"
    procs = []
    log = open(os.devnull, "w")  # noqa: SIM115 - closed in the teardown
    try:
        procs.append(subprocess.Popen([DASK, "scheduler", "--host", "127.0.0.1", "--port",
                                       str(port), "--dashboard-address", ":0"], env=env,
                                      stdout=log, stderr=log))
        workers = []
        for k in range(2):
            w = subprocess.Popen([DASK, "worker", addr, "--nthreads", "1", "--no-nanny",
                                  "--host", "127.0.0.1", "--name", f"w{k}",
                                  "--dashboard-address", ":0", "--death-timeout", "60"],
                                 env=env, stdout=log, stderr=log)
            procs.append(w)
            workers.append(w)
        with Client(addr, timeout="60s", set_as_default=False) as c:
            c.wait_for_workers(2, timeout=60)
        yield {"address": addr, "workers": workers, "env": env}
    finally:
        for p in reversed(procs):
            _stop(p)
        log.close()


def _grid():
    return grid_points({"kp": np.linspace(0.5, 4.0, 12), "kv": np.linspace(0.1, 3.0, 10),
                        "e": np.array([0.3])})[0] | {"i": np.arange(120.0)}


def _same(a, b):
    for k in a.outputs:
        np.testing.assert_allclose(a.outputs[k], b.outputs[k], rtol=0, atol=0,
                                   err_msg=f"{k}: the cluster's result is not the serial one")


def test_worker_killed_mid_sweep_costs_only_its_chunks(cluster, tmp_path):
    pts = _grid()
    # the reference without the delay, which only gives the kill below time to land mid-sweep
    serial = run_sweep(model_func, pts, chunk_size=4, executor="serial", progress=False)
    store = tmp_path / "kill.zarr"
    victim = cluster["workers"][1]
    killed = threading.Event()

    def kill_when_started():
        t_end = time.monotonic() + 60
        while time.monotonic() < t_end:
            done = list((store / "done").glob("*")) if (store / "done").exists() else []
            if len(list(store.rglob("*"))) > 20 or done:
                break
            time.sleep(0.05)
        time.sleep(0.4)                       # both workers are inside a chunk now
        victim.send_signal(signal.SIGKILL)
        killed.set()

    th = threading.Thread(target=kill_when_started, daemon=True)
    th.start()
    res = run_sweep(model_func, pts, chunk_size=4, executor=cluster["address"], store=store,
                    progress=False, func_kwargs={"sleep": 0.15}, timeout=120)
    th.join(timeout=60)
    assert killed.is_set() and victim.wait(timeout=10) is not None
    assert res.executor.startswith("dask[tcp://127.0.0.1:")
    assert res.n_chunks == 30 and res.n_resumed == 0
    _same(serial, res)


def test_interrupted_client_resumes_from_the_store(cluster, tmp_path):
    pts = _grid()
    log = tmp_path / "log"
    log.mkdir()
    serial = run_sweep(model_func, pts, chunk_size=8, executor="serial", progress=False,
                       func_kwargs={"log_dir": str(log)})
    (log / "fail_at").write_text("64")       # the chunk of points 64..71 fails: the run stops
    store = tmp_path / "resume.zarr"
    with pytest.raises(ChunkError):
        run_sweep(model_func, pts, chunk_size=8, executor=cluster["address"], store=store,
                  progress=False, func_kwargs={"log_dir": str(log)})
    (log / "fail_at").unlink()
    os.environ["DASK_SCHEDULER_ADDRESS"] = cluster["address"]
    try:
        res = run_sweep(model_func, pts, chunk_size=8, executor="dask", store=store,
                        progress=False, func_kwargs={"log_dir": str(log)})
    finally:
        del os.environ["DASK_SCHEDULER_ADDRESS"]
    assert res.n_resumed >= 1 and res.executor.startswith("dask[tcp://")
    _same(serial, res)


def test_cli_regions_on_the_cluster_match_serial(cluster, tmp_path, capsys, monkeypatch):
    base = ["regions", "--case", "collocated", "--mu", "0.1", "--e", "0.5", "--gamma", "0.75",
            "--omega", "5", "--kp", "1", "40", "6", "--kv", "1", "40", "5", "--json", "--quiet"]
    assert main(base) == 0
    ser = json.loads(capsys.readouterr().out)
    assert main([*base, "--scheduler", cluster["address"], "--store",
                 str(tmp_path / "r.zarr")]) == 0
    clu = json.loads(capsys.readouterr().out)
    assert clu == ser
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", cluster["address"])
    assert main(base) == 0
    assert json.loads(capsys.readouterr().out) == ser
    assert main([*base, "--scheduler", cluster["address"], "--executor", "processes"]) == 2
    assert "--scheduler" in capsys.readouterr().err
    assert main([*base, "--scheduler", "tcp://127.0.0.1:notaport"]) == 2
    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS")
    capsys.readouterr()
    bif = ["bifurcation", "--case", "collocated", "--mu", "0.1", "--e", "0.1", "--gamma",
           "0.75", "--omega", "5", "--kp", "10", "--param", "kv", "10", "35", "7",
           "--iterations", "120", "--keep", "24", "--out", str(tmp_path / "d.nc"), "--json"]
    assert main(bif) == 0
    ser = json.loads(capsys.readouterr().out)
    assert main([*bif, "--scheduler", cluster["address"]]) == 0
    assert json.loads(capsys.readouterr().out) == ser


@pytest.mark.slow      # the workers load the model code and compile: ~20 s on 2 cores
def test_model_region_map_on_the_cluster_is_the_serial_one(cluster, tmp_path):
    from _regions import model_region_map

    pair = {
        "system": {"dofs": ["x1", "x2"], "masses": [0.1, 1.0], "input": [0.0, 1.0]},
        "contact": [{"between": ["x1", "x2"], "lo": -0.75, "hi": 0.75, "restitution": 0.5}],
        "controller": {"type": "pd", "kp": 10.0, "kv": 20.0, "measure": "x2"},
        "reference": {"type": "sine", "amplitude": 0.4, "omega": 5.0,
                      "feedforward_mass": 1.0}}
    kw = {"x": ("controller.kp", 6.0, 14.0, 4), "y": ("controller.kv", 15.0, 25.0, 3),
          "tile": 2, "progress": False}
    ser = model_region_map(pair, executor="serial", **kw)
    clu = model_region_map(pair, executor=cluster["address"], store=tmp_path / "m.zarr", **kw)
    for k in ("status", "spectral_radius", "section_point", "signature", "n_orbits"):
        np.testing.assert_allclose(getattr(clu, k), getattr(ser, k), rtol=0, atol=0,
                                   err_msg=f"{k}: the cluster's map is not the serial one")
    again = model_region_map(pair, executor=cluster["address"], store=tmp_path / "m.zarr", **kw)
    np.testing.assert_allclose(again.spectral_radius, ser.spectral_radius, rtol=0, atol=0,
                               err_msg="resumed from the complete store")
