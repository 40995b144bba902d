"""Check an mgn BOP export with the BOP toolkit's own functions (development aid, not CI).

    python scripts/check_bop_toolkit.py BOP_DIR --toolkit SRC [--out VIS_DIR] [--delta 15]
        [--renderer vispy] [--vis 2] [--json report.json]

BOP_DIR is a folder written by ``mgn export bop`` (or ``mgn generate`` with ``output.formats``
naming ``bop``); SRC the folder holding the toolkit's ``bop_toolkit_lib`` package (a checkout of
github.com/thodan/bop_toolkit), run in an environment with the toolkit's requirements (numpy <
2, vispy, PyOpenGL, ...: a throwaway virtual environment; mgn is not needed).

For every annotation of every image the script does what the toolkit's ``calc_gt_info.py`` and
``calc_gt_masks.py`` do, with the toolkit's functions: it renders the model
(``models/obj_<id>.ply``, read by ``inout.load_ply``) in the annotated pose with the toolkit's
renderer (``renderer.create_renderer``; a canvas 3x the image, as ``calc_gt_info.py``), turns
depths into distances (``misc.depth_im_to_dist_im_fast``) and estimates the visible mask from
the export's depth image (``visibility.estimate_visib_mask_gt``, BOP19 mode, tolerance
``--delta`` mm). It compares the toolkit's results with mgn's files: the rendered silhouette
with ``mask/`` (IoU), the toolkit's visible mask with ``mask_visib/`` (IoU, the share of
each outside the other, and why the toolkit's extra pixels are visible to it), its
``visib_fract``, ``px_count_*`` and boxes with ``scene_gt_info.json``, the depth it renders
with the export's depth on the visible pixels; and draws the first ``--vis`` images of each
scene with ``visualization.vis_object_poses`` (the models in their annotated poses over the
RGB, and the depth difference) into VIS_DIR. It prints a JSON summary (medians, 5th
percentiles, maxima) and exits 0; reading it is up to the developer (docs/format.md,
"Checked with the BOP toolkit").
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import Any

import numpy as np


def _iou(a: np.ndarray, b: np.ndarray) -> float:
    union = int((a | b).sum())
    return 1.0 if union == 0 else int((a & b).sum()) / union


def _stats(values: list[float]) -> dict[str, float]:
    if not values:
        return {}
    v = np.asarray(values, np.float64)
    return {
        "n": len(v),
        "median": round(float(np.median(v)), 4),
        "p05": round(float(np.percentile(v, 5)), 4),
        "p95": round(float(np.percentile(v, 95)), 4),
        "min": round(float(v.min()), 4),
        "max": round(float(v.max()), 4),
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="check_bop_toolkit.py", description=__doc__.split("\n")[0])
    p.add_argument("bop", type=Path, help="a BOP folder written by mgn")
    p.add_argument("--toolkit", type=Path, required=True, help="folder with bop_toolkit_lib/")
    p.add_argument("--split", default="train_pbr")
    p.add_argument("--out", type=Path, default=None, help="folder for the pose visualisations")
    p.add_argument("--delta", type=float, default=15.0, help="visibility tolerance, mm")
    p.add_argument("--renderer", default="vispy", help="the toolkit's renderer type")
    p.add_argument("--vis", type=int, default=2, help="images per scene to visualise")
    p.add_argument("--json", type=Path, default=None, help="write the summary here too")
    a = p.parse_args(argv)

    sys.path.insert(0, os.fspath(a.toolkit.resolve()))
    from bop_toolkit_lib import inout, misc, visibility, visualization
    from bop_toolkit_lib.rendering import renderer

    cam = inout.load_json(a.bop / "camera.json")
    w, h = int(cam["width"]), int(cam["height"])
    info = inout.load_json(a.bop / "models" / "models_info.json", keys_to_int=True)
    ren = renderer.create_renderer(3 * w, 3 * h, a.renderer, mode="depth")
    vis_ren = None
    if a.vis > 0 and a.out is not None:
        vis_ren = renderer.create_renderer(w, h, a.renderer, mode="rgb+depth")
    for obj_id in sorted(info):
        path = os.fspath(a.bop / "models" / f"obj_{obj_id:06d}.ply")
        ren.add_object(obj_id, path)
        if vis_ren is not None:
            vis_ren.add_object(obj_id, path)

    found: dict[str, list[float]] = {
        "mask_iou": [],
        "mask_visib_iou": [],
        "visib_fract_abs_diff": [],
        "visib_fract_abs_diff_in_image": [],
        "bbox_visib_max_abs_diff_px": [],
        "bbox_obj_max_abs_diff_px": [],
        "px_count_valid_rel_diff": [],
        "depth_abs_diff_mm_median": [],
        "toolkit_visib_outside_mask_visib": [],
        "mask_visib_outside_toolkit_visib": [],
    }
    # Why the toolkit's visible pixels outside mgn's are visible to it: no depth value there
    # (BOP19 counts those visible), or the model lies at most delta behind the surface seen.
    extra = {"pixels": 0, "no_depth": 0, "within_delta_behind": 0}
    # Pixels of an image inside some toolkit visible mask, and inside two or more (mgn's
    # visible masks never overlap: one instance id per pixel).
    overlap = {"pixels": 0, "in_two_or_more": 0}
    truncated = 0
    counts = {"scenes": 0, "images": 0, "annotations": 0}
    for scene in sorted(q for q in (a.bop / a.split).iterdir() if q.name.isdigit()):
        counts["scenes"] += 1
        cams = inout.load_scene_camera(scene / "scene_camera.json")
        gts = inout.load_scene_gt(scene / "scene_gt.json")
        gt_info = inout.load_json(scene / "scene_gt_info.json", keys_to_int=True)
        for k, im_id in enumerate(sorted(gts)):
            counts["images"] += 1
            K = cams[im_id]["cam_K"]
            fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
            depth = inout.load_depth(scene / "depth" / f"{im_id:06d}.png")
            depth *= cams[im_id]["depth_scale"]  # mm
            dist_im = misc.depth_im_to_dist_im_fast(depth, K)
            claimed = np.zeros((h, w), np.int32)  # toolkit visible masks covering each pixel
            for gt_id, gt in enumerate(gts[im_id]):
                counts["annotations"] += 1
                large = ren.render_object(gt["obj_id"], gt["cam_R_m2c"], gt["cam_t_m2c"],
                                          fx, fy, cx + w, cy + h)["depth"]  # fmt: skip
                depth_gt = large[h : 2 * h, w : 2 * w]
                dist_gt = misc.depth_im_to_dist_im_fast(depth_gt, K)
                visib = visibility.estimate_visib_mask_gt(dist_im, dist_gt, a.delta, "bop19")
                full = dist_gt > 0
                name = f"{im_id:06d}_{gt_id:06d}.png"
                ours_full = inout.load_im(scene / "mask" / name) > 0
                ours_visib = inout.load_im(scene / "mask_visib" / name) > 0
                mine = gt_info[im_id][gt_id]
                found["mask_iou"].append(_iou(full, ours_full))
                found["mask_visib_iou"].append(_iou(visib, ours_visib))
                n_all_large = int((large > 0).sum())
                truncated += int(n_all_large > int(full.sum()))
                theirs = visib.sum() / n_all_large if n_all_large else 0.0
                theirs_in = visib.sum() / full.sum() if full.sum() else 0.0
                found["visib_fract_abs_diff"].append(abs(theirs - mine["visib_fract"]))
                found["visib_fract_abs_diff_in_image"].append(abs(theirs_in - mine["visib_fract"]))
                valid = int((dist_im[full] > 0).sum())
                found["px_count_valid_rel_diff"].append(
                    abs(valid - mine["px_count_valid"]) / max(mine["px_count_valid"], 1)
                )
                if visib.any() and mine["bbox_visib"][0] >= 0:
                    ys, xs = visib.nonzero()
                    bb = misc.calc_2d_bbox(xs, ys, (w, h))
                    found["bbox_visib_max_abs_diff_px"].append(
                        float(np.abs(np.subtract(bb, mine["bbox_visib"])).max())
                    )
                if full.any() and mine["bbox_obj"][0] >= 0:
                    ys, xs = full.nonzero()
                    bb = misc.calc_2d_bbox(xs, ys, (w, h))
                    found["bbox_obj_max_abs_diff_px"].append(
                        float(np.abs(np.subtract(bb, mine["bbox_obj"])).max())
                    )
                claimed += visib
                out_t = visib & ~ours_visib
                found["toolkit_visib_outside_mask_visib"].append(
                    int(out_t.sum()) / max(int(visib.sum()), 1)
                )
                found["mask_visib_outside_toolkit_visib"].append(
                    int((ours_visib & ~visib).sum()) / max(int(ours_visib.sum()), 1)
                )
                extra["pixels"] += int(out_t.sum())
                extra["no_depth"] += int((out_t & (dist_im == 0)).sum())
                extra["within_delta_behind"] += int((out_t & (dist_im > 0)).sum())
                both = ours_visib & (depth > 0) & (depth_gt > 0)
                if both.any():
                    found["depth_abs_diff_mm_median"].append(
                        float(np.median(np.abs(depth[both] - depth_gt[both])))
                    )
            overlap["pixels"] += int((claimed > 0).sum())
            overlap["in_two_or_more"] += int((claimed > 1).sum())
            if vis_ren is not None and k < a.vis:
                rgb = inout.load_im(scene / "rgb" / f"{im_id:06d}.png")[:, :, :3]
                poses = [{"obj_id": g["obj_id"], "R": g["cam_R_m2c"], "t": g["cam_t_m2c"],
                          "text_info": [{"name": "", "val": g["obj_id"], "fmt": ""}]}
                         for g in gts[im_id]]  # fmt: skip
                out = visualization.vis_object_poses(poses, K, vis_ren, rgb=rgb, depth=depth,
                                                     vis_rgb=True, vis_depth_diff=True,
                                                     vis_rgb_resolve_visib=True)  # fmt: skip
                a.out.mkdir(parents=True, exist_ok=True)
                for key in ("vis_im_rgb", "depth_diff_vis"):
                    if key in out:
                        path = a.out / f"{scene.name}_{im_id:06d}_{key}.png"
                        inout.save_im(path, np.asarray(out[key], np.uint8))

    summary: dict[str, Any] = {
        "toolkit": os.fspath(a.toolkit),
        "renderer": a.renderer,
        "delta_mm": a.delta,
        **counts,
        "truncated_annotations": truncated,
        "toolkit_extra_visible_pixels": extra,
        "toolkit_visible_masks_overlap": overlap,
        **{k: _stats(v) for k, v in found.items()},
        "mask_visib_iou_below_0.9": int(sum(x < 0.9 for x in found["mask_visib_iou"])),
        "mask_iou_below_0.99": int(sum(x < 0.99 for x in found["mask_iou"])),
    }
    text = json.dumps(summary, indent=1)
    print(text)
    if a.json is not None:
        a.json.write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
