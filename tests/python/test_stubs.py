"""The committed type stubs of the compiled core, the package python/mgn/_core/ with one
``<module>.pyi`` per submodule ``mgn._core.<module>`` (scripts/gen-stubs.sh), declare every
public name and method with the parameters the compiled core reports."""

import ast
import os
import re
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import pytest

import mgn
from mgn import _core

STUBS = Path(mgn.__file__).with_name("_core")
ROOT = Path(__file__).resolve().parents[2]


def _submodules() -> dict[str, ModuleType]:
    return {n: m for n, m in vars(_core).items() if isinstance(m, ModuleType)}


def _stub(name: str) -> ast.Module:
    return ast.parse((STUBS / f"{name}.pyi").read_text())


def _declared(body: list[ast.stmt]) -> set[str]:
    return {n.name for n in body if isinstance(n, (ast.ClassDef, ast.FunctionDef))} | {
        n.target.id for n in body if isinstance(n, ast.AnnAssign) and isinstance(n.target, ast.Name)
    }


def test_one_stub_per_submodule():
    assert len(_submodules()) >= 7
    assert {p.name for p in STUBS.glob("*.pyi")} == {"__init__.pyi"} | {
        f"{n}.pyi" for n in _submodules()
    }, "run scripts/gen-stubs.sh"


def test_package_stub_declares_the_submodules_and_the_version():
    tree = _stub("__init__")
    imported = {
        a.asname or a.name for n in tree.body if isinstance(n, ast.ImportFrom) for a in n.names
    }
    public = {n for n in dir(_core) if not n.startswith("_")} | {"__version__"}
    assert public - (imported | _declared(tree.body)) == set(), "run scripts/gen-stubs.sh"


def test_stub_declares_every_public_name_and_method():
    for sub_name, sub in _submodules().items():
        tree = _stub(sub_name)
        public = {n for n in dir(sub) if not n.startswith("_")}
        assert public - _declared(tree.body) == set(), f"{sub_name}: run scripts/gen-stubs.sh"
        for cls in (n for n in tree.body if isinstance(n, ast.ClassDef)):
            members = {m.name for m in cls.body if isinstance(m, ast.FunctionDef)} | {
                m.target.id
                for m in cls.body
                if isinstance(m, ast.AnnAssign) and isinstance(m.target, ast.Name)
            }
            real = {m for m in vars(getattr(sub, cls.name)) if not m.startswith("_")}
            assert real - members == set(), f"{sub_name}.{cls.name}: run scripts/gen-stubs.sh"


def test_committed_stubs_equal_regenerated_ones(tmp_path):
    """scripts/gen-stubs.sh run on the compiled core writes exactly the committed files (the
    generator and ruff are pinned in the dev extra)."""
    pytest.importorskip("pybind11_stubgen")
    pytest.importorskip("ruff")
    out = tmp_path / "_core"
    env = {**os.environ, "PYTHON": sys.executable}
    env["PYTHONPATH"] = os.pathsep.join([str(STUBS.parents[1]), env.get("PYTHONPATH", "")])
    subprocess.run(
        ["bash", str(ROOT / "scripts" / "gen-stubs.sh"), str(out)],
        env=env,
        check=True,
        capture_output=True,
        timeout=300,
    )
    committed = {p.name: p.read_text() for p in STUBS.glob("*.pyi")}
    regenerated = {p.name: p.read_text() for p in out.glob("*.pyi")}
    assert sorted(regenerated) == sorted(committed), "run scripts/gen-stubs.sh"
    stale = [name for name, text in committed.items() if regenerated[name] != text]
    assert not stale, f"stale stubs {stale}: run scripts/gen-stubs.sh"


def test_package_is_marked_typed():
    assert STUBS.with_name("py.typed").is_file()


def _split_params(text: str) -> list[str]:
    """Top-level comma split of a parameter list (brackets and quotes nest)."""
    parts, depth, cur, quote = [], 0, "", None
    for ch in text:
        if quote:
            quote = None if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append(cur.strip())
            cur = ""
            continue
        cur += ch
    if cur.strip():
        parts.append(cur.strip())
    return parts


