"""Suction-cup calibration: print a board, try the poses on a robot, fit the seal constants.

make_calibration_board()            board mesh (m) + graded features with the poses to try
write_calibration_board(out_dir)    board.stl (mm), poses.csv, results_template.csv, README
calibrate_from_csv(results_csv)     fit c1, c2 to measured outcomes (docs/models.md)
"""

from mgn.calibration.board import make_calibration_board, write_calibration_board
from mgn.calibration.fit import CalibrationReport, calibrate_from_csv

__all__ = [
    "CalibrationReport",
    "calibrate_from_csv",
    "make_calibration_board",
    "write_calibration_board",
]
