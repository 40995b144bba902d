"""A corpus of constructed bad inputs (meshes, user-object files, configs, command lines), each
with its expected outcome: a clear error naming the input, a warning naming it, or a repair
stated in the output. Every case builds its own files into ``tmp_path`` (nothing downloaded) and
runs the ``mgn`` command line as a user would; one parametrised test checks them all."""

from __future__ import annotations

import contextlib
import dataclasses
import errno
import io
import json
import math
import os
import re
import stat
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np
import pytest
import trimesh
import yaml
from PIL import Image

from mgn.cli import main
from mgn.geometry.mesh import Material, mass_properties, mesh_from_arrays
from mgn.geometry.repair import repair_mesh
from mgn.objects import ToteSpec, load_objects_yaml
from mgn.objects.user import UserObjectWarning
from mgn.pipeline import scene_task, scene_writer
from mgn.scene.penetration import render_penetration
from mgn.scene.scene import RemovedInstance, Scene

#: Every object label off, one tiny view, a short drop: a generate run of about a second.
FAST = {
    "camera": {"views": [0], "resolution_scale": 0.06},
    "labels": dict.fromkeys(
        ("suction", "paralleljaw", "pj_physics", "layout", "scene_grasps"), False
    ),
    "drop": {"max_time": 0.5},
}

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
    (stdout and stderr together) once (``once``) or at least once, and nothing matching
    ``absent``; ``check`` looks at the files afterwards. ``patch`` simulates
    what a file cannot hold (a Ctrl-C, a full disk) for the command's run only."""

    id: str
    kind: str  # "error" | "warning" | "repaired"
    build: Callable[[Path], list[str]]
    rc: int
    expect: str
    check: Callable[[Path], None] | None = None
    patch: Callable[[pytest.MonkeyPatch], None] | None = None
    absent: str | None = None
    once: bool = False


# ------------------------------------------------------------------ names, keys, resume, scale


def _bad_name(name: object) -> Callable[[Path], list[str]]:
    def build(tmp: Path) -> list[str]:
        cube_objects(tmp, name=name)  # type: ignore[arg-type]
        return ["objects", "list", "--add", str(tmp / "objs.yaml")]

    return build


def _bad_cli_name(tmp: Path) -> list[str]:
    write(tmp / "cube.obj", CUBE_OBJ)
    return ["objects", "add", str(tmp / "cube.obj"), "--to", str(tmp / "o.yaml"), "--name", "a,b"]


def _duplicate_config_key(tmp: Path) -> list[str]:
    write(tmp / "cfg.yaml", "objects:\n  count: 3\n  copies: [1, 2]\n  count: 30\n")
    return ["config", "check", str(tmp / "cfg.yaml")]


def _duplicate_object_key(tmp: Path) -> list[str]:
    write(tmp / "cube.obj", CUBE_OBJ)
    write(
        tmp / "objs.yaml",
        "objects:\n  - name: part\n    mesh: cube.obj\n    density: 500\n"
        "    friction: 0.5\n    density: 5000\n",
    )
    return ["objects", "list", "--add", str(tmp / "objs.yaml")]


def _resume_other_config(tmp: Path) -> list[str]:
    cfg = fast_config(tmp)
    args = [
        "generate",
        "--out",
        str(tmp / "ds"),
        "--scenes",
        "1",
        "--objects",
        "box_tea",
        "--quiet",
    ]
    assert main([*args, "--config", str(cfg)]) == 0
    fast_config(tmp, drop={"max_time": 0.6})
    return [*args, "--config", str(cfg), "--resume"]


def _nonuniform_yaml_scale(tmp: Path) -> list[str]:
    cube_objects(tmp, scale=[0.05, 0.05, 0.1])
    return ["objects", "list", "--add", str(tmp / "objs.yaml")]


def _nonuniform_cli_scale(tmp: Path) -> list[str]:
    write(tmp / "cube.obj", CUBE_OBJ)
    return [
        "objects",
        "add",
        str(tmp / "cube.obj"),
        "--to",
        str(tmp / "o.yaml"),
        "--scale",
        "0.05,0.05,0.1",
    ]


# ------------------------------------------------------ permissions, interrupts, full disks


def _tiny_generate(tmp: Path) -> list[str]:
    cfg = fast_config(tmp)
    return [
        "generate",
        "--out",
        str(tmp / "ds"),
        "--scenes",
        "1",
        "--objects",
        "box_tea",
        "--config",
        str(cfg),
        "--quiet",
    ]


def _usual_modes(tmp: Path) -> None:
    """models/<id>/, tote/ and their files have the modes of a new folder / file (0755 / 0644
    under umask 022), like the scene folders: other users can read them."""
    mask = os.umask(0)
    os.umask(mask)
    ds = tmp / "ds"
    for folder in (ds / "models" / "003", ds / "tote", ds / "scene0"):
        assert stat.S_IMODE(folder.stat().st_mode) == 0o777 & ~mask, folder
    for f in [*(ds / "models" / "003").iterdir(), *(ds / "tote").iterdir()]:
        assert stat.S_IMODE(f.stat().st_mode) == 0o666 & ~mask, f


