"""``hybridpd plot`` and ``--plot``: every result file draws, bad paths are refused early."""
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from hybridpd import ImpactPair, PDGains
from hybridpd.cli import main

PAIR = ["--case", "collocated", "--mu", "0.1", "--e", "0.5", "--omega", "5"]
SIM = [*PAIR, "--L", "0.75", "--kp", "10", "--kv", "20", "--xm", "1",
       "--x0", "0.3", "0.5", "0", "0", "--t-end", "4"]
REGIONS = [*PAIR[:4], "--e", "0.1", "0.5", "--gamma", "0.75", "--omega", "5",
           "--kp", "1", "50", "6", "--kv", "1", "50", "5", "--quiet"]
BASIN = [*PAIR, "--gamma", "0.75", "--kp", "10", "--kv", "20", "--x", "x1", "-3", "5", "7",
         "--y", "y1", "-2", "10", "6", "--iterations", "100", "--max-extensions", "0", "--quiet"]
MODEL = str(Path(__file__).resolve().parents[1] / "examples" / "models" / "drivetrain.toml")


def assert_image(path):
    """The file is a complete image of the format its suffix names."""
    data = Path(path).read_bytes()
    suffix = Path(path).suffix
    if suffix == ".png":
        import matplotlib.image

        assert data[:8] == b"\x89PNG\r\n\x1a\n"
        img = matplotlib.image.imread(path)
        assert img.shape[0] > 200 and img.shape[1] > 200
        assert img[..., :3].std() > 0.05  # something is drawn, not a blank canvas
    elif suffix == ".pdf":
        assert data[:5] == b"%PDF-" and data.rstrip().endswith(b"%%EOF")
    else:
        assert suffix == ".svg" and b"<svg" in data[:1000] and data.rstrip().endswith(b"</svg>")


def one_error_line(capsys):
    err = capsys.readouterr().err.strip()
    assert err and len(err.splitlines()) == 1, err
    return err


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """One small file of every kind hybridpd writes (in every format it writes it in)."""
    from hybridpd.analysis.diagrams import bifurcation_diagram
    from hybridpd.analysis.mappers import Growth
    from hybridpd.pair.bifdiagram import PAIR_SETTINGS, ImpactMapFamily
    from hybridpd.pair.continuation import continue_symmetric
    from hybridpd.pair.orbits import symmetric_orbit
    from hybridpd.pair.regions import SymmetricFamily
    from hybridpd.reproduce.basins import orbit_mapper
    from hybridpd.sweeps.basins import basin_of_attraction
    from hybridpd.sweeps.regions import region_map

    d = tmp_path_factory.mktemp("results")
    out = {}
    fam = SymmetricFamily("collocated", e=(0.1, 0.5), mu=0.1, omega=5.0, gamma=0.75)
    rm = region_map(fam, x=("kp", 1, 50, 5), y=("kv", 1, 50, 4), progress=False)
    for suf in (".nc", ".zarr", ".npz"):
        out[f"region_map{suf}"] = rm.save(d / f"regions{suf}")
    pair = ImpactPair(0.1, 0.5, 0.75)
    orb = symmetric_orbit(pair, PDGains(10, 20), 5.0, x10=1.0)
    mapper = orbit_mapper(orb, n_iter=100)
    b = basin_of_attraction(mapper, (-3, 5, 6), (-2, 10, 5), max_period=0)
    for suf in (".nc", ".zarr", ".npz"):
        b.save(d / f"basin{suf}")
        out[f"basin{suf}"] = d / f"basin{suf}"
    ab = basin_of_attraction(mapper, (-3, 5, 6), (-2, 10, 5), grow=Growth(0))
    for suf in (".nc", ".zarr", ".npz"):
        ab.save(d / f"attractors{suf}")
        out[f"basin.attractors{suf}"] = d / f"attractors{suf}"
    fam = ImpactMapFamily(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0, "kv")
    diag = bifurcation_diagram(fam, [20.0, 22.0, 24.0], **dict(PAIR_SETTINGS, iterations=60,
                                                                keep=16))
    out["bifurcation_diagram.nc"] = diag.save(d / "diagram.nc")
    out["bifurcation_diagram.npz"] = diag.save(d / "diagram.npz")
    br = continue_symmetric(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0, "kv", 23.0)
    out["branch.nc"] = br.save(d / "branch.nc")
    out["branch.npz"] = br.save(d / "branch.npz")
    assert main(["simulate", *SIM, "--out", str(d / "pair.json")]) == 0
    out["trajectory.json"] = d / "pair.json"
    assert main(["simulate", "--model", MODEL, "--t-end", "3", "--samples", "400",
                 "--out", str(d / "model.json")]) == 0
    out["model_trajectory.json"] = d / "model.json"
    return out


