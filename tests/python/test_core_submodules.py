"""The compiled core ``mgn._core`` has one submodule per C++ module of cpp/include/mgn/ that is
bound (``mgn._core.geometry``, ...), and each bound name lives in the submodule of the C++ module
whose ``bindings/bind_<module>*.cpp`` binds it (the source text is the independent truth)."""

from __future__ import annotations

import pickle
import re
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import mgn
from mgn import _core

ROOT = Path(__file__).resolve().parents[2]
BINDINGS = ROOT / "bindings"
MODULES = ROOT / "cpp" / "include" / "mgn"

CLASS = re.compile(r"py::(?:class_|enum_)<[^;]*?>\(\s*m,\s*\"(\w+)\"")
FUNCTION = re.compile(r"\bm\.def\(\s*\"(\w+)\"")
ATTRIBUTE = re.compile(r"\bm\.attr\(\"(\w+)\"\)")
EXCEPTION = re.compile(r"\bmake_type\(m,\s*\"(\w+)\"")


def _submodules() -> dict[str, ModuleType]:
    return {n: m for n, m in vars(_core).items() if isinstance(m, ModuleType)}


def bound_names(text: str) -> set[str]:
    """Names a binding source defines on its module ``m``."""
    found: set[str] = set()
    for pattern in (CLASS, FUNCTION, ATTRIBUTE, EXCEPTION):
        found |= {n for n in pattern.findall(text) if not n.startswith("_")}
    return found


def _binding_files(module: str) -> list[Path]:
    files = sorted(BINDINGS.glob(f"bind_{module}.cpp")) + sorted(
        BINDINGS.glob(f"bind_{module}_*.cpp")
    )
    return files + ([BINDINGS / "exceptions.cpp"] if module == "core" else [])


def test_the_submodules_are_the_bound_cpp_modules():
    bound = {d.name for d in MODULES.iterdir() if d.is_dir() and _binding_files(d.name)}
    assert {"core", "geometry", "raytrace", "collision", "grasp", "render", "scene"} <= bound
    assert set(_submodules()) == bound
    for f in BINDINGS.glob("bind_*.cpp"):
        module = f.stem.removeprefix("bind_").split("_")[0]
        assert (MODULES / module).is_dir(), f"{f.name} binds no module of cpp/include/mgn"


def test_each_name_is_in_the_submodule_of_the_file_that_binds_it():
    total = 0
    for name, sub in _submodules().items():
        source = set().union(*(bound_names(f.read_text()) for f in _binding_files(name)))
        runtime = {n for n in dir(sub) if not n.startswith("_")}
        assert runtime == source, f"mgn._core.{name}: {sorted(runtime ^ source)}"
        total += len(runtime)
    assert total >= 100


def test_the_binding_parser_reads_classes_functions_and_attributes():
    text = """
  py::class_<Foo, std::shared_ptr<Foo>>(
      m, "Foo", "doc")
      .def("method", &Foo::method);
  py::enum_<Kind>(m, "Kind");
  m.def(
      "make_foo", &make_foo);
  m.def("bar", &bar);
  m.attr("LIMIT") = 3;
  m.attr("__doc__") = "private";
  g_invalid = make_type(m, "InvalidThing", "doc", PyExc_ValueError);
"""
    assert bound_names(text) == {"Foo", "Kind", "make_foo", "bar", "LIMIT", "InvalidThing"}


def test_the_package_holds_only_the_submodules_and_the_version():
    assert {n for n in dir(_core) if not n.startswith("__")} == set(_submodules())
    assert _core.__version__ == mgn.__version__


def test_classes_name_their_submodule():
    for name, sub in _submodules().items():
        assert sub.__name__ == f"mgn._core.{name}"
        assert sys.modules[sub.__name__] is sub
        for obj in vars(sub).values():
            if isinstance(obj, type):
                assert obj.__module__ == sub.__name__, obj


def test_core_errors_round_trip_through_pickle():
    err = pickle.loads(pickle.dumps(_core.core.InvalidArgumentError("bad radius")))
    assert type(err) is mgn.InvalidArgumentError
    assert isinstance(err, ValueError)
    assert str(err) == "bad radius"


def test_submodules_import_by_name_in_a_fresh_interpreter():
    code = (
        "import importlib; g = importlib.import_module('mgn._core.geometry'); "
        "from mgn._core.scene import DropOptions; "
        "print(g.make_box([1, 2, 3]).num_vertices > 0, DropOptions.__module__)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert out.stdout.split() == ["True", "mgn._core.scene"]


def test_a_package_without_its_compiled_core_says_so(tmp_path):
    """A source tree without the built extension (only the stub folder ``mgn/_core/``) fails
    on import with a message naming the missing core, not an obscure name error."""
    import shutil

    package = Path(__file__).resolve().parents[2] / "python" / "mgn"  # the source tree
    shutil.copytree(package, tmp_path / "mgn", ignore=shutil.ignore_patterns("_core*.so", "*.pyc"))
    out = subprocess.run(
        [sys.executable, "-c", "import mgn"],
        capture_output=True,
        text=True,
        check=False,
        cwd=tmp_path,
        env={"PYTHONPATH": str(tmp_path), "PATH": "/usr/bin:/bin"},
    )
    assert out.returncode != 0
    assert "compiled core (mgn/_core*.so) is missing" in out.stderr
