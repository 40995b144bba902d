"""Export a scene to glTF binary (``.glb``) for any 3-D viewer: ``mgn scene export``.

The file holds one node per object instance (named ``<instance id>_<object name>``, its mesh in
the object frame and the node's matrix = ``X_WO``), the tote (node ``tote``, identity), one
node per camera (``camera_<view>``: a small frustum pyramid whose node matrix is ``X_WC``, the
OpenCV camera frame, apex at the optical centre and the base towards +z) and, when asked, the
best ``top_k`` grasps of every object: the suction cup body or the parallel-jaw hand at the
grasp pose (``grasp_<kind>_<instance>_<rank>``), coloured by score from red (0) to green (1).

Grasps come from the per-object labels (the same cached labels ``mgn generate`` uses), placed
with the instance pose; they are not checked against the other objects (the scene grasp labels
of a labelled view are). All lengths in metres, the world frame is the tote frame (z up); glTF's
own convention (y up) is not applied, so viewers show the scene lying on its side unless they
offer z-up.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn.errors import InvalidArgumentError, UnsupportedError
from mgn.hardware import normalize_grasp_kind

__all__ = ["export_scene_glb", "score_colors"]


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
    t = trimesh.Trimesh(np.asarray(vertices, np.float64), np.asarray(faces, np.int64),
                        process=False)  # fmt: skip
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


def _suction_frames(points: np.ndarray, approach: np.ndarray) -> np.ndarray:
    """(N, 4, 4) frames at the contact points with +z along the approach (into the surface)."""
    z = approach / np.linalg.norm(approach, axis=1, keepdims=True)
    helper = np.where(np.abs(z[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    y = np.cross(z, x)
    X = np.tile(np.eye(4), (len(points), 1, 1))
    X[:, :3, 0], X[:, :3, 1], X[:, :3, 2], X[:, :3, 3] = x, y, z, points
    return X


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
        views: (view index, :class:`mgn.render.CameraView`) of the cameras to draw.
        grasps: None, ``"suction"`` or ``"paralleljaw"``: also draw the ``top_k`` best grasps
            of every instance (object labels, computed or read from the label cache).
        top_k: grasps per instance (>= 1).
        config: the :class:`mgn.config.Config` giving the cup, gripper and label sizes
            (default: the MetaGraspNet defaults).
        num_threads: C++ threads for labels that are not cached yet (0 = all cores).

    Returns:
        Counts of the nodes written: ``objects``, ``cameras``, ``grasps``, ``nodes`` (all,
        including the tote).

    Raises:
        InvalidArgumentError: an unknown grasp kind, ``top_k`` < 1 or a path not ending in .glb.
    """
    from mgn.io.atomic import atomic_write_bytes
    from mgn.render.views import tote_mesh

    trimesh = _trimesh()
    out = Path(path)
    if out.suffix.lower() != ".glb":
        raise InvalidArgumentError(f"export_scene_glb: '{out}' must end in .glb")
    kind = None if grasps is None else normalize_grasp_kind(grasps)
    if isinstance(top_k, bool) or int(top_k) < 1:
        raise InvalidArgumentError(f"export_scene_glb: top_k must be >= 1, got {top_k!r}")
    tm_scene = trimesh.Scene(base_frame="world")
    tm_scene.add_geometry(_tm(*_arrays(tote_mesh(scene.tote)), scene.tote.color), node_name="tote",
                          geom_name="tote", parent_node_name="world")  # fmt: skip
    geoms: dict[tuple[str, str], Any] = {}
    for i, inst in enumerate(scene.instances):
        key = (inst.name, inst.source)
        if key not in geoms:
            spec = scene.object_spec(i)
            geoms[key] = _tm(spec.vertices, spec.faces, spec.material.base_color)
        tm_scene.add_geometry(geoms[key], node_name=f"{inst.instance_id}_{inst.name}",
                              geom_name=inst.name, transform=np.asarray(inst.X_WO),
                              parent_node_name="world")  # fmt: skip
    for v, cam in views:
        tm_scene.add_geometry(_tm(*_frustum(cam.K), (0.1, 0.1, 0.1, 1.0)), node_name=f"camera_{v}",
                              geom_name=f"camera_{v}", transform=np.asarray(cam.X_WC),
                              parent_node_name="world")  # fmt: skip
    num_grasps = 0
    if kind is not None and len(scene):
        num_grasps = _add_grasps(tm_scene, scene, kind, int(top_k), config, num_threads)
    data = tm_scene.export(file_type="glb")
    atomic_write_bytes(out, data)
    return {
        "objects": len(scene),
        "cameras": len(views),
        "grasps": num_grasps,
        "nodes": 1 + len(scene) + len(views) + num_grasps,
    }


