"""Compare the three seal models on the same candidates (the paper's Table VI analysis).

Every model scores the same evenly sampled surface points with the same cup. A model *predicts a
seal* when its score is >= ``seal_threshold`` (0.5). A point is *controversial* for the ordered
pair (A, B) when A scores it < 0.2 while B predicts a seal, or A scores it > 0.8 while B predicts
no seal (docs/models.md §2).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from mgn.errors import InvalidArgumentError
from mgn.geometry.mesh import Mesh, sample_surface
from mgn.hardware import SuctionCup
from mgn.suction.seal import FAILURE_REASONS, SealModel
from mgn.viz.pictures import draw_points, panels, score_colors, snapshot

MODELS: tuple[str, ...] = ("spring", "strain", "smoothness")
LOW, HIGH = 0.2, 0.8


@dataclass(frozen=True)
class PairStats:
    """Agreement of model ``a`` with model ``b`` on the same points.

    Attributes:
        agreement: fraction of points where both predict the same outcome (seal / no seal).
        low_vs_seal: points ``a`` scores < 0.2 while ``b`` predicts a seal.
        high_vs_no_seal: points ``a`` scores > 0.8 while ``b`` predicts no seal.
    """

    a: str
    b: str
    agreement: float
    low_vs_seal: int
    high_vs_no_seal: int

    @property
    def controversial(self) -> int:
        return self.low_vs_seal + self.high_vs_no_seal


@dataclass(frozen=True)
class Comparison:
    """Scores of every model on the same candidates.

    Attributes:
        points, normals: (N, 3) candidates on the surface (m, outward normals, object frame).
        scores: model name → (N,) float32 score in [0, 1].
        reasons: model name → (N,) uint8 failure reason (:data:`FAILURE_REASONS`).
        pairs: every ordered pair of models.
        seal_threshold: score at and above which a model predicts a seal.
    """

    points: npt.NDArray[np.float32]
    normals: npt.NDArray[np.float32]
    scores: dict[str, npt.NDArray[np.float32]]
    reasons: dict[str, npt.NDArray[np.uint8]]
    pairs: list[PairStats] = field(default_factory=list)
    seal_threshold: float = 0.5

    def controversial_mask(self) -> npt.NDArray[np.bool_]:
        """Points that are controversial for at least one ordered pair of models."""
        mask = np.zeros(len(self.points), bool)
        for a, b in itertools.permutations(self.scores, 2):
            mask |= _controversial(self.scores[a], self.scores[b], self.seal_threshold)
        return mask

    def format_table(self) -> str:
        """Human-readable agreement and controversial-point table."""
        n = len(self.points)
        lines = [f"{n} candidates; a model predicts a seal at score >= {self.seal_threshold}"]
        lines.append("")
        lines.append(f"{'model':<12}{'seal %':>8}{'mean':>8}   most common failure")
        for m, s in self.scores.items():
            reasons = self.reasons[m][s < self.seal_threshold]
            common = "-"
            if len(reasons):
                vals, counts = np.unique(reasons, return_counts=True)
                k = int(np.argmax(counts))
                common = f"{FAILURE_REASONS[int(vals[k])]} ({counts[k]})"
            seal_pct = 100.0 * float(np.mean(s >= self.seal_threshold))
            lines.append(f"{m:<12}{seal_pct:>8.1f}{float(np.mean(s)):>8.3f}   {common}")
        lines.append("")
        lines.append(
            f"{'A':<12}{'B':<12}{'agree %':>8}{'A<0.2, B seals':>16}{'A>0.8, B fails':>16}"
        )
        for p in self.pairs:
            lines.append(
                f"{p.a:<12}{p.b:<12}{100 * p.agreement:>8.1f}{p.low_vs_seal:>16d}"
                f"{p.high_vs_no_seal:>16d}"
            )
        lines.append("")
        lines.append(f"controversial points (any pair): {int(self.controversial_mask().sum())}")
        return "\n".join(lines)


def _controversial(a: np.ndarray, b: np.ndarray, threshold: float) -> np.ndarray:
    b_seal = b >= threshold
    return ((a < LOW) & b_seal) | ((a > HIGH) & ~b_seal)


def pair_stats(
    a: str, b: str, score_a: np.ndarray, score_b: np.ndarray, threshold: float = 0.5
) -> PairStats:
    """Agreement and controversial counts of model ``a`` against model ``b``."""
    sa, sb = np.asarray(score_a), np.asarray(score_b)
    if sa.shape != sb.shape:
        raise InvalidArgumentError(
            f"pair_stats: score arrays differ in shape {sa.shape} vs {sb.shape}"
        )
    b_seal = sb >= threshold
    agreement = float(np.mean((sa >= threshold) == b_seal)) if sa.size else 1.0
    return PairStats(
        a,
        b,
        agreement,
        int(np.sum((sa < LOW) & b_seal)),
        int(np.sum((sa > HIGH) & ~b_seal)),
    )


def compare_models(
    mesh: Mesh,
    *,
    cup: SuctionCup | None = None,
    models: tuple[str, ...] = MODELS,
    num_points: int = 1000,
    seed: int = 0,
    num_threads: int = 0,
    seal_threshold: float = 0.5,
) -> Comparison:
    """Score ``num_points`` evenly sampled surface points of ``mesh`` (m) with every model.

    All models see the same points, the same cup and the same random stream (seed, point index)
    for their trial perturbations, so differences come from the models alone.
    """
    if not 0.0 < seal_threshold <= 1.0:
        raise InvalidArgumentError(
            f"seal_threshold: expected a value in (0, 1], got {seal_threshold}"
        )
    if len(models) < 2:
        raise InvalidArgumentError(
            f"models: expected at least two models to compare, got {models!r}"
        )
    cup = cup if cup is not None else SuctionCup()
    samples = sample_surface(mesh, num_points, method="even", seed=seed)
    scores: dict[str, np.ndarray] = {}
    reasons: dict[str, np.ndarray] = {}
    for m in models:
        res = SealModel(mesh, cup, m).evaluate(  # type: ignore[arg-type]
            samples.points, samples.normals, seed=seed, num_threads=num_threads
        )
        scores[m], reasons[m] = res.score, res.reason
    pairs = [
        pair_stats(a, b, scores[a], scores[b], seal_threshold)
        for a, b in itertools.permutations(models, 2)
    ]
    return Comparison(samples.points, samples.normals, scores, reasons, pairs, seal_threshold)


def comparison_picture(mesh: Mesh, comparison: Comparison, *, size: int = 360) -> np.ndarray:
    """(H, W, 3) uint8: the object once per model, points coloured red (0) → green (1) by score,
    plus a last panel marking the controversial points in magenta."""

    snap = snapshot(mesh, size=size)
    imgs, titles = [], []
    for m, s in comparison.scores.items():
        imgs.append(draw_points(snap, comparison.points, score_colors(s)))
        titles.append(f"{m}: seal {100 * np.mean(s >= comparison.seal_threshold):.0f}%")
    mask = comparison.controversial_mask()
    colors = np.where(mask[:, None], [[220, 0, 220]], [[150, 150, 150]]).astype(np.uint8)
    imgs.append(draw_points(snap, comparison.points, colors))
    titles.append(f"controversial: {int(mask.sum())}")
    return panels(imgs, titles, footer="score: red 0 - yellow 0.5 - green 1")
