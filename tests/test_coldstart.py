"""Cold start: generated-code cache, lazily compiled kernels, PD loop without python-control.

* The cached closed-form code equals a fresh SymPy derivation (same source, same numbers on
  random inputs); a stale key, a corrupt entry or an unwritable directory regenerate it.
* A cache someone else could write is never executed: planted entries in a world-writable
  directory, writable or foreign entries, symbolic links and a temporary-directory folder with
  other permissions are refused with one warning line, and the code is generated in memory.
* The PD closed loop written out directly equals python-control's interconnection.
* Interpreted kernels (small calls before numba is loaded) give the compiled results.
* PD paths (orbit, simulate, regions, basins, design) import neither python-control, scipy.signal nor
  matplotlib; the orbit and simulate paths load neither numba nor SymPy once the code is cached.
"""
import hashlib
import json
import os
import stat
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hybridpd import _codecache, _jit
from hybridpd.loop import closed_loop
from hybridpd.model import ImpactPair, PDGains, Reference
from hybridpd.pair.symbolic import _numeric
from hybridpd.pair.symbolic.derive import KERNELS, kernel_source, lambdify_kernel

ROOT = Path(__file__).resolve().parents[1]
CASES = ("collocated", "noncollocated")


@pytest.fixture
def cache(tmp_path, monkeypatch):
    d = tmp_path / "cache"
    monkeypatch.setenv("HYBRIDPD_CACHE_DIR", str(d))
    return d


def _random_args(name, rng, k=7):
    """Random arguments (arrays of ``k`` values) for the kernel ``name``."""
    pos = lambda lo=0.1, hi=3.0: rng.uniform(lo, hi, k)
    real = lambda: rng.uniform(-2.0, 2.0, k)
    # kv spans under-, critically and over-damped against kp (D = kv^2/4 - kp changes sign)
    par = [pos(0.5, 40.0), pos(0.2, 15.0), pos(0.5, 2.0), pos(1.0, 8.0)]
    if name in ("flow", "gap"):
        return [pos(0.0, 2.0), *[real() for _ in range(6)], *par]
    if name == "transition":
        return [pos(0.0, 2.0), *par]
    if name == "existence":
        return [*par[:3], pos(0.05, 2.0), pos(0.0, 1.0), pos(0.2, 1.0), par[3], pos(0.5, 2.0),
                rng.choice([1.0, 3.0, 5.0], k)]
    # flight, flight_out: phi, z1, z2, z4, tau, xm, kp, kv, m2, w, L, sig
    return [pos(0.0, 1.0), real(), real(), real(), pos(0.01, 2.0), pos(0.1, 2.0), *par,
            pos(0.2, 1.0), rng.choice([-1.0, 1.0], k)]


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("name", KERNELS)
def test_cached_code_equals_fresh_derivation(cache, name, case):
    key = _numeric.derivation_key()
    cached = _numeric.load_kernel(name, case)            # miss: generated and written
    path = _codecache.entry_path(f"closed_form.{name}.{case}", key)
    assert path.is_file() and path.parent == cache
    text = path.read_text()
    # the entry holds exactly the source a fresh derivation generates
    assert text.endswith(kernel_source(name, case, func_name="kernel"))
    reread = _numeric.load_kernel(name, case)            # hit: executed from disk
    fresh = lambdify_kernel(name, case)
    rng = np.random.default_rng(zlib.crc32(f"{name}/{case}".encode()))
    args = _random_args(name, rng)
    want = [np.broadcast_to(v, args[0].shape) for v in fresh(*args)]
    for f in (cached, reread):
        got = [np.broadcast_to(v, args[0].shape) for v in f(*args)]
        assert len(got) == len(want)
        np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-13)
        assert np.all(np.isfinite(want))


