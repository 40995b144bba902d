"""The import layers of python/mgn (docs/architecture.md), checked on the source with ``ast``.

Every ``import`` statement of every module is read, at module level, inside functions and under
``if TYPE_CHECKING:`` alike, and resolved to the mgn module it names. Three rules:

1. *Downward only*: a module imports only modules of its own package or of a lower layer
   (:data:`LAYERS`); two packages of the same layer are independent of each other.
2. *No cycles* in the module import graph.
3. *Imports at the top*: an import inside a function is allowed only for the heavy optional
   dependencies of :data:`LAZY_IMPORTS` (not installed by default, or slow to import and needed
   by one command only).

A fourth check reads every ``raise``: mgn raises the classes of :mod:`mgn.errors` (which also
derive from the matching builtin), never a plain builtin of :data:`BANNED_RAISES`.

The test of the test copies the package to a temporary folder, adds one upward import, one cycle
and one function-level import, and checks that each is reported.
"""

from __future__ import annotations

import ast
import re
import shutil
from dataclasses import dataclass
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "python" / "mgn"

# Layer of each package (or module) of mgn, bottom first. A module belongs to the longest entry
# that prefixes its dotted name. ``mgn`` itself (the public facade, python/mgn/__init__.py) and
# ``mgn.__main__`` sit above everything: nothing inside the package may import the facade.
LAYERS: dict[str, int] = {
    "mgn._core": 0,
    "mgn.errors": 1,
    "mgn.base": 2,
    "mgn.geometry": 3,
    "mgn.hardware": 3,
    "mgn.objects": 4,
    "mgn.suction": 5,
    "mgn.pj": 5,
    "mgn.scene": 6,
    "mgn.render": 7,
    "mgn.view_labels": 7,
    "mgn.io": 8,
    "mgn.pipeline": 9,
    "mgn.calibration": 9,
    "mgn.eval": 10,
    "mgn.learn": 10,
    "mgn.viz": 10,
    "mgn.cli": 11,
    "mgn.__main__": 12,
    "mgn": 12,
}

# Third-party modules that may be imported inside a function: optional extras (dask, distributed,
# scipy, trimesh, fcl are not dependencies of mgn) or heavy and used by one command only.
LAZY_IMPORTS: frozenset[str] = frozenset(
    # pyoidn: optional denoiser; torch: the learning extra mgn[learn]
    {"dask", "distributed", "scipy", "trimesh", "fcl", "pyoidn", "torch"}
)


# Builtins mgn never raises itself: each has an mgn.errors class that also derives from it.
BANNED_RAISES: frozenset[str] = frozenset(
    {"Exception", "ValueError", "TypeError", "RuntimeError", "OSError", "IOError"}
)


@dataclass(frozen=True)
class Edge:
    """One import: ``importer`` imports ``target`` (both dotted module names) at ``line``."""

    importer: str
    target: str
    line: int
    in_function: bool

    def __str__(self) -> str:
        where = "inside a function" if self.in_function else "at module level"
        return f"{self.importer} -> {self.target} (line {self.line}, {where})"


