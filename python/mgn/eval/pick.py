"""Closed-loop picking in simulation: ``mgn pick`` (MetaGraspNet's R_grasp, R_object, R_mixture).

:func:`run_picking` repeatedly renders the top view of the tote, lets a policy choose a grasp,
decides whether the grasp succeeds, removes the object when it does, lets the rest of the pile
settle again (:func:`mgn.scene.settle`, Bullet) and measures how much the other objects moved,
until the tote is empty, every remaining object has failed ``max_failures_per_object`` times
(two, as in the paper), the policy gives up, or ``max_attempts`` is reached.

Success model (the label model, rebuilt at the current poses every step):

1. The grasp is one of the object-level labels placed at the object's current pose by
   :class:`mgn.view_labels.grasps.SceneGraspModel` (a policy giving a tool pose is matched to the
   nearest label of that object: tool origin within :data:`MATCH_DISTANCE`, approach within
   :data:`MATCH_ANGLE`; otherwise the attempt fails with reason ``"no_label"``).
2. It must be collision-free: the tool at the grasp and along its approach (the label model's
   offsets) touches no other object and not the tote; else reason ``"collision"``.
3. Its score at the current pose must reach ``success_threshold`` (default 0.5); else reason
   ``"score"``. Suction: seal score x suction wrench score (gravity (0, 0, -1) in the tote frame
   expressed at the object's current pose). Parallel jaw: physics (shake) score, or the
   analytical antipodal score where the labels have no physics score, x soft-finger wrench
   score at the current pose. Non-finite factors are left out.
4. With ``stochastic=True`` step 3 is replaced by a draw: success with probability = score,
   from a random stream seeded by (seed, step) (reason ``"draw"`` on failure), so a run is
   reproducible for a seed.

A failed attempt leaves the pile as it was (no disturbance); the same object may be tried
again with another grasp until it has failed ``max_failures_per_object`` times.

Policies:

- ``"label"``: the best-scored collision-free grasp whose contact is visible in the top view,
  among the top-layer objects (layer 0 of :func:`mgn.view_labels.layout.compute_layout` on the top
  view) that may still be tried; grasps already tried on an object are skipped. If no top-layer
  object has such a grasp, all visible objects are considered; if none has one, the run stops.
- ``"random"``: a random visible object that may still be tried, and a random visible grasp
  of it (colliding or not) not tried before, from a stream seeded by (seed, step).
- a callable ``policy(state) -> (instance_id, grasp) | None`` with ``state`` a
  :class:`PickState`: ``instance_id`` is an id of ``state.scene`` (1..N, renumbered after
  each pick), ``grasp`` is a row index of ``state.grasps`` (which must belong to that
  object) or a (4, 4) tool pose ``X_W_tool`` in the tote frame (hand flange pose for the
  parallel-jaw gripper, tool pose for suction, as in ``state.grasps.tool_poses``); ``None``
  stops the run.

Metrics: R_grasp = successful grasps / attempts; R_object = objects cleared / objects at the
start; R_mixture = objects cleared at their first attempt / objects cleared (0 when none).
Disturbance of a pick: translation (m) and rotation (rad) of every other object between before
the pick and after the pile settled again (max and mean); objects that left the tote while
settling are listed in ``lost``.
"""

from __future__ import annotations

import dataclasses
import importlib
import math
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from PIL import Image, ImageDraw

from mgn.errors import InvalidArgumentError
from mgn.eval.results import format_table, write_results_json
from mgn.hardware import normalize_grasp_kind
from mgn.objects import tote_mesh
from mgn.pipeline.config import Config, default_config
from mgn.pipeline.label_cache import ObjectLabels
from mgn.pipeline.label_cache import object_labels as cached_labels
from mgn.pipeline.label_scene import LabelOptions, strided_subset
from mgn.pipeline.scene_writer import scene_intrinsics
from mgn.render.views import ViewImages, iter_views
from mgn.scene.cameras import CameraView, mgn_rig
from mgn.scene.drop import settle_tracked
from mgn.scene.scene import DropOptions, Scene
from mgn.view_labels.grasps import PlacedGrasps, SceneGraspModel
from mgn.view_labels.layout import Layout, compute_layout
from mgn.view_labels.objects import SceneRayModel, ViewObjectLabels, view_object_labels

