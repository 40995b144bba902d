"""Suction grasps: seal models and object suction labels (calibration: :mod:`mgn.calibration`).

SealModel(mesh, cup, model)         seal score of candidates (spring, strain, smoothness)
suction_wrench_scores(...)          wrench resistance under gravity
label_object(mesh, mass=, com=)     object labels (mgn.io.grasp_file.write_suction_labels)

"""

from mgn.suction.labels import SuctionLabels, label_object
from mgn.suction.seal import (
    FAILURE_REASONS,
    SEAL_MODELS,
    SealModel,
    SealResult,
    core_cup,
    suction_wrench_scores,
)

__all__ = [
    "FAILURE_REASONS",
    "SEAL_MODELS",
    "SealModel",
    "SealResult",
    "SuctionLabels",
    "core_cup",
    "label_object",
    "suction_wrench_scores",
]
