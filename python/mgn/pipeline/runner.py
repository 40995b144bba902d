"""``mgn generate``: objects, gripper and cup in, a complete dataset out.

Steps:

1. ``dataset.json`` is written (atomically) with the schema version, the mgn version, the full
   config, the seed and the scene count (:mod:`mgn.pipeline.run_record`); it is updated at the
   end.
2. The objects of every scene are chosen up front (:func:`mgn.scene.compose_objects`, seeded by
   the scene seed), so that each distinct object is labelled once
   (:mod:`mgn.pipeline.label_cache`: cached on disk, missing ones computed as tasks of the
   executor) and ``models/<id>/`` is written.
3. Every scene is an independent task (:func:`mgn.pipeline.scene_task.run_scene`): drop the
   objects (:func:`mgn.scene.drop_scene`), then :func:`mgn.pipeline.scene_writer.write_scene`
   into ``DIR/.tmp-scene<N>-<pid>``, then the manifest (:mod:`mgn.io.manifest`), then a rename
   to ``DIR/scene<N>``. A half-written scene therefore only ever exists under a ``.tmp-`` name.
4. With ``output.formats`` naming other layouts (``bop``, ``graspnet``), the scene is then
   exported into ``DIR/bop/`` and ``DIR/graspnet/`` by the worker (:mod:`mgn.pipeline.exports`;
   by this process when the workers do not see ``DIR``, or after the views of a batch are
   selected and pruned), each scene's export built under a temporary name too.

Scene seeds: scene ``i`` (0-based, folder ``scene<i>``) of a dataset with seed ``S`` uses
:func:`scene_seed` ``(S, i)`` = ``numpy.random.SeedSequence([S, i]).generate_state(1,
numpy.uint32)[0] >> 1`` (31 bits): independent of the other scenes, of the executor and of the
number of workers, so the same seed gives byte-identical files.

Test sets (:mod:`mgn.pipeline.testset`, docs/testsets.md): the config's ``split`` section holds
unseen categories out of a ``train`` set (or into every scene of a ``test`` set); with a
``selection.quota`` the scenes are generated in batches steered towards the difficulty levels
still missing, and exactly the asked number of views per level is selected (``dataset.json``
records ``split`` and ``selection``).

Executors (:mod:`mgn.pipeline.executors`): in-process (``workers=1``), a local process pool
(``workers=K``, spawned processes), or a Dask distributed cluster
(``scheduler="tcp://host:8786"``; every worker must see ``DIR`` at the same path and have mgn
installed; see docs/cluster.md).

Failures: a scene that raises is reported with its index, seed and error and does not stop the
others. A full disk is reported as "disk full" with the path, and stops scheduling new scenes.
Ctrl-C stops the run, removes the temporary folders and leaves the complete scenes; ``--resume``
continues (it also removes any ``.tmp-`` folder a killed run left behind, redoes scenes whose
manifest is missing or inconsistent, and writes the exports that complete scenes lack).
``dataset.json`` ``status`` is ``running`` while the run goes on, then ``complete`` (every scene
written), ``incomplete`` (scenes failed or were not run), ``interrupted`` (Ctrl-C) or ``failed`` (an
error stopped the whole run, e.g. a full disk while writing ``models/``; ``error`` says which); only
a killed process leaves ``running``. What the run did is its :class:`GenerateReport`
(:mod:`mgn.pipeline.report`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tqdm import tqdm

from mgn.base.atomic import _io_error, disk_full_error
from mgn.errors import InvalidArgumentError, IoError
from mgn.io.dataset_record import removed_objects, write_dataset_record
from mgn.io.manifest import check_manifest
from mgn.objects import ObjectSpec
from mgn.pipeline.config import Config, ConfigError, load_config
from mgn.pipeline.executors import Executor, make_executor
from mgn.pipeline.exports import export_models, export_scene, missing_exports
from mgn.pipeline.label_cache import (
    ObjectLabels,
    compute_object_labels,
    estimate_label_seconds,
    load_cached_labels,
    save_cached_labels,
    write_models,
)
from mgn.pipeline.report import GenerateReport, rough_duration
from mgn.pipeline.run_record import check_resume, clean_tmp, dataset_doc, physics_record
from mgn.pipeline.sanity import config_errors, load_catalogue
from mgn.pipeline.scene_task import (
    SceneResult,
    SceneTask,
    folder_size,
    run_scene,
    store_collected,
)
from mgn.pipeline.seeds import scene_seed
from mgn.pipeline.testset import compose_scene, resolve_split, run_balanced
from mgn.scene.scene import BUILTIN

__all__ = ["generate"]


def _label_task(
    args: tuple[ObjectSpec, Config, int, bool | None],
) -> tuple[ObjectLabels, float]:
    """The labels of one object and the wall seconds they took (in the worker)."""

    spec, config, num_threads, progress = args
    t0 = time.perf_counter()
    labels = compute_object_labels(spec, config, num_threads, progress)
    return labels, time.perf_counter() - t0


@dataclass
class _Run:
    """What the scene loop of :func:`generate` needs; the test-set builder drives it as a
    :class:`mgn.pipeline.testset.BalancedRun`."""

    out: Path
    cfg: Config
    seed: int
    executor: Executor
    report: GenerateReport
    sources: dict[str, str]
    use_cache: bool
    progress: bool
    resume: bool
    extra: dict[str, Any] = field(default_factory=dict)  # dataset.json keys (split, selection)
    labels: dict[str, ObjectLabels] = field(default_factory=dict)
    modelled: set[str] = field(default_factory=set)
    collect: bool = False  # workers return the scene files; this process writes them
    # The exports wait until the views of a batch are selected and pruned (a test set with
    # selection.prune_rejected): run_balanced calls export_missing then.
    defer_exports: bool = False

    def ensure_labels(self, specs: Sequence[ObjectSpec]) -> None:
        """Read or compute the labels of the objects not labelled yet in this run and write
        their ``models/<id>/`` folders."""

        t0 = time.perf_counter()
        unique: dict[str, ObjectSpec] = {}
        for s in specs:
            if s.name not in self.modelled:
                unique.setdefault(s.name, s)
        new = sorted(unique.values(), key=lambda s: s.category_id)
        if not new:
            return
        cfg, missing = self.cfg, []
        for spec in new:
            cached = load_cached_labels(spec, cfg) if self.use_cache else None
            if cached is not None:
                self.labels[spec.name] = cached
                self.report.labels_cached += 1
            else:
                missing.append(spec)
        if missing and (cfg.labels.suction or cfg.labels.paralleljaw):
            if self.progress:
                threads = os.cpu_count() or 1  # the workers share the machine's cores
                low, high = estimate_label_seconds(cfg, len(missing), threads)
                print(
                    f"mgn: object labels: {len(missing)} to compute, "
                    f"{self.report.labels_cached} from the cache; roughly "
                    f"{rough_duration(low)}-{rough_duration(high)} on {threads} cores "
                    "(computed once, then cached)",
                    file=sys.stderr,
                )
            bar = tqdm(
                total=len(missing), desc="object labels", unit="obj", disable=not self.progress
            )
            # Per-grasp bars (physics, with an estimate) when progress is shown (None: if stderr
            # is a terminal).
            shown = None if self.progress else False
            items = [(s, cfg, self.executor.threads_per_task, shown) for s in missing]
            for (spec, _, _, _), value, exc in self.executor.run(_label_task, items):
                if exc is not None:
                    raise InvalidArgumentError(
                        f"labelling object '{spec.name}' failed: {type(exc).__name__}: {exc}"
                    ) from exc
                self.labels[spec.name], self.report.object_seconds[spec.name] = value
                if self.use_cache:
                    save_cached_labels(spec, cfg, self.labels[spec.name])
                bar.update(1)
            bar.close()
            self.report.labels_computed += len(missing)
        write_models(self.out, new, self.labels, cfg)
        export_models(self.out, cfg.output.exports)
        self.modelled.update(s.name for s in new)
        self.report.label_seconds += time.perf_counter() - t0

    def run_scenes(self, scenes: Sequence[tuple[int, list[ObjectSpec]]], total: int) -> None:
        """Run the scenes (index, objects) that are not complete yet (``--resume`` keeps the
        complete ones); results go to the report. Stops scheduling on a full disk."""

        report, todo, complete = self.report, [], []
        for i, specs in scenes:
            folder = self.out / f"scene{i}"
            if self.resume and folder.is_dir() and check_manifest(folder) is None:
                report.skipped.append(i)
                complete.append(i)
                continue
            todo.append(
                SceneTask(
                    index=i,
                    seed=scene_seed(self.seed, i),
                    out_dir=os.fspath(self.out),
                    config=self.cfg,
                    objects=tuple((s.name, self.sources.get(s.name, BUILTIN)) for s in specs),
                    labels={s.name: self.labels[s.name] for s in specs if s.name in self.labels},
                    collect=self.collect,
                    exports=() if self.collect or self.defer_exports else self.cfg.output.exports,
                )
            )
        self.export_missing(complete)  # stopped after their scene, before or in their export
        bar = tqdm(
            total=total,
            initial=len(report.skipped) + len(report.results),
            desc="scenes",
            unit="scene",
            disable=not self.progress,
        )
        t_scenes = time.perf_counter()
        n_before = sum(r.ok for r in report.results.values())
        for task, result, exc in self.executor.run(run_scene, todo):
            if exc is not None:  # the task itself could not run (e.g. a worker process died)
                result = SceneResult(
                    task.index, task.seed, False, f"worker failed: {type(exc).__name__}: {exc}"
                )
            elif result.files is not None:
                result = store_collected(self.out, result)
            report.results[task.index] = result
            if result.ok and task.collect and not self.defer_exports:
                self.export_missing([task.index])
            bar.update(1)
            elapsed = time.perf_counter() - t_scenes
            done = sum(r.ok for r in report.results.values()) - n_before
            bar.set_postfix(
                {
                    "scenes/h": f"{3600 * done / max(elapsed, 1e-9):.0f}",
                    "failed": len(report.failed),
                }
            )
            if result.disk_full:
                self.executor.cancel()
                break
        bar.close()
        report.not_run += sorted(t.index for t in todo if t.index not in report.results)

    def export_missing(self, indices: Sequence[int]) -> None:
        """Write the exports (``output.formats``) that the complete scenes ``indices`` lack, in
        this process; a failure marks the scene failed in the report (``--resume`` redoes the
        export). Stops at a full disk."""
        formats = self.cfg.output.exports
        if not formats:
            return
        for i in indices:
            if not (self.out / f"scene{i}").is_dir() or not missing_exports(self.out, i, formats):
                continue
            try:
                times = export_scene(self.out, i, formats, self.cfg.gripper)
            except Exception as e:
                full = disk_full_error(e)
                old = self.report.results.get(i)
                self.report.results[i] = SceneResult(
                    i,
                    scene_seed(self.seed, i),
                    False,
                    f"disk full while exporting scene{i}"
                    if full is not None
                    else f"export of scene{i}: {type(e).__name__}: {e}",
                    full is not None,
                    dict(old.times) if old else {},
                )
                if i in self.report.skipped:
                    self.report.skipped.remove(i)
                if full is not None:
                    raise IoError(f"disk full while exporting scene{i}") from e
                continue
            old = self.report.results.get(i)
            if old is not None:
                self.report.results[i] = dataclasses.replace(old, times={**old.times, **times})

    def write_doc(self, num_scenes: int, status: str, **more: Any) -> None:
        write_dataset_record(
            self.out, dataset_doc(self.cfg, self.seed, num_scenes, status, **self.extra, **more)
        )


def _closing_record(run: _Run) -> dict[str, Any]:
    """The entries of ``dataset.json`` written at the end of a run (``removed_objects``,
    ``no_paralleljaw_labels``, ``physics_scores``, ``failed_scenes``); fills the report's
    ``physics`` and ``no_paralleljaw``."""
    report = run.report
    more: dict[str, Any] = {"removed_objects": removed_objects(run.out)}
    report.physics = physics_record(run.cfg, run.labels)
    report.no_paralleljaw = {
        name: str(lab.paralleljaw.metadata["pj_skipped"])
        for name, lab in sorted(run.labels.items())
        if lab.paralleljaw is not None and lab.paralleljaw.metadata.get("pj_skipped")
    }
    if report.no_paralleljaw:
        more["no_paralleljaw_labels"] = report.no_paralleljaw
    if report.physics is not None:
        more["physics_scores"] = report.physics
    failed = [{"scene": r.index, "seed": r.seed, "error": r.error} for r in report.failed]
    if failed:
        more["failed_scenes"] = failed
    return more


def _record_stop(run: _Run, status: str, error: str) -> None:
    """Record in ``dataset.json`` that the run stopped before its end (``status``
    ``interrupted`` or ``failed``, with the ``error``), so that it no longer says ``running``.
    Written after the temporary folders are gone, which frees the space a full disk needs."""
    with contextlib.suppress(OSError):
        run.write_doc(
            run.report.num_scenes, status, error=error, removed_objects=removed_objects(run.out)
        )


def _check_generate_args(cfg: Config, num_scenes: int | None, workers: int, seed: int) -> None:
    """The argument checks of :func:`generate` (before anything is written)."""
    quota = cfg.selection.quota
    if quota is not None:
        if num_scenes is not None:
            raise InvalidArgumentError(
                "generate: --scenes cannot be combined with a difficulty quota (the quotas decide "
                f"the scene count; use --max-scenes), got --scenes {num_scenes!r}"
            )
        if not cfg.labels.layout:
            raise ConfigError(
                "config key 'labels.layout': a difficulty quota needs the layout labels "
                "(the views' difficulty); expected true, got false"
            )
    elif isinstance(num_scenes, bool) or not isinstance(num_scenes, int) or num_scenes < 1:
        raise InvalidArgumentError(
            f"generate: --scenes must be an integer >= 1, got {num_scenes!r}"
        )
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InvalidArgumentError(f"generate: --workers must be an integer >= 1, got {workers!r}")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InvalidArgumentError(f"generate: --seed must be an integer >= 0, got {seed!r}")


def generate(
    out_dir: str | os.PathLike[str],
    num_scenes: int | None = None,
    *,
    config: Config | str | os.PathLike[str] | None = None,
    seed: int = 0,
    objects: Sequence[str] | None = None,
    workers: int = 1,
    resume: bool = False,
    scheduler: str | None = None,
    progress: bool = True,
    use_cache: bool = True,
    collect: bool = False,
) -> GenerateReport:
    """Generate (or, with ``resume``, complete) a dataset of ``num_scenes`` scenes in
    ``out_dir`` (see the module doc), or, when ``config.selection.quota`` is set, a
    difficulty-balanced test set (:mod:`mgn.pipeline.testset`; ``num_scenes`` must then be
    None: the scene count follows from the quotas, at most ``selection.max_scenes``).

    Args:
        config: a :class:`Config`, a YAML path, or None for the MGN defaults. Its ``split``
            section chooses the unseen-object split (``all``, ``train``, ``test``).
        seed: dataset seed; scene i uses :func:`scene_seed` (seed, i).
        objects: object names (repeat for copies) replacing ``config.objects``.
        workers: local worker processes (1 = in this process); ignored with ``scheduler``.
        resume: keep complete scenes, redo the others; the config (but
            ``selection.max_scenes``), split and seed must be those recorded in
            ``dataset.json``.
        scheduler: address of a Dask scheduler (``tcp://host:8786``).
        progress: show tqdm progress bars.
        use_cache: read/write the object-label cache.
        collect: the workers write each scene into a temporary folder of their own and send
            the files back; this process writes them into ``out_dir`` (for cluster workers that
            do not share a disk with it). The files are the same bytes either way.

    Returns:
        A :class:`GenerateReport` (:meth:`GenerateReport.format_summary` for people). A
        balanced run that reached ``max_scenes`` with levels still short is not ``complete``:
        ``report.unmet`` lists them (level -> views missing).

    Raises:
        InvalidArgumentError / ConfigError: bad arguments or config (before anything is written).
        IoError: ``out_dir`` already holds a dataset and ``resume`` is not set; a full disk
            while writing ``dataset.json`` or ``models/``.
        KeyboardInterrupt: after removing the temporary folders of the run.
    """

    t_start = time.perf_counter()
    cfg = config if isinstance(config, Config) else load_config(config)
    if objects:
        cfg = dataclasses.replace(
            cfg,
            objects=dataclasses.replace(
                cfg.objects, names=tuple(objects), count=None, categories=None
            ),
        )
    quota = cfg.selection.quota
    _check_generate_args(cfg, num_scenes, workers, seed)
    out = Path(out_dir).resolve()
    if out.exists() and not out.is_dir():
        raise IoError(f"generate: '{out}' exists and is not a folder")
    recorded = None
    if resume:
        recorded = check_resume(out, cfg, seed)
    elif out.exists() and any(out.iterdir()):
        raise IoError(
            f"generate: '{out}' is not empty; use --resume to continue the dataset in it, or an "
            "empty or new folder"
        )

    # Compose every scene first (cheap, deterministic): the object set decides the labels.
    cat = load_catalogue(cfg)
    problems = config_errors(cfg, cat)
    if problems:
        raise ConfigError(
            "generate: the config fails every scene (mgn config check says the same):\n  "
            + "\n  ".join(problems)
        )
    catalogue, sources = list(cat.specs), cat.sources
    split = resolve_split(cfg, catalogue)
    extra: dict[str, Any] = {"split": split.to_json()} if split.name != "all" else {}
    per_scene: list[list[ObjectSpec]] = []
    if quota is None:
        assert num_scenes is not None
        per_scene = [
            compose_scene(cfg, catalogue, scene_seed(seed, i), split) for i in range(num_scenes)
        ]
        cat.warn({s.name for specs in per_scene for s in specs})  # the objects of this run only
    else:
        cat.warn(cat.used_names(cfg))

    try:
        out.mkdir(parents=True, exist_ok=True)
        if resume:
            clean_tmp(out)
        report = GenerateReport(out, num_scenes or 0, seed)
        if quota is None:
            assert num_scenes is not None  # checked above: without a quota the count is given
            write_dataset_record(out, dataset_doc(cfg, seed, num_scenes, "running", **extra))
    except OSError as e:
        raise (e if isinstance(e, IoError) else _io_error(out, e)) from e

    executor = make_executor(workers, scheduler)
    run = _Run(
        out,
        cfg,
        seed,
        executor,
        report,
        sources,
        use_cache,
        progress,
        resume,
        extra,
        collect=collect,
        defer_exports=quota is not None and cfg.selection.prune_rejected,
    )
    try:
        if quota is None:
            run.ensure_labels([s for specs in per_scene for s in specs])
            run.run_scenes(list(enumerate(per_scene)), num_scenes or 0)
        else:
            run_balanced(run, catalogue, split, recorded)
    except KeyboardInterrupt:
        executor.cancel()
        clean_tmp(out)
        _record_stop(run, "interrupted", "stopped by Ctrl-C (SIGINT)")
        raise
    except BaseException as e:
        executor.cancel()
        clean_tmp(out)
        _record_stop(run, "failed", f"{type(e).__name__}: {e}")
        raise
    finally:
        executor.close()

    report.wall_seconds = time.perf_counter() - t_start
    status = "complete" if report.complete else "incomplete"
    with contextlib.suppress(OSError):
        run.write_doc(report.num_scenes, status, **_closing_record(run))
    clean_tmp(out)
    report.output_bytes = folder_size(out)
    return report
