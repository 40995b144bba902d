"""The BOP export (``mgn export bop``) checked against the BOP format documentation
(bop_toolkit docs/bop_datasets_format.md) and against mgn's own files, read here directly
(``np.load`` of ``{v}.npz``, h5py, the OBJ text), not through the exporter's reader."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest
from PIL import Image

from mgn.cli.main import main
from mgn.errors import InvalidArgumentError, IoError
from mgn.geometry.mesh import Mesh
from mgn.geometry.raytrace import RayScene, camera_rays
from mgn.io import bop
from mgn.io.bop import export_bop, validate_bop


@pytest.fixture(scope="module")
def exported(small_dataset: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("bop") / "out"
    result = export_bop(small_dataset, out)
    assert result.written == [0, 1]
    assert result.skipped == []
    assert result.models_written
    return out


def _png(path: Path) -> np.ndarray:
    with Image.open(path) as im:
        return np.asarray(im)


def _json(path: Path) -> dict:
    return json.loads(path.read_text())


def _views(ds: Path, n: int) -> list[int]:
    return sorted(int(p.name.split("_")[0]) for p in (ds / f"scene{n}").glob("*_rgb.png"))


def _read_ply(path: Path) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """(vertices (V, k) float64 of every vertex property, faces (F, 3), property names) of an
    ASCII PLY."""
    lines = path.read_text().splitlines()
    end = lines.index("end_header")
    header = lines[:end]
    assert header[0] == "ply"
    assert header[1] == "format ascii 1.0"
    nv = int(next(h.split()[2] for h in header if h.startswith("element vertex")))
    nf = int(next(h.split()[2] for h in header if h.startswith("element face")))
    props = [h.split()[2] for h in header if h.startswith("property float")]
    v = np.array([[float(x) for x in ln.split()] for ln in lines[end + 1 : end + 1 + nv]])
    f = np.array([[int(x) for x in ln.split()] for ln in lines[end + 1 + nv : end + 1 + nv + nf]])
    assert (f[:, 0] == 3).all()
    return v, f[:, 1:], props


def _obj_vertices_m(path: Path) -> np.ndarray:
    return np.array(
        [
            [float(x) for x in ln.split()[1:4]]
            for ln in path.read_text().splitlines()
            if ln.startswith("v ")
        ]
    )


def test_top_level_files(exported: Path, small_dataset: Path) -> None:
    cam = _json(exported / "camera.json")
    assert set(cam) == {"cx", "cy", "depth_scale", "fx", "fy", "height", "width"}
    params = _json(small_dataset / "scene0" / "0_camera_params.json")
    for k in ("cx", "cy", "fx", "fy", "width", "height"):
        assert cam[k] == params[k]
    assert cam["depth_scale"] == 0.1
    assert isinstance(cam["width"], int)
    info = _json(exported / "models" / "models_info.json")
    ids = sorted(int(p.name) for p in (small_dataset / "models").iterdir())
    assert sorted(int(k) for k in info) == ids
    for obj_id in ids:
        entry = info[str(obj_id)]
        box_keys = {"diameter", "min_x", "min_y", "min_z", "size_x", "size_y", "size_z"}
        assert box_keys <= set(entry)
        assert set(entry) - box_keys <= {"symmetries_discrete", "symmetries_continuous"}
        ply = exported / "models" / f"obj_{obj_id:06d}.ply"
        v, f, props = _read_ply(ply)
        assert props == ["x", "y", "z", "nx", "ny", "nz", "texture_u", "texture_v"]
        assert np.allclose(np.linalg.norm(v[:, 3:6], axis=1), 1.0, atol=1e-6)
        assert f.min() >= 0
        assert f.max() < len(v)
        assert (exported / "models" / f"obj_{obj_id:06d}.png").is_file()
        assert f"comment TextureFile obj_{obj_id:06d}.png" in ply.read_text()[:500]
        # mm: the OBJ's vertices (m) x 1000, and the box of models_info is theirs.
        obj = _obj_vertices_m(small_dataset / "models" / f"{obj_id:03d}" / "textured.obj") * 1000
        assert np.allclose(v[:, :3].min(0), obj.min(0), atol=1e-3)
        assert np.allclose(v[:, :3].max(0), obj.max(0), atol=1e-3)
        lo = [entry["min_x"], entry["min_y"], entry["min_z"]]
        size = [entry["size_x"], entry["size_y"], entry["size_z"]]
        assert np.allclose(lo, obj.min(0), atol=1e-3)
        assert np.allclose(size, obj.max(0) - obj.min(0), atol=1e-3)
        # Diameter: the largest vertex distance, at least the box's largest side.
        d = np.sqrt(((obj[:, None, :] - obj[None, :, :]) ** 2).sum(-1)).max()
        assert entry["diameter"] == pytest.approx(d, abs=1e-3)
    # box_tea (category 3) is a 125 x 75 x 65 mm box centred on its origin: by hand.
    tea = info["3"]
    assert (tea["min_x"], tea["min_y"], tea["min_z"]) == (-62.5, -37.5, -32.5)
    assert (tea["size_x"], tea["size_y"], tea["size_z"]) == (125.0, 75.0, 65.0)
    assert tea["diameter"] == pytest.approx(np.sqrt(125**2 + 75**2 + 65**2), abs=1e-6)


def test_scene_files_field_by_field(exported: Path, small_dataset: Path) -> None:
    for n in (0, 1):
        folder = exported / "train_pbr" / f"{n:06d}"
        src = small_dataset / f"scene{n}"
        views = _views(small_dataset, n)
        cams = _json(folder / "scene_camera.json")
        gts = _json(folder / "scene_gt.json")
        infos = _json(folder / "scene_gt_info.json")
        mgn_gt = _json(src / "scene_gt.json")
        assert list(cams) == list(gts) == list(infos) == [str(v) for v in views]
        names = {p.name for p in (folder / "rgb").iterdir()}
        assert names == {f"{v:06d}.png" for v in views}
        for v in views:
            cam = cams[str(v)]
            assert set(cam) == {"cam_K", "cam_R_w2c", "cam_t_w2c", "depth_scale"}
            p = _json(src / f"{v}_camera_params.json")
            assert cam["cam_K"] == [p["fx"], 0.0, p["cx"], 0.0, p["fy"], p["cy"], 0.0, 0.0, 1.0]
            assert cam["depth_scale"] == 0.1
            with h5py.File(src / f"{v}_scene.hdf5", "r") as h5:
                X_WC = np.asarray(h5["camera/pose_relative_to_world"], np.float64).reshape(4, 4)
                X_CO = np.asarray(h5["objects/poses_relative_to_camera"], np.float64)
                cats = np.asarray(h5["objects/categories"])
            X_WC[:3, 3] *= 10.0  # cm -> mm
            X_CW = np.eye(4)
            X_CW[:3, :3] = np.reshape(cam["cam_R_w2c"], (3, 3))
            X_CW[:3, 3] = cam["cam_t_w2c"]
            assert np.allclose(X_CW @ X_WC, np.eye(4), atol=1e-3)
            # rgb: the view's picture, byte for byte.
            assert (folder / "rgb" / f"{v:06d}.png").read_bytes() == (
                src / f"{v}_rgb.png"
            ).read_bytes()
            gt = gts[str(v)]
            assert len(gt) == len(X_CO) == len(mgn_gt[str(v)]) == len(infos[str(v)])
            for k, e in enumerate(gt):
                assert set(e) == {"cam_R_m2c", "cam_t_m2c", "obj_id"}
                assert isinstance(e["obj_id"], int)
                assert e["obj_id"] == int(cats[k])
                assert len(e["cam_R_m2c"]) == 9
                assert len(e["cam_t_m2c"]) == 3
                R = np.reshape(e["cam_R_m2c"], (3, 3))
                assert np.allclose(R, X_CO[k, :3, :3], atol=1e-5)
                assert np.allclose(e["cam_t_m2c"], X_CO[k, :3, 3] * 10.0, atol=1e-3)  # mm
                assert np.allclose(e["cam_t_m2c"], np.array(mgn_gt[str(v)][k]["cam_t_m2c"]) * 10)


def _bbox(mask: np.ndarray) -> list[int]:
    """BOP toolkit's box (x, y, x_max - x_min, y_max - y_min), by rows and columns."""
    cols = np.flatnonzero(mask.any(axis=0))
    rows = np.flatnonzero(mask.any(axis=1))
    if len(cols) == 0:
        return [-1, -1, -1, -1]
    return [int(cols[0]), int(rows[0]), int(cols[-1] - cols[0]), int(rows[-1] - rows[0])]


