"""The dataset pipeline: ``mgn generate`` (scene tasks on a process pool or Dask), object-label
cache, the config and the scene writer.

- :func:`generate`: objects, gripper and cup in, a complete dataset out (resumable).
- :func:`scene_seed`: the seed of scene i of a dataset.
- :func:`run_scene`: one scene task (drop, write, manifest, rename).
- :func:`write_scene`: the one function that writes a scene folder.
- :func:`object_labels`: an object's labels, cached in ``$MGN_CACHE_DIR/labels``.

Names are imported on first use, so ``import mgn`` stays light.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mgn.base.lazy import lazy_exports

_EXPORTS = {
    "GenerateReport": "report",
    "SceneResult": "scene_task",
    "SceneTask": "scene_task",
    "generate": "runner",
    "run_scene": "scene_task",
    "scene_seed": "seeds",
    "ObjectLabels": "label_cache",
    "label_cache_dir": "label_cache",
    "object_labels": "label_cache",
    "write_models": "label_cache",
    "scene_views": "scene_writer",
    "write_scene": "scene_writer",
}

__all__ = [
    "GenerateReport",
    "ObjectLabels",
    "SceneResult",
    "SceneTask",
    "generate",
    "label_cache_dir",
    "object_labels",
    "run_scene",
    "scene_seed",
    "scene_views",
    "write_models",
    "write_scene",
]


__getattr__, __dir__ = lazy_exports("mgn.pipeline", _EXPORTS, globals())


if TYPE_CHECKING:
    from mgn.pipeline.label_cache import (
        ObjectLabels,
        label_cache_dir,
        object_labels,
        write_models,
    )
    from mgn.pipeline.report import GenerateReport
    from mgn.pipeline.runner import generate
    from mgn.pipeline.scene_task import SceneResult, SceneTask, run_scene
    from mgn.pipeline.scene_writer import scene_views, write_scene
    from mgn.pipeline.seeds import scene_seed
