"""Training views of an mgn dataset as arrays at the network's resolution (no PyTorch here).

:func:`training_views` picks the views (the dataset's ``"selection"`` when ``dataset.json`` has
one, else every view, optionally narrowed to some scenes and view indices); :func:`load_views`
reads each view through :class:`mgn.Dataset` -- RGB, the sensor model's depth (as a real
camera gives it; for the height modalities with the view's intrinsics and, by default, the
scene's own floor and bin interior: :func:`scene_geometry`), the visible
instance ids, the amodal masks (amodal models) and the non-colliding scene suction grasps --
and builds the targets of :mod:`mgn.learn.targets`.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from mgn.errors import InvalidArgumentError, IoError
from mgn.io.dataset import Dataset, View
from mgn.learn.config import ModelConfig
from mgn.learn.floor import FloorPlane, bin_interior, scene_floor
from mgn.learn.targets import (
    core_target,
    hidden_target,
    network_input,
    network_shape,
    resize_nearest,
    suction_target,
    uses_depth,
    uses_rgb,
)

__all__ = ["TrainingArrays", "load_views", "scene_geometry", "training_views", "view_targets"]


def training_views(
    dataset: Dataset | str | os.PathLike[str],
    *,
    scenes: Sequence[int] | None = None,
    views: Sequence[int] | None = None,
) -> list[View]:
    """The views to train on, ascending by (scene, view): the ``dataset.json`` ``"selection"``
    when present, else every view; only ``scenes`` / ``views`` (indices) when given. An empty
    result is an :class:`~mgn.errors.InvalidArgumentError` naming the dataset."""
    ds = dataset if isinstance(dataset, Dataset) else Dataset(dataset)
    selection = (ds.info or {}).get("selection")
    if selection is not None:
        try:
            pairs = sorted({(int(e["scene"]), int(e["view"])) for e in selection["views"]})
        except (KeyError, TypeError, ValueError) as e:
            raise IoError(f"{ds.root}/dataset.json: unreadable 'selection': {e}") from e
    else:
        pairs = [(s.scene_id, v) for s in ds.scenes() for v in s.view_ids]
    if scenes is not None:
        pairs = [p for p in pairs if p[0] in set(scenes)]
    if views is not None:
        pairs = [p for p in pairs if p[1] in set(views)]
    if not pairs:
        raise InvalidArgumentError(
            f"'{ds.root}': no views to train on (scenes {ds.scene_ids[:10]}; filters: scenes "
            f"{list(scenes) if scenes is not None else 'all'}, views "
            f"{list(views) if views is not None else 'all'})"
        )
    return [View(ds.root / f"scene{s}", v) for s, v in pairs]


def view_targets(view: View, config: ModelConfig) -> dict[str, np.ndarray]:
    """The targets of one view at its own resolution: ``foreground`` and ``hidden`` (amodal
    models) as bool, ``core``, ``suction`` and ``suction_weight`` as float32."""
    ids = view.instances
    out: dict[str, np.ndarray] = {"foreground": ids > 0, "core": core_target(ids)}
    if config.amodal:
        out["hidden"] = hidden_target(ids, view.amodal)
    grasps = view.grasps("suction")
    if grasps and len(grasps.get("object_id", ())):
        if config.suction_score not in grasps:
            raise IoError(f"{view}: the suction grasps have no '{config.suction_score}'")
        contacts = grasps["contact_poses_relative_to_camera"][:, :3, 3]
        raw = np.asarray(grasps[config.suction_score], np.float64)
        if np.isnan(raw).all():
            raise InvalidArgumentError(
                f"{view}: every suction '{config.suction_score}' is NaN (not computed for this "
                "dataset); train with another --suction-score"
            )
        scores = np.nan_to_num(raw, nan=0.0)
        ids_of = grasps["object_id"].astype(np.int64) + 1  # object_id = instance id - 1
        q, w = suction_target(
            contacts, scores, ids_of, ids, view.intrinsics, radius_m=config.suction_radius_m
        )
    else:
        q = np.zeros(ids.shape, np.float32)
        w = (ids == 0).astype(np.float32)
    out["suction"], out["suction_weight"] = q, w
    return out


@dataclass
class TrainingArrays:
    """Stacked network inputs and targets of V views at one resolution (H, W).

    Attributes:
        inputs: (V, C, H, W) float32 (:func:`mgn.learn.targets.network_input`).
        targets: (V, T, H, W) float32, channels in the order of ``ModelConfig.outputs``.
        weights: (V, H, W) float32 weight of the suction channel.
        names: "scene<N>/<v>" per view.
    """

    inputs: npt.NDArray[np.float32]
    targets: npt.NDArray[np.float32]
    weights: npt.NDArray[np.float32]
    names: list[str]

    def __len__(self) -> int:
        return len(self.names)


def _bin_size(folder: Path) -> tuple[float, float] | None:
    """(inner_length, inner_width) m of the bin of the dataset holding scene ``folder``, from its
    ``dataset.json`` config; None when the file or the sizes are missing."""
    info = Dataset(folder.parent).info or {}
    tote = (info.get("config") or {}).get("tote") or {}
    try:
        return float(tote["inner_length"]), float(tote["inner_width"])
    except (KeyError, TypeError, ValueError):
        return None


def scene_geometry(
    view: View, bin_size: tuple[float, float] | None, *, interior: bool = True
) -> tuple[FloorPlane | None, np.ndarray | None]:
    """(floor, inside) of a synthetic view for the height modalities: the bin's inner floor in
    the camera frame (:func:`mgn.learn.floor.scene_floor`) and, with ``interior``, the bin's
    interior (:func:`mgn.learn.floor.bin_interior`, ``bin_size`` (inner length, width) m;
    without it None: the footprint of the floor's pixels is used); (None, None) when the view
    has no camera pose or ``bin_size`` is None, so that the fit is used."""
    if bin_size is None:
        return None, None
    try:
        X_WC = view.X_WC
    except (IoError, KeyError):
        return None, None
    if not interior:
        return scene_floor(X_WC), None
    inside = bin_interior(view.depth, view.intrinsics, X_WC, *bin_size, name=str(view))
    return scene_floor(X_WC), inside


def load_views(views: Sequence[View], config: ModelConfig) -> TrainingArrays:
    """Inputs and targets of ``views`` at the network resolution of the first view (the
    others are resized to it)."""
    if not views:
        raise InvalidArgumentError("load_views: no views")
    first = views[0].rgb
    shape = network_shape(first.shape[0], first.shape[1], config.image_size)
    height = config.modality in ("height", "rgb-height")
    scene = height and config.training_floor in ("scene", "interior")
    bin_sizes: dict[str, tuple[float, float] | None] = {}
    inputs, targets, weights, names = [], [], [], []
    for view in views:
        name = f"{view.folder.name}/{view.index}"
        rgb = view.rgb if uses_rgb(config.modality) else None
        depth = view.depth if uses_depth(config.modality) else None
        intrinsics = view.intrinsics if height else None
        floor, inside = None, None
        if scene:
            root = os.fspath(view.folder.parent)
            if root not in bin_sizes:
                bin_sizes[root] = _bin_size(view.folder)
            floor, inside = scene_geometry(
                view, bin_sizes[root], interior=config.training_floor == "interior"
            )
        inputs.append(
            network_input(
                rgb,
                depth,
                config.modality,
                shape,
                name=name,
                intrinsics=intrinsics,
                floor_footprint=config.floor_footprint,
                floor=floor,
                inside=inside,
            )
        )
        t = view_targets(view, config)
        targets.append(
            np.stack([resize_nearest(t[k], shape).astype(np.float32) for k in config.outputs])
        )
        weights.append(resize_nearest(t["suction_weight"], shape))
        names.append(name)
    return TrainingArrays(np.stack(inputs), np.stack(targets), np.stack(weights), names)
