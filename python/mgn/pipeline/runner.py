"""``mgn generate``: objects, gripper and cup in, a complete dataset out.

Steps:

1. ``dataset.json`` is written (atomically) with the schema version, the mgn version, the full
   config, the seed and the scene count; it is updated at the end.
2. The objects of every scene are chosen up front (:func:`mgn.scene.compose_objects`, seeded by
   the scene seed), so that each distinct object is labelled once
   (:mod:`mgn.pipeline.label_cache`: cached on disk, missing ones computed as tasks of the
   executor) and ``models/<id>/`` is written.
3. Every scene is an independent task (:func:`run_scene`): drop the objects
   (:func:`mgn.scene.drop_scene`), then :func:`mgn.pipeline.scene_writer.write_scene` into
   ``DIR/.tmp-scene<N>-<pid>``, then the manifest (:mod:`mgn.io.manifest`), then a rename
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

Executors: in-process (``workers=1``), a local process pool (``workers=K``, spawned processes),
or a Dask distributed cluster (``scheduler="tcp://host:8786"``; every worker must see ``DIR``
at the same path and have mgn installed; see docs/cluster.md).

Failures: a scene that raises is reported with its index, seed and error and does not stop the
others. A full disk is reported as "disk full" with the path, and stops scheduling new scenes.
Ctrl-C stops the run, removes the temporary folders and leaves the complete scenes; ``--resume``
continues (it also removes any ``.tmp-`` folder a killed run left behind, redoes scenes whose
manifest is missing or inconsistent, and writes the exports that complete scenes lack).
``dataset.json`` ``status`` is ``running`` while the run goes on, then ``complete`` (every scene
written), ``incomplete`` (scenes failed or were not run), ``interrupted`` (Ctrl-C) or ``failed`` (an
error stopped the whole run, e.g. a full disk while writing ``models/``; ``error`` says which); only
a killed process leaves ``running``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import multiprocessing
import os
import shutil
import socket
import sys
import tempfile
import time
import traceback
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from mgn._core import __version__
from mgn.base.atomic import _io_error, disk_full_error
from mgn.errors import InvalidArgumentError, IoError
from mgn.io.dataset_record import read_dataset_record, removed_objects, write_dataset_record
from mgn.io.manifest import check_manifest, write_manifest
from mgn.objects import ObjectSpec
from mgn.pipeline import scene_writer
from mgn.pipeline.config import Config, ConfigError, load_config
from mgn.pipeline.exports import clean_export_tmp, export_models, export_scene, missing_exports
from mgn.pipeline.label_cache import (
    ObjectLabels,
    compute_object_labels,
    estimate_label_seconds,
    load_cached_labels,
    save_cached_labels,
    write_models,
)
from mgn.pipeline.sanity import config_errors, load_catalogue
from mgn.pipeline.seeds import SCENE_SEED_RULE, scene_seed
from mgn.pipeline.testset import compose_scene, resolve_split, run_balanced
from mgn.render.photo import RenderSettings
from mgn.scene.drop import drop_scene, drop_scene_refilled
from mgn.scene.scene import BUILTIN, Scene, resolve_object

__all__ = [
    "DATASET_SCHEMA_VERSION",
    "GenerateReport",
    "SceneResult",
    "SceneTask",
    "generate",
    "run_scene",
]

#: ``schema_version`` of ``dataset.json``.
DATASET_SCHEMA_VERSION = 1
TMP_PREFIX = ".tmp-"
STAGES = ("drop", "write", "finalize")


# ------------------------------------------------------------------------------------- tasks


@dataclass(frozen=True)
class SceneTask:
    """Everything a worker needs for one scene (picklable).

    Attributes:
        index: scene number N (folder ``scene<N>``); seed: its seed (:func:`scene_seed`).
        out_dir: the dataset folder (absolute; shared by every worker).
        config: the dataset config.
        objects: (name, source) of the objects to drop, in drop order (source ``"builtin"`` or
            a user-objects YAML path).
        labels: name -> the labels of the objects of this scene.
        collect: write into a temporary folder of the worker and return the files in the
            result (``SceneResult.files``) instead of writing into ``out_dir``: for workers
            that do not see the output folder; the caller writes them.
        exports: the layouts (``bop``, ``graspnet``) the worker writes after the scene
            (:func:`mgn.pipeline.exports.export_scene`); not with ``collect``.
    """

    index: int
    seed: int
    out_dir: str
    config: Config
    objects: tuple[tuple[str, str], ...]
    labels: dict[str, ObjectLabels] = field(default_factory=dict)
    collect: bool = False
    exports: tuple[str, ...] = ()


@dataclass(frozen=True)
class SceneResult:
    """The outcome of one scene task.

    Attributes:
        index, seed: the scene. ok: written completely.
        error: one-line error when not ok; disk_full: the error was a full disk.
        times: seconds per stage (drop, write, finalize, and "write: <label stage>"; "export:
            bop", "export: graspnet" for the exports); "cpu": CPU seconds of the worker process
            over the scene, all its threads.
        num_bytes: size of the scene folder; num_objects: objects in the tote.
        worker: host and process id that ran it.
        files: with ``SceneTask.collect``: the scene's files (relative path -> bytes, the
            manifest included), for the caller to write; None otherwise.
        removed: names of the objects that left the tote during the drop (not in the scene).
    """

    index: int
    seed: int
    ok: bool
    error: str | None = None
    disk_full: bool = False
    times: dict[str, float] = field(default_factory=dict)
    num_bytes: int = 0
    num_objects: int = 0
    worker: str = ""
    files: dict[str, bytes] | None = field(default=None, repr=False, compare=False)
    removed: tuple[str, ...] = ()


def _disk_full(e: BaseException) -> BaseException | None:
    """The disk-full error in the chain of ``e``, if any (``disk_full_error``)."""
    return disk_full_error(e)


def _folder_size(folder: Path) -> int:
    return sum(p.stat().st_size for p in folder.rglob("*") if p.is_file())


def drop_task_scene(task: SceneTask) -> Scene:
    """The settled scene of ``task`` (its objects dropped with its seed): the drop step of
    :func:`run_scene`. Depends only on the task, never on when or in which thread it runs."""
    specs = [resolve_object(name, source) for name, source in task.objects]
    sources = {name: source for name, source in task.objects if source != BUILTIN}
    drop_kw: dict[str, Any] = {
        "seed": task.seed,
        "tote": task.config.tote,
        "options": task.config.drop,
        "sources": sources,
    }
    if task.config.objects.refill:
        return drop_scene_refilled(specs, attempts=task.config.objects.refill_attempts, **drop_kw)
    return drop_scene(specs, **drop_kw)


def run_scene(task: SceneTask, dropped: Future[Scene] | None = None) -> SceneResult:
    """Drop, write and finalise one scene (see the module doc). Never raises for an ordinary
    error: the result says what went wrong. The temporary folder is removed on any failure,
    including KeyboardInterrupt (which is re-raised).

    ``dropped``: the task's drop (:func:`drop_task_scene`) already started elsewhere (the
    in-process executor drops scene k + 1 while scene k is labelled); ``times["drop"]`` is
    then the time spent waiting for it and ``times["cpu"]`` this process's CPU over the
    scene, which includes the next scene's drop running alongside."""

    out = Path(task.out_dir)
    final = out / f"scene{task.index}"
    if task.collect:  # the worker may not see out_dir: a folder of its own, returned as bytes
        tmp = Path(tempfile.mkdtemp(prefix=f"{TMP_PREFIX}scene{task.index}-")) / "scene"
    else:
        tmp = out / f"{TMP_PREFIX}scene{task.index}-{os.getpid()}"
    worker = f"{socket.gethostname()}:{os.getpid()}"
    times: dict[str, float] = {}
    t0 = time.perf_counter()
    # CPU of this process over the scene, all threads (a worker runs one scene at a time).
    c0 = time.process_time()
    try:
        scene = drop_task_scene(task) if dropped is None else dropped.result()
        times["drop"] = time.perf_counter() - t0
        if len(scene) == 0:
            left = ", ".join(f"'{r.name}' ({r.reason})" for r in scene.removed)
            raise InvalidArgumentError(
                f"no object stayed in the tote ({left or 'none was dropped'}): the scene would "
                "hold nothing to see or grasp; check the objects' sizes and scales (mgn config "
                "check)"
            )
        t1 = time.perf_counter()
        if tmp.exists():
            shutil.rmtree(tmp)
        tmp.mkdir(parents=True)
        # Looked up on the module at call time (tests replace it to simulate an interrupt).
        stages = scene_writer.write_scene(scene, tmp, task.config, task.labels)
        times["write"] = time.perf_counter() - t1
        times.update({f"write: {k}": v for k, v in (stages or {}).items()})
        t2 = time.perf_counter()
        # What made the RGB images (engine, samples, denoiser), for `mgn report`.
        write_manifest(tmp, scene=task.index, seed=task.seed, render=task.config.render.describe())
        size = _folder_size(tmp)
        if task.collect:
            files = {p.relative_to(tmp).as_posix(): p.read_bytes()
                     for p in sorted(tmp.rglob("*")) if p.is_file()}  # fmt: skip
            shutil.rmtree(tmp.parent, ignore_errors=True)
            times["finalize"] = time.perf_counter() - t2
            times["cpu"] = time.process_time() - c0
            return SceneResult(task.index, task.seed, True, None, False, times, size,
                               len(scene), worker, files,
                               removed=tuple(r.name for r in scene.removed))  # fmt: skip
        if final.exists():  # an inconsistent leftover the caller decided to redo
            shutil.rmtree(final)
        tmp.rename(final)
        times["finalize"] = time.perf_counter() - t2
        if task.exports:  # the scene is complete: a failed export leaves it, --resume redoes it
            times.update(export_scene(out, task.index, task.exports, task.config.gripper))
        times["cpu"] = time.process_time() - c0
        return SceneResult(
            task.index, task.seed, True, None, False, times, size, len(scene), worker,
            removed=tuple(r.name for r in scene.removed),
        )  # fmt: skip
    except Exception as e:  # reported per scene, the others go on
        shutil.rmtree(tmp.parent if task.collect else tmp, ignore_errors=True)
        full = _disk_full(e)
        if full is not None:
            where = getattr(full, "filename", None) or tmp
            msg = f"disk full while writing scene{task.index} ('{where}')"
        else:
            frame = traceback.extract_tb(e.__traceback__)[-1:]
            at = f" [{Path(frame[0].filename).name}:{frame[0].lineno}]" if frame else ""
            msg = f"{type(e).__name__}: {e}{at}"
        return SceneResult(task.index, task.seed, False, msg, full is not None, times, 0, 0, worker)
    except BaseException:
        shutil.rmtree(tmp.parent if task.collect else tmp, ignore_errors=True)
        raise