__all__ = [
    "MATCH_ANGLE",
    "MATCH_DISTANCE",
    "PickAttempt",
    "PickResults",
    "PickState",
    "run_picking",
]

#: A policy's tool pose matches a label when the tool origins are this close, m.
MATCH_DISTANCE = 0.01
#: ... and the approach axes (tool z) are within this angle, rad.
MATCH_ANGLE = 0.2
_GRIPPERS = ("suction", "paralleljaw")


@dataclass(frozen=True)
class PickState:
    """What a policy sees before an attempt.

    Attributes:
        step: attempt index (0-based).
        scene: the current scene (instances 1..N; renumbered after every successful pick).
        original_ids: (N,) the id each current instance had in the start scene.
        view: the top camera; images: its rendering (``rgb``, ``depth_ideal``,
            ``instance_ids``); labels: its object labels (masks, occlusion); layout: its layout
            (``layer``: 0 = top layer).
        grasps: every grasp label of the gripper placed at the current poses (world frame,
            objects concatenated; ``object_id`` = instance id - 1, ``colliding``, scores).
        model: the :class:`~mgn.view_labels.grasps.SceneGraspModel` the grasps come from.
        visible: (M,) bool, the grasp's contact is visible in the top view.
        score: (M,) float, the success model's score of each grasp (see the module doc).
        eligible: (N,) bool, the instance may still be tried (fewer failures than allowed).
        tried: (M,) bool, the grasp was already tried on this object.
    """

    step: int
    scene: Scene
    original_ids: tuple[int, ...]
    view: CameraView
    images: ViewImages
    labels: ViewObjectLabels
    layout: Layout
    grasps: PlacedGrasps
    model: SceneGraspModel = field(repr=False)
    visible: npt.NDArray[np.bool_] = field(repr=False)
    score: npt.NDArray[np.float64] = field(repr=False)
    eligible: npt.NDArray[np.bool_] = field(repr=False)
    tried: npt.NDArray[np.bool_] = field(repr=False)


