"""Per-view object labels (docs/models.md §7): masks, occlusion, boxes, poses, keypoints, CoM map.

Build a :class:`SceneRayModel` once per scene (Embree scenes of every object alone, and of all
objects with the tote), then call :func:`view_object_labels` for each rendered view with the
view's instance image (``ViewImages.instance_ids``).

Frames and units: the world W is the tote frame (metres); the camera frame C is OpenCV (x right,
y down, z forward); ``X_AB`` is the (4, 4) pose of B in A. Pixel (u, v) is the ray through the
image point (u + 0.5, v + 0.5), the same model as the renderer and
:meth:`mgn.scene.cameras.CameraView.rays`. The object axis of every per-object array has length
N = ``len(scene.instances)`` in scene order: row i is instance id i + 1, including objects not
seen in the view (their masks are empty, their occlusion is 1).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.base.core_result import from_core
from mgn.errors import InvalidArgumentError, InvalidTypeError
from mgn.geometry.mesh import Mesh, mass_properties
from mgn.objects import com_keypoints, tote_mesh
from mgn.scene.cameras import CameraView
from mgn.scene.lens import Lens
from mgn.scene.scene import Scene

__all__ = [
    "DEFAULT_KEYPOINT_TOLERANCE",
    "SceneRayModel",
    "ViewObjectLabels",
    "distort_view_object_labels",
    "round_occlusion",
    "seen_objects",
    "view_object_labels",
]

#: A keypoint is visible when nothing lies on the ray from the camera centre closer than its
#: distance minus this tolerance, m (absorbs float32 geometry and points sampled on the surface).
DEFAULT_KEYPOINT_TOLERANCE = 0.002


@dataclass(frozen=True)
class ViewObjectLabels:
    """Object labels of one view (SI units: metres; images (H, W) top row first).

    Attributes:
        instance_ids: (N,) int32 instance ids 1..N.
        category_ids: (N,) int32 category id of each instance.
        visible: (H, W) int32 visible instance mask, 0 = background / tote / floor, else i + 1.
        semantic: (H, W) int32 category id of the visible object, 0 = background.
        amodal: (N, H, W) bool, object i alone (every other object and the tote ignored): the
            pixels whose centre ray hits it, united with its visible pixels (so it always
            contains the visible mask).
        visible_pixels, amodal_pixels: (N,) int64 pixel counts.
        occlusion: (N,) float64 occlusion rate 1 - visible / amodal in [0, 1] (1.0 when the
            amodal mask is empty); every occluder counts, the tote included.
        occlusion_map: (H, W) float32, each visible pixel carries its object's occlusion rate.
        bbox_tight: (N, 4) int32 COCO [x, y, w, h] px of the visible mask (zeros when empty).
        bbox_loose: (N, 4) int32 COCO [x, y, w, h] px of the amodal mask (zeros when empty).
        X_CO: (N, 4, 4) float64 object poses in the camera frame, ``X_WC^-1 X_WO``.
        keypoints: (P, 4) float64 visible semantic keypoints [id, x, y, z], camera frame, m.
        keypoint_object: (P,) int32 object index (instance id - 1) of each row.
        occluded_keypoints: (P', 4) float64 the other semantic keypoints (hidden, behind the
            camera or outside the image), same layout.
        occluded_keypoint_object: (P',) int32.
        com_points: (Q, 4) float64 every CoM-scored surface point [score, x, y, z], camera
            frame, m, object by object (1000 per object).
        com_object: (Q,) int32 object index of each CoM point.
        com_visible: (Q,) bool, the point is visible (same test as the semantic keypoints).
        com_heatmap: (H, W) float32 in [0, 1]: the CoM score of the surface seen at each visible
            pixel. For a visible pixel of object i whose centre ray first hits object i at x
            (world; with a depth image, x is the pixel's back-projected depth point),
            ``clamp((d_max - |x - c|) / (d_max - d_min), 0, 1)`` with c the centre of mass and
            d_min, d_max the smallest and largest distance of its CoM-scored points to c (the
            score of ``mgn.objects.com_keypoints``); 0 on background, on edge pixels
            where the ray misses the object and on pixels without a valid depth.
    """

    instance_ids: npt.NDArray[np.int32]
    category_ids: npt.NDArray[np.int32]
    visible: npt.NDArray[np.int32]
    semantic: npt.NDArray[np.int32]
    amodal: npt.NDArray[np.bool_]
    visible_pixels: npt.NDArray[np.int64]
    amodal_pixels: npt.NDArray[np.int64]
    occlusion: npt.NDArray[np.float64]
    occlusion_map: npt.NDArray[np.float32]
    bbox_tight: npt.NDArray[np.int32]
    bbox_loose: npt.NDArray[np.int32]
    X_CO: npt.NDArray[np.float64]
    keypoints: npt.NDArray[np.float64]
    keypoint_object: npt.NDArray[np.int32]
    occluded_keypoints: npt.NDArray[np.float64]
    occluded_keypoint_object: npt.NDArray[np.int32]
    com_points: npt.NDArray[np.float64]
    com_object: npt.NDArray[np.int32]
    com_visible: npt.NDArray[np.bool_]
    com_heatmap: npt.NDArray[np.float32]

    @property
    def num_objects(self) -> int:
        return int(self.instance_ids.shape[0])


class SceneRayModel:
    """Ray-tracing model of one scene, built once and reused for all its views.

    Holds one Embree scene per object (for its amodal mask) and one of all objects and the tote
    (for keypoint visibility). Immutable; thread-safe.

    Build it from a :class:`~mgn.scene.Scene` with :meth:`from_scene`, or from explicit parts
    with the constructor.

    Args:
        meshes: N object-frame meshes.
        poses: (N, 4, 4) object poses ``X_WO`` in the world (tote frame), m.
        category_ids: N category ids (>= 1).
        keypoints: per object a (K_i, 4) array [id, x, y, z] of semantic keypoints, object frame,
            m; None for none.
        com_points: per object a (Q_i, 4) array [score, x, y, z] of CoM-scored surface points,
            object frame, m; None for none.
        coms: (N, 3) centres of mass, object frame, m; None = the mass centre of each mesh at
            uniform density.
        tote: tote mesh (an occluder of keypoints only) or None.
        X_W_tote: (4, 4) tote pose in the world (default identity).
    """

    def __init__(
        self,
        meshes: list[Mesh],
        poses: npt.ArrayLike,
        category_ids: list[int] | npt.ArrayLike,
        *,
        keypoints: Sequence[npt.ArrayLike] | None = None,
        com_points: Sequence[npt.ArrayLike] | None = None,
        coms: npt.ArrayLike | None = None,
        tote: Mesh | None = None,
        X_W_tote: npt.ArrayLike | None = None,
    ) -> None:
        meshes = list(meshes)
        n = len(meshes)
        if n == 0:
            raise InvalidArgumentError(
                "SceneRayModel: the scene has no objects; expected at least one"
            )
        P = np.asarray(poses, np.float64).reshape(-1, 4, 4)
        cats = np.asarray(category_ids, np.int64).reshape(-1)

        def rows4(items: Sequence[npt.ArrayLike] | None, name: str) -> list[np.ndarray]:
            if items is None:
                return [np.zeros((0, 4))] * n
            out = [np.asarray(k, np.float64).reshape(-1, 4) for k in items]
            if len(out) != n:
                raise InvalidArgumentError(
                    f"SceneRayModel: {name} has {len(out)} entries; expected one per mesh ({n})"
                )
            return out

        kp = rows4(keypoints, "keypoints")
        cp = rows4(com_points, "com_points")
        if coms is None:
            c = np.stack([mass_properties(m).center_of_mass for m in meshes])
        else:
            c = np.asarray(coms, np.float64).reshape(-1, 3)
        self._meshes = meshes
        self._tote = tote
        self._category_ids = cats.astype(np.int32)
        self._com_parameters = _com_parameters(P, c, cp, meshes)
        self._model = _core.scene.ViewLabelModel(
            meshes,
            P,
            [int(x) for x in cats],
            kp,
            cp,
            c,
            tote,
            None if X_W_tote is None else np.asarray(X_W_tote, np.float64),
        )

    @classmethod
    def from_scene(cls, scene: Scene, *, tote: bool = True) -> SceneRayModel:
        """The model of a :class:`~mgn.scene.Scene`: every instance's mesh at its ``X_WO``, its
        category, semantic keypoints (``ObjectSpec.keypoints``), its 1000 CoM-scored points
        (:func:`mgn.objects.com_keypoints` with the object-folder seed, the category
        id) and centre of mass at the object's density; the tote (world = tote frame) when
        ``tote`` is True. Objects repeated in the scene are prepared once."""

        if not isinstance(scene, Scene):  # a runtime check for callers without a type checker
            raise InvalidTypeError(f"from_scene expects a Scene, got {type(scene).__name__}")
        if len(scene.instances) == 0:
            raise InvalidArgumentError(
                "SceneRayModel.from_scene: the scene has no objects; expected at least one"
            )
        cache: dict[tuple[str, str], tuple[Mesh, np.ndarray, np.ndarray, np.ndarray]] = {}
        meshes, kps, cps, coms = [], [], [], []
        for i, inst in enumerate(scene.instances):
            key = (inst.name, inst.source)
            if key not in cache:
                spec = scene.object_spec(i)
                mesh = scene.mesh(i)
                kp = np.array([[k.id, *k.position] for k in spec.keypoints], np.float64)
                com = mass_properties(mesh, spec.density).center_of_mass
                cp = com_keypoints(mesh, spec.density, seed=spec.category_id)
                cache[key] = (mesh, kp.reshape(-1, 4), cp, np.asarray(com, np.float64))
            mesh, kp, cp, com = cache[key]
            meshes.append(mesh)
            kps.append(kp)
            cps.append(cp)
            coms.append(com)
        return cls(
            meshes,
            scene.poses,
            [inst.category_id for inst in scene.instances],
            keypoints=kps,
            com_points=cps,
            coms=np.stack(coms),
            tote=tote_mesh(scene.tote) if tote else None,
        )

    @property
    def num_objects(self) -> int:
        return int(self._model.num_objects)

    @property
    def has_tote(self) -> bool:
        return bool(self._model.has_tote)

    def com_parameters(self) -> npt.NDArray[np.float64]:
        """(N, 5) per instance [c_W (3), d_min, d_max], world frame, m: the centre of mass and
        the nearest and farthest distances of the CoM-scored points from it, which define
        ``com_heatmap`` = clip((d_max - |p_W - c_W|) / (d_max - d_min), 0, 1) at each visible
        surface point p_W (docs/models.md §7; computed here as the C++ model does, to the last
        bits or nearly: the dataset writer predicts the heat map from them,
        :func:`mgn.io.image_codecs.com_heatmap_prediction`)."""
        out: npt.NDArray[np.float64] = self._com_parameters.copy()
        return out

    @property
    def category_ids(self) -> npt.NDArray[np.int32]:
        """(N,) category ids in scene order."""
        out: npt.NDArray[np.int32] = self._category_ids.copy()
        return out

    def __repr__(self) -> str:
        return f"SceneRayModel(objects={self.num_objects}, tote={self.has_tote})"


def _com_parameters(
    poses: np.ndarray, coms: np.ndarray, com_points: list[np.ndarray], meshes: list[Mesh]
) -> npt.NDArray[np.float64]:
    """(N, 5) [c_W, d_min, d_max] of :meth:`SceneRayModel.com_parameters`."""
    out = np.zeros((len(meshes), 5))
    for i, (X, c, cp, mesh) in enumerate(zip(poses, coms, com_points, meshes, strict=True)):
        R, t = X[:3, :3], X[:3, 3]
        c_W = R @ c + t
        if len(cp):
            pts = cp[:, 1:4] @ R.T + t
            d = np.sqrt(np.sum((pts - c_W) ** 2, axis=1))
            out[i] = [*c_W, d.min(), d.max()]
        else:
            v = np.asarray(mesh.vertices, np.float64) @ R.T + t
            out[i] = [*c_W, 0.0, np.sqrt(np.sum((v - c_W) ** 2, axis=1)).max()]
    return out


def view_object_labels(
    model: SceneRayModel,
    view: CameraView,
    instance_image: npt.ArrayLike,
    *,
    depth: npt.ArrayLike | None = None,
    keypoint_tolerance: float = DEFAULT_KEYPOINT_TOLERANCE,
    keypoints: bool = True,
    num_threads: int = 0,
) -> ViewObjectLabels:
    """Object labels of one view.

    Args:
        model: the scene's :class:`SceneRayModel`.
        view: the camera (intrinsics and ``X_WC``).
        instance_image: (H, W) integer instance ids of the view (0 = background, tote and floor,
            else 1..N), e.g. ``ViewImages.instance_ids``; H, W must be the camera's size.
        depth: optional (H, W) z-depth of the same view, m (<= 0 or NaN where nothing is seen),
            e.g. ``ViewImages.depth_ideal``. With it the heat map takes each visible pixel's
            3-D point from the depth (back-projected through the pixel centre) instead of a ray
            cast per visible pixel: about half the rays, and the heat map follows the rendered
            surface exactly. Masks, occlusion and keypoints do not depend on it.
        keypoint_tolerance: see :data:`DEFAULT_KEYPOINT_TOLERANCE`, m.
        keypoints: compute the keypoint sets (False leaves them empty).
        num_threads: threads (0 = all); the result does not depend on it.

    Raises:
        InvalidArgumentError: image of the wrong size or type, ids outside 0..N, bad camera.
    """
    if not isinstance(model, SceneRayModel):
        raise InvalidTypeError(f"model must be a SceneRayModel, got {type(model).__name__}")
    if not isinstance(view, CameraView):
        raise InvalidTypeError(f"view must be a CameraView, got {type(view).__name__}")
    if view.K.distortion:
        raise InvalidArgumentError(
            f"view_object_labels works on pinhole views; the camera has distortion "
            f"{list(view.K.distortion)}: label the pinhole render (ViewImages.pinhole) and "
            "resample the labels with distort_view_object_labels"
        )
    img = np.asarray(instance_image)
    if img.dtype == np.bool_ or not np.issubdtype(img.dtype, np.integer):
        raise InvalidArgumentError(
            f"instance_image must be an integer array, got dtype {img.dtype}"
        )
    if img.shape != (view.K.height, view.K.width):
        raise InvalidArgumentError(
            f"instance_image has shape {img.shape}; expected (H, W) = "
            f"({view.K.height}, {view.K.width}) of the camera"
        )
    if img.size and (int(img.min()) < 0 or int(img.max()) > model.num_objects):
        raise InvalidArgumentError(
            f"instance_image ids must be in 0..{model.num_objects} (the number of objects), "
            f"got {int(img.min())}..{int(img.max())}"
        )
    z = None
    if depth is not None:
        z = np.asarray(depth)
        if not np.issubdtype(z.dtype, np.floating):
            raise InvalidArgumentError(f"depth must be a float array, got dtype {z.dtype}")
        if z.shape != img.shape:
            raise InvalidArgumentError(
                f"depth has shape {z.shape}; expected the instance image's {img.shape}"
            )
        z = np.ascontiguousarray(z, np.float32)
    out = model._model.label_view(
        view.K.to_core(),
        view.X_WC,
        np.ascontiguousarray(img, np.int32),
        float(keypoint_tolerance),
        bool(keypoints),
        int(num_threads),
        z,
    )
    n = model.num_objects
    return from_core(
        ViewObjectLabels,
        out,
        instance_ids=np.arange(1, n + 1, dtype=np.int32),
        category_ids=model.category_ids,
    )


def _coco_boxes(masks: npt.NDArray[np.bool_]) -> npt.NDArray[np.int32]:
    """(N, 4) int32 COCO [x, y, w, h] of (N, H, W) masks (zeros when empty)."""
    out = np.zeros((masks.shape[0], 4), np.int32)
    cols = np.asarray(masks.any(axis=1), bool)
    rows = np.asarray(masks.any(axis=2), bool)
    for i in range(masks.shape[0]):
        c, r = np.flatnonzero(cols[i]), np.flatnonzero(rows[i])
        if c.size:
            out[i] = (c[0], r[0], c[-1] - c[0] + 1, r[-1] - r[0] + 1)
    return out


def _move_outside(
    kept: npt.NDArray[np.float64],
    kept_obj: npt.NDArray[np.int32],
    other: npt.NDArray[np.float64],
    other_obj: npt.NDArray[np.int32],
    inside: npt.NDArray[np.bool_],
) -> tuple[
    npt.NDArray[np.float64], npt.NDArray[np.int32], npt.NDArray[np.float64], npt.NDArray[np.int32]
]:
    """Moves the rows of ``kept`` not ``inside`` to ``other`` (object by object, stable)."""
    rows = np.concatenate([other.reshape(-1, 4), kept[~inside].reshape(-1, 4)])
    objs = np.concatenate([other_obj, kept_obj[~inside]]).astype(np.int32)
    order = np.argsort(objs, kind="stable")
    return kept[inside], kept_obj[inside], rows[order], objs[order]


def distort_view_object_labels(labels: ViewObjectLabels, lens: Lens) -> ViewObjectLabels:
    """The labels of a camera with lens distortion from those of its pinhole render.

    ``labels`` are :func:`view_object_labels` of the pinhole view ``lens.render_K`` (same pose;
    ``ViewImages.pinhole``). Pixel images (visible, semantic, amodal masks, CoM heat map) are
    resampled by nearest neighbour (:meth:`mgn.scene.lens.Lens.warp_nearest`, the same map as
    the instance image); pixel counts, occlusion, the occlusion map and the boxes are recomputed
    from the resampled masks; keypoints and CoM points whose projection through the lens falls
    outside the image become occluded / not visible. Poses and 3-D points do not change.
    """
    vis = lens.warp_nearest(labels.visible)
    amodal = lens.warp_nearest(labels.amodal, stacked=True)
    n = labels.num_objects
    vis_px = np.bincount(vis.reshape(-1), minlength=n + 1)[1 : n + 1].astype(np.int64)
    am_px = amodal.reshape(n, -1).sum(axis=1).astype(np.int64)
    occ = np.where(am_px > 0, 1.0 - vis_px / np.maximum(am_px, 1), 1.0)
    occ_map = np.where(vis > 0, np.concatenate([[0.0], occ])[vis], 0.0).astype(np.float32)
    tight = _coco_boxes(np.stack([vis == i + 1 for i in range(n)]) if n else amodal)
    kp, kp_obj, okp, okp_obj = (
        labels.keypoints,
        labels.keypoint_object,
        labels.occluded_keypoints,
        labels.occluded_keypoint_object,
    )
    if kp.shape[0]:
        kp, kp_obj, okp, okp_obj = _move_outside(kp, kp_obj, okp, okp_obj, lens.in_image(kp[:, 1:]))
    com_visible = labels.com_visible
    if labels.com_points.shape[0]:
        com_visible = com_visible & lens.in_image(labels.com_points[:, 1:])
    return ViewObjectLabels(
        instance_ids=labels.instance_ids,
        category_ids=labels.category_ids,
        visible=vis,
        semantic=lens.warp_nearest(labels.semantic),
        amodal=amodal,
        visible_pixels=vis_px,
        amodal_pixels=am_px,
        occlusion=occ,
        occlusion_map=occ_map,
        bbox_tight=tight,
        bbox_loose=_coco_boxes(amodal),
        X_CO=labels.X_CO,
        keypoints=kp,
        keypoint_object=kp_obj,
        occluded_keypoints=okp,
        occluded_keypoint_object=okp_obj,
        com_points=labels.com_points,
        com_object=labels.com_object,
        com_visible=com_visible,
        com_heatmap=lens.warp_nearest(labels.com_heatmap),
    )


def round_occlusion(labels: ViewObjectLabels, decimals: int) -> ViewObjectLabels:
    """``labels`` with the occlusion rates rounded to ``decimals`` decimals (numpy's
    ``round``) and the occlusion image made from the rounded rates, so that every file that holds
    an object's occlusion holds the same number (MetaGraspNet's files: 4 decimals)."""
    occ = np.asarray(np.round(np.asarray(labels.occlusion, np.float64), int(decimals)), np.float64)
    vis = labels.visible
    occ_map = np.where(vis > 0, np.concatenate([[0.0], occ])[vis], 0.0).astype(np.float32)
    return dataclasses.replace(labels, occlusion=occ, occlusion_map=occ_map)


def seen_objects(
    labels: ViewObjectLabels,
) -> tuple[ViewObjectLabels, npt.NDArray[np.int64]]:
    """The labels of the objects seen in the view (at least one visible pixel), numbered 1..N'
    in scene order, and the (N',) 0-based scene index of each.

    MetaGraspNet's files hold the objects of a view with instance ids 1..N' that all appear in
    the instance image (its ``visualize_layout.py`` counts the ids it finds; ``scene_gt.json``
    entry k is instance k + 1): an object hidden from the camera (occlusion 1) is left out of
    the view with its masks, pose, keypoints and CoM points, and the ids above it move down.
    """
    keep = np.flatnonzero(np.asarray(labels.visible_pixels) > 0).astype(np.int64)
    n = labels.num_objects
    if keep.size == n:
        return labels, keep
    new_id = np.zeros(n + 1, np.int32)  # old instance id (0 = none) -> new one
    new_id[keep + 1] = np.arange(1, keep.size + 1, dtype=np.int32)
    new_index = new_id[1:] - 1  # old object index -> new one (-1: left out)

    def rows(points: np.ndarray, owner: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        ok = new_index[owner] >= 0
        return points[ok], new_index[owner[ok]].astype(np.int32)

    kp, kp_obj = rows(labels.keypoints, labels.keypoint_object)
    okp, okp_obj = rows(labels.occluded_keypoints, labels.occluded_keypoint_object)
    ok = new_index[labels.com_object] >= 0
    return (
        ViewObjectLabels(
            instance_ids=np.arange(1, keep.size + 1, dtype=np.int32),
            category_ids=labels.category_ids[keep],
            visible=new_id[labels.visible],
            semantic=labels.semantic,
            amodal=labels.amodal[keep],
            visible_pixels=labels.visible_pixels[keep],
            amodal_pixels=labels.amodal_pixels[keep],
            occlusion=labels.occlusion[keep],
            occlusion_map=labels.occlusion_map,
            bbox_tight=labels.bbox_tight[keep],
            bbox_loose=labels.bbox_loose[keep],
            X_CO=labels.X_CO[keep],
            keypoints=kp,
            keypoint_object=kp_obj,
            occluded_keypoints=okp,
            occluded_keypoint_object=okp_obj,
            com_points=labels.com_points[ok],
            com_object=new_index[labels.com_object[ok]].astype(np.int32),
            com_visible=labels.com_visible[ok],
            com_heatmap=labels.com_heatmap,
        ),
        keep,
    )
