"""The BOP export of a dataset (``mgn export bop DS OUT``) and its check (``mgn validate --format
bop``).

BOP is the file layout of the Benchmark for 6D Object Pose Estimation ("BOP-scenewise"; what
each file holds and how mgn's export differs from BlenderProc's: docs/format.md, "BOP export").
``export_bop`` writes::

    OUT/
      camera.json                 fx, fy, cx, cy, width, height (px), depth_scale (mm per unit)
      models/models_info.json     per obj_id: diameter, min_x .. size_z (mm), symmetries
      models/obj_<obj_id:06d>.ply ASCII PLY, mm, vertex normals, texture coordinates
      models/obj_<obj_id:06d>.png the object's texture (when it has one)
      <split>/<scene:06d>/        one mgn scene<N> folder = one BOP scene, one view = one image
        rgb/<im:06d>.png          the view's {v}_rgb.png, byte for byte
        depth/<im:06d>.png        16-bit grey: sensor depth in mm / depth_scale, 0 = no value
        mask/<im:06d>_<gt:06d>.png       amodal mask of annotation gt (0 / 255)
        mask_visib/<im:06d>_<gt:06d>.png visible mask of annotation gt (0 / 255)
        scene_camera.json, scene_gt.json, scene_gt_info.json

The image id is mgn's view index v; annotation gt of an image is mgn's instance gt + 1 of that
view; ``obj_id`` is the object's category id (the ``models/<id>/`` folder of the dataset).
Lengths are millimetres. Every file is written atomically; each scene folder is built under a
temporary name and renamed when complete, so a run that stops leaves only whole scenes, and a
new run skips the scenes already there (and the models already in ``models_info.json``). One
view's images are in memory at a time, with the scene's three JSON documents.
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from PIL import Image

from mgn.base.atomic import atomic_dir, atomic_write_bytes, atomic_write_text
from mgn.errors import InvalidArgumentError, IoError
from mgn.geometry.convex import convex_hull
from mgn.geometry.mesh import Mesh, load_mesh
from mgn.geometry.symmetry import find_symmetries
from mgn.io.dataset import Dataset, SceneFolder, View
from mgn.io.image_codecs import png_bytes
from mgn.io.validate import Problem

__all__ = [
    "DEFAULT_DEPTH_SCALE_MM",
    "DEFAULT_SPLIT",
    "BopExport",
    "export_bop",
    "export_bop_scene",
    "hull_candidates",
    "model_info",
    "model_symmetries",
    "ply_text",
    "validate_bop",
    "vertices_mm",
    "write_bop_models",
]

#: Millimetres per unit of the 16-bit depth PNGs (``depth_scale``): 0.1 mm, as most BOP datasets;
#: depths up to 6.5535 m fit.
DEFAULT_DEPTH_SCALE_MM = 0.1
#: The split folder the scenes go to: ``train_pbr``, BOP's name for synthetic training images.
DEFAULT_SPLIT = "train_pbr"

_M_TO_MM = 1000.0
_CM_TO_MM = 10.0
_SPLIT_RE = re.compile(r"^[A-Za-z0-9_]+$")
_SCENE_DIR_RE = re.compile(r"^\d{6}$")
_MASK_RE = re.compile(r"^(\d{6})_(\d{6})\.png$")
_IMAGE_RE = re.compile(r"^(\d{6})\.png$")
_MODEL_RE = re.compile(r"^obj_(\d{6})\.ply$")
_INFO_KEYS = ("diameter", "min_x", "min_y", "min_z", "size_x", "size_y", "size_z")
_GT_INFO_KEYS = (
    "bbox_obj",
    "bbox_visib",
    "px_count_all",
    "px_count_valid",
    "px_count_visib",
    "visib_fract",
)


@dataclass(frozen=True)
class BopExport:
    """What :func:`export_bop` did: the output folder, the scene ids written and skipped (already
    complete), and whether models were written (False: ``models/`` held every model already)."""

    root: Path
    written: list[int]
    skipped: list[int]
    models_written: bool


def _dump(obj: Any) -> str:
    return json.dumps(obj, indent=1, sort_keys=False) + "\n"


# --- models --------------------------------------------------------------------------------------


def _vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unit vertex normals: the sum of the (area-weighted) normals of the faces at each vertex;
    +z for a vertex of no face or of faces of zero area."""
    tri = vertices[faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])  # length = 2 x area
    acc = np.zeros_like(vertices)
    for c in range(3):
        np.add.at(acc, faces[:, c], n)
    length = np.linalg.norm(acc, axis=1)
    out = np.zeros_like(acc)
    ok = length > 0
    out[ok] = acc[ok] / length[ok, None]
    out[~ok] = (0.0, 0.0, 1.0)
    return out


