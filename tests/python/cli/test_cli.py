"""The `mgn` command line: help, listing, export, info, demo, one-line errors."""

import json
import subprocess
import sys

import pytest

from mgn.cli.main import main
from mgn.objects import builtin_objects


def run(*args):
    return subprocess.run(
        [sys.executable, "-m", "mgn", *args], capture_output=True, text=True, check=False
    )


@pytest.mark.parametrize("args", [[], ["objects"], ["info"], ["demo"]])
def test_help_everywhere(args):
    r = run(*args, "--help")
    assert r.returncode == 0
    assert "usage: mgn" in r.stdout


def test_objects_list_json(capsys):
    assert main(["objects", "list", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["name"] for r in rows] == [s.name for s in builtin_objects()]
    assert all(r["mass_g"] > 0 for r in rows)


def test_objects_export_only(tmp_path, capsys):
    assert main(["objects", "export", str(tmp_path), "--only", "mug", "12", "--quiet"]) == 0
    assert (tmp_path / "models" / "012" / "textured.obj").is_file()
    assert (tmp_path / "gripper.yaml").is_file()
    assert (tmp_path / "suction_cup.yaml").is_file()


def test_info_reports_json(data_dir, capsys):
    assert main(["info", str(data_dir / "cube.stl"), "--density", "500"]) == 0
    info = json.loads(capsys.readouterr().out)
    v, m = info["validation"], info["mass_properties"]
    assert v["is_watertight"]
    assert m["mass"] == pytest.approx(0.004, rel=1e-5)


def test_errors_are_one_line_without_traceback(data_dir):
    r = run("info", str(data_dir / "missing.obj"))
    assert r.returncode == 1
    assert r.stderr.strip().count("\n") == 0
    assert "missing.obj" in r.stderr
    assert "Traceback" not in r.stderr
    r = run("objects", "export", "/tmp/x", "--only", "no_such_object")
    assert r.returncode == 1
    assert "no_such_object" in r.stderr
    assert "Traceback" not in r.stderr
    r = run("--debug", "info", str(data_dir / "missing.obj"))
    assert r.returncode != 0
    assert "Traceback" in r.stderr


def test_demo_runs_and_all_checks_pass(tmp_path):
    r = run("demo", "--out", str(tmp_path))
    assert r.returncode == 0, r.stdout + r.stderr
    summary = json.loads((tmp_path / "smoke.json").read_text())
    assert summary["reloaded_ok"] == summary["num_objects"] == len(builtin_objects())
    assert summary["collision_errors"] == 0
    assert summary["collision_checks"] > 100
    from PIL import Image

    with Image.open(tmp_path / "gallery.png") as img:
        assert img.size[0] == 2 * img.size[1]
