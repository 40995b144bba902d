"""``mgn eval grasps``: precision@k of suction and parallel-jaw grasp predictions per view.

Predictions are matched to the scene grasp labels of each view (docs/format.md ``{v}_scene.hdf5``,
both the ``non_colliding_grasps`` and the ``colliding_grasps`` groups) and checked for collision
by the SAME model that made the labels (:meth:`mgn.view_labels.grasps.SceneGraspModel.collides`:
same gripper / cup and tool geometry from the dataset's config, same approach offsets, the tote
and every object of the scene), rebuilt from the scene's ``scene.json``.

Prediction file (JSON, metres and radians, camera frame = OpenCV: x right, y down, z forward)::

    [{"image_id": 1005,              # scene_id * 1000 + view_id (as the COCO export)
      "kind": "suction",             # or "paralleljaw"
      "grasps": [
        {"pose": [[...4 rows...]], "score": 0.93},                 # 6-DoF
        {"uv": [61.5, 40.5], "score": 0.88},                        # pixel (suction)
        ...]},
     {"image_id": 1005, "kind": "paralleljaw",
      "grasps": [
        {"pose": [[...]], "width": 0.031, "score": 0.7},            # 6-DoF
        {"uv": [50.5, 70.5], "angle": 0.3, "width": 0.04,
         "depth": 0.02, "score": 0.6}]}]                            # pixel (planar)

- Suction 6-DoF ``pose``: the suction CONTACT pose X_CS, as docs/format.md's
  ``suctioncup/contact_poses_relative_to_camera``: origin at the contact point on the surface,
  z = approach direction into the surface (x, y free: the cup is axially symmetric).
- Parallel-jaw 6-DoF ``pose`` + ``width``: the CONTACT (grasp) frame X_CG, as docs/format.md's
  ``paralleljaw/contact_poses_relative_to_camera``: origin at the first contact p1,
  x = closing direction v (towards the second contact p2 = p1 + width v), z = approach a; y = z x x.
  ``width`` = contact width |p2 - p1| in m, in [0, gripper max_opening]. The hand (flange) is at
  X_CG * translation(width/2, 0, -grasp_depth) (gripper.hpp).
- Pixel coordinates ``uv`` = [u, v] are continuous image coordinates: pixel (column c, row r)
  spans [c, c+1) x [r, r+1) and its centre is (c + 0.5, r + 0.5) (the renderer's rays). The depth
  is that of the pixel containing (u, v), read from the noise-free ``depth_ideal`` of the view's
  npz (the real surface the robot would meet; the sensor ``depth`` when no ideal depth is stored).
  A pixel without depth (NaN) gives a prediction that cannot match (counted as unmatched).
- Suction pixel grasp: contact = the back-projection of (u, v) at that depth; approach = minus the
  surface normal of a plane fitted (least squares) to the back-projected pixels of a 5 x 5 window
  around it that belong to the same instance (``instances_objects``), oriented away from the
  camera.
- Parallel-jaw pixel grasp (a planar, "top-down" grasp as seen by the camera): approach = the
  camera's optical axis (0, 0, 1); closing v = (cos angle, sin angle, 0), ``angle`` in rad in the
  image plane from the +u axis towards +v (clockwise on screen); the grasp centre lies on the
  pixel's ray at z = surface depth + ``depth`` (optional, m, default 0: how far past the seen
  surface the fingertip contacts go); p1 = centre - (width / 2) v.
- ``score``: the predictor's confidence; ranks the grasps of a view (ties keep the file order).

Matching: a prediction matches the label of the same view and kind that minimises
``distance / match_distance + angle / match_angle`` among the labels within both tolerances:

- suction: distance = |c_pred - c_label|; angle = angle between the approach axes;
- parallel-jaw: distance = the larger contact distance under the better of the two pairings
  (p1-q1, p2-q2) or (p1-q2, p2-q1), so a grasp with swapped jaws matches the same label;
  angle = max(angle between the approaches, angle between the closing LINES (v ~ -v)).

Defaults: ``match_distance`` = 10 mm (:data:`DEFAULT_MATCH_DISTANCE`): the size of the contact
patch a label describes (the MetaGraspNet cup ring radius is 7 mm and its robust seal score jitters
the contact by r/4 per axis; a parallel-jaw finger pad is 20 mm wide), so a prediction within it
lands on the surface patch whose label it is scored by. ``match_angle`` = 30 deg
(:data:`DEFAULT_MATCH_ANGLE`), the orientation tolerance of the rectangle metric of the Cornell
and Jacquard grasp benchmarks.

A prediction is a SUCCESS at a threshold t when it matches a label whose score is >= t AND the
predicted pose itself is collision-free in the scene (tool at the grasp and at every approach
offset; for parallel-jaw grasps the hand is also checked against the grasped object, i.e. the
matched label's object, at the grasp: ``check_target_at_grasp``, the test the object-level labels
passed). Label score (``label_score``): suction ``"analytical"`` = the seal score (default);
parallel-jaw ``"analytical"`` = the antipodal robustness score (default; mgn computes the physics
score ``"simulation"`` for a subset of the grasps only) ; ``"simulation"`` and ``"wrench"`` can be
chosen. A NaN label score never succeeds.

precision@k of a view = successes among its k highest-scored predictions / min(k, number of
predictions) (GraspNet-style: a view with fewer than k predictions is divided by the number
given; :attr:`GraspResults.views_short` counts such views per k; a view entry with no grasps
scores 0). Reported: the mean over the views of the prediction file, per threshold and k; the
success rate over all predictions per threshold; how many predictions were unmatched, matched but
colliding, or matched and free but below each threshold. Predictions are judged independently
(no non-maximum suppression: two predictions of one label both count).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn.errors import InvalidArgumentError, IoError
from mgn.eval.results import format_table
from mgn.hardware import ParallelJawGripper, SuctionCup, normalize_grasp_kind
from mgn.io.dataset import Dataset
from mgn.io.scene_json import read_scene_json
from mgn.pipeline.config import Config
from mgn.pipeline.label_scene import LabelOptions
from mgn.scene.lens import lens_for
from mgn.view_labels.grasps import SceneGraspModel

__all__ = [
    "DEFAULT_KS",
    "DEFAULT_MATCH_ANGLE",
    "DEFAULT_MATCH_DISTANCE",
    "DEFAULT_THRESHOLDS",
    "LABEL_SCORES",
    "GraspResults",
    "ViewGraspResult",
    "evaluate_grasps",
    "ground_truth_grasps",
    "load_predictions",
]

#: Kinds of grasps (the ``kind`` of a prediction entry).
KINDS = ("suction", "paralleljaw")
DEFAULT_KS: tuple[int, ...] = (1, 5, 10, 25, 50)
DEFAULT_THRESHOLDS: tuple[float, ...] = (0.2, 0.4, 0.6, 0.8)
#: Contact position tolerance of the matching, m (see the module docstring).
DEFAULT_MATCH_DISTANCE = 0.01
#: Axis angle tolerance of the matching, rad (30 deg, as the Cornell / Jacquard rectangle metric).
DEFAULT_MATCH_ANGLE = math.pi / 6
#: A pose's rotation may deviate this much from orthonormal (max |R^T R - I|) before it is
#: rejected; accepted rotations are re-orthonormalised.
ORTHONORMAL_TOLERANCE = 1e-3
LABEL_SCORES = ("analytical", "simulation", "wrench")
_GROUP = {"suction": "suctioncup", "paralleljaw": "paralleljaw"}
_WINDOW = 2  # half-size of the normal-estimation window, px


# --------------------------------------------------------------------------------------------
# Results


@dataclass(frozen=True)
class ViewGraspResult:
    """The score of one view.

    Attributes:
        image_id: scene_id * 1000 + view_id.
        num_predictions: predictions of the evaluated kind in the view.
        matched: predictions that matched a label; colliding: of those, how many collide.
        precision: {threshold: {k: precision@k}}.
    """

    image_id: int
    num_predictions: int
    matched: int
    colliding: int
    precision: dict[float, dict[int, float]]


@dataclass(frozen=True)
class GraspResults:
    """Result of :func:`evaluate_grasps` (see the module docstring for the definitions).

    Attributes:
        kind: "suction" or "paralleljaw"; label_score: the label score compared with thresholds.
        ks, thresholds: as requested; match_distance (m), match_angle (rad): the tolerances.
        precision: {threshold: {k: mean precision@k over the views}}.
        success_rate: {threshold: successes / predictions}.
        num_views: views scored (entries of the file of this kind); num_predictions: grasps.
        views_short: {k: views with fewer than k predictions (divided by their count)}.
        matched: predictions that matched a label; unmatched = num_predictions - matched
            (no label within the tolerances, or no depth at a pixel prediction).
        rejected_by_collision: matched predictions whose pose collides.
        below_threshold: {threshold: matched, collision-free predictions with label score < t}.
        ignored_entries: entries of the other kind in the prediction list (not scored).
        views: per-view results, in the order of the prediction list.
    """

    kind: str
    label_score: str
    ks: tuple[int, ...]
    thresholds: tuple[float, ...]
    match_distance: float
    match_angle: float
    precision: dict[float, dict[int, float]]
    success_rate: dict[float, float]
    num_views: int
    num_predictions: int
    views_short: dict[int, int]
    matched: int
    rejected_by_collision: int
    below_threshold: dict[float, int]
    ignored_entries: int = 0
    views: tuple[ViewGraspResult, ...] = field(default=(), repr=False)

    @property
    def rejected_by_matching(self) -> int:
        """Predictions that matched no label."""
        return self.num_predictions - self.matched

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (keys ``"P@k"`` and thresholds as strings)."""

        def by_k(d: Mapping[int, float]) -> dict[str, float]:
            return {f"P@{k}": v for k, v in d.items()}

        return {
            "kind": self.kind,
            "label_score": self.label_score,
            "ks": list(self.ks),
            "thresholds": list(self.thresholds),
            "match_distance_m": self.match_distance,
            "match_angle_rad": self.match_angle,
            "num_views": self.num_views,
            "num_predictions": self.num_predictions,
            "precision": {str(t): by_k(p) for t, p in self.precision.items()},
            "success_rate": {str(t): v for t, v in self.success_rate.items()},
            "views_short": {f"P@{k}": v for k, v in self.views_short.items()},
            "matched": self.matched,
            "rejected_by_matching": self.rejected_by_matching,
            "rejected_by_collision": self.rejected_by_collision,
            "below_threshold": {str(t): v for t, v in self.below_threshold.items()},
            "ignored_entries": self.ignored_entries,
            "views": [
                {
                    "image_id": v.image_id,
                    "num_predictions": v.num_predictions,
                    "matched": v.matched,
                    "colliding": v.colliding,
                    "precision": {str(t): by_k(p) for t, p in v.precision.items()},
                }
                for v in self.views
            ],
        }

    def table(self) -> str:
        """Rows: label-score thresholds; columns: P@k for each k, then the success rate."""
        cols = ["threshold"] + [f"P@{k}" for k in self.ks] + ["success"]
        rows = [
            {
                "threshold": f"{t:g}",
                **{f"P@{k}": self.precision[t][k] for k in self.ks},
                "success": self.success_rate[t],
            }
            for t in self.thresholds
        ]
        title = (
            f"{self.kind} grasps: {self.num_views} views, {self.num_predictions} predictions "
            f"({self.rejected_by_matching} unmatched, {self.rejected_by_collision} colliding); "
            f"label score: {self.label_score}"
        )
        return format_table(rows, cols, title=title)


