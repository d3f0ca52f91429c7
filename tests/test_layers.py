"""The package's layers, read from the source: imports point one way and never form a cycle.

Layers, lowest first: the parameter modules (``model``, ``loop`` and the private helpers) ->
``hybrid`` (the automaton, the map protocol, the section map of any automaton) ->
``mechanics`` -> ``analysis`` (only what works on any map) -> ``sweeps`` -> ``pair`` (the
impact pair: a client of the generic layers that supplies maps and hooks) -> ``plotting`` ->
``reproduce`` -> ``cli``. So no module of ``hybrid``, ``mechanics``, ``analysis`` or
``sweeps`` imports the pair: the general modules are every module of those packages, read from
the tree. Every import is an arrow, of four kinds: at the top of a module (``top``), inside a
function (``func``), by name (``string``: a module-path string such as ``import_module`` or a
lazy table takes) and ``import_module`` of an f-string (``fstring``: every child of its
package); only imports under ``if TYPE_CHECKING:`` (annotations) are not. No module but the
root's lazy namespace answers for names it does not define (a module ``__getattr__``).
"""
from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "hybridpd"

LAYER = {"model": 0, "loop": 1, "hybrid": 2, "mechanics": 3, "analysis": 4, "sweeps": 5,
         "pair": 6, "plotting": 7, "reproduce": 8, "cli": 9, "explore": 9, "__main__": 10}

# The general path: every module of these packages, found in the tree (none may import the
# impact pair).
GENERAL_PACKAGES = ("hybrid", "mechanics", "analysis", "sweeps")
GENERAL = tuple(sorted(
    ".".join(p.relative_to(PKG.parent).with_suffix("").parts).removesuffix(".__init__")
    for pkg in GENERAL_PACKAGES for p in (PKG / pkg).rglob("*.py")))


def _module_name(path: Path) -> str:
    parts = path.relative_to(PKG.parent).with_suffix("").parts
    name = ".".join(parts)
    return name.removesuffix(".__init__")


# every module of the package, read from the tree
MODULE_PATHS = {_module_name(p): p for p in sorted(PKG.rglob("*.py"))
                if "__pycache__" not in p.parts}


def _type_checking_lines(tree) -> set:
    lines = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for sub in node.body:
                lines.update(range(sub.lineno, (sub.end_lineno or sub.lineno) + 1))
    return lines


def _top_level_imports(tree) -> set:
    """The import statements run when the module loads: the module's own statements and those
    in a top-level ``try``/``if`` (an optional dependency), not those inside a function."""
    top = set()
    for node in tree.body:
        if isinstance(node, (ast.Try, ast.If)):
            top.update(id(sub) for sub in ast.walk(node)
                       if isinstance(sub, (ast.Import, ast.ImportFrom)))
        else:
            top.add(id(node))
    return top


# a module path given by name: "hybridpd.x.y" or "hybridpd.x.y:name" (import_module, tables)
_DOTTED = re.compile(r"^hybridpd(\.\w+)+(:\w+)?$")


def _from_import(node, mod: str, path: Path) -> list:
    if node.level:
        base = mod.split(".")[: -node.level + (1 if path.name == "__init__.py" else 0) or None]
        first = ".".join([*base, node.module] if node.module else base)
    else:
        first = node.module or ""
    # ``from hybridpd.x import y`` may name a submodule y
    return [first, *(f"{first}.{a.name}" for a in node.names)]


def _fstring_children(node, modules) -> list:
    """The modules an ``import_module(f"hybridpd.x.{...}")`` call can load: every child of
    ``hybridpd.x`` (the f-string's constant head)."""
    arg = node.args[0] if node.args else None
    if not (isinstance(arg, ast.JoinedStr) and arg.values
            and isinstance(arg.values[0], ast.Constant)):
        return []
    head = str(arg.values[0].value)
    if not head.startswith("hybridpd.") or not head.endswith("."):
        return []
    pkg = head[:-1]
    depth = pkg.count(".") + 1
    return [m for m in modules if m.startswith(head) and m.count(".") == depth]


