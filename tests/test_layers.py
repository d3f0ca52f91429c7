"""The package's layers, read from the source: imports point one way and never form a cycle.

Layers, lowest first: the parameter modules (``model``, ``loop`` and the private helpers) ->
``hybrid`` (the automaton, the map protocol, the section map of any automaton) ->
``mechanics`` -> ``analysis`` (only what works on any map) -> ``sweeps`` -> ``pair`` (the
impact pair: a client of the generic layers that supplies maps and hooks) -> ``plotting`` ->
``reproduce`` -> ``cli``. So no module of ``hybrid``, ``mechanics``, ``analysis`` or
``sweeps`` imports the pair: the general modules are every module of those packages, read from
the tree. Every import is an arrow: at the top of a module, inside a function, and by name
(a module-path string such as ``import_module`` or a lazy table takes, an f-string
``import_module``); only imports under ``if TYPE_CHECKING:`` (annotations) are not.
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


def _type_checking_lines(tree) -> set:
    lines = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for sub in node.body:
                lines.update(range(sub.lineno, (sub.end_lineno or sub.lineno) + 1))
    return lines


def _imports(path: Path):
    """Yield ``(target module, line, deferred)`` for every hybridpd import in ``path``."""
    src = path.read_text()
    tree = ast.parse(src)
    skip = _type_checking_lines(tree)
    top = {id(n) for n in tree.body}
    mod = _module_name(path)
    for node in ast.walk(tree):
        if node.lineno in skip if hasattr(node, "lineno") else False:
            continue
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = mod.split(".")[: -node.level + (1 if path.name == "__init__.py" else 0)
                                    or None]
                names = [".".join([*base, node.module] if node.module else base)]
            else:
                names = [node.module or ""]
            # ``from hybridpd.x import y`` may name a submodule y
            names += [f"{names[0]}.{a.name}" for a in node.names]
        else:
            continue
        for n in names:
            if n.startswith("hybridpd"):
                yield n, node.lineno, id(node) not in top


_DOTTED = re.compile(r"^hybridpd(\.\w+)+(:\w+)?$")


def _string_imports(path: Path, modules):
    """Yield ``(target module, line, True)`` for imports by name: a string that is a module
    path (``"hybridpd.x.y"`` or ``"hybridpd.x.y:name"``, as ``import_module`` and lazy tables
    take them) and ``import_module(f"hybridpd.x.{...}")`` (every module below
    ``hybridpd.x``). An import by name is an import: it counts for cycles and layers."""
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) \
                and _DOTTED.match(node.value):
            yield node.value.split(":")[0], node.lineno, True
        elif isinstance(node, ast.JoinedStr) and node.values \
                and isinstance(node.values[0], ast.Constant) \
                and str(node.values[0].value).startswith("hybridpd."):
            head = str(node.values[0].value).rstrip(".")
            for m in modules:
                if m.startswith(head + "."):
                    yield m, node.lineno, True


def _graph():
    modules = {_module_name(p): p for p in PKG.rglob("*.py")}
    edges = {}
    for mod, path in modules.items():
        targets = set()
        arrows = [*_imports(path)]
        if mod != "hybridpd":      # the root's lazy table names every public module
            arrows += [*_string_imports(path, modules)]
        for name, line, deferred in arrows:
            # resolve to the longest existing module prefix
            parts = name.split(".")
            while parts and ".".join(parts) not in modules:
                parts.pop()
            if parts and ".".join(parts) != mod:
                targets.add((".".join(parts), line, deferred))
        edges[mod] = targets
    return modules, edges


def _layer(mod: str) -> int:
    parts = mod.split(".")
    if len(parts) == 1:
        return -1
    return LAYER.get(parts[1], 0)


MODULES, EDGES = _graph()


def test_the_graph_is_read():
    assert len(MODULES) > 80
    assert ("hybridpd.hybrid.events", ) and any(
        t[0] == "hybridpd.hybrid.events" for t in EDGES["hybridpd.hybrid.automaton"])


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
    for name, line, deferred in _imports(path):
        if not deferred or "deferred" in lines[line - 1]:
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


def test_imports_by_name_are_arrows(tmp_path):
    f = tmp_path / "m.py"
    f.write_text('import importlib\nX = {"a": "hybridpd.sweeps.regions:RegionMap"}\n'
                 'def g(k):\n    return importlib.import_module(f"hybridpd.plotting.{k}")\n'
                 'DOC = "see hybridpd.pair for more"\n')
    got = {(m, line) for m, line, _ in _string_imports(f, MODULES)}
    assert ("hybridpd.sweeps.regions", 2) in got
    assert ("hybridpd.plotting.regions", 4) in got and ("hybridpd.plotting.basins", 4) in got
    assert not any(line == 5 for _, line in got)          # prose is not an import
    # the command line's f-string import of its subcommands is in the graph
    assert any(t == "hybridpd.cli.basin" for t, _, _ in EDGES["hybridpd.cli"])
