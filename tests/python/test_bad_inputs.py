"""A corpus of constructed bad inputs (meshes, user-object files, configs, command lines), each
with its expected outcome: a clear error naming the input, a warning naming it, or a repair
stated in the output. Every case builds its own files into ``tmp_path`` (nothing downloaded) and
runs the ``mgn`` command line as a user would; one parametrised test checks them all."""

from __future__ import annotations

import contextlib
import io
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest
import yaml

from mgn.cli import main

#: Every object label off, one tiny view, a short drop: a generate run of about a second.
FAST = {
    "camera": {"views": [0], "resolution_scale": 0.05},
    "labels": {k: False for k in ("suction", "paralleljaw", "pj_physics", "layout",
                                  "scene_grasps")},
    "drop": {"max_time": 0.5},
}  # fmt: skip

CUBE_OBJ = """v -0.5 -0.5 -0.5
v 0.5 -0.5 -0.5
v 0.5 0.5 -0.5
v -0.5 0.5 -0.5
v -0.5 -0.5 0.5
v 0.5 -0.5 0.5
v 0.5 0.5 0.5
v -0.5 0.5 0.5
f 1 4 3
f 1 3 2
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 2 3 7
f 2 7 6
f 3 4 8
f 3 8 7
f 4 1 5
f 4 5 8
"""


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def write_yaml(path: Path, data: object) -> Path:
    return write(path, yaml.safe_dump(data, sort_keys=False))


def cube_objects(tmp: Path, name: str = "part", **extra: object) -> Path:
    """A user-object YAML with one 5 cm cube (the OBJ above, scale 0.05)."""
    write(tmp / "cube.obj", CUBE_OBJ)
    entry = {"name": name, "mesh": "cube.obj", "scale": 0.05, "density": 500, "friction": 0.5}
    return write_yaml(tmp / "objs.yaml", {"objects": [{**entry, **extra}]})


def fast_config(tmp: Path, **sections: dict) -> Path:
    data = {k: dict(v) for k, v in FAST.items()}
    for key, value in sections.items():
        data[key] = {**data.get(key, {}), **value}
    return write_yaml(tmp / "cfg.yaml", data)


@dataclass(frozen=True)
class Case:
    """One bad input. ``build`` writes the files into the folder it gets and returns the
    ``mgn`` arguments; the run must exit with ``rc`` and print text matching ``expect``
    (stdout and stderr together); ``check`` looks at the files afterwards."""

    id: str
    kind: str  # "error" | "warning" | "repaired"
    build: Callable[[Path], list[str]]
    rc: int
    expect: str
    check: Callable[[Path], None] | None = None


# ------------------------------------------------------------------ names, keys, resume, scale


def _bad_name(name: object) -> Callable[[Path], list[str]]:
    def build(tmp: Path) -> list[str]:
        cube_objects(tmp, name=name)  # type: ignore[arg-type]
        return ["objects", "list", "--add", str(tmp / "objs.yaml")]

    return build


def _bad_cli_name(tmp: Path) -> list[str]:
    write(tmp / "cube.obj", CUBE_OBJ)
    return ["objects", "add", str(tmp / "cube.obj"), "--to", str(tmp / "o.yaml"),
            "--name", "a,b"]  # fmt: skip


def _duplicate_config_key(tmp: Path) -> list[str]:
    write(tmp / "cfg.yaml", "objects:\n  count: 3\n  copies: [1, 2]\n  count: 30\n")
    return ["config", "check", str(tmp / "cfg.yaml")]


def _duplicate_object_key(tmp: Path) -> list[str]:
    write(tmp / "cube.obj", CUBE_OBJ)
    write(tmp / "objs.yaml", "objects:\n  - name: part\n    mesh: cube.obj\n    density: 500\n"
          "    friction: 0.5\n    density: 5000\n")  # fmt: skip
    return ["objects", "list", "--add", str(tmp / "objs.yaml")]


def _resume_other_config(tmp: Path) -> list[str]:
    cfg = fast_config(tmp)
    args = ["generate", "--out", str(tmp / "ds"), "--scenes", "1", "--objects", "box_tea",
            "--quiet"]  # fmt: skip
    assert main([*args, "--config", str(cfg)]) == 0
    fast_config(tmp, drop={"max_time": 0.6})
    return [*args, "--config", str(cfg), "--resume"]


def _nonuniform_yaml_scale(tmp: Path) -> list[str]:
    cube_objects(tmp, scale=[0.05, 0.05, 0.1])
    return ["objects", "list", "--add", str(tmp / "objs.yaml")]


def _nonuniform_cli_scale(tmp: Path) -> list[str]:
    write(tmp / "cube.obj", CUBE_OBJ)
    return ["objects", "add", str(tmp / "cube.obj"), "--to", str(tmp / "o.yaml"),
            "--scale", "0.05,0.05,0.1"]  # fmt: skip


# fmt: off
CASES = [
    Case("name-with-space", "error", _bad_name("My Part!"), 1, r"objs\.yaml: objects\[0\]: "
         r"key 'name': object name 'My Part!' is not allowed"),
    Case("name-with-comma", "error", _bad_name("a,b"), 1, r"'a,b' is not allowed \(name lists "
         "on the command line are split at commas"),
    Case("name-a-number", "error", _bad_name(12), 1, r"'12' is not allowed \(a number names a "
         r"category id: it would shadow category 12\)"),
    Case("cli-name-with-comma", "error", _bad_cli_name, 1, r"--name: object name 'a,b' is not "
         "allowed"),
    Case("duplicate-config-key", "error", _duplicate_config_key, 1, r"cfg\.yaml' is not valid "
         r"YAML.*found the key 'count' twice \(first on line 2, again on line 4\)"),
    Case("duplicate-object-key", "error", _duplicate_object_key, 1, r"found the key 'density' "
         r"twice \(first on line 4, again on line 6\)"),
    Case("resume-other-config", "error", _resume_other_config, 1, r"--resume: the config "
         r"differs .* in 1 key\(s\): drop\.max_time: recorded 0\.5, now 0\.6"),
    Case("nonuniform-yaml-scale", "error", _nonuniform_yaml_scale, 1, r"key 'scale': only a "
         r"uniform scale is supported .* got \[0\.05, 0\.05, 0\.1\]"),
    Case("nonuniform-cli-scale", "error", _nonuniform_cli_scale, 2, r"argument --scale: only a "
         "uniform scale is supported"),
]
# fmt: on


def run_cli(argv: list[str]) -> tuple[int, str]:
    """Exit code and stdout + stderr of ``mgn argv`` (argparse's exit included)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main(argv)
        except SystemExit as e:
            rc = int(e.code or 0)
    return rc, out.getvalue() + err.getvalue()


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input_gets_its_outcome(case: Case, tmp_path: Path) -> None:
    argv = case.build(tmp_path)
    rc, text = run_cli(argv)
    assert re.search(case.expect, text, re.S), f"{case.kind} {case.expect!r} not in:\n{text}"
    assert rc == case.rc, text
    if case.check is not None:
        case.check(tmp_path)