def store_collected(out: Path, result: SceneResult) -> SceneResult:
    """Write the files a collecting scene task returned (``SceneResult.files``) into
    ``out/scene<N>`` the way a worker would (a temporary folder renamed when complete); returns
    the result without the bytes, or a failed result if they cannot be written."""
    if result.files is None:
        return result
    final = out / f"scene{result.index}"
    tmp = out / f"{TMP_PREFIX}scene{result.index}-{os.getpid()}"
    try:
        if tmp.exists():
            shutil.rmtree(tmp)
        for rel, data in result.files.items():
            path = tmp / rel
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)
        if final.exists():
            shutil.rmtree(final)
        tmp.rename(final)
    except OSError as e:
        shutil.rmtree(tmp, ignore_errors=True)
        full = _disk_full(e)
        msg = (f"disk full while writing scene{result.index}" if full is not None
               else f"cannot write scene{result.index}: {e}")  # fmt: skip
        return dataclasses.replace(
            result, ok=False, error=msg, disk_full=full is not None, files=None
        )
    return dataclasses.replace(result, files=None)


def _duration(seconds: float) -> str:
    """``45 s``, ``3 min``, ``1.5 h``: a rough duration for people."""
    if seconds < 90:
        return f"{max(1, round(seconds))} s"
    if seconds < 5400:
        return f"{round(seconds / 60)} min"
    return f"{seconds / 3600:.1f} h"