def vertices_mm(mesh: Mesh) -> npt.NDArray[np.float64]:
    """(V, 3) vertices of ``mesh`` in mm: each float32 coordinate (m) read as its shortest
    decimal (0.0375, not 0.03750000149), times 1000, rounded to 0.1 µm."""
    m = np.asarray(mesh.vertices, np.float32)
    return np.round(m.astype(str).astype(np.float64) * _M_TO_MM, 4)


def ply_text(mesh: Mesh, *, texture_file: str | None = None) -> str:
    """ASCII PLY (format ascii 1.0) of ``mesh`` in **millimetres**: per vertex x, y, z (mm), nx,
    ny, nz (unit, area-weighted face normals) and texture_u, texture_v when the mesh has texture
    coordinates; triangles as ``vertex_indices``. ``texture_file`` is named in a
    ``comment TextureFile`` line as BOP's textured models do."""
    v = vertices_mm(mesh)
    f = np.asarray(mesh.faces, np.int64)
    nrm = _vertex_normals(v, f)
    uvs = mesh.uvs
    has_uv = uvs is not None and len(uvs) == len(v)
    lines = ["ply", "format ascii 1.0", "comment units: millimetres"]
    if texture_file is not None and has_uv:
        lines.append(f"comment TextureFile {texture_file}")
    lines.append(f"element vertex {len(v)}")
    lines += [f"property float {k}" for k in ("x", "y", "z", "nx", "ny", "nz")]
    if has_uv:
        lines += ["property float texture_u", "property float texture_v"]
    lines += [f"element face {len(f)}", "property list uchar int vertex_indices", "end_header"]
    cols = [v, nrm]
    if has_uv:
        cols.append(np.asarray(uvs, np.float32).astype(str).astype(np.float64))
    data = np.hstack(cols)
    body = [" ".join(f"{x:.10g}" for x in row) for row in data]
    body += [f"3 {a} {b} {c}" for a, b, c in f]
    return "\n".join(lines + body) + "\n"


def _diameter(v: np.ndarray) -> float:
    """The largest distance between two of the points ``v`` (exact; blocks of 1024 rows)."""
    best = 0.0
    for i in range(0, len(v), 1024):
        d = np.linalg.norm(v[i : i + 1024, None, :] - v[None, :, :], axis=2)
        best = max(best, float(d.max()))
    return best


def hull_candidates(vertices_mm: npt.ArrayLike, hull: Mesh, *, tol_mm: float = 0.01) -> np.ndarray:
    """The vertices (mm) within ``tol_mm`` of the boundary of ``hull`` (the convex hull of the
    same mesh, in metres): the farthest pair of vertices lies on the hull, so the diameter of
    these equals the model's (up to ``tol_mm``) for a fraction of the pairs."""
    v = np.asarray(vertices_mm, np.float64).reshape(-1, 3)
    hv = np.asarray(hull.vertices, np.float64) * _M_TO_MM
    hf = np.asarray(hull.faces, np.int64)
    n = np.cross(hv[hf[:, 1]] - hv[hf[:, 0]], hv[hf[:, 2]] - hv[hf[:, 0]])
    length = np.linalg.norm(n, axis=1)
    ok = length > 0
    n = n[ok] / length[ok, None]
    d = np.einsum("ij,ij->i", n, hv[hf[ok, 0]])
    keep = np.zeros(len(v), bool)
    for i in range(0, len(v), 4096):
        keep[i : i + 4096] = (v[i : i + 4096] @ n.T - d).max(axis=1) >= -tol_mm
    return v[keep]


def model_info(
    vertices_mm: npt.ArrayLike, *, diameter_points: npt.ArrayLike | None = None
) -> dict[str, float]:
    """``models_info.json`` entry of a model from its vertices (mm): ``diameter`` (the largest
    distance between two vertices) and the axis-aligned box ``min_x``, ``min_y``, ``min_z``,
    ``size_x``, ``size_y``, ``size_z``. ``diameter_points``: the subset of the vertices that
    holds the farthest pair (:func:`hull_candidates`), to find it faster; default all."""
    v = np.asarray(vertices_mm, np.float64).reshape(-1, 3)
    if len(v) == 0:
        raise InvalidArgumentError("model_info: a model without vertices")
    lo, hi = v.min(axis=0), v.max(axis=0)
    pts = v if diameter_points is None else np.asarray(diameter_points, np.float64).reshape(-1, 3)
    return {
        "diameter": _diameter(pts),
        "min_x": float(lo[0]),
        "min_y": float(lo[1]),
        "min_z": float(lo[2]),
        "size_x": float(hi[0] - lo[0]),
        "size_y": float(hi[1] - lo[1]),
        "size_z": float(hi[2] - lo[2]),
    }


