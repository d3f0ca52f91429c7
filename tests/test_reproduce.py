"""The main job end to end on small grids: files, figures, summary.md and summary.json, and
every verdict of the lead table recomputed here from the numbers the summary stores."""
import copy
import io
import json
from contextlib import redirect_stdout

import numpy as np
import pytest
from _reproduce_run import SMALL, small_run

from hybridpd.analysis.basins import load_basin
from hybridpd.reproduce import SCHEMA, Settings, validate
from hybridpd.reproduce import rules as R
from hybridpd.sweeps.regions import load_region_map

ES = ("0.1", "0.5", "0.9")
CASES = ("collocated", "noncollocated")


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
                     "regions_noncollocated.nc"):
            assert (d / name).stat().st_size > 0
    for name in ("m2_study.png", "mu_study.png", "gamma_study.png", "robustness.json",
                 "scaled_regions_collocated.png", "scaled_regions_noncollocated.png"):
        assert (out / name).stat().st_size > 0
    # the lead table comes first, one row per claim
    assert text.index("## What the paper says and what holds") < text.index("## The secondary")
    rows = {ln.split(" | ")[0].lstrip("| "): ln for ln in text.splitlines()
            if ln.startswith("| ") and " | **" in ln}
    for row in data["table"]:
        line = rows[str(row["id"])]
        assert line.startswith(f"| {row['id']} | {row['paper']} | ")
        assert f" | **{row['verdict']}**: " in line
    for k in range(1, 6):
        assert f"### {k}. *" in text            # each of the paper's conclusions in detail
    assert not list(out.rglob("*.npz"))                # the labelled format only
    for repr_leak in ("[False", "[True", "np.float", "None", "{'", "depends"):
        assert repr_leak not in text, repr_leak
    rm = load_region_map(out / "m2=1" / "regions_collocated.nc")
    assert rm.exists.shape == (3, 9, 9)
    ab = load_basin(out / "m2=100" / "basin_collocated_e0.5.nc")
    crit = ab.criterion_labels
    assert crit.shape == ab.labels.shape == (5, 6) and np.isin(crit, range(-3, 6)).all()
    assert ab.attractors[0].label == 0                 # the symmetric orbit


def test_summary_json_matches_its_schema(run):
    _, data = run
    assert validate(data, SCHEMA) == []
    assert [c["id"] for c in data["conclusions"]] == [1, 2, 3, 4, 5]
    assert [r["id"] for r in data["table"]] == [1, 2, 3, 4, 5, "mu-existence", "mu-small"]
    for case in CASES:
        assert set(data["m2_stable_intervals"][case]) == set(ES)
    # the validator can fail
    bad = copy.deepcopy(data)
    bad["conclusions"][0]["verdict"] = "depends"
    del bad["conventions"]["x10"]
    bad["m2_stable_intervals"]["noncollocated"]["0.5"] = [[1.0]]
    bad["certified_shares"]["collocated"]["0.1"]["exists_stable"] = [0.2]
    errs = validate(bad, SCHEMA)
    assert len(errs) == 4, errs


def test_certified_shares_in_the_json(run):
    _, data = run
    cert = data["certified"]["main"]
    n = SMALL.certified[0] * 2 ** SMALL.certified[1]
    assert cert["grid"] == [n, n]
    for case in CASES:
        for e in ES:
            s = data["certified_shares"][case][e]
            assert s["grid"] == [n, n] and s["box"]["kp/m2"] == [0.1, 50.0]
            for name in ("exists_stable", "exists", "exists_unstable", "no_orbit"):
                lo, hi = s[name]
                c = s["cells"][name]
                assert c["of"] == n * n and c["proved"] + c["proved_not"] + c["undecided"] == n * n
                np.testing.assert_allclose([lo, hi], [c["proved"] / n ** 2,
                                                      (c["proved"] + c["undecided"]) / n ** 2],
                                           rtol=0, atol=1e-12)
            # the classes partition the box: their enclosures are consistent
            st, ex, un = s["exists_stable"], s["exists"], s["exists_unstable"]
            assert st[0] + un[0] <= ex[1] + 1e-12 and ex[0] <= st[1] + un[1] + 1e-12
            np.testing.assert_allclose(s["no_orbit"], [1 - ex[1], 1 - ex[0]], rtol=0,
                                       atol=1e-12)


# independent statements of the rules (CONVENTIONS.md, "Verdict rules"), for recomputation
def _below(a, b):
    return a[1] < b[0]


def _trend(first, last, decreasing):
    if _below(last, first):
        return "agrees" if decreasing else "contradicted"
    if _below(first, last):
        return "contradicted" if decreasing else "agrees"
    return "unresolved"


def _all(vs):
    return ("contradicted" if "contradicted" in vs else
            "agrees" if all(v == "agrees" for v in vs) else "unresolved")


