"""Suction grasps: seal models, object suction labels, the calibration board and the fit.

SealModel(mesh, cup, model)         seal score of candidates (spring, strain, smoothness)
suction_wrench_scores(...)          wrench resistance under gravity
label_object(mesh, mass=, com=)     object labels; write_suction_labels(hdf5, labels)

make_calibration_board()            board mesh (m) + graded features with the poses to try
write_calibration_board(out_dir)    board.stl (mm), poses.csv, results_template.csv, README
calibrate_from_csv(results_csv)     fit c1, c2 to measured outcomes (docs/models.md §4)
"""

from mgn.suction.board import make_calibration_board, write_calibration_board
from mgn.suction.calibrate import CalibrationReport, calibrate_from_csv
from mgn.suction.labels import SuctionLabels, label_object, write_suction_labels
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
    "write_suction_labels",
    "CalibrationReport",
    "calibrate_from_csv",
    "make_calibration_board",
    "write_calibration_board",
]