def _imports(path: Path, modules=MODULE_PATHS, mod: str | None = None):
    """Yield ``(target, line, kind)`` for every arrow from ``path`` into the package.

    ``kind`` is ``"top"`` (an import run when the module loads), ``"func"`` (an import inside
    a function), ``"string"`` (a string that is a module path, as ``import_module`` and lazy
    tables take it) or ``"fstring"`` (``import_module(f"hybridpd.x.{...}")``: every child of
    ``hybridpd.x``). Only imports under ``if TYPE_CHECKING:`` (annotations) are left out.
    ``mod``: the module's name (read from ``path`` in the package by default).
    """
    tree = ast.parse(path.read_text())
    skip = _type_checking_lines(tree)
    top = _top_level_imports(tree)
    mod = mod or _module_name(path)
    for node in ast.walk(tree):
        line = getattr(node, "lineno", None)
        if line in skip:
            continue
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else _from_import(node, mod, path))
            kind = "top" if id(node) in top else "func"
            yield from ((n, line, kind) for n in names if n.startswith("hybridpd"))
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) \
                and _DOTTED.match(node.value):
            yield node.value.split(":")[0], line, "string"
        elif isinstance(node, ast.Call) and ast.unparse(node.func).endswith("import_module"):
            yield from ((m, line, "fstring") for m in _fstring_children(node, modules))


def _resolve(name: str, modules) -> str | None:
    """The longest module prefix of ``name`` (``hybridpd.x.y.Name`` -> ``hybridpd.x.y``)."""
    parts = name.split(".")
    while parts and ".".join(parts) not in modules:
        parts.pop()
    return ".".join(parts) if parts else None


def _graph():
    edges = {}
    for mod, path in MODULE_PATHS.items():
        targets = set()
        for name, line, kind in _imports(path):
            target = _resolve(name, MODULE_PATHS)
            if target and target != mod:
                targets.add((target, line, kind))
        edges[mod] = targets
    return MODULE_PATHS, edges


def _layer(mod: str) -> int:
    parts = mod.split(".")
    if len(parts) == 1:
        return -1
    return LAYER.get(parts[1], 0)


MODULES, EDGES = _graph()


def test_the_graph_is_read():
    assert len(MODULES) > 80
    assert any(t[0] == "hybridpd.hybrid.events" for t in EDGES["hybridpd.hybrid.automaton"])


def test_no_import_points_upward():
    upward = [f"{m} -> {t} (line {line})" for m, ts in EDGES.items() for t, line, _ in ts
              if _layer(t) > _layer(m) >= 0 and _layer(t) >= 0
              # a package's __init__ may gather its own subpackages
              and not t.startswith(m + ".")]
    assert not upward, "imports pointing to a higher layer:\n" + "\n".join(sorted(upward))


def test_general_path_does_not_import_the_pair():
    bad = [f"{m} -> {t} (line {line})" for m in GENERAL for t, line, _ in EDGES[m]
           if t.startswith("hybridpd.pair")]
    assert not bad, "the general path imports the impact pair:\n" + "\n".join(bad)


