"""The explorer's logic without a browser: its state and URL, its computations checked against
the package's own answers, and the page's callbacks driven directly (no server)."""
from __future__ import annotations

import io
import itertools
import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hybridpd as hp
from hybridpd.explore import state as S

PAPER = dict(mu=0.1, gamma=0.75, omega=5.0)


def _message(fn, *args):
    with pytest.raises(ValueError) as info:
        fn(*args)
    return str(info.value)


# ---- fields and the URL ---------------------------------------------------------------------

@pytest.mark.parametrize(("name", "raw", "package_call"), [
    ("e", "1.5", lambda: hp.ImpactPair(0.1, 1.5, 0.75)),
    ("mu", "-1", lambda: hp.ImpactPair(-1.0, 0.5, 0.75)),
    ("kp", "0", lambda: hp.PDGains(0.0, 1.0)),
    ("n", "2", lambda: hp.symmetric_orbit(hp.ImpactPair(0.1, 0.5, 0.75), (1, 1), 5.0, n=2)),
    ("case", "diagonal", lambda: hp.Case.parse("diagonal")),
])
def test_a_refused_field_gives_the_packages_own_message(name, raw, package_call):
    assert _message(S.check_field, name, raw) == _message(package_call)


def test_words_are_named_in_the_message():
    assert "e must be a real number in [0, 1], got 'abc'" in _message(S.check_field, "e", "abc")
    assert "branch must be 'kp' or 'kv'" in _message(S.check_field, "branch", "mu")
    assert "num must be an integer in [2, 401]" in _message(S.check_field, "num", "1000")


def test_query_keeps_good_fields_and_names_bad_ones():
    state, errors = S.parse_query({"case": [b"non-collocated"], "e": ["0.1"], "kp": "12.5",
                                   "mu": "0", "omega": "x", "unknown": "1"})
    assert (state.case, state.e, state.kp) == ("noncollocated", 0.1, 12.5)
    assert state.mu == S.PairState().mu and state.omega == S.PairState().omega
    assert set(errors) == {"mu", "omega"}
    assert errors["mu"].startswith("mu must be > 0")


def test_an_empty_box_drops_its_fields_with_the_message():
    state, errors = S.parse_query({"kp_min": "60", "kp_max": "55", "kv_min": "1"})
    assert set(errors) == {"kp_min", "kp_max"}
    assert "kp range must be increasing" in errors["kp_min"]
    assert (state.kp_min, state.kp_max, state.kv_min) == (0.1, 50.0, 1.0)


def test_a_branch_ending_where_it_starts_is_refused():
    state, errors = S.parse_query({"kv": "30", "stop": "30"})
    assert "stop" in errors and state.stop is None and state.kv == 30.0
    assert state.stop_value() == 50.0


positive = st.floats(1e-3, 1e3, allow_nan=False)


@settings(max_examples=40, deadline=None)
@given(e=st.floats(0, 1), mu=positive, kp=positive, kv=positive, n=st.sampled_from([1, 3, 5]),
       case=st.sampled_from(["collocated", "noncollocated"]))
def test_the_url_round_trips_every_state_exactly(e, mu, kp, kv, n, case):
    s = S.PairState(case=case, e=e, mu=mu, kp=kp, kv=kv, n=n)
    back, errors = S.parse_query(S.to_query(s))
    assert errors == {} and back == s


def test_a_click_snaps_to_the_nearest_grid_point():
    s = S.PairState(kp_min=1.0, kp_max=11.0, kv_min=2.0, kv_max=4.0, num=11)
    rng = np.random.default_rng(1)
    xs, ys = s.kp_axis(), s.kv_axis()
    for x, y in rng.uniform([0, 1], [12, 5], size=(50, 2)):
        kp, kv = S.snap(s, x, y)
        assert abs(kp - x) <= np.min(np.abs(xs - x)) + 1e-12 and kp in xs
        assert abs(kv - y) <= np.min(np.abs(ys - y)) + 1e-12 and kv in ys


# ---- computations against the package -------------------------------------------------------

