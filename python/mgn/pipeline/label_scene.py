"""Label a settled scene and write its MetaGraspNet scene folder (issue "Scene labels").

:func:`label_scene` is the scene step of ``mgn generate`` and of ``mgn scene label``: it renders
every view (RGB, sensor and ideal depth, instance ids), computes the per-view object labels
(visible / semantic / amodal masks, occlusion, boxes, poses, keypoints, CoM heat map:
:mod:`mgn.view_labels.objects`), the layout (relations, layers, order, bin relation, difficulty:
:mod:`mgn.view_labels.layout`) and the scene grasps (object grasps placed at the settled poses,
collision-checked once per scene, kept per view when seen: :mod:`mgn.view_labels.grasps`), and
writes the files of docs/format.md with :func:`mgn.io.scene_folder.write_view`.

Models built once per scene (Embree scene, FCL models, GL meshes) are reused by all views; a
view's arrays are released before the next view is rendered, so memory does not grow with the
number of views.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import queue
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mgn.errors import InvalidArgumentError
from mgn.io.scene_folder import scene_gt_entries, write_scene_gt, write_view
from mgn.io.scene_json import write_scene_json
from mgn.io.scene_schema import ViewRecord
from mgn.objects import tote_mesh
from mgn.pj.labels import PjLabels
from mgn.render.sensor import SensorName
from mgn.render.settings import RenderSettings
from mgn.render.views import iter_views
from mgn.scene.cameras import CameraView
from mgn.scene.scene import Scene
from mgn.suction.labels import SuctionLabels
from mgn.view_labels.grasps import SceneGraspModel
from mgn.view_labels.layout import OCCLUSION_DECIMALS, compute_layout
from mgn.view_labels.objects import (
    SceneRayModel,
    distort_view_object_labels,
    round_occlusion,
    seen_objects,
    view_object_labels,
)

__all__ = [
    "LabelOptions",
    "LabelTimings",
    "label_scene",
    "strided_subset",
    "view_grasps",
    "view_record",
]


@dataclass(frozen=True)
class LabelOptions:
    """What to label and how (defaults: everything, MetaGraspNet settings).

    Attributes:
        sensor: depth sensor preset of ``depth`` (the ideal depth is kept too).
        randomize: per-view light and tote / floor colour randomisation.
        seed: seed of the randomisation and of the sensor noise (view v uses seed + v).
        layout: relations, layers, order and difficulty (else empty order files, difficulty 0).
        scene_grasps: place and collision-check the object grasps.
        keypoints: keypoint visibility sets.
        grasp_offsets: distances back along the approach where the tools are checked, m.
        max_grasps_per_object: object grasps of each kind placed in the scene per object (an
            evenly strided subset of the object labels when there are more; 0 = all).
            Object labels often hold tens of thousands of parallel-jaw grasps; MetaGraspNet's
            scenes carry a few thousand per object.
        num_threads: C++ threads (0 = all cores); results do not depend on it.
        render: how the RGB images are made (:class:`mgn.render.settings.RenderSettings`;
            None = the raster engine). Labels do not depend on it.
        archival: write the compact archival files (docs/format.md; lossy depth).
    """

    sensor: SensorName = "structured-light"
    randomize: bool = True
    seed: int = 0
    layout: bool = True
    scene_grasps: bool = True
    keypoints: bool = True
    grasp_offsets: tuple[float, ...] = (0.0, 0.1)
    max_grasps_per_object: int = 2000
    num_threads: int = 0
    render: RenderSettings | None = None
    archival: bool = False


@dataclass
class LabelTimings:
    """Seconds spent per stage over all views of a scene (wall clock).

    ``render`` is the time of the render thread, which overlaps the other stages; ``render
    (waiting)`` is the time the labelling waited for it. ``prepare: scene grasp collisions``
    also runs in a thread of its own; ``scene grasps`` includes waiting for it at the first
    view."""

    seconds: dict[str, float] = field(default_factory=dict)
    views: int = 0
    #: What made the RGB images (``ViewImages.engine`` of the last view).
    engine: dict[str, Any] = field(default_factory=dict)

    def add(self, stage: str, dt: float) -> None:
        self.seconds[stage] = self.seconds.get(stage, 0.0) + dt

    def per_view_ms(self) -> dict[str, float]:
        n = max(self.views, 1)
        return {k: 1000.0 * v / n for k, v in self.seconds.items()}


#: Per-grasp fields of the object label dataclasses (the others are per object or per point).
_PJ_GRASP_FIELDS = (
    "approach",
    "closing",
    "p1",
    "width",
    "quality_score",
    "score_wrench",
    "quality_score_simulation",
    "point_index",
)
_SUCTION_GRASP_FIELDS = ("points", "approach", "score", "wrench", "reason", "simulation")


def strided_subset(labels: Any, limit: int) -> Any:
    """``labels`` (PjLabels or SuctionLabels) reduced to at most ``limit`` grasps, evenly strided
    over the label order (deterministic; keeps the score distribution); None stays None."""
    if labels is None or limit <= 0:
        return labels
    kind = _PJ_GRASP_FIELDS if hasattr(labels, "closing") else _SUCTION_GRASP_FIELDS
    fields = [f for f in kind if getattr(labels, f) is not None]  # simulation may be None
    m = len(getattr(labels, fields[0]))
    if m <= limit:
        return labels
    keep = np.unique(np.linspace(0, m - 1, limit).round().astype(np.int64))
    return dataclasses.replace(labels, **{f: getattr(labels, f)[keep] for f in fields})


def view_grasps(model: SceneGraspModel, view: CameraView, index: np.ndarray, n: int) -> Any:
    """The scene grasps of the ``n`` scene objects whose 0-based scene indices ``index`` the
    view holds, with ``object_id`` numbering them as the view does (0..len(index) - 1)."""
    seen = np.zeros(n, bool)
    seen[index] = True
    new_index = np.full(n, -1, np.int64)
    new_index[index] = np.arange(len(index))
    return model.view_grasps(view, seen).renumbered(new_index)


def _empty_layout_files(n: int) -> tuple[dict[str, Any], str, dict[str, Any]]:
    order = {
        str(i + 1): {
            "id": i + 1,
            "parents": [{"id": 0, "depth_diff": 0.0, "edge_size": 0.0}],
            "children": [],
        }
        for i in range(n)
    }
    return order, "".join(",".join("0" for _ in range(n)) + "\n" for _ in range(n)), {}


def view_record(
    index: int,
    view: CameraView,
    images: Any,
    labels: Any,
    layout: Any | None,
    grasps: Any | None,
    com_parameters: np.ndarray | None = None,
    *,
    instance_ids: np.ndarray | None = None,
) -> ViewRecord:
    """The :class:`ViewRecord` of one view from its images (``ViewImages``), object labels
    (``ViewObjectLabels``, the objects of the view: :func:`~mgn.view_labels.objects.seen_objects`),
    layout (``Layout`` or None) and scene grasps (``SceneGrasps`` or None), all numbering the
    objects of the view 1..N. Lengths in metres; the writer converts. ``com_parameters``: the
    (N, 5) rows of the scene's (:meth:`~mgn.view_labels.objects.SceneRayModel.com_parameters`)
    for these objects when the heat map was computed from ``images.depth_ideal`` through
    ``view`` (no lens): the writer then stores it as a residual. ``instance_ids``: (N,) each
    object's ``instance_id`` in the scene (``scene.json``; default 1..N), written as
    ``objects/scene_instance_id``."""
    n = labels.num_objects
    if instance_ids is None:
        instance_ids = np.arange(1, n + 1)
    com = labels.com_points.reshape(-1, 4)
    seen_com = np.asarray(labels.com_visible, bool)
    h5: dict[str, np.ndarray] = {
        "camera/pose_relative_to_world": np.asarray(view.X_WC, np.float64)[None],
        "objects/poses_relative_to_camera": labels.X_CO,
        "objects/categories": labels.category_ids,
        "objects/bbox_loose": labels.bbox_loose,
        "objects/bbox_tight": labels.bbox_tight,
        "objects/occlusion": labels.occlusion,
        "objects/scene_instance_id": np.asarray(instance_ids, np.int32),
        "keypts/byhand/keypts_relative_to_camera": labels.keypoints.reshape(-1, 4),
        "keypts/byhand/object_id": labels.keypoint_object,
        "keypts/byhand/occluded_keypts_relative_to_camera": labels.occluded_keypoints.reshape(
            -1, 4
        ),
        "keypts/byhand/occluded_object_id": labels.occluded_keypoint_object,
        # MetaGraspNet's keypts/com holds the visible CoM points; mgn keeps the others under
        # the names of keypts/byhand's occluded ones.
        "keypts/com/keypts_relative_to_camera": com[seen_com],
        "keypts/com/object_id": labels.com_object[seen_com],
        "keypts/com/occluded_keypts_relative_to_camera": com[~seen_com],
        "keypts/com/occluded_object_id": labels.com_object[~seen_com],
    }
    if grasps is not None:
        h5.update(grasps.datasets())
    if layout is not None:
        order, csv, extra = layout.order_json(), layout.order_csv(), layout.layout_json()
    else:
        order, csv, extra = _empty_layout_files(n)
    depth_ideal = np.where(images.depth_ideal > 0, images.depth_ideal, np.float32(np.nan))
    depth_ideal = depth_ideal.astype(np.float32, copy=False)
    return ViewRecord(
        index=index,
        rgb=images.rgb,
        depth=images.depth,
        depth_ideal=depth_ideal,
        valid_depth=images.valid,
        instances=labels.visible,
        semantic=labels.semantic,
        occlusion_map=labels.occlusion_map,
        amodal=labels.amodal,
        intrinsics=view.K,
        scene_hdf5=h5,
        order_json=order,
        order_csv=csv,
        layout_json=extra,
        extra_npz={"com_heatmap": labels.com_heatmap},
        com_parameters=com_parameters,
    )


class _RenderAhead:
    """Runs an iterator (the view renderer) in a thread of its own, at most ``depth`` items ahead
    of the consumer, so view k + 1 renders (OpenGL and the depth sensor release the GIL) while
    view k is labelled. Items come out in the iterator's order; an exception in the iterator is
    raised in the consumer. ``busy`` is the time the thread spent producing items, s.

    The iterator is created, advanced and closed in the thread only (the OpenGL context of the
    renderer lives there)."""

    def __init__(self, make: Callable[[], Iterator[Any]], depth: int = 1) -> None:
        self.busy = 0.0
        self._queue: queue.Queue[tuple[str, Any]] = queue.Queue(maxsize=depth)
        self._stop = threading.Event()
        self._thread = threading.Thread(
            target=self._run, args=(make,), name="mgn-render", daemon=True
        )
        self._thread.start()

    def _put(self, message: tuple[str, Any]) -> bool:
        while not self._stop.is_set():
            try:
                self._queue.put(message, timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def _run(self, make: Callable[[], Iterator[Any]]) -> None:
        it: Iterator[Any] | None = None
        try:
            it = make()
            while not self._stop.is_set():
                t0 = time.perf_counter()
                try:
                    item = next(it)
                except StopIteration:
                    break
                self.busy += time.perf_counter() - t0
                if not self._put(("item", item)):
                    break
            self._put(("end", None))
        except BaseException as e:  # handed to the consumer, which raises it
            self._put(("error", e))
        finally:
            close = getattr(it, "close", None)
            if close is not None:
                close()

    def __iter__(self) -> Iterator[Any]:
        while True:
            kind, value = self._queue.get()
            if kind == "item":
                yield value
            elif kind == "error":
                raise value
            else:
                return

    def close(self) -> None:
        """Stops the thread (after the item it is producing) and waits for it."""
        self._stop.set()
        while self._thread.is_alive():
            with contextlib.suppress(queue.Empty):
                self._queue.get(timeout=0.1)
        self._thread.join()


def label_scene(
    scene: Scene,
    folder: str | os.PathLike[str],
    views: Sequence[tuple[int, CameraView]],
    *,
    pj_labels: Sequence[PjLabels | None] | None = None,
    suction_labels: Sequence[SuctionLabels | None] | None = None,
    gripper: Any = None,
    cup: Any = None,
    options: LabelOptions | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> LabelTimings:
    """Render and label ``views`` of ``scene`` and write the scene folder into ``folder``.

    Args:
        scene: a settled scene with at least one object.
        folder: the scene folder (created); files are written atomically.
        views: (view index, camera) pairs, e.g. from the MetaGraspNet rig.
        pj_labels, suction_labels: object-level labels per instance in scene order (object
            frame), None entries for objects without them; None: no grasps of that kind.
        gripper, cup: the end effectors the labels were made for (defaults: MetaGraspNet's).
        options: what to label (:class:`LabelOptions`).
        progress: called with (views done, views) after each view.

    Returns:
        Time per stage over the views.
    """

    opt = options or LabelOptions()
    n = len(scene.instances)
    if n == 0:
        raise InvalidArgumentError("label_scene: the scene has no objects; nothing to label")
    if not views:
        raise InvalidArgumentError("label_scene: no views given; expected at least one camera")
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    timings = LabelTimings()

    t0 = time.perf_counter()
    rays = SceneRayModel.from_scene(scene)
    timings.add("prepare: ray model", time.perf_counter() - t0)

    def grasp_model() -> SceneGraspModel:
        t = time.perf_counter()
        cap = opt.max_grasps_per_object
        model = SceneGraspModel(
            scene,
            [strided_subset(g, cap) for g in pj_labels] if pj_labels is not None else [None] * n,
            [strided_subset(g, cap) for g in suction_labels]
            if suction_labels is not None
            else [None] * n,
            gripper,
            cup,
            offsets=opt.grasp_offsets,
            num_threads=opt.num_threads,
            # The files store the flags and why at the first colliding pose, not the hits per
            # offset: the later offsets of a colliding grasp need not be checked.
            first_collision_only=True,
        )
        timings.add("prepare: scene grasp collisions", time.perf_counter() - t)
        return model

    want_grasps = opt.scene_grasps and (pj_labels is not None or suction_labels is not None)
    categories = np.array([inst.category_id for inst in scene.instances], np.int64)
    scene_ids = np.array([inst.instance_id for inst in scene.instances], np.int32)
    bins = [inst.bin_relation for inst in scene.instances]
    objects = scene.render_items()
    gt: dict[int, list[dict[str, Any]]] = {}

    pending: deque[Future[Any]] = deque()
    # View k + 1 renders in its own thread while view k is labelled; files are encoded (libdeflate,
    # LZMA; both release the GIL) by writer threads. At most one rendered view and two views
    # being written wait, so memory stays bounded. Every view's result depends only on the
    # view (its randomisation is seeded by the view index), so the bytes do not depend on this
    # overlap.
    tote = tote_mesh(scene.tote)
    ahead = _RenderAhead(
        lambda: iter_views(
            objects,
            tote,
            views,
            sensor=opt.sensor,
            randomize=opt.randomize,
            seed=opt.seed,
            render=opt.render,
            num_threads=opt.num_threads,
        )
    )
    try:
        with (
            ThreadPoolExecutor(max_workers=2, thread_name_prefix="mgn-write") as pool,
            ThreadPoolExecutor(max_workers=1, thread_name_prefix="mgn-grasps") as prepare,
        ):
            # The scene grasps' collision pass (once per scene) runs while the first views
            # render and are labelled; the first view_grasps waits for it.
            sgm_future = prepare.submit(grasp_model) if want_grasps else None
            t0 = time.perf_counter()
            for k, images in enumerate(ahead):
                t1 = time.perf_counter()
                timings.add("render (waiting)", t1 - t0)
                for part, dt in images.seconds.items():
                    timings.add(f"render: {part}", dt)
                timings.engine = dict(images.engine)
                v, view = views[k]
                # A camera with lens distortion: label its pinhole render, then resample the
                # labels through the lens (the images are resampled the same way,
                # docs/cameras.md).
                src = images.pinhole if images.pinhole is not None else images
                labels = view_object_labels(
                    rays,
                    src.view,
                    src.instance_ids,
                    depth=src.depth_ideal,
                    keypoints=opt.keypoints,
                    num_threads=opt.num_threads,
                )
                if images.lens is not None:
                    labels = distort_view_object_labels(labels, images.lens)
                labels = round_occlusion(labels, OCCLUSION_DECIMALS)
                # The view holds the objects it sees, numbered 1..N' (MetaGraspNet's readers).
                labels, index = seen_objects(labels)
                del src
                t2 = time.perf_counter()
                timings.add("object labels", t2 - t1)
                layout = None
                if opt.layout:
                    layout = compute_layout(
                        labels.visible,
                        labels.amodal,
                        images.depth_ideal,
                        categories[index],
                        [bins[i] for i in index],
                        occlusion=labels.occlusion,
                        num_threads=opt.num_threads,
                    )
                t3 = time.perf_counter()
                timings.add("layout", t3 - t2)
                gt[v] = scene_gt_entries(labels.X_CO, categories[index])
                grasps = None
                if sgm_future is not None:
                    grasps = view_grasps(sgm_future.result(), view, index, n)
                t4 = time.perf_counter()
                timings.add("scene grasps", t4 - t3)
                com = rays.com_parameters()[index] if images.lens is None else None
                record = view_record(
                    v, view, images, labels, layout, grasps, com, instance_ids=scene_ids[index]
                )
                del images, labels, layout, grasps
                pending.append(pool.submit(write_view, out, record, archival=opt.archival))
                del record
                while len(pending) > 2:
                    pending.popleft().result()
                t0 = time.perf_counter()
                timings.add("write (waiting)", t0 - t4)
                timings.views += 1
                if progress is not None:
                    progress(k + 1, len(views))
            t4 = time.perf_counter()
            for fut in pending:
                fut.result()
            timings.add("write (waiting)", time.perf_counter() - t4)
    finally:
        ahead.close()
    # Time the render thread spent rendering (overlapped with the stages above).
    timings.add("render", ahead.busy)
    write_scene_gt(out, gt)
    write_scene_json(scene, out / "scene.json")
    return timings
