"""The structure of harness/plclab: data flows one way, so imports run one way.

LAYERS is the one statement of the order, lowest first (README's Layout section lists the same
order; the last test holds the two together). A module may import its own layer and the ones
below it, never one above; and no modules import each other round a circle. Imports are read
with ast, those inside functions included: a lazy import is still a dependency.
"""
from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "harness" / "plclab"

# lowest first; the names on one line are one layer (they may import each other, without a circle)
LAYERS: list[tuple[str, ...]] = [
    ("errors",),
    ("fileio", "limits"),
    ("config",),
    ("iec",),
    ("trace",),
    ("frontend", "nc"),           # language front ends: ST (and plc.xml), G-code
    ("runtime",),
    ("scenario", "plants"),
    ("modbus", "plcopen"),
    ("stands",),
    ("hmi", "cnc"),
    ("serve",),
    ("grader", "build"),
    ("runner", "handout", "lab"),
    ("bench", "cli"),
]
LAYER_OF = {name: i for i, names in enumerate(LAYERS) for name in names}


def module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


MODULES = {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _existing(name: str) -> str:
    """The module an import names: `a.b.c` if it is a module, else its package."""
    while name not in MODULES and "." in name:
        name = name.rsplit(".", 1)[0]
    return name


def imports(module: str) -> list[tuple[str, int]]:
    """(imported plclab module, line) for every import statement of `module`, at any depth."""
    path = MODULES[module]
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join(up + ([node.module] if node.module else []))
            subs = [f"{base}.{a.name}" for a in node.names]
            names = subs if all(s in MODULES for s in subs) else [base]
        else:
            continue
        found += [(_existing(n), node.lineno) for n in names if n == "plclab" or n.startswith("plclab.")]
    return found


def unit(module: str) -> str:
    """The layer unit of a module: its top-level module or package under plclab."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def test_every_module_and_package_has_a_layer():
    units = {unit(m) for m in MODULES} - {"__init__", "__main__"}
    assert sorted(units - set(LAYER_OF)) == [], "add it to LAYERS (and to README's Layout)"
    assert sorted(set(LAYER_OF) - units) == [], "a layer names a module that is gone"


def test_no_import_runs_up_a_layer():
    upward = []
    for module in MODULES:
        here = LAYER_OF.get(unit(module))
        if here is None:
            continue
        for target, line in imports(module):
            there = LAYER_OF.get(unit(target))
            if there is not None and there > here:
                upward.append(f"{MODULES[module].relative_to(ROOT)}:{line}: {module} imports {target} "
                              f"(layer {there} above {here})")
    assert upward == []


def test_no_modules_import_each_other_round_a_circle():
    graph = {m: {t for t, _ in imports(m) if t != m and t in MODULES} for m in MODULES}
    circles = [c for c in _strongly_connected(graph) if len(c) > 1]
    assert circles == []


def _strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's algorithm, iterative: the groups of modules that reach each other."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    groups: list[list[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            v, children = work[-1]
            for w in children:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    group = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        group.append(w)
                        if w == v:
                            break
                    groups.append(sorted(group))
    return groups


def test_the_checks_see_an_upward_import_and_a_circle(tmp_path, monkeypatch):
    """The tests above fail when the structure breaks: an import inside a function that runs
    up, and two modules importing each other."""
    pkg = tmp_path / "plclab"
    (pkg / "iec").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "iec" / "__init__.py").write_text("")
    (pkg / "iec" / "a.py").write_text("def f():\n    from plclab.runtime import plc\n    from . import b\n")
    (pkg / "iec" / "b.py").write_text("from plclab.iec.a import f\n")
    (pkg / "runtime").mkdir()
    (pkg / "runtime" / "__init__.py").write_text("")
    (pkg / "runtime" / "plc.py").write_text("")
    monkeypatch.setattr(sys.modules[__name__], "PACKAGE", pkg)
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    monkeypatch.setattr(sys.modules[__name__], "MODULES", {module_name(p): p for p in sorted(pkg.rglob("*.py"))})
    assert ("plclab.runtime.plc", 2) in imports("plclab.iec.a")
    with pytest.raises(AssertionError, match="plclab.iec.a imports plclab.runtime.plc"):
        test_no_import_runs_up_a_layer()
    with pytest.raises(AssertionError, match="plclab.iec.a"):
        test_no_modules_import_each_other_round_a_circle()


def test_readme_layout_lists_the_layers_in_this_order():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("## Layout", 1)[1].split("\n## ", 1)[0]
    m = re.search(r"Layers, lowest first:(.*?)(?:\n\n|\Z)", section, re.S)
    assert m, "README's Layout section states the layer order"
    written = [tuple(w.strip() for w in layer.split(",")) for layer in m.group(1).replace("\n", " ").split("<")]
    assert [tuple(n.strip("` .") for n in layer) for layer in written] == LAYERS