def test_the_map_classes_agree_with_the_orbit_cell_by_cell():
    s = S.PairState(case="noncollocated", e=0.1, kp_min=1, kp_max=40, kv_min=1, kv_max=40,
                    num=9)
    cls = S.map_classes(S.pair_map(s))
    assert set(np.unique(cls)) == {0, 1, 2}          # the box shows every class
    for iy, kv in enumerate(s.kv_axis()):
        for ix, kp in enumerate(s.kp_axis()):
            o = hp.symmetric_orbit(hp.ImpactPair(0.1, 0.1, 0.75), (kp, kv), 5.0,
                                   case="noncollocated")
            assert cls[iy, ix] == (2 if o.exists and o.stable else 1 if o.exists else 0)


def test_the_orbit_series_is_the_orbits_motion():
    orb = S.pair_orbit(S.PairState(e=0.5, kp=10, kv=20))
    s = S.orbit_series(orb, samples=101)
    half = slice(0, 101)
    # the free primary mass moves at constant velocity between impacts
    t, x1 = s["t"][half], s["x1"][half]
    assert np.allclose(np.diff(x1) / np.diff(t), -orb.pre_plus[1], rtol=1e-9)
    # the half period starts at the +L impact and ends at the -L one
    assert np.allclose([s["x1"][0], s["x2"][0]], orb.post_plus[[0, 2]], atol=1e-12)
    assert np.allclose(s["z3"][100], -orb.pair.L, atol=1e-9)
    # inside the flight the gap keeps off the walls by the viability margin
    inner = np.abs(s["z3"][1:100])
    assert inner.max() <= orb.pair.L * (1 - orb.viability_margin) + 1e-9 or \
        orb.viability_margin == 1.0
    assert inner.max() < orb.pair.L
    assert np.isnan(s["z3"][101]) and np.allclose(s["x1"][102:], -x1)


def test_the_orbit_is_what_hybridpd_orbit_computes():
    from hybridpd.cli import main

    buf = io.StringIO()
    import contextlib

    with contextlib.redirect_stdout(buf):
        main(["orbit", "--json", "--case", "noncollocated", "--mu", "0.1", "--e", "0.1",
              "--gamma", "0.75", "--omega", "5", "--kp", "12.5", "--kv", "25"])
    cli = json.loads(buf.getvalue())
    orb = S.pair_orbit(S.PairState(case="noncollocated", e=0.1, kp=12.5, kv=25))
    assert math.isclose(orb.spectral_radius, cli["spectral_radius"], rel_tol=1e-12)
    assert orb.to_dict()["xm"] == pytest.approx(cli["xm"], rel=1e-12)


def test_the_branch_finds_the_grazing_of_the_paper_case():
    br = S.pair_branch(S.PairState(e=0.1, kp=10, kv=20, branch="kv", stop=23))
    ev = br.events_of("grazing")
    assert len(ev) == 1 and 21.9 < ev[0].parameter < 22.0
    # independent check: the orbit on either side of the event is viable, then not
    pair = hp.ImpactPair(0.1, 0.1, 0.75)
    before = hp.symmetric_orbit(pair, (10, ev[0].parameter - 1e-3), 5.0)
    after = hp.symmetric_orbit(pair, (10, ev[0].parameter + 1e-3), 5.0)
    assert before.exists and not after.exists


def test_saved_data_are_the_command_lines_files(tmp_path):
    from hybridpd.explore import figures as F

    s = S.PairState(e=0.5, kp=10, kv=20, num=11)
    rm = S.pair_map(s)
    p = tmp_path / "map.nc"
    p.write_bytes(F.data_bytes("map", rm))
    back = hp.load_region_map(p)
    assert np.array_equal(back.stable, rm.stable) and np.array_equal(back.x, rm.x)
    orb = S.pair_orbit(s)
    d = json.loads(F.data_bytes("orbit", orb))
    assert d["spectral_radius"] == orb.spectral_radius and d["kp"] == 10.0
    png = F.figure_bytes("multipliers", orb)
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000


# ---- the page's callbacks, without a server --------------------------------------------------

pn = pytest.importorskip("panel", reason="the page needs Panel (pip install 'hybridpd[explore]')")


def _text(pane) -> str:
    import re

    return re.sub(r"<[^>]+>", "", pane.object)


def _testid(pane, name):
    import re

    m = re.search(f'data-testid="{name}">([^<]*)<', pane.object)
    return None if m is None else m.group(1)


@pytest.fixture
def page():
    from hybridpd.explore.app import PairExplorer

    return PairExplorer(S.PairState(e=0.5, kp=10, kv=20, num=21), url=False)


