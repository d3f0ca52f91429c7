"""The explorer's page in a real browser: ``hybridpd explore`` served on a free local port,
driven by Playwright in a headless Chromium (Debian's ``/usr/bin/chromium``).

Skipped, with the reason, where Playwright, Panel or that Chromium is missing. The server is
the command line's own (a subprocess), always stopped at the end.
"""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest
from _browser import CHROMIUM, CHROMIUM_ARGS
from _browser import MAP_POINT_JS as _MAP_POINT_JS

import hybridpd as hp
from hybridpd.explore import state as S

pytest.importorskip("panel", reason="the page needs Panel (pip install 'hybridpd[explore]')")
sync_api = pytest.importorskip("playwright.sync_api",
                               reason="browser tests need Playwright (pip install playwright)")
if not Path(CHROMIUM).exists():
    pytest.skip(f"browser tests need Chromium at {CHROMIUM} (Debian: apt-get install chromium)",
                allow_module_level=True)

pytestmark = pytest.mark.browser

ROOT = Path(__file__).resolve().parents[1]
WAIT_MS = 20_000


@pytest.fixture(scope="module")
def server():
    from hybridpd.explore.server import free_port

    port = free_port()
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1")
    proc = subprocess.Popen([sys.executable, "-m", "hybridpd", "explore", "--no-browser",
                             "--port", str(port)], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, env=env)
    try:
        line = proc.stdout.readline()       # the address, printed once listening
        assert "serving" in line, line + (proc.stdout.read() if proc.poll() is not None else "")
        yield f"http://127.0.0.1:{port}/"
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    assert proc.returncode is not None


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield b
        b.close()


@pytest.fixture
def page(browser, server):
    ctx = browser.new_context(viewport={"width": 1500, "height": 1500}, accept_downloads=True)
    pg = ctx.new_page()
    pg.set_default_timeout(WAIT_MS)
    yield pg
    ctx.close()


def _open(page, server, **query):
    q = "&".join(f"{k}={v}" for k, v in query.items())
    page.goto(f"{server}?{q}")
    page.get_by_test_id("map-e").wait_for()
    return page


def _is_number(text) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _text(page, tid):
    return page.get_by_test_id(tid).inner_text()


def _until(page, tid, ok, what):
    """Wait (at most WAIT_MS) until ``ok(text of tid)``; the text."""
    deadline = time.monotonic() + WAIT_MS / 1000
    while time.monotonic() < deadline:     # bounded by the deadline
        loc = page.get_by_test_id(tid)
        if loc.count() and ok(t := loc.first.inner_text()):
            return t
        page.wait_for_timeout(20)
    pytest.fail(f"{what}: {tid} still {page.get_by_test_id(tid).first.inner_text()!r}")



def _url_has(page, pattern, what):
    """Wait (at most WAIT_MS) until the page's URL matches ``pattern``: the page states its
    fields in the URL from a callback after it loads, which may come after what it shows."""
    deadline = time.monotonic() + WAIT_MS / 1000
    while time.monotonic() < deadline:     # bounded by the deadline
        if re.search(pattern, page.url):
            return page.url
        page.wait_for_timeout(20)
    pytest.fail(f"{what}: the URL is still {page.url}")


def _field(page, name):
    return page.get_by_role("textbox", name=name, exact=True)


def test_the_spectral_radius_is_hybridpd_orbits(page, server):
    _open(page, server, case="noncollocated", e="0.1", kp="12.5", kv="25")
    # the orbit panel fills in once its computation is done, possibly after the map
    _until(page, "selected-kp", lambda t: _is_number(t) and float(t) == 12.5,
           "the orbit of kp = 12.5 never showed")
    rho = float(_until(page, "spectral-radius", _is_number, "no spectral radius shown"))
    r = subprocess.run([sys.executable, "-m", "hybridpd", "orbit", "--json", "--case",
                        "noncollocated", "--mu", "0.1", "--e", "0.1", "--gamma", "0.75",
                        "--omega", "5", "--kp", "12.5", "--kv", "25"], capture_output=True,
                       text=True, timeout=120, check=False, cwd=ROOT)
    cli = json.loads(r.stdout)
    assert abs(rho - cli["spectral_radius"]) <= 1e-6 * max(1.0, abs(cli["spectral_radius"]))
    assert _text(page, "exists") == str(cli["exists"]).lower()
    assert _text(page, "stable") == str(cli["stable"]).lower()
    assert float(_text(page, "selected-kp")) == 12.5
    # the URL states every field, so the view reopens as it is
    url = _url_has(page, r"num=201", "the URL never stated every field")
    assert "case=noncollocated" in url