def model_symmetries(vertices_mm: npt.ArrayLike, faces: npt.ArrayLike) -> dict[str, Any]:
    """The ``models_info.json`` symmetry keys of a model (vertices in mm) from its shape
    (:func:`mgn.geometry.symmetry.find_symmetries`; the texture is not compared):
    ``symmetries_discrete``, a list of 4 x 4 transforms flattened row-wise (translation in mm),
    and ``symmetries_continuous``, a list of {``axis``, ``offset`` (mm, a point of the axis)};
    each key only when the model has such symmetries. Numbers rounded to 1e-9."""
    sym = find_symmetries(vertices_mm, faces)
    out: dict[str, Any] = {}
    if len(sym.discrete):
        out["symmetries_discrete"] = [[_clean(x) for x in T.reshape(16)] for T in sym.discrete]
    if len(sym.continuous):
        offset = [_clean(x) for x in sym.center]
        out["symmetries_continuous"] = [
            {"axis": [_clean(x) for x in a], "offset": offset} for a in sym.continuous
        ]
    return out


def _clean(x: float) -> float:
    """``x`` rounded to 1e-9, without a negative zero."""
    return float(round(float(x), 9)) + 0.0


def _model_entry(folder: Path, out: Path) -> dict[str, Any]:
    """Write ``obj_<id>.ply`` (and its texture) of the object folder ``models/<id>/`` into
    ``out``; its ``models_info.json`` entry."""
    obj_id = int(folder.name)
    mesh = load_mesh(folder / "textured.obj")
    tex = folder / "texture.png"
    tex_name = f"obj_{obj_id:06d}.png" if tex.exists() else None
    atomic_write_text(out / f"obj_{obj_id:06d}.ply", ply_text(mesh, texture_file=tex_name))
    if tex_name is not None:
        atomic_write_bytes(out / tex_name, tex.read_bytes())
    v = vertices_mm(mesh)
    try:
        pts = hull_candidates(v, convex_hull(mesh))
    except InvalidArgumentError:  # a flat mesh has no hull: every vertex
        pts = v
    return model_info(v, diameter_points=pts) | model_symmetries(
        v, np.asarray(mesh.faces, np.int64)
    )


def write_bop_models(
    dataset: Dataset | str | os.PathLike[str], root: str | os.PathLike[str]
) -> int:
    """Bring ``root/models/`` up to date with the dataset's object folders ``models/<id>/``:
    write the models whose obj_id is not in ``models_info.json`` yet and rewrite that file
    (entries by ascending obj_id), the last step, so that a model is listed only once its
    files are complete. A new folder is built under a temporary name. Returns the number of
    models written (0: up to date). The result does not depend on the order in which the
    models were added."""
    ds = dataset if isinstance(dataset, Dataset) else Dataset(dataset)
    folders = sorted(ds.model_folders(), key=lambda p: int(p.name))
    if not folders:
        raise IoError(f"{ds.root}: no models/<id>/ object folders to export")
    target = Path(root) / "models"
    if not target.exists():
        with atomic_dir(target) as tmp:
            info = {str(int(f.name)): _model_entry(f, tmp) for f in folders}
            atomic_write_text(tmp / "models_info.json", _dump(info))
        return len(folders)
    path = target / "models_info.json"
    try:
        old = json.loads(path.read_text()) if path.exists() else {}
    except (OSError, ValueError) as e:
        raise IoError(
            f"{path}: not readable JSON ({e}); remove the models folder to rewrite it"
        ) from e
    new = [f for f in folders if str(int(f.name)) not in old]
    if not new:
        return 0
    merged = dict(old)
    for f in new:
        merged[str(int(f.name))] = _model_entry(f, target)
    info = {k: merged[k] for k in sorted(merged, key=int)}
    atomic_write_text(path, _dump(info))
    return len(new)


# --- scenes --------------------------------------------------------------------------------------


def _bbox(mask: np.ndarray) -> list[int]:
    """(x, y, width, height) of a mask as the BOP toolkit computes it (width = x_max - x_min,
    so a one-pixel mask has width 0); [-1, -1, -1, -1] for an empty mask."""
    cols = np.flatnonzero(mask.any(axis=0))
    if len(cols) == 0:
        return [-1, -1, -1, -1]
    rows = np.flatnonzero(mask.any(axis=1))
    x0, y0 = int(cols[0]), int(rows[0])
    return [x0, y0, int(cols[-1]) - x0, int(rows[-1]) - y0]


def _K(view: View) -> list[float]:
    intr = view.intrinsics
    if any(c != 0.0 for c in intr.distortion):
        raise InvalidArgumentError(
            f"{view.path('_camera_params.json')}: the view was taken through a lens with "
            "distortion; BOP's cam_K describes a pinhole camera (export views of a camera "
            "without 'distortion')"
        )
    return [intr.fx, 0.0, intr.cx, 0.0, intr.fy, intr.cy, 0.0, 0.0, 1.0]


