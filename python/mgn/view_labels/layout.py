"""Layout labels of one camera view: who lies on whom, layers, a picking order, difficulty.

:func:`compute_layout` takes the per-view label arrays (visible instance ids, amodal masks, depth,
per-object categories, bin relations and occlusion rates) and returns a frozen :class:`Layout`.
The pixel work is done in C++ (``cpp/include/mgn/scene/layout.hpp``, where every rule is stated);
in short:

- *Relation*: A occludes (is a parent of) B when A is seen on at least ``min_overlap_px`` pixels
  of B's amodal mask and on at least ``min_overlap_fraction`` of the pixels of the two amodal
  masks' overlap that show A or B, and A is seen above B where they meet (below). Both
  directions can hold (interlocked or nested objects), each on its own stretch of boundary.
  Relation matrix ``M[i, j] = -1`` if object j occludes object i, ``+1`` for the reverse, ``0``
  otherwise (mutual occlusion: both entries -1).
- *Own stretch of boundary* of A over B: the pixels p of B's visible mask with a 4-neighbour q
  that shows A inside B's amodal mask (A covers B at q) and lies in front (depth(q) <
  depth(p)). A pixel pair belongs to the stretch of whichever object is in front there, so no
  boundary counts for both directions. ``edge_size`` = the stretch's pixel count,
  ``depth_diff`` = median of depth(p) - depth(q) over it (m, > 0). A parent candidate that
  meets B on a measured contour but is in front nowhere on it lies behind B: no relation. When
  their contour has no pixel pair with valid depths, the masks alone decide (edge_size 0,
  depth_diff NaN; pass the noise-free depth for clean values).
- *Layers*: 0 top (no parent), 1 secondary (exactly one parent, a top object), 2 interlock (in an
  occlusion cycle -- a strongly connected component of size >= 2 -- whose members each have at
  most one parent outside it), 3 others. Objects without visible pixels get layer 3, no
  relations, ``visible=False``, and are left out of the order and of the difficulty (the
  dataset files leave them out of the view: :func:`mgn.view_labels.objects.seen_objects`).
- *Order*: instance ids of the visible objects, parents always before children (smallest id
  first; a cycle is broken at its least occluded object).
- *Complete*: one 8-connected visible region, ignoring specks smaller than
  ``max(min_region_px, min_region_fraction * visible px)``.
- *Difficulty* (paper Table IV): 1 = <= 2 layers present, no occlusion > 5 %, all complete,
  classes unique; 2 = all complete, classes unique; 3 = unique, some incomplete; 4 = all complete,
  some class repeated; 5 = some incomplete and some repeated.

Serialisation (MetaGraspNet layout, docs/format.md): :meth:`Layout.order_json` (``{v}_order.json``,
depth differences in cm), :meth:`Layout.order_csv` (``{v}_order.csv``, the -1 entries only),
:meth:`Layout.layout_json` (``{v}_layout.json``: difficulty and its ingredients); the files are
written by :func:`mgn.io.scene_folder.write_view` and read back by :mod:`mgn.io.order_files`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.base.units import M_TO_CM
from mgn.errors import InvalidArgumentError

__all__ = [
    "BIN_RELATIONS",
    "OCCLUSION_DECIMALS",
    "Layout",
    "compute_layout",
]

#: Valid per-object bin relations.
BIN_RELATIONS: tuple[str, ...] = ("no_rel", "edge", "corner")

#: Decimals of the occlusion rates in the dataset files (``{v}_order.json``, and the pipeline's
#: ``{v}.npz`` occlusion image and ``objects/occlusion``): MetaGraspNet's files hold them to 4.
OCCLUSION_DECIMALS = 4


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class Layout:
    """Layout labels of one view. Object axis: N objects in scene order (row i = instance i+1).

    Relations are listed once each, sorted by (child, parent), as 1-based instance ids.
    """

    relation: npt.NDArray[np.int8]  #: (N, N) matrix M (see module docstring)
    parent_ids: npt.NDArray[np.int32]  #: (R,) instance id of each relation's parent (on top)
    child_ids: npt.NDArray[np.int32]  #: (R,) instance id of each relation's child (below)
    depth_diff: npt.NDArray[np.float64]  #: (R,) m, median depth(child) - depth(parent), > 0
    edge_size: npt.NDArray[np.int32]  #: (R,) px of the parent's own stretch of boundary
    seen_px: npt.NDArray[np.int64]  #: (R,) px of the child's amodal mask showing the parent
    occlusion: npt.NDArray[np.float64]  #: (N,) occlusion rates (input, passed through)
    categories: npt.NDArray[np.int32]  #: (N,) category ids (input, passed through)
    bin_relations: tuple[str, ...]  #: (N,) "no_rel" | "edge" | "corner" (passed through)
    visible: npt.NDArray[np.bool_]  #: (N,) at least one visible pixel
    visible_px: npt.NDArray[np.int64]  #: (N,)
    layer: npt.NDArray[np.int8]  #: (N,) 0 top, 1 secondary, 2 interlock, 3 others
    num_regions: npt.NDArray[np.int32]  #: (N,) visible regions above the speck size
    complete: npt.NDArray[np.bool_]  #: (N,) visible and one region
    total_covered_edge: npt.NDArray[np.int64]  #: (N,) px, sum of the children's edge_size
    order: npt.NDArray[np.int32]  #: picking order of the visible objects (instance ids)
    num_layers: int  #: distinct layers among the visible objects
    max_occlusion: float  #: largest occlusion rate of a visible object (0 without any)
    classes_unique: bool  #: no two visible objects share a category
    difficulty: int  #: 1..5

    @property
    def num_objects(self) -> int:
        return int(self.relation.shape[0])

    def parents(self, instance_id: int) -> list[tuple[int, float, int]]:
        """(parent id, depth_diff m, edge_size px) of each parent of an instance, by parent id."""
        k = np.flatnonzero(self.child_ids == instance_id)
        return [
            (int(self.parent_ids[i]), float(self.depth_diff[i]), int(self.edge_size[i])) for i in k
        ]

    def children(self, instance_id: int) -> list[tuple[int, float, int]]:
        """(child id, depth_diff m, edge_size px) of each child of an instance, by child id."""
        k = np.flatnonzero(self.parent_ids == instance_id)
        k = k[np.argsort(self.child_ids[k], kind="stable")]
        return [
            (int(self.child_ids[i]), float(self.depth_diff[i]), int(self.edge_size[i])) for i in k
        ]

    def order_json(self) -> dict[str, Any]:
        """The ``{v}_order.json`` content: keys "1".."N"; depth differences in centimetres,
        occlusion rates to :data:`OCCLUSION_DECIMALS` decimals.

        A depth difference that could not be measured (NaN: no valid depth at the boundary) is
        written as 0.0; its ``edge_size`` tells whether a boundary exists.
        """

        def entry(other: int, dd: float, edge: int) -> dict[str, Any]:
            return {
                "id": other,
                "depth_diff": 0.0 if math.isnan(dd) else round(dd * M_TO_CM, 6),
                "edge_size": edge,
            }

        out: dict[str, Any] = {}
        for i in range(self.num_objects):
            iid = i + 1
            parents = [entry(*p) for p in self.parents(iid)]
            out[str(iid)] = {
                "id": iid,
                "occlusion": round(float(self.occlusion[i]), OCCLUSION_DECIMALS),
                "layer": int(self.layer[i]),
                "parents": parents or [{"id": 0, "depth_diff": 0.0, "edge_size": 0.0}],
                "children": [entry(*c) for c in self.children(iid)],
                "total_covered_edge": int(self.total_covered_edge[i]),
                "bin_rel": self.bin_relations[i],
            }
        return out

    def layout_json(self) -> dict[str, Any]:
        """The ``{v}_layout.json`` content (mgn extension): the view's difficulty, its
        ingredients, the picking order and per-object visibility and completeness."""
        return {
            "difficulty": int(self.difficulty),
            "num_layers": int(self.num_layers),
            "max_occlusion": float(self.max_occlusion),
            "classes_unique": bool(self.classes_unique),
            "all_complete": bool(np.all(self.complete[self.visible])),
            "order": [int(x) for x in self.order],
            "objects": {
                str(i + 1): {
                    "visible": bool(self.visible[i]),
                    "visible_px": int(self.visible_px[i]),
                    "complete": bool(self.complete[i]),
                    "num_regions": int(self.num_regions[i]),
                    "layer": int(self.layer[i]),
                    "category_id": int(self.categories[i]),
                    "bin_rel": self.bin_relations[i],
                }
                for i in range(self.num_objects)
            },
        }

    def order_csv(self) -> str:
        """The ``{v}_order.csv`` content: N rows of N comma-separated integers, ``-1`` where
        instance j+1 lies on / occludes instance i+1, else ``0`` (the synthetic convention: only
        the -1 entries are stored). Empty for N = 0."""
        stored = np.where(self.relation == -1, -1, 0)
        return "".join(",".join(str(int(x)) for x in row) + "\n" for row in stored)


def _ids_array(visible: npt.ArrayLike) -> np.ndarray:
    v = np.asarray(visible)
    if v.ndim != 2:
        raise InvalidArgumentError(f"compute_layout: visible: expected shape (H, W), got {v.shape}")
    if v.dtype.kind == "f":
        if not np.all(np.isfinite(v)) or not np.array_equal(v, np.round(v)):
            raise InvalidArgumentError(
                "compute_layout: visible: expected integer instance ids, got non-integer values"
            )
    elif v.dtype.kind not in "iub":
        raise InvalidArgumentError(
            f"compute_layout: visible: expected integer instance ids, got dtype {v.dtype}"
        )
    if v.size and (v.min() < 0 or v.max() > np.iinfo(np.int32).max):
        raise InvalidArgumentError(
            f"compute_layout: visible: ids must be >= 0, got min {v.min()}, max {v.max()}"
        )
    return np.ascontiguousarray(v, np.int32)


def _mask_array(amodal: npt.ArrayLike) -> np.ndarray:
    a = np.asarray(amodal)
    if a.ndim != 3:
        raise InvalidArgumentError(
            f"compute_layout: amodal: expected shape (N, H, W), got {a.shape}"
        )
    if a.dtype == np.bool_:
        return np.ascontiguousarray(a).view(np.uint8)  # no copy when already contiguous
    if a.dtype.kind not in "iuf":
        raise InvalidArgumentError(
            f"compute_layout: amodal: expected boolean masks, got dtype {a.dtype}"
        )
    return np.ascontiguousarray(a != 0).view(np.uint8)


def compute_layout(
    visible: npt.ArrayLike,
    amodal: npt.ArrayLike,
    depth: npt.ArrayLike,
    categories: npt.ArrayLike,
    bin_relations: Sequence[str],
    *,
    occlusion: npt.ArrayLike,
    min_overlap_px: int = 10,
    min_overlap_fraction: float = 0.1,
    min_region_px: int = 10,
    min_region_fraction: float = 0.005,
    max_occlusion_level1: float = 0.05,
    num_threads: int = 0,
) -> Layout:
    """Layout labels of one view.

    Args:
        visible: (H, W) visible instance id per pixel, 0 = none, else 1..N.
        amodal: (N, H, W) bool amodal masks, row i = instance i+1.
        depth: (H, W) z-depth in metres, 0 or NaN where invalid (the noise-free depth gives the
            cleanest depth differences).
        categories: (N,) category ids.
        bin_relations: N strings, each "no_rel", "edge" or "corner" (passed through).
        occlusion: (N,) occlusion rates in [0, 1] (from the per-view masks).
        min_overlap_px, min_overlap_fraction: relation thresholds (module docstring).
        min_region_px, min_region_fraction: speck size ignored by the completeness test.
        max_occlusion_level1: largest occlusion rate allowed in difficulty level 1.
        num_threads: threads for the per-object passes (0 = all); results do not depend on it.

    Raises:
        InvalidArgumentError: a shape, dtype or value that does not fit (the message names it).
    """
    vis = _ids_array(visible)
    masks = _mask_array(amodal)
    n = masks.shape[0]
    d = np.asarray(depth)
    if d.dtype.kind not in "iuf":
        raise InvalidArgumentError(f"compute_layout: depth: expected float32, got {d.dtype}")
    d = np.ascontiguousarray(d, np.float32)
    cats = np.asarray(categories)
    if cats.shape != (n,) or (cats.size and cats.dtype.kind not in "iu"):
        raise InvalidArgumentError(
            f"compute_layout: categories: expected ({n},) integer category ids, got shape "
            f"{cats.shape}, dtype {cats.dtype}"
        )
    cats = np.ascontiguousarray(cats, np.int32)
    occ = np.ascontiguousarray(occlusion, np.float64)
    if occ.shape != (n,):
        raise InvalidArgumentError(
            f"compute_layout: occlusion: expected shape ({n},), got {occ.shape}"
        )
    if isinstance(bin_relations, str):
        raise InvalidArgumentError(
            "compute_layout: bin_relations: expected a sequence of N strings, got one string"
        )
    bins = tuple(bin_relations)
    if len(bins) != n:
        raise InvalidArgumentError(
            f"compute_layout: bin_relations: expected {n} entries (one per object), got {len(bins)}"
        )
    bad = sorted({str(b) for b in bins} - set(BIN_RELATIONS))
    if bad:
        raise InvalidArgumentError(
            f"compute_layout: bin_relations: unknown values {bad}; valid: {list(BIN_RELATIONS)}"
        )
    r = _core.scene.compute_layout(
        vis,
        masks,
        d,
        cats,
        occ,
        min_overlap_px=min_overlap_px,
        min_overlap_fraction=min_overlap_fraction,
        min_region_px=min_region_px,
        min_region_fraction=min_region_fraction,
        max_occlusion_level1=max_occlusion_level1,
        num_threads=num_threads,
    )
    return Layout(
        relation=_frozen(np.asarray(r.relation, np.int8).reshape(n, n)),
        parent_ids=_frozen(np.asarray(r.rel_parent, np.int32) + 1),
        child_ids=_frozen(np.asarray(r.rel_child, np.int32) + 1),
        depth_diff=_frozen(np.asarray(r.rel_depth_diff, np.float64)),
        edge_size=_frozen(np.asarray(r.rel_edge_size, np.int32)),
        seen_px=_frozen(np.asarray(r.rel_seen_px, np.int64)),
        occlusion=_frozen(occ.copy()),
        categories=_frozen(cats.copy()),
        bin_relations=tuple(str(b) for b in bins),
        visible=_frozen(np.asarray(r.visible, bool)),
        visible_px=_frozen(np.asarray(r.visible_px, np.int64)),
        layer=_frozen(np.asarray(r.layer, np.int8)),
        num_regions=_frozen(np.asarray(r.num_regions, np.int32)),
        complete=_frozen(np.asarray(r.complete, bool)),
        total_covered_edge=_frozen(np.asarray(r.total_covered_edge, np.int64)),
        order=_frozen(np.asarray(r.order, np.int32)),
        num_layers=int(r.num_layers),
        max_occlusion=float(r.max_occlusion),
        classes_unique=bool(r.classes_unique),
        difficulty=int(r.difficulty),
    )
