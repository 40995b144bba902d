"""Parallel-jaw grasps: gripper conversion, antipodal sampling, wrench score, object labels.

core_gripper(gripper)                  the C++ gripper for a mgn.hardware.ParallelJawGripper
AntipodalSampler(mesh, gripper)        antipodal robust sampler (docs/models.md §5)
pj_wrench_scores(...)                  soft-finger wrench score under gravity
label_object(mesh, mass=, com=)        object labels (written by mgn.io.grasp_file.write_pj_labels)
shake_scores(...), ShakeScorer         Bullet shake test (physics score), label_object's scorer
calibrate_staircase(grids, checks)     ShakeScorer's object-level staircase-or-full-grid policy
"""

from mgn.pj.labels import PjLabels, label_object
from mgn.pj.physics import (
    ShakeOptions,
    ShakeScorer,
    ShakeScores,
    ShakeTrajectory,
    StaircaseCalibration,
    calibrate_staircase,
    replay_staircase,
    shake_scores,
    shake_trajectory,
)
from mgn.pj.sampler import (
    AntipodalResult,
    AntipodalSampler,
    core_gripper,
    gripper_meshes,
    hand_poses,
    pj_wrench_scores,
)

__all__ = [
    "AntipodalResult",
    "AntipodalSampler",
    "PjLabels",
    "ShakeOptions",
    "ShakeScorer",
    "ShakeScores",
    "ShakeTrajectory",
    "StaircaseCalibration",
    "calibrate_staircase",
    "core_gripper",
    "gripper_meshes",
    "hand_poses",
    "label_object",
    "pj_wrench_scores",
    "replay_staircase",
    "shake_scores",
    "shake_trajectory",
]
