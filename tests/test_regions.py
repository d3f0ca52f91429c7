"""Region maps: pointwise agreement, executors, resume, bad grids; the CLI commands."""
import json
import subprocess
import sys

import numpy as np
import pytest
from _regions import pair_region_map

from hybridpd import ImpactPair, PDGains
from hybridpd.pair.orbits import symmetric_orbit
from hybridpd.sweeps.regions import load_region_map

PAPER = dict(mu=0.1, omega=5.0, gamma=0.75, x10=1.0, n=1)


@pytest.mark.parametrize("case", ["collocated", "noncollocated"])
def test_coarse_map_agrees_pointwise_with_symmetric_orbit(case):
    rm = pair_region_map(case, x=("kp", 0.5, 40, 7), y=("kv", 0.2, 30, 6), e=(0.1, 0.9), **PAPER)
    for k, e in enumerate(rm.e):
        for i, kv in enumerate(rm.y):
            for j, kp in enumerate(rm.x):
                o = symmetric_orbit(ImpactPair(0.1, e, 0.75), PDGains(kp, kv), 5.0, case=case)
                assert rm.exists[k, i, j] == o.exists
                if o.exists:
                    assert rm.stable[k, i, j] == o.stable
                    assert rm.spectral_radius[k, i, j] == pytest.approx(o.spectral_radius,
                                                                        rel=1e-10)


def test_other_axes_and_save_load(tmp_path):
    rm = pair_region_map("collocated", x=("mu", 0.05, 0.5, 5), y=("omega", 2, 8, 4), e=(0.5,),
                    kp=10, kv=20, gamma=0.75)
    assert rm.exists.shape == (1, 4, 5) and rm.x_name == "mu"
    o = symmetric_orbit(ImpactPair(rm.x[2], 0.5, 0.75), PDGains(10, 20), rm.y[1])
    assert rm.exists[0, 1, 2] == o.exists
    rm.save(tmp_path / "m.npz")
    back = load_region_map(tmp_path / "m.npz")
    np.testing.assert_array_equal(back.stable, rm.stable)
    np.testing.assert_array_equal(back.spectral_radius, rm.spectral_radius)
    assert back.fixed["kp"] == 10 and back.case == "collocated"


