"""Everything the documentation shows runs.

* Every Python block of the README (in order, one namespace, as a reader pastes them) and of
  each user-guide page (``docs/guide/*.rst``, ``.. code-block:: python``, one namespace per
  page) runs without error, in a scratch directory. Claims of the text are ``assert``\\ s in
  the blocks, so they are checked too.
* Every docstring example (``>>>``) of the public modules runs as a doctest after
  ``import numpy as np`` and ``import hybridpd as hp``. Printed numbers are compared with a
  relative tolerance (:data:`DOCTEST_RTOL`), not digit for digit: the last digits of a
  computed float differ between machines and library versions. New examples are collected
  automatically.

Both compare with numbers written down from an earlier run, so both are marked
``stored_data``: .ci/run runs them a second time on NumPy's narrower SIMD paths.
"""
import doctest
import importlib
import os
import pkgutil
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import hybridpd

ROOT = Path(__file__).resolve().parents[1]
GUIDE = ROOT / "docs" / "guide"

# a printed value agrees when within this relative tolerance (or DOCTEST_ATOL of zero)
DOCTEST_RTOL = 1e-6
DOCTEST_ATOL = 1e-12


# ---------------------------------------------------------------------------------------------
# code blocks of the README and the guide

_MD_BLOCK = re.compile(r"^```python[ \t]*\n(.*?)^```[ \t]*$", re.DOTALL | re.MULTILINE)
_RST_BLOCK = re.compile(r"^( *)\.\. code-block:: python[ \t]*\n((?:[ \t]*:[\w-]+:.*\n)*)"
                        r"((?:\1[ \t]+.*\n|[ \t]*\n)+)", re.MULTILINE)


def markdown_blocks(text):
    """The bodies of the ```` ```python ```` blocks of a Markdown text, in order."""
    return [m.group(1) for m in _MD_BLOCK.finditer(text)]


def rst_blocks(text):
    """The bodies of the ``.. code-block:: python`` directives of an rST text, in order."""
    return [textwrap.dedent(m.group(3)) for m in _RST_BLOCK.finditer(text)]


def run_blocks(blocks, cwd, label, timeout=300):
    """Run the blocks one after the other in one fresh interpreter; fail naming the block."""
    script = ["import sys"]
    for i, b in enumerate(blocks, 1):
        script.append(f"print('--- block {i}', file=sys.stderr, flush=True)")
        script.append(b)
    path = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=path)
    r = subprocess.run([sys.executable, "-c", "\n".join(script)], cwd=cwd, env=env,
                       capture_output=True, text=True, timeout=timeout, check=False)
    assert r.returncode == 0, f"{label}:\n{r.stderr[-3000:]}"
    return r


def test_block_extraction():
    md = "x\n```python\na = 1\n```\n```bash\nno\n```\n```python\nb = a\n```\n"
    assert markdown_blocks(md) == ["a = 1\n", "b = a\n"]
    rst = ("Text\n\n.. code-block:: python\n   :caption: c\n\n   a = 1\n\n   if a:\n"
           "       b = 2\n\nafter\n\n.. code-block:: bash\n\n   no\n")
    assert rst_blocks(rst) == ["\na = 1\n\nif a:\n    b = 2\n\n"]


@pytest.mark.stored_data
def test_readme_python_blocks_run(tmp_path):
    blocks = markdown_blocks((ROOT / "README.md").read_text(encoding="utf-8"))
    assert len(blocks) >= 2
    r = run_blocks(blocks, tmp_path, "README.md")
    assert "stable" in r.stdout            # the orbit prints its one-line summary
    assert (tmp_path / "basin.png").stat().st_size > 10_000


GUIDE_PAGES = sorted(GUIDE.glob("*.rst"))


