"""Fit the suction cup constants c1, c2 of the spring seal model to measured outcomes.

The workflow (docs/models.md §4)::

    mgn suction board OUT/            # print OUT/board.stl, try the poses of OUT/poses.csv
    mgn suction calibrate results.csv # fit c1, c2 and print the metrics table

The fit itself is C++ (``mgn::calibrate_cup``): NLopt GN_DIRECT_L over (ln c1, ln c2) in a box,
then LN_BOBYQA from the best point, maximising the training accuracy of the nominal (one
deterministic, unperturbed trial) spring-model prediction. Among equally accurate constants the
ones closest to the initial cup's (in log space) win. Metrics are reported on a stratified
held-out split; a rate whose denominator is zero is NaN (printed as ``n/a``).
"""

from __future__ import annotations

import csv
import dataclasses
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.calibration.board import board_poses, make_calibration_board
from mgn.errors import InvalidArgumentError, IoError
from mgn.geometry.mesh import Mesh, load_mesh
from mgn.hardware import SuctionCup
from mgn.suction.seal import core_cup

__all__ = [
    "BoardPoses",
    "CalibrationReport",
    "MeasuredResults",
    "calibrate",
    "calibrate_from_csv",
    "classification_metrics",
    "predict_seals",
    "read_poses_csv",
    "read_results_csv",
]

_METRICS = ("accuracy", "ppv", "npv", "sensitivity", "specificity")
_METRIC_LABELS = {
    "accuracy": "accuracy",
    "ppv": "PPV (precision)",
    "npv": "NPV",
    "sensitivity": "sensitivity (TPR)",
    "specificity": "specificity (TNR)",
}


@dataclass(frozen=True)
class CalibrationReport:
    """Result of a calibration.

    Attributes:
        cup: the initial cup with the fitted ``c1`` and ``c2``.
        initial_cup: the cup the fit started from.
        train: metrics of the fitted cup on the training split: ``tp``, ``fp``, ``tn``, ``fn``
            (int) and ``accuracy``, ``ppv``, ``npv``, ``sensitivity``, ``specificity`` (float,
            NaN when the denominator is zero).
        test: the same on the held-out split.
        initial_train: metrics of the initial cup on the training split.
        initial_test: metrics of the initial cup on the held-out split.
        objective: training accuracy of the fitted cup (the maximised quantity).
        evaluations: objective evaluations of the search.
        train_indices: (T,) int64 experiment indices of the training split.
        test_indices: (H,) int64 experiment indices of the held-out split.
        predicted: (N,) bool nominal prediction of the fitted cup per experiment.
        measured: (N,) bool measured outcome per experiment.
        pose_ids: pose id per experiment when the experiments came from a board, else None.
        features: feature name per experiment when known, else None.
        seed: seed of the split.
    """

    cup: SuctionCup
    initial_cup: SuctionCup
    train: dict[str, float]
    test: dict[str, float]
    initial_train: dict[str, float]
    initial_test: dict[str, float]
    objective: float
    evaluations: int
    train_indices: npt.NDArray[np.int64]
    test_indices: npt.NDArray[np.int64]
    predicted: npt.NDArray[np.bool_]
    measured: npt.NDArray[np.bool_]
    pose_ids: tuple[int, ...] | None = None
    features: tuple[str, ...] | None = None
    seed: int = 0

    def format_report(self) -> str:
        """The human-readable summary printed by ``mgn suction calibrate``."""

        def num(v: float, fmt: str = ".3f") -> str:
            return "n/a" if isinstance(v, float) and math.isnan(v) else format(v, fmt)

        n = len(self.measured)
        lines = [
            "Suction cup calibration (spring seal model, nominal trial; docs/models.md §4)",
            f"experiments: {n} ({int(self.measured.sum())} sealed), "
            f"train {len(self.train_indices)} / held-out {len(self.test_indices)} "
            f"(stratified, seed {self.seed}); {self.evaluations} objective evaluations",
            "",
            f"{'cup constant':<20}{'initial':>12}{'fitted':>12}",
            f"{'c1':<20}{self.initial_cup.c1:>12.5g}{self.cup.c1:>12.5g}",
            f"{'c2':<20}{self.initial_cup.c2:>12.5g}{self.cup.c2:>12.5g}",
            "",
            f"{'metric':<20}{'train':>10}{'held-out':>10}{'initial, held-out':>19}",
        ]
        for key in _METRICS:
            lines.append(
                f"{_METRIC_LABELS[key]:<20}{num(self.train[key]):>10}{num(self.test[key]):>10}"
                f"{num(self.initial_test[key]):>19}"
            )
        for label, m in (("train", self.train), ("held-out", self.test)):
            lines.append(
                f"{'TP/FP/TN/FN ' + label:<20}{m['tp']:>6}{m['fp']:>6}{m['tn']:>6}{m['fn']:>6}"
            )
        if self.features is not None:
            lines += ["", f"{'feature kind':<20}{'n':>5}{'sealed':>8}{'predicted':>11}{'agree':>8}"]
            kinds: dict[str, list[int]] = {}
            for i, name in enumerate(self.features):
                kinds.setdefault(_kind_of(name), []).append(i)
            for kind, idx in kinds.items():
                sel = np.asarray(idx)
                agree = float(np.mean(self.predicted[sel] == self.measured[sel]))
                lines.append(
                    f"{kind:<20}{len(sel):>5}{int(self.measured[sel].sum()):>8}"
                    f"{int(self.predicted[sel].sum()):>11}{agree:>8.2f}"
                )
        lines += ["", "NaN rates (n/a): the denominator is zero on that split."]
        return "\n".join(lines) + "\n"


