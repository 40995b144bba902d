#!/usr/bin/env python3
"""Rewrites references to names of the compiled core onto its submodules.

``_core.Mesh`` / ``mgn._core.Mesh`` -> ``_core.geometry.Mesh``, and
``from mgn._core import A, B`` -> ``from mgn._core.<module> import A`` (one import per
submodule). Which submodule holds a name is read from the committed stubs
``python/mgn/_core/<module>.pyi`` (regenerate them first: scripts/gen-stubs.sh). Idempotent:
names already under a submodule are left alone. Usage, from the repository root:

    python scripts/codemod_core_submodules.py [paths ...]   # default: the trees listed below

then ``ruff check --fix --select I`` and ``ruff format`` on the files it lists.
"""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STUBS = ROOT / "python" / "mgn" / "_core"
TREES = ["python", "tests", "benchmarks", "scripts", "docs", "bindings", "README.md"]
SUFFIXES = {".py", ".md", ".cpp", ".hpp", ".sh", ".toml"}
IMPORT = re.compile(r"from mgn\._core import (\([^)]*\)|[^\n]*)")
ATTRIBUTE = re.compile(r"\b_core\.([A-Za-z_]\w*)\b")


def name_map() -> dict[str, str]:
    """Public name -> submodule, from the top-level definitions of every submodule stub."""
    owner: dict[str, str] = {}
    for stub in sorted(STUBS.glob("*.pyi")):
        if stub.stem == "__init__":
            continue
        for node in ast.parse(stub.read_text()).body:
            if isinstance(node, ast.ClassDef | ast.FunctionDef):
                names = [node.name]
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
                names = [node.target.id]
            elif isinstance(node, ast.Assign):
                names = [t.id for t in node.targets if isinstance(t, ast.Name)]
            else:
                continue
            for name in names:
                if name.startswith("_"):
                    continue
                if owner.get(name, stub.stem) != stub.stem:
                    sys.exit(f"{name} is defined in {owner[name]}.pyi and {stub.name}")
                owner[name] = stub.stem
    if not owner:
        sys.exit(f"no stubs under {STUBS}: run scripts/gen-stubs.sh first")
    clash = set(owner) & submodules()
    if clash:
        sys.exit(f"names that are also submodules would be rewritten twice: {sorted(clash)}")
    return owner


def rewrite_import(match: re.Match[str], owner: dict[str, str], unknown: set[str]) -> str:
    body = match.group(1).strip().strip("()")
    groups: dict[str, list[str]] = {}
    for item in (p.strip() for p in body.replace("\n", " ").split(",")):
        if not item:
            continue
        name = item.split(" as ")[0].strip()
        module = owner.get(name, "")
        if not module and not name.startswith("__") and name not in submodules():
            unknown.add(name)
        groups.setdefault(module, []).append(item)
    lines = []
    for module, items in groups.items():
        where = f"mgn._core.{module}" if module else "mgn._core"
        lines.append(f"from {where} import {', '.join(items)}")
    indent = re.match(r"[ \t]*", match.string[match.string.rfind("\n", 0, match.start()) + 1 :])
    return ("\n" + (indent.group(0) if indent else "")).join(lines)


def submodules() -> set[str]:
    return {p.stem for p in STUBS.glob("*.pyi") if p.stem != "__init__"}


def rewrite(text: str, owner: dict[str, str], unknown: set[str]) -> str:
    text = IMPORT.sub(lambda m: rewrite_import(m, owner, unknown), text)
    return ATTRIBUTE.sub(
        lambda m: f"_core.{owner[m.group(1)]}.{m.group(1)}" if m.group(1) in owner else m.group(0),
        text,
    )


def files(paths: list[str]) -> list[Path]:
    found: list[Path] = []
    for p in (ROOT / q for q in paths):
        candidates = [p] if p.is_file() else sorted(p.rglob("*"))
        found += [
            f
            for f in candidates
            if f.is_file()
            and f.suffix in SUFFIXES
            and STUBS not in f.parents
            and f != Path(__file__).resolve()
        ]
    return found


def main(argv: list[str]) -> int:
    owner = name_map()
    unknown: set[str] = set()
    for path in files(argv or TREES):
        text = path.read_text()
        new = rewrite(text, owner, unknown)
        if new != text:
            path.write_text(new)
            print(path.relative_to(ROOT))
    if unknown:
        print(
            "not in any submodule stub (regenerate the stubs?):", sorted(unknown), file=sys.stderr
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
