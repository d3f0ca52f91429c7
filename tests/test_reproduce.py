"""The main job end to end on small grids: files, figures, summary.md and summary.json."""
import copy
import io
import json
from contextlib import redirect_stdout

import numpy as np
import pytest
from _reproduce_run import SMALL, small_run

from hybridpd.pair.attractor_basins import load_attractor_basin
from hybridpd.reproduce import PAPER, SCHEMA, Settings, validate
from hybridpd.reproduce import conclusions as C
from hybridpd.reproduce import rules as R
from hybridpd.reproduce.study import box_fractions
from hybridpd.sweeps.regions import load_region_map


@pytest.fixture(scope="module")
def run():
    path, _ = small_run()
    return path, json.loads((path.parent / "summary.json").read_text())


def test_reproduce_small(run):
    path, data = run
    out = path.parent
    text = path.read_text()
    assert data["conventions"]["m2"][0] == 1.0 and len(data["conventions"]["m2"]) == 2
    for m2 in data["conventions"]["m2"]:
        d = out / f"m2={m2:g}"
        for name in ("fig3_orbit.png", "fig4_regions_collocated.png",
                     "fig5_regions_noncollocated.png", "fig6_basins_collocated.png",
                     "fig7_basins_noncollocated.png", "regions_collocated.nc",
                     "regions_noncollocated.nc", "robustness.json"):
            assert (d / name).stat().st_size > 0
    for name in ("m2_study.png", "mu_study.png", "gamma_study.png", "summary.json"):
        assert (out / name).stat().st_size > 0
    for k in range(1, 6):
        assert f"### {k}. *" in text            # each of the paper's conclusions is checked
    assert text.count("**Verdict: ") == 5 + 2          # the conclusions and the mu remarks
    assert not list(out.rglob("*.npz"))                # the labelled format only
    for repr_leak in ("[False", "[True", "np.float", "None", "{'"):
        assert repr_leak not in text, repr_leak
    rm = load_region_map(out / "m2=1" / "regions_collocated.nc")
    assert rm.exists.shape == (3, 9, 9)
    from hybridpd._format import pct as _pct

    assert _pct(rm.fraction("stable")[1]) in text   # the summary quotes the data files
    ab = load_attractor_basin(out / "m2=1" / "basin_collocated_e0.5.nc")
    b = ab.basin
    assert b.labels.shape == ab.labels.shape == (5, 6) and np.isin(b.labels, range(6)).all()
    assert ab.attractors[0].label == 0                 # the symmetric orbit
    assert _pct(b.converged_fraction) in text


def test_summary_json_matches_its_schema(run):
    _, data = run
    assert validate(data, SCHEMA) == []
    assert [c["id"] for c in data["conclusions"]] == [1, 2, 3, 4, 5]
    for case in ("collocated", "noncollocated"):
        assert set(data["m2_stable_intervals"][case]) == {"0.1", "0.5", "0.9"}
    # the validator can fail
    bad = copy.deepcopy(data)
    bad["conclusions"][0]["verdict"] = "maybe"
    del bad["conventions"]["x10"]
    bad["m2_stable_intervals"]["noncollocated"]["0.5"] = [[1.0]]
    bad["conclusions"][1]["resolution_check"]["verdicts"] = ["agrees"]
    errs = validate(bad, SCHEMA)
    assert len(errs) == 4, errs


def _shares(rm, run_dict, case):
    q = {"exists": rm.fraction("exists"), "both": rm.fraction("stable")}
    fx = rm.fixed
    q["stability"] = box_fractions(case, rm.x, rm.y, e=rm.e, mu=fx["mu"], L=fx["L"],
                                   omega=fx["omega"], m2=fx["m2"], x10=fx["x10"],
                                   n=fx["n"])["stability"]
    return q


def test_summary_json_additions(run):
    _, data = run
    for con in data["conclusions"]:
        rc = con["resolution_check"]
        assert len(rc["grids"]) == 2 and rc["grids"][0] != rc["grids"][1]
        assert con["verdict"] == R.resolution(*rc["verdicts"])
    for r in data["remarks"]:
        assert r["verdict"] == R.resolution(*r["resolution_check"]["verdicts"])
    c4 = data["conclusions"][3]["evidence"]["by_convention"]
    for m2, chk in c4.items():
        assert set(chk["touches_edge"]) == {"collocated", "noncollocated"}
        assert len(chk["touches_edge"]["collocated"]) == 3 and len(chk["window"]) == 4
    for name in ("mu", "gamma"):
        s = data["studies"][name]
        assert {"values", "fractions", "box"} <= set(s)
        assert s["box"]["kp"][2] == SMALL.param_grid
        assert np.shape(s["fractions"]["collocated"]["exists"]) == (3, len(s["values"]))
    fb = data["conventions"]["feedback_at_chosen_m2"]
    m2 = data["conventions"]["chosen_m2"]
    np.testing.assert_allclose([fb["kp_over_m2"], fb["kv_over_m2"]], [10 / m2, 20 / m2],
                               rtol=1e-12)