def _add_grasps(tm_scene: Any, scene: Any, kind: str, top_k: int, config: Any,
                num_threads: int) -> int:  # fmt: skip
    import dataclasses

    from mgn.config import Config
    from mgn.pipeline.label_cache import object_labels

    cfg = config if config is not None else Config()
    labels_cfg = dataclasses.replace(
        cfg.labels, suction=kind == "suction", paralleljaw=kind == "paralleljaw", pj_physics=False
    )
    cfg = dataclasses.replace(cfg, labels=labels_cfg)
    cache: dict[tuple[str, str], Any] = {}
    count = 0
    for i, inst in enumerate(scene.instances):
        key = (inst.name, inst.source)
        if key not in cache:
            cache[key] = object_labels(scene.object_spec(i), cfg, num_threads=num_threads)
        got = cache[key]
        X_WO = np.asarray(inst.X_WO)
        if kind == "suction":
            lab = got.suction
            order = np.argsort(-lab.score, kind="stable")[:top_k]
            frames = _suction_frames(np.asarray(lab.points, np.float64)[order],
                                     np.asarray(lab.approach, np.float64)[order])  # fmt: skip
            body = _cup_body(cfg.cup.outer_radius, cfg.cup.body_height)
            for rank, (X_OG, c) in enumerate(zip(frames, score_colors(lab.score[order]),
                                                 strict=True)):  # fmt: skip
                g = body.copy()
                g.visual = trimesh_colors(g, c)
                tm_scene.add_geometry(g, node_name=f"grasp_suction_{inst.instance_id}_{rank}",
                                      transform=X_WO @ X_OG, parent_node_name="world")  # fmt: skip
                count += 1
        else:
            from mgn.pj.sampler import gripper_meshes, hand_poses

            lab = got.paralleljaw
            score = np.asarray(lab.quality_score, np.float64)
            order = np.argsort(-score, kind="stable")[:top_k]
            X_OH = hand_poses(lab.p1[order], lab.closing[order], lab.approach[order],
                              lab.width[order], cfg.gripper)  # fmt: skip
            for rank, k in enumerate(order):
                opening = min(float(lab.width[k]) + cfg.gripper.collision_margin,
                              cfg.gripper.max_opening)  # fmt: skip
                parts = gripper_meshes(cfg.gripper, opening)
                color = score_colors(score[k : k + 1])[0]
                v = np.concatenate([_arrays(p)[0] for p in parts])
                offs = np.cumsum([0] + [len(p.vertices) for p in parts[:-1]])
                f = np.concatenate(
                    [np.asarray(p.faces) + o for p, o in zip(parts, offs, strict=True)]
                )
                tm_scene.add_geometry(
                    _tm(v, f, color),
                    node_name=f"grasp_paralleljaw_{inst.instance_id}_{rank}",
                    transform=X_WO @ X_OH[rank],
                    parent_node_name="world",
                )
                count += 1
    return count


def trimesh_colors(mesh: Any, rgba: npt.NDArray[np.uint8]) -> Any:
    """Face colours of ``mesh`` all set to ``rgba``."""
    trimesh = _trimesh()
    return trimesh.visual.ColorVisuals(mesh, face_colors=np.tile(rgba, (len(mesh.faces), 1)))
