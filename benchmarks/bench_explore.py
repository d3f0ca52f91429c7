"""Response times of ``hybridpd explore``: measured in a browser and on the server side.

Run ``python benchmarks/bench_explore.py`` (needs Panel, Bokeh, Playwright and Chromium at
``/usr/bin/chromium`` or ``$HYBRIDPD_CHROMIUM``). Prints, with the goal of each:

* in the browser (Playwright, headless Chromium; the server is ``hybridpd explore
  --no-browser`` started by the script): the page usable after the command starts (its map
  and orbit shown; goal 3 s), a click on the map until the orbit and multipliers show (goal
  0.3 s), a change of ``e`` until the 201 x 201 map is redrawn (goal 2 s), a 101 x 101
  basin slice until it shows (goal 3 s; for a stable and an unstable orbit);
* on the server side, in this process: the computation behind each (wall and CPU time).

Wall time depends on what else runs on the machine: the CPU time (user + system) is given
beside it. ``--screenshots DIR`` takes the user guide's pictures of the page instead.
"""
from __future__ import annotations

import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from _browser import CHROMIUM  # the browser, flags and map script of the tests
from _browser import CHROMIUM_ARGS as ARGS
from _browser import MAP_POINT_JS as _MAP_POINT_JS

LIMIT = 30.0        # seconds: the longest any wait below may take