def test_every_guide_page_with_code_is_collected():
    assert len(GUIDE_PAGES) >= 9
    with_code = [p.name for p in GUIDE_PAGES if rst_blocks(p.read_text(encoding="utf-8"))]
    assert len(with_code) >= 8, with_code
    for p in GUIDE_PAGES:  # a block written another way would escape the tests
        text = p.read_text(encoding="utf-8")
        assert "code-block:: py\n" not in text and ".. code::" not in text, p.name
        assert not re.search(r"^\.\. (ipython|plot)::", text, re.MULTILINE), p.name


@pytest.mark.stored_data
@pytest.mark.parametrize("page", [p for p in GUIDE_PAGES
                                  if rst_blocks(p.read_text(encoding="utf-8"))],
                         ids=lambda p: p.stem)
def test_guide_python_blocks_run(page, tmp_path):
    run_blocks(rst_blocks(page.read_text(encoding="utf-8")), tmp_path, page.name)


# ---------------------------------------------------------------------------------------------
# docstring examples

_NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?(?:j)?")


class TolerantChecker(doctest.OutputChecker):
    """Doctest output checker that compares the numbers in the output with a tolerance.

    The text between numbers must match (whitespace normalised); the numbers must agree to
    :data:`DOCTEST_RTOL` relative or :data:`DOCTEST_ATOL` absolute. ``...`` keeps its doctest
    meaning (the exact check is tried first).
    """

    def check_output(self, want, got, optionflags):
        if super().check_output(want, got, optionflags):
            return True
        w_text, g_text = _NUMBER.split(want), _NUMBER.split(got)
        w_num, g_num = _NUMBER.findall(want), _NUMBER.findall(got)
        if len(w_num) != len(g_num) or not w_num:
            return False
        if [" ".join(t.split()) for t in w_text] != [" ".join(t.split()) for t in g_text]:
            return False
        a = np.array([complex(x) for x in g_num])
        b = np.array([complex(x) for x in w_num])
        return bool(np.all(np.abs(a - b) <= DOCTEST_ATOL + DOCTEST_RTOL * np.abs(b)))


def _public_modules():
    names = ["hybridpd"]
    for info in pkgutil.walk_packages(hybridpd.__path__, "hybridpd."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            names.append(info.name)
    return sorted(names)


def _doctests():
    finder = doctest.DocTestFinder(exclude_empty=True)
    out = []
    for name in _public_modules():
        try:
            module = importlib.import_module(name)
        except ImportError:  # an optional dependency is missing: its examples cannot run
            continue
        for t in finder.find(module, name):
            if t.examples:
                out.append(t)
    return sorted(out, key=lambda t: t.name)


DOCTESTS = _doctests()


_IMPORT_EACH = """
import importlib, sys
failed = []
for name in sys.argv[1:]:
    for loaded in [m for m in sys.modules if m == "hybridpd" or m.startswith("hybridpd.")]:
        del sys.modules[loaded]
    try:
        importlib.import_module(name)
    except Exception as exc:  # noqa: BLE001 - reported below
        failed.append(f"{name}: {type(exc).__name__}: {exc}")
print("\\n".join(failed))
sys.exit(1 if failed else 0)
"""


@pytest.mark.slow  # ~20 s; the documentation build (autosummary) also imports them this way
def test_every_public_module_imports_first():
    """Each module imports in a process where no other hybridpd module was loaded before it
    (as the API reference imports them, in its own order): no import cycle hides behind the
    usual import order."""
    names = _public_modules()
    assert len(names) > 50
    path = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
    r = subprocess.run([sys.executable, "-c", _IMPORT_EACH, *names], capture_output=True,
                       text=True, timeout=300, check=False,
                       env=dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=path))
    assert r.returncode == 0, r.stdout + r.stderr[-2000:]


def test_doctests_are_collected():
    # the modules with examples today; new examples are collected without a change here
    assert len(DOCTESTS) >= 40
    assert {t.name.rsplit(".", 1)[0] for t in DOCTESTS} >= {"hybridpd.model",
                                                            "hybridpd.pair.regions"}