def _depth_png(view: View, depth_scale: float) -> tuple[bytes, np.ndarray]:
    """The 16-bit depth PNG and its valid pixels (depth value > 0)."""
    mm = view.depth.astype(np.float64) * _M_TO_MM
    valid = np.isfinite(mm) & (mm > 0)
    q = np.zeros(mm.shape, np.float64)
    q[valid] = np.round(mm[valid] / depth_scale)
    top = float(q.max(initial=0.0))
    if top > 65535:
        raise InvalidArgumentError(
            f"{view.path('.npz')}: depth {top * depth_scale:.1f} mm does not fit a 16-bit PNG at "
            f"depth_scale {depth_scale} mm (at most {65535 * depth_scale:.1f} mm): choose a larger "
            "depth_scale"
        )
    valid &= q > 0
    return png_bytes(q.astype(np.uint16)), valid


def _write_view(
    view: View, gt_json: list[dict[str, Any]], tmp: Path, depth_scale: float
) -> tuple[dict[str, Any], list[dict[str, Any]], list[dict[str, Any]]]:
    v = view.index
    K = _K(view)
    X_WC = view.hdf5_dataset("camera/pose_relative_to_world").astype(np.float64).reshape(4, 4)
    X_CW = np.linalg.inv(X_WC)
    camera = {
        "cam_K": K,
        "cam_R_w2c": [float(x) for x in X_CW[:3, :3].ravel()],
        "cam_t_w2c": [float(x) * _M_TO_MM for x in X_CW[:3, 3]],
        "depth_scale": depth_scale,
    }
    atomic_write_bytes(tmp / "rgb" / f"{v:06d}.png", view.path("_rgb.png").read_bytes())
    depth, valid = _depth_png(view, depth_scale)
    atomic_write_bytes(tmp / "depth" / f"{v:06d}.png", depth)
    ids = view.instances
    amodal = view.amodal
    n = amodal.shape[0]
    if len(gt_json) != n:
        raise IoError(
            f"{view.folder / 'scene_gt.json'}: view {v} has {len(gt_json)} entries, its npz "
            f"{n} amodal masks"
        )
    gts: list[dict[str, Any]] = []
    infos: list[dict[str, Any]] = []
    for k in range(n):
        entry = gt_json[k]
        R = np.asarray(entry["cam_R_m2c"], np.float64).reshape(3, 3)
        t = np.asarray(entry["cam_t_m2c"], np.float64).reshape(3) * _CM_TO_MM
        gts.append(
            {
                "cam_R_m2c": [float(x) for x in R.ravel()],
                "cam_t_m2c": [float(x) for x in t],
                "obj_id": int(entry["obj_id"]),
            }
        )
        full = amodal[k]
        visib = ids == k + 1
        name = f"{v:06d}_{k:06d}.png"
        atomic_write_bytes(tmp / "mask" / name, png_bytes(full.astype(np.uint8) * 255))
        atomic_write_bytes(tmp / "mask_visib" / name, png_bytes(visib.astype(np.uint8) * 255))
        n_all = int(full.sum())
        n_vis = int(visib.sum())
        infos.append(
            {
                "bbox_obj": _bbox(full),
                "bbox_visib": _bbox(visib),
                "px_count_all": n_all,
                "px_count_valid": int((full & valid).sum()),
                "px_count_visib": n_vis,
                "visib_fract": n_vis / n_all if n_all > 0 else 0.0,
            }
        )
    return camera, gts, infos


def _write_scene(scene: SceneFolder, target: Path, depth_scale: float) -> None:
    gt = scene.scene_gt
    if gt is None:
        raise IoError(f"{scene.folder}: no scene_gt.json (the object poses of the views)")
    with atomic_dir(target) as tmp:
        for sub in ("rgb", "depth", "mask", "mask_visib"):
            (tmp / sub).mkdir()
        cams: dict[str, Any] = {}
        gts: dict[str, Any] = {}
        infos: dict[str, Any] = {}
        for v in scene.view_ids:  # one View (and its cached arrays) alive at a time
            view = scene.view(v)
            key = str(view.index)
            if key not in gt:
                raise IoError(f"{scene.folder / 'scene_gt.json'}: no entry for view {key}")
            cams[key], gts[key], infos[key] = _write_view(view, gt[key], tmp, depth_scale)
        atomic_write_text(tmp / "scene_camera.json", _dump(cams))
        atomic_write_text(tmp / "scene_gt.json", _dump(gts))
        atomic_write_text(tmp / "scene_gt_info.json", _dump(infos))


