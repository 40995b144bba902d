"""User objects from mesh files plus YAML."""

import numpy as np
import pytest

import mgn
from mgn.cli.main import main
from mgn.io import read_model_folder
from mgn.objects import builtin_objects, load_objects_yaml


def write_yaml(tmp_path, text):
    path = tmp_path / "objects.yaml"
    path.write_text(text)
    return path


def test_two_user_objects_load_with_defaults(tmp_path, data_dir):
    path = write_yaml(
        tmp_path,
        f"""
objects:
  - name: red_cube
    mesh: {data_dir / "cube.obj"}
    density: 500
    friction: 0.6
  - name: big_cube
    mesh: {data_dir / "cube.stl"}
    scale: 5.0
    density: 1000
    friction: 0.5
    color: [0.1, 0.9, 0.1]
    keypoints: {{corner: [0.05, 0.05, 0.05], centre: [0, 0, 0]}}
    tags: [box]
""",
    )
    red, big = load_objects_yaml(path)
    n = len(builtin_objects())
    assert (red.category_id, big.category_id) == (n + 1, n + 2)
    assert red.material.texture is not None
    assert red.uvs is not None
    assert red.material.opacity == pytest.approx(0.5)
    assert [k.name for k in red.keypoints] == ["top", "bottom"]
    assert big.keypoints[0].position == (0.05, 0.05, 0.05)
    assert big.material.base_color == (0.1, 0.9, 0.1, 1.0)
    mesh = mgn.Mesh(big.vertices.astype(np.float32), big.faces)
    assert mgn.mass_properties(mesh, big.density).mass == pytest.approx(1.0, rel=1e-5)  # 10 cm


def test_cli_exports_user_objects(tmp_path, data_dir):
    path = write_yaml(
        tmp_path,
        f"objects:\n  - {{name: part, mesh: {data_dir / 'cube.ply'}, density: 7800, "
        "friction: 0.3, category_id: 500}\n",
    )
    out = tmp_path / "out"
    assert main(["objects", "export", str(out), "--add", str(path), "--only", "part"]) == 0
    mf = read_model_folder(out / "models" / "500")
    assert mf.metadata["name"] == "part"
    assert mf.metadata["mass_kg"] == pytest.approx(7800 * 8e-6, rel=1e-5)


@pytest.mark.parametrize(
    ("entry", "message"),
    [
        ("{name: a, mesh: cube.stl, density: 1}", "missing required key 'friction'"),
        ("{name: a, mesh: cube.stl, density: 1, friction: 1, colour: red}", "unknown key"),
        ("{name: mug, mesh: cube.stl, density: 1, friction: 1}", "clashes"),
        ("{name: a, mesh: cube.stl, density: -1, friction: 1}", "density"),
        ("{name: a, mesh: open.obj, density: 1, friction: 1}", "not closed"),
        ("{name: a, mesh: gone.stl, density: 1, friction: 1}", "gone.stl"),
    ],
)
def test_bad_user_objects_are_named(tmp_path, data_dir, entry, message):
    (tmp_path / "cube.stl").write_bytes((data_dir / "cube.stl").read_bytes())
    (tmp_path / "open.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\n")
    path = write_yaml(tmp_path, f"objects:\n  - {entry}\n")
    with pytest.raises(mgn.MgnError, match=message):
        load_objects_yaml(path)
