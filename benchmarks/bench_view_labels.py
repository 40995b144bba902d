"""Per-view object labels: mgn.view_labels.objects.view_object_labels (Embree) against amodal
masks rendered one object at a time with the OSMesa renderer.

The frame: the 20 built-in objects of the render benchmark (a 5 x 4 grid on the floor of the
default tote), seen from views of the MetaGraspNet rig at 1200 x 1200 (quick: 600 x 600). The
scene's ray model (:class:`mgn.view_labels.objects.SceneRayModel`) is built once, untimed, as a
scene pipeline does for its 37 views. One timed call = the labels of one view:

- mgn "masks": visible / semantic / amodal masks, occlusion, boxes, poses, CoM heat map
  (``keypoints=False``; the rendered depth is passed, as the scene pipeline has it, so the heat
  map needs no rays).
- mgn "masks + keypoints": the same plus the visibility of every semantic keypoint and of the
  20 x 1000 CoM-scored points (one ray each through the whole scene).
- peer: ``Renderer.render(view, visible_instances=[i])`` for each of the 20 objects (the
  rasteriser's way to an amodal mask; geometry-only passes), plus the occlusion rates in NumPy.

Agreement: amodal pixels equal on the union of both masks, over all objects.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from functools import partial
from typing import Any

import numpy as np

from .bench_render import N_OBJECTS, camera, scene_items
from .common import Row, fraction, measure_alternating, percent, thread_counts

AGREEMENT_MIN = 0.99
VIEWS = (0, 14)


def _setup(width: int) -> tuple[Any, Any, float, list[tuple[int, Any, np.ndarray, np.ndarray]]]:
    from mgn.geometry.mesh import mass_properties
    from mgn.objects import builtin_objects, com_keypoints, tote_mesh
    from mgn.render import Instance, Renderer
    from mgn.scene.cameras import CameraView
    from mgn.view_labels.objects import SceneRayModel

    items = scene_items()
    specs = builtin_objects()[:N_OBJECTS]
    tote = tote_mesh()
    K, poses = camera(width)
    kps = [np.array([[k.id, *k.position] for k in s.keypoints]) for s in specs]
    cps = [
        com_keypoints(m, s.density, seed=s.category_id)
        for (m, _, _), s in zip(items, specs, strict=True)
    ]
    coms = [
        mass_properties(m, s.density).center_of_mass
        for (m, _, _), s in zip(items, specs, strict=True)
    ]
    t0 = time.perf_counter()
    model = SceneRayModel(
        [m for m, _, _ in items],
        np.stack([X for _, X, _ in items]),
        [s.category_id for s in specs],
        keypoints=kps,
        com_points=cps,
        coms=np.stack(coms),
        tote=tote,
    )
    build = time.perf_counter() - t0
    r = Renderer(K.width, K.height)
    r.set_instances(
        [Instance(r.add_mesh(m), X, i) for m, X, i in items]
        + [Instance(r.add_mesh(tote), np.eye(4), 0)]
    )
    frames = []
    for v in VIEWS:
        view = CameraView(K, poses[v])
        out = r.render(view, rgb=False, depth=True)
        frames.append((v, view, out.instance_ids, out.depth))
    return model, r, build, frames


def _peer(r: Any, view: Any, ids: np.ndarray) -> np.ndarray:
    amodal = np.stack(
        [
            r.render(view, rgb=False, depth=False, visible_instances=[i + 1]).instance_ids == i + 1
            for i in range(N_OBJECTS)
        ]
    )
    visible = np.stack([ids == i + 1 for i in range(N_OBJECTS)])
    counts = amodal.sum(axis=(1, 2))
    _ = 1.0 - visible.sum(axis=(1, 2)) / np.maximum(counts, 1)
    return amodal


def run(
    quick: bool, repeats: int, mgn: Any, mgn_status: str, log: Callable[[str], None]
) -> list[Row]:
    width = 600 if quick else 1200
    rows: list[Row] = []
    if mgn is None:
        return [
            Row(
                "view labels",
                f"20 objects, {width} x {width}",
                1,
                "views/s",
                "Renderer.render(visible_instances=[i]) x 20",
                mgn_status=mgn_status,
            )
        ]
    from mgn.view_labels.objects import view_object_labels

    model, r, build, frames = _setup(width)
    log(f"  view labels: ray model of 20 objects + tote built in {1e3 * build:.0f} ms (untimed)")
    threads = thread_counts()
    for v, view, ids, depth in frames:
        for with_kp in (False, True):
            what = "masks + keypoints" if with_kp else "masks"
            row = Row(
                "view labels",
                f"{what}, 20 objects, view {v}, {width} x {width}",
                1,
                "views/s",
                "Renderer.render(visible_instances=[i]) x 20",
            )
            cases: dict[str, Callable[[], object]] = {}
            for t in threads:
                cases[f"mgn{t}"] = partial(
                    view_object_labels,
                    model,
                    view,
                    ids,
                    depth=depth,
                    keypoints=with_kp,
                    num_threads=t,
                )
            cases["peer"] = lambda view=view, ids=ids: _peer(r, view, ids)
            warm = {k: f() for k, f in cases.items()}
            timings = measure_alternating(cases, repeats)
            row.mgn = {t: timings[f"mgn{t}"] for t in threads}
            row.peer = timings["peer"]
            labels = warm[f"mgn{max(threads)}"]
            peer_amodal = warm["peer"]
            union = labels.amodal | peer_amodal
            agree = fraction((labels.amodal == peer_amodal)[union])
            row.agreement = f"amodal pixels {percent(agree)} of the union"
            row.agreement_ok = agree >= AGREEMENT_MIN
            row.notes.append(
                f"{int(labels.amodal_pixels.sum()):,} amodal pixels, "
                f"{len(labels.keypoints)} visible / {len(labels.occluded_keypoints)} occluded "
                f"keypoints, {int(labels.com_visible.sum())} visible CoM points"
            )
            ms = {t: 1e3 * row.mgn[t].median for t in threads}
            log(
                f"  view {v} {what}: "
                + ", ".join(f"{ms[t]:.1f} ms ({t} thread{'s' if t > 1 else ''})" for t in threads)
                + f"; peer {1e3 * row.peer.median:.1f} ms; agreement {percent(agree)}"
            )
            rows.append(row)
    return rows


if __name__ == "__main__":
    import sys

    from .common import import_mgn

    module, status = import_mgn()
    quick = "--quick" in sys.argv
    for row in run(quick, 3 if quick else 7, module, status, lambda m: print(m, flush=True)):
        print(row.case, {t: f"{1e3 * x.median:.1f} ms" for t, x in row.mgn.items()})