def test_depth_masks_and_gt_info(exported: Path, small_dataset: Path) -> None:
    checked = 0
    for n in (0, 1):
        folder = exported / "train_pbr" / f"{n:06d}"
        infos = _json(folder / "scene_gt_info.json")
        for v in _views(small_dataset, n):
            with np.load(small_dataset / f"scene{n}" / f"{v}.npz") as z:
                depth_cm = z["depth"]
                ids = z["instances_objects"]
                amodal = z["occlusion_objects"]
            with Image.open(folder / "depth" / f"{v:06d}.png") as im:
                assert im.mode in ("I;16", "I;16B")
                assert im.size == depth_cm.shape[::-1]
                depth = np.asarray(im, np.float64)
            valid = np.isfinite(depth_cm)
            assert (depth[~valid] == 0).all()
            assert (depth[valid] > 0).all()
            err = np.abs(depth[valid] * 0.1 - depth_cm[valid].astype(np.float64) * 10.0)
            assert err.max() <= 0.05 + 1e-6  # half a depth_scale step, mm
            visible = np.zeros(ids.shape, np.int32)
            for k, info in enumerate(infos[str(v)]):
                name = f"{v:06d}_{k:06d}.png"
                mask = _png(folder / "mask" / name)
                visib = _png(folder / "mask_visib" / name)
                assert mask.dtype == visib.dtype == np.uint8
                assert mask.shape == ids.shape
                assert set(np.unique(mask)) <= {0, 255}
                assert set(np.unique(visib)) <= {0, 255}
                assert np.array_equal(visib > 0, ids == k + 1)
                assert np.array_equal(mask > 0, amodal[k])
                visible += visib > 0
                n_all, n_vis = int(amodal[k].sum()), int((ids == k + 1).sum())
                assert info["px_count_all"] == n_all
                assert info["px_count_visib"] == n_vis
                assert info["px_count_valid"] == int((amodal[k] & valid).sum())
                assert info["visib_fract"] == pytest.approx(n_vis / n_all, rel=1e-12)
                assert info["bbox_obj"] == _bbox(amodal[k])
                assert info["bbox_visib"] == _bbox(ids == k + 1)
                checked += 1
            assert visible.max() <= 1  # no two visible masks of a view overlap
            assert np.array_equal(visible > 0, ids > 0)
    assert checked >= 6


