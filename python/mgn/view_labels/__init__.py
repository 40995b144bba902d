"""Per-view labels of a settled scene, as arrays (no files; :mod:`mgn.io` writes them).

- :mod:`mgn.view_labels.objects`: :class:`SceneRayModel`, :func:`view_object_labels` (masks,
  occlusion, boxes, poses, keypoints, CoM heat map of each object in a view).
- :mod:`mgn.view_labels.layout`: :func:`compute_layout` (relations, layers, picking order,
  difficulty) -> :class:`Layout` (its files are read back by :mod:`mgn.io.order_files`).
- :mod:`mgn.view_labels.grasps`: :class:`SceneGraspModel`, the object grasps placed at the settled
  poses and collision-checked once per scene.

Names are imported on first use, so ``import mgn`` stays light.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mgn.base.lazy import lazy_exports

_EXPORTS = {
    "BIN_RELATIONS": "layout",
    "Layout": "layout",
    "compute_layout": "layout",
    "SceneGraspModel": "grasps",
    "SceneGrasps": "grasps",
    "PjGraspSet": "grasps",
    "SuctionGraspSet": "grasps",
    "GraspGroups": "grasps",
    "PlacedGrasps": "grasps",
    "GraspCollisions": "grasps",
    "DEFAULT_KEYPOINT_TOLERANCE": "objects",
    "SceneRayModel": "objects",
    "ViewObjectLabels": "objects",
    "view_object_labels": "objects",
    "distort_view_object_labels": "objects",
}

__all__ = [
    "BIN_RELATIONS",
    "DEFAULT_KEYPOINT_TOLERANCE",
    "GraspCollisions",
    "GraspGroups",
    "Layout",
    "PjGraspSet",
    "PlacedGrasps",
    "SceneGraspModel",
    "SceneGrasps",
    "SceneRayModel",
    "SuctionGraspSet",
    "ViewObjectLabels",
    "compute_layout",
    "distort_view_object_labels",
    "view_object_labels",
]


__getattr__, __dir__ = lazy_exports("mgn.view_labels", _EXPORTS, globals())


if TYPE_CHECKING:
    from mgn.view_labels.grasps import (
        GraspCollisions,
        GraspGroups,
        PjGraspSet,
        PlacedGrasps,
        SceneGraspModel,
        SceneGrasps,
        SuctionGraspSet,
    )
    from mgn.view_labels.layout import (
        BIN_RELATIONS,
        Layout,
        compute_layout,
    )
    from mgn.view_labels.objects import (
        DEFAULT_KEYPOINT_TOLERANCE,
        SceneRayModel,
        ViewObjectLabels,
        distort_view_object_labels,
        view_object_labels,
    )
