"""Extract real, labelled bin photographs from a local copy of a public repository into folders
that ``mgn eval real`` reads (images + one COCO instances JSON + ``<stem>_depth.npy``).

No network: the source is a repository you already have, either a checkout (a folder with the
files) or a bare git directory (read with ``git show``).

Source (the only one so far): BerkeleyAutomation/gqcnn (https://github.com/BerkeleyAutomation/gqcnn),
``data/examples/clutter/``: real RGB-D photographs of piles of household objects with a
foreground mask per image (``segmask_<i>.png``, 255 on objects) shipped as grasp-planning
examples. Licence: the repository's LICENSE (UC Berkeley, "educational, research, and
not-for-profit purposes, without fee"; commercial use needs a licence from UC Berkeley). That is
why the photographs are not in this project: fetch the repository yourself and run this script.

- ``gqcnn_phoxi/``: 10 photographs of a black bin from above (Photoneo PhoXi, two example sets
  ``dex-net_4.0`` and ``fcgqcnn``, 5 each). The colour image (1032 x 772) is reduced 2 x 2 to
  the mask's and the depth's 516 x 386 px (mean of each 2 x 2 block).
- ``gqcnn_primesense/``: 5 photographs of objects on a green table from above (PrimeSense,
  640 x 480).

The masks mark every object pixel without separating the objects, so each image gets one COCO
annotation with ``iscrowd: 1``: ``mgn eval real`` scores the foreground IoU on it and reports
no mask AP. How the masks were made is not documented (their holes at depth shadows suggest a
depth-based background subtraction rather than hand drawing).

    python scripts/get_real_photos.py /path/to/gqcnn OUT

writes ``OUT/gqcnn_phoxi/`` and ``OUT/gqcnn_primesense/`` and prints the files' git blob ids
(the same ids mean the same photographs).
"""

from __future__ import annotations

import argparse
import hashlib
import io
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
from PIL import Image
from pycocotools import mask as mask_utils

CLUTTER = "data/examples/clutter"
SETS = {
    "gqcnn_phoxi": [(f"phoxi/{s}", i) for s in ("dex-net_4.0", "fcgqcnn") for i in range(5)],
    "gqcnn_primesense": [("primesense", i) for i in range(5)],
}


class Source:
    """Files of a checkout folder or of HEAD of a bare git directory."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.git = not (path / CLUTTER).is_dir()
        if self.git and not (path / "HEAD").exists() and not (path / ".git").exists():
            raise SystemExit(
                f"'{path}': neither a gqcnn checkout (no {CLUTTER}/) nor a git directory"
            )

    def read(self, rel: str) -> bytes:
        if not self.git:
            return (self.path / rel).read_bytes()
        r = subprocess.run(
            ["git", "--git-dir", str(self.path), "show", f"HEAD:{rel}"],
            capture_output=True,
            check=False,
        )
        if r.returncode != 0:
            raise SystemExit(f"'{self.path}': cannot read {rel}: {r.stderr.decode().strip()}")
        return r.stdout


def blob_id(data: bytes) -> str:
    return hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest()


def halve(rgb: np.ndarray) -> np.ndarray:
    h, w = rgb.shape[0] // 2, rgb.shape[1] // 2
    blocks = rgb[: 2 * h, : 2 * w].reshape(h, 2, w, 2, 3).astype(np.float64)
    out: np.ndarray = np.rint(blocks.mean(axis=(1, 3))).astype(np.uint8)
    return out


def extract(src: Source, name: str, items: list[tuple[str, int]], out: Path) -> list[str]:
    folder = out / name
    folder.mkdir(parents=True, exist_ok=True)
    images, anns, ids = [], [], []
    for k, (sub, i) in enumerate(items):
        files = {
            key: f"{CLUTTER}/{sub}/{key}_{i}.{ext}"
            for key, ext in (("color", "png"), ("segmask", "png"), ("depth", "npy"))
        }
        raw = {key: src.read(rel) for key, rel in files.items()}
        ids += [f"{blob_id(raw[key])}  {rel}" for key, rel in files.items()]
        rgb = np.asarray(Image.open(io.BytesIO(raw["color"])).convert("RGB"))
        seg = np.asarray(Image.open(io.BytesIO(raw["segmask"])).convert("L")) > 0
        depth = np.load(io.BytesIO(raw["depth"]), allow_pickle=False).astype(np.float32)
        depth = depth.reshape(depth.shape[0], depth.shape[1])
        if rgb.shape[:2] == (2 * seg.shape[0], 2 * seg.shape[1]):
            rgb = halve(rgb)
        if rgb.shape[:2] != seg.shape or depth.shape != seg.shape:
            raise SystemExit(
                f"{sub} {i}: colour {rgb.shape[:2]}, mask {seg.shape}, depth {depth.shape} differ"
            )
        stem = f"{sub.replace('/', '_').replace('.', '')}_{i}"
        Image.fromarray(rgb).save(folder / f"{stem}.png")
        np.save(folder / f"{stem}_depth.npy", depth)
        rle = mask_utils.encode(np.asfortranarray(seg.astype(np.uint8)))
        h, w = seg.shape
        images.append({"id": k + 1, "file_name": f"{stem}.png", "width": w, "height": h})
        anns.append(
            {
                "id": k + 1,
                "image_id": k + 1,
                "category_id": 1,
                "iscrowd": 1,
                "segmentation": {"size": [h, w], "counts": rle["counts"].decode("ascii")},
                "area": float(mask_utils.area(rle)),
                "bbox": [float(v) for v in mask_utils.toBbox(rle)],
            }
        )
    doc = {
        "info": {
            "description": f"{name}: real photographs from BerkeleyAutomation/gqcnn "
            f"{CLUTTER}; foreground masks as iscrowd annotations",
            "licence": "UC Berkeley educational/research/not-for-profit (gqcnn LICENSE)",
        },
        "images": images,
        "annotations": anns,
        "categories": [{"id": 1, "name": "object"}],
    }
    (folder / "annotations.json").write_text(json.dumps(doc) + "\n")
    return ids


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("gqcnn", type=Path, help="gqcnn checkout folder or bare git directory")
    ap.add_argument("out", type=Path, help="output folder")
    args = ap.parse_args(argv)
    src = Source(args.gqcnn)
    for name, items in SETS.items():
        for line in extract(src, name, items, args.out):
            print(line)
        print(f"wrote {args.out / name} ({len(items)} images)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
