"""Labelled results: xarray Datasets, netCDF/Zarr by suffix, files of earlier versions."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from _regions import pair_region_map

from hybridpd import ImpactPair, PDGains
from hybridpd.analysis.basins import basin_of_attraction, load_basin
from hybridpd.pair.basins import ImpactMapper
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.orbits import symmetric_orbit
from hybridpd.sweeps.labelled import check_suffix, decode_attrs, encode_attrs, write_dataset
from hybridpd.sweeps.regions import load_region_map
from hybridpd.sweeps.sweep import load_sweep, run_sweep

xr = pytest.importorskip("xarray")
DATA = Path(__file__).parent / "data"
REPO = Path(__file__).resolve().parents[1]
PAPER = dict(mu=0.1, omega=5.0, gamma=0.75)
# Files of earlier versions were computed on another machine with other library versions: their
# floating-point values agree with a fresh computation to rounding (amplified by up to ~1e3 where
# a spectral radius is large), not bit for bit. Booleans, labels and counts must agree exactly.
STORED_RTOL = 1e-9
STORED_ATOL = 1e-12
#: Iterations to enter a criterion, against stored files: rounding moves a point's count by a few.
ITER_ATOL = 5


@pytest.fixture(scope="module")
def rm():
    return pair_region_map("noncollocated", x=("kp", 0.5, 30, 5), y=("kv", 0.2, 20, 4),
                           e=(0.1, 0.5), progress=False, **PAPER)


@pytest.fixture(scope="module")
def basin():
    orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    m = ImpactMapper(ImpactMap(orb.pair, orb.gains, orb.reference()), orb.fixed_point)
    return basin_of_attraction(m.map, (-3, 5, 6), (-2, 10, 5), criterion=m, max_period=0)


def assert_close_or_equal(actual, desired, err_msg):
    """Floats to the stored tolerance (NaN where NaN), everything else exactly."""
    actual, desired = np.asarray(actual), np.asarray(desired)
    if np.issubdtype(desired.dtype, np.floating):
        np.testing.assert_allclose(actual, desired, rtol=STORED_RTOL, atol=STORED_ATOL,
                                   equal_nan=True, err_msg=err_msg)
    else:
        np.testing.assert_array_equal(actual, desired, err_msg=err_msg)


def assert_same_map(a, b, exact=True):
    """Same map; ``exact`` for a file round trip (the bits written are read back), else floats
    to the stored tolerance."""
    # files of earlier versions hold no table of reasons (the package's is REASONS)
    meta = lambda m: {k: v for k, v in m.metadata.items() if exact or k != "reasons"}
    assert (a.case, a.x_name, a.y_name, a.fixed, meta(a)) == (
        b.case, b.x_name, b.y_name, b.fixed, meta(b))
    for f in ("x", "y", "e", "exists", "stable", "reason", "spectral_radius", "xm"):
        va, vb = getattr(a, f), getattr(b, f)
        assert va.dtype == vb.dtype, f
        if exact:
            np.testing.assert_array_equal(va, vb, err_msg=f)
        else:
            assert_close_or_equal(va, vb, err_msg=f)


def assert_same_basin(a, b):
    for f in ("x1", "y1", "labels", "criterion_labels", "iterations", "fixed_point"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f), err_msg=f)
    assert a.converged_fraction == b.converged_fraction and a.metadata == b.metadata


def test_region_dataset_is_labelled_and_plots(rm):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ds = rm.to_dataset()
    assert ds.stable.dims == ("e", "kv", "kp") and ds.stable.dtype == bool
    assert ds.kp.attrs["units"] == "mass/time^2" and ds.kv.attrs["units"] == "mass/time"
    assert ds.e.attrs["units"] == "1" and ds.xm.attrs["units"] == "length"
    assert ds.attrs["case"] == "noncollocated" and ds.attrs["mu"] == 0.1
    assert ds.attrs["L"] == 0.75 and ds.attrs["n"] == 1
    # A labelled look-up gives what symmetric_orbit says at that point.
    kp, kv = float(ds.kp[3]), float(ds.kv[2])
    o = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(kp, kv), 5.0, case="noncollocated")
    assert bool(ds.exists.sel(e=0.5, kp=kp, kv=kv)) == o.exists
    assert bool(ds.stable.sel(e=0.5, kp=kp, kv=kv)) == (o.exists and o.stable)
    np.testing.assert_array_equal(ds.stable.sel(e=0.5).values, rm.stable[1])
    fig = plt.figure()
    ds.stable.sel(e=0.5).plot()
    ax = fig.axes[0]
    assert "kp" in ax.get_xlabel() and "kv" in ax.get_ylabel()
    plt.close(fig)
    meanings = ds.reason.attrs["flag_meanings"].split()
    assert meanings[0] == "exists" and len(meanings) == len(ds.reason.attrs["flag_values"])


@pytest.mark.parametrize("suffix", [".nc", ".zarr", ".npz"])
def test_region_map_round_trips_by_suffix(rm, tmp_path, suffix):
    p = tmp_path / f"map{suffix}"
    rm.save(p)
    assert_same_map(rm, load_region_map(p))
    rm.save(p)  # overwriting an earlier result is fine
    assert_same_map(rm, load_region_map(str(p)))
    if suffix != ".npz":  # any xarray user reads it without hybridpd
        engine = "netcdf4" if suffix == ".nc" else "zarr"
        with xr.open_dataset(p, engine=engine) as ds:
            np.testing.assert_array_equal(ds.stable.values, rm.stable)
            assert ds.kp.attrs["long_name"] == "proportional gain kp"


@pytest.mark.parametrize("suffix", [".nc", ".zarr", ".npz"])
def test_basin_round_trips_by_suffix(basin, tmp_path, suffix):
    ds = basin.to_dataset()
    assert ds.labels.dims == ("y1", "x1") and ds.x1.attrs["units"] == "length"
    assert ds.y1.attrs["units"] == "length/time"
    assert ds.criterion_labels.attrs["flag_meanings"].split()[0] == "converged"
    assert ds.labels.attrs["flag_meanings"].split()[0] == "converged_to_the_symmetric_orbit"
    meta = decode_attrs(ds.attrs)["metadata"]
    assert meta["kp"] == 10.0 and meta["case"] == "collocated"
    np.testing.assert_array_equal(ds.labels.sel(x1=basin.x1[2]).values, basin.labels[:, 2])
    p = tmp_path / f"b{suffix}"
    basin.save(p)
    assert_same_basin(basin, load_basin(p))


def test_unknown_suffix_is_refused(rm, basin, tmp_path):
    for call in (lambda: rm.save(tmp_path / "r.png"), lambda: load_region_map("r.txt"),
                 lambda: basin.save(tmp_path / "b.csv"), lambda: load_basin("b")):
        with pytest.raises(ValueError, match=r"must end in one of \.nc, \.zarr, \.npz"):
            call()
    assert not list(tmp_path.iterdir())
    assert check_suffix("A.NC") == ".nc"
    (tmp_path / "mine.zarr").mkdir()
    (tmp_path / "mine.zarr" / "notes.txt").write_text("x")
    with pytest.raises(ValueError, match="not a Zarr store"):
        write_dataset(rm.to_dataset(), tmp_path / "mine.zarr")
    assert (tmp_path / "mine.zarr" / "notes.txt").exists()
    assert [p.name for p in tmp_path.iterdir()] == ["mine.zarr"]  # no temporary left
    with pytest.raises(ValueError, match="does not exist"):
        load_region_map(tmp_path / "missing.nc")
    rm.save(tmp_path / "m.nc")
    with pytest.raises(ValueError, match="does not hold a basin"):
        load_basin(tmp_path / "m.nc")


def test_files_of_earlier_versions_stay_readable():
    """``.npz`` files written by the previous version (tests/data) equal a fresh computation."""
    old = load_region_map(DATA / "regions_v0.npz")
    new = pair_region_map("noncollocated", x=("kp", 0.5, 30, 5), y=("kv", 0.2, 20, 4),
                          e=(0.1, 0.5), progress=False, **PAPER)
    assert_same_map(old, new, exact=False)
    orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    m = ImpactMapper(ImpactMap(orb.pair, orb.gains, orb.reference()), orb.fixed_point)
    new_b = basin_of_attraction(m.map, (-3, 5, 5), (-2, 10, 4), criterion=m, max_period=0)
    old_b = load_basin(DATA / "basin_v0.npz")
    np.testing.assert_array_equal(old_b.labels, new_b.labels)
    np.testing.assert_array_equal(old_b.criterion_labels, new_b.criterion_labels)
    np.testing.assert_array_equal(old_b.iterations, new_b.iterations)
    assert old_b.metadata["kp"] == 10.0
    np.testing.assert_allclose(old_b.converged_fraction, new_b.converged_fraction,
                               rtol=STORED_RTOL, atol=0.0)
    from hybridpd.pair.regions import _region_chunk

    s = load_sweep(DATA / "sweep_v0.npz")
    pts = {"kp": np.linspace(1, 5, 6), "kv": np.linspace(1, 8, 6), "e": np.full(6, 0.5)}
    fixed = {"mu": 0.1, "omega": 5.0, "L": 0.75, "x10": 1.0, "m2": 1.0}
    fresh = run_sweep(_region_chunk, pts, executor="serial", chunk_size=4, progress=False,
                      func_kwargs={"case": "collocated", "n": 1, "fixed": fixed})
    assert s.metadata == {"kind": "region_sweep"} and s.n_chunks == 2
    for k, v in fresh.outputs.items():
        assert_close_or_equal(s.outputs[k], v, err_msg=k)


def test_basin_files_of_earlier_versions_read_as_the_one_basin_result():
    """The pair's basins, attractor basins and model basins written by the previous version
    (tests/data) read back as one :class:`BasinResult` equal to a fresh computation."""
    from _pair_model import PAIR

    from hybridpd.pair.basins import attractor_basin
    from hybridpd.sweeps.model_basins import model_basin

    orb = symmetric_orbit(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0)
    fresh = attractor_basin(ImpactMapper.from_orbit(orb, n_iter=300), (-3, 5, 6), (-2, 10, 5),
                            extend=False)
    for name in ("attractor_basin_v02.nc", "attractor_basin_v02.npz"):
        old = load_basin(DATA / name)
        assert old.axes == ("x1", "y1") and old.names == ("phi", "z1", "z2", "z4")
        for f in ("labels", "criterion_labels"):
            np.testing.assert_array_equal(getattr(old, f), getattr(fresh, f), err_msg=f)
        # how many iterations a point takes to enter the criterion depends on rounding (the
        # vectorised sin/cos of another CPU move the last digits): a few either way
        np.testing.assert_allclose(old.iterations, fresh.iterations, rtol=0, atol=ITER_ATOL,
                                   err_msg="iterations")
        for f in ("x1", "y1", "fixed_point"):
            np.testing.assert_allclose(getattr(old, f), getattr(fresh, f), rtol=STORED_RTOL,
                                       atol=STORED_ATOL, err_msg=f)
        assert [a.name for a in old.attractors] == [a.name for a in fresh.attractors]
        for a, b in zip(old.attractors, fresh.attractors):
            np.testing.assert_allclose(a.points, b.points, rtol=1e-7, atol=1e-9)
            assert a.walls == b.walls and a.stable == b.stable
        assert old.metadata["kp"] == 10.0 and old.metadata["gamma"] == 0.75
    orb5 = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    m5 = ImpactMapper.from_orbit(orb5, n_iter=100)
    pb = basin_of_attraction(m5.map, (-3, 5, 5), (-2, 10, 4), criterion=m5, max_period=0)
    old = load_basin(DATA / "basin_v02.nc")
    np.testing.assert_array_equal(old.labels, pb.labels)
    np.testing.assert_array_equal(old.criterion_labels, pb.criterion_labels)
    assert [a.label for a in old.attractors] == [a.label for a in pb.attractors]
    mb = model_basin(PAIR, ("x2", -1.0, 1.0, 4), ("x1_dot", -1.0, 3.0, 3), n_iter=100,
                     event="impact")
    old = load_basin(DATA / "model_basin_v02.nc")
    assert old.axes == mb.axes and old.names == mb.names and old.source == mb.source
    np.testing.assert_array_equal(old.labels, mb.labels)
    np.testing.assert_array_equal(old.criterion_labels, mb.criterion_labels)
    np.testing.assert_allclose(old.base, mb.base, rtol=1e-7, atol=1e-9)
    assert old.summary() == mb.summary()


def test_sweep_store_and_result_as_datasets(tmp_path):
    from hybridpd.sweeps.sweep import grid_points

    axes = {"e": np.array([0.1, 0.5]), "kp": np.linspace(1, 30, 4), "kv": np.linspace(1, 20, 3)}
    pts, shape = grid_points(axes)
    fixed = {"mu": 0.1, "omega": 5.0, "L": 0.75, "x10": 1.0, "m2": 1.0}
    from hybridpd.pair.regions import _region_chunk

    res = run_sweep(_region_chunk, pts, executor="serial", chunk_size=5, progress=False,
                    store=tmp_path / "s.zarr", metadata={"note": "x", "flag": True},
                    func_kwargs={"case": "collocated", "n": 1, "fixed": fixed})
    ds = res.to_dataset(grid=axes)
    assert ds.stable.dims == ("e", "kp", "kv")
    np.testing.assert_array_equal(ds.stable.values, res.grid("stable", shape))
    assert ds.attrs["note"] == "x" and ds.attrs["flag"] == "json:true"
    with pytest.raises(ValueError, match="grid does not generate"):
        res.to_dataset(grid={"e": [0.1, 0.5], "kp": [1.0], "kv": [1.0]})
    # The store itself opens with xarray: outputs over "point", the points as coordinates.
    with xr.open_dataset(tmp_path / "s.zarr", engine="zarr") as st:
        np.testing.assert_array_equal(st.stable.values, res.outputs["stable"])
        np.testing.assert_array_equal(st.stable.kp.values, pts["kp"])


@pytest.mark.parametrize("value", [0, -3, 2.5, "text", True, None, [1, 2], {"a": [1, None]},
                                   float("nan"), "json:looks encoded"])
def test_attrs_encoding_round_trips(value):
    enc = encode_attrs({"v": value})
    assert isinstance(enc["v"], (int, float, str)) and not isinstance(enc["v"], bool)
    dec = decode_attrs(enc)["v"]
    if isinstance(value, float) and np.isnan(value):
        assert np.isnan(dec)
    else:
        assert dec == value and type(dec) is type(value)


def test_import_hybridpd_does_not_import_xarray():
    code = ("import sys, hybridpd, hybridpd.pair.regions, hybridpd.pair.basins, "
            "hybridpd.sweeps.sweep; print(sorted(m for m in ('xarray', 'zarr', 'netCDF4', "
            "'tqdm') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], cwd=str(REPO), capture_output=True,
                         text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_docstring_examples_run():
    import doctest

    import hybridpd._results as res
    import hybridpd.sweeps.labelled as mod

    failures, tried = doctest.testmod(mod, optionflags=doctest.ELLIPSIS)
    f2, t2 = doctest.testmod(res, optionflags=doctest.ELLIPSIS, extraglobs={"np": np})
    assert tried + t2 >= 3 and failures + f2 == 0