def _label_task(
    args: tuple[ObjectSpec, Config, int, bool | None],
) -> tuple[ObjectLabels, float]:
    """The labels of one object and the wall seconds they took (in the worker)."""

    spec, config, num_threads, progress = args
    t0 = time.perf_counter()
    labels = compute_object_labels(spec, config, num_threads, progress)
    return labels, time.perf_counter() - t0


# --------------------------------------------------------------------------------- executors


_Outcome = tuple[Any, Any, Exception | None]
"""(item, result, exception) of one task: result None when the task raised."""


class _Executor(ABC):
    """Runs independent tasks; yields (item, result, exception) as they complete."""

    threads_per_task = 0

    @abstractmethod
    def run(self, fn: Callable[[Any], Any], items: Sequence[Any]) -> Iterator[_Outcome]:
        """Run ``fn`` on every item; yield (item, result, exception) in completion order."""

    def cancel(self) -> None:  # noqa: B027 (optional hook: nothing to stop by default)
        """Stop scheduling; stop running tasks where possible."""

    def close(self) -> None:  # noqa: B027 (optional hook: nothing to release by default)
        """Release the executor's workers."""


class _InProcess(_Executor):
    """Runs the tasks one after the other in this process. Scenes (``fn`` is
    :func:`run_scene`): the drop of scene k + 1 (one core, Bullet releases the GIL) runs in a
    thread of its own while scene k is rendered, labelled and written, so the second core is
    not idle during the drop. A drop depends only on its task, so the files do not change."""

    def __init__(self) -> None:
        self._stop = False

    def run(self, fn: Callable[[Any], Any], items: Sequence[Any]) -> Iterator[_Outcome]:
        self._stop = False
        if fn is run_scene:
            yield from self._run_scenes(items)
            return
        for item in items:
            if self._stop:
                return
            try:
                yield item, fn(item), None
            except Exception as e:  # reported per scene, the others go on
                yield item, None, e

    def _run_scenes(self, tasks: Sequence[SceneTask]) -> Iterator[_Outcome]:
        pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="mgn-drop")
        try:
            ahead = pool.submit(drop_task_scene, tasks[0]) if tasks else None
            for k, task in enumerate(tasks):
                if self._stop:
                    return
                current = ahead
                ahead = None
                if k + 1 < len(tasks):
                    ahead = pool.submit(drop_task_scene, tasks[k + 1])
                try:
                    yield task, run_scene(task, current), None
                except Exception as e:
                    yield task, None, e
        finally:
            # A cancelled run does not wait for a drop nobody will use (it finishes alone).
            pool.shutdown(wait=False, cancel_futures=True)

    def cancel(self) -> None:  # optional hook: nothing to stop by default
        self._stop = True


