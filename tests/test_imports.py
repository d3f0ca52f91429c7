"""Every module of the package imports on its own (no import cycles hidden by import order)."""
import os
import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest

import hybridpd

ROOT = Path(__file__).resolve().parents[1]
MODULES = sorted(m.name for m in pkgutil.walk_packages(hybridpd.__path__, "hybridpd.")
                 if m.name != "hybridpd.__main__")

# Each module is imported after every hybridpd module was dropped from sys.modules: the same
# import order as in a fresh interpreter for the package's own modules, at a fraction of the
# cost of one interpreter per module.
_SCRIPT = """
import importlib, sys, traceback
bad = []
for name in sys.argv[1:]:
    for m in [k for k in sys.modules if k == "hybridpd" or k.startswith("hybridpd.")]:
        del sys.modules[m]
    try:
        importlib.import_module(name)
    except Exception:
        bad.append(name + ": " + traceback.format_exc().splitlines()[-1])
print("\\n".join(bad))
sys.exit(1 if bad else 0)
"""


def _env():
    return dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1")


def test_every_module_imports_first(tmp_path):
    assert len(MODULES) > 50
    # The script executes the package's modules some 8000 times: with PYTHONDONTWRITEBYTECODE
    # set (as on some machines) each would be compiled from source again, most of its cost.
    # Bytecode is cached in a scratch directory instead (never in the checkout); what runs is
    # the same.
    env = {k: v for k, v in _env().items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = str(tmp_path / "pycache")
    r = subprocess.run([sys.executable, "-c", _SCRIPT, *MODULES], capture_output=True,
                       text=True, env=env, timeout=300, check=False)
    assert r.returncode == 0, r.stdout + r.stderr


@pytest.mark.slow
@pytest.mark.parametrize("name", MODULES)
def test_module_imports_in_a_fresh_interpreter(name):
    r = subprocess.run([sys.executable, "-c", f"import {name}"], capture_output=True,
                       text=True, env=_env(), timeout=120, check=False)
    assert r.returncode == 0, r.stderr
