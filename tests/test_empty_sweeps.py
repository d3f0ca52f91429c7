"""A sweep of a model file in which no cell has an answer exits 3 with one line saying what
every cell reported (the output is written all the same)."""
import json
from pathlib import Path

from hybridpd.cli import main

MODELS = Path(__file__).resolve().parents[1] / "examples" / "models"


def _file(tmp_path, name, old, new):
    text = (MODELS / name).read_text(encoding="utf-8")
    assert f"\n{old}\n" in text
    f = tmp_path / f"edited_{name}"
    f.write_text(text.replace(f"\n{old}\n", f"\n{new}\n"), encoding="utf-8")
    return str(f)


def test_regions_where_every_cell_diverges(tmp_path, capsys):
    f = _file(tmp_path, "robot_joint_sampled.toml", "kp = 8.0", "kp = -5.0")
    out = tmp_path / "r.nc"
    rc = main(["regions", "--model", f, "--x", "controller.kp", "-6", "-5", "2", "--y",
               "controller.kd", "0.3", "0.4", "2", "--quiet", "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 3 and out.exists()
    assert err.strip().splitlines() == ["hybridpd regions: no cell has an orbit: 4 diverged"]


def test_regions_where_no_cell_has_an_orbit(tmp_path, capsys):
    # sampled at 100 Hz against a reference of period pi: no motion repeats in any cell
    f = _file(tmp_path, "robot_joint.toml", "dt = 0.001                             # sampled "
              "at 1 kHz, zero-order hold", "dt = 0.01")
    rc = main(["regions", "--model", f, "--x", "controller.kp", "19", "20", "2", "--y",
               "controller.kd", "1", "1.1", "2", "--quiet", "--json"])
    out, err = capsys.readouterr()
    assert rc == 3 and json.loads(out)["counts"]["sampling_incommensurate"] == 4
    assert err.strip().splitlines() == [
        "hybridpd regions: no cell has an orbit: 4 sampling_incommensurate"]


def test_bifurcation_where_every_value_diverges(tmp_path, capsys):
    f = _file(tmp_path, "robot_joint_sampled.toml", "kp = 8.0", "kp = -5.0")
    out = tmp_path / "d.nc"
    rc = main(["bifurcation", "--model", f, "--param", "controller.kp", "-6", "-5", "3",
               "--iterations", "20", "--keep", "10", "--out", str(out), "--json"])
    doc, err = capsys.readouterr()
    assert rc == 3 and out.exists()
    assert json.loads(doc)["classification"] == ["diverged"] * 3
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("hybridpd bifurcation: no value has an "
                                                   "answer") and lines[0].endswith(": 3 diverged")


def test_a_sweep_with_answers_exits_0(tmp_path, capsys):
    f = str(MODELS / "gear_train.toml")
    rc = main(["bifurcation", "--model", f, "--param", "controller.kp", "10", "11", "2",
               "--iterations", "20", "--keep", "10", "--out", str(tmp_path / "d.nc")])
    assert rc == 0, capsys.readouterr().err
