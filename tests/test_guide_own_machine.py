"""The guide page "Analysing your own machine" (``docs/guide/own_machine.rst``) runs as shown.

Its Python blocks run in ``test_docs.py`` with every guide page (one namespace per page;
their claims are ``assert``\\ s there). Here the blocks that write its model files run again
in a scratch directory, then every ``hybridpd`` command of its ``console`` blocks: each must
exit 0, and the output the page shows after it (the ``text`` block that follows) must agree
with what the command prints now in its key numbers — the section and its phase, the
section point, the jumps per period, the multipliers, structural zeros and spectral radius,
the shares of the region map and of the basin (relative 1e-4: the page shows rounded
numbers; rounding noise such as a multiplier of 2e-15 within 1e-12). The prose's claims on
the region map's cells and on the command's ``--json`` are checked on the files the commands
write.
"""
import json
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from test_docs import hybridpd_commands, rst_blocks, run_blocks

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "guide" / "own_machine.rst"
TEXT = PAGE.read_text(encoding="utf-8")

RTOL, ATOL = 1e-4, 1e-12

_BLOCK = re.compile(r"^\.\. code-block:: (console|text|python)[ \t]*\n((?:[ \t]*:[\w-]+:.*\n)*)"
                    r"((?:[ \t]+.*\n|[ \t]*\n)+)", re.MULTILINE)


def _shown_commands():
    """``(argv, shown output)`` of every ``hybridpd`` command of the page's console blocks,
    in order; the output is the ``text`` block right after the console block."""
    blocks = [(m.group(1), textwrap.dedent(m.group(3))) for m in _BLOCK.finditer(TEXT)]
    out = []
    for i, (kind, body) in enumerate(blocks):
        if kind != "console":
            continue
        shown = blocks[i + 1][1] if i + 1 < len(blocks) and blocks[i + 1][0] == "text" else ""
        rst = ".. code-block:: console\n\n" + textwrap.indent(body, "   ")
        out.extend((argv, shown) for argv in hybridpd_commands(rst, rst=True))
    return out


COMMANDS = _shown_commands()

_NUM = r"([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)"
#: what the page's outputs show, as patterns; the groups that parse as numbers are compared
#: with a tolerance, the others exactly
KEYS = [
    rf"stroboscopic section \(phase phi0 = {_NUM} of the common period {_NUM}, mode ([\w+-]+)",
    r"orbit on contact (\d+) \(wall ([+-]\d), (\w+) in mode ([\w+-]+)",
    r"the event section chosen is the (\w+) of contact (\d+) at wall ([+-]\d)",
    rf"\((\d+) impacts, (\d+) releases in the second half of a {_NUM}-long simulation\)",
    r"section point: (.*)",
    rf"period {_NUM}; jumps per period: (\d+)",
    r"multipliers \|lambda\| = ([^(\n]*)",
    r"\(and (\d+) structural zeros?\b",
    rf"spectral radius = {_NUM} -> (\w+)",
    r"controller\.kp x controller\.kv = (\d+) x (\d+)",
    rf"\bstable {_NUM}%",
    rf"\bunstable {_NUM}%",
    r"cells with two or more orbits: (\d+)",
    rf"slice (\w+) in \[{_NUM}, {_NUM}\], (\w+) in \[{_NUM}, {_NUM}\] \((\d+) x (\d+) points\)",
    rf"off the section or inadmissible: (\d+) of the (\d+) points \({_NUM} %\)",
    (rf"the period-(\d+) orbit \((\d+) T\): {_NUM} % of the (\d+) points, area {_NUM}; "
    rf"(\w+), spectral radius {_NUM}"),
    (rf"inadmissible \(a gap beyond its bounds\): {_NUM} % of the (\d+) points, area {_NUM} "
    r"\((\d+) points"),
]


def _values(text):
    """The numbers of a text (in order) and the text with them replaced by ``#``."""
    nums = [float(x) for x in re.findall(_NUM, text)]
    return nums, re.sub(_NUM, "#", text).split()


def _agree(shown, printed, where):
    """The groups of one pattern agree: the same words, the numbers within tolerance."""
    for a, b in zip(shown, printed, strict=True):
        na, wa = _values(a)
        nb, wb = _values(b)
        assert wa == wb, f"{where}: the page shows {a!r}, the command prints {b!r}"
        assert len(na) == len(nb) and np.allclose(nb, na, rtol=RTOL, atol=ATOL), \
            f"{where}: the page shows {a!r}, the command prints {b!r}"


def _env():
    path = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
    return dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=path)


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    """A scratch directory holding the page's model files (its blocks that write them)."""
    d = tmp_path_factory.mktemp("own_machine")
    writing = [b for b in rst_blocks(TEXT) if "write_text(" in b]
    run_blocks(writing, d, "own_machine.rst (the blocks that write the model files)")
    return d


