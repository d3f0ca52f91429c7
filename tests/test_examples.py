"""Every example and every symbolic derivation script runs (examples with ``--quick``).

The examples are the documentation's gallery: ``examples/<topic>/plot_*.py``, each topic a
folder with a ``README.txt`` header.
"""
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples").glob("*/plot_*.py"))
SCRIPTS = sorted((ROOT / "symbolic").glob("*.py"))


def _run(args, cwd, timeout=600):
    # the checkout under test, whatever hybridpd the interpreter has installed
    path = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=path)
    return subprocess.run([sys.executable, *map(str, args)], check=False, cwd=cwd, env=env,
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


@pytest.mark.parametrize("path", EXAMPLES, ids=_id)
def test_example_help_computes_nothing(path, tmp_path):
    r = _run([path, "--help"], cwd=tmp_path, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "--out" in r.stdout
    assert list(tmp_path.iterdir()) == []  # no folder named after the flag, no output


@pytest.mark.parametrize("path", EXAMPLES, ids=_id)
def test_example_runs_quick(path, tmp_path):
    out = tmp_path / "out"
    r = _run([path, "--quick", "--out", out], cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    assert any(out.glob("*.png")), "the example wrote no figure"


@pytest.mark.parametrize("path", SCRIPTS, ids=lambda p: p.name)
def test_symbolic_script_runs(path, tmp_path):
    r = _run([path], cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.strip()
