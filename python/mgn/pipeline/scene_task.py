"""One scene of ``mgn generate`` as a task a worker runs: :class:`SceneTask` in,
:class:`SceneResult` out.

:func:`run_scene` drops the task's objects (:func:`drop_task_scene`, seeded by the scene seed),
writes the scene (:func:`mgn.pipeline.scene_writer.write_scene`) into
``DIR/.tmp-scene<N>-<pid>``, then its manifest (:mod:`mgn.io.manifest`), then renames the folder
to ``DIR/scene<N>``, so a half-written scene only ever exists under a ``.tmp-`` name
(:data:`TMP_PREFIX`). With ``SceneTask.exports`` it then exports the complete scene
(:mod:`mgn.pipeline.exports`). A worker that does not see ``DIR`` writes into a temporary folder of
its own and returns the files (``SceneTask.collect``); :func:`store_collected` writes them the
same way in the process that sees ``DIR``.

A task depends only on its fields (scene seed, config, objects, labels), never on the worker, the
executor or the time it runs.
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import socket
import tempfile
import time
import traceback
from concurrent.futures import Future
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mgn.base.atomic import disk_full_error
from mgn.errors import InvalidArgumentError
from mgn.io.manifest import write_manifest
from mgn.pipeline import scene_writer
from mgn.pipeline.config import Config
from mgn.pipeline.exports import export_scene
from mgn.pipeline.label_cache import ObjectLabels
from mgn.scene.drop import drop_scene, drop_scene_refilled
from mgn.scene.scene import BUILTIN, Scene, resolve_object

__all__ = [
    "TMP_PREFIX",
    "SceneResult",
    "SceneTask",
    "drop_task_scene",
    "folder_size",
    "run_scene",
    "store_collected",
]

#: Name prefix of the temporary folders of a run (a scene, an export) inside ``DIR``.
TMP_PREFIX = ".tmp-"


@dataclass(frozen=True)
class SceneTask:
    """Everything a worker needs for one scene (picklable).

    Attributes:
        index: scene number N (folder ``scene<N>``); seed: its seed
            (:func:`mgn.pipeline.seeds.scene_seed`).
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


def folder_size(folder: Path) -> int:
    """Bytes of the files under ``folder``."""
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
        size = folder_size(tmp)
        if task.collect:
            files = {
                p.relative_to(tmp).as_posix(): p.read_bytes()
                for p in sorted(tmp.rglob("*"))
                if p.is_file()
            }
            shutil.rmtree(tmp.parent, ignore_errors=True)
            times["finalize"] = time.perf_counter() - t2
            times["cpu"] = time.process_time() - c0
            return SceneResult(
                task.index,
                task.seed,
                True,
                None,
                False,
                times,
                size,
                len(scene),
                worker,
                files,
                removed=tuple(r.name for r in scene.removed),
            )
        if final.exists():  # an inconsistent leftover the caller decided to redo
            shutil.rmtree(final)
        tmp.rename(final)
        times["finalize"] = time.perf_counter() - t2
        if task.exports:  # the scene is complete: a failed export leaves it, --resume redoes it
            times.update(export_scene(out, task.index, task.exports, task.config.gripper))
        times["cpu"] = time.process_time() - c0
        return SceneResult(
            task.index,
            task.seed,
            True,
            None,
            False,
            times,
            size,
            len(scene),
            worker,
            removed=tuple(r.name for r in scene.removed),
        )
    except Exception as e:  # reported per scene, the others go on
        shutil.rmtree(tmp.parent if task.collect else tmp, ignore_errors=True)
        full = disk_full_error(e)
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
        full = disk_full_error(e)
        msg = (
            f"disk full while writing scene{result.index}"
            if full is not None
            else f"cannot write scene{result.index}: {e}"
        )
        return dataclasses.replace(
            result, ok=False, error=msg, disk_full=full is not None, files=None
        )
    return dataclasses.replace(result, files=None)