def module_names(root: Path) -> dict[str, Path]:
    """Dotted name of every module under ``root`` (a folder named after its package)."""
    names = {}
    for path in sorted(root.rglob("*.py")):
        parts = list(path.relative_to(root.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        names[".".join(parts)] = path
    return names


def _imports(tree: ast.AST) -> list[tuple[ast.Import | ast.ImportFrom, bool]]:
    """Every import statement of ``tree`` with whether it sits inside a function."""
    found: list[tuple[ast.Import | ast.ImportFrom, bool]] = []

    def visit(node: ast.AST, in_function: bool) -> None:
        for child in ast.iter_child_nodes(node):
            inside = in_function or isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef)
            if isinstance(child, ast.Import | ast.ImportFrom):
                found.append((child, inside))
            visit(child, inside)

    visit(tree, False)
    return found


def import_edges(root: Path) -> tuple[list[Edge], list[Edge]]:
    """(edges between mgn modules, imports of other modules made inside functions)."""
    names = module_names(root)
    known = set(names) | {"mgn._core"}
    edges: list[Edge] = []
    lazy_external: list[Edge] = []
    for name, path in names.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node, in_function in _imports(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            else:
                if node.level:
                    base = package.split(".")[: len(package.split(".")) - node.level + 1]
                    module = ".".join(base + ([node.module] if node.module else []))
                else:
                    module = node.module or ""
                # ``from P import m`` imports the module P.m when it exists, else names of P.
                targets = [
                    f"{module}.{alias.name}" if f"{module}.{alias.name}" in known else module
                    for alias in node.names
                ]
            for target in dict.fromkeys(targets):
                edge = Edge(name, target, node.lineno, in_function)
                if target == "mgn" or target.startswith("mgn."):
                    edges.append(edge)
                elif in_function:
                    lazy_external.append(edge)
    return edges, lazy_external


def layer(module: str) -> tuple[str, int]:
    """(layer entry, layer number) of a dotted mgn module name."""
    best = max((k for k in LAYERS if module == k or module.startswith(k + ".")), key=len)
    return best, LAYERS[best]


def upward_edges(edges: list[Edge]) -> list[Edge]:
    """Edges to a higher layer, or to another package of the same layer."""
    bad = []
    for e in edges:
        (home, rank), (target_home, target_rank) = layer(e.importer), layer(e.target)
        if target_rank > rank or (target_rank == rank and target_home != home):
            bad.append(e)
    return bad


def cycles(edges: list[Edge]) -> list[list[str]]:
    """The non-trivial strongly connected components of the module graph (Tarjan)."""
    graph: dict[str, set[str]] = {}
    for e in edges:
        graph.setdefault(e.importer, set()).add(e.target)
        graph.setdefault(e.target, set())
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def strongconnect(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                strongconnect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1 or v in graph[v]:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            strongconnect(v)
    return found


def function_level(edges: list[Edge], lazy_external: list[Edge]) -> list[Edge]:
    """Imports inside functions other than those of :data:`LAZY_IMPORTS`."""
    bad = [e for e in edges if e.in_function]
    bad += [e for e in lazy_external if e.target.partition(".")[0] not in LAZY_IMPORTS]
    return bad


def plain_raises(root: Path) -> list[str]:
    """``raise X(...)`` / ``raise X`` statements whose X is in :data:`BANNED_RAISES`."""
    found = []
    for name, path in module_names(root).items():
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Raise) and node.exc is not None:
                exc = node.exc.func if isinstance(node.exc, ast.Call) else node.exc
                if isinstance(exc, ast.Name) and exc.id in BANNED_RAISES:
                    found.append((name, node.lineno, exc.id))
    return [f"{name} line {line}: raise {exc}" for name, line, exc in sorted(found)]


def problems(root: Path) -> dict[str, list[str]]:
    edges, lazy_external = import_edges(root)
    return {
        "upward": [str(e) for e in upward_edges(edges)],
        "cycles": [" <-> ".join(c) for c in cycles(edges)],
        "function_level": [str(e) for e in function_level(edges, lazy_external)],
    }


def test_every_module_has_a_layer():
    for name in module_names(PACKAGE):
        assert layer(name)[0] != "mgn" or name == "mgn", (
            f"{name} is in no layer of LAYERS: put it into an existing package, or add the new"
            " package to LAYERS and to the table of docs/architecture.md"
        )


def test_imports_go_downward_only():
    bad = problems(PACKAGE)["upward"]
    assert not bad, (
        "imports of a higher layer or a sibling package (docs/architecture.md: move the code to the"
        " layer that owns it, or pass the object down as an argument):\n" + "\n".join(bad)
    )


def test_no_import_cycles():
    bad = problems(PACKAGE)["cycles"]
    assert not bad, "import cycles:\n" + "\n".join(bad)


def test_imports_at_module_level():
    bad = problems(PACKAGE)["function_level"]
    assert not bad, (
        "imports inside functions (move them to the top of the module; only the optional heavy"
        " dependencies of LAZY_IMPORTS may be imported late):\n" + "\n".join(bad)
    )


def test_raises_use_mgn_errors():
    bad = plain_raises(PACKAGE)
    assert not bad, "raise an mgn.errors class instead of:\n" + "\n".join(bad)


@pytest.fixture
def package_copy(tmp_path: Path) -> Path:
    copy = tmp_path / "mgn"
    shutil.copytree(PACKAGE, copy, ignore=shutil.ignore_patterns("*.so", "__pycache__"))
    return copy


def test_the_checks_find_an_added_upward_import(package_copy: Path):
    assert problems(package_copy) == {"upward": [], "cycles": [], "function_level": []}
    geometry = package_copy / "geometry" / "mesh.py"
    geometry.write_text(geometry.read_text() + "\nfrom mgn.io.dataset import Dataset\n")
    found = problems(package_copy)
    assert found["upward"] == [
        f"mgn.geometry.mesh -> mgn.io.dataset (line {len(geometry.read_text().splitlines())}, "
        "at module level)"
    ]
    # io.dataset imports geometry.mesh (indirectly or directly) only if there is a path back.
    assert all("mgn.geometry.mesh" in c for c in found["cycles"])


def test_the_checks_find_a_sibling_import_and_a_cycle(package_copy: Path):
    labels = package_copy / "pj" / "labels.py"
    labels.write_text(labels.read_text() + "\nimport mgn.suction.seal\n")
    seal = package_copy / "suction" / "seal.py"
    seal.write_text(seal.read_text() + "\nimport mgn.pj.labels\n")
    found = problems(package_copy)
    assert len(found["upward"]) == 2
    assert {e.split(" ")[0] for e in found["upward"]} == {"mgn.pj.labels", "mgn.suction.seal"}
    assert any(
        {"mgn.pj.labels", "mgn.suction.seal"} <= set(c.split(" <-> ")) for c in found["cycles"]
    )


def test_the_raise_check_finds_a_plain_value_error(package_copy: Path):
    assert plain_raises(package_copy) == []
    tote = package_copy / "objects" / "tote.py"
    text = tote.read_text()
    tote.write_text(
        text + "\n\ndef _bad(x):\n    if x:\n        raise ValueError('x')\n    raise TypeError\n"
    )
    n = len(text.splitlines())
    assert plain_raises(package_copy) == [
        f"mgn.objects.tote line {n + 5}: raise ValueError",
        f"mgn.objects.tote line {n + 6}: raise TypeError",
    ]


def test_the_checks_find_a_function_level_import(package_copy: Path):
    tote = package_copy / "objects" / "tote.py"
    tote.write_text(
        tote.read_text() + "\n\ndef _late():\n    import json\n    from mgn.errors import IoError\n"
        "    import scipy.spatial\n\n    return json, IoError, scipy\n"
    )
    found = problems(package_copy)
    assert found["upward"] == []
    assert found["cycles"] == []
    assert [e.split(" (")[0] for e in found["function_level"]] == [
        "mgn.objects.tote -> mgn.errors",
        "mgn.objects.tote -> json",
    ]


# ----------------------------------------------------------------------------- C++ detail headers

CPP_SRC = PACKAGE.parents[1] / "cpp" / "src"
_DETAIL_INCLUDE = re.compile(r'^\s*#\s*include\s+"([a-z_]+)/detail/[^"]+"', re.MULTILINE)


def _foreign_detail_includes(root: Path) -> list[str]:
    """``file: include`` for every include of ``<module>/detail/...`` from outside ``<module>``
    (a file's module is its first folder under ``root``)."""
    found = []
    for path in sorted(root.rglob("*")):
        if path.suffix not in {".cpp", ".hpp", ".h"}:
            continue
        own = path.relative_to(root).parts[0]
        for match in _DETAIL_INCLUDE.finditer(path.read_text()):
            if match.group(1) != own:
                found.append(f"{path.relative_to(root)}: {match.group(0).strip()}")
    return found


def test_no_cpp_module_includes_another_modules_detail_header() -> None:
    """A header in ``cpp/src/<module>/detail/`` is that module's own; what a module offers the
    library's other modules sits directly in ``cpp/src/<module>/`` (docs/architecture.md)."""
    assert CPP_SRC.is_dir()
    assert _foreign_detail_includes(CPP_SRC) == []


def test_the_detail_check_finds_a_foreign_include(tmp_path: Path) -> None:
    (tmp_path / "render").mkdir()
    (tmp_path / "render" / "a.cpp").write_text(
        '#include "render/detail/own.hpp"\n#include "raytrace/detail/x.hpp"\n'
    )
    assert _foreign_detail_includes(tmp_path) == ['render/a.cpp: #include "raytrace/detail/x.hpp"']
