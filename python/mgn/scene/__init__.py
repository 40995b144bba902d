"""Scenes: objects dropped into the tote (Bullet), serialisable to JSON.

- :func:`compose_objects`: choose the objects (names, categories x 2-5 copies, or a count).
- :func:`drop_scene`: drop them and let them settle -> :class:`Scene`.
- :class:`Scene`: instances with settled poses ``X_WO`` (tote frame) and tote contacts;
  ``to_json`` / ``from_json``; ``mesh(i)`` gives an instance's mesh back.
- :func:`convex_decomposition`, :func:`convex_hull`, :func:`cached_convex_decomposition`: the
  convex parts the physics uses.
- :func:`compute_layout`: layout labels of a view (relations, layers, order, difficulty) ->
  :class:`Layout`; :func:`read_order_json`, :func:`read_order_csv` read the order files back.

Names are imported on first use, so ``import mgn`` stays light.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

_EXPORTS = {
    "MGN_COPIES": "compose",
    "compose_objects": "compose",
    "ConvexDecompositionOptions": "convex",
    "cache_dir": "convex",
    "cached_convex_decomposition": "convex",
    "convex_decomposition": "convex",
    "convex_hull": "convex",
    "drop_scene": "drop",
    "settle": "drop",
    "settle_tracked": "drop",
    "tote_mesh": "drop",
    "BUILTIN": "scene",
    "CONTACT_NAMES": "scene",
    "DropOptions": "scene",
    "RemovedInstance": "scene",
    "Scene": "scene",
    "SceneInstance": "scene",
    "resolve_object": "scene",
    "BIN_RELATIONS": "layout",
    "Layout": "layout",
    "OrderGraph": "layout",
    "compute_layout": "layout",
    "read_order_csv": "layout",
    "read_order_json": "layout",
    "SceneGraspModel": "scene_grasps",
    "SceneGrasps": "scene_grasps",
    "PjGraspSet": "scene_grasps",
    "SuctionGraspSet": "scene_grasps",
    "GraspGroups": "scene_grasps",
    "PlacedGrasps": "scene_grasps",
    "GraspCollisions": "scene_grasps",
    "DEFAULT_KEYPOINT_TOLERANCE": "view_labels",
    "SceneRayModel": "view_labels",
    "ViewObjectLabels": "view_labels",
    "view_object_labels": "view_labels",
}

__all__ = [
    "BUILTIN",
    "CONTACT_NAMES",
    "ConvexDecompositionOptions",
    "DropOptions",
    "MGN_COPIES",
    "RemovedInstance",
    "Scene",
    "SceneInstance",
    "cache_dir",
    "cached_convex_decomposition",
    "compose_objects",
    "convex_decomposition",
    "convex_hull",
    "drop_scene",
    "settle",
    "settle_tracked",
    "resolve_object",
    "tote_mesh",
    "BIN_RELATIONS",
    "Layout",
    "OrderGraph",
    "compute_layout",
    "read_order_csv",
    "read_order_json",
    "SceneGraspModel",
    "SceneGrasps",
    "PjGraspSet",
    "SuctionGraspSet",
    "GraspGroups",
    "PlacedGrasps",
    "GraspCollisions",
    "DEFAULT_KEYPOINT_TOLERANCE",
    "SceneRayModel",
    "ViewObjectLabels",
    "view_object_labels",
]


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'mgn.scene' has no attribute {name!r}")
    return getattr(importlib.import_module(f"mgn.scene.{module}"), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))


if TYPE_CHECKING:
    from mgn.scene.compose import MGN_COPIES, compose_objects
    from mgn.scene.convex import (
        ConvexDecompositionOptions,
        cache_dir,
        cached_convex_decomposition,
        convex_decomposition,
        convex_hull,
    )
    from mgn.scene.drop import drop_scene, settle, settle_tracked, tote_mesh
    from mgn.scene.layout import (
        BIN_RELATIONS,
        Layout,
        OrderGraph,
        compute_layout,
        read_order_csv,
        read_order_json,
    )
    from mgn.scene.scene import (
        BUILTIN,
        CONTACT_NAMES,
        DropOptions,
        RemovedInstance,
        Scene,
        SceneInstance,
        resolve_object,
    )
    from mgn.scene.scene_grasps import (
        GraspCollisions,
        GraspGroups,
        PjGraspSet,
        PlacedGrasps,
        SceneGraspModel,
        SceneGrasps,
        SuctionGraspSet,
    )
    from mgn.scene.view_labels import (
        DEFAULT_KEYPOINT_TOLERANCE,
        SceneRayModel,
        ViewObjectLabels,
        view_object_labels,
    )
