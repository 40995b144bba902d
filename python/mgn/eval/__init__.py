"""Evaluation: test-set builders, detection / grasp / layout metrics and closed-loop picking.

Every metric reads a dataset written by ``mgn generate`` (or an original MetaGraspNet download)
through :class:`mgn.Dataset`, scores predictions against its labels and returns a frozen result
object with ``to_dict()`` (JSON) and ``table()`` (the printed table, see
:func:`mgn.eval.results.format_table`). The command line is ``mgn eval ...`` and ``mgn pick``.
"""

from __future__ import annotations

from mgn.eval.detections import (
    DetectionResults,
    DetectionRow,
    evaluate_detections,
    ground_truth_detections,
)
from mgn.eval.grasps import GraspResults, evaluate_grasps, ground_truth_grasps
from mgn.eval.layout_metrics import LayoutResults, evaluate_layout, ground_truth_layout
from mgn.eval.pick import PickAttempt, PickResults, PickState, run_picking

__all__ = [
    "DetectionResults",
    "DetectionRow",
    "GraspResults",
    "LayoutResults",
    "PickAttempt",
    "PickResults",
    "PickState",
    "evaluate_detections",
    "evaluate_grasps",
    "evaluate_layout",
    "ground_truth_detections",
    "ground_truth_grasps",
    "ground_truth_layout",
    "run_picking",
]