def test_every_verdict_is_recomputed_from_the_data(run):
    path, data = run
    sh = data["certified_shares"]
    es = {c: [sh[c][e]["exists_stable"] for e in ES] for c in CASES}
    table = {row["id"]: row["verdict"] for row in data["table"]}
    # 3: the collocated share at least 30 % for every e
    v3 = _all(["agrees" if lo >= 0.3 else "contradicted" if hi < 0.3 else "unresolved"
               for lo, hi in es["collocated"]])
    # 1: non-collocated / collocated below 0.2, the ratio bracketed from the intervals
    v1 = []
    for (nlo, nhi), (clo, chi) in zip(es["noncollocated"], es["collocated"]):
        up = nhi / clo if clo > 0 else np.inf
        low = nlo / chi if chi > 0 else (np.inf if nlo > 0 else 0.0)
        v1.append("agrees" if up < 0.2 else "contradicted" if low >= 0.2 else "unresolved")
    # 2: trends from the first to the last e
    v2 = _all([_trend(es["noncollocated"][0], es["noncollocated"][-1], True),
               _trend(es["collocated"][0], es["collocated"][-1], False)])
    assert (table[1], table[2], table[3]) == (_all(v1), v2, v3)
    # mu -> 0: the share at mu = 1e-4 above the one at the paper's mu, every case and e
    lim = data["certified_studies"]["limit"]
    vs = [_trend(lim[c][e]["exists_stable"], sh[c][e]["exists_stable"], True)
          for c in CASES for e in ES]
    assert table["mu-small"] == _all(vs)
    ends = data["certified_studies"]["mu_ends"]
    lo_mu, hi_mu = (f"{v:g}" for v in SMALL.mu_range)
    vs = [_trend(ends[c][lo_mu][e]["exists"], ends[c][hi_mu][e]["exists"], True)
          for c in CASES for e in ES]
    assert table["mu-existence"] == _all(vs)
    # 5: both criteria from robustness.json, each checked on a second grid
    rows = {r["case"]: r for r in json.loads((path.parent / "robustness.json").read_text())
            ["rows"]}
    c5 = next(c for c in data["conclusions"] if c["id"] == 5)["evidence"]
    for crit, key in (("robust stability", "robust_stable_fraction"),
                      ("robust stability and amplitude within 10 %", "robust_fraction")):
        np.testing.assert_allclose([c5["fractions"][crit][c] for c in CASES],
                                   [rows[c][key] for c in CASES], rtol=1e-12, atol=0)
        run_v = ("agrees" if rows["noncollocated"][key] < rows["collocated"][key]
                 else "contradicted")
        chk = c5["check_fractions"][crit]
        chk_v = "agrees" if chk["noncollocated"] < chk["collocated"] else "contradicted"
        assert c5["by_criterion"][crit] == (run_v if run_v == chk_v else "unresolved")
    decided = {v for v in c5["by_criterion"].values() if v != "unresolved"}
    assert table[5] == ("split" if len(decided) == 2 else decided.pop() if decided
                        else "unresolved")
    # both criteria stand side by side in the finding
    row5 = next(r for r in data["table"] if r["id"] == 5)["finding"]
    assert "by robust stability " in row5 and "amplitude within 10 %" in row5


def test_basins_are_recomputed_from_their_files(run):
    path, data = run
    out = path.parent
    for r in data["runs"]:
        d = out / f"m2={r['m2']:g}"
        bas = {case: [load_basin(d / f"basin_{case}_e{e}.nc")
                      if (d / f"basin_{case}_e{e}.nc").exists() else None for e in ES]
               for case in CASES}
        windows = {tuple(b.window) for v in bas.values() for b in v if b is not None}
        assert len(windows) <= 1           # one window for every panel and case
        touch = {c: [bool(b is not None and b.reaches_edge) for b in v]
                 for c, v in bas.items()}
        assert touch == r["conclusion_4"]["run_grid"]["touches_edge"]
        for row in r["basins"]:
            if row["measured"]:
                # one denominator per row: the window's grid points
                assert row["points"] == row["grid"][0] * row["grid"][1]
                assert sum(s["count"] for s in row["shares"]) <= row["points"]
        assert r["conclusion_4"]["verdict"] == R.resolution(*r["conclusion_4"]["verdicts"])


def test_hybridpd_plot_draws_every_data_file_reproduce_writes(run, capsys):
    from hybridpd.cli import main

    path, _ = run
    files = sorted(path.parent.rglob("*.nc"))
    assert len(files) >= 2 * 3 + 3
    for f in files[:4]:
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
        np.testing.assert_allclose(b.x, m2 * a.x, rtol=1e-12, atol=0)
        assert np.mean(a.exists == b.exists) > 0.99 and np.mean(a.stable == b.stable) > 0.99
        both = a.exists & b.exists
        np.testing.assert_allclose(b.spectral_radius[both], a.spectral_radius[both],
                                   rtol=1e-6, atol=0)


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
    for row in data["table"]:
        assert any(ln.split()[:2] == [str(row["id"]), row["verdict"]] for ln in lines)
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
                     (dict(m2_range=(10.0, 1.0)), "m2_range"), (dict(m2=()), "m2"),
                     (dict(certified=(16, 3)), "certified"),
                     (dict(certified_readings=(8, 2, 1.5)), "certified_readings")):
        with pytest.raises(ValueError, match=name):
            Settings.quick(**kw)
    assert SMALL.L == pytest.approx(0.75)


