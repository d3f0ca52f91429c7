"""Every example and every symbolic derivation script runs (examples with ``--quick``).

The examples are the documentation's gallery: ``examples/<topic>/plot_*.py``, each topic a
folder with a ``README.txt`` header. Like the gallery, the tests run them one after the other
in one interpreter (each as ``__main__``, in its own directory).
"""
import json
import os
import runpy
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples").glob("*/plot_*.py"))
SCRIPTS = sorted((ROOT / "symbolic").glob("*.py"))
REPRODUCTION = ROOT / "examples" / "reproduction" / "plot_reproduce_paper.py"
#: Examples whose quick run is a benchmark of the package rather than a check of the script:
#: slow here (``-m slow``; .ci/run's documentation build runs every example in quick mode
#: too). The reproduction example is ``hybridpd reproduce --quick`` (over a minute and ~2 min
#: of CPU); its fast version is test_reproduction_example_prints_what_the_command_wrote, and
#: the reproduction itself is checked on small grids by test_reproduce.py and test_figures.py.
SLOW_QUICK_RUNS = {REPRODUCTION}


def _env():
    # the checkout under test, whatever hybridpd the interpreter has installed
    path = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
    return dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=path)


def _run(args, cwd, timeout=600):
    return subprocess.run([sys.executable, *map(str, args)], check=False, cwd=cwd, env=_env(),
                          capture_output=True, text=True, timeout=timeout)


def _id(p):
    return f"{p.parent.name}/{p.name}"


def test_every_example_is_in_a_gallery_topic():
    assert len(EXAMPLES) >= 14
    loose = [p.name for p in (ROOT / "examples").glob("*.py") if not p.name.startswith("_")]
    assert loose == [], "examples belong in a topic folder as plot_*.py"
    assert (ROOT / "examples" / "README.txt").is_file()
    for topic in {p.parent for p in EXAMPLES}:
        assert (topic / "README.txt").is_file(), f"{topic.name} has no gallery header"
        stray = [q.name for q in topic.glob("*.py") if not q.name.startswith("plot_")]
        assert stray == [], f"{topic.name}: only plot_*.py scripts are run by the gallery"
    for p in EXAMPLES:  # the gallery takes each page's title from the docstring's first lines
        lines = p.read_text().split("\n")
        assert lines[0].startswith('"""') and set(lines[1]) == {"="}, p.name
        assert len(lines[1]) >= len(lines[0]) - 3, f"{p.name}: title underline too short"
        # the gallery runs the scripts inside the Sphinx process: an exit would end the build
        assert "SystemExit(main" not in p.read_text() and "sys.exit(" not in p.read_text()


# The examples run as scripts in one interpreter, one after the other, as the gallery runs them
# in the documentation build (one start-up and one import of the package instead of one per
# example), each in its own empty directory, with matplotlib's figures closed and its settings
# reset in between as the gallery does: for each, its exit status (None: it ran to its end),
# what it printed, the traceback of an error, what it left in its directory.
_RUN_EACH = """
import contextlib, io, json, os, runpy, sys, time, traceback
import matplotlib
import matplotlib.pyplot as plt
base, args, paths, out = sys.argv[1], json.loads(sys.argv[2]), sys.argv[3:], {}
for i, path in enumerate(paths):
    cwd = os.path.join(base, str(i))
    os.mkdir(cwd)
    os.chdir(cwd)
    plt.close("all")
    matplotlib.rcdefaults()
    sys.argv, saved_path, text = [path, *args], list(sys.path), io.StringIO()
    status, error, t0, c0 = None, "", time.perf_counter(), time.process_time()
    try:
        with contextlib.redirect_stdout(text):
            runpy.run_path(path, run_name="__main__")
    except SystemExit as exc:
        status = exc.code
    except BaseException:
        status, error = "error", traceback.format_exc()[-3000:]
    sys.path[:] = saved_path
    left = {d: sorted(os.listdir(os.path.join(cwd, d))) for d in os.listdir(cwd)
            if os.path.isdir(os.path.join(cwd, d))}
    out[path] = {"status": status, "stdout": text.getvalue(), "error": error,
                 "left": sorted(os.listdir(cwd)), "files": left,
                 "seconds": time.perf_counter() - t0, "cpu": time.process_time() - c0}
print(json.dumps(out))
"""