def _check_options(split: str, depth_scale: float) -> None:
    if not (isinstance(split, str) and _SPLIT_RE.match(split)):
        raise InvalidArgumentError(
            f"export_bop: split {split!r} must be a folder name of letters, digits and '_'"
        )
    if not (np.isfinite(depth_scale) and depth_scale > 0):
        raise InvalidArgumentError(f"export_bop: depth_scale {depth_scale} must be > 0 (mm)")


def export_bop_scene(
    scene: SceneFolder,
    out: str | os.PathLike[str],
    *,
    split: str = DEFAULT_SPLIT,
    depth_scale: float = DEFAULT_DEPTH_SCALE_MM,
) -> bool:
    """Write one mgn scene folder as the BOP scene ``out/<split>/<N:06d>/`` (built under a
    temporary name, renamed when complete), and ``out/camera.json`` from its first view when
    that file is absent; the models are :func:`write_bop_models`'s. Returns False (and writes
    nothing) when the scene folder is already there. What :func:`export_bop` does per scene:
    ``mgn generate`` with ``output.formats`` containing ``bop`` calls it after each scene.

    Raises:
        IoError, InvalidArgumentError: as :func:`export_bop`.
    """
    _check_options(split, depth_scale)
    root = Path(out)
    target = root / split / f"{scene.scene_id:06d}"
    written = not target.exists()
    if written:
        _write_scene(scene, target, depth_scale)
    if not (root / "camera.json").exists():
        intr = scene.view(scene.view_ids[0]).intrinsics
        cam = {
            "cx": intr.cx,
            "cy": intr.cy,
            "depth_scale": depth_scale,
            "fx": intr.fx,
            "fy": intr.fy,
            "height": intr.height,
            "width": intr.width,
        }
        atomic_write_text(root / "camera.json", _dump(cam))
    return written


def export_bop(
    dataset: str | os.PathLike[str],
    out: str | os.PathLike[str],
    *,
    scenes: Iterable[int] | None = None,
    split: str = DEFAULT_SPLIT,
    depth_scale: float = DEFAULT_DEPTH_SCALE_MM,
    progress: Callable[[int], None] | None = None,
) -> BopExport:
    """Write the BOP layout of ``dataset`` into ``out`` (module doc).

    Args:
        dataset: an mgn dataset folder.
        out: the BOP folder (created; scenes already in it are kept and skipped; models of
            the dataset missing from its ``models/`` are added, :func:`write_bop_models`).
        scenes: mgn scene ids N to export (default: every ``scene<N>``).
        split: the split folder name (letters, digits, ``_``; default ``train_pbr``).
        depth_scale: mm per unit of the depth PNGs, > 0 (default 0.1).
        progress: called with each scene id after it is written or skipped.

    Raises:
        IoError: an unreadable dataset file, a missing scene, or an unwritable output.
        InvalidArgumentError: a bad ``split`` or ``depth_scale``, a depth beyond the 16-bit
            range, a view with lens distortion.
    """
    _check_options(split, depth_scale)
    ds = Dataset(dataset)
    ids = ds.scene_ids if scenes is None else sorted({int(s) for s in scenes})
    missing = [s for s in ids if s not in ds.scene_ids]
    if missing:
        raise IoError(f"{ds.root}: no scene folder for scene ids {missing}")
    if not ids:
        raise IoError(f"{ds.root}: no scene<N> folders to export")
    root = Path(out)
    root.mkdir(parents=True, exist_ok=True)
    models_written = write_bop_models(ds, root) > 0
    written: list[int] = []
    skipped: list[int] = []
    for n in ids:
        if export_bop_scene(ds.scene(n), root, split=split, depth_scale=depth_scale):
            written.append(n)
        else:
            skipped.append(n)
        if progress is not None:
            progress(n)
    return BopExport(root, written, skipped, models_written)


# --- validation ----------------------------------------------------------------------------------


def _load_json(path: Path, root: Path, problems: list[Problem]) -> Any:
    rel = path.relative_to(root).as_posix()
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        problems.append(Problem(rel, "missing"))
    except (OSError, ValueError) as e:
        problems.append(Problem(rel, f"not readable JSON: {e}"))
    return None