class _ProcessPool(_Executor):
    def __init__(self, workers: int) -> None:

        # spawn, not fork: the parent may hold OpenMP/TBB/Embree threads and a GL context.
        ctx = multiprocessing.get_context("spawn")
        self.pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx)
        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1
        self.threads_per_task = max(1, cores // workers)
        self._futures: list[Future[Any]] = []

    def run(self, fn: Callable[[Any], Any], items: Sequence[Any]) -> Iterator[_Outcome]:

        futures = {self.pool.submit(fn, item): item for item in items}
        self._futures = list(futures)
        for fut in as_completed(futures):
            if fut.cancelled():
                continue
            try:
                yield futures[fut], fut.result(), None
            except Exception as e:
                yield futures[fut], None, e

    def cancel(self) -> None:
        for f in self._futures:
            f.cancel()
        procs = list(getattr(self.pool, "_processes", {}).values())
        self.pool.shutdown(wait=False, cancel_futures=True)
        for p in procs:  # no worker may still be writing once we clean up
            with contextlib.suppress(Exception):
                p.terminate()
        for p in procs:
            with contextlib.suppress(Exception):
                p.join(timeout=10)

    def close(self) -> None:  # optional hook: nothing to release by default
        self.pool.shutdown(wait=True, cancel_futures=True)


class _Dask(_Executor):
    threads_per_task = 1

    def __init__(self, scheduler: str) -> None:
        try:
            from distributed import Client
        except ImportError as e:  # pragma: no cover - depends on the install
            raise InvalidArgumentError(
                "--scheduler needs Dask distributed: pip install 'mgn[cluster]'"
            ) from e
        self.client = Client(scheduler)
        self._futures: list[Any] = []

    def run(self, fn: Callable[[Any], Any], items: Sequence[Any]) -> Iterator[_Outcome]:
        from distributed import as_completed

        futures: dict[Any, tuple[Any, Any]] = {}
        for item in items:
            fut = self.client.submit(fn, item, pure=False)
            futures[fut.key] = (fut, item)
        self._futures = [f for f, _ in futures.values()]
        for fut in as_completed(self._futures):
            item = futures[fut.key][1]
            if fut.cancelled():
                continue
            try:
                yield item, fut.result(), None
            except Exception as e:
                yield item, None, e

    def cancel(self) -> None:
        with contextlib.suppress(Exception):
            self.client.cancel(self._futures, force=True)

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self.client.close()


def _executor(workers: int, scheduler: str | None) -> _Executor:
    if scheduler:
        return _Dask(scheduler)
    if workers == 1:
        return _InProcess()
    return _ProcessPool(workers)


# ------------------------------------------------------------------------------------ report


@dataclass
class GenerateReport:
    """What :func:`generate` did.

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
        physics: ``dataset.json`` ``physics_scores`` (see :func:`physics_record`), None when no
            parallel-jaw labels with physics were made.
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
                + ("" if len(lost) > 5 else ": " + "; ".join(
                    f"scene{r.index}: {', '.join(r.removed)}" for r in lost))
                + " (objects.refill drops a scene again, at most objects.refill_attempts times, "
                "until its objects stay in; fewer or smaller objects per scene help)"
            )  # fmt: skip
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


# ---------------------------------------------------------------------------------- generate


def _catalogue(config: Config) -> tuple[list[ObjectSpec], dict[str, str]]:

    cat = load_catalogue(config)
    return list(cat.specs), cat.sources


def _dataset_doc(
    config: Config, seed: int, num_scenes: int, status: str, **extra: Any
) -> dict[str, Any]:
    return {
        "schema_version": DATASET_SCHEMA_VERSION,
        "mgn_version": __version__,
        "seed": int(seed),
        "num_scenes": int(num_scenes),
        "scene_seed": SCENE_SEED_RULE,
        "scene_folders": "scene<i>, i = 0..num_scenes-1",
        "depth_invalid": "NaN",
        "config": config.to_dict(),
        "splits": {"train": [], "val": [], "test": []},
        "status": status,
        **extra,
    }


def physics_record(config: Config, labels: Mapping[str, ObjectLabels]) -> dict[str, Any] | None:
    """``dataset.json`` ``physics_scores``: how the parallel-jaw physics scores were made and how
    many stored grasps of each object got one (``scored``) or kept NaN because of the cap
    ``object_labels.physics_grasps`` (``unscored``). None without physics labels."""

    if not (config.labels.paralleljaw and config.labels.pj_physics):
        return None
    ol = config.object_labels
    objects: dict[str, dict[str, int]] = {}
    for name in sorted(labels):
        pj = labels[name].paralleljaw
        if pj is None:
            continue
        sim = np.asarray(pj.quality_score_simulation)
        scored = int(np.count_nonzero(np.isfinite(sim)))
        objects[name] = {"grasps": int(sim.shape[0]), "scored": scored}
    total = sum(o["grasps"] for o in objects.values())
    scored = sum(o["scored"] for o in objects.values())
    return {
        "cap": ol.physics_grasps,
        "search": ol.physics_search,
        "checks": ol.staircase_checks if ol.physics_search == "staircase" else None,
        "calibration": ol.physics_calibration if ol.physics_search == "staircase" else None,
        "grid": ol.physics_grid,
        "grasps": total,
        "scored": scored,
        "unscored": total - scored,
        "capped_objects": sorted(n for n, o in objects.items() if o["scored"] < o["grasps"]),
        "objects": objects,
    }


def _clean_tmp(out: Path) -> list[Path]:
    removed = []
    for p in out.glob(f"{TMP_PREFIX}*"):
        if p.is_dir():
            shutil.rmtree(p, ignore_errors=True)
            removed.append(p)
    return removed + clean_export_tmp(out)


def _comparable(config_doc: Any) -> Any:
    """A config dict as compared by ``--resume`` (``selection.max_scenes`` and ``output`` may
    change: the exports are made from the scene folders, which they do not change)."""
    doc = json.loads(json.dumps(config_doc))
    if isinstance(doc, dict) and isinstance(doc.get("selection"), dict):
        doc["selection"].pop("max_scenes", None)
    if isinstance(doc, dict):
        doc.pop("output", None)
    if isinstance(doc, dict) and "render" not in doc:
        # Recorded before the render section existed: those images came from the raster.

        doc["render"] = json.loads(json.dumps(Config(render=RenderSettings()).to_dict()["render"]))
    return doc


def _check_resume(out: Path, config: Config, seed: int) -> dict[str, Any] | None:
    """The recorded ``dataset.json`` of ``out`` (None: nothing started yet), checked against
    the seed and config of the resumed run."""
    try:
        doc = read_dataset_record(out)
    except IoError as e:
        raise IoError(f"--resume: {e}") from e
    if doc is None:
        return None  # nothing started yet: a fresh run
    if doc.get("seed") != seed:
        raise InvalidArgumentError(
            f"--resume: '{out}' was generated with seed {doc.get('seed')}, got --seed {seed}"
        )
    recorded: dict[str, Any] = doc["config"] if isinstance(doc.get("config"), dict) else {}
    split = json.loads(json.dumps(config.split.to_dict()))
    if recorded.get("split", {"name": "all", "unseen": "novel"}) != split:
        raise InvalidArgumentError(
            f"--resume: '{out}' was generated with split {recorded.get('split')}, got {split} "
            "(--split / config key 'split'); use the same split or a new output folder"
        )
    diffs = _config_differences(_comparable(recorded), _comparable(config.to_dict()))
    if diffs:
        shown = "; ".join(f"{k}: recorded {a!r}, now {b!r}" for k, a, b in diffs[:5])
        more = f" (and {len(diffs) - 5} more)" if len(diffs) > 5 else ""
        raise InvalidArgumentError(
            f"--resume: the config differs from the one recorded in '{out / 'dataset.json'}' in "
            f"{len(diffs)} key(s): {shown}{more}; use the same config (or a new output folder)"
        )
    return doc


_MISSING = "<not set>"


def _config_differences(recorded: Any, current: Any, key: str = "") -> list[tuple[str, Any, Any]]:
    """(dotted key, recorded value, current value) of every leaf where two config dicts
    differ, in key order; a key only one side has shows ``<not set>`` on the other."""
    if isinstance(recorded, dict) and isinstance(current, dict):
        out: list[tuple[str, Any, Any]] = []
        for k in sorted(set(recorded) | set(current), key=str):
            sub = f"{key}.{k}" if key else str(k)
            out += _config_differences(recorded.get(k, _MISSING), current.get(k, _MISSING), sub)
        return out
    return [] if recorded == current else [(key or "<config>", recorded, current)]


@dataclass
class _Run:
    """What the scene loop of :func:`generate` needs; the test-set builder drives it as a
    :class:`mgn.pipeline.testset.BalancedRun`."""

    out: Path
    cfg: Config
    seed: int
    executor: _Executor
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
                    f"{_duration(low)}-{_duration(high)} on {threads} cores (computed once, "
                    "then cached)",
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
        bar = tqdm(total=total, initial=len(report.skipped) + len(report.results),
                   desc="scenes", unit="scene", disable=not self.progress)  # fmt: skip
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
                {"scenes/h": f"{3600 * done / max(elapsed, 1e-9):.0f}",
                 "failed": len(report.failed)}
            )  # fmt: skip
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
                full = _disk_full(e)
                old = self.report.results.get(i)
                self.report.results[i] = SceneResult(
                    i, scene_seed(self.seed, i), False,
                    f"disk full while exporting scene{i}" if full is not None
                    else f"export of scene{i}: {type(e).__name__}: {e}",
                    full is not None, dict(old.times) if old else {},
                )  # fmt: skip
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
            self.out, _dataset_doc(self.cfg, self.seed, num_scenes, status, **self.extra, **more)
        )


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
            cfg, objects=dataclasses.replace(cfg.objects, names=tuple(objects), count=None,
                                             categories=None)
        )  # fmt: skip
    quota = cfg.selection.quota
    _check_generate_args(cfg, num_scenes, workers, seed)
    out = Path(out_dir).resolve()
    if out.exists() and not out.is_dir():
        raise IoError(f"generate: '{out}' exists and is not a folder")
    recorded = None
    if resume:
        recorded = _check_resume(out, cfg, seed)
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
            _clean_tmp(out)
        report = GenerateReport(out, num_scenes or 0, seed)
        if quota is None:
            assert num_scenes is not None  # checked above: without a quota the count is given
            write_dataset_record(out, _dataset_doc(cfg, seed, num_scenes, "running", **extra))
    except OSError as e:
        raise (e if isinstance(e, IoError) else _io_error(out, e)) from e

    executor = _executor(workers, scheduler)
    run = _Run(out, cfg, seed, executor, report, sources, use_cache, progress, resume, extra,
               collect=collect,
               defer_exports=quota is not None and cfg.selection.prune_rejected)  # fmt: skip
    try:
        if quota is None:
            run.ensure_labels([s for specs in per_scene for s in specs])
            run.run_scenes(list(enumerate(per_scene)), num_scenes or 0)
        else:
            run_balanced(run, catalogue, split, recorded)
    except KeyboardInterrupt:
        executor.cancel()
        _clean_tmp(out)
        _record_stop(run, "interrupted", "stopped by Ctrl-C (SIGINT)")
        raise
    except BaseException as e:
        executor.cancel()
        _clean_tmp(out)
        _record_stop(run, "failed", f"{type(e).__name__}: {e}")
        raise
    finally:
        executor.close()

    report.wall_seconds = time.perf_counter() - t_start
    status = "complete" if report.complete else "incomplete"
    failed = [{"scene": r.index, "seed": r.seed, "error": r.error} for r in report.failed]
    more: dict[str, Any] = {"removed_objects": removed_objects(out)}
    report.physics = physics_record(cfg, run.labels)
    report.no_paralleljaw = {
        name: str(lab.paralleljaw.metadata["pj_skipped"])
        for name, lab in sorted(run.labels.items())
        if lab.paralleljaw is not None and lab.paralleljaw.metadata.get("pj_skipped")
    }
    if report.physics is not None:
        more["physics_scores"] = report.physics
    if failed:
        more["failed_scenes"] = failed
    with contextlib.suppress(OSError):
        run.write_doc(report.num_scenes, status, **more)
    _clean_tmp(out)
    report.output_bytes = _folder_size(out)
    return report