KINDS = ["region_map.nc", "region_map.zarr", "region_map.npz", "basin.nc", "basin.zarr",
         "basin.npz", "basin.attractors.nc", "basin.attractors.zarr", "basin.attractors.npz",
         "bifurcation_diagram.npz", "bifurcation_diagram.nc", "branch.npz", "branch.nc",
         "trajectory.json", "model_trajectory.json"]


@pytest.mark.parametrize("name", KINDS)
def test_every_kind_round_trips_through_plot(files, name, tmp_path, capsys):
    from hybridpd.plotting.files import file_kind

    kind = name.split(".")[0].replace("model_", "")
    assert file_kind(files[name]) == kind
    suffix = (".png", ".pdf", ".svg")[KINDS.index(name) % 3]
    img = tmp_path / f"figure{suffix}"
    assert main(["plot", str(files[name]), "--out", str(img)]) == 0
    assert str(img) in capsys.readouterr().out
    assert_image(img)


def test_default_output_replaces_the_suffix(files, tmp_path):
    src = tmp_path / "run.json"
    shutil.copy(files["trajectory.json"], src)
    assert main(["plot", str(src)]) == 0
    assert_image(tmp_path / "run.png")
    store = tmp_path / "r.zarr"
    shutil.copytree(files["region_map.zarr"], store)
    assert main(["plot", str(store) + "/"]) == 0
    assert_image(tmp_path / "r.png")


def test_the_kind_comes_from_the_metadata_not_the_name(files, tmp_path):
    from hybridpd.plotting.files import file_kind

    # a basin named like a region map and a branch named like a diagram
    shutil.copy(files["basin.npz"], tmp_path / "regions.npz")
    shutil.copy(files["branch.npz"], tmp_path / "diagram.npz")
    assert file_kind(tmp_path / "regions.npz") == "basin"
    assert file_kind(tmp_path / "diagram.npz") == "branch"
    assert main(["plot", str(tmp_path / "diagram.npz"), "--quantity", "margin"]) == 0
    assert_image(tmp_path / "diagram.png")


def test_options_apply_to_their_kind_only(files, tmp_path, capsys):
    img = tmp_path / "d.png"
    assert main(["plot", str(files["bifurcation_diagram.npz"]), "--coordinate", "x1",
                 "--title", "kv sweep", "--out", str(img)]) == 0
    assert_image(img)
    assert main(["plot", str(files["region_map.nc"]), "--coordinate", "x1",
                 "--out", str(tmp_path / "r.png")]) == 2
    assert "coordinate" in one_error_line(capsys)
    assert not (tmp_path / "r.png").exists()


def test_unknown_or_unreadable_files_exit_2_with_one_line(files, tmp_path, capsys):
    text = tmp_path / "notes.txt"
    text.write_text("not a result\n")
    plain = tmp_path / "plain.npz"
    np.savez(plain, x=np.arange(3))
    nokind = tmp_path / "other.json"
    nokind.write_text(json.dumps({"impacts": []}))
    broken = tmp_path / "broken.nc"
    broken.write_bytes(b"\x89HDF\r\n\x1a\n" + b"\0" * 64)
    sweep = tmp_path / "sweep.npz"
    np.savez(sweep, x=np.arange(3), __metadata__=np.array(json.dumps({"kind": "something_else"})))
    for path, why in ((text, "neither"), (plain, "no hybridpd metadata"),
                      (nokind, "no hybridpd metadata"), (broken, "not a result file"),
                      (sweep, "something_else"), (tmp_path / "missing.nc", "does not exist")):
        assert main(["plot", str(path), "--out", str(tmp_path / "x.png")]) == 2
        err = one_error_line(capsys)
        assert why in err and str(path.name) in err
    assert not (tmp_path / "x.png").exists()
    # never overwrite the input with the default output
    img = tmp_path / "old.png"
    shutil.copy(files["basin.npz"], img)
    assert main(["plot", str(img)]) == 2
    assert "overwrite" in one_error_line(capsys)


def _no_compute(*args, **kwargs):
    raise AssertionError("computed before checking the output path")


