"""Grasp files in the layouts of the grasp community's tools (``mgn export graspnet DS OUT``):
parallel-jaw grasps as graspnetAPI's ``GraspGroup`` arrays, suction grasps as suctionnetAPI's
``SuctionGroup`` arrays, and 2-D grasp rectangles for planar grasp detectors (graspnetAPI's
``RectGraspGroup`` arrays and Jacquard's ``_grasps.txt``), per view, in the camera frame
(docs/format.md, "GraspNet export")::

    OUT/scenes/scene_<N:04d>/<camera>/
      camK.npy                  (3, 3) float64 camera matrix, OpenCV pixel convention (when
                                every view of the scene has the same)
      grasp/<v:04d>.npy         (M, 17) float32 parallel-jaw grasps (GraspGroup)
      suction/<v:04d>.npz       arr_0: (K, 8) float32 suction grasps (SuctionGroup)
      rect/<v:04d>.npy          (R, 7) float32 grasp rectangles (RectGraspGroup)
      jacquard/<v:04d>_grasps.txt   the same rectangles, one "x;y;theta;w;h" line each

Only the collision-free scene grasps (``non_colliding_grasps``) are written. Every file is
written atomically; each scene folder is built under a temporary name and renamed when complete,
so a run that stops leaves whole scenes only and a new run skips the scenes already there. One
view is in memory at a time.
"""

from __future__ import annotations

import io
import math
import os
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn.base.atomic import atomic_dir, atomic_write_bytes, atomic_write_text
from mgn.base.deterministic import npz_bytes
from mgn.errors import InvalidArgumentError, IoError
from mgn.geometry.mesh import load_mesh
from mgn.hardware import ParallelJawGripper
from mgn.io.dataset import Dataset, SceneFolder, View
from mgn.scene.cameras import Intrinsics
from mgn.scene.lens import lens_for

__all__ = [
    "DEFAULT_CAMERA",
    "DEFAULT_MAX_TILT_DEG",
    "DEFAULT_PJ_SCORE",
    "DEFAULT_SUCTION_SCORE",
    "GRASPNET_COLUMNS",
    "GRASPNET_DEPTH_BASE",
    "PJ_SCORES",
    "SUCTION_SCORES",
    "GraspNetExport",
    "GraspNetGripper",
    "GraspRectangles",
    "export_graspnet",
    "export_graspnet_scene",
    "grasp_rectangles",
    "graspnet_gripper",
    "graspnet_rows",
    "gripper_of",
    "jacquard_text",
    "pj_scores",
    "rect_rows",
    "suction_scores",
    "suctionnet_rows",
    "view_rectangles",
]

#: The camera folder name under each scene (graspnetAPI's are ``kinect`` and ``realsense``).
DEFAULT_CAMERA = "mgn"
#: Largest angle between a grasp's approach and the camera's optical axis (+z) for a 2-D grasp
#: rectangle, degrees.
DEFAULT_MAX_TILT_DEG = 20.0
#: mgn's parallel-jaw scores by name (the ``score_*`` datasets of ``{v}_scene.hdf5``).
PJ_SCORES = ("analytical", "simulation", "wrench")
#: The parallel-jaw score written by default: the friction-cone score (nearest to GraspNet's).
DEFAULT_PJ_SCORE = "analytical"
#: mgn's suction scores by name: the seal score, the wrench score, and their product.
SUCTION_SCORES = ("seal", "wrench", "product")
#: The suction score written by default: seal x wrench, as SuctionNet's labels combine its two.
DEFAULT_SUCTION_SCORE = "product"
#: Columns of a graspnetAPI ``GraspGroup`` row.
GRASPNET_COLUMNS = (
    "score",
    "width",
    "height",
    "depth",
    *(f"rotation_{r}{c}" for r in range(3) for c in range(3)),
    "x",
    "y",
    "z",
    "object_id",
)

_CAMERA_RE = re.compile(r"^[A-Za-z0-9_]+$")
#: graspnetAPI's distance from its grasp point back to the palm (``depth_base`` of its gripper
#: model), m.
GRASPNET_DEPTH_BASE = 0.02