def _cpu(pid: int) -> float:
    """User + system CPU seconds of process ``pid`` so far (Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _wait(page, tid, ok):
    """Seconds until the text of ``tid`` satisfies ``ok`` (polled every 5 ms, bounded)."""
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < LIMIT:        # bounded: LIMIT seconds
        loc = page.get_by_test_id(tid)
        if loc.count() and ok(loc.first.inner_text()):
            return time.perf_counter() - t0
        page.wait_for_timeout(5)
    raise TimeoutError(f"{tid} not ready within {LIMIT} s: "
                       f"{page.get_by_test_id(tid).first.inner_text()!r}")



def _click_cell(page, kp, kv, xs=None, ys=None):
    page.mouse.click(*page.evaluate(_MAP_POINT_JS, [kp, kv]))


def browser_times() -> dict:
    from playwright.sync_api import sync_playwright

    from hybridpd.explore.server import free_port
    from hybridpd.explore.state import PairState

    port = free_port()
    url = f"http://127.0.0.1:{port}/"
    out = {}
    with sync_playwright() as p:
        # the browser is up before the command starts, as a user's is
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        page = b.new_page(viewport={"width": 1500, "height": 1500})
        t_start = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "hybridpd", "explore", "--no-browser",
                                 "--port", str(port)], stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True,
                                env=dict(os.environ, PYTHONPATH=str(ROOT)))
        try:
            proc.stdout.readline()          # listening
            out["listening"] = time.perf_counter() - t_start
            page.goto(url + "?case=collocated&e=0.5&kp=10&kv=20")
            _wait(page, "map-e", lambda t: t == "0.5")
            _wait(page, "spectral-radius", lambda t: t != "none")
            out["page usable after the command"] = time.perf_counter() - t_start
            st = PairState()
            xs, ys = st.kp_axis(), st.kv_axis()
            clicks = []
            for k in range(10):
                ix, iy = 20 + 17 * k, 180 - 15 * k
                page.wait_for_timeout(400)    # two taps closer than this make a double tap
                _click_cell(page, float(xs[ix]), float(ys[iy]))
                t0 = time.perf_counter()
                want = f"{xs[ix]:.12g}"
                _wait(page, "selected-kp", lambda t, w=want: t == w)
                clicks.append(time.perf_counter() - t0)
            out["click -> orbit shown (median of 10)"] = statistics.median(clicks)
            out["click -> orbit shown (max of 10)"] = max(clicks)
            field = page.get_by_role("textbox", name="e", exact=True)
            redraws = []
            for e in ("0.1", "0.9", "0.3", "0.7", "0.5"):
                field.fill(e)
                t0 = time.perf_counter()
                field.press("Enter")
                _wait(page, "map-e", lambda t, w=e: t == w)
                redraws.append(time.perf_counter() - t0)
            out["e changed -> 201 x 201 map redrawn (median of 5)"] = statistics.median(redraws)
            for label, q in (("stable orbit", "case=collocated&e=0.5&kp=10&kv=20"),
                             ("unstable orbit", "case=noncollocated&e=0.9&kp=30&kv=12")):
                page.goto(url + "?" + q)
                _wait(page, "map-e", lambda t: True)
                page.get_by_role("button", name="compute basin slice").click()
                t0 = time.perf_counter()
                _wait(page, "basin-status", lambda t: t == "done")
                out[f"101 x 101 basin shown ({label})"] = time.perf_counter() - t0
            out["server CPU (user+sys) over the whole run"] = _cpu(proc.pid)
        finally:
            proc.terminate()
            proc.wait(timeout=20)
            b.close()
    return out


def server_times() -> dict:
    from hybridpd.explore.state import PairState, orbit_series, pair_basin, pair_map, pair_orbit

    def timed(fn):
        w, c = time.perf_counter(), time.process_time()
        fn()
        return time.perf_counter() - w, time.process_time() - c

    st = PairState()
    pair_map(st)                                  # warm: numba's compiled kernels
    stable = pair_orbit(st)
    unstable = pair_orbit(PairState(case="noncollocated", e=0.9, kp=30, kv=12))
    pair_basin(stable, 11)
    return {
        "orbit + series (one click)": timed(lambda: orbit_series(pair_orbit(st))),
        "201 x 201 map": timed(lambda: pair_map(st.replace(e=0.1))),
        "101 x 101 basin (stable orbit)": timed(lambda: pair_basin(stable, 101)),
        "101 x 101 basin (unstable orbit)": timed(lambda: pair_basin(unstable, 101)),
    }


def screenshots(folder: Path) -> list:
    """The user guide's pictures of the page (PNG), taken in the browser."""
    from playwright.sync_api import sync_playwright

    from hybridpd.explore.app import pair_app
    from hybridpd.explore.server import free_port, serve

    folder.mkdir(parents=True, exist_ok=True)
    port = free_port()
    thread = serve(port, open_browser=False, app=pair_app, threaded=True, verbose=False)
    written = []
    try:
        with sync_playwright() as p:
            b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            page = b.new_page(viewport={"width": 1400, "height": 1000})
            page.goto(f"http://127.0.0.1:{port}/?case=noncollocated&e=0.1&kp=12.5&kv=25")
            _wait(page, "map-e", lambda t: t == "0.1")
            page.wait_for_timeout(500)
            _click_cell(page, 20.06, 15.0)
            _wait(page, "selected-kp", lambda t: t != "12.5")
            page.wait_for_timeout(500)
            shot = folder / "explore_page.png"
            page.screenshot(path=shot, clip={"x": 0, "y": 0, "width": 1340, "height": 980})
            written.append(shot)
            page.wait_for_timeout(400)
            _click_cell(page, 5.09, 3.094)        # a stable orbit: its basin is worth a look
            _wait(page, "selected-kp", lambda t: t == "5.09")
            page.get_by_role("button", name="compute basin slice").click()
            _wait(page, "basin-status", lambda t: t == "done" or "failed" in t)
            page.get_by_role("button", name="follow branch").click()
            _wait(page, "branch-status", lambda t: t.startswith("done") or "failed" in t)
            page.wait_for_timeout(500)
            for name in ("basin slice", "branch"):
                shot = folder / f"explore_{name.split()[0]}.png"
                page.locator(".card").filter(has_text=name).last.screenshot(path=shot)
                written.append(shot)
            page.evaluate("window.scrollTo(0, 0)")
            field = page.get_by_role("textbox", name="e", exact=True)
            field.fill("1.5")
            field.press("Enter")
            page.get_by_test_id("error-e").wait_for()
            page.wait_for_timeout(300)
            shot = folder / "explore_refused.png"
            page.screenshot(path=shot, clip={"x": 0, "y": 0, "width": 260, "height": 200})
            written.append(shot)
            b.close()
    finally:
        thread.stop()
    return written


def main():
    if "--screenshots" in sys.argv:
        for path in screenshots(Path(sys.argv[sys.argv.index("--screenshots") + 1])):
            print(f"wrote {path}")
        return
    if "--browser-only" not in sys.argv:
        print("server side (this process; seconds wall, CPU):")
        for k, (w, c) in server_times().items():
            print(f"  {k:40s} {w:8.3f} {c:8.3f}")
    if not Path(CHROMIUM).exists():
        print(f"browser times skipped: no Chromium at {CHROMIUM}")
        return
    print("in the browser (seconds wall):")
    for k, v in browser_times().items():
        print(f"  {k:50s} {v:8.3f}")


if __name__ == "__main__":
    main()
