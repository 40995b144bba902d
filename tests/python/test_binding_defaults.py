"""Defaults of the typed boundary live in the C++ headers only (docs/architecture.md, "The typed
boundary").

An option of the core is a field of a C++ struct with its default written once, in the header
(``struct SealOptions { int num_trials = 10; ... }``). A binding either takes the bound struct
(``py::arg_v("options", SealOptions{}, "SealOptions()")``) or reads the default from it
(``py::arg("tnear") = CastOptions{}.tnear``); it never writes the number again. This test reads
every struct of ``cpp/include/mgn`` and every ``py::arg("name") = <default>`` of ``bindings/``,
and fails when a default is a numeric literal for a name that is a field of a struct with a
default, i.e. a second copy that could drift from the header.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
HEADERS = ROOT / "cpp" / "include" / "mgn"
BINDINGS = ROOT / "bindings"

#: Binding arguments allowed a literal default although a struct has a field of that name, each
#: with the reason: (binding file, argument name) -> reason.
LITERAL_DEFAULTS: dict[tuple[str, str], str] = {
    ("bind_grasp_calibration.cpp", "num_threads"): (
        "predict_experiments' own parameter (mgn/grasp/calibration.hpp), no options struct"
    ),
}

_COMMENT = re.compile(r"//[^\n]*|/\*.*?\*/", re.DOTALL)
_STRUCT = re.compile(r"\bstruct\s+(\w+)\s*(?::[^{;]*)?\{")
_FIELD = re.compile(r"^[\w:<>,\s*&]*?\b(\w+)\s*(?:=\s*(.+)|\{(.*)\})$", re.DOTALL)
_FUNCTION_BODY = re.compile(r"\)[\w\s]*\{")
_NOT_FIELDS = ("using ", "friend ", "static ", "struct ", "enum ", "class ", "template")
_ARG = re.compile(r'py::arg\("(\w+)"\)\s*=\s*')
_NUMERIC = re.compile(r"^[-+*/().\s\deEfFuUlL]*(?:M_PI)?[-+*/().\s\deEfFuUlL]*$")


def _body(text: str, start: int) -> tuple[str, int]:
    """The text between the brace at ``start - 1`` and its match, and the index after it."""
    depth, i = 1, start
    while depth:
        depth += {"{": 1, "}": -1}.get(text[i], 0)
        i += 1
    return text[start : i - 1], i


def struct_defaults(text: str) -> dict[str, dict[str, str]]:
    """struct name -> {field: default text} for the members declared with an initializer at the
    top level of the struct (nested structs are read on their own)."""
    text = _COMMENT.sub("", text)
    out: dict[str, dict[str, str]] = {}
    for m in _STRUCT.finditer(text):
        body, _ = _body(text, m.end())
        fields: dict[str, str] = {}
        depth, stmt = 0, ""
        for ch in body:
            if ch == ";" and depth == 0:
                s = " ".join(stmt.split())
                stmt = ""
                if "(" in s.split("=", 1)[0].split("{", 1)[0] or s.startswith(_NOT_FIELDS):
                    continue  # a function, an alias, a static member or a nested type
                f = _FIELD.match(s)
                if f and (f.group(2) or f.group(3)) is not None:
                    fields[f.group(1)] = (f.group(2) or f.group(3) or "").strip()
                continue
            depth += {"{": 1, "(": 1, "}": -1, ")": -1}.get(ch, 0)
            stmt += ch
            if depth == 0 and ch == "}" and _FUNCTION_BODY.search(stmt):
                stmt = ""  # an inline function body ends without a ';'

        if fields:
            out.setdefault(m.group(1), {}).update(fields)
    return out


def _default_expression(text: str, start: int) -> str:
    """The default argument beginning at ``start``: up to the next top-level ``,`` or ``)``."""
    depth, i = 0, start
    while i < len(text):
        ch = text[i]
        if ch in "([{":
            depth += 1
        elif ch in ")]}":
            if depth == 0:
                break
            depth -= 1
        elif ch == "," and depth == 0:
            break
        i += 1
    return " ".join(text[start:i].split())


def literal_defaults(text: str) -> list[tuple[str, int, str]]:
    """(argument name, line, default) of every ``py::arg("name") = <numeric literal>``."""
    text = _COMMENT.sub(lambda m: "\n" * m.group(0).count("\n"), text)
    found = []
    for m in _ARG.finditer(text):
        expr = _default_expression(text, m.end())
        if _NUMERIC.match(expr) and re.search(r"\d|M_PI", expr):
            found.append((m.group(1), text.count("\n", 0, m.start()) + 1, expr))
    return found


def duplicated_defaults(headers: dict[str, str], bindings: dict[str, str]) -> list[str]:
    """Binding literal defaults whose name is a field with a default in a header struct."""
    owners: dict[str, list[str]] = {}
    for text in headers.values():
        for struct, fields in struct_defaults(text).items():
            for name, value in fields.items():
                owners.setdefault(name, []).append(f"{struct}.{name} = {value}")
    bad = []
    for file, text in sorted(bindings.items()):
        for name, line, expr in literal_defaults(text):
            if name in owners and (file, name) not in LITERAL_DEFAULTS:
                bad.append(
                    f'{file} line {line}: py::arg("{name}") = {expr} repeats '
                    f"{', '.join(sorted(owners[name]))}"
                )
    return bad


def _read(folder: Path, pattern: str) -> dict[str, str]:
    return {p.name: p.read_text() for p in sorted(folder.rglob(pattern))}


def test_binding_defaults_are_not_written_twice():
    headers = _read(HEADERS, "*.hpp")
    structs = {s for text in headers.values() for s in struct_defaults(text)}
    # The reader finds the option structs it guards (a broken parser would find nothing).
    assert {"SealOptions", "AntipodalOptions", "RenderOptions", "SceneGraspOptions"} <= structs
    assert {"DropOptions", "PathTraceOptions", "CastOptions", "PjWrenchOptions"} <= structs
    bad = duplicated_defaults(headers, _read(BINDINGS, "*.cpp"))
    assert not bad, (
        "bind the options struct, or take the default from it (Struct{}.field):\n" + "\n".join(bad)
    )


def test_allowed_literal_defaults_are_still_used():
    bindings = _read(BINDINGS, "*.cpp")
    for (file, name), reason in LITERAL_DEFAULTS.items():
        assert any(n == name for n, _, _ in literal_defaults(bindings[file])), (
            f"{file}: {name} has no literal default any more; remove it from LITERAL_DEFAULTS "
            f"({reason})"
        )


def test_the_default_check_finds_a_repeated_default():
    header = """
    /// Options.
    struct WidgetOptions {
      int probes = 5;               ///< probes
      double tilt = M_PI / 16.0;    ///< rad
      std::vector<double> offsets = {0.0, 0.1};
      Vec3d gravity{0.0, 0.0, -1.0};
      void validate() const;
      int count() const { return probes; }
    };
    """
    assert struct_defaults(header) == {
        "WidgetOptions": {
            "probes": "5",
            "tilt": "M_PI / 16.0",
            "offsets": "{0.0, 0.1}",
            "gravity": "0.0, 0.0, -1.0",
        }
    }
    binding = """
      m.def("f", &f, py::arg("points"), py::arg("probes") = 5,
            py::arg("tilt") = M_PI / 16.0, py::arg("name") = "x", py::arg("other") = 3,
            py::arg("seed") = WidgetOptions{}.probes,  // from the struct: fine
            py::arg_v("options", WidgetOptions{}, "WidgetOptions()"));
    """
    assert literal_defaults(binding) == [
        ("probes", 2, "5"),
        ("tilt", 3, "M_PI / 16.0"),
        ("other", 3, "3"),
    ]
    bad = duplicated_defaults({"w.hpp": header}, {"bind_w.cpp": binding})
    assert [b.split(" repeats")[0] for b in bad] == [
        'bind_w.cpp line 2: py::arg("probes") = 5',
        'bind_w.cpp line 3: py::arg("tilt") = M_PI / 16.0',
    ]
