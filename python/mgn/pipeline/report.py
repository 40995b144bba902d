"""What ``mgn generate`` did: :class:`GenerateReport`, the scene results of a run, the time spent
per stage and per part of the scene work (``mgn generate --profile``), and the summary printed
for people (:meth:`GenerateReport.format_summary`) with what to do about failed scenes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mgn.pipeline.scene_task import SceneResult

__all__ = ["STAGES", "GenerateReport", "rough_duration"]

#: The stages of a scene task whose seconds :meth:`GenerateReport.stage_seconds` sums.
STAGES = ("drop", "write", "finalize")


def rough_duration(seconds: float) -> str:
    """``45 s``, ``3 min``, ``1.5 h``: a rough duration for people."""
    if seconds < 90:
        return f"{max(1, round(seconds))} s"
    if seconds < 5400:
        return f"{round(seconds / 60)} min"
    return f"{seconds / 3600:.1f} h"


@dataclass
class GenerateReport:
    """What :func:`mgn.pipeline.runner.generate` did.

    Attributes:
        out_dir: the dataset folder; num_scenes: scenes asked for; seed: dataset seed.
        results: the scene results of this run (ok and failed), by scene index.
        skipped: scenes already complete (``--resume``).
        labels_computed, labels_cached: objects labelled now / read from the cache.
        label_seconds: wall time of the object-label step; wall_seconds: of the whole run.
        object_seconds: wall seconds each object's labels took to compute (objects read from
            the cache are not listed).
        output_bytes: size of the dataset folder at the end.
        not_run: scenes not attempted (stopped by a full disk).
        physics: ``dataset.json`` ``physics_scores`` (see
            :func:`mgn.pipeline.run_record.physics_record`), None when no parallel-jaw labels
            with physics were made.
        no_paralleljaw: objects of the run that got no parallel-jaw labels although they were
            asked for (an open mesh, ``allow_open``), with the reason.
    """

    out_dir: Path
    num_scenes: int
    seed: int
    results: dict[int, SceneResult] = field(default_factory=dict)
    skipped: list[int] = field(default_factory=list)
    labels_computed: int = 0
    labels_cached: int = 0
    label_seconds: float = 0.0
    object_seconds: dict[str, float] = field(default_factory=dict)
    wall_seconds: float = 0.0
    output_bytes: int = 0
    not_run: list[int] = field(default_factory=list)
    selection: dict[str, Any] | None = None
    unmet: dict[int, int] = field(default_factory=dict)
    physics: dict[str, Any] | None = None
    no_paralleljaw: dict[str, str] = field(default_factory=dict)

    @property
    def ok(self) -> list[SceneResult]:
        return [r for _, r in sorted(self.results.items()) if r.ok]

    @property
    def failed(self) -> list[SceneResult]:
        return [r for _, r in sorted(self.results.items()) if not r.ok]

    @property
    def complete(self) -> bool:
        return not self.failed and not self.not_run and not self.unmet

    def stage_seconds(self) -> dict[str, float]:
        """Total seconds per stage over the scenes of this run."""
        return {s: sum(r.times.get(s, 0.0) for r in self.results.values()) for s in STAGES}

    def scene_part_seconds(self) -> dict[str, float]:
        """Seconds per part of the scene work, summed over the scenes of this run: ``drop``,
        the parts of writing a scene (``render``: the render thread's busy time, overlapped
        with the rest; ``object labels``, ``layout``, ``scene grasps``: per-view labels;
        ``write (waiting)``: the file encoders the view loop waited for; ``prepare: ...``)
        and ``finalize``, largest first."""
        total: dict[str, float] = {}
        for r in self.results.values():
            for k, v in r.times.items():
                if k in ("write", "cpu"):
                    continue  # "write" is the sum of its parts; cpu is not a stage
                name = k.removeprefix("write: ")
                total[name] = total.get(name, 0.0) + v
        return dict(sorted(total.items(), key=lambda kv: -kv[1]))

    def profile(self) -> dict[str, Any]:
        """Where the time of the run went, as written by ``mgn generate --profile FILE``:
        wall seconds of the run, of the object-label step (with each computed object's
        seconds) and of the scene parts (:meth:`scene_part_seconds`, summed over scenes and
        workers; ``render`` overlaps the other parts), the scenes' CPU seconds, and scene
        counts."""
        cpu = sum(r.times.get("cpu", 0.0) for r in self.results.values())
        return {
            "wall_s": round(self.wall_seconds, 3),
            "object_labels": {
                "wall_s": round(self.label_seconds, 3),
                "computed": self.labels_computed,
                "cached": self.labels_cached,
                "objects_s": {k: round(v, 3) for k, v in self.object_seconds.items()},
            },
            "scenes": {
                "written": len(self.ok),
                "failed": len(self.failed),
                "skipped": len(self.skipped),
                "parts_s": {k: round(v, 3) for k, v in self.scene_part_seconds().items()},
                "cpu_s": round(cpu, 3),
            },
        }

    def format_summary(self) -> str:
        n_ok = len(self.ok) + len(self.skipped)
        lines = [
            f"dataset {self.out_dir}: {n_ok}/{self.num_scenes} scenes complete "
            f"({len(self.ok)} written now, {len(self.skipped)} already there), "
            f"{len(self.failed)} failed"
            + (f", {len(self.not_run)} not run" if self.not_run else "")
        ]
        lines.append(
            f"  object labels: {self.labels_computed} computed, {self.labels_cached} from the "
            f"cache ({self.label_seconds:.1f} s)"
        )
        if self.object_seconds:
            slow = sorted(self.object_seconds.items(), key=lambda kv: -kv[1])
            shown = ", ".join(f"{n} {v:.1f} s" for n, v in slow[:6])
            more = f", {len(slow) - 6} more" if len(slow) > 6 else ""
            lines.append(f"    per object: {shown}{more}")
        if self.results:
            k = max(len(self.results), 1)
            parts = ", ".join(
                f"{s} {v:.1f} s ({v / k:.2f} s/scene)"
                for s, v in self.scene_part_seconds().items()
                if v >= 0.05
            )
            lines.append(
                f"  where the scene time went (summed over workers; render overlaps the rest): "
                f"{parts}"
            )
        rate = 3600.0 * len(self.ok) / self.wall_seconds if self.wall_seconds > 0 else 0.0
        lines.append(
            f"  wall time {self.wall_seconds:.1f} s ({rate:.0f} scenes/hour); output "
            f"{self.output_bytes / 1e6:.1f} MB"
        )
        lost = [r for r in self.ok if r.removed]
        if lost:
            n_lost = sum(len(r.removed) for r in lost)
            kept = sum(r.num_objects for r in self.ok)
            lines.append(
                f"  {n_lost} objects left the tote and were removed ({kept} kept) in "
                f"{len(lost)} of {len(self.ok)} scenes"
                + (
                    ""
                    if len(lost) > 5
                    else ": " + "; ".join(f"scene{r.index}: {', '.join(r.removed)}" for r in lost)
                )
                + " (objects.refill drops a scene again, at most objects.refill_attempts times, "
                "until its objects stay in; fewer or smaller objects per scene help)"
            )
        if self.physics is not None and self.physics["unscored"]:
            p = self.physics
            lines.append(
                f"  physics scores: {p['scored']} of {p['grasps']} parallel-jaw grasps scored, "
                f"{p['unscored']} left NaN by object_labels.physics_grasps = {p['cap']} "
                "(null scores every grasp)"
            )
        if self.no_paralleljaw:
            lines.append(
                f"  no parallel-jaw labels for {len(self.no_paralleljaw)} object(s): "
                + "; ".join(f"{n}: {why}" for n, why in sorted(self.no_paralleljaw.items()))
            )
        for r in self.failed:
            lines.append(f"  FAILED scene{r.index} (seed {r.seed}): {r.error}")
        if self.not_run:
            lines.append(f"  not run: {', '.join(f'scene{i}' for i in self.not_run)}")
        if self.selection is not None:
            q = self.selection["quota"]
            got = dict.fromkeys(q, 0)
            for e in self.selection["views"]:
                got[str(e["difficulty"])] += 1
            per = ", ".join(f"{k}: {got[k]}/{n}" for k, n in q.items())
            lines.append(
                f"  difficulty selection (level: selected/quota): {per}; "
                f"{len(self.selection['rejected'])} views rejected"
                + (" (files pruned)" if self.selection.get("pruned") else "")
            )
        if self.unmet and not self.failed and not self.not_run:
            short = ", ".join(f"level {k} lacks {n}" for k, n in sorted(self.unmet.items()))
            lines.append(
                f"  DIFFICULTY QUOTA NOT MET after {self.num_scenes} scenes: {short}; rerun "
                "with --resume and a larger --max-scenes to continue"
            )
        elif not self.complete:
            lines.append(self._resume_advice())
        return "\n".join(lines)

    def _resume_advice(self) -> str:
        """What to do about the failed and not-run scenes: ``--resume`` redoes a scene, and
        helps where the failure came from outside (a full disk, a worker that died, memory); a
        scene depends only on its seed and the config, so any other failure comes back."""
        redo = [r.index for r in self.failed if _transient(r)] + list(self.not_run)
        same = [r.index for r in self.failed if not _transient(r)]
        if not same:
            return "  rerun with --resume to redo the missing scenes"
        names = ", ".join(f"scene{i}" for i in same)
        text = (
            f"  {names} failed the way they will fail on every run (a scene depends only on its "
            "seed and the config): fix the cause above first (mgn config check CONFIG checks "
            "the config)"
        )
        if redo:
            text += f"; then --resume also redoes {', '.join(f'scene{i}' for i in sorted(redo))}"
        else:
            text += ", then rerun with --resume"
        return text


def _transient(result: SceneResult) -> bool:
    """A failure that may not come back on a rerun: a full disk, a worker process that died,
    memory."""
    error = result.error or ""
    return result.disk_full or error.startswith("worker failed") or "MemoryError" in error