def test_summary_opens_with_the_bottom_line_of_the_papers_gains(run):
    # the three lines after the title, checked against orbits computed here at m2 = 1
    from hybridpd.pair.orbits import symmetric_orbits

    path, data = run
    lines = path.read_text().splitlines()
    assert lines[0].startswith("# Reproduction")
    head = [ln for ln in lines[1:6] if ln.strip()][:3]
    assert head[0].startswith("**Bottom line** (the paper's gains kp = 10, kv = 20, at m2 = 1)")
    assert head[1].startswith("Non-collocated:") and head[2].startswith("Of the ")
    P, c = data["paper"], data["conventions"]
    for case, line in (("collocated", head[0]), ("noncollocated", head[1])):
        r = symmetric_orbits(P["kp"], P["kv"], mu=P["mu"], e=np.asarray(P["e"], float),
                             L=c["L"], x10=c["x10"], omega=P["omega"], m2=1.0, n=P["n"],
                             case=case)
        for e, ex, st, rho in zip(P["e"], np.asarray(r.exists), np.asarray(r.stable),
                                  np.asarray(r.spectral_radius)):
            if not ex:
                assert f"e = {e:g} no orbit" in line
            else:
                word = "stable" if st else "unstable"
                assert f"e = {e:g} {word} (spectral radius {rho:.3g})" in line
    verdicts = [row["verdict"] for row in data["table"]]
    assert f"{verdicts.count('agrees')} agree" in head[2]


def test_the_lead_table_states_each_rows_convention_and_box(run):
    path, data = run
    text = path.read_text()
    head = "| # | the paper says | read on (convention, box) |"
    assert head in text
    rows = [ln for ln in text.splitlines() if ln.startswith("| ") and not ln.startswith(head)
            and not ln.startswith("|---")]
    by_id = {ln.split("|")[1].strip(): ln.split("|")[3] for ln in rows[:len(data["table"])]}
    box = data["certified"]["box"]["kp/m2"]
    for rid in ("1", "2", "3", "mu-existence", "mu-small"):
        assert f"kp/m2 in [{box[0]:g}, {box[1]:g}]" in by_id[rid] and "certified" in by_id[rid]
    assert f"basins at m2 = {data['conventions']['chosen_m2']:g}" in by_id["4"]
    c5 = next(c for c in data["conclusions"] if c["id"] == 5)["evidence"]
    assert f"kp/m2 in [{c5['gains']['kp'][0]:g}, {c5['gains']['kp'][1]:g}]" in by_id["5"]
    # one box for every region row: conclusion 5's gain grid spans the certified box
    assert c5["gains"]["kp"] == pytest.approx(box)
    assert c5["gains"]["kv"] == pytest.approx(data["certified"]["box"]["kv/m2"])


def test_the_studies_are_certified_at_every_value(run):
    # SMALL certifies every value: the mu remark's series holds every value of the mu study
    # (and the paper's mu), the gamma study every value of its own, and the remark's
    # reported rise is recomputed here from the series it rests on
    from hybridpd.reproduce.certified import study_values

    S = SMALL
    path, data = run
    rem = next(r for r in data["remarks"] if r["id"] == "mu-existence")["evidence"]
    mus = sorted(set(study_values(S, "mu")) | {data["paper"]["mu"]})
    for key, series in rem["series"].items():
        assert [m for m, _ in series] == pytest.approx(mus)
        ivs = [iv for _, iv in series]
        best = max(((ivs[j][0] - ivs[i][1], i, j) for i in range(len(ivs))
                    for j in range(i + 1, len(ivs))), default=(0, 0, 0))
        against = rem["trends"][key]["against"]
        if best[0] > 0:
            # the largest proved rise (ties: any pair that realises it)
            i, j = (mus.index(pytest.approx(m)) for m in against["interval"])
            assert i < j and against["by"] == pytest.approx(best[0])
            assert ivs[j][0] - ivs[i][1] == pytest.approx(best[0])
        else:
            assert against is None
    gam = data["gamma_certified"]["shares"]
    for case in CASES:
        for e in ES:
            r = gam[case][e]
            assert r["gamma"] == pytest.approx(study_values(S, "gamma"))
            assert all(0 <= lo <= hi <= 1 for lo, hi in r["exists_stable"])
            assert r["proved_somewhere"] == [g for g, iv in zip(r["gamma"], r["exists_stable"])
                                             if iv[0] > 0]
    assert "Certified at every value of gamma" in path.read_text()