def test_a_click_on_the_map_selects_that_cell(page, server):
    _open(page, server, case="collocated", e="0.5", num="51", kp="10", kv="20")
    st = S.PairState(num=51)
    xs, ys = st.kp_axis(), st.kv_axis()
    target = (xs[37], ys[12])
    page.mouse.click(*page.evaluate(_MAP_POINT_JS, list(map(float, target))))
    kp = float(_until(page, "selected-kp", lambda t: t != "10", "the click selected nothing"))
    kv = float(_text(page, "selected-kv"))
    assert abs(kp - target[0]) < 1e-9 and abs(kv - target[1]) < 1e-9
    orb = hp.symmetric_orbit(hp.ImpactPair(0.1, 0.5, 0.75), (kp, kv), 5.0)
    assert float(_text(page, "spectral-radius")) == pytest.approx(orb.spectral_radius,
                                                                  rel=1e-10)
    _url_has(page, r"kp=3\d\.", "the URL never stated the selected kp")


def test_changing_e_redraws_the_map(page, server):
    _open(page, server, case="noncollocated", e="0.5", num="101")
    before = float(_text(page, "map-stable-share"))
    _field(page, "e").fill("0.1")
    _field(page, "e").press("Enter")
    _until(page, "map-e", lambda t: t == "0.1", "the map was not redrawn")
    share = float(_text(page, "map-stable-share"))
    rm = S.pair_map(S.PairState(case="noncollocated", e=0.1, num=101))
    assert share == pytest.approx(rm.fraction("stable")[0], abs=1e-11)
    assert share != before
    _url_has(page, r"e=0\.1\b", "the URL never stated the new e")


def test_bad_input_is_refused_beside_its_control_and_the_server_lives(page, server):
    _open(page, server, e="0.5", num="21")
    _field(page, "mu").fill("-1")
    _field(page, "mu").press("Enter")
    msg = page.get_by_test_id("error-mu")
    msg.wait_for()
    with pytest.raises(ValueError) as want:
        hp.ImpactPair(-1.0, 0.5, 0.75)
    assert msg.inner_text() == str(want.value)
    assert _text(page, "status").startswith("refused")
    _field(page, "mu").fill("0.2")                  # the same page goes on working
    _field(page, "mu").press("Enter")
    page.get_by_test_id("error-mu").wait_for(state="detached")
    rho = hp.symmetric_orbit(hp.ImpactPair(0.2, 0.5, 0.75), (10, 20), 5.0).spectral_radius
    _until(page, "spectral-radius", lambda t: abs(float(t) - rho) < 1e-9, "no new orbit")


def test_save_figure_and_data(page, server, tmp_path):
    _open(page, server, e="0.5", kp="10", kv="20", num="21")
    with page.expect_download() as dl:
        page.get_by_role("button", name="save orbit figure").click()
    png = tmp_path / dl.value.suggested_filename
    dl.value.save_as(png)
    data = png.read_bytes()
    assert png.name == "orbit.png" and data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000
    with page.expect_download() as dl:
        page.get_by_role("button", name="save orbit data").click()
    path = tmp_path / "orbit.json"
    dl.value.save_as(path)
    d = json.loads(path.read_text())
    orb = hp.symmetric_orbit(hp.ImpactPair(0.1, 0.5, 0.75), (10, 20), 5.0)
    assert d["spectral_radius"] == pytest.approx(orb.spectral_radius, rel=1e-12)