@dataclass(frozen=True)
class GraspNetGripper:
    """A parallel-jaw gripper in graspnetAPI's terms (m).

    Attributes:
        depth: how far the fingertips reach beyond graspnetAPI's grasp point: the finger length
            less :data:`GRASPNET_DEPTH_BASE` (at least 0).
        height: the jaws' extent across the opening and the approach (the finger width).
        contact_from_tip: mgn's contact-pad centre above the fingertip.
        margin, max_opening: the jaws stand at ``min(w + margin, max_opening)`` (at least w)
            for a contact width w: the opening mgn checks for collisions.
    """

    depth: float
    height: float
    contact_from_tip: float
    margin: float
    max_opening: float

    def opening(self, contact_width: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The jaws' opening (m) for contact widths ``contact_width`` (m)."""
        w = np.asarray(contact_width, np.float64)
        return np.maximum(w, np.minimum(w + self.margin, self.max_opening))


# --- per-grasp conversions -----------------------------------------------------------------------


def _poses(contact_poses: npt.ArrayLike, what: str) -> np.ndarray:
    p = np.asarray(contact_poses, np.float64)
    if p.ndim != 3 or p.shape[1:] != (4, 4):
        raise InvalidArgumentError(f"{what}: contact poses must be (M, 4, 4), got {p.shape}")
    return p


def _column(values: npt.ArrayLike, n: int, what: str) -> np.ndarray:
    a = np.asarray(values, np.float64).reshape(-1)
    if len(a) != n:
        raise InvalidArgumentError(f"{what}: expected {n} values (one per grasp), got {len(a)}")
    return a


def graspnet_rows(
    contact_poses: npt.ArrayLike,
    contact_width: npt.ArrayLike,
    score: npt.ArrayLike,
    object_id: npt.ArrayLike,
    gripper: GraspNetGripper,
) -> npt.NDArray[np.float32]:
    """(M, 17) float32 rows of a graspnetAPI ``GraspGroup`` from mgn's parallel-jaw grasps.

    mgn's grasp frame (``contact_poses``, camera frame, m) has x = closing direction v, z =
    approach a, origin at the first contact p1; graspnetAPI's has x = approach, y = closing,
    z = x × y, origin at its grasp point t, with the palm :data:`GRASPNET_DEPTH_BASE` behind t
    and the fingertips ``depth`` beyond it. A row is [score, width (m), height (m), depth (m),
    R (9, row-major: columns a, v, a × v), t (3, m), object_id], with the fingers of
    ``gripper`` (:func:`graspnet_gripper`): width = the opening of the jaws,
    ``gripper.opening(w)``; t = the fingertips' midpoint p1 + (w / 2) v +
    ``contact_from_tip`` a moved back by ``depth`` along a, so that graspnetAPI's finger span
    from the palm to the tips is the gripper's. ``contact_width``: w, the distance between the
    contacts (m).
    """
    p = _poses(contact_poses, "graspnet_rows")
    n = len(p)
    w = _column(contact_width, n, "graspnet_rows: contact_width")
    s = _column(score, n, "graspnet_rows: score")
    oid = _column(object_id, n, "graspnet_rows: object_id")
    v, b, a = p[:, :3, 0], p[:, :3, 1], p[:, :3, 2]
    R = np.stack([a, v, b], axis=2)  # columns: approach, closing, approach x closing
    c = p[:, :3, 3] + 0.5 * w[:, None] * v
    t = c + (gripper.contact_from_tip - gripper.depth) * a
    out = np.empty((n, 17), np.float64)
    out[:, 0] = s
    out[:, 1] = gripper.opening(w)
    out[:, 2] = gripper.height
    out[:, 3] = gripper.depth
    out[:, 4:13] = R.reshape(n, 9)
    out[:, 13:16] = t
    out[:, 16] = oid
    return out.astype(np.float32)


def suctionnet_rows(
    contact_poses: npt.ArrayLike, score: npt.ArrayLike, object_id: npt.ArrayLike
) -> npt.NDArray[np.float32]:
    """(K, 8) float32 rows of a suctionnetAPI ``SuctionGroup`` from mgn's suction contact frames
    (z = approach into the surface, origin at the contact; camera frame, m): [score, direction
    (3), point (3, m), object_id], where the direction is the surface's outward normal as
    suctionnetAPI reads it (the suction cup lies along +direction from the point): −z of the
    contact frame."""
    p = _poses(contact_poses, "suctionnet_rows")
    n = len(p)
    s = _column(score, n, "suctionnet_rows: score")
    oid = _column(object_id, n, "suctionnet_rows: object_id")
    out = np.empty((n, 8), np.float64)
    out[:, 0] = s
    out[:, 1:4] = -p[:, :3, 2]
    out[:, 4:7] = p[:, :3, 3]
    out[:, 7] = oid
    return out.astype(np.float32)


@dataclass(frozen=True)
class GraspRectangles:
    """2-D parallel-jaw grasp rectangles of one view (Cornell / Jacquard convention).

    Pixel coordinates are OpenCV's: x = column, y = row, the centre of pixel (row r, column c)
    at (c, r). Attributes, one entry per rectangle:

        center: (R, 2) float64 the projected grasp point (midpoint of the contacts), px.
        angle: (R,) float64 radians in (−π/2, π/2]: the direction of the opening (from one jaw
            to the other) measured from the image x axis towards the image y axis (clockwise as
            the image is seen, since y points down).
        width: (R,) float64 opening: the distance between the projected contacts, px.
        height: (R,) float64 jaw size: the projected extent of the jaw across the opening, px.
        score: (R,) float64 the grasp's score.
        object_id: (R,) int64 the object's category id.
        index: (R,) int64 the grasp's row among the view's non-colliding parallel-jaw grasps.
    """

    center: npt.NDArray[np.float64]
    angle: npt.NDArray[np.float64]
    width: npt.NDArray[np.float64]
    height: npt.NDArray[np.float64]
    score: npt.NDArray[np.float64]
    object_id: npt.NDArray[np.int64]
    index: npt.NDArray[np.int64]

    def __len__(self) -> int:
        return len(self.angle)

    def corners(self) -> npt.NDArray[np.float64]:
        """(R, 4, 2) corners, px: the jaws are the edges 0-1 and 2-3 (across the opening)."""
        d = np.stack([np.cos(self.angle), np.sin(self.angle)], axis=1)
        n = np.stack([-d[:, 1], d[:, 0]], axis=1)
        hw = 0.5 * self.width[:, None] * d
        hh = 0.5 * self.height[:, None] * n
        c = self.center
        return np.stack([c - hw - hh, c - hw + hh, c + hw + hh, c + hw - hh], axis=1)


def _project_px(points: np.ndarray, K: Intrinsics | npt.ArrayLike) -> np.ndarray:
    """(N, 2) OpenCV pixel coordinates of camera-frame points (N, 3) in front of the camera."""
    if isinstance(K, Intrinsics):
        lens = lens_for(K)
        if lens is not None:
            return lens.project(points) - 0.5
        M = K.K_opencv
    else:
        M = np.asarray(K, np.float64)
        if M.shape != (3, 3):
            raise InvalidArgumentError(f"grasp_rectangles: K must be (3, 3), got {M.shape}")
    q = points @ M.T
    uv: np.ndarray = q[:, :2] / q[:, 2:3]
    return uv


def grasp_rectangles(
    contact_poses: npt.ArrayLike,
    contact_width: npt.ArrayLike,
    score: npt.ArrayLike,
    object_id: npt.ArrayLike,
    K: Intrinsics | npt.ArrayLike,
    *,
    jaw_height: float,
    opening: npt.ArrayLike | None = None,
    max_tilt_deg: float = DEFAULT_MAX_TILT_DEG,
) -> GraspRectangles:
    """The 2-D rectangles of the parallel-jaw grasps (mgn grasp frames, camera frame, m) whose
    approach is within ``max_tilt_deg`` (degrees, [0, 90)) of the optical axis +z, in front of
    the camera. ``K``: :class:`~mgn.scene.cameras.Intrinsics` (with its lens distortion, if
    any) or a (3, 3) matrix in OpenCV's pixel convention. ``opening``: the jaws' opening per
    grasp, m (default: the contact width w). The rectangle's centre is the projected contact
    midpoint c = p1 + (w / 2) v; its width the distance between the projections of the jaws at
    c ± (opening / 2) v; its height the distance between the projections of c ± ``jaw_height``
    / 2 along approach × closing; its angle that of the projected opening (see
    :class:`GraspRectangles`). A grasp straight down the optical axis at depth z, opening along
    x, has width opening · fx / z px."""
    if not (isinstance(max_tilt_deg, (int, float)) and 0 <= max_tilt_deg < 90):
        raise InvalidArgumentError(
            f"grasp_rectangles: max_tilt_deg must be in [0, 90) degrees, got {max_tilt_deg!r}"
        )
    if not (math.isfinite(jaw_height) and jaw_height > 0):
        raise InvalidArgumentError(f"grasp_rectangles: jaw_height must be > 0 m, got {jaw_height}")
    p = _poses(contact_poses, "grasp_rectangles")
    n = len(p)
    w = _column(contact_width, n, "grasp_rectangles: contact_width")
    o = w if opening is None else _column(opening, n, "grasp_rectangles: opening")
    s = _column(score, n, "grasp_rectangles: score")
    oid = _column(object_id, n, "grasp_rectangles: object_id").astype(np.int64)
    v, b, a, p1 = p[:, :3, 0], p[:, :3, 1], p[:, :3, 2], p[:, :3, 3]
    c = p1 + 0.5 * w[:, None] * v
    p1, p2 = c - 0.5 * o[:, None] * v, c + 0.5 * o[:, None] * v
    ends = [c - 0.5 * jaw_height * b, c + 0.5 * jaw_height * b]
    # cos of the tilt, rounded to 1e-12 so that a grasp exactly at the limit is kept.
    keep = np.round(a[:, 2], 12) >= np.round(math.cos(math.radians(max_tilt_deg)), 12)
    keep &= np.stack([q[:, 2] for q in (p1, p2, *ends)], axis=1).min(axis=1) > 1e-6
    idx = np.flatnonzero(keep)
    uc, u1, u2, e0, e1 = (_project_px(q[idx], K) for q in (c, p1, p2, *ends))
    d = u2 - u1
    angle = np.arctan2(d[:, 1], d[:, 0])
    angle = np.where(angle <= -np.pi / 2, angle + np.pi, angle)
    angle = np.where(angle > np.pi / 2, angle - np.pi, angle)
    return GraspRectangles(
        center=uc,
        angle=angle,
        width=np.linalg.norm(d, axis=1),
        height=np.linalg.norm(e1 - e0, axis=1),
        score=s[idx],
        object_id=oid[idx],
        index=idx.astype(np.int64),
    )


def rect_rows(rects: GraspRectangles) -> npt.NDArray[np.float32]:
    """(R, 7) float32 rows of a graspnetAPI ``RectGraspGroup``: [center_x, center_y, open_x,
    open_y, height, score, object_id] (px; the open point is the centre moved by half the
    opening along the angle)."""
    d = np.stack([np.cos(rects.angle), np.sin(rects.angle)], axis=1)
    opened = rects.center + 0.5 * rects.width[:, None] * d
    cols = [
        rects.center,
        opened,
        rects.height[:, None],
        rects.score[:, None],
        rects.object_id[:, None].astype(np.float64),
    ]
    return np.hstack(cols).astype(np.float32)


def jacquard_text(rects: GraspRectangles) -> str:
    """Jacquard's ``_grasps.txt``: one line ``x;y;theta;w;h`` per rectangle (px; theta in
    degrees, the angle of :class:`GraspRectangles`), 2 decimals."""
    deg = np.degrees(rects.angle)
    lines = [
        f"{x:.2f};{y:.2f};{t:.2f};{w:.2f};{h:.2f}"
        for (x, y), t, w, h in zip(rects.center, deg, rects.width, rects.height, strict=True)
    ]
    return "".join(line + "\n" for line in lines)


# --- scores and the gripper ----------------------------------------------------------------------


def pj_scores(grasps: dict[str, np.ndarray], name: str) -> npt.NDArray[np.float64]:
    """The parallel-jaw score ``name`` (one of :data:`PJ_SCORES`) of a view's grasp group."""
    if name not in PJ_SCORES:
        raise InvalidArgumentError(f"parallel-jaw score {name!r}: expected one of {PJ_SCORES}")
    n = len(grasps.get("object_id", ()))
    return np.asarray(grasps.get(f"score_{name}", np.full(n, np.nan)), np.float64)


def suction_scores(grasps: dict[str, np.ndarray], name: str) -> npt.NDArray[np.float64]:
    """The suction score ``name`` (one of :data:`SUCTION_SCORES`) of a view's grasp group."""
    if name not in SUCTION_SCORES:
        raise InvalidArgumentError(f"suction score {name!r}: expected one of {SUCTION_SCORES}")
    n = len(grasps.get("object_id", ()))

    def get(key: str) -> npt.NDArray[np.float64]:
        return np.asarray(grasps.get(key, np.full(n, np.nan)), np.float64)

    if name == "seal":
        return get("score_analytical")
    if name == "wrench":
        return get("score_wrench")
    product: npt.NDArray[np.float64] = get("score_analytical") * get("score_wrench")
    return product


def gripper_of(ds: Dataset) -> ParallelJawGripper:
    """The parallel-jaw gripper a dataset was labelled with (``config.gripper`` of
    ``dataset.json``; the default gripper when the file or the key is absent)."""
    config = (ds.info or {}).get("config") or {}
    spec = config.get("gripper")
    return ParallelJawGripper() if spec is None else ParallelJawGripper.from_dict(spec)


def graspnet_gripper(gripper: ParallelJawGripper) -> GraspNetGripper:
    """``gripper`` in graspnetAPI's terms: the finger length and width from ``finger_size``
    (z and y), or from the extent of the finger mesh along z and y."""
    if gripper.finger_left_mesh is None:
        length, width = float(gripper.finger_size[2]), float(gripper.finger_size[1])
    else:
        mesh = load_mesh(gripper.finger_left_mesh)
        ext = np.ptp(np.asarray(mesh.vertices, np.float64), axis=0) * gripper.mesh_scale
        length, width = float(ext[2]), float(ext[1])
    return GraspNetGripper(
        depth=max(length - GRASPNET_DEPTH_BASE, 0.0),
        height=width,
        contact_from_tip=float(gripper.contact_from_tip),
        margin=float(gripper.collision_margin),
        max_opening=float(gripper.max_opening),
    )


def _category_ids(view: View) -> np.ndarray:
    cats = view.hdf5.get("objects/categories")
    if cats is None:
        raise IoError(f"{view.path('_scene.hdf5')}: no objects/categories dataset")
    return np.asarray(cats, np.int64).reshape(-1)


def _object_ids(view: View, instance_index: np.ndarray, cats: np.ndarray) -> np.ndarray:
    """Category ids of the grasped objects (``object_id`` = instance id − 1)."""
    i = np.asarray(instance_index, np.int64).reshape(-1)
    if len(i) and (i.min() < 0 or i.max() >= len(cats)):
        raise IoError(
            f"{view.path('_scene.hdf5')}: grasp object_id {int(i.max())} outside the view's "
            f"{len(cats)} objects"
        )
    return cats[i]


def view_rectangles(
    view: View,
    gripper: GraspNetGripper,
    *,
    max_tilt_deg: float = DEFAULT_MAX_TILT_DEG,
    score: str = DEFAULT_PJ_SCORE,
) -> GraspRectangles:
    """The grasp rectangles of a view's non-colliding parallel-jaw grasps (see
    :func:`grasp_rectangles`) for ``gripper`` (its jaws' opening and height), best score first
    (ties in grasp order); grasps whose ``score`` is NaN are left out."""
    g = view.grasps("paralleljaw")
    poses = g.get("contact_poses_relative_to_camera", np.zeros((0, 4, 4)))
    s = pj_scores(g, score)
    oid = _object_ids(view, g.get("object_id", np.zeros(0)), _category_ids(view))
    w = g.get("contact_width", np.zeros(len(poses)))
    r = grasp_rectangles(
        poses,
        w,
        s,
        oid,
        view.intrinsics,
        jaw_height=gripper.height,
        opening=gripper.opening(w),
        max_tilt_deg=max_tilt_deg,
    )
    keep = np.flatnonzero(~np.isnan(r.score))
    order = keep[np.argsort(-r.score[keep], kind="stable")]
    return GraspRectangles(*(getattr(r, f)[order] for f in GraspRectangles.__dataclass_fields__))


# --- the export ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class GraspNetExport:
    """What :func:`export_graspnet` did: the output folder, the scene ids written and skipped
    (already complete), and per kind the rows written (``grasp``, ``suction``, ``rect``) and the
    grasps left out because their chosen score is NaN (``grasp_unscored``,
    ``suction_unscored``)."""

    root: Path
    written: list[int]
    skipped: list[int]
    counts: dict[str, int]


def _npy_bytes(array: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array(buf, np.ascontiguousarray(array), allow_pickle=False)
    return buf.getvalue()


def _by_score(rows: np.ndarray, score: np.ndarray) -> np.ndarray:
    """The rows whose ``score`` (float64, one per row) is not NaN, best first; ties keep their
    order."""
    keep = np.flatnonzero(~np.isnan(score))
    return rows[keep[np.argsort(-score[keep], kind="stable")]]


def _write_view(view: View, tmp: Path, options: dict[str, Any], counts: dict[str, int]) -> None:
    v = view.index
    cats = _category_ids(view)
    pj = view.grasps("paralleljaw")
    poses = pj.get("contact_poses_relative_to_camera", np.zeros((0, 4, 4)))
    oid = _object_ids(view, pj.get("object_id", np.zeros(0)), cats)
    score = pj_scores(pj, options["pj_score"])
    rows = graspnet_rows(
        poses,
        pj.get("contact_width", np.zeros(len(poses))),
        score,
        oid,
        options["gripper"],
    )
    good = _by_score(rows, score)
    counts["grasp"] += len(good)
    counts["grasp_unscored"] += len(rows) - len(good)
    atomic_write_bytes(tmp / "grasp" / f"{v:04d}.npy", _npy_bytes(good))

    su = view.grasps("suction")
    sposes = su.get("contact_poses_relative_to_camera", np.zeros((0, 4, 4)))
    soid = _object_ids(view, su.get("object_id", np.zeros(0)), cats)
    sscore = suction_scores(su, options["suction_score"])
    sgood = _by_score(suctionnet_rows(sposes, sscore, soid), sscore)
    counts["suction"] += len(sgood)
    counts["suction_unscored"] += len(sscore) - len(sgood)
    atomic_write_bytes(tmp / "suction" / f"{v:04d}.npz", npz_bytes(arr_0=sgood))

    rects = view_rectangles(
        view,
        options["gripper"],
        max_tilt_deg=options["max_tilt_deg"],
        score=options["pj_score"],
    )
    counts["rect"] += len(rects)
    atomic_write_bytes(tmp / "rect" / f"{v:04d}.npy", _npy_bytes(rect_rows(rects)))
    atomic_write_text(tmp / "jacquard" / f"{v:04d}_grasps.txt", jacquard_text(rects))


def _check_options(camera: str, pj_score: str, suction_score: str, max_tilt_deg: float) -> None:
    if not (isinstance(camera, str) and _CAMERA_RE.match(camera)):
        raise InvalidArgumentError(
            f"export_graspnet: camera {camera!r} must be a folder name of letters, digits and '_'"
        )
    if pj_score not in PJ_SCORES:
        raise InvalidArgumentError(f"export_graspnet: pj_score {pj_score!r}: one of {PJ_SCORES}")
    if suction_score not in SUCTION_SCORES:
        raise InvalidArgumentError(
            f"export_graspnet: suction_score {suction_score!r}: one of {SUCTION_SCORES}"
        )
    if not (isinstance(max_tilt_deg, (int, float)) and 0 <= max_tilt_deg < 90):
        raise InvalidArgumentError(
            f"export_graspnet: max_tilt_deg must be in [0, 90) degrees, got {max_tilt_deg!r}"
        )


def _new_counts() -> dict[str, int]:
    return dict.fromkeys(("grasp", "suction", "rect", "grasp_unscored", "suction_unscored"), 0)


def export_graspnet_scene(
    scene: SceneFolder,
    out: str | os.PathLike[str],
    gripper: GraspNetGripper,
    *,
    camera: str = DEFAULT_CAMERA,
    pj_score: str = DEFAULT_PJ_SCORE,
    suction_score: str = DEFAULT_SUCTION_SCORE,
    max_tilt_deg: float = DEFAULT_MAX_TILT_DEG,
    counts: dict[str, int] | None = None,
) -> bool:
    """Write the grasp files of one mgn scene folder into ``out/scenes/scene_<N:04d>/<camera>/``
    (built under a temporary name, renamed when complete), one view in memory at a time;
    ``gripper``: the dataset's gripper (``graspnet_gripper(gripper_of(dataset))``). Returns
    False (and writes nothing) when that folder is already there. ``counts`` (the keys of
    :attr:`GraspNetExport.counts`) is increased by the rows written. What
    :func:`export_graspnet` does per scene: ``mgn generate`` with ``output.formats``
    containing ``graspnet`` calls it after each scene.

    Raises:
        IoError, InvalidArgumentError: as :func:`export_graspnet`.
    """
    _check_options(camera, pj_score, suction_score, max_tilt_deg)
    target = Path(out) / "scenes" / f"scene_{scene.scene_id:04d}" / camera
    if target.exists():
        return False
    options = {
        "pj_score": pj_score,
        "suction_score": suction_score,
        "max_tilt_deg": float(max_tilt_deg),
        "gripper": gripper,
    }
    tally = _new_counts()
    with atomic_dir(target) as tmp:
        cams = set()
        for v in scene.view_ids:  # one View (and its cached arrays) alive at a time
            view = scene.view(v)
            _write_view(view, tmp, options, tally)
            cams.add(view.intrinsics.K_opencv.tobytes())
        if len(cams) == 1:
            K = np.frombuffer(cams.pop(), np.float64).reshape(3, 3)
            atomic_write_bytes(tmp / "camK.npy", _npy_bytes(K))
    if counts is not None:
        for k, v in tally.items():
            counts[k] = counts.get(k, 0) + v
    return True


def export_graspnet(
    dataset: str | os.PathLike[str],
    out: str | os.PathLike[str],
    *,
    scenes: Iterable[int] | None = None,
    camera: str = DEFAULT_CAMERA,
    pj_score: str = DEFAULT_PJ_SCORE,
    suction_score: str = DEFAULT_SUCTION_SCORE,
    max_tilt_deg: float = DEFAULT_MAX_TILT_DEG,
    progress: Callable[[int], None] | None = None,
) -> GraspNetExport:
    """Write the grasp files of ``dataset``'s scenes to ``out`` (layout in the module docstring
    and docs/format.md, "GraspNet export").

    Args:
        scenes: the scene ids to export (default: every scene).
        camera: the camera folder name (letters, digits, ``_``).
        pj_score: the parallel-jaw score in column 0 of the grasp rows and in the rectangles
            (:data:`PJ_SCORES`); grasps whose score is NaN are left out.
        suction_score: the suction score in column 0 (:data:`SUCTION_SCORES`).
        max_tilt_deg: largest angle between a grasp's approach and the optical axis for a
            rectangle, degrees in [0, 90).
        progress: called with each scene id when it is done.

    Raises:
        IoError: a missing dataset or scene, a view without ``objects/categories``.
        InvalidArgumentError: a bad camera name, score name or angle.
    """
    _check_options(camera, pj_score, suction_score, max_tilt_deg)
    ds = Dataset(dataset)
    ids = ds.scene_ids if scenes is None else sorted({int(s) for s in scenes})
    missing = [s for s in ids if s not in ds.scene_ids]
    if missing:
        raise IoError(f"{ds.root}: no scene folder for scene ids {missing}")
    if not ids:
        raise IoError(f"{ds.root}: no scene<N> folders to export")
    gripper = graspnet_gripper(gripper_of(ds))
    root = Path(out)
    root.mkdir(parents=True, exist_ok=True)
    counts = _new_counts()
    written: list[int] = []
    skipped: list[int] = []
    for n in ids:
        if export_graspnet_scene(
            ds.scene(n),
            root,
            gripper,
            camera=camera,
            pj_score=pj_score,
            suction_score=suction_score,
            max_tilt_deg=max_tilt_deg,
            counts=counts,
        ):
            written.append(n)
        else:
            skipped.append(n)
        if progress is not None:
            progress(n)
    return GraspNetExport(root, written, skipped, counts)