def test_hit_does_not_regenerate_and_stale_key_does(cache, monkeypatch):
    calls = []
    real_generate = _numeric._generate

    def counting(name, case):
        calls.append((name, case))
        return real_generate(name, case)

    monkeypatch.setattr(_numeric, "_generate", counting)
    _numeric.load_kernel("existence", "collocated")
    _numeric.load_kernel("existence", "collocated")
    assert calls == [("existence", "collocated")]
    # a new SymPy (or hybridpd) version gives a new key: the entry is stale and regenerated
    monkeypatch.setattr(_numeric, "sympy_version", lambda: "0.0-other")
    stale_key = _numeric.derivation_key.__wrapped__()
    assert stale_key != _numeric.derivation_key()
    f = _numeric.load_kernel("existence", "collocated", key=stale_key)
    assert len(calls) == 2
    files = sorted(p.name for p in cache.glob("closed_form.existence.collocated-*.py"))
    assert files == [f"closed_form.existence.collocated-{stale_key}.py"]  # old one removed
    np.testing.assert_allclose(f(10, 20, 1, 0.1, 0.5, 0.75, 5, 1, 1),
                               _numeric.kernel("existence", "collocated")(
                                   10, 20, 1, 0.1, 0.5, 0.75, 5, 1, 1), rtol=1e-15)