def _cycles():
    adj = {m: sorted({t for t, _, _ in ts if not m.startswith(t + ".")}) for m, ts in
           EDGES.items()}
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def strong(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in adj.get(v, ()):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(adj):
        if v not in index:
            strong(v)
    return out


def test_no_import_cycles():
    """Deferred imports count: an import moved into a function does not break a cycle."""
    cycles = _cycles()
    assert not cycles, "import cycles:\n" + "\n".join(" <-> ".join(c) for c in cycles)


@pytest.mark.parametrize("layer", ["hybrid", "mechanics"])
def test_lower_layers_import_nothing_above(layer):
    banned = ("analysis", "pair", "sweeps", "plotting", "reproduce", "cli")
    bad = [f"{m} -> {t}" for m, ts in EDGES.items() if m.startswith(f"hybridpd.{layer}")
           for t, _, _ in ts if t.split(".")[1] in banned]
    assert not bad, "\n".join(bad)


def _deferred_without_reason(path: Path) -> list:
    """Lines of ``path`` with an import of hybridpd inside a function (or below the top level)
    that no ``deferred`` comment explains (on the line, or above it in its block of imports)."""
    lines = path.read_text().split("\n")
    out = []
    for name, line, kind in _imports(path):
        if kind != "func" or "deferred" in lines[line - 1]:
            continue
        j = line - 2
        while j >= 0:
            s = lines[j].strip()
            if s.startswith("#") and "deferred" in s:
                break
            if s.startswith(("#", "from ", "import ", ")")) or s == "" or s.endswith(","):
                j -= 1
                continue
            out.append(f"{_module_name(path)}:{line} ({name})")
            break
    return out


def test_deferred_imports_say_why():
    """An import of the package placed inside a function is there for start-up time and says
    so; one placed there to dodge a cycle would show up in test_no_import_cycles."""
    bad = sorted({b for p in PKG.rglob("*.py") for b in _deferred_without_reason(p)})
    assert not bad, "deferred imports without a comment saying why:\n" + "\n".join(bad)


def test_every_kind_of_import_is_an_arrow(tmp_path):
    f = tmp_path / "m.py"
    f.write_text(
        "import importlib\n"
        "from hybridpd.model import Case\n"
        "try:\n    import hybridpd.loop\nexcept ImportError:\n    pass\n"
        'X = {"a": "hybridpd.sweeps.regions:RegionMap"}\n'
        "def g(k):\n    from hybridpd.analysis import maps\n"
        '    return importlib.import_module(f"hybridpd.pair.{k}")\n'
        'DOC = "see hybridpd.pair for more"\n'
        'NOTE = f"hybridpd.plotting.{DOC}"\n')
    got = {(t, line, kind) for t, line, kind in _imports(f, mod="hybridpd.m")}
    assert {("hybridpd.model", 2, "top"), ("hybridpd.model.Case", 2, "top"),
            ("hybridpd.loop", 4, "top"), ("hybridpd.sweeps.regions", 7, "string"),
            ("hybridpd.analysis", 9, "func"), ("hybridpd.analysis.maps", 9, "func"),
            ("hybridpd.pair.impactmap", 10, "fstring"),
            ("hybridpd.pair.continuation", 10, "fstring")} <= got
    # an f-string import loads a child of its package, not a grandchild
    assert ("hybridpd.pair.continuation.switching", 10, "fstring") not in got
    # prose is not an import, nor an f-string given to anything but import_module
    assert not any(line in (11, 12) for _, line, _ in got)


def test_the_graph_holds_every_kind():
    kinds = {kind for ts in EDGES.values() for _, _, kind in ts}
    assert kinds == {"top", "func", "string", "fstring"}, kinds
    # the command line's f-string import of its subcommands is in the graph
    assert ("hybridpd.cli.basin", "fstring") in {(t, k) for t, _, k in EDGES["hybridpd.cli"]}


def _module_getattr_and_path(path: Path) -> list:
    """The module-level ``__getattr__`` definitions and every assignment to ``__path__`` in
    ``path`` (a ``__path__`` turns a module into a package that imports can reach by name)."""
    tree = ast.parse(path.read_text())
    found = []
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) \
                and node.name == "__getattr__":
            found.append(("__getattr__", node.lineno))
    for node in ast.walk(tree):
        targets = (node.targets if isinstance(node, ast.Assign) else
                   [node.target] if isinstance(node, (ast.AugAssign, ast.AnnAssign)) else [])
        for tg in targets:
            name = tg.id if isinstance(tg, ast.Name) else getattr(tg, "attr", None)
            if name == "__path__" or (name == "__getattr__" and node in tree.body):
                found.append((name, node.lineno))
        if isinstance(node, ast.Call) and ast.unparse(node.func) == "setattr" \
                and len(node.args) > 1 and isinstance(node.args[1], ast.Constant) \
                and node.args[1].value in ("__path__", "__getattr__"):
            found.append((node.args[1].value, node.lineno))
    return found


def test_no_module_getattr_except_namespace():
    """No module answers for names it does not define: the only module ``__getattr__`` is the
    root's lazy namespace (the table ``_NAMES`` and the subpackages), and nothing assigns
    ``__path__``."""
    found = {m: f for m, p in MODULE_PATHS.items() if (f := _module_getattr_and_path(p))}
    root = found.pop("hybridpd", [])
    assert not found, f"module __getattr__ or __path__ outside the root namespace: {found}"
    assert [n for n, _ in root] == ["__getattr__"], root
    getattr_def = next(n for n in ast.parse(MODULE_PATHS["hybridpd"].read_text()).body
                       if getattr(n, "name", None) == "__getattr__")
    used = {n.id for n in ast.walk(getattr_def) if isinstance(n, ast.Name)}
    assert {"_NAMES", "_SUBPACKAGES"} <= used


def test_the_getattr_check_finds_shims(tmp_path):
    f = tmp_path / "shim.py"
    f.write_text("import sys\n__path__ = []\ndef __getattr__(name):\n    return name\n"
                 "sys.modules[__name__].__path__ = []\n")
    assert _module_getattr_and_path(f) == [("__getattr__", 3), ("__path__", 2),
                                           ("__path__", 5)]