@pytest.fixture(scope="module")
def run(workdir):
    """``run(argv)``: ``hybridpd argv`` in the scratch directory, each command once."""
    done = {}

    def _run(argv):
        key = tuple(argv)
        if key not in done:
            done[key] = subprocess.run([sys.executable, "-m", "hybridpd", *argv], cwd=workdir,
                                       env=_env(), capture_output=True, text=True,
                                       timeout=600, check=False)
        return done[key]

    return _run


def test_page_is_in_the_guide():
    index = (ROOT / "docs" / "guide" / "index.rst").read_text(encoding="utf-8")
    assert re.search(r"^   own_machine$", index, re.MULTILINE)
    assert TEXT.splitlines()[0] == "Analysing your own machine"


def test_every_command_shows_its_output():
    # the orbit of each file, the hunting loop, the region map and the basin
    assert len(COMMANDS) >= 5
    subcommands = [argv[0] for argv, _ in COMMANDS]
    assert {"orbit", "regions", "basin"} <= set(subcommands)
    for argv, shown in COMMANDS:
        assert shown.strip(), f"hybridpd {' '.join(argv)}: no output shown after it"
        assert any(re.search(k, shown) for k in KEYS), f"hybridpd {' '.join(argv)}"


@pytest.mark.parametrize("argv, shown", COMMANDS, ids=lambda v: "-".join(v[:3])
                         if isinstance(v, list) else None)
def test_command_prints_what_the_page_shows(argv, shown, run):
    r = run(argv)
    label = "hybridpd " + " ".join(argv)
    assert r.returncode == 0, f"{label}:\n{r.stderr[-3000:]}"
    for key in KEYS:
        want = re.search(key, shown)
        if want is None:
            continue
        got = re.search(key, r.stdout)
        assert got is not None, f"{label}: prints no {key!r}:\n{r.stdout}"
        _agree(want.groups(), got.groups(), label)


def _command(name):
    argvs = [argv for argv, _ in COMMANDS if argv[0] == name]
    assert len(argvs) == 1, name
    return argvs[0]


def test_region_map_cells_as_the_page_says(run, workdir):
    """The unstable cell is kp = 32, kv = 0.45; the cells with two orbits are kp = 32 at
    kv = 0.45 and 1.65, and their two orbits are a fraction of a percent apart."""
    import xarray as xr

    argv = _command("regions")
    assert run(argv).returncode == 0
    out = argv[argv.index("--out") + 1]
    with xr.open_dataset(workdir / out) as ds:
        kp, kv = ds["controller.kp"].values, ds["controller.kv"].values
        stable, exists = ds.stable.values[0], ds.exists.values[0]
        n_orbits = ds.n_orbits.values[0]
        z1, z2 = ds.section_state.values[0], ds.section_state2.values[0]
    unstable = [(kp[i], kv[j]) for j in range(len(kv)) for i in range(len(kp))
                if exists[j, i] and not stable[j, i]]
    assert unstable == [(32.0, 0.45)]
    two = [(j, i) for j in range(len(kv)) for i in range(len(kp)) if n_orbits[j, i] >= 2]
    assert [(kp[i], kv[j]) for j, i in two] == [(32.0, 0.45), (32.0, 1.65)]
    for j, i in two:
        gap = np.max(np.abs(z1[j, i] - z2[j, i])) / max(1.0, np.max(np.abs(z1[j, i])))
        assert 0 < gap < 1e-2, (kp[i], kv[j], gap)


def test_orbit_json_gives_the_tables_numbers(run):
    """``hybridpd orbit ... --json`` gives the numbers the page's table computes in Python:
    its row of the file's gains at T/1000, on the free-flight section."""
    row = re.search(r"\* - ``kp = 8, kv = 1`` \(the file\)\n((?:     - .*\n){5})", TEXT)
    radii = [float(x) for x in re.findall(r"- ([\d.]+)", row.group(1))]
    r = run(["orbit", "--model", "joint.toml", "--set", "controller.dt", "0.001",
             "--phase", "0.3825", "--json"])
    assert r.returncode == 0, r.stderr[-3000:]
    d = json.loads(r.stdout)
    assert d["event"] == "stroboscopic" and d["section_mode"] == "free"
    assert d["coordinates"] == ["motor", "motor_dot", "link", "link_dot", "h0"]
    assert d["structural_zeros"] == 3 and len(d["multipliers"]) == 2
    np.testing.assert_allclose(d["spectral_radius"], radii[2], rtol=2e-3)
    assert len(d["pre"]) == 4 and d["jacobian"] == "saltation"