def test_poses_reproject_onto_the_amodal_masks(exported: Path, small_dataset: Path) -> None:
    """Ray-cast each BOP model (read from its PLY, mm) at its scene_gt pose through cam_K:
    the silhouette is the exported amodal mask (IoU >= 0.99)."""
    meshes: dict[int, Mesh] = {}
    ious = []
    for n in (0, 1):
        folder = exported / "train_pbr" / f"{n:06d}"
        cams = _json(folder / "scene_camera.json")
        gts = _json(folder / "scene_gt.json")
        for key, gt in gts.items():
            K = np.reshape(cams[key]["cam_K"], (3, 3))
            for k, e in enumerate(gt):
                if e["obj_id"] not in meshes:
                    v, f, _ = _read_ply(exported / "models" / f"obj_{e['obj_id']:06d}.ply")
                    meshes[e["obj_id"]] = Mesh(v[:, :3] / 1000.0, f.astype(np.int32))
                mask = _png(folder / "mask" / f"{int(key):06d}_{k:06d}.png") > 0
                h, w = mask.shape
                X = np.eye(4)
                X[:3, :3] = np.reshape(e["cam_R_m2c"], (3, 3))
                X[:3, 3] = np.array(e["cam_t_m2c"]) / 1000.0
                scene = RayScene(meshes[e["obj_id"]], X[None])
                o, d = camera_rays(K, w, h, np.eye(4))
                hit = scene.intersect(o, d, coherent=True).hit.reshape(h, w)
                ious.append((hit & mask).sum() / (hit | mask).sum())
    assert len(ious) >= 6, ious
    assert min(ious) >= 0.99, ious