def _kind_of(feature: str) -> str:
    """Feature kind from a board feature name: the words before the first one with a digit
    (step_04mm -> step, convex_cylinder_r10mm -> convex_cylinder, tilt_y_10deg -> tilt_y)."""
    words = []
    for w in feature.split("_"):
        if any(ch.isdigit() for ch in w):
            break
        words.append(w)
    return "_".join(words) or feature


def _core_cup(cup: SuctionCup) -> _core.grasp.Cup:
    if not isinstance(cup, SuctionCup):
        raise InvalidArgumentError(
            f"cup: expected a mgn.hardware.SuctionCup, got {type(cup).__name__}"
        )
    return core_cup(cup)


def _metrics(m: _core.grasp.ClassificationMetrics) -> dict[str, float]:
    """The JSON form of the core's metrics: counts as int, rates as float."""
    d = m.to_dict()
    return {k: (int(v) if k in ("tp", "fp", "tn", "fn") else float(v)) for k, v in d.items()}


def classification_metrics(predicted: npt.ArrayLike, measured: npt.ArrayLike) -> dict[str, float]:
    """Confusion counts and PPV, NPV, sensitivity, specificity, accuracy ("positive" = sealed).

    A rate whose denominator is zero is NaN.
    """
    p = np.asarray(predicted, dtype=bool).ravel()
    y = np.asarray(measured, dtype=bool).ravel()
    return _metrics(_core.grasp.classification_metrics(p.tolist(), y.tolist()))