def test_tolerant_checker():
    c, flags = TolerantChecker(), doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    assert c.check_output("rho 0.5238180000\n", "rho 0.5238180000001\n", flags)
    assert c.check_output("[1.0, 2.5e-3]\n", "[1.0000000001, 0.0025]\n", flags)
    assert not c.check_output("rho 0.52\n", "rho 0.53\n", flags)
    assert not c.check_output("stable 1\n", "unstable 1\n", flags)
    assert not c.check_output("1 2\n", "1 2 3\n", flags)
    assert c.check_output("x = ...\n", "x = anything\n", flags)


@pytest.mark.stored_data
@pytest.mark.parametrize("test", DOCTESTS, ids=lambda t: t.name)
def test_docstring_examples(test, tmp_path, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)  # examples that write files write them here
    test.globs = {**test.globs, "np": np, "hp": hybridpd}
    runner = doctest.DocTestRunner(TolerantChecker(), verbose=False,
                                   optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    out = []
    result = runner.run(test, out=out.append)
    assert result.failed == 0, "".join(out)


# ---------------------------------------------------------------------------------------------
# command lines of the README and the guide
_MD_SHELL = re.compile(r"^```(?:bash|console|sh)[ \t]*\n(.*?)^```[ \t]*$", re.DOTALL | re.MULTILINE)
_RST_SHELL = re.compile(r"^( *)\.\. code-block:: (?:bash|console|sh)[ \t]*\n((?:[ \t]*:[\w-]+:.*\n)*)"
                        r"((?:\1[ \t]+.*\n|[ \t]*\n)+)", re.MULTILINE)


def hybridpd_commands(text, rst=False):
    """Every ``hybridpd ...`` command of the shell blocks of a text (continuation lines
    joined, comments dropped), as argument lists without the program name."""
    import shlex

    bodies = ([textwrap.dedent(m.group(3)) for m in _RST_SHELL.finditer(text)] if rst
              else [m.group(1) for m in _MD_SHELL.finditer(text)])
    out = []
    for body in bodies:
        for line in body.replace("\\\n", " ").splitlines():
            line = line.split("#", 1)[0].strip().removeprefix("$ ")
            for part in re.split(r"&&|;|\|", line):
                words = shlex.split(part)
                if words[:1] == ["hybridpd"]:
                    out.append(words[1:])
    return out


def _documents():
    yield "README.md", (ROOT / "README.md").read_text(encoding="utf-8"), False
    for page in sorted(GUIDE.glob("*.rst")):
        yield f"docs/guide/{page.name}", page.read_text(encoding="utf-8"), True


def test_every_documented_command_line_parses():
    """The command lines the documentation shows are accepted by the CLI's parser (their
    options exist and their values have the right types); running them is the job of the
    command-line tests, which run each subcommand on small inputs."""
    from hybridpd.cli import build_parser

    parser = build_parser()
    seen = 0
    for label, text, rst in _documents():
        for argv in hybridpd_commands(text, rst):
            try:
                parser.parse_args(argv)
            except SystemExit as exc:  # argparse reports and exits (0 for --help, --version)
                if exc.code == 0:
                    continue
                pytest.fail(f"{label}: hybridpd {' '.join(argv)} (exit {exc.code})")
            seen += 1
    assert seen >= 10


@pytest.mark.slow
def test_readme_three_joint_arm_commands_run(tmp_path):
    """The README's commands on the three-joint arm run as printed (a few minutes)."""
    import shlex

    text = (ROOT / "README.md").read_text(encoding="utf-8")
    argvs = [a for a in hybridpd_commands(text) if any("arm3.toml" in w for w in a)]
    assert len(argvs) >= 2          # its orbit and its region map
    path = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=path)
    for argv in argvs:
        argv = [str(ROOT / w) if w.startswith("examples/") else w for w in argv]
        r = subprocess.run([sys.executable, "-m", "hybridpd", *argv], cwd=tmp_path, env=env,
                           capture_output=True, text=True, timeout=1800, check=False)
        assert r.returncode == 0, f"hybridpd {shlex.join(argv)}:\n{r.stderr[-2000:]}"