def _ctrl_c_in_scene(mp: pytest.MonkeyPatch) -> None:
    def interrupted(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    mp.setattr(scene_writer, "write_scene", interrupted)


def _status(expected: str) -> Callable[[Path], None]:
    def check(tmp: Path) -> None:
        doc = json.loads((tmp / "ds" / "dataset.json").read_text())
        assert doc["status"] == expected, doc["status"]
        assert not list((tmp / "ds").glob(".tmp-*"))

    return check


def _disk_full_in_models(mp: pytest.MonkeyPatch) -> None:
    """HDF5 writes go to /dev/full: the real h5py error of a full disk (errno 28)."""
    real = h5py.File

    def full(path: object, mode: str = "r", *args: object, **kwargs: object) -> h5py.File:
        return real("/dev/full", "w") if mode == "w" else real(path, mode, *args, **kwargs)

    mp.setattr(h5py, "File", full)


def _disk_full_reported(tmp: Path) -> None:
    _status("failed")(tmp)
    doc = json.loads((tmp / "ds" / "dataset.json").read_text())
    assert doc["error"].startswith("IoError: disk full while writing"), doc["error"]
    assert not (tmp / "ds" / "models").exists()


# ------------------------------------------------------------ warnings of the run's objects


def _objects_replace_a_large_count(tmp: Path) -> list[str]:
    cfg = fast_config(tmp, objects={"count": 1000})
    return [
        "generate",
        "--out",
        str(tmp / "ds"),
        "--scenes",
        "1",
        "--config",
        str(cfg),
        "--objects",
        "box_tea,can_soda",
        "--quiet",
    ]


def _two_user_objects(tmp: Path) -> Path:
    """A 5 cm cube 'small_part' and the same cube read in the wrong unit, 'speck' (0.5 mm)."""
    write(tmp / "cube.obj", CUBE_OBJ)
    entry = {"mesh": "cube.obj", "density": 500, "friction": 0.5}
    return write_yaml(
        tmp / "objs.yaml",
        {
            "objects": [
                {"name": "small_part", "scale": 0.05, **entry},
                {"name": "speck", "scale": 5e-4, **entry},
            ]
        },
    )


def _generate_with(*objects: str) -> Callable[[Path], list[str]]:
    def build(tmp: Path) -> list[str]:
        objs = _two_user_objects(tmp)
        cfg = fast_config(tmp)
        return [
            "generate",
            "--out",
            str(tmp / "ds"),
            "--scenes",
            "1",
            "--config",
            str(cfg),
            "--add",
            str(objs),
            "--objects",
            *objects,
            "--quiet",
        ]

    return build


# -------------------------------------------------------------------- missing material files


def _obj_with_missing_mtl(tmp: Path) -> list[str]:
    write(tmp / "meshes" / "part.obj", "mtllib part.mtl\n" + CUBE_OBJ)
    return [
        "objects",
        "add",
        str(tmp / "meshes" / "part.obj"),
        "--scale",
        "0.05",
        "--to",
        str(tmp / "o.yaml"),
    ]


def _obj_with_missing_map_kd(tmp: Path) -> list[str]:
    write(tmp / "part.obj", "mtllib part.mtl\nusemtl wood\n" + CUBE_OBJ)
    write(tmp / "part.mtl", "newmtl wood\nKd 1 1 1\nmap_Kd -s 1 1 1 tex/wood grain.png\n")
    entry = {"name": "part", "mesh": "part.obj", "scale": 0.05, "density": 500, "friction": 0.5}
    write_yaml(tmp / "objs.yaml", {"objects": [entry]})
    return [
        "generate",
        "--out",
        str(tmp / "ds"),
        "--scenes",
        "1",
        "--config",
        str(fast_config(tmp)),
        "--add",
        str(tmp / "objs.yaml"),
        "--objects",
        "part",
        "--quiet",
    ]


def _obj_with_unreadable_texture(tmp: Path) -> list[str]:
    write(tmp / "part.obj", "mtllib part.mtl\nusemtl paper\n" + CUBE_OBJ)
    write(tmp / "part.mtl", "newmtl paper\nKd 0.5 0.5 0.5\nmap_Kd label.png\n")
    write(tmp / "label.png", "not an image\n")
    return ["objects", "add", str(tmp / "part.obj"), "--to", str(tmp / "o.yaml")]


def _gltf_with_missing_image(tmp: Path) -> list[str]:
    box = trimesh.creation.box((0.05, 0.05, 0.05))
    box.visual = trimesh.visual.TextureVisuals(
        uv=np.zeros((len(box.vertices), 2)), image=Image.new("RGB", (4, 4))
    )
    for name, data in trimesh.exchange.gltf.export_gltf(trimesh.Scene(box)).items():
        (tmp / name).write_bytes(data)
    doc = json.loads((tmp / "model.gltf").read_text())
    doc["images"] = [{"uri": "images/label.png"}]  # an external image that is not there
    (tmp / "model.gltf").write_text(json.dumps(doc))
    return ["objects", "add", str(tmp / "model.gltf"), "--to", str(tmp / "o.yaml")]


# ------------------------------------------------------------ implausible bins and counts


def _bin_in_millimetres(tmp: Path) -> list[str]:
    """A bin drawn in millimetres (outer 416 x 316 x 160 mm) read as metres: 416 m across."""
    trimesh.creation.box(bounds=[(-208, -158, -10), (208, 158, 150)]).export(tmp / "bin.stl")
    return ["config", "check", str(write_yaml(tmp / "cfg.yaml", {"tote": {"mesh": "bin.stl"}}))]


def _inner_box_in_millimetres(tmp: Path) -> list[str]:
    tote = {"inner_length": 400, "inner_width": 300, "inner_height": 150}
    return ["config", "check", str(write_yaml(tmp / "cfg.yaml", {"tote": tote}))]


def _million_objects(command: str) -> Callable[[Path], list[str]]:
    def build(tmp: Path) -> list[str]:
        cfg = fast_config(tmp, objects={"count": 1_000_000})
        if command == "check":
            return ["config", "check", str(cfg)]
        return [
            "generate",
            "--out",
            str(tmp / "ds"),
            "--scenes",
            "1",
            "--config",
            str(cfg),
            "--quiet",
        ]

    return build


def _many_named_objects(tmp: Path) -> list[str]:
    """``--objects`` naming 3000 tennis balls (~50x the tote's volume in boxes): refused before
    any object is composed or dropped."""
    return [
        "generate",
        "--out",
        str(tmp / "ds"),
        "--scenes",
        "1",
        "--config",
        str(fast_config(tmp)),
        "--objects",
        ",".join(["tennis_ball"] * 3000),
        "--quiet",
    ]


def _nothing_written(tmp: Path) -> None:
    assert not (tmp / "ds").exists()


# ------------------------------------------------------ configs that fail (or empty) every scene


def _check(**sections: dict) -> Callable[[Path], list[str]]:
    def build(tmp: Path) -> list[str]:
        return ["config", "check", str(fast_config(tmp, **sections))]

    return build


def _generate(**sections: dict) -> Callable[[Path], list[str]]:
    def build(tmp: Path) -> list[str]:
        return [
            "generate",
            "--out",
            str(tmp / "ds"),
            "--scenes",
            "1",
            "--config",
            str(fast_config(tmp, **sections)),
            "--objects",
            "box_tea",
            "--quiet",
        ]

    return build


def _poses(*eyes: list[float], away: bool = False) -> dict:
    """Cameras at ``eyes`` looking at the tote centre, or (``away``) straight up."""
    look = {"target": [0, 0, 2.0], "up": [0, 1, 0]} if away else {"target": [0, 0, 0]}
    return {"rig": "poses", "views": None, "poses": [{"eye": e, **look} for e in eyes]}


def _one_micron_part(tmp: Path) -> list[str]:
    cube_objects(tmp, name="speck", scale=1e-6)
    return [
        "generate",
        "--out",
        str(tmp / "ds"),
        "--scenes",
        "1",
        "--config",
        str(fast_config(tmp)),
        "--add",
        str(tmp / "objs.yaml"),
        "--objects",
        "speck",
        "--quiet",
    ]


def _user_name_with_add(tmp: Path) -> list[str]:
    cube_objects(tmp, name="my_part")
    cfg = fast_config(tmp, objects={"names": ["my_part", "box_tea"]})
    return ["config", "check", str(cfg), "--add", str(tmp / "objs.yaml")]


def _part_larger_than_tote(tmp: Path) -> list[str]:
    cube_objects(tmp, name="big_part", scale=0.6)  # 60 cm: plausible, but not in this tote
    return [
        "generate",
        "--out",
        str(tmp / "ds"),
        "--scenes",
        "1",
        "--config",
        str(fast_config(tmp)),
        "--add",
        str(tmp / "objs.yaml"),
        "--objects",
        "big_part",
        "box_tea",
        "--quiet",
    ]


def _drawn_part_larger_than_tote(tmp: Path) -> list[str]:
    cube_objects(tmp, name="big_part", scale=0.6)
    objects = {
        "categories": ["box_tea", "big_part"],
        "count": 1,
        "copies": [1, 1],
        "user_objects": [str(tmp / "objs.yaml")],
    }
    return ["config", "check", str(fast_config(tmp, objects=objects))]


def _everything_leaves(mp: pytest.MonkeyPatch) -> None:
    """The drop ends with no object in the tote (as for a part that falls through the floor)."""
    real = scene_task.drop_task_scene

    def empty(task: scene_task.SceneTask) -> Scene:
        scene = real(task)
        gone = tuple(RemovedInstance(i.name, i.source, "left_tote") for i in scene.instances)
        return dataclasses.replace(scene, instances=(), removed=gone)

    mp.setattr(scene_task, "drop_task_scene", empty)


def _disk_full_in_scene(mp: pytest.MonkeyPatch) -> None:
    def full(*args: object, **kwargs: object) -> None:
        raise OSError(errno.ENOSPC, "No space left on device", "0_rgb.png")

    mp.setattr(scene_writer, "write_scene", full)


# ------------------------------------------------------------------ nearly closed meshes

#: A 10 x 5 x 1.2 cm box: 60 cm^3, 60 g at 1000 kg/m^3.
BOX = trimesh.creation.box((0.1, 0.05, 0.012))
#: A bottle-like 48-sided prism, r 4 cm, h 12 cm: 0.5 n r^2 sin(2 pi / n) h m^3.
BOTTLE = trimesh.creation.cylinder(radius=0.04, height=0.12, sections=48)
BOTTLE_G = 0.5 * 48 * 0.04**2 * math.sin(2 * math.pi / 48) * 0.12 * 1e6


def _add_mesh(name: str, vertices: np.ndarray, faces: np.ndarray) -> Callable[[Path], list[str]]:
    def build(tmp: Path) -> list[str]:
        trimesh.Trimesh(vertices, faces, process=False).export(tmp / f"{name}.ply")
        return [
            "objects",
            "add",
            str(tmp / f"{name}.ply"),
            "--to",
            str(tmp / "o.yaml"),
            "--density",
            "1000",
        ]

    return build


def _mixed_winding() -> tuple[np.ndarray, np.ndarray]:
    f = BOX.faces.copy()
    f[[0, 3, 5, 8, 9, 11]] = f[[0, 3, 5, 8, 9, 11]][:, ::-1]
    return BOX.vertices, f


def _with_fin() -> tuple[np.ndarray, np.ndarray]:
    """A triangle hanging off one edge: that edge has three faces, the fin two free edges."""
    a, b = BOTTLE.faces[0][:2]
    v = np.vstack([BOTTLE.vertices, [[0.1, 0.1, 0.1]]])
    return v, np.vstack([BOTTLE.faces, [[a, b, len(BOTTLE.vertices)]]])


def _without_cap() -> tuple[np.ndarray, np.ndarray]:
    top = BOTTLE.triangles_center[:, 2] > 0.059
    return BOTTLE.vertices, BOTTLE.faces[~top]


def _touching_boxes(top: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Two 5 cm cubes sharing one edge (four faces on it): 250 cm^3. Without ``top`` the
    first cube has no top face (a 25 cm^2 hole, too large to close)."""
    b = trimesh.creation.box((0.05, 0.05, 0.05))
    first = b if top else trimesh.Trimesh(b.vertices, b.faces[b.triangles_center[:, 2] < 0.02])
    both = trimesh.util.concatenate([first, b.copy().apply_translation((0.05, 0.05, 0))])
    return both.vertices, both.faces


#: Edge a of the tetrahedra below: 5 cm.
TET_A = 0.05


def _tetrahedra_sharing_a_vertex() -> tuple[np.ndarray, np.ndarray]:
    """Tetrahedra (0, a e_x, a e_y, a e_z) and (0, -a e_x, -a e_z, -2a e_y), one vertex index
    at the origin for both: a^3/6 + 2a^3/6 = a^3/2."""
    a = TET_A
    v = np.array(
        [[0, 0, 0], [a, 0, 0], [0, a, 0], [0, 0, a], [-a, 0, 0], [0, 0, -a], [0, -2 * a, 0]]
    )
    faces = []
    for p, q, r, t in ((0, 1, 2, 3), (0, 4, 5, 6)):  # det(q - p, r - p, t - p) > 0
        faces += [[p, r, q], [p, q, t], [p, t, r], [q, r, t]]
    return v, np.array(faces)


def _mixed_winding_yaml(tmp: Path) -> list[str]:
    trimesh.Trimesh(*_mixed_winding(), process=False).export(tmp / "box.ply")
    entry = {"name": "box", "mesh": "box.ply", "density": 1000, "friction": 0.5}
    return ["objects", "list", "--add", str(write_yaml(tmp / "o.yaml", {"objects": [entry]}))]


def _entry_mass(expected_g: float, **keys: object) -> Callable[[Path], None]:
    """The YAML entry has ``keys``; the object read back has the solid mass ``expected_g``."""

    def check(tmp: Path) -> None:
        (entry,) = yaml.safe_load((tmp / "o.yaml").read_text())["objects"]
        assert {k: entry.get(k) for k in keys} == keys, entry
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserObjectWarning)
            (spec,) = load_objects_yaml(tmp / "o.yaml")
        props = mass_properties(spec.to_mesh(), spec.density)
        assert props.is_exact
        assert props.mass * 1e3 == pytest.approx(expected_g, rel=1e-5)

    return check


def _open_entry(tmp: Path) -> None:
    (entry,) = yaml.safe_load((tmp / "o.yaml").read_text())["objects"]
    assert entry.get("allow_open") is True, entry


def _generate_open_object(tmp: Path) -> list[str]:
    trimesh.Trimesh(*_without_cap(), process=False).export(tmp / "cup.ply")
    assert main(["objects", "add", str(tmp / "cup.ply"), "--to", str(tmp / "o.yaml")]) == 0
    cfg = fast_config(
        tmp,
        labels={"suction": True, "paralleljaw": True},
        object_labels={"suction_points": 40, "pj_points": 40},
    )
    return [
        "generate",
        "--out",
        str(tmp / "ds"),
        "--scenes",
        "1",
        "--config",
        str(cfg),
        "--add",
        str(tmp / "o.yaml"),
        "--objects",
        "cup",
        "--quiet",
        "--no-cache",
    ]


# ------------------------------------------------------------------- Phong -> PBR materials


def _phong(kd: str, ks: str, ns: str) -> Callable[[Path], list[str]]:
    def build(tmp: Path) -> list[str]:
        write(tmp / "part.obj", "mtllib part.mtl\nusemtl m\n" + CUBE_OBJ)
        write(tmp / "part.mtl", f"newmtl m\nKd {kd}\nKs {ks}\nNs {ns}\n")
        return [
            "objects",
            "add",
            str(tmp / "part.obj"),
            "--scale",
            "0.05",
            "--to",
            str(tmp / "o.yaml"),
        ]

    return build


def _material_is(metallic: float, roughness: float, rgb: tuple) -> Callable[[Path], None]:
    def check(tmp: Path) -> None:
        (spec,) = load_objects_yaml(tmp / "o.yaml")
        m = spec.material
        assert (m.metallic, m.roughness) == (metallic, pytest.approx(roughness, abs=1e-6))
        assert m.base_color[:3] == pytest.approx(rgb)

    return check


# ---------------------------------------------------------------- a dataset scene's own config


def _export_dataset_scene(tmp: Path) -> list[str]:
    assert main(_tiny_generate(tmp)) == 0  # one camera per scene (camera.views: [0])
    return ["scene", "export", str(tmp / "ds" / "scene0"), str(tmp / "scene.glb")]


def _one_camera_in_glb(tmp: Path) -> None:
    data = (tmp / "scene.glb").read_bytes()
    n = int.from_bytes(data[12:16], "little")
    doc = json.loads(data[20 : 20 + n])
    assert [node["name"] for node in doc["nodes"] if node["name"].startswith("camera")] == [
        "camera_0"
    ]  # the dataset's one view, not the 37 of the default rig


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
    Case("folder-modes", "repaired", _tiny_generate, 0, r"1/1 scenes complete",
         check=_usual_modes),
    Case("ctrl-c", "error", _tiny_generate, 130, r"mgn: interrupted", check=_status("interrupted"),
         patch=_ctrl_c_in_scene),
    Case("disk-full-in-models", "error", _tiny_generate, 1, r"mgn: error: disk full while "
         r"writing '[^']*/ds/models/003': free some space and retry\n", check=_disk_full_reported,
         patch=_disk_full_in_models),
    Case("missing-mtl", "warning", _obj_with_missing_mtl, 0, r"warning: [^\n]*o\.yaml: "
         r"objects\[0\] \('part'\): mesh '[^']*meshes/part\.obj': its material library "
         r"\(mtllib\) '[^']*meshes/part\.mtl' is missing; the object renders in its plain base "
         r"colour \(0\.60, 0\.60, 0\.60\)", once=True),
    Case("missing-map-kd", "warning", _obj_with_missing_map_kd, 0, r"warning: [^\n]*objs\.yaml:"
         r" objects\[0\] \('part'\): mesh '[^']*part\.obj': its texture of material 'wood' "
         r"'[^']*tex/wood grain\.png' is missing; the object renders in its plain base colour "
         r"\(1\.00, 1\.00, 1\.00\)", once=True),
    Case("unreadable-texture", "warning", _obj_with_unreadable_texture, 0, r"its texture of "
         r"material 'paper' \(not a readable image\) '[^']*label\.png' cannot be read; the "
         r"object renders in its plain base colour \(0\.50, 0\.50, 0\.50\)", once=True),
    Case("missing-gltf-image", "warning", _gltf_with_missing_image, 0, r"warning: [^\n]*"
         r"model\.gltf': its texture of material '[^']*' '[^']*images/label\.png' is missing",
         once=True),
    Case("bin-in-millimetres", "warning", _bin_in_millimetres, 0, r"warning: tote\.mesh '[^']*"
         r"bin\.stl' \(mesh_scale 1\) is 416 m across, too large for a bin around an inner box "
         r"of 0\.4 x 0\.3 x 0\.15 m; if the file is in millimetres, use tote\.mesh_scale 0\.001",
         once=True),
    Case("inner-box-in-millimetres", "warning", _inner_box_in_millimetres, 0, r"warning: tote\."
         r"inner_length / inner_width / inner_height: 400 x 300 x 150 m is too large for a bin"),
    Case("million-objects-check", "error", _million_objects("check"), 1, r"error: objects\.count: "
         r"1000000 objects per scene; their boxes add up to [0-9.e+]+x the tote's inner volume "
         r"\(more than 10x\), about 24 fit; expected at most about 240"),
    Case("million-objects-generate", "error", _million_objects("generate"), 1, r"error: "
         r"generate: the config fails every scene .*\n  objects\.count: 1000000 objects",
         check=_nothing_written),
    Case("overfill-via-objects", "error", _many_named_objects, 1, r"generate: the config fails "
         r"every scene .*\n  objects\.names: 3000 objects per scene; their boxes add up to "
         r"[0-9.]+x the tote's inner volume \(more than 10x\)", check=_nothing_written),
    Case("tote-smaller-than-window", "error", _check(tote={"inner_length": 0.1,
         "inner_width": 0.05}), 1, r"error: drop\.window_min / drop\.window_max: the release "
         r"window x \[-0\.06, 0\.06\], y \[-0\.03, 0\.03\], z >= 0\.3 m does not lie above "
         r"the tote's cavity \(\|x\| <= 0\.05, \|y\| <= 0\.025"),
    Case("tote-smaller-than-window-generate", "error", _generate(tote={"inner_length": 0.1,
         "inner_width": 0.05}), 1, r"generate: the config fails every scene .*drop\.window_min",
         check=_nothing_written),
    Case("max-bounces", "error", _check(render={"engine": "path", "max_bounces": 2000}), 1,
         r"config key 'render\.max_bounces': PathTraceOptions\.max_bounces must be in "
         r"\[0, 1000\], got 2000"),
    Case("unknown-name", "error", _check(objects={"names": ["box_tea", "box_tee"]}), 1,
         r"error: objects\.names: unknown object\(s\) 'box_tee'; known: [^\n]*box_tea, "),
    Case("user-name-with-add", "warning", _user_name_with_add, 0, r"cfg\.yaml: valid",
         absent="unknown"),
    Case("camera-facing-away", "error", _check(camera=_poses([0, 0, 1.0], away=True)), 1, r"error: "
         r"camera\.poses\[0\] \(eye \[0\.0, 0\.0, 1\.0\] m\): the camera looks away from "
         r"the tote"),
    Case("camera-below-floor", "error", _check(camera=_poses([0.3, 0, -0.5])), 1, r"error: "
         r"camera\.poses: no camera sees into the tote .*camera\.poses\[0\] \(eye \[0\.3, "
         r"0\.0, -0\.5\] m\): the camera is below the tote's floor \(z = -0\.5 m < 0\)"),
    Case("one-camera-below-floor", "warning", _check(camera=_poses([0.3, 0, -0.5], [0.3, 0, 0.8])),
         0, r"warning: camera\.poses\[0\] \(eye \[0\.3, 0\.0, -0\.5\] m\): the camera is "
         r"below the tote's floor", once=True, absent=r"poses\[1\]"),
    Case("one-micron-part", "error", _one_micron_part, 1, r"generate: the config fails every "
         r"scene .*objects\.names: every object is smaller than 1 mm \('speck' 0\.001 mm\)",
         check=_nothing_written),
    Case("part-larger-than-tote", "error", _part_larger_than_tote, 1, r"generate: the config "
         r"fails every scene .*objects\.names: object 'big_part' \(0\.6 x 0\.6 x 0\.6 m\) is "
         r"larger than the tote's cavity \(0\.4 x 0\.3 m\)", check=_nothing_written),
    Case("drawn-part-larger-than-tote", "warning", _drawn_part_larger_than_tote, 0, r"warning: "
         r"objects\.categories: the objects of each scene are drawn at random, and 'big_part' "
         r"cannot lie in the tote's cavity: every scene that draws one fails"),
    Case("scene-ends-empty", "error", _tiny_generate, 1, r"FAILED scene0 \(seed \d+\): "
         r"InvalidArgumentError: no object stayed in the tote \('box_tea' \(left_tote\)\).*"
         r"scene0 failed the way they will fail on every run .* fix the cause above first",
         absent=r"redo the missing", patch=_everything_leaves),
    Case("disk-full-scene-resume", "error", _tiny_generate, 1, r"FAILED scene0 \(seed \d+\): "
         r"disk full while writing scene0 .*rerun with --resume to redo the missing scenes",
         absent=r"every run", patch=_disk_full_in_scene),
    Case("mixed-winding-box", "repaired", _add_mesh("box", *_mixed_winding()), 0,
         r"box: [^\n]* 100x50x12 mm; repaired as it is read \(turned 6 of 12 faces to the winding "
         r"of the rest of their piece \(1 piece\(s\)\)\): closed, solid mass 60 g",
         check=_entry_mass(60.0, repair=True, allow_open=None)),
    Case("bottle-with-fin", "repaired", _add_mesh("bottle", *_with_fin()), 0, r"bottle: "
         r"[^\n]* 80x80x120 mm; repaired as it is read \(removed 1 stray face\(s\) hanging off "
         r"edges shared by more than two faces; dropped 1 vertex no face uses any more\): "
         rf"closed, solid mass {BOTTLE_G:.4g} g",
         check=_entry_mass(BOTTLE_G, repair=True, allow_open=None)),
    Case("bottle-missing-triangle", "repaired", _add_mesh("bottle", BOTTLE.vertices,
         BOTTLE.faces[1:]), 0, r"repaired as it is read \(closed 1 small hole\(s\) with 1 "
         r"triangle\(s\)\): closed", check=_entry_mass(BOTTLE_G, repair=True)),
    Case("duplicate-faces", "repaired", _add_mesh("bottle", BOTTLE.vertices,
         np.vstack([BOTTLE.faces, BOTTLE.faces[:5]])), 0, r"repaired as it is read \(removed 5 "
         r"duplicate face\(s\)\): closed", check=_entry_mass(BOTTLE_G, repair=True)),
    Case("unrepaired-yaml-entry", "error", _mixed_winding_yaml, 1, r"o\.yaml: objects\[0\] "
         r"\('box'\): key 'mesh': '[^']*box\.ply' is not closed \(0 boundary, 0 non-manifold, "
         r"\d+ misoriented edges\); set repair: true to repair it as it is read"),
    Case("open-cup", "warning", _add_mesh("cup", *_without_cap()), 0, r"warning: cup \('[^']*"
         r"cup\.ply'\) stays open: 48 free edges \(1 hole\(s\) larger than 1 % of the surface"
         r"\), which the repair \(winding, duplicate and stray faces, small holes\) cannot fix\. "
         r"It is marked allow_open: its mass [0-9.]+ g is a shell mass \(2 mm walls, not a "
         r"solid\), and it gets suction labels only, no parallel-jaw labels", check=_open_entry),
    Case("cubes-sharing-an-edge", "repaired", _add_mesh("pair", *_touching_boxes()), 0, r"pair: "
         r"[^\n]* 100x100x50 mm; split 1 edge and 2 vertices where closed pieces touch \(2 "
         r"closed pieces\): closed, solid mass 250 g", absent=r"allow_open|OPEN|repaired as",
         check=_entry_mass(250.0, repair=None, allow_open=None)),
    Case("tetrahedra-sharing-a-vertex", "repaired", _add_mesh("tets",
         *_tetrahedra_sharing_a_vertex()), 0, r"tets: [^\n]* 100x150x100 mm; split 1 vertex "
         r"where closed pieces touch \(2 closed pieces\): closed, solid mass 62\.5 g",
         absent=r"allow_open|OPEN", check=_entry_mass(TET_A**3 / 2 * 1e6, allow_open=None)),
    Case("open-box-touching-a-cube", "warning", _add_mesh("pair", *_touching_boxes(top=False)),
         0, r"stays open: 4 free edges[^,]*, 1 edge\(s\) shared by more than two faces, which "
         r"the repair .* It is marked allow_open: its mass [0-9.]+ g is a shell mass",
         check=_open_entry),
    Case("open-object-in-generate", "warning", _generate_open_object, 0, r"no parallel-jaw "
         r"labels for 1 object\(s\): cup: open mesh \(48 boundary edges, allow_open\)"),
    Case("phong-white-high-ks-ns", "repaired", _phong("1 1 1", "1 1 1", "1000"), 0, r"material: "
         r"dielectric, roughness 0\.30 \(derived from the file's Phong material \(luminance of Kd "
         r"1\.00, of Ks 1\.00; Ns 1000\): not a metal, roughness at least 0\.3",
         check=_material_is(0.0, 0.3, (1.0, 1.0, 1.0))),
    Case("phong-dark-mirror", "repaired", _phong("0.02 0.02 0.02", "0.9 0.8 0.6", "800"), 0,
         r"material: metal, roughness 0\.30 \(derived from the file's Phong material .*a dark "
         r"diffuse and mirror-like specular read as a metal",
         check=_material_is(1.0, 0.3, (0.9, 0.8, 0.6))),
    Case("phong-matte", "repaired", _phong("0.6 0.5 0.4", "0.1 0.1 0.1", "10"), 0, r"material: "
         r"dielectric, roughness 0\.64 ", check=_material_is(0.0, (2 / 12) ** 0.25,
                                                              (0.6, 0.5, 0.4))),
    Case("export-without-config", "repaired", _export_dataset_scene, 0, r"config \(cameras, "
         r"gripper, cup\) from [^\n]*ds/dataset\.json; --config replaces it\n[^\n]*scene\.glb: "
         r"1 objects, tote, 1 cameras", check=_one_camera_in_glb),
    Case("tote-color-randomised", "warning", _check(tote={"color": [0.9, 0.1, 0.1, 1.0]}), 0,
         r"warning: tote\.color = \[0\.9, 0\.1, 0\.1, 1\.0\] is not used: camera\.randomize "
         r"draws the tote's colour per view; set camera\.randomize: false to keep it"),
    Case("tote-color-kept", "warning", _check(tote={"color": [0.9, 0.1, 0.1, 1.0]},
         camera={"randomize": False}), 0, r"valid", absent=r"tote\.color"),
    Case("objects-replace-count", "warning", _objects_replace_a_large_count, 0,
         r"1/1 scenes complete", absent=r"objects per scene"),
    Case("unused-object-not-warned", "warning", _generate_with("small_part"), 0,
         r"1/1 scenes complete", absent=r"speck|warning"),
    Case("used-object-warned-once", "warning", _generate_with("speck", "box_tea"), 0,
         r"warning: [^\n]*objs\.yaml: objects\[1\] \('speck'\): mesh '[^']*cube\.obj' "
         r"\(scale 0\.0005\) is 0\.5 mm across, too small", once=True, absent="small_part"),
]
# fmt: on


def test_repair_keeps_uvs_materials_and_the_solid() -> None:
    """The repair changes faces only: each kept vertex keeps its position and uv, the material
    stays, and the mass is that of the closed solid (hand-computed: 60 g)."""
    v, f = _mixed_winding()
    uvs = np.random.default_rng(1).random((len(v), 2)).astype(np.float32)
    mat = Material()
    mat.name = "paint"
    broken = mesh_from_arrays(v, f, uvs=uvs, material=mat)
    fixed = repair_mesh(broken)
    assert fixed.closed
    assert not fixed.before.is_winding_consistent
    assert np.array_equal(fixed.mesh.vertices, broken.vertices)
    assert np.array_equal(fixed.mesh.uvs, uvs)
    assert [m.name for m in fixed.mesh.materials] == ["paint"]
    assert mass_properties(fixed.mesh, 1000).mass == pytest.approx(0.060, rel=1e-6)
    # Every face keeps its three vertices; only the order of 6 of them changed.
    assert sorted(map(sorted, fixed.mesh.faces.tolist())) == sorted(map(sorted, f.tolist()))
    assert repair_mesh(fixed.mesh).changes == ()  # closed: nothing to do


def test_penetration_of_an_object_made_of_overlapping_solids() -> None:
    """One object modelled as two overlapping boxes (faces partly coincident): a small cube in
    the empty corner of its bounding box touches nothing (penetration 0; the parity of the
    whole mesh counted it 18 mm deep), and a cube sunk 4 mm into one box measures 4 mm."""
    upper = trimesh.creation.box(bounds=[(-0.05, -0.05, 0.02), (0.05, 0.05, 0.06)])
    lower = trimesh.creation.box(bounds=[(0.0, -0.05, 0.0), (0.05, 0.05, 0.04)])
    both = trimesh.util.concatenate([upper, lower])
    b = mesh_from_arrays(both.vertices, both.faces)
    cube = trimesh.creation.box((0.006, 0.006, 0.006))
    a = mesh_from_arrays(cube.vertices, cube.faces)
    X_b = np.eye(4)
    X_b[2, 3] = 0.001  # the object rests 1 mm above the floor
    rng = np.random.default_rng(0)
    for _ in range(60):
        X_a = np.eye(4)
        X_a[:3, 3] = rng.uniform([-0.046, -0.046, 0.0045], [-0.004, 0.046, 0.0165])
        assert render_penetration([a, b], [X_a, X_b], ToteSpec()) == 0.0
    X_a = np.eye(4)
    X_a[:3, 3] = (-0.02, 0.0, 0.022)  # top face at 0.025, the upper box's bottom at 0.021
    depth = render_penetration([a, b], [X_a, X_b], ToteSpec())
    assert depth == pytest.approx(0.004, abs=1e-6)


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
def test_bad_input_gets_its_outcome(
    case: Case, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    argv = case.build(tmp_path)
    if case.patch is not None:
        case.patch(monkeypatch)
    rc, text = run_cli(argv)
    found = re.findall(case.expect, text, re.DOTALL)
    assert found, f"{case.kind} {case.expect!r} not in:\n{text}"
    assert not case.once or len(found) == 1, f"{case.expect!r} {len(found)} times in:\n{text}"
    assert case.absent is None or not re.search(case.absent, text, re.DOTALL), text
    assert rc == case.rc, text
    if case.check is not None:
        case.check(tmp_path)
