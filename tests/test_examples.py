"""Every example and every symbolic derivation script runs (examples with ``--quick``)."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted(p for p in (ROOT / "examples").glob("*.py") if not p.name.startswith("_"))
SCRIPTS = sorted((ROOT / "symbolic").glob("*.py"))


def _run(args, cwd, timeout=600):
    # the checkout under test, whatever hybridpd the interpreter has installed
    path = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=path)
    return subprocess.run([sys.executable, *map(str, args)], check=False, cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=timeout)


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_example_help_computes_nothing(path, tmp_path):
    r = _run([path, "--help"], cwd=tmp_path, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "--out" in r.stdout
    assert list(tmp_path.iterdir()) == []  # no folder named after the flag, no output


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_example_runs_quick(path, tmp_path):
    out = tmp_path / "out"
    r = _run([path, "--quick", "--out", out], cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    assert any(out.iterdir()), "the example wrote no figure"


@pytest.mark.parametrize("path", SCRIPTS, ids=lambda p: p.name)
def test_symbolic_script_runs(path, tmp_path):
    r = _run([path], cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.strip()
