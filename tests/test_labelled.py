"""Labelled results: xarray Datasets, netCDF/Zarr by suffix, files of earlier versions."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from _regions import pair_region_map

from hybridpd import ImpactPair, PDGains
from hybridpd._results import check_suffix, decode_attrs, encode_attrs, write_dataset
from hybridpd.analysis.basins import load_basin
from hybridpd.analysis.mappers import mapper
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.pair.orbits import symmetric_orbit
from hybridpd.sweeps.basins import basin_of_attraction
from hybridpd.sweeps.regions import load_region_map
from hybridpd.sweeps.sweep import run_sweep

xr = pytest.importorskip("xarray")
DATA = Path(__file__).parent / "data"
REPO = Path(__file__).resolve().parents[1]
PAPER = dict(mu=0.1, omega=5.0, gamma=0.75)
RM_AXES = (("kp", 0.5, 30, 5), ("kv", 0.2, 20, 4))
# Files of earlier versions were computed on another machine with other library versions (and
# another CPU: NumPy's vectorised sin, cos and exp differ in the last bit between its SIMD
# paths), so nothing in them is compared with a fresh computation for equality as such:
# * floats to STORED_RTOL: one evaluation rounds at ~1e-16; the spectral radii (up to ~7e3)
#   and the orbit amplitudes come out of an eigenvalue problem and a nonlinear solve whose
#   condition numbers here are below ~1e5, so 1e-9 leaves a margin of ~1e2;
# * counts of iterations to enter a criterion within ITER_ATOL;
# * labels, booleans and reasons exactly, but only at the points where they cannot flip by
#   rounding (see certain_points); elsewhere anything goes.
STORED_RTOL = 1e-9
STORED_ATOL = 1e-12
#: Iterations to enter a criterion, against stored files: rounding moves a point's count by a few.
ITER_ATOL = 5
#: Relative move of the inputs (gains, start points) that finds the points near a boundary: the
#: "uncertain" points of Grebogi, McDonald, Ott & Yorke (Phys. Lett. A 99, 1983), whose result
#: changes when the input moves by this much either way. The move is ~1e7 times the rounding of
#: one evaluation, so a point it leaves on its side of every boundary is not carried across one
#: by the rounding of another machine.
UNCERTAIN_SHIFT = 1e-9
#: Share of each stored grid that must be certain (all of it today): the exact comparison keeps
#: checking something.
MIN_CERTAIN = 0.9


@pytest.fixture(scope="module")
def rm():
    return _region_map(0.0)


def _region_map(shift):
    """The stored region map's computation, gains moved by the relative ``shift``."""
    (xn, xlo, xhi, nx), (yn, ylo, yhi, ny) = RM_AXES
    k = 1.0 + shift
    return pair_region_map("noncollocated", x=(xn, xlo * k, xhi * k, nx),
                           y=(yn, ylo * k, yhi * k, ny), e=(0.1, 0.5), progress=False, **PAPER)


def _shifted(axis, shift):
    """A start-point axis ``(..., lo, hi, n)`` moved by ``shift`` times its span."""
    *name, lo, hi, n = axis
    d = shift * (hi - lo)
    return (*name, lo + d, hi + d, n)


def certain_points(compute, fields):
    """``(result, certain)``: ``compute(0.0)`` and the mask of its points whose ``fields``
    (labels, booleans, reasons) stay the same when ``compute`` moves its inputs by
    ±:data:`UNCERTAIN_SHIFT`; only there can a stored value be required to equal them."""
    base = compute(0.0)
    value = lambda r, f: np.asarray(r[f] if isinstance(r, dict) else getattr(r, f))
    ok = np.ones(value(base, fields[0]).shape, bool)
    for shift in (UNCERTAIN_SHIFT, -UNCERTAIN_SHIFT):
        moved = compute(shift)
        for f in fields:
            ok &= value(moved, f) == value(base, f)
    assert ok.mean() >= MIN_CERTAIN, f"only {ok.sum()} of {ok.size} points are certain"
    return base, ok


@pytest.fixture(scope="module")
def basin():
    orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0)
    m = mapper(ImpactMap(orb.pair, orb.gains, orb.reference()), orb.fixed_point)
    return basin_of_attraction(m, (-3, 5, 6), (-2, 10, 5), max_period=0)


def assert_close_or_equal(actual, desired, err_msg, where=None):
    """Floats to the stored tolerance (NaN where NaN), everything else exactly; only at the
    points ``where`` (the certain points) when given."""
    actual, desired = np.asarray(actual), np.asarray(desired)
    assert actual.shape == desired.shape, err_msg
    if where is not None:
        actual, desired = actual[where], desired[where]
    if np.issubdtype(desired.dtype, np.floating):
        np.testing.assert_allclose(actual, desired, rtol=STORED_RTOL, atol=STORED_ATOL,
                                   equal_nan=True, err_msg=err_msg)
    else:
        np.testing.assert_array_equal(actual, desired, err_msg=err_msg)


def assert_same_map(a, b, exact=True, where=None):
    """Same map; ``exact`` for a file round trip (the bits written are read back), else floats
    to the stored tolerance and labels at the certain points ``where``."""
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
            assert_close_or_equal(va, vb, err_msg=f, where=None if f in ("x", "y", "e") else where)


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
    import hybridpd.sweeps.regions as mod

    failures, tried = doctest.testmod(mod, optionflags=doctest.ELLIPSIS)
    f2, t2 = doctest.testmod(res, optionflags=doctest.ELLIPSIS, extraglobs={"np": np})
    assert tried + t2 >= 3 and failures + f2 == 0
