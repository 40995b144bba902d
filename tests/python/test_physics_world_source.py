"""The Bullet fence of docs/architecture.md, checked on the C++ source.

1. ``physics::World`` (cpp/src/physics/world.cpp) is the one place that constructs Bullet's world
   and its parts (collision configuration, dispatcher, broadphase, constraint solver); the
   re-implemented parts in cpp/src/physics/bullet_ext derive from Bullet's classes and are
   exempt. Tests (tests/cpp) build worlds of their own to compare against Bullet's code.
2. Every header of cpp/src/physics/bullet_ext names the Bullet 3.24 functions it mirrors and
   includes the version check (bullet_ext/version.hpp).
3. No installed header (cpp/include) includes a Bullet header.

The test of the test plants a world built by hand in a copy of the tree and checks that it is
reported.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
WORLD_FILE = "cpp/src/physics/world.cpp"
EXT_DIR = "cpp/src/physics/bullet_ext"
BULLET_WORLD_PARTS = (
    "btDiscreteDynamicsWorld",
    "btCollisionDispatcher",
    "btDbvtBroadphase",
    "btDefaultCollisionConfiguration",
    "btSequentialImpulseConstraintSolver",
)
# A construction: `new T`, `make_unique<T>`, `T name` / `T name(`/`T name{`, `T(`, `T{`.
# References, pointers, scope (`T::`) and template arguments (`T>`) are uses, not constructions.
_PARTS = "|".join(BULLET_WORLD_PARTS)
_CONSTRUCT = re.compile(
    rf"(?:\bnew\s+|\bmake_(?:unique|shared)<\s*)({_PARTS})\b|\b({_PARTS})\b(?!\s*[&*:>.])"
)


def _code(text: str) -> str:
    """The C++ text without comments, string literals, preprocessor lines and forward
    declarations (``class T;``)."""
    text = re.sub(r"//[^\n]*", "", text)
    text = re.sub(r"\b(?:class|struct)\s+\w+\s*;", "", text)
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.DOTALL)
    text = re.sub(r'"(?:\\.|[^"\\])*"', '""', text)
    return "\n".join(line for line in text.split("\n") if not line.lstrip().startswith("#"))


def world_constructions(root: Path) -> list[str]:
    """'path:line: name' of every construction of a part of Bullet's world outside physics::World
    and bullet_ext, in cpp/src, cpp/apps and bindings."""
    found = []
    for top in ("cpp/src", "cpp/apps", "bindings"):
        for path in sorted((root / top).rglob("*")):
            if path.suffix not in (".cpp", ".hpp", ".h", ".cc"):
                continue
            rel = path.relative_to(root).as_posix()
            if rel == WORLD_FILE or rel.startswith(EXT_DIR + "/"):
                continue
            for n, line in enumerate(_code(path.read_text()).split("\n"), start=1):
                found += [
                    f"{rel}:{n}: {m.group(1) or m.group(2)}" for m in _CONSTRUCT.finditer(line)
                ]
    return found


def test_only_the_physics_world_builds_a_bullet_world():
    assert world_constructions(ROOT) == []


def test_the_physics_world_builds_each_part():
    code = _code((ROOT / WORLD_FILE).read_text())
    for part in ("btDefaultCollisionConfiguration", "btCollisionDispatcher", "btDbvtBroadphase"):
        assert re.search(rf"\b{part}\s+\w+;", code), part
    assert re.search(r"\bbtDiscreteDynamicsWorld\s+world;", code)


def test_every_bullet_ext_header_names_what_it_mirrors_and_checks_the_version():
    headers = sorted((ROOT / EXT_DIR).glob("*.hpp"))
    names = {h.name for h in headers}
    assert {"hull_support.hpp", "one_sided_solver.hpp", "separated_pair_skip.hpp"} <= names
    for h in headers:
        if h.name == "version.hpp":
            assert "BT_BULLET_VERSION != MGN_BULLET_EXT_VERSION" in h.read_text()
            continue
        text = h.read_text()
        assert re.search(r"// Mirrors Bullet 3\.24: .*\bbt[A-Z]\w*::\w+", text), h.name
        assert '#include "physics/bullet_ext/version.hpp"' in text, h.name
    for source in sorted((ROOT / EXT_DIR).glob("*.cpp")):  # each .cpp has its header
        assert source.with_suffix(".hpp").name in names, source.name


def test_installed_headers_include_no_bullet_header():
    bullet = re.compile(
        r"#\s*include\s*[<\"](?:bt\w+\.h|LinearMath/|BulletCollision/|BulletDynamics/)"
    )
    offenders = [
        p.relative_to(ROOT).as_posix()
        for p in sorted((ROOT / "cpp/include").rglob("*.hpp"))
        if bullet.search(p.read_text())
    ]
    assert offenders == []


def test_the_check_finds_a_world_built_by_hand(tmp_path: Path):
    for top in ("cpp/src", "cpp/apps", "bindings"):
        shutil.copytree(ROOT / top, tmp_path / top)
    planted = tmp_path / "cpp/src/scene/planted.cpp"
    planted.write_text(
        "// btDiscreteDynamicsWorld world; in a comment is no construction\n"
        "class btDbvtBroadphase;\n"
        "void f(btCollisionDispatcher& d, btDbvtBroadphase* b) {\n"
        "  btDefaultCollisionConfiguration config;\n"
        "  auto w = std::make_unique<btDiscreteDynamicsWorld>(&d, b, nullptr, &config);\n"
        "  auto* s = new btSequentialImpulseConstraintSolver;\n"
        "}\n"
    )
    assert world_constructions(tmp_path) == [
        "cpp/src/scene/planted.cpp:4: btDefaultCollisionConfiguration",
        "cpp/src/scene/planted.cpp:5: btDiscreteDynamicsWorld",
        "cpp/src/scene/planted.cpp:6: btSequentialImpulseConstraintSolver",
    ]