@pytest.mark.parametrize("damage", ["truncate", "edit", "garbage", "empty"])
def test_corrupt_entry_regenerates(cache, damage):
    key = _numeric.derivation_key()
    _numeric.load_kernel("flow", "noncollocated")
    path = _codecache.entry_path("closed_form.flow.noncollocated", key)
    good = path.read_text()
    bad = {"truncate": good[: len(good) // 2], "edit": good.replace("x0", "x1", 1),
           "garbage": "\x00 not python (", "empty": ""}[damage]
    path.write_text(bad)
    f = _numeric.load_kernel("flow", "noncollocated")
    assert path.read_text() == good
    X = f(0.3, 0.1, 0.2, -0.1, 0.4, 1.0, 0.0, 10.0, 20.0, 1.0, 5.0)
    assert np.all(np.isfinite(np.asarray(X, float)))


def test_unwritable_location_falls_back(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("")
    monkeypatch.setenv("HYBRIDPD_CACHE_DIR", str(blocker / "sub"))  # cannot mkdir under a file
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    d = _codecache.cache_dir()
    assert d is not None and d.parent == tmp_path / "tmp"
    ns = _codecache.load("test.entry", "ab12", lambda: "VALUE = 42\n")
    assert ns["VALUE"] == 42 and (d / "test.entry-ab12.py").is_file()


def _plant(directory, name, key, marker):
    """A valid-looking entry (right header and checksum) that would leave ``marker`` if run."""
    body = f"open({str(marker)!r}, 'w').close()\nVALUE = 'planted'\n"
    digest = hashlib.sha256(body.encode()).hexdigest()
    path = directory / f"{name}-{key}.py"
    path.write_text(_codecache._HEADER.format(name=name, key=key, digest=digest) + body)
    return path


def _generated():
    return "VALUE = 'generated'\n"


def test_planted_entry_in_world_writable_directory_is_never_executed(tmp_path, monkeypatch):
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    marker = tmp_path / "planted-code-ran"
    planted = _plant(shared, "test.entry", "ab12", marker)
    planted.chmod(0o600)  # the entry itself looks fine: the directory gives it away
    text = planted.read_text()
    monkeypatch.setenv("HYBRIDPD_CACHE_DIR", str(shared))
    assert _codecache.cache_dir() is None
    for _ in range(2):
        with pytest.warns(_codecache.UnsafeCacheWarning,
                          match=r"not used.*writable by group or others \(mode 0777\)") as rec:
            ns = _codecache.load("test.entry", "ab12", _generated)
        assert ns["VALUE"] == "generated" and not marker.exists()
        assert len(rec) == 1 and "\n" not in str(rec[0].message)   # one line
    assert sorted(p.name for p in shared.iterdir()) == [planted.name]  # nothing written there
    assert planted.read_text() == text


def test_planted_kernel_is_never_executed(tmp_path, monkeypatch):
    """The same through the closed-form kernels that every orbit computation loads."""
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    marker = tmp_path / "planted-code-ran"
    _plant(shared, "closed_form.existence.collocated", _numeric.derivation_key(), marker)
    monkeypatch.setenv("HYBRIDPD_CACHE_DIR", str(shared))
    with pytest.warns(_codecache.UnsafeCacheWarning, match="writable by group or others"):
        f = _numeric.load_kernel("existence", "collocated")
    assert not marker.exists()
    np.testing.assert_allclose(f(10, 20, 1, 0.1, 0.5, 0.75, 5, 1, 1),
                               lambdify_kernel("existence", "collocated")(
                                   10, 20, 1, 0.1, 0.5, 0.75, 5, 1, 1), rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("attack", ["group_writable", "world_writable", "symlink", "other_owner"])
def test_unsafe_entry_in_own_directory_is_replaced_not_run(cache, tmp_path, attack):
    if attack == "other_owner" and os.geteuid() != 0:
        pytest.skip("giving a file to another user needs root")
    cache.mkdir(mode=0o700)
    marker = tmp_path / "planted-code-ran"
    path = _plant(cache if attack != "symlink" else tmp_path, "test.entry", "ab12", marker)
    if attack == "symlink":
        (cache / path.name).symlink_to(path)
        path = cache / path.name
    elif attack == "other_owner":
        path.chmod(0o644)
        os.chown(path, 65534, 65534)
    else:
        path.chmod(0o620 if attack == "group_writable" else 0o666)
    with pytest.warns(_codecache.UnsafeCacheWarning, match=str(cache)):
        ns = _codecache.load("test.entry", "ab12", _generated)
    assert ns["VALUE"] == "generated" and not marker.exists()
    st = os.lstat(path)   # our directory: the entry was replaced by our own, closed one
    assert stat.S_ISREG(st.st_mode) and st.st_uid == os.getuid()
    assert stat.S_IMODE(st.st_mode) & 0o077 == 0
    ns = _codecache.load("test.entry", "ab12", lambda: pytest.fail("entry should be cached"))
    assert ns["VALUE"] == "generated"


def _fallback_only(tmp_path, monkeypatch):
    """Make the preferred location impossible and the temporary directory ``tmp_path/tmp``."""
    blocker = tmp_path / "file"
    blocker.write_text("")
    monkeypatch.setenv("HYBRIDPD_CACHE_DIR", str(blocker / "sub"))
    (tmp_path / "tmp").mkdir()
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path / "tmp"))
    return tmp_path / "tmp" / f"hybridpd-{os.getuid()}"


def test_temporary_fallback_is_created_closed(tmp_path, monkeypatch):
    d = _fallback_only(tmp_path, monkeypatch)
    assert _codecache.cache_dir() == d
    assert stat.S_IMODE(os.lstat(d).st_mode) == 0o700


@pytest.mark.parametrize("attack", ["open_mode", "symlink", "other_owner"])
def test_temporary_fallback_made_by_someone_else_is_refused(tmp_path, monkeypatch, attack):
    if attack == "other_owner" and os.geteuid() != 0:
        pytest.skip("giving a folder to another user needs root")
    d = _fallback_only(tmp_path, monkeypatch)
    marker = tmp_path / "planted-code-ran"
    if attack == "symlink":
        target = tmp_path / "elsewhere"
        target.mkdir(mode=0o700)
        d.symlink_to(target)
        _plant(target, "test.entry", "ab12", marker)
        why = "symbolic link"
    else:
        d.mkdir(mode=0o700)
        _plant(d, "test.entry", "ab12", marker).chmod(0o600)
        if attack == "open_mode":
            d.chmod(0o755)
            why = "mode 0755, not 0700"
        else:
            os.chown(d, 65534, 65534)
            why = "owned by uid 65534"
    assert _codecache.cache_dir() is None
    with pytest.warns(_codecache.UnsafeCacheWarning, match=why):
        ns = _codecache.load("test.entry", "ab12", _generated)
    assert ns["VALUE"] == "generated" and not marker.exists()


def test_default_location_follows_xdg(tmp_path, monkeypatch):
    monkeypatch.delenv("HYBRIDPD_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert _codecache.cache_dir() == tmp_path / "hybridpd"


@settings(max_examples=25, deadline=None)
@given(kp=st.floats(0.01, 1e3), kv=st.floats(0.01, 1e3), m2=st.floats(0.05, 20),
       w=st.floats(0.05, 50), xm=st.floats(0, 5), case=st.sampled_from(CASES))
def test_pd_fast_path_equals_interconnect(kp, kv, m2, w, xm, case):
    args = (ImpactPair(0.1, 0.5, 0.75, m2), PDGains(kp, kv), Reference(xm, w), case)
    fast = closed_loop(*args)
    ref = closed_loop(*args, method="interconnect")
    scale = max(1.0, np.max(np.abs(ref.A)))
    np.testing.assert_allclose(fast.A, ref.A, rtol=1e-13, atol=1e-15 * scale)
    np.testing.assert_allclose(fast.force, ref.force, rtol=1e-13, atol=1e-15 * scale)
    assert fast.state_names == ref.state_names and fast.gains == ref.gains


def test_fast_path_builds_the_python_control_system_on_demand():
    cl = closed_loop(ImpactPair(0.1, 0.5, 0.75), {"kp": 10, "kv": 20}, Reference(1.0, 5.0),
                     "noncollocated")
    np.testing.assert_allclose(np.asarray(cl.sys.A), cl.A, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(np.asarray(cl.sys.C)[4], cl.force, rtol=1e-14, atol=1e-14)
    assert tuple(cl.sys.state_labels) == cl.state_names


@pytest.mark.parametrize("case", CASES)
def test_interpreted_kernels_equal_compiled(case, monkeypatch):
    from hybridpd.hybrid import automaton
    from hybridpd.pair import orbits
    from hybridpd.pair.impactpair import ControlledImpactPair
    from hybridpd.pair.orbits import symmetric_orbit

    def run(budget):
        monkeypatch.setattr(_jit, "_interpret_budget", lambda: budget)
        if budget:  # as in a new process: these two kernels not compiled yet
            monkeypatch.setattr(automaton.run_hybrid, "_dispatcher", None)
            monkeypatch.setattr(orbits._viability_kernel, "_dispatcher", None)
        sysm = ControlledImpactPair(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20),
                                    Reference(1.0, 5.0), case)
        traj = sysm.simulate([0.2, 0.0, 0.0, 0.1], (0.0, 8.0), max_impacts=150)
        orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0, case=case)
        return traj, orb

    interp_before = _jit.Kernel.interpret
    seen = []
    monkeypatch.setattr(_jit.Kernel, "interpret",
                        lambda self, *a, **k: seen.append(self.__name__) or
                        interp_before(self, *a, **k))
    ti, oi = run(float("inf"))
    assert {"run_hybrid", "_viability_kernel"} <= set(seen)
    seen.clear()
    tc, oc = run(0.0)
    assert not seen
    assert ti.n_impacts == tc.n_impacts > 5
    np.testing.assert_allclose(ti.impact_times, tc.impact_times, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(ti.post, tc.post, rtol=1e-10, atol=1e-10)
    assert oi.exists == oc.exists and oi.reason == oc.reason
    assert oi.viability_margin == pytest.approx(oc.viability_margin, rel=1e-10, abs=1e-12)


def test_interpreted_run_resumes_across_chunks(monkeypatch):
    """Chunks bounded by steps and jumps give the same trajectory as one compiled run."""
    from hybridpd.hybrid import automaton
    from hybridpd.pair.impactpair import ControlledImpactPair

    sysm = ControlledImpactPair(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), Reference(1, 5),
                                "noncollocated")
    monkeypatch.setattr(_jit, "_interpret_budget", lambda: 0.0)
    ref = sysm.simulate([0.0, 0.0, 0.0, 0.0], (0.0, 3.0), max_impacts=200)
    monkeypatch.setattr(_jit, "_interpret_budget", lambda: float("inf"))
    monkeypatch.setattr(automaton, "_INTERP_MAX_STEPS", 7)
    monkeypatch.setattr(automaton, "_INTERP_JUMPS", 5)
    monkeypatch.setattr(automaton.run_hybrid, "_dispatcher", None)  # force interpretation
    got = sysm.simulate([0.0, 0.0, 0.0, 0.0], (0.0, 3.0), max_impacts=200)
    assert got.n_impacts == ref.n_impacts > 20
    np.testing.assert_allclose(got.impact_times, ref.impact_times, rtol=1e-12, atol=1e-12)
    assert got.termination == ref.termination
    assert got.t_final == pytest.approx(ref.t_final)
    np.testing.assert_allclose(got(np.linspace(0, 3, 50)), ref(np.linspace(0, 3, 50)),
                               rtol=1e-9, atol=1e-9)


_PROBE = """
import json, sys
import numpy as np
from hybridpd import ImpactPair, PDGains, Reference
from hybridpd.pair.orbits import symmetric_orbit
from hybridpd.pair.impactpair import ControlledImpactPair
from hybridpd.sweeps.regions import region_map
from hybridpd.pair.regions import SymmetricFamily
out = {}
heavy = ("control", "scipy.signal", "matplotlib", "numba", "sympy")
loaded = lambda: sorted(h for h in heavy if h in sys.modules)
orb = symmetric_orbit(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), 5.0, case="noncollocated")
out["orbit"] = loaded()
tr = ControlledImpactPair(ImpactPair(0.1, 0.5, 0.75), PDGains(10, 20), Reference(1, 5)
                          ).simulate([0, 0, 0, 0], (0, 100), max_impacts=30)
out["simulate"] = loaded()
region_map(SymmetricFamily("collocated", e=(0.5,), mu=0.1, omega=5, L=0.75),
           x=("kp", 1, 20, 3), y=("kv", 1, 20, 3))
out["regions"] = loaded()
from hybridpd.pair.impactmap import ImpactMap
from hybridpd.analysis.mappers import mapper
from hybridpd.sweeps.basins import basin_of_attraction
P = ImpactMap(orb.pair, orb.gains, orb.reference(), orb.case)
basin_of_attraction(mapper(P, orb.fixed_point, n_iter=5), (-0.5, 0.5, 2), (-0.5, 0.5, 2),
                    max_period=0)
out["basins"] = loaded()
from hybridpd.pair.design import design
design("collocated", mu=0.1, e=0.5, omega=5.0, L=0.75, grid=(4, 4), n_starts=1, maxiter=2)
out["design"] = loaded()
out["check"] = [bool(orb.exists), int(tr.n_impacts)]
print(json.dumps(out))
"""


def test_pd_paths_do_not_import_control(cache):
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1",
               HYBRIDPD_CACHE_DIR=str(cache))
    runs = [subprocess.run([sys.executable, "-c", _PROBE], cwd=ROOT, env=env,
                           capture_output=True, text=True, timeout=300, check=False)
            for _ in range(2)]
    for r in runs:
        assert r.returncode == 0, r.stderr
    first, second = (json.loads(r.stdout.strip().splitlines()[-1]) for r in runs)
    for out in (first, second):
        assert out["check"] == [True, 30]
        for path in ("orbit", "simulate", "regions", "basins", "design"):
            assert not {"control", "scipy.signal", "matplotlib"} & set(out[path]), (path, out)
    # with the generated code cached, a PD orbit and a short simulation need no SymPy or numba
    assert second["orbit"] == [] and second["simulate"] == [], second


