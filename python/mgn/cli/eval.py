"""``mgn eval ...``: score predictions against a dataset's labels.

The ``eval`` command group: ``detections`` (:mod:`mgn.eval.detections`), ``layout``
(:mod:`mgn.eval.layout_metrics`), ``grasps`` (:mod:`mgn.eval.grasps`) and ``real`` (a trained
model on labelled photographs, :mod:`mgn.learn.real_eval`). The evaluation itself
lives in :mod:`mgn.eval`; this module only parses the arguments and prints or writes the results.
"""

from __future__ import annotations

import argparse
import math

from mgn.cli.args import (
    add_device_arguments,
    add_instance_threshold_arguments,
    add_quiet_argument,
    add_tta_argument,
    device_kwargs,
    grasp_kind_arg,
    instance_threshold_kwargs,
)
from mgn.eval import grasps as grasps_module
from mgn.eval.detections import evaluate_detections
from mgn.eval.grasps import (
    DEFAULT_KS,
    DEFAULT_MATCH_ANGLE,
    DEFAULT_MATCH_DISTANCE,
    DEFAULT_THRESHOLDS,
    LABEL_SCORES,
    evaluate_grasps,
)
from mgn.eval.layout_metrics import evaluate_layout
from mgn.eval.results import print_and_write
from mgn.io.real import REAL_FORMATS
from mgn.learn.real_eval import DEFAULT_KS as REAL_KS
from mgn.learn.real_eval import evaluate_real

__all__ = ["register"]

grasps_module_doc = grasps_module.__doc__ or ""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``eval`` command group to the ``mgn`` subparsers."""
    p = sub.add_parser("eval", help="score predictions against a dataset's labels")
    eval_sub = p.add_subparsers(dest="eval_command", metavar="ACTION", required=True)
    _register_detections(eval_sub)
    _register_layout(eval_sub)
    _register_grasps(eval_sub)
    _register_real(eval_sub)


def _cmd_detections(args: argparse.Namespace) -> int:
    res = evaluate_detections(
        args.dataset,
        args.predictions,
        class_agnostic=args.class_agnostic,
        amodal=args.amodal,
        strict=not args.lenient,
    )
    return print_and_write(res, args.out)


def _register_detections(eval_sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``detections`` to the ``mgn eval`` actions."""
    p = eval_sub.add_parser(
        "detections", help="box / mask AP of COCO-format predictions (overall and by subset)"
    )
    p.add_argument("predictions", help="COCO results JSON (list of detections)")
    p.add_argument("--dataset", required=True, help="dataset folder")
    p.add_argument("--class-agnostic", action="store_true", help="one category 'object'")
    p.add_argument("--amodal", action="store_true", help="score against the amodal masks/boxes")
    p.add_argument(
        "--lenient", action="store_true", help="drop predictions for images not evaluated"
    )
    p.add_argument("--out", help="write the results as JSON here")
    p.set_defaults(func=_cmd_detections)


def _cmd_layout(args: argparse.Namespace) -> int:
    res = evaluate_layout(args.dataset, args.predictions)
    return print_and_write(res, args.out)


def _register_layout(eval_sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``layout`` to the ``mgn eval`` actions."""
    p = eval_sub.add_parser("layout", help="layer accuracy and top-object scores of predictions")
    p.add_argument("predictions", help="JSON list of {image_id, instance_id, layer}")
    p.add_argument("--dataset", required=True, help="dataset folder")
    p.add_argument("--out", help="write the results as JSON here")
    p.set_defaults(func=_cmd_layout)


def _cmd_grasps(args: argparse.Namespace) -> int:
    res = evaluate_grasps(
        args.dataset,
        args.predictions,
        kind=args.kind,
        ks=args.k,
        thresholds=args.thresholds,
        match_distance=args.match_distance,
        match_angle=math.radians(args.match_angle_deg),
        label_score=args.label_score,
        num_threads=args.threads,
    )
    return print_and_write(res, args.out)


def _register_grasps(eval_sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``grasps`` to the ``mgn eval`` subparsers."""
    p = eval_sub.add_parser(
        "grasps",
        help="precision@k of suction / parallel-jaw grasp predictions",
        description=grasps_module_doc.split("\n\n")[0].replace("``", ""),
    )
    p.add_argument("predictions", metavar="PRED.json", help="prediction list (see the docs)")
    p.add_argument("--dataset", required=True, metavar="DIR", help="dataset folder")

    p.add_argument(
        "--kind",
        type=grasp_kind_arg,
        default="suction",
        help="grasp kind: suction or paralleljaw (default suction; aliases suctioncup, pj)",
    )
    p.add_argument("--out", metavar="JSON", help="write the results here")
    p.add_argument(
        "--k",
        type=int,
        nargs="+",
        default=list(DEFAULT_KS),
        metavar="K",
        help="k of precision@k (default 1 5 10 25 50)",
    )
    p.add_argument(
        "--thresholds",
        type=float,
        nargs="+",
        default=list(DEFAULT_THRESHOLDS),
        metavar="T",
        help="label-score thresholds (default 0.2 ... 0.8)",
    )
    p.add_argument(
        "--match-distance",
        type=float,
        default=DEFAULT_MATCH_DISTANCE,
        metavar="M",
        help="contact tolerance, m (default 0.01)",
    )
    p.add_argument(
        "--match-angle-deg",
        type=float,
        default=math.degrees(DEFAULT_MATCH_ANGLE),
        metavar="DEG",
        help="axis tolerance, degrees (default 30)",
    )
    p.add_argument(
        "--label-score",
        choices=LABEL_SCORES,
        default=None,
        help="label score held against the thresholds (default analytical)",
    )
    p.add_argument(
        "--num-threads",
        "--threads",
        dest="threads",
        type=int,
        default=0,
        help="C++ threads (0 = all cores)",
    )
    p.set_defaults(func=_cmd_grasps)


def _cmd_real(args: argparse.Namespace) -> int:
    res = evaluate_real(
        args.model,
        args.real,
        args.out,
        fmt=args.format,
        amodal=args.amodal,
        ks=args.k,
        tta=args.tta,
        **instance_threshold_kwargs(args),
        **device_kwargs(args),
    )
    print(res.table())
    if args.out:
        print(f"wrote {args.out}/results.json, report.html, overlays/")
    return 0


def _register_real(eval_sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``real`` to the ``mgn eval`` actions."""
    p = eval_sub.add_parser(
        "real",
        help="a trained model (mgn train) on labelled real photographs: mask AP, foreground "
        "IoU, suction precision@k, report (needs mgn[learn])",
    )
    p.add_argument(
        "real",
        help="MetaGraspNet real layout (dataset_real/ or one scene folder) or a COCO folder "
        "(images + one instances JSON, or the JSON)",
    )
    p.add_argument("--model", required=True, help="model.pt of mgn train")
    p.add_argument("--out", help="write results.json, report.html and overlays/ here")
    p.add_argument(
        "--format", choices=("auto", *REAL_FORMATS), default="auto", help="layout of REAL"
    )
    p.add_argument("--amodal", action="store_true", help="score amodal masks (amodal model)")
    p.add_argument(
        "--k",
        type=int,
        nargs="+",
        default=list(REAL_KS),
        metavar="K",
        help="k of suction precision@k (default 1 5 10)",
    )
    add_instance_threshold_arguments(p)
    add_tta_argument(p)
    add_device_arguments(p)
    add_quiet_argument(p)
    p.set_defaults(func=_cmd_real)