def _is_num(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and bool(np.isfinite(x))


def _num_list(x: Any, n: int) -> bool:
    return isinstance(x, list) and len(x) == n and all(_is_num(e) for e in x)


def _is_int(x: Any) -> bool:
    return isinstance(x, int) and not isinstance(x, bool)


def _image(path: Path) -> tuple[str, tuple[int, int]] | None:
    """(PIL mode, (width, height)) of a PNG, None if unreadable."""
    try:
        with Image.open(path) as im:
            if im.format != "PNG":
                return None
            return im.mode, im.size
    except OSError:
        return None


def _check_models(root: Path, problems: list[Problem]) -> dict[int, float | None]:
    models = root / "models"
    if not models.is_dir():
        problems.append(Problem("models", "missing folder"))
        return {}
    info = _load_json(models / "models_info.json", root, problems)
    plys = {int(m.group(1)) for p in models.iterdir() if (m := _MODEL_RE.match(p.name))}
    ids: dict[int, float | None] = {}
    if isinstance(info, dict):
        for key, entry in info.items():
            where = f"models/models_info.json [{key}]"
            if not key.isdigit():
                problems.append(Problem(where, "key must be an integer obj_id"))
                continue
            ids[int(key)] = None
            if not isinstance(entry, dict) or not all(_is_num(entry.get(k)) for k in _INFO_KEYS):
                problems.append(Problem(where, f"needs numbers {', '.join(_INFO_KEYS)} (mm)"))
                continue
            ids[int(key)] = float(entry["diameter"])
            _check_symmetries(where, entry, problems)
            if entry["diameter"] <= 0 or min(entry[k] for k in _INFO_KEYS[4:]) < 0:
                problems.append(Problem(where, "diameter must be > 0 and sizes >= 0 (mm)"))
            elif entry["diameter"] > 10000:
                problems.append(Problem(where, f"diameter {entry['diameter']} mm: not in mm?"))
        for obj_id in sorted(set(ids) - plys):
            problems.append(Problem(f"models/obj_{obj_id:06d}.ply", "missing"))
    elif info is not None:
        problems.append(Problem("models/models_info.json", "must be an object by obj_id"))
    for obj_id in sorted(plys):
        path = models / f"obj_{obj_id:06d}.ply"
        with path.open("rb") as fh:
            head = fh.read(4096)
        if not head.startswith(b"ply\n") or b"element vertex" not in head:
            problems.append(Problem(path.relative_to(root).as_posix(), "not a PLY file"))
    return ids


def _check_symmetries(where: str, entry: dict[str, Any], problems: list[Problem]) -> None:
    """``symmetries_discrete`` (4 x 4 rigid transforms, 16 numbers each) and
    ``symmetries_continuous`` ({axis: unit 3-vector, offset: 3 numbers}), when present."""
    disc = entry.get("symmetries_discrete", [])
    if not isinstance(disc, list) or not all(
        _num_list(T, 16)
        and _is_rotation([T[0], T[1], T[2], T[4], T[5], T[6], T[8], T[9], T[10]])
        and T[12:16] == [0, 0, 0, 1]
        for T in disc
    ):
        problems.append(
            Problem(where, "symmetries_discrete must be 4 x 4 rigid transforms, 16 numbers each")
        )
    cont = entry.get("symmetries_continuous", [])
    if not isinstance(cont, list) or not all(
        isinstance(c, dict)
        and _num_list(c.get("axis"), 3)
        and _num_list(c.get("offset"), 3)
        and abs(float(np.linalg.norm(c["axis"])) - 1.0) <= 1e-3
        for c in cont
    ):
        problems.append(
            Problem(where, "symmetries_continuous must be {axis: unit vector, offset: 3 numbers}")
        )


def _check_camera(root: Path, problems: list[Problem]) -> None:
    cam = _load_json(root / "camera.json", root, problems)
    if cam is None:
        return
    keys = ("cx", "cy", "depth_scale", "fx", "fy", "height", "width")
    if not isinstance(cam, dict) or not all(_is_num(cam.get(k)) for k in keys):
        problems.append(Problem("camera.json", f"needs numbers {', '.join(keys)}"))
    elif not (_is_int(cam["width"]) and _is_int(cam["height"]) and cam["depth_scale"] > 0):
        problems.append(Problem("camera.json", "width, height must be integers, depth_scale > 0"))


Bad = Callable[[str, str], None]


def _check_camera_entry(key: str, cam: Any, bad: Bad) -> bool:
    """One ``scene_camera.json`` entry; False if it cannot be used further."""
    if not isinstance(cam, dict) or not _num_list(cam.get("cam_K"), 9):
        bad("scene_camera.json", f"[{key}] cam_K must be 9 numbers (3 x 3, row-wise)")
        return False
    if not _is_num(cam.get("depth_scale")) or cam["depth_scale"] <= 0:
        bad("scene_camera.json", f"[{key}] depth_scale must be a number > 0 (mm per unit)")
        return False
    if "cam_R_w2c" in cam or "cam_t_w2c" in cam:
        if not (_num_list(cam.get("cam_R_w2c"), 9) and _num_list(cam.get("cam_t_w2c"), 3)):
            bad("scene_camera.json", f"[{key}] cam_R_w2c / cam_t_w2c: 9 and 3 numbers")
        elif not _is_rotation(cam["cam_R_w2c"]):
            bad("scene_camera.json", f"[{key}] cam_R_w2c is not a rotation")
    return True


def _is_rotation(values: list[float]) -> bool:
    R = np.reshape(np.asarray(values, np.float64), (3, 3))
    return bool(np.abs(R @ R.T - np.eye(3)).max() <= 1e-3 and np.linalg.det(R) > 0)


def _check_gt_entry(where: str, e: Any, diameters: dict[int, float | None], bad: Bad) -> bool:
    """One annotation of ``scene_gt.json``; False if it cannot be used further."""
    if not isinstance(e, dict) or not (
        _num_list(e.get("cam_R_m2c"), 9)
        and _num_list(e.get("cam_t_m2c"), 3)
        and _is_int(e.get("obj_id"))
    ):
        bad("scene_gt.json", f"{where} needs cam_R_m2c (9), cam_t_m2c (3, mm), obj_id")
        return False
    if not _is_rotation(e["cam_R_m2c"]):
        bad("scene_gt.json", f"{where} cam_R_m2c is not a rotation")
    if diameters and e["obj_id"] not in diameters:
        bad("scene_gt.json", f"{where} obj_id {e['obj_id']} has no model")
    if not 0 < e["cam_t_m2c"][2] < 100000:
        bad("scene_gt.json", f"{where} cam_t_m2c z {e['cam_t_m2c'][2]}: not mm in front?")
    return True


def _check_info_entry(where: str, i: Any, bad: Bad) -> bool:
    """One annotation of ``scene_gt_info.json``; False if it cannot be used further."""
    if not isinstance(i, dict) or not all(k in i for k in _GT_INFO_KEYS):
        bad("scene_gt_info.json", f"{where} needs {', '.join(_GT_INFO_KEYS)}")
        return False
    ints = ("px_count_all", "px_count_valid", "px_count_visib")
    if not all(_is_int(i[k]) and i[k] >= 0 for k in ints) or not all(
        isinstance(i[k], list) and len(i[k]) == 4 and all(_is_int(x) for x in i[k])
        for k in ("bbox_obj", "bbox_visib")
    ):
        bad("scene_gt_info.json", f"{where} needs integer counts >= 0 and 4-integer boxes")
        return False
    if not _is_num(i["visib_fract"]) or not 0 <= i["visib_fract"] <= 1:
        bad("scene_gt_info.json", f"{where} visib_fract must be in [0, 1]")
    return True


def _check_masks(
    folder: Path, name: str, i: dict[str, Any], size: tuple[int, int], bad: Bad
) -> dict[str, np.ndarray]:
    """The annotation's ``mask`` and ``mask_visib`` (those readable, as bool arrays)."""
    masks: dict[str, np.ndarray] = {}
    for sub, count in (("mask", "px_count_all"), ("mask_visib", "px_count_visib")):
        p = folder / sub / name
        try:
            with Image.open(p) as mim:
                a = np.asarray(mim)
        except FileNotFoundError:
            bad(f"{sub}/{name}", "missing")
            continue
        except OSError as err:
            bad(f"{sub}/{name}", f"not a readable PNG: {err}")
            continue
        if a.ndim != 2 or a.dtype != np.uint8 or a.shape[::-1] != size:
            bad(f"{sub}/{name}", f"must be 8-bit grey {size[0]} x {size[1]}")
            continue
        masks[sub] = a > 0
        px = int(masks[sub].sum())
        if px != i[count]:
            bad(f"{sub}/{name}", f"{px} px, but scene_gt_info has {count} {i[count]}")
    if len(masks) == 2 and (masks["mask_visib"] & ~masks["mask"]).any():
        bad(f"mask_visib/{name}", "visible pixels outside the amodal mask")
    return masks


def _check_units(where: str, tz: float, seen_mm: np.ndarray, diameter: float, bad: Bad) -> None:
    """The depth seen on the object (mm) lies within its diameter of its pose's z (mm)."""
    seen = seen_mm[seen_mm > 0]
    if len(seen) > 0 and abs(float(np.median(seen)) - tz) > diameter:
        bad(
            "scene_gt.json",
            f"{where} cam_t_m2c z {tz:.1f} mm but the depth image (x depth_scale) sees the "
            f"object at {float(np.median(seen)):.1f} mm: are both in mm?",
        )


def _read_depth_mm(folder: Path, im: int, scale: float, size: tuple[int, int], bad: Bad) -> Any:
    """The depth image in mm, None if it is missing or not 16-bit grey of ``size``."""
    path = folder / "depth" / f"{im:06d}.png"
    d = _image(path)
    if d is None:
        bad(f"depth/{im:06d}.png", "missing or not a PNG")
        return None
    if d[0] not in ("I;16", "I;16B", "I") or d[1] != size:
        bad(f"depth/{im:06d}.png", f"must be 16-bit grey {size[0]} x {size[1]}, is {d}")
        return None
    with Image.open(path) as dim:
        return np.asarray(dim, np.float64) * scale


def _check_image(
    folder: Path, key: str, docs: tuple[Any, Any, Any], diameters: dict[int, float | None], bad: Bad
) -> None:
    """One image id of a scene folder: its camera, images, annotations and masks."""
    cam, gt, info = docs
    im = int(key)
    if not _check_camera_entry(key, cam, bad):
        return
    shape = _image(folder / "rgb" / f"{im:06d}.png")
    if shape is None or shape[0] not in ("RGB", "L"):
        bad(f"rgb/{im:06d}.png", "missing or not an 8-bit RGB or grey PNG")
        return
    size = shape[1]
    depth_mm = _read_depth_mm(folder, im, float(cam["depth_scale"]), size, bad)
    if not isinstance(gt, list) or not isinstance(info, list) or len(gt) != len(info):
        bad("scene_gt.json", f"[{key}] scene_gt and scene_gt_info must be lists of one length")
        return
    for g, (e, i) in enumerate(zip(gt, info, strict=True)):
        where = f"[{key}][{g}]"
        gt_ok = _check_gt_entry(where, e, diameters, bad)
        if not _check_info_entry(where, i, bad):
            continue
        masks = _check_masks(folder, f"{im:06d}_{g:06d}.png", i, size, bad)
        diameter = diameters.get(e["obj_id"]) if gt_ok else None
        if depth_mm is not None and "mask_visib" in masks and diameter is not None:
            _check_units(where, e["cam_t_m2c"][2], depth_mm[masks["mask_visib"]], diameter, bad)


def _check_scene_dir(
    folder: Path, root: Path, diameters: dict[int, float | None], problems: list[Problem]
) -> None:
    rel = folder.relative_to(root).as_posix()

    def bad(path: str, msg: str) -> None:
        problems.append(Problem(f"{rel}/{path}", msg))

    docs = [
        _load_json(folder / f"{name}.json", root, problems)
        for name in ("scene_camera", "scene_gt", "scene_gt_info")
    ]
    if not all(isinstance(d, dict) for d in docs):
        if not any(d is None for d in docs):
            bad(".", "scene_camera / scene_gt / scene_gt_info must be objects by image id")
        return
    cams, gts, infos = docs
    if set(cams) != set(gts) or set(gts) != set(infos):
        bad("scene_gt.json", "scene_camera, scene_gt and scene_gt_info name different images")
    for key in sorted(cams, key=lambda s: int(s) if s.isdigit() else -1):
        if not key.isdigit():
            bad("scene_camera.json", f"key {key!r} is not an integer image id")
            continue
        _check_image(folder, key, (cams[key], gts.get(key), infos.get(key)), diameters, bad)
    images = {m.group(1) for p in (folder / "rgb").glob("*.png") if (m := _IMAGE_RE.match(p.name))}
    extra = sorted(int(k) for k in images if str(int(k)) not in cams)
    if extra:
        bad("rgb", f"images {extra} have no scene_camera.json entry")


def validate_bop(
    root: str | os.PathLike[str], *, splits: Sequence[str] | None = None
) -> list[Problem]:
    """Every problem found in the BOP folder ``root`` (an empty list: valid): ``camera.json``;
    ``models/models_info.json`` (diameter and box per obj_id, mm) with a PLY per model; in every
    scene folder ``<split>/<6 digits>/`` the keys, types and units of ``scene_camera.json``,
    ``scene_gt.json`` and ``scene_gt_info.json``, an RGB and a 16-bit depth PNG per image, and
    per annotation an 8-bit ``mask`` and ``mask_visib`` of the image's size whose pixel counts
    are ``px_count_all`` and ``px_count_visib``, the visible mask inside the amodal one.
    ``splits``: the split folders to check (default: every folder holding scene folders)."""
    base = Path(root)
    if not base.is_dir():
        raise IoError(f"validate_bop: '{base}' is not a folder")
    problems: list[Problem] = []
    _check_camera(base, problems)
    diameters = _check_models(base, problems)
    if splits is None:
        names = [
            p.name
            for p in sorted(base.iterdir())
            if p.is_dir() and any(_SCENE_DIR_RE.match(q.name) for q in p.iterdir())
        ]
    else:
        names = list(splits)
    if not names:
        problems.append(Problem(".", "no split folder with scene folders <6 digits>/"))
    for name in names:
        folder = base / name
        if not folder.is_dir():
            problems.append(Problem(name, "missing split folder"))
            continue
        for scene in sorted(p for p in folder.iterdir() if _SCENE_DIR_RE.match(p.name)):
            _check_scene_dir(scene, base, diameters, problems)
    return problems
