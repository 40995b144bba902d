"""Learning baselines trained on mgn datasets (optional extra ``mgn[learn]``: PyTorch, SciPy).

- class-agnostic instance segmentation of the visible objects (amodal masks as an option) and a
  per-pixel suction quality map, from RGB, the depth sensor's depth, or both
  (:mod:`mgn.learn.training`, ``mgn train``);
- prediction on any photographs (:mod:`mgn.learn.predict`, ``mgn predict``);
- evaluation on real photographs with labels (:mod:`mgn.learn.real_eval`, ``mgn eval real``).

PyTorch is imported inside functions only: ``import mgn.learn`` works without it, and the
first call that needs it raises :class:`~mgn.errors.UnsupportedError` naming ``mgn[learn]``.
"""

from __future__ import annotations

from mgn.learn.backend import require_torch
from mgn.learn.config import ModelConfig, TrainConfig
from mgn.learn.instances import InstanceMaps, instances_from_maps
from mgn.learn.predict import Prediction, Predictor, predict_files
from mgn.learn.training import TrainResult, train

__all__ = [
    "InstanceMaps",
    "ModelConfig",
    "Prediction",
    "Predictor",
    "TrainConfig",
    "TrainResult",
    "instances_from_maps",
    "predict_files",
    "require_torch",
    "train",
]
