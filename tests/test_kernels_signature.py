"""No compiled kernel takes more than 8 positional arguments: options and tables travel as
named records (``RunOptions``, ``FlowTables``, ``ReturnRun``, ``LabelSpec``, ``Flight``, ...),
read by name inside the kernels, so that no call site can pass two of them swapped.

The check parses the package's sources: a kernel is a function decorated by a compiler
(``njit`` of :mod:`hybridpd._jit` or numba's ``njit``/``jit``/``vectorize``/..., bare, called
with options or through a module attribute) or wrapped by one in a call (``f = njit(g)``).
"""
import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "hybridpd"
MAX_POSITIONAL = 8
COMPILERS = {"njit", "jit", "generated_jit", "vectorize", "guvectorize", "cfunc", "stencil",
             "Kernel"}
# a decorator line of a compiler, read as text: the AST scan must find as many kernels
_DECORATOR_LINE = re.compile(r"^\s*@(?:\w+\.)*(?:" + "|".join(sorted(COMPILERS)) + r")\b",
                             re.MULTILINE)


def _compiler(node) -> bool:
    """``njit``, ``numba.njit``, ``njit(cache=True)``, ``nb.jit(...)``, ..."""
    if isinstance(node, ast.Call):
        node = node.func
    name = node.attr if isinstance(node, ast.Attribute) else getattr(node, "id", None)
    return name in COMPILERS


def _positional(fn) -> float:
    a = fn.args
    return float("inf") if a.vararg else len(a.posonlyargs) + len(a.args)


def kernels(source: str) -> list:
    """``(name, line, positional arguments)`` of every compiled function in ``source``."""
    tree = ast.parse(source)
    defs = {}
    found = {}
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            defs.setdefault(node.name, node)
            if any(_compiler(d) for d in node.decorator_list):
                found[id(node)] = (node.name, node.lineno, _positional(node))
    # compiled by a call: njit(f), njit(cache=True)(f), Kernel(f, {...})
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and (_compiler(node.func) or _compiler(node)):
            for arg in node.args[:1]:
                fn = defs.get(arg.id) if isinstance(arg, ast.Name) else None
                if fn is not None:
                    found[id(fn)] = (fn.name, fn.lineno, _positional(fn))
    return sorted(found.values(), key=lambda k: k[1])


def _package_kernels() -> dict:
    out = {}
    for path in sorted(ROOT.rglob("*.py")):
        src = path.read_text(encoding="utf-8")
        ks = kernels(src)
        decorated = len(_DECORATOR_LINE.findall(src))
        assert len(ks) >= decorated, f"{path}: {decorated} compiler decorators, {len(ks)} found"
        if ks:
            out[path.relative_to(ROOT.parent).as_posix()] = ks
    return out


def test_no_kernel_takes_more_than_eight_positional_arguments():
    found = _package_kernels()
    names = {name for ks in found.values() for name, _, _ in ks}
    # the scan sees the package's kernels (the decorator of hybridpd._jit included)
    assert sum(len(ks) for ks in found.values()) > 50
    assert {"run_hybrid_ex", "advance", "_to_return", "_label_kernel", "next_impact",
            "map_labels", "_viability_kernel"} <= names
    bad = [f"{path}:{line} {name} ({n} positional)" for path, ks in found.items()
           for name, line, n in ks if n > MAX_POSITIONAL]
    assert not bad, "kernels with more than 8 positional arguments (pass records):\n" + \
        "\n".join(bad)


BAD = '''
import numba
import numba as nb
from hybridpd._jit import njit

@njit(cache=True)
def a(p1, p2, p3, p4, p5, p6, p7, p8, p9):
    pass

@numba.njit
def b(p1, p2, p3, p4, p5, p6, p7, p8, p9=0):
    pass

@nb.jit(nopython=True)
def c(p1, p2, p3, p4, p5, p6, p7, p8, p9, *, fine=1):
    pass

def d(p1, p2, p3, p4, p5, p6, p7, p8, p9):
    pass

d_compiled = njit(cache=True)(d)

@njit
def e(*args):
    pass

@njit(cache=True)
def ok(p1, p2, p3, p4, p5, p6, p7, p8, *, k=1):
    pass

def plain(p1, p2, p3, p4, p5, p6, p7, p8, p9):
    pass
'''


@pytest.mark.parametrize("name", ["a", "b", "c", "d", "e"])
def test_the_check_catches_a_wide_kernel(name):
    found = {k[0]: k[2] for k in kernels(BAD)}
    assert found[name] > MAX_POSITIONAL


def test_the_check_passes_narrow_kernels_and_ignores_plain_functions():
    found = {k[0]: k[2] for k in kernels(BAD)}
    assert found["ok"] == 8 and "plain" not in found
    assert len(_DECORATOR_LINE.findall(BAD)) == 5