def _experiment_arrays(
    surfaces: Mesh | Sequence[Mesh],
    surface_index: npt.ArrayLike | None,
    points: npt.ArrayLike,
    normals: npt.ArrayLike,
) -> tuple[list[Mesh], npt.NDArray[np.int64], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    mesh_list = [surfaces] if isinstance(surfaces, Mesh) else list(surfaces)
    pts = np.ascontiguousarray(points, dtype=np.float64)
    nrm = np.ascontiguousarray(normals, dtype=np.float64)
    idx = (
        np.zeros(len(pts), dtype=np.int64)
        if surface_index is None
        else np.ascontiguousarray(surface_index, dtype=np.int64)
    )
    return mesh_list, idx, pts, nrm


def predict_seals(
    surfaces: Mesh | Sequence[Mesh],
    points: npt.ArrayLike,
    normals: npt.ArrayLike,
    cup: SuctionCup | None = None,
    *,
    surface_index: npt.ArrayLike | None = None,
    num_threads: int = 0,
) -> npt.NDArray[np.bool_]:
    """Nominal spring-model prediction (one deterministic trial, no perturbation) per pose.

    Args:
        surfaces: one mesh or several (metres).
        points: (N, 3) contact points on the surfaces, m.
        normals: (N, 3) outward normals (the cup approaches along -normal).
        cup: the cup (default: :class:`SuctionCup` defaults).
        surface_index: (N,) index of the surface of each pose (default: all on surface 0).
        num_threads: 0 = all hardware threads.

    Returns:
        (N,) bool, True where the model predicts a seal.
    """
    meshes, idx, pts, nrm = _experiment_arrays(surfaces, surface_index, points, normals)
    c = _core_cup(cup if cup is not None else SuctionCup())
    return _core.grasp.predict_experiments(meshes, idx, pts, nrm, c, int(num_threads))


def calibrate(
    surfaces: Mesh | Sequence[Mesh],
    points: npt.ArrayLike,
    normals: npt.ArrayLike,
    sealed: npt.ArrayLike,
    cup: SuctionCup | None = None,
    *,
    surface_index: npt.ArrayLike | None = None,
    c1_range: tuple[float, float] = (1e-3, 1.0),
    c2_range: tuple[float, float] = (1e-3, 1.0),
    global_evaluations: int = 200,
    local_evaluations: int = 100,
    holdout_fraction: float = 0.3,
    seed: int = 0,
    num_threads: int = 0,
    pose_ids: Sequence[int] | None = None,
    features: Sequence[str] | None = None,
) -> CalibrationReport:
    """Fit ``c1`` and ``c2`` of ``cup`` to measured outcomes (see the module docstring).

    Args:
        surfaces: one mesh or several (metres).
        points: (N, 3) contact points of the attempts on their surfaces, m.
        normals: (N, 3) outward surface normals (the cup approached along -normal).
        sealed: (N,) measured outcomes, bool or 0/1.
        cup: the starting cup (default: :class:`SuctionCup` defaults); every other field is kept.
        surface_index: (N,) surface of each attempt (default: all on surface 0).
        c1_range: search interval of c1, 0 < min < max.
        c2_range: search interval of c2, 0 < min < max.
        global_evaluations: budget of the global search (GN_DIRECT_L), >= 1.
        local_evaluations: budget of the local polish (LN_BOBYQA), >= 0.
        holdout_fraction: share of each outcome class held out for the test metrics, [0, 0.9].
        seed: seed of the split.
        num_threads: seal evaluation threads, 0 = all.
        pose_ids: optional pose id per attempt (kept in the report).
        features: optional feature name per attempt (per-kind table in the report).

    Raises:
        InvalidArgumentError: bad shapes or values, naming the argument (or the experiment).
        BackendError: the optimiser failed.
    """
    initial = cup if cup is not None else SuctionCup()
    meshes, idx, pts, nrm = _experiment_arrays(surfaces, surface_index, points, normals)
    y = np.asarray(sealed)
    if y.dtype != bool and not np.all(np.isin(y, (0, 1))):
        raise InvalidArgumentError("sealed: expected booleans or 0/1 values")
    y = y.astype(bool).ravel()
    out = _core.grasp.calibrate_cup(
        meshes,
        idx,
        pts,
        nrm,
        y.astype(np.int64),
        _core_cup(initial),
        c1_min=float(c1_range[0]),
        c1_max=float(c1_range[1]),
        c2_min=float(c2_range[0]),
        c2_max=float(c2_range[1]),
        global_evaluations=int(global_evaluations),
        local_evaluations=int(local_evaluations),
        holdout_fraction=float(holdout_fraction),
        seed=int(seed),
        num_threads=int(num_threads),
    )
    fitted = dataclasses.replace(initial, c1=float(out.cup.c1), c2=float(out.cup.c2))
    train_idx = np.asarray(out.train_indices, dtype=np.int64)
    test_idx = np.asarray(out.test_indices, dtype=np.int64)
    before = _core.grasp.predict_experiments(
        meshes, idx, pts, nrm, _core_cup(initial), int(num_threads)
    )
    return CalibrationReport(
        cup=fitted,
        initial_cup=initial,
        train=_metrics(out.train),
        test=_metrics(out.test),
        initial_train=classification_metrics(before[train_idx], y[train_idx]),
        initial_test=classification_metrics(before[test_idx], y[test_idx]),
        objective=float(out.objective),
        evaluations=int(out.evaluations),
        train_indices=train_idx,
        test_indices=test_idx,
        predicted=np.asarray(out.predicted, dtype=bool),
        measured=y,
        pose_ids=None if pose_ids is None else tuple(int(p) for p in pose_ids),
        features=None if features is None else tuple(str(f) for f in features),
        seed=int(seed),
    )


# ----------------------------------------------------------------------------------------------
# CSV files of the board workflow
# ----------------------------------------------------------------------------------------------

_POSE_COLUMNS = ("pose_id", "feature", "parameter_m", "x_m", "y_m", "z_m", "nx", "ny", "nz")


@dataclass(frozen=True)
class BoardPoses:
    """The poses of a board (``poses.csv``), in file order.

    Attributes:
        pose_ids: (P,) int64.
        features: feature name per pose.
        parameters: (P,) float64 graded parameter of the pose's feature, m.
        points: (P, 3) float64 contact points, m.
        normals: (P, 3) float64 unit outward normals.
    """

    pose_ids: npt.NDArray[np.int64]
    features: tuple[str, ...]
    parameters: npt.NDArray[np.float64]
    points: npt.NDArray[np.float64]
    normals: npt.NDArray[np.float64]

    def index_of(self) -> dict[int, int]:
        """pose id -> row."""
        return {int(p): i for i, p in enumerate(self.pose_ids)}


@dataclass(frozen=True)
class MeasuredResults:
    """Rows of a results CSV that hold an outcome (blank ``sealed`` rows are skipped).

    Attributes:
        pose_ids: (N,) int64, a pose may repeat (repeated attempts).
        sealed: (N,) bool.
        tear_off_force: (N,) float64 newtons, NaN where not given.
        rows: (N,) int64 line number of each row in the file (header = 1).
    """

    pose_ids: npt.NDArray[np.int64]
    sealed: npt.NDArray[np.bool_]
    tear_off_force: npt.NDArray[np.float64]
    rows: npt.NDArray[np.int64]


def _open_csv(
    path: str | os.PathLike[str], required: Sequence[str], what: str
) -> tuple[list[str], list[tuple[int, dict[str, Any]]]]:
    """(header, rows with line numbers) of a CSV file; checks the required columns."""
    try:
        with Path(path).open(newline="", encoding="utf-8-sig") as fh:
            reader = csv.DictReader(fh)
            header = [h.strip() for h in (reader.fieldnames or [])]
            reader.fieldnames = header
            rows = [(reader.line_num, row) for row in reader]
    except FileNotFoundError as e:
        raise IoError(f"{what}: file not found: '{os.fspath(path)}'") from e
    except (OSError, csv.Error, UnicodeDecodeError) as e:
        raise IoError(f"{what}: cannot read '{os.fspath(path)}': {e}") from e
    missing = [c for c in required if c not in header]
    if missing:
        raise InvalidArgumentError(
            f"{what}: '{os.fspath(path)}' is missing column(s) {missing}; "
            f"expected columns {list(required)}, got {header}"
        )
    return header, rows


def _blank(row: dict[str, Any]) -> bool:
    return all((v or "").strip() == "" for k, v in row.items() if k is not None)


def read_poses_csv(path: str | os.PathLike[str]) -> BoardPoses:
    """Read a board's ``poses.csv`` (see :func:`mgn.calibration.write_calibration_board`).

    Raises:
        IoError: the file cannot be read.
        InvalidArgumentError: a missing column, a bad number or a repeated pose id (naming the row).
    """
    name = os.fspath(path)
    _, rows = _open_csv(path, _POSE_COLUMNS, "poses.csv")
    ids, feats, params, pts, nrm, seen = [], [], [], [], [], set()
    for line, row in rows:
        if _blank(row):
            continue
        try:
            pid = int(row["pose_id"])
            vals = [float(row[c]) for c in ("parameter_m", "x_m", "y_m", "z_m", "nx", "ny", "nz")]
        except (TypeError, ValueError) as e:
            raise InvalidArgumentError(f"{name}, row {line}: bad number ({e})") from e
        if not all(math.isfinite(v) for v in vals):
            raise InvalidArgumentError(f"{name}, row {line}: non-finite value")
        if pid in seen:
            raise InvalidArgumentError(f"{name}, row {line}: pose_id {pid} appears twice")
        seen.add(pid)
        ids.append(pid)
        feats.append((row["feature"] or "").strip())
        params.append(vals[0])
        pts.append(vals[1:4])
        nrm.append(vals[4:7])
    if not ids:
        raise InvalidArgumentError(f"{name}: no poses")
    return BoardPoses(
        np.asarray(ids, dtype=np.int64),
        tuple(feats),
        np.asarray(params, dtype=np.float64),
        np.asarray(pts, dtype=np.float64),
        np.asarray(nrm, dtype=np.float64),
    )


def read_results_csv(
    path: str | os.PathLike[str], known_pose_ids: Sequence[int] | None = None
) -> MeasuredResults:
    """Read measured outcomes (columns ``pose_id``, ``sealed``, optional ``tear_off_force_N``).

    ``sealed`` must be 0 or 1; rows with a blank ``sealed`` (poses not tried) are skipped, and so
    are empty rows. A pose may appear in several rows (repeated attempts).

    Raises:
        IoError: the file cannot be read.
        InvalidArgumentError: a missing column, a pose id that is not an integer or not in
            ``known_pose_ids``, an outcome other than 0/1, a bad force, or no outcome at all
            (each naming the file and the row).
    """
    name = os.fspath(path)
    header, rows = _open_csv(path, ("pose_id", "sealed"), "results CSV")
    has_force = "tear_off_force_N" in header
    known = None if known_pose_ids is None else {int(p) for p in known_pose_ids}
    ids, sealed, force, lines = [], [], [], []
    for line, row in rows:
        if _blank(row):
            continue
        raw_id = (row.get("pose_id") or "").strip()
        try:
            pid = int(raw_id)
        except ValueError as e:
            raise InvalidArgumentError(
                f"{name}, row {line}: pose_id must be an integer, got {raw_id!r}"
            ) from e
        if known is not None and pid not in known:
            raise InvalidArgumentError(
                f"{name}, row {line}: pose_id {pid} is not in poses.csv "
                f"(known ids {min(known)}..{max(known)})"
            )
        raw = (row.get("sealed") or "").strip()
        if raw == "":
            continue  # not tried
        if raw not in ("0", "1"):
            raise InvalidArgumentError(
                f"{name}, row {line}: sealed must be 0 or 1 (or blank if not tried), got {raw!r}"
            )
        f = math.nan
        raw_f = (row.get("tear_off_force_N") or "").strip() if has_force else ""
        if raw_f:
            try:
                f = float(raw_f)
            except ValueError:
                raise InvalidArgumentError(
                    f"{name}, row {line}: tear_off_force_N must be a number (newtons), "
                    f"got {raw_f!r}"
                ) from None
            if not math.isfinite(f) or f < 0:
                raise InvalidArgumentError(
                    f"{name}, row {line}: tear_off_force_N must be finite and >= 0, got {raw_f!r}"
                )
        ids.append(pid)
        sealed.append(raw == "1")
        force.append(f)
        lines.append(line)
    if not ids:
        raise InvalidArgumentError(f"{name}: no measured outcomes (every 'sealed' cell is blank)")
    return MeasuredResults(
        np.asarray(ids, dtype=np.int64),
        np.asarray(sealed, dtype=bool),
        np.asarray(force, dtype=np.float64),
        np.asarray(lines, dtype=np.int64),
    )


def _default_board() -> tuple[Mesh, BoardPoses]:

    v, f, feats = make_calibration_board()
    ids, names, params, pts, nrm = board_poses(feats)
    poses = BoardPoses(np.asarray(ids, dtype=np.int64), tuple(names), params, pts, nrm)
    return Mesh(v, f), poses


def calibrate_from_csv(
    results_csv: str | os.PathLike[str],
    board_dir: str | os.PathLike[str] | None = None,
    cup: SuctionCup | None = None,
    seed: int = 0,
    *,
    holdout_fraction: float = 0.3,
    global_evaluations: int = 200,
    local_evaluations: int = 100,
    num_threads: int = 0,
) -> CalibrationReport:
    """Fit c1, c2 to the outcomes measured on the calibration board.

    Args:
        results_csv: the filled-in results (columns ``pose_id``, ``sealed``, optional
            ``tear_off_force_N``; see :func:`read_results_csv`).
        board_dir: folder written by :func:`mgn.calibration.write_calibration_board` (its
            ``poses.csv`` and ``board.stl``, millimetres). None: the folder of ``results_csv`` if
            it holds both files, else the board of this mgn version (built in memory).
        cup: the starting cup (default: :class:`SuctionCup` defaults).
        seed: seed of the held-out split.
        holdout_fraction: share of each outcome class held out, [0, 0.9].
        global_evaluations: budget of the global search (GN_DIRECT_L).
        local_evaluations: budget of the local polish (LN_BOBYQA).
        num_threads: 0 = all hardware threads.

    Raises:
        IoError: a file cannot be read.
        InvalidArgumentError: a bad CSV (naming the row) or bad options.
    """
    if board_dir is None:
        here = Path(results_csv).parent
        if (here / "poses.csv").is_file() and (here / "board.stl").is_file():
            board_dir = here
    if board_dir is None:
        mesh, poses = _default_board()
    else:
        root = Path(board_dir)
        poses = read_poses_csv(root / "poses.csv")
        stl = root / "board.stl"
        if not stl.is_file():
            raise IoError(f"calibrate_from_csv: '{stl}' not found (the board mesh, millimetres)")
        mesh = load_mesh(stl, scale=1e-3)
    results = read_results_csv(results_csv, poses.pose_ids.tolist())
    row_of = poses.index_of()
    sel = np.asarray([row_of[int(p)] for p in results.pose_ids], dtype=np.int64)
    return calibrate(
        mesh,
        poses.points[sel],
        poses.normals[sel],
        results.sealed,
        cup,
        holdout_fraction=holdout_fraction,
        global_evaluations=global_evaluations,
        local_evaluations=local_evaluations,
        seed=seed,
        num_threads=num_threads,
        pose_ids=results.pose_ids.tolist(),
        features=[poses.features[i] for i in sel],
    )