def test_every_verdict_is_recomputed_from_the_data(run):
    path, data = run
    out = path.parent
    for con in data["conclusions"]:
        k = con["id"]
        for m2, chk in con["evidence"]["by_convention"].items():
            d = out / f"m2={m2}"
            r = next(r for r in data["runs"] if f"{r['m2']:g}" == m2)
            if k in (1, 2, 3):
                sh = {case: _shares(load_region_map(d / f"regions_{case}.nc"), r, case)
                      for case in ("collocated", "noncollocated")}
                g = (SMALL.gains[2],) * 2
                mine = {1: C.check_1(sh["collocated"], sh["noncollocated"], g),
                        2: C.check_2(sh["collocated"], sh["noncollocated"], g, PAPER["e"]),
                        3: C.check_3(sh["collocated"], g)}[k]
            elif k == 4:
                bas = {case: [load_attractor_basin(d / f"basin_{case}_e{e:g}.nc")
                              if (d / f"basin_{case}_e{e:g}.nc").exists() else None
                              for e in PAPER["e"]] for case in ("collocated", "noncollocated")}
                windows = {tuple(b.window) for v in bas.values() for b in v if b is not None}
                assert len(windows) <= 1           # one window for every panel and case
                meas = {c: [None if b is None else b.measure(0).area for b in v]
                        for c, v in bas.items()}
                touch = {c: [bool(b is not None and b.reaches_edge) for b in v]
                         for c, v in bas.items()}
                assert touch == chk["touches_edge"]
                mine = C.check_4(meas["collocated"], meas["noncollocated"], touch)
            else:
                rows = json.loads((d / "robustness.json").read_text())
                f = {row["case"]: row for row in rows}
                mine = {"verdict": R.AGREES if f["noncollocated"]["robust_stable_fraction"]
                        < f["collocated"]["robust_stable_fraction"] else R.CONTRADICTED}
            assert mine["verdict"] == chk["verdict"], (k, m2)
            other = con["evidence"]["by_convention_check_grid"][m2]["verdict"]
            assert con["by_convention"][m2] == R.resolution(chk["verdict"], other)


def test_hybridpd_plot_draws_every_data_file_reproduce_writes(run, capsys):
    from hybridpd.cli import main

    path, _ = run
    files = sorted(path.parent.rglob("*.nc"))
    assert len(files) >= 2 * 3 + 3
    for f in files:
        out = f.parent / f"{f.stem}_plot.png"
        assert main(["plot", str(f), "--out", str(out)]) == 0, f
        assert out.stat().st_size > 0
    capsys.readouterr()


def test_gain_box_scaling_leaves_the_maps_unchanged(run):
    # only kp/m2 and kv/m2 matter: the map at m2 on the box scaled by m2 is the m2 = 1 map
    path, data = run
    m2 = data["conventions"]["m2"][1]
    for case in ("collocated", "noncollocated", "noncollocated_zoom"):
        a = load_region_map(path.parent / "m2=1" / f"regions_{case}.nc")
        b = load_region_map(path.parent / f"m2={m2:g}" / f"regions_{case}.nc")
        np.testing.assert_allclose(b.x, m2 * a.x, rtol=1e-12)
        assert np.mean(a.exists == b.exists) > 0.99 and np.mean(a.stable == b.stable) > 0.99
        both = a.exists & b.exists
        np.testing.assert_allclose(b.spectral_radius[both], a.spectral_radius[both], rtol=1e-6)


def test_cli_prints_json_or_a_short_table(run, monkeypatch):
    import hybridpd.reproduce as rp
    from hybridpd.cli import main

    path, data = run
    seen = {}

    def fake(out, **kw):
        seen.update(kw)
        return path

    monkeypatch.setattr(rp, "reproduce", fake)
    buf = io.StringIO()
    with redirect_stdout(buf):
        assert main(["reproduce", "--json", "--m2", "1", "auto", "--x10", "2",
                     "--basin-window", "-1", "1", "-1", "1"]) == 0
    assert json.loads(buf.getvalue()) == data
    s = seen["settings"]
    assert s.m2 == (1.0, "auto") and s.x10 == 2.0 and s.basin_window == (-1, 1, -1, 1)
    buf = io.StringIO()
    with redirect_stdout(buf):
        assert main(["reproduce"]) == 0
    lines = buf.getvalue().splitlines()
    assert len(lines) < 12 and "#" not in buf.getvalue()
    for c in data["conclusions"]:
        assert any(ln.split()[:2] == [str(c["id"]), c["verdict"]] for ln in lines)
    assert str(path.parent) in lines[-1]


@pytest.mark.parametrize("argv", [["--m2", "heavy"], ["--m2", "-1"], ["--x10", "0"],
                                  ["--basin-window", "1", "0", "0", "1"]])
def test_cli_bad_conventions_exit_2(argv, capsys):
    from hybridpd.cli import main

    assert main(["reproduce", *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("hybridpd: error:")


def test_settings_validate_every_convention():
    for kw, name in ((dict(m2=(0.0,)), "m2"), (dict(x10=-1.0), "x10"),
                     (dict(basin_window=(0, 1, 2)), "basin_window"),
                     (dict(m2_range=(10.0, 1.0)), "m2_range"), (dict(m2=()), "m2")):
        with pytest.raises(ValueError, match=name):
            Settings.quick(**kw)
    assert SMALL.L == pytest.approx(0.75)