def test_validate_accepts_the_export_and_names_each_fault(exported: Path, tmp_path: Path) -> None:
    assert validate_bop(exported) == []
    assert main(["validate", "--format", "bop", str(exported)]) == 0
    bad = tmp_path / "bad"
    shutil.copytree(exported, bad)
    scene = bad / "train_pbr" / "000000"
    (scene / "mask_visib" / "000000_000001.png").unlink()
    cams = _json(scene / "scene_camera.json")
    cams["17"]["cam_K"] = cams["17"]["cam_K"][:8]
    (scene / "scene_camera.json").write_text(json.dumps(cams))
    gts = _json(scene / "scene_gt.json")
    gts["5"][0]["cam_t_m2c"] = [t / 1000.0 for t in gts["5"][0]["cam_t_m2c"]]  # metres
    (scene / "scene_gt.json").write_text(json.dumps(gts))
    Image.fromarray(np.zeros((3, 3), np.uint8)).save(scene / "mask" / "000000_000002.png")
    info = _json(bad / "models" / "models_info.json")
    other = next(k for k in info if int(k) != gts["5"][0]["obj_id"])
    del info[other]["diameter"]
    (bad / "models" / "models_info.json").write_text(json.dumps(info))
    (bad / "camera.json").unlink()
    found = {str(p) for p in validate_bop(bad)}
    expected = [
        r"^camera.json: missing$",
        rf"^models/models_info.json \[{other}\]: needs numbers diameter",
        r"^train_pbr/000000/mask_visib/000000_000001.png: missing$",
        r"^train_pbr/000000/scene_camera.json: \[17\] cam_K must be 9 numbers",
        r"^train_pbr/000000/scene_gt.json: \[5\]\[0\] cam_t_m2c z .* are both in mm\?$",
        r"^train_pbr/000000/mask/000000_000002.png: must be 8-bit grey 120 x 120$",
    ]
    for pattern in expected:
        assert any(re.search(pattern, f) for f in found), (pattern, sorted(found))
    assert main(["validate", "--format", "bop", str(bad)]) == 1


