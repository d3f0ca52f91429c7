"""The one result writer: the ``.npz`` codec from and to the dataset, and ``to_dict`` from the
fields (``hybridpd._results``)."""
import json
from dataclasses import dataclass, field

import numpy as np
import pytest
import xarray as xr

from hybridpd._results import Fields, Result, read_dataset, read_npz, write_dataset, write_npz


def _dataset():
    return xr.Dataset(
        {"stable": (("e", "kv"), np.array([[True, False, True]])),
         "rho": (("e", "kv"), np.array([[0.5, np.nan, 2.0]]), {"units": "1"}),
         "lam": (("kv",), np.array([1 + 2j, -0.5j, 3.0])),
         "code": (("kv",), np.array([0, 3, 7], np.int8),
                  {"flag_values": np.array([0, 3, 7], np.int8), "flag_meanings": "a b c"})},
        coords={"e": [0.5], "kv": [1.0, 2.0, 3.0], "coordinate": ("coordinate", ["x1", "y1"])},
        attrs={"kind": "scan", "case": "collocated", "n": 2, "x10": 1.5,
               "fixed": "json:" + json.dumps({"mu": 0.1, "L": 0.75})})


def test_npz_gives_back_the_dataset_it_was_written_from(tmp_path):
    ds = _dataset()
    back = read_npz(write_npz(ds, tmp_path / "scan.npz"))
    # the same variables, dimensions, values and dtypes; the attributes as netCDF holds them
    assert set(back.variables) == set(ds.variables)
    assert set(back.coords) == set(ds.coords) and set(back.data_vars) == set(ds.data_vars)
    for name, v in ds.variables.items():
        assert back[name].dims == v.dims, name
        assert back[name].dtype == v.dtype, name
        assert np.array_equal(back[name].values, v.values,
                              equal_nan=v.dtype.kind in "fc"), name
    assert back.attrs == ds.attrs
    assert back.rho.attrs == {"units": "1"}
    assert back.code.attrs["flag_values"] == [0, 3, 7]
    # and what a netCDF file gives back, variable for variable
    nc = read_dataset(write_dataset(ds, tmp_path / "scan.nc"))
    for name in ds.variables:
        assert np.array_equal(nc[name].values, back[name].values,
                              equal_nan=back[name].dtype.kind in "fc"), name
    assert dict(nc.attrs) == dict(back.attrs)


def test_npz_is_a_plain_numpy_archive_replaced_atomically(tmp_path):
    p = write_npz(_dataset(), tmp_path / "scan.npz")
    with np.load(p, allow_pickle=False) as z:       # no pickle needed
        meta = json.loads(str(z["__metadata__"][()]))
        assert meta["kind"] == "scan" and meta["format"] == "hybridpd.dataset/1"
        assert z["kv"].tolist() == [1.0, 2.0, 3.0]
    write_npz(_dataset().assign(rho=(("e", "kv"), np.zeros((1, 3)))), p)
    assert read_npz(p).rho.values.tolist() == [[0.0, 0.0, 0.0]]
    assert [q.name for q in tmp_path.iterdir()] == ["scan.npz"]     # no temporary left


def test_other_archives_and_paths_are_refused(tmp_path):
    np.savez(tmp_path / "plain.npz", x=np.arange(3))
    np.savez(tmp_path / "old.npz", x=np.arange(3),
             __metadata__=np.array(json.dumps({"kind": "region_map", "case": "collocated"})))
    for name in ("plain.npz", "old.npz"):
        with pytest.raises(ValueError, match=f"{name}.*not a result archive"):
            read_npz(tmp_path / name)
    with pytest.raises(ValueError, match="does not exist"):
        read_npz(tmp_path / "missing.npz")
    with pytest.raises(ValueError, match="must end in one of .npz"):
        write_npz(_dataset(), tmp_path / "scan.nc")
    bad = xr.Dataset({"__metadata__": (("i",), np.zeros(2))})
    with pytest.raises(ValueError, match="__metadata__"):
        write_npz(bad, tmp_path / "bad.npz")


@dataclass(frozen=True, eq=False)
class _Scan(Result):
    kind = "scan"
    name: str
    p: np.ndarray = field(metadata={"coord": "@name"})
    rho: np.ndarray = field(metadata={"dims": ("@name",), "dict_name": "radius"})
    note: dict = field(default_factory=dict)
    seconds: float = field(default=0.0, metadata={"dict_skip": True})


def test_every_suffix_of_a_result_reads_back_the_same(tmp_path):
    r = _Scan("kv", np.array([1.0, 2.0]), np.array([0.5, np.nan]), {"k": (1, 2)}, 3.5)
    for suffix in (".nc", ".zarr", ".npz"):
        back = _Scan.load(r.save(tmp_path / f"scan{suffix}"))
        assert back.name == "kv" and back.note == {"k": [1, 2]} and back.seconds == 3.5
        assert np.array_equal(back.rho, r.rho, equal_nan=True) and back.p.tolist() == [1, 2]
        assert back.to_dict() == r.to_dict()


def test_to_dict_follows_the_fields_and_their_metadata():
    r = _Scan("kv", np.array([1.0, 2.0]), np.array([0.5, np.nan]), {"k": (1, 2)}, 3.5)
    assert r.to_dict() == {"name": "kv", "p": [1.0, 2.0], "radius": [0.5, None],
                           "note": {"k": [1, 2]}}

    @dataclass(frozen=True)
    class End(Fields):
        m2: float
        kind: str
        inner: object = None

    e = End(np.float64(0.5), "window", End(1.0, "stability"))
    d = e.to_dict()
    assert d == {"m2": 0.5, "kind": "window",
                 "inner": {"m2": 1.0, "kind": "stability", "inner": None}}
    assert type(d["m2"]) is float and json.loads(json.dumps(d)) == d