def _compare(a, b):
    for f in ("exists", "stable", "reason"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
    np.testing.assert_array_equal(np.nan_to_num(a.spectral_radius, nan=-1),
                                  np.nan_to_num(b.spectral_radius, nan=-1))


def test_same_results_serial_processes_dask():
    pytest.importorskip("distributed")
    kw = dict(x=("kp", 0.5, 30, 9), y=("kv", 0.2, 20, 8), e=(0.1, 0.5), **PAPER)
    serial = pair_region_map("noncollocated", **kw)
    procs = pair_region_map("noncollocated", executor="processes", max_workers=2, chunk_size=17, **kw)
    _compare(serial, procs)
    dask = pair_region_map("noncollocated", executor="dask", max_workers=2, chunk_size=17, **kw)
    _compare(serial, dask)


def test_interrupted_sweep_resumes_to_the_same_file(tmp_path, monkeypatch):
    from hybridpd.pair import regions

    kw = dict(x=("kp", 0.5, 30, 9), y=("kv", 0.2, 20, 8), e=(0.5,), chunk_size=10, **PAPER)
    full = pair_region_map("collocated", store=tmp_path / "full.zarr", executor="serial", **kw)
    calls = {"n": 0}
    original = regions.symmetric_orbits

    def flaky(*a, **k):
        calls["n"] += 1
        if calls["n"] == 4:
            raise KeyboardInterrupt   # the user pressed Ctrl-C mid-sweep
        return original(*a, **k)

    # interrupt inside the evaluation: the sweep's identity (its chunk function) is unchanged
    monkeypatch.setattr(regions, "symmetric_orbits", flaky)
    with pytest.raises(KeyboardInterrupt):
        pair_region_map("collocated", store=tmp_path / "part.zarr", executor="serial", **kw)
    done_before = calls["n"] - 1
    calls["n"] = -100  # counts again, never fails
    resumed = pair_region_map("collocated", store=tmp_path / "part.zarr", executor="serial", **kw)
    _compare(full, resumed)
    assert done_before == 3
    assert calls["n"] + 100 == 8 - 3  # 72 points, chunks of 10: only the 5 unfinished ran
    files = {p: sorted(q.relative_to(p) for q in p.rglob("*") if q.is_file())
             for p in (tmp_path / "part.zarr", tmp_path / "full.zarr")}
    for q in files[tmp_path / "full.zarr"]:  # the same store, file by file
        assert (tmp_path / "part.zarr" / q).read_bytes() == (tmp_path / "full.zarr" / q).read_bytes()
    assert files[tmp_path / "part.zarr"] == files[tmp_path / "full.zarr"]


@pytest.mark.parametrize("kwargs, match", [
    (dict(x=("kp", 5, 1, 10)), "increasing"),
    (dict(x=("kp", 0, float("nan"), 10)), "finite"),
    (dict(x=("kp", 1, 5, 0)), "NUM"),
    (dict(x=("kp", -1, 5, 4)), "> 0"),
    (dict(x=("zeta", 1, 5, 4)), "axis name"),
    (dict(e=()), "e must"),
    (dict(e=(1.2,)), "e must"),
    (dict(executor="threads-on-mars"), "executor"),
])
def test_bad_grids_raise(kwargs, match):
    kw = dict(x=("kp", 1, 5, 4), y=("kv", 1, 5, 4), e=(0.5,), **PAPER)
    kw.update(kwargs)
    with pytest.raises(ValueError, match=match):
        pair_region_map("collocated", **kw)


def cli(*args):
    return subprocess.run([sys.executable, "-m", "hybridpd", *args], capture_output=True,
                          text=True, timeout=600, check=False)


PLANT = ["--mu", "0.1", "--gamma", "0.75", "--omega", "5", "--n", "1"]


def test_cli_orbit_json():
    r = cli("orbit", "--case", "collocated", "--e", "0.5", "--kp", "10", "--kv", "20", *PLANT,
            "--json")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    o = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    assert d["exists"] is True and d["stable"] is True
    assert d["xm"] == pytest.approx(o.xm, rel=1e-12)
    assert d["spectral_radius"] == pytest.approx(o.spectral_radius, rel=1e-12)
    assert len(d["multipliers"]) == 4 and len(d["multipliers"][0]) == 2
    r = cli("orbit", "--case", "noncollocated", "--e", "0.9", "--kp", "10", "--kv", "20", *PLANT,
            "--json")
    d = json.loads(r.stdout)
    assert d["exists"] is False and d["stable"] is None and "viability" in d["reason"]
    for bad in (["--n", "2"], ["--e", "1.5"]):
        args = ["orbit", "--case", "collocated", "--e", "0.5", "--kp", "10", "--kv", "20",
                *PLANT]
        args[args.index(bad[0]) + 1] = bad[1]
        r = cli(*args)
        assert r.returncode == 2 and r.stderr.count("\n") == 1 and "Traceback" not in r.stderr


def test_cli_regions_and_basin_json():
    r = cli("regions", "--case", "noncollocated", "--e", "0.1", "0.5", "--kp", "0.5", "20", "4",
            "--kv", "0.2", "6", "3", *PLANT, "--json")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert d["e"] == [0.1, 0.5] and len(d["kp"]) == 4 and len(d["kv"]) == 3
    assert np.array(d["exists"]).shape == (2, 3, 4)
    rho = d["spectral_radius"]
    for k in range(2):
        for i in range(3):
            for j in range(4):
                assert (rho[k][i][j] is None) == (not d["exists"][k][i][j])
    r = cli("regions", "--case", "collocated", "--e", "0.5", "--kp", "5", "1", "4", "--kv", "1",
            "2", "3", *PLANT)
    assert r.returncode == 2 and r.stderr.count("\n") == 1
    r = cli("basin", "--case", "collocated", "--e", "0.5", "--kp", "10", "--kv", "20", *PLANT,
            "--x", "x1", "-2", "4", "5", "--y", "y1", "-1", "8", "4", "--json")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert np.array(d["labels"]).shape == (4, 5) and d["label_names"][0] == "converged"
    assert 0 <= d["converged_fraction"] <= 1 and "x1" in d["fixed_point"]


def test_cli_design_exit_codes():
    r = cli("design", "--case", "collocated", "--e", "0.5", *PLANT, "--json")
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    o = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(d["kp"], d["kv"]), 5.0)
    assert o.exists and o.stable
    assert o.spectral_radius == pytest.approx(d["spectral_radius"], rel=1e-8)
    r = cli("design", "--case", "noncollocated", "--e", "0.5", *PLANT, "--kp-range", "50", "60",
            "--kv-range", "50", "60")
    assert r.returncode == 3 and r.stderr.count("\n") == 1
    r = cli("design", "--case", "collocated", "--e", "0.5", *PLANT, "--kp-range", "5", "1")
    assert r.returncode == 2 and r.stderr.count("\n") == 1


def test_region_figure_labels_cells_with_k_returns_per_period():
    """Cells whose orbit returns twice per period carry their own hatch and legend entry, and
    the hatch covers exactly the grid points of those cells (tested on the drawn paths)."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.path import Path as MPath

    from hybridpd.plotting.regions import plot_region_panels
    from hybridpd.sweeps.regions import RegionMap

    x, y = np.linspace(0.0, 4.0, 5), np.linspace(0.0, 3.0, 4)
    exists = np.ones((1, 4, 5), bool)
    exists[0, 0, 0] = False
    k = np.ones((1, 4, 5), np.int64)
    k[0, 2:, 3:] = 2                       # a 2 x 2 block of period-2 orbits
    stable = exists & (k == 1)
    rm = RegionMap("model.toml", "kp", "kv", x, y, np.array([0.5]), {}, exists, stable,
                   np.where(exists, 0.5, np.nan), np.where(exists, 0, 2), {"period": k})
    fig = plot_region_panels(rm, title="k test")
    labels = {t.get_text() for leg in fig.legends for t in leg.get_texts()}
    assert "k = 2 returns per period" in labels
    ax = fig.axes[0]
    hatched = [a for a in ax.collections if a.get_gid() == "k = 2 returns per period"]
    assert len(hatched) == 1
    paths = hatched[0].get_paths()
    inside = lambda px, py: any(MPath(p.vertices).contains_point((px, py), radius=1e-9)
                                or np.min(np.hypot(p.vertices[:, 0] - px,
                                                   p.vertices[:, 1] - py)) < 1e-9
                                for p in paths)
    for iy in range(4):
        for ix in range(5):
            assert inside(x[ix], y[iy]) == bool(k[0, iy, ix] == 2), (iy, ix)
    # an orbit everywhere but one cell: no white where an orbit exists
    assert rm.returns()[0, 0, 0] == 0 and rm.returns()[0, 3, 4] == 2