def test_the_page_starts_with_its_map_and_orbit(page):
    assert page.rm is not None and page.rm.x.size == 21
    orb = hp.symmetric_orbit(hp.ImpactPair(0.1, 0.5, 0.75), (10, 20), 5.0)
    rho = float(_testid(page.orbit_info, "spectral-radius"))
    assert rho == pytest.approx(orb.spectral_radius, rel=1e-11)
    assert _testid(page.orbit_info, "stable") == "true"
    assert _testid(page.status, "status") == "ready"


def test_the_warm_up_map_is_drawn_in_the_first_page_of_its_box_only():
    """A page whose box is the warm-up's draws the warm-up's map as it is built (no
    computation scheduled); another box, or a warm-up not finished, computes its own."""
    from hybridpd.explore.app import PairExplorer, _ready_map, warm_up

    base = S.PairState(e=0.5, kp=10, kv=20, num=21)
    warm = warm_up(base)
    done, rm, ms = warm.result(timeout=60)
    assert done is base and ms > 0
    ready = _ready_map(warm, S.PairState(e=0.5, kp=3, kv=4, num=21))   # another selection
    assert ready == (rm, ms)
    assert _ready_map(warm, S.PairState(e=0.3, num=21)) is None
    assert _ready_map(None, base) is None
    p = PairExplorer(S.PairState(e=0.5, kp=3, kv=4, num=21), url=False, ready=ready)
    assert p.rm is rm and p._gen["map"] == 0          # nothing computed for the page
    assert _testid(p.map_info, "map-e") == "0.5"
    fresh = PairExplorer(S.PairState(e=0.5, kp=3, kv=4, num=21), url=False)
    np.testing.assert_array_equal(S.map_classes(fresh.rm), S.map_classes(p.rm))


def test_the_first_map_computed_in_a_forked_process_is_the_map():
    """The command's first map (a process forked before Panel loads) is what the page
    computes itself: the same classes and shares."""
    base = S.PairState(case="noncollocated", e=0.3, num=31)
    done, rm, ms = S.warm_map(base).result(timeout=120)
    assert done == base and ms > 0
    mine = S.pair_map(base)
    np.testing.assert_array_equal(S.map_classes(rm), S.map_classes(mine))
    np.testing.assert_array_equal(rm.x, mine.x)
    np.testing.assert_array_equal(rm.y, mine.y)


def test_a_tap_selects_the_nearest_cell(page):
    class Tap:
        x, y = 31.3, 7.9

    page._on_tap(Tap())
    kp, kv = S.snap(page.state, 31.3, 7.9)
    assert float(_testid(page.orbit_info, "selected-kp")) == pytest.approx(kp, rel=1e-11)
    assert float(_testid(page.orbit_info, "selected-kv")) == pytest.approx(kv, rel=1e-11)
    assert (page.state.kp, page.state.kv) == (kp, kv)


def test_a_bad_control_is_refused_beside_it_and_a_good_one_redraws(page):
    page.inputs["e"].value = "1.5"
    assert _text(page.messages["e"]) == "e must lie in [0, 1], got 1.5"
    assert page.state.e == 0.5 and _testid(page.status, "status").startswith("refused")
    page.inputs["e"].value = "0.9"
    assert _text(page.messages["e"]) == ""
    assert page.state.e == 0.9 and float(_testid(page.map_info, "map-e")) == 0.9
    want = S.pair_map(page.state).fraction("stable")[0]
    assert float(_testid(page.map_info, "map-stable-share")) == pytest.approx(want, abs=1e-11)


def test_an_empty_box_is_refused_with_the_packages_message(page):
    page.inputs["kp_min"].value = "80"
    assert "kp range must be increasing" in _text(page.messages["kp_min"])
    assert page.state.kp_min == 0.1


def test_basin_and_branch_on_demand(page):
    page._schedule(page._compute_basin)
    assert _testid(page.basin_info, "basin-status") == "done"
    want = S.pair_basin(page.orb, 101).converged_fraction
    assert float(_testid(page.basin_info, "basin-share")) == pytest.approx(want, abs=1e-11)
    page.branch_stop.value = "12"
    page.branch_param.value = "kp"
    page._schedule(page._compute_branch)
    assert _testid(page.branch_info, "branch-status") == "done: reached stop"
    assert page.branch.parameter[-1] == pytest.approx(12.0)