@pytest.mark.parametrize("argv, allowed", [
    (["plot", "FILE", "--out", "x.jpg"], ".png, .pdf or .svg"),
    (["regions", *REGIONS, "--out", "r.png"], ".nc, .zarr or .npz"),
    (["regions", *REGIONS, "--plot", "r.npz"], ".png, .pdf or .svg"),
    (["basin", *BASIN, "--out", "b.png"], ".nc, .zarr or .npz"),
    (["basin", *BASIN, "--plot", "b.gif"], ".png, .pdf or .svg"),
    (["simulate", *SIM, "--out", "run.npz"], ".json"),
    (["simulate", *SIM, "--plot", "run"], ".png, .pdf or .svg"),
])
def test_unwritable_suffixes_are_refused_before_computing(argv, allowed, files, tmp_path,
                                                          monkeypatch, capsys):
    import hybridpd.pair.impactpair
    import hybridpd.pair.orbits
    import hybridpd.plotting.files
    import hybridpd.sweeps.regions

    monkeypatch.setattr(hybridpd.sweeps.regions, "region_map", _no_compute)
    monkeypatch.setattr(hybridpd.pair.orbits, "symmetric_orbit", _no_compute)
    monkeypatch.setattr(hybridpd.pair.impactpair, "ControlledImpactPair", _no_compute)
    monkeypatch.setattr(hybridpd.plotting.files, "plot_file", _no_compute)
    monkeypatch.chdir(tmp_path)
    argv = [str(files["branch.npz"]) if a == "FILE" else a for a in argv]
    assert main(argv) == 2
    err = one_error_line(capsys)
    assert allowed in err and "must end in" in err
    assert list(tmp_path.iterdir()) == []


def test_simulate_out_holds_dense_samples_that_agree_with_the_result(files):
    doc = json.loads(files["trajectory.json"].read_text())
    assert doc["kind"] == "trajectory" and doc["dofs"] == ["x1", "x2"]
    t = np.array(doc["samples"]["t"])
    q, v = np.array(doc["samples"]["q"]), np.array(doc["samples"]["v"])
    assert t.shape == (2000,) and q.shape == v.shape == (2000, 2)
    assert t[0] == 0.0 and t[-1] == doc["t_final"] == 4.0
    np.testing.assert_allclose([q[0, 0], v[0, 0], q[0, 1], v[0, 1]], [0.3, 0.5, 0, 0])
    # the gap never leaves the clearance, and the samples just before each impact approach
    # its pre-impact state (an independent check: dense output vs the located impacts)
    assert np.all(np.abs(q[:, 0] - q[:, 1]) <= 0.75 + 1e-9)
    for imp in doc["impacts"]:
        k = np.searchsorted(t, imp["t"]) - 1
        dt = imp["t"] - t[k]
        pre = np.array(imp["pre"])
        np.testing.assert_allclose(q[k] + dt * v[k], pre[[0, 2]], atol=50 * dt ** 2 + 1e-9)
    model = json.loads(files["model_trajectory.json"].read_text())
    assert model["dofs"] == ["load", "gear", "motor"] and len(model["contacts"]) == 2
    assert np.array(model["samples"]["q"]).shape == (400, 3)
    np.testing.assert_allclose(model["samples"]["q"][0], [0.05, 0.0, 0.0])


def test_plot_option_draws_right_away(tmp_path, capsys):
    assert main(["simulate", *SIM, "--plot", str(tmp_path / "run.svg")]) == 0
    assert_image(tmp_path / "run.svg")
    assert main(["simulate", "--model", MODEL, "--t-end", "2", "--plot",
                 str(tmp_path / "model.png")]) == 0
    assert_image(tmp_path / "model.png")
    assert main(["regions", *REGIONS, "--plot", str(tmp_path / "regions.pdf"),
                 "--out", str(tmp_path / "regions.nc")]) == 0
    assert_image(tmp_path / "regions.pdf")
    assert main(["plot", str(tmp_path / "regions.nc")]) == 0
    assert_image(tmp_path / "regions.png")
    assert main(["basin", *BASIN, "--plot", str(tmp_path / "basin.png"),
                 "--out", str(tmp_path / "basin.npz")]) == 0
    assert_image(tmp_path / "basin.png")
    from hybridpd.plotting.files import file_kind

    assert file_kind(tmp_path / "basin.npz") == "basin"


def test_branch_save_load_round_trip(files):
    from hybridpd.pair.continuation import continue_symmetric, load_branch

    br = continue_symmetric(ImpactPair(0.1, 0.1, 0.75), PDGains(10, 20), 5.0, "kv", 23.0)
    for name in ("branch.nc", "branch.npz"):
        back = load_branch(files[name])
        for var in ("parameter", "points", "multipliers", "spectral_radius", "stable",
                    "viable", "margin", "min_impact_speed", "xm", "newton_iterations"):
            np.testing.assert_array_equal(getattr(back, var), getattr(br, var), err_msg=var)
        assert back.to_dict() == br.to_dict(), name
        assert back.patterns == br.patterns and back.case == br.case
        assert [e.kind for e in back.events] == [e.kind for e in br.events]
    with pytest.raises(ValueError, match="path"):
        br.save(Path(files["branch.nc"]).with_suffix(".csv"))