def _run_each(paths, args, base, timeout, processes=1):
    """``{str(path): record}`` of :data:`_RUN_EACH` for the scripts ``paths``, shared out
    between ``processes`` interpreters that run at the same time."""
    groups = [paths[k::processes] for k in range(processes) if paths[k::processes]]
    procs = []
    for k, group in enumerate(groups):
        cwd = Path(base) / f"p{k}"
        cwd.mkdir()
        procs.append(subprocess.Popen(
            [sys.executable, "-c", _RUN_EACH, str(cwd), json.dumps(args), *map(str, group)],
            cwd=cwd, env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True))
    out = {}
    try:
        for p in procs:
            stdout, stderr = p.communicate(timeout=timeout)
            assert p.returncode == 0, stderr[-3000:]
            out.update(json.loads(stdout.splitlines()[-1]))
    finally:
        for p in procs:
            if p.poll() is None:  # pragma: no cover - only on a timeout
                p.kill()
                p.wait()
    return out


def _selected(request, test):
    """The ``path`` parameters of this module's ``test`` that this session runs."""
    return [it.callspec.params["path"] for it in request.session.items
            if getattr(it, "originalname", None) == test and it.module.__name__ == __name__]


@pytest.fixture(scope="module")
def helps(request, tmp_path_factory):
    return _run_each(_selected(request, "test_example_help_computes_nothing"), ["--help"],
                     tmp_path_factory.mktemp("helps"), timeout=300)


@pytest.fixture(scope="module")
def quick_runs(request, tmp_path_factory):
    # two interpreters: the examples take most of this module's time, and the test machine
    # has two cores at least
    return _run_each(_selected(request, "test_example_runs_quick"), ["--quick", "--out", "out"],
                     tmp_path_factory.mktemp("quick"), timeout=1800, processes=2)


@pytest.mark.parametrize("path", EXAMPLES, ids=_id)
def test_example_help_computes_nothing(path, helps):
    h = helps[str(path)]
    assert h["status"] == 0 and "--out" in h["stdout"], h
    assert h["left"] == []  # no folder named after the flag, no output


def test_reproduction_example_prints_what_the_command_wrote(tmp_path, monkeypatch, capsys):
    """The fast version of the reproduction example's quick run: the script runs as the gallery
    runs it, and the command it calls, whose command line must parse, is answered by the tests'
    shared small reproduction (tests/_reproduce_run.py) instead of the quick one."""
    import shutil

    from _reproduce_run import small_run

    import hybridpd.cli

    out, calls = tmp_path / "out", []

    def command(argv):
        hybridpd.cli.build_parser().parse_args(argv)
        calls.append(argv)
        shutil.copytree(small_run()[0].parent, out, dirs_exist_ok=True)
        return 0

    monkeypatch.setattr(hybridpd.cli, "main", command)
    monkeypatch.setattr(sys, "argv", [str(REPRODUCTION), "--quick", "--out", str(out)])
    monkeypatch.setattr(sys, "path", list(sys.path))  # the script puts examples/ on it
    monkeypatch.chdir(tmp_path)
    runpy.run_path(str(REPRODUCTION), run_name="__main__")
    assert calls == [["reproduce", "--quick", "--out", str(out), "--quiet"]]
    printed = capsys.readouterr().out
    assert printed.strip() and printed.strip() == (out / "summary.md").read_text().strip()
    assert any(out.rglob("*.png"))


def _quick(p):
    return pytest.param(p, id=_id(p), marks=pytest.mark.slow if p in SLOW_QUICK_RUNS else ())


@pytest.mark.parametrize("path", [_quick(p) for p in EXAMPLES])
def test_example_runs_quick(path, quick_runs):
    r = quick_runs[str(path)]
    assert r["status"] is None, r["error"] or r
    assert any(f.endswith(".png") for f in r["files"].get("out", [])), \
        "the example wrote no figure"


@pytest.mark.parametrize("path", SCRIPTS, ids=lambda p: p.name)
def test_symbolic_script_runs(path, tmp_path):
    r = _run([path], cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.strip()
