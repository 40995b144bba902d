"""The committed type stubs of the compiled core cover every public name (scripts/gen-stubs.sh)."""

import ast
from pathlib import Path

import mgn
from mgn import _core

STUB = Path(mgn.__file__).with_name("_core.pyi")


def test_stub_declares_every_public_name_and_method():
    tree = ast.parse(STUB.read_text())
    declared = {n.name for n in tree.body if isinstance(n, (ast.ClassDef, ast.FunctionDef))} | {
        n.target.id for n in tree.body if isinstance(n, ast.AnnAssign)
    }
    public = {n for n in dir(_core) if not n.startswith("_")}
    assert public - declared == set(), "run scripts/gen-stubs.sh"
    for cls in (n for n in tree.body if isinstance(n, ast.ClassDef)):
        members = {m.name for m in cls.body if isinstance(m, ast.FunctionDef)} | {
            m.target.id for m in cls.body if isinstance(m, ast.AnnAssign)
        }
        real = {m for m in vars(getattr(_core, cls.name)) if not m.startswith("_")}
        assert real - members == set(), f"{cls.name}: run scripts/gen-stubs.sh"


def test_package_is_marked_typed():
    assert STUB.with_name("py.typed").is_file()
