"""Export a scene to glTF binary (``.glb``) for any 3-D viewer: ``mgn scene export``.

The file holds one node per object instance (named ``<instance id>_<object name>``, its mesh in
the object frame and the node's matrix = ``X_WO``), the tote (node ``tote``, identity), one
node per camera (``camera_<view>``: a small frustum pyramid whose node matrix is ``X_WC``, the
OpenCV camera frame, apex at the optical centre and the base towards +z) and, when asked, the
best ``top_k`` grasps of every object: the suction cup body or the parallel-jaw hand at the
grasp pose (``grasp_<kind>_<instance>_<rank>``), coloured by score from red (0) to green (1).
Every node hangs under the node ``tote_frame``, whose matrix turns the tote frame (z up) into
glTF's y-up world (:data:`X_GLTF_TOTE`), so viewers show the tote upright; a node's matrix
relative to ``tote_frame`` is the pose in the tote frame.

Grasps come from the per-object labels (the same cached labels ``mgn generate`` uses), placed
with the instance pose and kept only when the tool is collision-free in the scene, under the
same collision model as the scene grasp labels
(:class:`mgn.view_labels.grasps.SceneGraspModel`); the best ``top_k`` of each object by analytic
score are drawn (fewer when fewer are free). All lengths in metres.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn.base.atomic import atomic_write_bytes
from mgn.errors import InvalidArgumentError, UnsupportedError
from mgn.hardware import normalize_grasp_kind
from mgn.objects import tote_mesh
from mgn.pipeline.config import Config
from mgn.pipeline.label_cache import object_labels
from mgn.pj.sampler import gripper_meshes
from mgn.view_labels.grasps import SceneGraspModel

__all__ = ["X_GLTF_TOTE", "export_scene_glb", "score_colors"]

#: The tote frame (z up) in glTF's world (y up, z towards the viewer): x -> x, z -> y, y -> -z.
X_GLTF_TOTE = np.array(
    [[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, -1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
)


def score_colors(score: npt.ArrayLike) -> npt.NDArray[np.uint8]:
    """(N, 4) RGBA uint8 colours of scores in [0, 1]: red (0) through yellow to green (1)."""
    s = np.clip(np.nan_to_num(np.asarray(score, np.float64), nan=0.0), 0.0, 1.0)
    r = np.where(s < 0.5, 1.0, 2.0 * (1.0 - s))
    g = np.where(s < 0.5, 2.0 * s, 1.0)
    rgba = np.stack([r, g, np.full_like(s, 0.1), np.ones_like(s)], axis=-1)
    return np.round(rgba * 255).astype(np.uint8)


def _trimesh() -> Any:
    try:
        import trimesh
    except ImportError as e:  # pragma: no cover (a declared dependency)
        raise UnsupportedError(
            "mgn scene export needs trimesh (pip install trimesh) to write glTF"
        ) from e
    return trimesh


def _tm(vertices: npt.ArrayLike, faces: npt.ArrayLike, rgba: Sequence[float]) -> Any:
    """A trimesh with every face coloured ``rgba`` (floats in [0, 1] or uint8)."""
    trimesh = _trimesh()
    color = np.asarray(rgba)
    if color.dtype != np.uint8:
        color = np.round(np.clip(color.astype(np.float64), 0, 1) * 255).astype(np.uint8)
    t = trimesh.Trimesh(
        np.asarray(vertices, np.float64), np.asarray(faces, np.int64), process=False
    )
    t.visual = trimesh_colors(t, color)
    return t


def _arrays(mesh: Any) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64)


def _frustum(K: Any, depth: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    """A pyramid: apex at the optical centre, base = the image corners at z = depth (m)."""
    corners = np.array([[0, 0], [K.width, 0], [K.width, K.height], [0, K.height]], np.float64)
    x = (corners[:, 0] - K.cx) / K.fx * depth
    y = (corners[:, 1] - K.cy) / K.fy * depth
    v = np.vstack([[0.0, 0.0, 0.0], np.column_stack([x, y, np.full(4, depth)])])
    f = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1], [1, 3, 2], [1, 4, 3]], np.int64)
    return v, f


def _cup_body(radius: float, height: float) -> Any:
    """The cup body: a cylinder from the contact (z = 0) back along -z (the approach is +z)."""
    trimesh = _trimesh()
    c = trimesh.creation.cylinder(radius=radius, height=height, sections=24)
    c.apply_translation([0.0, 0.0, -height / 2.0])
    return c


def export_scene_glb(
    scene: Any,
    path: str | os.PathLike[str],
    *,
    views: Sequence[tuple[int, Any]] = (),
    grasps: str | None = None,
    top_k: int = 5,
    config: Any = None,
    num_threads: int = 0,
) -> dict[str, int]:
    """Write ``scene`` (a :class:`mgn.scene.Scene`) as a ``.glb`` file (see the module doc).

    Args:
        scene: the scene (instances, poses X_WO in the tote frame, tote).
        path: the output file (``.glb``).
        views: (view index, :class:`mgn.scene.cameras.CameraView`) of the cameras to draw.
        grasps: None, ``"suction"`` or ``"paralleljaw"``: also draw the ``top_k`` best grasps
            of every instance (object labels, computed or read from the label cache).
        top_k: grasps per instance (>= 1).
        config: the :class:`mgn.pipeline.config.Config` giving the cup, gripper and label sizes
            (default: the MetaGraspNet defaults).
        num_threads: C++ threads for labels that are not cached yet (0 = all cores).

    Returns:
        Counts of the nodes written: ``objects``, ``cameras``, ``grasps``, ``nodes`` (all,
        including the tote).

    Raises:
        InvalidArgumentError: an unknown grasp kind, ``top_k`` < 1 or a path not ending in .glb.
    """

    trimesh = _trimesh()
    out = Path(path)
    if out.suffix.lower() != ".glb":
        raise InvalidArgumentError(f"export_scene_glb: '{out}' must end in .glb")
    kind = None if grasps is None else normalize_grasp_kind(grasps)
    if isinstance(top_k, bool) or int(top_k) < 1:
        raise InvalidArgumentError(f"export_scene_glb: top_k must be >= 1, got {top_k!r}")
    tm_scene = trimesh.Scene(base_frame="world")
    tm_scene.graph.update(frame_from="world", frame_to="tote_frame", matrix=X_GLTF_TOTE)
    tm_scene.add_geometry(
        _tm(*_arrays(tote_mesh(scene.tote)), scene.tote.color),
        node_name="tote",
        geom_name="tote",
        parent_node_name="tote_frame",
    )
    geoms: dict[tuple[str, str], Any] = {}
    for i, inst in enumerate(scene.instances):
        key = (inst.name, inst.source)
        if key not in geoms:
            spec = scene.object_spec(i)
            geoms[key] = _tm(spec.vertices, spec.faces, spec.material.base_color)
        tm_scene.add_geometry(
            geoms[key],
            node_name=f"{inst.instance_id}_{inst.name}",
            geom_name=inst.name,
            transform=np.asarray(inst.X_WO),
            parent_node_name="tote_frame",
        )
    for v, cam in views:
        tm_scene.add_geometry(
            _tm(*_frustum(cam.K), (0.1, 0.1, 0.1, 1.0)),
            node_name=f"camera_{v}",
            geom_name=f"camera_{v}",
            transform=np.asarray(cam.X_WC),
            parent_node_name="tote_frame",
        )
    num_grasps = 0
    if kind is not None and len(scene):
        num_grasps = _add_grasps(tm_scene, scene, kind, int(top_k), config, num_threads)
    data = tm_scene.export(file_type="glb")
    atomic_write_bytes(out, data)
    return {
        "objects": len(scene),
        "cameras": len(views),
        "grasps": num_grasps,
        "nodes": 2 + len(scene) + len(views) + num_grasps,
    }


def _add_grasps(
    tm_scene: Any, scene: Any, kind: str, top_k: int, config: Any, num_threads: int
) -> int:

    cfg = config if config is not None else Config()
    labels_cfg = dataclasses.replace(
        cfg.labels, suction=kind == "suction", paralleljaw=kind == "paralleljaw", pj_physics=False
    )
    cfg = dataclasses.replace(cfg, labels=labels_cfg)
    cache: dict[tuple[str, str], Any] = {}
    got = []
    for i, inst in enumerate(scene.instances):
        key = (inst.name, inst.source)
        if key not in cache:
            cache[key] = object_labels(scene.object_spec(i), cfg, num_threads=num_threads)
        got.append(cache[key])
    pj = [g.paralleljaw for g in got] if kind == "paralleljaw" else [None] * len(got)
    su = [g.suction for g in got] if kind == "suction" else [None] * len(got)
    model = SceneGraspModel(scene, pj, su, cfg.gripper, cfg.cup, num_threads=num_threads)
    placed = model.pj if kind == "paralleljaw" else model.suction
    body = _cup_body(cfg.cup.outer_radius, cfg.cup.body_height)
    count = 0
    for i, inst in enumerate(scene.instances):
        mine = np.nonzero((placed.object_id == i) & ~placed.colliding)[0]
        score = np.nan_to_num(np.asarray(placed.score_analytical, np.float64)[mine], nan=0.0)
        best = mine[np.argsort(-score, kind="stable")[:top_k]]
        colors = score_colors(np.nan_to_num(placed.score_analytical[best], nan=0.0))
        for rank, (k, color) in enumerate(zip(best, colors, strict=True)):
            name = f"grasp_{kind}_{inst.instance_id}_{rank}"
            if kind == "suction":
                g = body.copy()
                g.visual = trimesh_colors(g, color)
                X = placed.contact_poses[k]  # z into the surface; the body lies along -z
            else:
                opening = min(
                    float(placed.width[k]) + cfg.gripper.collision_margin, cfg.gripper.max_opening
                )
                parts = gripper_meshes(cfg.gripper, opening)
                v = np.concatenate([_arrays(p)[0] for p in parts])
                offs = np.cumsum([0] + [len(p.vertices) for p in parts[:-1]])
                f = np.concatenate(
                    [np.asarray(p.faces) + o for p, o in zip(parts, offs, strict=True)]
                )
                g = _tm(v, f, color)
                X = placed.tool_poses[k]  # the hand (flange) pose X_WH
            tm_scene.add_geometry(
                g, node_name=name, transform=np.asarray(X), parent_node_name="tote_frame"
            )
            count += 1
    return count


def trimesh_colors(mesh: Any, rgba: npt.NDArray[np.uint8]) -> Any:
    """Face colours of ``mesh`` all set to ``rgba``."""
    trimesh = _trimesh()
    return trimesh.visual.ColorVisuals(mesh, face_colors=np.tile(rgba, (len(mesh.faces), 1)))