# --------------------------------------------------------------------------------------------
# Input


def load_predictions(
    source: str | os.PathLike[str] | Sequence[Mapping[str, Any]],
) -> list[dict[str, Any]]:
    """The prediction list from a JSON file path, or a list given directly (checked to be a list
    of objects)."""
    if isinstance(source, (str, os.PathLike)):
        p = Path(source)
        try:
            data = json.loads(p.read_text())
        except FileNotFoundError:
            raise IoError(f"predictions: '{p}' does not exist") from None
        except (OSError, ValueError) as e:
            raise InvalidArgumentError(f"predictions: '{p}' is not readable JSON: {e}") from e
    else:
        data = source
    if not isinstance(data, (list, tuple)) or not all(isinstance(e, Mapping) for e in data):
        raise InvalidArgumentError(
            "predictions: expected a list of {'image_id', 'kind', 'grasps'} objects"
        )
    return list(data)


def _number(value: Any, what: str, *, low: float | None = None, high: float | None = None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InvalidArgumentError(f"{what}: expected a number, got {value!r}")
    x = float(value)
    if not math.isfinite(x) or (low is not None and x < low) or (high is not None and x > high):
        rng = f" in [{low}, {high}]" if low is not None or high is not None else ""
        raise InvalidArgumentError(f"{what}: expected a finite number{rng}, got {value!r}")
    return x


def _rigid(value: Any, what: str) -> npt.NDArray[np.float64]:
    """A 4x4 rigid transform (rotation re-orthonormalised), or InvalidArgumentError."""
    try:
        X = np.asarray(value, np.float64)
    except (TypeError, ValueError):
        raise InvalidArgumentError(f"{what}: expected a 4x4 array of numbers") from None
    if X.shape != (4, 4):
        raise InvalidArgumentError(f"{what}: expected a 4x4 matrix, got shape {X.shape}")
    if not np.isfinite(X).all():
        raise InvalidArgumentError(f"{what}: contains NaN or infinity")
    R = X[:3, :3]
    err = float(np.abs(R.T @ R - np.eye(3)).max())
    if err > ORTHONORMAL_TOLERANCE or np.linalg.det(R) <= 0:
        raise InvalidArgumentError(
            f"{what}: the rotation must be orthonormal and right-handed (max |R^T R - I| <= "
            f"{ORTHONORMAL_TOLERANCE}, det > 0), got max |R^T R - I| = {err:.3g}, "
            f"det = {np.linalg.det(R):.3g}"
        )
    if np.abs(X[3] - (0, 0, 0, 1)).max() > 1e-9:
        raise InvalidArgumentError(f"{what}: the last row must be [0, 0, 0, 1], got {X[3]}")
    u, _, vt = np.linalg.svd(R)
    out: npt.NDArray[np.float64] = X.copy()
    out[:3, :3] = u @ vt
    out[3] = (0, 0, 0, 1)
    return out


def _frame_z(a: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """A rotation with z = a (unit)."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, a)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(a, x), a])


@dataclass
class _ViewData:
    """What the evaluation reads of one view (camera frame, metres)."""

    scene_id: int
    X_WC: npt.NDArray[np.float64]
    K: Any
    depth: npt.NDArray[np.float32] | None
    instances: npt.NDArray[np.int32] | None
    # labels: contact frames (L, 4, 4), widths (L,), scores (L,), object ids (L,)
    contact: npt.NDArray[np.float64]
    width: npt.NDArray[np.float64]
    score: npt.NDArray[np.float64]
    object_id: npt.NDArray[np.int32]
    num_non_colliding: int
    source: Any = None  # the mgn.io.dataset.View (depth and instances are read on demand)


class _Context:
    """Lazy per-view data and per-scene collision models of one dataset."""

    def __init__(self, dataset: Any, kind: str, label_score: str, num_threads: int) -> None:

        self.ds = dataset if isinstance(dataset, Dataset) else Dataset(dataset)
        self.kind = kind
        self.label_score = label_score
        self.num_threads = num_threads
        self._views: dict[int, _ViewData] = {}
        self._models: dict[int, Any] = {}
        self._hardware: tuple[Any, Any] | None = None

    def hardware(self) -> tuple[Any, Any]:
        """(gripper, cup) of the dataset: its config, else the root YAML files, else defaults."""
        if self._hardware is None:
            info = self.ds.info
            if info is not None and isinstance(info.get("config"), Mapping):
                cfg = Config.from_dict(info["config"], base_dir=self.ds.root)
                self._hardware = (cfg.gripper, cfg.cup)
            else:
                g, c = self.ds.root / "gripper.yaml", self.ds.root / "suction_cup.yaml"
                self._hardware = (
                    ParallelJawGripper.from_yaml(g) if g.exists() else ParallelJawGripper(),
                    SuctionCup.from_yaml(c) if c.exists() else SuctionCup(),
                )
        return self._hardware

    def view(self, image_id: int, what: str) -> _ViewData:
        if image_id in self._views:
            return self._views[image_id]
        scene_id, view_id = divmod(image_id, 1000)
        if image_id < 0 or scene_id not in self.ds.scene_ids:
            raise InvalidArgumentError(
                f"{what}: unknown image_id {image_id} (scene {scene_id} is not in the dataset; "
                f"scenes: {self.ds.scene_ids[:20]}); expected scene_id * 1000 + view_id"
            )
        scene = self.ds.scene(scene_id)
        if view_id not in scene.view_ids:
            raise InvalidArgumentError(
                f"{what}: unknown image_id {image_id} (scene {scene_id} has views "
                f"{scene.view_ids}); expected scene_id * 1000 + view_id"
            )
        v = scene.view(view_id)
        group = _GROUP[self.kind]
        parts = [v.grasps(group, colliding=False), v.grasps(group, colliding=True)]
        key = f"score_{self.label_score}"
        contact, width, score, obj = [], [], [], []
        for g in parts:
            n = len(g.get("object_id", ()))
            X = g.get("contact_poses_relative_to_camera", np.zeros((0, 4, 4)))
            contact.append(np.asarray(X, np.float64).reshape(n, 4, 4))
            width.append(np.asarray(g.get("contact_width", np.zeros(n)), np.float64).reshape(n))
            s = g.get(key)
            score.append(np.full(n, np.nan) if s is None else np.asarray(s, np.float64))
            obj.append(np.asarray(g.get("object_id", np.zeros(0)), np.float64).astype(np.int32))
        d = v.depth_ideal
        data = _ViewData(
            scene_id=scene_id,
            X_WC=_rigid(v.X_WC, f"image {image_id} camera pose"),
            K=v.intrinsics,
            depth=d,
            instances=None,
            contact=np.concatenate(contact),
            width=np.concatenate(width),
            score=np.concatenate(score),
            object_id=np.concatenate(obj),
            num_non_colliding=len(parts[0].get("object_id", ())),
            source=v,
        )
        self._views[image_id] = data
        return data

    def pixel_maps(self, data: _ViewData) -> tuple[np.ndarray, np.ndarray]:
        if data.depth is None:
            data.depth = data.source.depth
        if data.instances is None:
            data.instances = data.source.instances
        return data.depth, data.instances

    def model(self, scene_id: int) -> Any:
        """The scene's SceneGraspModel: obstacles and tools of the labels (no labels needed)."""
        if scene_id not in self._models:
            folder = self.ds.scene(scene_id).folder
            path = folder / "scene.json"
            if not path.exists():
                raise IoError(
                    f"{folder}: no scene.json; grasp evaluation needs the scene (object poses, "
                    "tote) to check collisions with the labels' model"
                )
            scene = read_scene_json(path)
            gripper, cup = self.hardware()
            n = len(scene.instances)
            self._models[scene_id] = SceneGraspModel(
                scene,
                [None] * n,
                [None] * n,
                gripper,
                cup,
                offsets=LabelOptions().grasp_offsets,
                num_threads=self.num_threads,
            )
        return self._models[scene_id]


# --------------------------------------------------------------------------------------------
# Predictions -> contact frames


def _rays(K: Any, u: npt.ArrayLike, v: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """(N, 2) normalised rays (x/z, y/z) through image points (u, v), px, through the lens of
    the view's camera (docs/cameras.md)."""
    lens = lens_for(K)
    if lens is not None:
        return lens.normalized(u, v)
    ua, va = np.atleast_1d(np.asarray(u, np.float64)), np.atleast_1d(np.asarray(v, np.float64))
    return np.stack([(ua - K.cx) / K.fx, (va - K.cy) / K.fy], axis=1)


def _backproject(K: Any, u: float, v: float, z: float) -> npt.NDArray[np.float64]:
    x, y = _rays(K, u, v)[0]
    return np.array([x * z, y * z, z])


def _pixel(
    ctx: _Context, data: _ViewData, g: Mapping[str, Any], what: str
) -> tuple[float, float, int, int, float, np.ndarray, np.ndarray]:
    uv = g["uv"]
    if not isinstance(uv, (list, tuple)) or len(uv) != 2:
        raise InvalidArgumentError(f"{what}.uv: expected [u, v] in pixels, got {uv!r}")
    K = data.K
    u = _number(uv[0], f"{what}.uv[0]", low=0.0, high=float(K.width))
    v = _number(uv[1], f"{what}.uv[1]", low=0.0, high=float(K.height))
    c, r = min(int(u), K.width - 1), min(int(v), K.height - 1)
    depth, inst = ctx.pixel_maps(data)
    z = float(depth[r, c])
    return u, v, c, r, z, depth, inst


def _suction_pixel(
    ctx: _Context, data: _ViewData, g: Mapping[str, Any], what: str
) -> npt.NDArray[np.float64] | None:
    u, v, c, r, z, depth, inst = _pixel(ctx, data, g, what)
    if not math.isfinite(z):
        return None
    K = data.K
    p = _backproject(K, u, v, z)
    r0, r1 = max(r - _WINDOW, 0), min(r + _WINDOW + 1, K.height)
    c0, c1 = max(c - _WINDOW, 0), min(c + _WINDOW + 1, K.width)
    rows, cols = np.mgrid[r0:r1, c0:c1]
    zz = depth[r0:r1, c0:c1].astype(np.float64)
    ok = np.isfinite(zz) & (inst[r0:r1, c0:c1] == inst[r, c])
    if ok.sum() < 3:
        return None
    xy = _rays(K, cols[ok] + 0.5, rows[ok] + 0.5)
    pts = np.column_stack([xy[:, 0] * zz[ok], xy[:, 1] * zz[ok], zz[ok]])
    centred = pts - pts.mean(axis=0)
    _, s, vt = np.linalg.svd(centred, full_matrices=False)
    if len(s) < 3 or s[1] <= 1e-12:
        return None  # collinear pixels: no plane
    n = vt[2]
    if n @ p < 0:  # point the approach away from the camera (into the surface)
        n = -n
    X = np.eye(4)
    X[:3, :3] = _frame_z(n / np.linalg.norm(n))
    X[:3, 3] = p
    return X


def _pj_pixel(
    ctx: _Context, data: _ViewData, g: Mapping[str, Any], what: str, width: float
) -> npt.NDArray[np.float64] | None:
    for key in ("angle",):
        if key not in g:
            raise InvalidArgumentError(f"{what}: a pixel parallel-jaw grasp needs '{key}' (rad)")
    angle = _number(g["angle"], f"{what}.angle")
    extra = _number(g.get("depth", 0.0), f"{what}.depth")
    u, v, _, _, z, _, _ = _pixel(ctx, data, g, what)
    if not math.isfinite(z):
        return None
    centre = _backproject(data.K, u, v, z + extra)
    a = np.array([0.0, 0.0, 1.0])
    closing = np.array([math.cos(angle), math.sin(angle), 0.0])
    X = np.eye(4)
    X[:3, :3] = np.column_stack([closing, np.cross(a, closing), a])
    X[:3, 3] = centre - 0.5 * width * closing
    return X


def _parse_view(
    ctx: _Context, data: _ViewData, entry: Mapping[str, Any], what: str
) -> tuple[
    npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.bool_]
]:
    """(contact frames (n,4,4) camera, widths (n,), scores (n,), located (n,) bool)."""
    grasps = entry.get("grasps")
    if not isinstance(grasps, (list, tuple)):
        raise InvalidArgumentError(f"{what}.grasps: expected a list of grasps, got {grasps!r}")
    n = len(grasps)
    X = np.tile(np.eye(4), (n, 1, 1))
    width = np.zeros(n)
    score = np.zeros(n)
    located = np.ones(n, bool)
    max_opening = float(ctx.hardware()[0].max_opening)
    for i, g in enumerate(grasps):
        w_i = f"{what}.grasps[{i}]"
        if not isinstance(g, Mapping):
            raise InvalidArgumentError(f"{w_i}: expected an object, got {g!r}")
        score[i] = _number(g.get("score"), f"{w_i}.score")
        has_pose, has_uv = "pose" in g, "uv" in g
        if has_pose == has_uv:
            raise InvalidArgumentError(f"{w_i}: expected exactly one of 'pose' (6-DoF) or 'uv'")
        if ctx.kind == "paralleljaw":
            if "width" not in g:
                raise InvalidArgumentError(f"{w_i}: a parallel-jaw grasp needs 'width' (m)")
            width[i] = _number(g["width"], f"{w_i}.width", low=0.0, high=max_opening)
        elif "width" in g or "angle" in g:
            raise InvalidArgumentError(
                f"{w_i}: 'width' / 'angle' belong to parallel-jaw grasps, but the entry's kind "
                "is 'suction'"
            )
        if has_pose:
            X[i] = _rigid(g["pose"], f"{w_i}.pose")
            continue
        Xi = (
            _pj_pixel(ctx, data, g, w_i, width[i])
            if ctx.kind == "paralleljaw"
            else _suction_pixel(ctx, data, g, w_i)
        )
        if Xi is None:
            located[i] = False
        else:
            X[i] = Xi
    return X, width, score, located


# --------------------------------------------------------------------------------------------
# Matching


def _angle(cos: np.ndarray) -> np.ndarray:
    out: np.ndarray = np.arccos(np.clip(cos, -1.0, 1.0))
    return out


def _match(
    kind: str,
    X: np.ndarray,
    width: np.ndarray,
    L: np.ndarray,
    Lw: np.ndarray,
    match_distance: float,
    match_angle: float,
) -> np.ndarray:
    """Index of the matched label per prediction, -1 for none (see the module docstring)."""
    n, m = len(X), len(L)
    if n == 0 or m == 0:
        return np.full(n, -1, np.int64)
    a, la = X[:, :3, 2], L[:, :3, 2]
    v, lv = X[:, :3, 0], L[:, :3, 0]
    p1, q1 = X[:, :3, 3], L[:, :3, 3]
    if kind == "suction":
        c, lc = p1, q1
    else:
        p2, q2 = p1 + width[:, None] * v, q1 + Lw[:, None] * lv
        # Midpoints: under the better pairing they are at most the contact distance apart.
        c, lc = 0.5 * (p1 + p2), 0.5 * (q1 + q2)
    # Candidate pairs by the centre distance (|c|^2 + |l|^2 - 2 c.l, with a margin for rounding).
    sq = (c * c).sum(1)[:, None] + (lc * lc).sum(1)[None, :] - 2.0 * (c @ lc.T)
    i, j = np.nonzero(sq <= (match_distance + 1e-6) ** 2)
    ang = _angle((a[i] * la[j]).sum(1))
    if kind == "suction":
        dist = np.linalg.norm(p1[i] - q1[j], axis=1)
    else:

        def d(p: np.ndarray, q: np.ndarray) -> np.ndarray:
            out: np.ndarray = np.linalg.norm(p - q, axis=1)
            return out

        same = np.maximum(d(p1[i], q1[j]), d(p2[i], q2[j]))
        swapped = np.maximum(d(p1[i], q2[j]), d(p2[i], q1[j]))
        dist = np.minimum(same, swapped)
        ang = np.maximum(ang, _angle(np.abs((v[i] * lv[j]).sum(1))))
    ok = (dist <= match_distance) & (ang <= match_angle)
    cost = np.full((n, m), np.inf)
    cost[i[ok], j[ok]] = dist[ok] / match_distance + ang[ok] / match_angle
    best = np.argmin(cost, axis=1)
    return np.where(np.isfinite(cost[np.arange(n), best]), best, -1)


# --------------------------------------------------------------------------------------------
# Evaluation


def _check_kind(kind: Any, what: str) -> str:

    try:
        return normalize_grasp_kind(kind)
    except InvalidArgumentError:
        raise InvalidArgumentError(
            f"{what}: kind must be 'suction' or 'paralleljaw' (or an alias: suctioncup, pj, ...), "
            f"got {kind!r}"
        ) from None


def _default_label_score(kind: str, label_score: str | None) -> str:
    score = label_score if label_score is not None else "analytical"
    if score not in LABEL_SCORES:
        raise InvalidArgumentError(
            f"label_score must be one of {list(LABEL_SCORES)}, got {label_score!r}"
        )
    if kind == "suction" and score == "simulation":
        raise InvalidArgumentError(
            "label_score 'simulation' does not exist for suction labels (their physics score is "
            "the seal score, 'analytical')"
        )
    return score


def evaluate_grasps(
    dataset: Any,
    predictions: str | os.PathLike[str] | Sequence[Mapping[str, Any]],
    *,
    kind: str = "suction",
    ks: Iterable[int] = DEFAULT_KS,
    thresholds: Iterable[float] = DEFAULT_THRESHOLDS,
    match_distance: float = DEFAULT_MATCH_DISTANCE,
    match_angle: float = DEFAULT_MATCH_ANGLE,
    label_score: str | None = None,
    num_threads: int = 0,
) -> GraspResults:
    """precision@k of the grasp predictions of one kind (see the module docstring).

    Args:
        dataset: a :class:`mgn.Dataset` or its root folder.
        predictions: the prediction list or the path of its JSON file.
        kind: "suction" or "paralleljaw"; entries of the other kind are ignored (counted).
        ks: positive k of precision@k; thresholds: label-score thresholds in [0, 1].
        match_distance: contact tolerance, m (> 0); match_angle: axis tolerance, rad (> 0).
        label_score: "analytical" (default: seal score / antipodal score), "simulation"
            (parallel-jaw physics) or "wrench".
        num_threads: C++ threads of the collision checks (0 = all); results do not depend on it.

    Raises:
        InvalidArgumentError: an unknown image_id or kind, no entry of ``kind``, two entries for
            one view, a malformed grasp (missing or non-finite field, a non-orthonormal pose,
            a width outside [0, max_opening], uv outside the image), bad ks / thresholds /
            tolerances.
        IoError: the dataset or the prediction file cannot be read.
    """
    kind = _check_kind(kind, "evaluate_grasps")
    score_name = _default_label_score(kind, label_score)
    ks_in, th_in = list(ks), list(thresholds)
    if not ks_in or any(
        isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1 for k in ks_in
    ):
        raise InvalidArgumentError(f"evaluate_grasps: ks must be integers >= 1, got {ks_in}")
    ks_t = tuple(int(k) for k in ks_in)
    if not th_in or any(
        not isinstance(t, (int, float, np.number)) or not (0.0 <= t <= 1.0) for t in th_in
    ):
        raise InvalidArgumentError(
            f"evaluate_grasps: thresholds must be numbers in [0, 1], got {th_in}"
        )
    th = tuple(float(t) for t in th_in)
    md = _number(match_distance, "evaluate_grasps: match_distance (m)", low=0.0)
    ma = _number(match_angle, "evaluate_grasps: match_angle (rad)", low=0.0, high=math.pi)
    if md <= 0 or ma <= 0:
        raise InvalidArgumentError("evaluate_grasps: match_distance and match_angle must be > 0")
    entries = load_predictions(predictions)
    ctx = _Context(dataset, kind, score_name, num_threads)

    mine: list[tuple[int, Mapping[str, Any]]] = []
    seen: set[int] = set()
    kinds_found: set[str] = set()
    for e_i, entry in enumerate(entries):
        what = f"predictions[{e_i}]"
        kinds_found.add(_check_kind(entry.get("kind"), what))
        image_id = entry.get("image_id")
        if isinstance(image_id, bool) or not isinstance(image_id, (int, np.integer)):
            raise InvalidArgumentError(f"{what}.image_id: expected an integer, got {image_id!r}")
        if entry["kind"] != kind:
            continue
        if int(image_id) in seen:
            raise InvalidArgumentError(
                f"{what}: a second '{kind}' entry for image_id {image_id}; expected one per view"
            )
        seen.add(int(image_id))
        mine.append((e_i, entry))
    if not mine:
        raise InvalidArgumentError(
            f"evaluate_grasps: no '{kind}' predictions (the list has kinds {sorted(kinds_found)})"
        )

    # Parse everything first (errors before any collision work), then score per view.
    parsed = []
    for e_i, pred in mine:
        what = f"predictions[{e_i}]"
        data = ctx.view(int(pred["image_id"]), what)
        parsed.append((int(pred["image_id"]), data, *_parse_view(ctx, data, pred, what)))

    views: list[ViewGraspResult] = []
    total = matched_all = colliding_all = 0
    successes = dict.fromkeys(th, 0)
    below = dict.fromkeys(th, 0)
    core_kind = "pj" if kind == "paralleljaw" else "suction"
    for image_id, data, X, width, score, located in parsed:
        n = len(score)
        match = _match(kind, X, width, data.contact, data.width, md, ma)
        match[~located] = -1
        ok = match >= 0
        free = np.zeros(n, bool)
        if ok.any():
            model = ctx.model(data.scene_id)
            X_W = data.X_WC[None] @ X[ok]
            c = model.collides(
                core_kind, X_W, width[ok], data.object_id[match[ok]], check_target_at_grasp=True
            )
            free[ok] = ~c.colliding
        lab = np.where(ok, data.score[np.maximum(match, 0)] if len(data.score) else 0.0, np.nan)
        order = np.argsort(-score, kind="stable")
        prec: dict[float, dict[int, float]] = {}
        for t in th:
            with np.errstate(invalid="ignore"):
                succ = ok & free & (lab >= t)
            successes[t] += int(succ.sum())
            below[t] += int((ok & free).sum() - succ.sum())
            ranked = succ[order]
            prec[t] = {k: float(ranked[:k].sum() / min(k, n)) if n else 0.0 for k in ks_t}
        total += n
        matched_all += int(ok.sum())
        colliding_all += int((ok & ~free).sum())
        views.append(ViewGraspResult(image_id, n, int(ok.sum()), int((ok & ~free).sum()), prec))

    nv = len(views)
    return GraspResults(
        kind=kind,
        label_score=score_name,
        ks=ks_t,
        thresholds=th,
        match_distance=md,
        match_angle=ma,
        precision={
            t: {k: float(np.mean([v.precision[t][k] for v in views])) for k in ks_t} for t in th
        },
        success_rate={t: successes[t] / total if total else 0.0 for t in th},
        num_views=nv,
        num_predictions=total,
        views_short={k: sum(1 for v in views if v.num_predictions < k) for k in ks_t},
        matched=matched_all,
        rejected_by_collision=colliding_all,
        below_threshold=below,
        ignored_entries=len(entries) - len(mine),
        views=tuple(views),
    )


def ground_truth_grasps(
    dataset: Any,
    kind: str = "suction",
    *,
    label_score: str | None = None,
    min_score: float | None = None,
) -> list[dict[str, Any]]:
    """The non-colliding label grasps of every view as a prediction list (6-DoF contact poses,
    camera frame; score = the label score, NaN scores become 0). ``min_score`` keeps only labels
    with score >= it. Views without such grasps get an entry with an empty list."""

    kind = _check_kind(kind, "ground_truth_grasps")
    score_name = _default_label_score(kind, label_score)
    ds = dataset if isinstance(dataset, Dataset) else Dataset(dataset)
    out: list[dict[str, Any]] = []
    for scene in ds.scenes():
        for view in scene.views():
            g = view.grasps(_GROUP[kind])
            n = len(g.get("object_id", ()))
            poses = np.asarray(
                g.get("contact_poses_relative_to_camera", np.zeros((0, 4, 4))), np.float64
            ).reshape(n, 4, 4)
            s = np.asarray(g.get(f"score_{score_name}", np.full(n, np.nan)), np.float64)
            s = np.where(np.isfinite(s), s, 0.0)
            keep = np.ones(n, bool) if min_score is None else s >= min_score
            grasps = []
            for i in np.flatnonzero(keep):
                item: dict[str, Any] = {"pose": poses[i].tolist(), "score": float(s[i])}
                if kind == "paralleljaw":
                    item["width"] = float(g["contact_width"][i])
                grasps.append(item)
            out.append(
                {"image_id": scene.scene_id * 1000 + view.index, "kind": kind, "grasps": grasps}
            )
    return out