def test_a_failing_computation_says_why_in_its_panel(page):
    page.orb = None
    page._schedule(page._compute_basin)
    assert "no orbit at the selected gains" in _testid(page.basin_info, "basin-status")
    payload = page.basin_downloads[0].callback().getvalue()
    assert payload.startswith(b"cannot save: nothing computed yet")
    assert _testid(page.status, "status").startswith("error: cannot save")


# ---- model files ---------------------------------------------------------------------------

def test_model_axes_read_as_hybridpd_regions_takes_them():
    from hybridpd.cli.explore import model_axis

    assert model_axis("x", ["a.b,c.d", "1", "2", "3"]) == ("a.b,c.d", 1.0, 2.0, 3)
    assert model_axis("y", ["controller.kv", "1", "20", "8"]) == ("controller.kv", 1.0, 20.0, 8)
    with pytest.raises(ValueError, match="--x NUM must be an integer"):
        model_axis("x", ["controller.kp", "5", "60", "1"])
    with pytest.raises(ValueError, match="--y MIN and MAX must be numbers"):
        model_axis("y", ["controller.kp", "5", "x", "3"])
    with pytest.raises(ValueError, match="--y must be NAME MIN MAX NUM"):
        model_axis("y", ["controller.kp,5,60,8"])       # the comma form of earlier versions


def test_a_model_file_that_fails_says_what_hybridpd_orbit_says(tmp_path, capsys):
    from hybridpd.cli import main

    bad = tmp_path / "bad.toml"
    bad.write_text("[system]\nmasses = [1.0, -2.0]\n")
    assert main(["orbit", "--model", str(bad)]) == 2
    want = capsys.readouterr().err
    assert main(["explore", "--no-browser", "--model", str(bad), "--x", "controller.kp", "1", "2",
                 "3", "--y", "controller.kv", "1", "2", "3"]) == 2
    got = capsys.readouterr().err
    assert got == want and got.count("\n") == 1 and got.startswith("hybridpd: error: ")


def test_hp_explore_is_the_callable_package_and_loads_no_web_library_until_called():
    import subprocess
    import sys

    code = ("import sys, hybridpd as hp; e = hp.explore; import hybridpd.explore.state; "
            "print(callable(e), e is sys.modules['hybridpd.explore'], "
            "[m for m in ('panel', 'bokeh') if m in sys.modules])")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=120, check=True)
    assert r.stdout.split() == ["True", "True", "[]"]


def test_hp_explore_builds_the_page_and_checks_its_fields():
    page = hp.explore(case="noncollocated", e=0.1, kp=12.5, kv=25, num=11)
    assert page is not None and len(page.objects) == 2
    with pytest.raises(ValueError, match="unknown: gain"):
        hp.explore(gain=3)
    with pytest.raises(ValueError, match="e must lie in"):
        hp.explore(e=3)


def test_an_unstable_orbits_basin_runs_fewer_iterations_and_reports_its_progress():
    from hybridpd.analysis.mappers import Growth
    from hybridpd.reproduce.basins import orbit_mapper
    from hybridpd.sweeps.basins import basin_of_attraction

    orb = S.pair_orbit(S.PairState(case="noncollocated", e=0.9, kp=30, kv=12))
    assert orb.exists and not orb.stable
    calls = []
    b = S.pair_basin(orb, 21, lambda done, total: calls.append((done, total)))
    assert b.metadata["n_iter"] == S.UNSTABLE_ITERATIONS < 1500
    assert calls[0] == (0, 441) and calls[-1] == (441, 441)
    assert all(a[0] <= c[0] for a, c in itertools.pairwise(calls))
    # against the command line's 1500 iterations: no point converges to the orbit in either,
    # and the same points are off the section
    full = basin_of_attraction(orbit_mapper(orb, n_iter=1500), (-3, 5, 21), (-2, 10, 21),
                               grow=Growth(0))
    assert b.converged_fraction == full.converged_fraction == 0.0
    assert np.array_equal(b.labels < 0, full.labels < 0)
    stable = S.pair_orbit(S.PairState())
    assert S.pair_basin(stable, 5).metadata["n_iter"] == 1500