def test_cli_orbit_does_not_import_control(cache):
    env = dict(os.environ, PYTHONPATH=str(ROOT), HYBRIDPD_CACHE_DIR=str(cache))
    code = ("import runpy, sys; sys.argv = ['hybridpd', 'orbit', '--case', 'collocated', "
            "'--mu', '0.1', '--e', '0.5', '--omega', '5', '--L', '0.75', '--kp', '10', "
            "'--kv', '20', '--json']\n"
            "try:\n    runpy.run_module('hybridpd', run_name='__main__')\n"
            "except SystemExit:\n    pass\n"
            "print('control' in sys.modules, 'scipy.signal' in sys.modules, "
            "'matplotlib' in sys.modules, file=sys.stderr)")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True,
                       text=True, timeout=300, check=False)
    assert json.loads(r.stdout)["exists"] is True
    assert r.stderr.strip().splitlines()[-1] == "False False False"


def test_kernels_pickle_by_reference():
    import pickle

    from hybridpd.pair import batch

    assert pickle.loads(pickle.dumps(batch.next_impact)) is batch.next_impact


_RACE = """
import sys, time
from hybridpd import _codecache

def slow():
    time.sleep(0.2)  # widen the window in which the writers overlap
    return "VALUE = " + repr("x" * 200000) + "\\n"

ns = _codecache.load("race.entry", "feed", slow)
print(len(ns["VALUE"]))
"""


def test_concurrent_writers_leave_a_valid_entry(cache):
    env = dict(os.environ, PYTHONPATH=str(ROOT), HYBRIDPD_CACHE_DIR=str(cache))
    procs = [subprocess.Popen([sys.executable, "-c", _RACE], cwd=ROOT, env=env,
                              stdout=subprocess.PIPE, text=True) for _ in range(4)]
    outs = [p.communicate(timeout=120)[0] for p in procs]
    assert all(p.returncode == 0 for p in procs)
    assert [o.split() for o in outs] == [["200000"]] * 4
    ns = _codecache.load("race.entry", "feed", lambda: pytest.fail("entry should be cached"))
    assert len(ns["VALUE"]) == 200000
    assert sorted(p.name for p in cache.iterdir()) == ["race.entry-feed.py"]  # no temp files