@dataclass(frozen=True)
class PickAttempt:
    """One attempt.

    Attributes:
        step: attempt index (0-based).
        instance_id: the target's id in the start scene; name: its object name.
        grasp_index: the grasp's row among the target object's placed labels (-1: none matched).
        X_W_tool: the tool pose of the grasp (4x4 nested tuples, tote frame, m).
        score: the success model's score (NaN when no label matched).
        success: the object was picked; reason: ``"ok"``, ``"collision"``, ``"score"``,
            ``"draw"`` (stochastic failure) or ``"no_label"``.
        disturbance_max_translation, disturbance_mean_translation: m, of the other objects
            after re-settling (0 for a failed attempt or when no other object is left).
        disturbance_max_rotation, disturbance_mean_rotation: rad, likewise.
        lost: start-scene ids of objects that left the tote while settling.
        remaining: objects in the tote after the attempt.
    """

    step: int
    instance_id: int
    name: str
    grasp_index: int
    X_W_tool: tuple[tuple[float, ...], ...]
    score: float
    success: bool
    reason: str
    disturbance_max_translation: float = 0.0
    disturbance_mean_translation: float = 0.0
    disturbance_max_rotation: float = 0.0
    disturbance_mean_rotation: float = 0.0
    lost: tuple[int, ...] = ()
    remaining: int = 0

    def to_dict(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["X_W_tool"] = [list(r) for r in self.X_W_tool]
        d["lost"] = list(self.lost)
        return d


_TABLE_COLUMNS = (
    "step",
    "instance_id",
    "name",
    "grasp_index",
    "score",
    "success",
    "reason",
    "dist_max_mm",
    "dist_mean_mm",
    "rot_max_deg",
    "remaining",
)


@dataclass(frozen=True)
class PickResults:
    """The outcome of :func:`run_picking`.

    Attributes:
        attempts: every attempt in order.
        num_objects: objects in the tote at the start.
        cleared: start-scene ids of the picked objects, in pick order; cleared_first_attempt:
            those picked at their first attempt.
        stop_reason: ``"empty"``, ``"failures"`` (every remaining object failed too often),
            ``"no_grasp"`` (the policy found nothing), or ``"max_attempts"``.
        policy, gripper, seed, stochastic, success_threshold: the settings of the run.
    """

    attempts: tuple[PickAttempt, ...]
    num_objects: int
    cleared: tuple[int, ...]
    cleared_first_attempt: tuple[int, ...]
    stop_reason: str
    policy: str
    gripper: str
    seed: int
    stochastic: bool
    success_threshold: float

    @property
    def R_grasp(self) -> float:  # the paper's symbol
        """Successful grasps / attempts (0 without attempts)."""
        return len(self.cleared) / len(self.attempts) if self.attempts else 0.0

    @property
    def R_object(self) -> float:
        """Objects cleared / objects at the start."""
        return len(self.cleared) / self.num_objects if self.num_objects else 0.0

    @property
    def R_mixture(self) -> float:
        """Objects cleared at the first attempt / objects cleared (0 when none)."""
        return len(self.cleared_first_attempt) / len(self.cleared) if self.cleared else 0.0

    def to_dict(self) -> dict[str, Any]:
        return {
            "policy": self.policy,
            "gripper": self.gripper,
            "seed": self.seed,
            "stochastic": self.stochastic,
            "success_threshold": self.success_threshold,
            "num_objects": self.num_objects,
            "num_attempts": len(self.attempts),
            "cleared": list(self.cleared),
            "cleared_first_attempt": list(self.cleared_first_attempt),
            "stop_reason": self.stop_reason,
            "R_grasp": self.R_grasp,
            "R_object": self.R_object,
            "R_mixture": self.R_mixture,
            "attempts": [a.to_dict() for a in self.attempts],
        }

    def table(self) -> str:

        rows = [
            {
                "step": a.step,
                "instance_id": a.instance_id,
                "name": a.name,
                "grasp_index": a.grasp_index,
                "score": a.score,
                "success": a.success,
                "reason": a.reason,
                "dist_max_mm": 1000.0 * a.disturbance_max_translation,
                "dist_mean_mm": 1000.0 * a.disturbance_mean_translation,
                "rot_max_deg": math.degrees(a.disturbance_max_rotation),
                "remaining": a.remaining,
            }
            for a in self.attempts
        ]
        title = (
            f"closed-loop picking ({self.policy}, {self.gripper}): R_grasp {self.R_grasp:.3f}  "
            f"R_object {self.R_object:.3f}  R_mixture {self.R_mixture:.3f}  "
            f"(stopped: {self.stop_reason})"
        )
        return format_table(rows, _TABLE_COLUMNS, title=title, digits=3)


# ---------------------------------------------------------------------------- helpers


def _rotation_angle(Ra: np.ndarray, Rb: np.ndarray) -> float:
    c = (np.trace(Ra.T @ Rb) - 1.0) / 2.0
    return float(math.acos(min(1.0, max(-1.0, c))))


def _grasp_scores(grasps: PlacedGrasps, gripper: str) -> np.ndarray:
    """The success model's score of every grasp (see the module doc)."""
    if gripper == "suction":
        first = np.asarray(grasps.score_analytical, np.float64)
    else:
        sim = np.asarray(grasps.score_simulation, np.float64)
        first = np.where(np.isfinite(sim), sim, np.asarray(grasps.score_analytical, np.float64))
    wrench = np.asarray(grasps.score_wrench, np.float64)
    first = np.where(np.isfinite(first), first, 1.0)
    wrench = np.where(np.isfinite(wrench), wrench, 1.0)
    return np.clip(first * wrench, 0.0, 1.0)


def _labels_for(
    scene: Scene,
    object_labels: Mapping[str, ObjectLabels] | None,
    config: Config,
    gripper: str,
) -> dict[str, Any]:
    """name -> the gripper's object labels (computed and cached when not given)."""

    need = sorted({inst.name for inst in scene.instances})
    out: dict[str, Any] = {}
    labels_cfg = dataclasses.replace(
        config.labels, suction=gripper == "suction", paralleljaw=gripper == "paralleljaw"
    )
    cfg = dataclasses.replace(config, labels=labels_cfg)
    for name in need:
        lab = None if object_labels is None else object_labels.get(name)
        if lab is None:
            index = next(i for i, inst in enumerate(scene.instances) if inst.name == name)
            lab = cached_labels(scene.object_spec(index), cfg)
        got = lab.suction if gripper == "suction" else lab.paralleljaw
        if got is None:
            raise InvalidArgumentError(
                f"run_picking: object '{name}' has no {gripper} labels; compute them with "
                f"labels.{gripper}: true in the config"
            )
        out[name] = got
    return out


def _top_view(scene: Scene, config: Config, resolution: int) -> CameraView:

    poses, _ = mgn_rig(scene.seed)
    # The rectified camera: picking decides from the ideal pinhole view (lens distortion changes
    # only where pixels are, not what the policy sees).
    K = scene_intrinsics(config.camera).pinhole()
    K = K.scaled(resolution / max(K.width, K.height))
    return CameraView(K, poses[0])


def _render(scene: Scene, view: CameraView, render: Any = None, num_threads: int = 0) -> ViewImages:
    """The top view without noise or randomisation; the picture by ``render``
    (:class:`mgn.render.settings.RenderSettings`, default the raster engine)."""

    frames = iter_views(
        scene.render_items(),
        tote_mesh(scene.tote),
        [(0, view)],
        sensor="ideal",
        randomize=False,
        seed=scene.seed,
        render=render,
        num_threads=num_threads,
    )
    return next(iter(frames))


def _observe(
    scene: Scene, view: CameraView, num_threads: int, render: Any = None
) -> tuple[Any, Any, Any]:

    images = _render(scene, view, render, num_threads)
    rays = SceneRayModel.from_scene(scene)
    labels = view_object_labels(
        rays,
        view,
        images.instance_ids,
        depth=images.depth_ideal,
        keypoints=False,
        num_threads=num_threads,
    )
    layout = compute_layout(
        labels.visible,
        labels.amodal,
        images.depth_ideal,
        np.array([inst.category_id for inst in scene.instances], np.int64),
        [inst.bin_relation for inst in scene.instances],
        occlusion=labels.occlusion,
        num_threads=num_threads,
    )
    return images, labels, layout


def _project(view: CameraView, p_W: np.ndarray) -> tuple[float, float] | None:
    X_CW = np.linalg.inv(view.X_WC)
    p = X_CW[:3, :3] @ p_W + X_CW[:3, 3]
    if p[2] <= 1e-6:
        return None
    return (view.K.fx * p[0] / p[2] + view.K.cx, view.K.fy * p[1] / p[2] + view.K.cy)


def _draw(rgb: np.ndarray, view: CameraView, attempt: PickAttempt | None, contact: Any) -> Any:
    """The top view with the attempted grasp: a circle at the contact and a line along the
    approach (green: success, red: failure)."""

    img = Image.fromarray(np.ascontiguousarray(rgb[..., :3]))
    if attempt is None or contact is None:
        return img
    draw = ImageDraw.Draw(img)
    color = (40, 220, 40) if attempt.success else (230, 30, 30)
    X = np.array(attempt.X_W_tool)
    p0 = _project(view, np.asarray(contact, np.float64))
    p1 = _project(view, np.asarray(contact, np.float64) - 0.05 * X[:3, 2])
    r = max(2, img.width // 60)
    if p0 is not None:
        draw.ellipse([p0[0] - r, p0[1] - r, p0[0] + r, p0[1] + r], outline=color, width=2)
        if p1 is not None:
            draw.line([p0, p1], fill=color, width=2)
    return img


def _resolve_policy(policy: Any) -> tuple[str, Callable[[PickState], Any] | None]:
    if callable(policy):
        return getattr(policy, "__name__", "callable"), policy
    if policy in ("label", "random"):
        return str(policy), None
    if isinstance(policy, str) and ":" in policy:
        module, _, name = policy.partition(":")
        try:
            fn = getattr(importlib.import_module(module), name)
        except (ImportError, AttributeError) as e:
            raise InvalidArgumentError(
                f"run_picking: cannot load policy '{policy}' ({type(e).__name__}: {e}); "
                "expected 'label', 'random' or 'module:function'"
            ) from e
        if not callable(fn):
            raise InvalidArgumentError(f"run_picking: policy '{policy}' is not callable")
        return policy, fn
    raise InvalidArgumentError(
        f"run_picking: unknown policy {policy!r}; expected 'label', 'random', "
        "'module:function' or a callable"
    )


def _label_policy(state: PickState) -> tuple[int, int] | None:
    g = state.grasps
    obj = np.asarray(g.object_id, np.int64)
    ok = state.visible & ~np.asarray(g.colliding, bool) & ~state.tried & state.eligible[obj]
    top = np.asarray(state.layout.layer) == 0
    for allowed in (ok & top[obj], ok):
        idx = np.flatnonzero(allowed)
        if len(idx):
            best = idx[np.argmax(state.score[idx])]  # first of equal scores: lowest index
            return int(obj[best]) + 1, int(best)
    return None


def _random_policy(state: PickState, seed: int) -> tuple[int, int] | None:
    g = state.grasps
    obj = np.asarray(g.object_id, np.int64)
    ok = state.visible & ~state.tried & state.eligible[obj]
    objects = np.unique(obj[ok])
    if len(objects) == 0:
        return None
    rng = np.random.default_rng([int(seed), int(state.step), 1])
    target = int(objects[rng.integers(len(objects))])
    idx = np.flatnonzero(ok & (obj == target))
    return target + 1, int(idx[rng.integers(len(idx))])


def _match_tool_pose(g: PlacedGrasps, rows: np.ndarray, X: np.ndarray) -> int:
    """Row (of ``rows``) of the label nearest to tool pose X within the match tolerances, -1."""
    if len(rows) == 0:
        return -1
    T = g.tool_poses[rows]
    d = np.linalg.norm(T[:, :3, 3] - X[:3, 3], axis=1)
    cosang = np.clip(T[:, :3, 2] @ X[:3, 2], -1.0, 1.0)
    ok = (d <= MATCH_DISTANCE) & (np.arccos(cosang) <= MATCH_ANGLE)
    if not ok.any():
        return -1
    k = np.flatnonzero(ok)
    return int(rows[k[np.argmin(d[k])]])


# ---------------------------------------------------------------------------- the loop


def _grasp_kind(gripper: str) -> str:
    """``gripper`` as a grasp kind name (``normalize_grasp_kind``), errors naming run_picking."""
    try:
        return normalize_grasp_kind(gripper)
    except InvalidArgumentError as e:
        raise InvalidArgumentError(f"run_picking: gripper: {e}") from None


def _check_picking_args(
    scene: Scene,
    gripper: str,
    max_failures_per_object: int,
    success_threshold: float,
    resolution: int,
    max_attempts: int | None,
) -> int:
    """The argument checks of :func:`run_picking`; returns the attempt limit."""
    if len(scene.instances) == 0:
        raise InvalidArgumentError("run_picking: the scene has no objects; nothing to pick")
    if gripper not in _GRIPPERS:
        raise InvalidArgumentError(
            f"run_picking: gripper must be one of {list(_GRIPPERS)}, got {gripper!r}"
        )
    if isinstance(max_failures_per_object, bool) or int(max_failures_per_object) < 1:
        raise InvalidArgumentError(
            f"run_picking: max_failures_per_object must be >= 1, got {max_failures_per_object!r}"
        )
    if not 0.0 <= float(success_threshold) <= 1.0:
        raise InvalidArgumentError(
            f"run_picking: success_threshold must be in [0, 1], got {success_threshold!r}"
        )
    if int(resolution) < 16:
        raise InvalidArgumentError(f"run_picking: resolution must be >= 16 px, got {resolution}")
    n0 = len(scene.instances)
    limit = (int(max_failures_per_object) + 1) * n0 if max_attempts is None else int(max_attempts)
    if limit < 1:
        raise InvalidArgumentError(f"run_picking: max_attempts must be >= 1, got {max_attempts}")
    return limit


def _observe_pile(
    cur: Scene,
    labels: dict[str, Any],
    view: CameraView,
    gripper: str,
    config: Config,
    max_grasps_per_object: int,
    num_threads: int,
) -> tuple[Any, ...]:
    """Scene grasp model, top view and labels of the current pile:
    (model, grasps, images, view labels, layout, visible (G,), score (G,))."""
    n = len(cur.instances)
    per = [strided_subset(labels[i.name], max_grasps_per_object) for i in cur.instances]
    model = SceneGraspModel(
        cur,
        per if gripper == "paralleljaw" else [None] * n,
        per if gripper == "suction" else [None] * n,
        config.gripper,
        config.cup,
        offsets=LabelOptions().grasp_offsets,  # the labels' collision model, exactly
        num_threads=num_threads,
    )
    g = model.suction if gripper == "suction" else model.pj
    images, vlabels, layout = _observe(cur, view, num_threads, config.render)
    vis = model.view_grasps(view, np.asarray(vlabels.visible_pixels) > 0)
    visible = np.zeros(len(g), bool)
    for s in (vis.non_colliding, vis.colliding):
        visible[(s.suctioncup if gripper == "suction" else s.paralleljaw).index] = True
    score = _grasp_scores(g, gripper)
    visible.setflags(write=False)
    score.setflags(write=False)
    return model, g, images, vlabels, layout, visible, score


def _checked_choice(
    choice: Any, obj: np.ndarray, g: Any, eligible: np.ndarray, max_failures_per_object: int
) -> tuple[int, int, np.ndarray]:
    """(object index k, grasp row or -1 when no label matches, X_W_tool) of a policy's choice."""
    n = len(eligible)
    try:
        target, grasp = choice
    except (TypeError, ValueError) as e:
        raise InvalidArgumentError(
            f"run_picking: the policy must return (instance_id, grasp index or X_W_tool) or "
            f"None, got {choice!r}"
        ) from e
    if isinstance(target, bool) or not isinstance(target, (int, np.integer)):
        raise InvalidArgumentError(
            f"run_picking: the policy returned instance id {target!r}; expected an int"
        )
    if not 1 <= int(target) <= n:
        raise InvalidArgumentError(
            f"run_picking: the policy returned instance id {target}, but the scene has "
            f"instances 1..{n}"
        )
    k = int(target) - 1
    if not eligible[k]:
        raise InvalidArgumentError(
            f"run_picking: the policy chose instance {target}, which already failed "
            f"{max_failures_per_object} times (see state.eligible)"
        )
    rows = np.flatnonzero(obj == k)
    if isinstance(grasp, (int, np.integer)) and not isinstance(grasp, bool):
        row = int(grasp)
        if row not in set(rows.tolist()):
            raise InvalidArgumentError(
                f"run_picking: the policy returned grasp {row} for instance {target}, but "
                f"that object's grasps are rows {rows[:1].tolist()}..{rows[-1:].tolist()} "
                f"of state.grasps ({len(g)} rows)"
            )
        X_tool = g.tool_poses[row]
    else:
        X_tool = np.asarray(grasp, np.float64)
        if X_tool.shape != (4, 4) or not np.all(np.isfinite(X_tool)):
            raise InvalidArgumentError(
                "run_picking: the policy's grasp must be a row index of state.grasps or a "
                f"finite (4, 4) tool pose, got {grasp!r}"
            )
        row = _match_tool_pose(g, rows, X_tool)
    return k, row, X_tool


def _remove_and_settle(
    cur: Scene, ids: tuple[int, ...], k: int, settle_options: DropOptions | None
) -> tuple[Scene, tuple[int, ...], dict[str, Any]]:
    """Remove object k and let the rest settle: (new scene, its start-scene ids, the
    disturbance record of the attempt)."""
    n = len(cur.instances)
    before = {ids[j]: cur.instances[j].X_WO for j in range(n) if j != k}
    nxt, old = settle_tracked(cur, remove=(k + 1,), options=settle_options)
    new_ids = tuple(ids[o - 1] for o in old)
    moved: list[float] = []
    turned: list[float] = []
    for j, inst in zip(new_ids, nxt.instances, strict=True):
        moved.append(float(np.linalg.norm(inst.X_WO[:3, 3] - before[j][:3, 3])))
        turned.append(_rotation_angle(before[j][:3, :3], inst.X_WO[:3, :3]))
    lost = tuple(sorted(set(before) - set(new_ids)))
    record = {
        "disturbance_max_translation": max(moved, default=0.0),
        "disturbance_mean_translation": float(np.mean(moved)) if moved else 0.0,
        "disturbance_max_rotation": max(turned, default=0.0),
        "disturbance_mean_rotation": float(np.mean(turned)) if turned else 0.0,
        "lost": lost,
    }
    return nxt, new_ids, record


def _tried_mask(num_rows: int, start_row: np.ndarray, tried: list[set[int]]) -> np.ndarray:
    """(G,) bool: the grasp rows already tried (``tried[k]``: row offsets within object k)."""
    mask = np.zeros(num_rows, bool)
    for k, rows in enumerate(tried):
        for r in rows:
            mask[start_row[k] + r] = True
    return mask


def _choose(
    policy_name: str, policy_fn: Callable[[PickState], Any] | None, state: PickState, seed: int
) -> Any:
    """The policy's choice for ``state`` (None: nothing left to try)."""
    if policy_fn is not None:
        return policy_fn(state)
    if policy_name == "label":
        return _label_policy(state)
    return _random_policy(state, seed)


def _outcome(
    g: Any, score: np.ndarray, row: int, *, stochastic: bool, seed: int, step: int, threshold: float
) -> tuple[bool, str, float]:
    """(success, reason, score) of the attempt with grasp ``row`` (-1: no label matched)."""
    if row < 0:
        return False, "no_label", float("nan")
    s_val = float(score[row])
    if bool(g.colliding[row]):
        return False, "collision", s_val
    if stochastic:
        u = np.random.default_rng([int(seed), step, 2]).random()
        return bool(u < s_val), ("ok" if u < s_val else "draw"), s_val
    ok = s_val >= threshold
    return ok, ("ok" if ok else "score"), s_val


def run_picking(
    scene: Scene,
    *,
    policy: str | Callable[[PickState], Any] = "label",
    gripper: str = "suction",
    object_labels: Mapping[str, ObjectLabels] | None = None,
    config: Config | None = None,
    max_failures_per_object: int = 2,
    max_attempts: int | None = None,
    seed: int = 0,
    stochastic: bool = False,
    success_threshold: float = 0.5,
    resolution: int = 160,
    max_grasps_per_object: int = 500,
    settle_options: DropOptions | None = None,
    out: str | os.PathLike[str] | None = None,
    num_threads: int = 0,
) -> PickResults:
    """Pick objects out of ``scene`` until it is empty (see the module doc for the models).

    Args:
        scene: the settled scene to clear (at least one object).
        policy: ``"label"``, ``"random"``, ``"module:function"`` or a callable (module doc).
        gripper: ``"suction"`` or ``"paralleljaw"``.
        object_labels: name -> :class:`~mgn.pipeline.label_cache.ObjectLabels` of the scene's
            objects (e.g. a dataset's); missing ones are computed with ``config`` and cached.
        config: dataset configuration (object-label settings, gripper, cup, camera); default
            :func:`mgn.pipeline.config.default_config`.
        max_failures_per_object: failed attempts after which an object is given up (>= 1).
        max_attempts: attempts at most (default: (max_failures_per_object + 1) x objects).
        seed: seeds the random policy and the stochastic success draws.
        stochastic: success with probability = score instead of score >= threshold.
        success_threshold: score needed for success, in [0, 1].
        resolution: the top view's larger image side, px.
        max_grasps_per_object: object labels placed per object (evenly strided subset; 0 = all).
        settle_options: simulation options of the re-settling (default: the scene's).
        out: folder for ``step_NNN.png`` (the top view of each attempt with its grasp drawn),
            ``final.png``, ``picking.gif`` and ``results.json``; None writes nothing.
        num_threads: C++ threads (0 = all); results do not depend on it.

    Raises:
        InvalidArgumentError: an empty scene, an unknown policy or gripper, bad numbers, a policy
            answer that names an unknown instance or grasp.
    """

    gripper = _grasp_kind(gripper)
    policy_name, policy_fn = _resolve_policy(policy)
    n0 = len(scene.instances)
    limit = _check_picking_args(
        scene, gripper, max_failures_per_object, success_threshold, resolution, max_attempts
    )
    config = config or default_config()
    labels = _labels_for(scene, object_labels, config, gripper)
    view = _top_view(scene, config, int(resolution))
    folder = None if out is None else Path(out)
    if folder is not None:
        folder.mkdir(parents=True, exist_ok=True)

    ids = tuple(inst.instance_id for inst in scene.instances)  # start-scene ids
    failures: dict[int, int] = dict.fromkeys(ids, 0)
    tried: dict[int, set[int]] = {i: set() for i in ids}
    attempts: list[PickAttempt] = []
    cleared: list[int] = []
    first: list[int] = []
    frames: list[Any] = []
    stop = "max_attempts"
    cur = scene
    step = 0
    observed = None
    while step < limit:
        if len(cur.instances) == 0:
            stop = "empty"
            break
        if all(failures[i] >= max_failures_per_object for i in ids):
            stop = "failures"
            break
        n = len(cur.instances)
        if observed is None:  # the pile changed (or first step): model, view and labels
            observed = _observe_pile(
                cur, labels, view, gripper, config, max_grasps_per_object, num_threads
            )
        model, g, images, vlabels, layout, visible, score = observed
        obj = np.asarray(g.object_id, np.int64)
        start_row = np.searchsorted(obj, np.arange(n))  # rows are grouped by object in order
        eligible = np.array([failures[ids[k]] < max_failures_per_object for k in range(n)])
        tried_mask = _tried_mask(len(g), start_row, [tried[i] for i in ids])
        state = PickState(
            step,
            cur,
            ids,
            view,
            images,
            vlabels,
            layout,
            g,
            model,
            visible,
            score,
            eligible,
            tried_mask,
        )
        choice = _choose(policy_name, policy_fn, state, seed)
        if choice is None:
            stop = "no_grasp"
            break
        k, row, X_tool = _checked_choice(choice, obj, g, eligible, max_failures_per_object)
        orig = ids[k]
        name = cur.instances[k].name
        index = -1 if row < 0 else int(row - start_row[k])
        if row >= 0:
            X_tool = g.tool_poses[row]
            tried[orig].add(index)
        success, reason, s_val = _outcome(
            g, score, row, stochastic=stochastic, seed=seed, step=step, threshold=success_threshold
        )
        record: dict[str, Any] = {}
        if success:
            nxt, new_ids, record = _remove_and_settle(cur, ids, k, settle_options)
            lost = record["lost"]
            if failures[orig] == 0:
                first.append(orig)
            cleared.append(orig)
            for j in lost:  # gone from the tote: nothing left to try on it
                failures[j] = max_failures_per_object
            cur, ids = nxt, new_ids
        else:
            failures[orig] += 1
        attempt = PickAttempt(
            step=step,
            instance_id=int(orig),
            name=name,
            grasp_index=index,
            X_W_tool=tuple(tuple(float(v) for v in row_) for row_ in np.asarray(X_tool)),
            score=s_val,
            success=success,
            reason=reason,
            remaining=len(cur.instances),
            **record,
        )
        attempts.append(attempt)
        if folder is not None:
            contact = g.contacts[row] if row >= 0 else None
            frame = _draw(images.rgb, view, attempt, contact)
            frame.save(folder / f"step_{step:03d}.png")
            frames.append(frame)
        if success:
            observed = None  # the pile changed: render again
        step += 1
    else:
        if len(cur.instances) == 0:
            stop = "empty"
    results = PickResults(
        attempts=tuple(attempts),
        num_objects=n0,
        cleared=tuple(cleared),
        cleared_first_attempt=tuple(first),
        stop_reason=stop,
        policy=policy_name,
        gripper=gripper,
        seed=int(seed),
        stochastic=bool(stochastic),
        success_threshold=float(success_threshold),
    )
    if folder is not None:
        _write_outputs(folder, results, cur, view, frames, num_threads, config.render)
    return results


def _write_outputs(
    folder: Path,
    results: PickResults,
    scene: Scene,
    view: CameraView,
    frames: list[Any],
    threads: int,
    render: Any = None,
) -> None:

    final = _render(scene, view, render, threads)
    img = _draw(final.rgb, view, None, None)
    img.save(folder / "final.png")
    frames = [*frames, img]
    frames[0].save(
        folder / "picking.gif", save_all=True, append_images=frames[1:], duration=600, loop=0
    )
    write_results_json(folder / "results.json", results)