def test_basin_and_branch_on_demand(page, server):
    _open(page, server, e="0.1", kp="10", kv="20", num="21", basin_num="41")
    page.get_by_role("button", name="compute basin slice").click()
    _until(page, "basin-status", lambda t: t == "done", "the basin did not finish")
    orb = hp.symmetric_orbit(hp.ImpactPair(0.1, 0.1, 0.75), (10, 20), 5.0)
    want = S.pair_basin(orb, 41).converged_fraction
    assert float(_text(page, "basin-share")) == pytest.approx(want, abs=1e-11)
    _field(page, "up to").fill("23")
    page.get_by_role("button", name="follow branch").click()
    _until(page, "branch-status", lambda t: t.startswith("done"), "the branch did not finish")
    assert int(_text(page, "branch-events")) >= 1
    graze = float(_text(page, "event-grazing"))
    assert 21.9 < graze < 22.0


def test_a_model_files_cell_shows_hybridpd_orbits_multipliers(browser, tmp_path):
    """``--model``: the map over two entries, a click, the cell's orbit on the stroboscopic
    section against ``hybridpd orbit --model --set``."""
    from hybridpd.explore.server import free_port

    model = ROOT / "examples" / "models" / "robot_joint_pd.toml"
    port = free_port()
    proc = subprocess.Popen([sys.executable, "-m", "hybridpd", "explore", "--no-browser",
                             "--port", str(port), "--model", str(model), "--x",
                             "controller.kp", "5", "60", "4", "--y", "controller.kv", "1", "20",
                             "4"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env=dict(os.environ, PYTHONPATH=str(ROOT)))
    ctx = browser.new_context(viewport={"width": 1300, "height": 1200})
    try:
        assert "serving" in proc.stdout.readline()
        page = ctx.new_page()
        page.set_default_timeout(WAIT_MS)
        page.goto(f"http://127.0.0.1:{port}/")
        _until(page, "map-status", lambda t: t == "done", "the model's map did not finish")
        page.mouse.click(*page.evaluate(_MAP_POINT_JS, [41.666666666666664, 7.333333333333333]))
        _until(page, "orbit-status", lambda t: t == "done", "no orbit shown")
        kp, kv = float(_text(page, "selected-x")), float(_text(page, "selected-y"))
        assert kp == pytest.approx(125 / 3, rel=1e-11) and kv == pytest.approx(22 / 3, rel=1e-11)
        r = subprocess.run([sys.executable, "-m", "hybridpd", "orbit", "--json", "--model",
                            str(model), "--set", "controller.kp", repr(kp), "--set",
                            "controller.kv", repr(kv)], capture_output=True, text=True,
                           timeout=120, check=False, cwd=ROOT)
        cli = json.loads(r.stdout)
        rho = float(_text(page, "spectral-radius"))
        assert abs(rho - cli["spectral_radius"]) <= 1e-6 * max(1.0, cli["spectral_radius"])
        assert _text(page, "stable") == str(cli["stable"]).lower()
        # the panels save what the command line writes: the orbit's --json object (with
        # the mapped values), the multipliers' figure, the map's file
        with page.expect_download() as dl:
            page.get_by_role("button", name="save orbit data").click()
        saved = tmp_path / "orbit.json"
        dl.value.save_as(saved)
        d = json.loads(saved.read_text())
        assert set(d["values"]) == {"controller.kp", "controller.kv"}
        assert d["values"]["controller.kp"] == pytest.approx(kp, rel=1e-10)
        assert d["values"]["controller.kv"] == pytest.approx(kv, rel=1e-10)
        assert set(cli) <= set(d) and d["event"] == cli["event"] == "stroboscopic"
        assert d["spectral_radius"] == pytest.approx(cli["spectral_radius"], rel=1e-9)
        with page.expect_download() as dl:
            page.get_by_role("button", name="save orbit figure").click()
        png = tmp_path / "orbit.png"
        dl.value.save_as(png)
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        with page.expect_download() as dl:
            page.get_by_role("button", name="save map data").click()
        nc = tmp_path / "map.nc"
        dl.value.save_as(nc)
        rm = hp.load_region_map(nc)
        assert rm.x.size == 4 and rm.y.size == 4
        with page.expect_download() as dl:          # no basin yet: says so, saves no file
            page.get_by_role("button", name="save basin data").click()
        empty = tmp_path / "basin.npz"
        dl.value.save_as(empty)
        assert empty.read_bytes().startswith(b"cannot save: nothing computed yet")
    finally:
        ctx.close()
        proc.terminate()
        proc.wait(timeout=10)
