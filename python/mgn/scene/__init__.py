"""Scenes: objects dropped into the tote (Bullet), serialisable to JSON, and the cameras.

- :func:`compose_objects`: choose the objects (names, categories x 2-5 copies, or a count).
- :func:`drop_scene`: drop them and let them settle -> :class:`Scene`.
- :class:`Scene`: instances with settled poses ``X_WO`` (tote frame) and tote contacts;
  ``to_dict`` / ``from_dict`` (the file: :mod:`mgn.io.scene_json`); ``mesh(i)`` gives an
  instance's mesh back.
- :mod:`mgn.scene.cameras`: :class:`Intrinsics`, :class:`CameraView`, the 37-view MetaGraspNet rig
  (:func:`mgn_rig`), hemisphere rigs, :func:`look_at`.
- :mod:`mgn.scene.lens`: the OpenCV lens-distortion model and the resampling of pinhole renders
  (:func:`lens_for`, :class:`Lens`).

Names are imported on first use, so ``import mgn`` stays light.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mgn.base.lazy import lazy_exports

_EXPORTS = {
    "MGN_COPIES": "compose",
    "compose_objects": "compose",
    "drop_scene": "drop",
    "settle": "drop",
    "settle_tracked": "drop",
    "BUILTIN": "scene",
    "CONTACT_NAMES": "scene",
    "DropOptions": "scene",
    "RemovedInstance": "scene",
    "Scene": "scene",
    "SceneInstance": "scene",
    "resolve_object": "scene",
    "CameraView": "cameras",
    "Intrinsics": "cameras",
    "MgnRigParams": "cameras",
    "hemisphere_rig": "cameras",
    "look_at": "cameras",
    "mgn_rig": "cameras",
    "mgn_rig_from_params": "cameras",
    "mgn_views": "cameras",
    "Lens": "lens",
    "lens_for": "lens",
}

__all__ = [
    "BUILTIN",
    "CONTACT_NAMES",
    "MGN_COPIES",
    "CameraView",
    "DropOptions",
    "Intrinsics",
    "Lens",
    "MgnRigParams",
    "RemovedInstance",
    "Scene",
    "SceneInstance",
    "compose_objects",
    "drop_scene",
    "hemisphere_rig",
    "lens_for",
    "look_at",
    "mgn_rig",
    "mgn_rig_from_params",
    "mgn_views",
    "resolve_object",
    "settle",
    "settle_tracked",
]


__getattr__, __dir__ = lazy_exports("mgn.scene", _EXPORTS, globals())


if TYPE_CHECKING:
    from mgn.scene.cameras import (
        CameraView,
        Intrinsics,
        MgnRigParams,
        hemisphere_rig,
        look_at,
        mgn_rig,
        mgn_rig_from_params,
        mgn_views,
    )
    from mgn.scene.compose import MGN_COPIES, compose_objects
    from mgn.scene.drop import drop_scene, settle, settle_tracked
    from mgn.scene.lens import Lens, lens_for
    from mgn.scene.scene import (
        BUILTIN,
        CONTACT_NAMES,
        DropOptions,
        RemovedInstance,
        Scene,
        SceneInstance,
        resolve_object,
    )