def test_resume_and_atomic_scenes(
    small_dataset: Path, exported: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "out"
    first = export_bop(small_dataset, out, scenes=[1])
    assert first.written == [1]
    assert first.skipped == []
    # A run that fails inside scene 0 leaves no part of it.
    calls = {"n": 0}
    real = bop.png_bytes

    def failing(image: np.ndarray, **kw: int) -> bytes:
        calls["n"] += 1
        if calls["n"] == 5:
            raise IoError("disk full while writing 'x': free some space and retry")
        return real(image, **kw)

    monkeypatch.setattr(bop, "png_bytes", failing)
    with pytest.raises(IoError, match="disk full"):
        export_bop(small_dataset, out)
    monkeypatch.undo()
    assert sorted(p.name for p in (out / "train_pbr").iterdir()) == ["000001"]
    again = export_bop(small_dataset, out)
    assert again.written == [0]
    assert again.skipped == [1]
    assert not again.models_written
    # Byte for byte the files of one uninterrupted run.
    files = sorted(p.relative_to(exported) for p in exported.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(out) for p in out.rglob("*") if p.is_file())
    for rel in files:
        assert (out / rel).read_bytes() == (exported / rel).read_bytes(), rel


def test_cli_and_bad_inputs(small_dataset: Path, tmp_path: Path) -> None:
    out = tmp_path / "cli"
    assert (
        main(
            [
                "export",
                "bop",
                str(small_dataset),
                str(out),
                "--scenes",
                "1",
                "--split",
                "val",
                "--depth-scale",
                "1.0",
            ]
        )
        == 0
    )
    assert [p.name for p in (out / "val").iterdir()] == ["000001"]
    assert _json(out / "camera.json")["depth_scale"] == 1.0
    assert validate_bop(out) == []
    with pytest.raises(InvalidArgumentError, match="depth_scale"):
        export_bop(small_dataset, tmp_path / "a", depth_scale=0.0)
    with pytest.raises(InvalidArgumentError, match=r"depth_scale 0.001 mm"):
        export_bop(small_dataset, tmp_path / "b", depth_scale=0.001)  # 65.5 mm at most
    assert not (tmp_path / "b" / "train_pbr" / "000000").exists()
    with pytest.raises(InvalidArgumentError, match="split 'a/b'"):
        export_bop(small_dataset, tmp_path / "c", split="a/b")
    with pytest.raises(IoError, match=r"no scene folder for scene ids \[7\]"):
        export_bop(small_dataset, tmp_path / "d", scenes=[7])
    with pytest.raises(IoError, match="is not a folder"):
        validate_bop(tmp_path / "nowhere")


def test_diameter_from_the_hull_candidates_is_the_brute_force_one() -> None:
    from mgn.geometry.convex import convex_hull

    rng = np.random.default_rng(3)
    pts = rng.normal(size=(3000, 3)) * (0.05, 0.03, 0.02)  # m, an ellipsoidal cloud
    faces = np.arange(3000, dtype=np.int32).reshape(-1, 3)
    mesh = Mesh(pts, faces)
    v = bop.vertices_mm(mesh)
    cand = bop.hull_candidates(v, convex_hull(mesh))
    assert 4 <= len(cand) < len(v) // 10
    d = np.sqrt(((v[:, None, :] - v[None, :, :]) ** 2).sum(-1)).max()
    info = bop.model_info(v, diameter_points=cand)
    assert info["diameter"] == pytest.approx(d, abs=1e-9)
    assert info["size_x"] == pytest.approx(v[:, 0].max() - v[:, 0].min())


def test_models_info_symmetries(exported: Path) -> None:
    """The built-in boxes (tea, cereal) have the three half turns about their box axes through
    the box's centre; the soda can has a continuous axis along z and no flip (its ends differ).
    Each discrete transform maps the PLY's vertices onto the box's faces."""
    info = _json(exported / "models" / "models_info.json")
    for obj_id, entry in info.items():
        v, _, _ = _read_ply(exported / "models" / f"obj_{int(obj_id):06d}.ply")
        xyz = v[:, :3]
        lo, hi = xyz.min(axis=0), xyz.max(axis=0)
        disc = entry.get("symmetries_discrete", [])
        cont = entry.get("symmetries_continuous", [])
        if cont:
            assert len(cont) == 1
            assert disc == []
            assert np.abs(cont[0]["axis"]) == pytest.approx([0, 0, 1])
            assert cont[0]["offset"][:2] == pytest.approx([0, 0], abs=0.05)
            continue
        assert len(disc) == 3
        for flat in disc:
            T = np.array(flat).reshape(4, 4)
            R, t = T[:3, :3], T[:3, 3]
            assert T[3].tolist() == [0, 0, 0, 1]
            # a half turn about a box axis: diagonal, two entries -1
            assert np.allclose(R, np.diag(np.diag(R)), atol=1e-9)
            assert sorted(np.diag(R).round(9).tolist()) == [-1.0, -1.0, 1.0]
            moved = xyz @ R.T + t
            # every vertex stays inside the box and the box's centre is fixed
            assert (moved >= lo - 0.01).all()
            assert (moved <= hi + 0.01).all()
            c = (lo + hi) / 2
            assert R @ c + t == pytest.approx(c, abs=0.05)


def test_validate_flags_bad_symmetries(exported: Path, tmp_path: Path) -> None:
    out = tmp_path / "bop"
    shutil.copytree(exported, out)
    path = out / "models" / "models_info.json"
    info = _json(path)
    key = min(info)
    info[key]["symmetries_discrete"] = [[1.0] * 16]
    info[key]["symmetries_continuous"] = [{"axis": [0, 0, 2], "offset": [0, 0, 0]}]
    path.write_text(json.dumps(info))
    found = [p.message for p in validate_bop(out)]
    assert any("symmetries_discrete" in m for m in found)
    assert any("symmetries_continuous" in m for m in found)