def _runtime_signatures(obj: object, name: str) -> set[tuple[tuple[str, bool], ...]]:
    """(parameter name, has default) per overload, from pybind11's docstring signature lines."""
    found = set()
    for line in (getattr(obj, "__doc__", None) or "").splitlines():
        m = re.match(rf"^(?:\d+\. )?{re.escape(name)}\((.*)\) -> ", line)
        if m is None:
            continue
        params = []
        for p in _split_params(m.group(1)):
            pname = p.split(":", 1)[0].split("=", 1)[0].strip()
            if pname in ("*", "/") or pname.startswith("*"):
                continue
            params.append((pname, "=" in p.split(":", 1)[-1] or "=" in p))
        found.add(tuple(params))
    return found


def _stub_signatures(fn: ast.FunctionDef) -> tuple[tuple[str, bool], ...]:
    args = fn.args
    positional = args.posonlyargs + args.args
    first_default = len(positional) - len(args.defaults)
    params = [(a.arg, i >= first_default) for i, a in enumerate(positional)]
    params += [
        (a.arg, d is not None) for a, d in zip(args.kwonlyargs, args.kw_defaults, strict=True)
    ]
    return tuple(params)


def _stub_functions(body: list[ast.stmt]) -> dict[str, set[tuple[tuple[str, bool], ...]]]:
    """Parameters per overload of every function of a stub body (properties left out)."""
    out: dict[str, set[tuple[tuple[str, bool], ...]]] = {}
    for node in body:
        if isinstance(node, ast.FunctionDef):
            decorators = [ast.unparse(d) for d in node.decorator_list]
            if any("property" in d or ".setter" in d for d in decorators):
                continue
            out.setdefault(node.name, set()).add(_stub_signatures(node))
    return out


def test_stub_signatures_match_the_compiled_core():
    """Every function and method of the stubs has the parameters (names, order, which have a
    default) that the compiled core reports, overload by overload."""
    checked = 0
    mismatches = []
    for sub_name, sub in _submodules().items():
        tree = _stub(sub_name)
        targets = [(sub, tree.body, f"{sub_name}.")]
        targets += [
            (getattr(sub, n.name), n.body, f"{sub_name}.{n.name}.")
            for n in tree.body
            if isinstance(n, ast.ClassDef) and hasattr(sub, n.name)
        ]
        for owner, body, prefix in targets:
            for name, stub_sigs in _stub_functions(body).items():
                runtime = _runtime_signatures(getattr(owner, name, None), name)
                checked += 1
                if runtime != stub_sigs:
                    mismatches.append(
                        f"{prefix}{name}: stub {sorted(stub_sigs)}, core {sorted(runtime)}"
                    )
    assert checked >= 90, f"only {checked} functions and methods were compared"
    assert not mismatches, "run scripts/gen-stubs.sh:\n" + "\n".join(mismatches)


def test_the_signature_check_finds_a_renamed_parameter():
    sigs = _runtime_signatures(_core.geometry.make_box, "make_box")
    assert sigs == {(("extents", False),)}
    fn = ast.parse("def make_box(size: int) -> None: ...").body[0]
    assert isinstance(fn, ast.FunctionDef)
    assert {_stub_signatures(fn)} != sigs


#: Functions of the compiled core that still return a plain dict, each with the reason. Every
#: other function returns a bound class (docs/architecture.md, "The typed boundary").
DICT_RETURNS = {
    "ClassificationMetrics.to_dict": "the JSON form of a bound result class",
}


def _dict_returning(body: list[ast.stmt], prefix: str = "") -> set[str]:
    found: set[str] = set()
    for node in body:
        if isinstance(node, ast.ClassDef):
            found |= _dict_returning(node.body, node.name + ".")
        elif isinstance(node, ast.FunctionDef) and node.returns is not None:
            ret = ast.unparse(node.returns)
            if ret == "dict" or ret.startswith(("dict[", "typing.Dict")):
                found.add(prefix + node.name)
    return found


def test_results_cross_the_boundary_as_classes_not_dicts():
    found: set[str] = set()
    for sub_name in _submodules():
        found |= _dict_returning(_stub(sub_name).body)
    assert found - set(DICT_RETURNS) == set(), "bind a result class instead of returning a dict"
    assert set(DICT_RETURNS) - found == set(), "converted: remove it from DICT_RETURNS"


def test_the_dict_check_finds_a_dict_returning_function():
    stub = "class A:\n    def f(self) -> dict: ...\ndef g() -> dict[str, int]: ...\n"
    assert _dict_returning(ast.parse(stub).body) == {"A.f", "g"}
