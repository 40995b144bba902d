"""Where the tasks of ``mgn generate`` run: :func:`make_executor` picks one of three executors
with one interface (:class:`Executor`: run a function on every item, yield the outcomes as they
complete, cancel, close).

- in-process (``workers=1``): the tasks one after the other; for scene tasks the next scene's
  drop runs in a thread alongside (:func:`mgn.pipeline.scene_task.drop_task_scene`);
- a local process pool (``workers=K``, spawned processes), each task with
  ``cores // K`` threads;
- a Dask distributed cluster (``scheduler="tcp://host:8786"``; every worker must see ``DIR``
  at the same path and have mgn installed; see docs/cluster.md).

A task's result depends only on the task, never on the executor, so every executor gives the
same files.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, ThreadPoolExecutor, as_completed
from typing import Any

from mgn.errors import InvalidArgumentError
from mgn.pipeline import scene_task
from mgn.pipeline.scene_task import SceneTask

__all__ = ["Executor", "Outcome", "make_executor"]

Outcome = tuple[Any, Any, Exception | None]
"""(item, result, exception) of one task: result None when the task raised."""


class Executor(ABC):
    """Runs independent tasks; yields (item, result, exception) as they complete."""

    threads_per_task = 0

    @abstractmethod
    def run(self, fn: Callable[[Any], Any], items: Sequence[Any]) -> Iterator[Outcome]:
        """Run ``fn`` on every item; yield (item, result, exception) in completion order."""

    def cancel(self) -> None:  # noqa: B027 (optional hook: nothing to stop by default)
        """Stop scheduling; stop running tasks where possible."""

    def close(self) -> None:  # noqa: B027 (optional hook: nothing to release by default)
        """Release the executor's workers."""


class _InProcess(Executor):
    """Runs the tasks one after the other in this process. Scenes (``fn`` is
    :func:`mgn.pipeline.scene_task.run_scene`): the drop of scene k + 1 (one core, Bullet
    releases the GIL) runs in a thread of its own while scene k is rendered, labelled and
    written, so the second core is not idle during the drop. A drop depends only on its task, so
    the files do not change."""

    def __init__(self) -> None:
        self._stop = False

    def run(self, fn: Callable[[Any], Any], items: Sequence[Any]) -> Iterator[Outcome]:
        self._stop = False
        if fn is scene_task.run_scene:
            yield from self._run_scenes(items)
            return
        for item in items:
            if self._stop:
                return
            try:
                yield item, fn(item), None
            except Exception as e:  # reported per scene, the others go on
                yield item, None, e

    def _run_scenes(self, tasks: Sequence[SceneTask]) -> Iterator[Outcome]:
        pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="mgn-drop")
        try:
            ahead = pool.submit(scene_task.drop_task_scene, tasks[0]) if tasks else None
            for k, task in enumerate(tasks):
                if self._stop:
                    return
                current = ahead
                ahead = None
                if k + 1 < len(tasks):
                    ahead = pool.submit(scene_task.drop_task_scene, tasks[k + 1])
                try:
                    yield task, scene_task.run_scene(task, current), None
                except Exception as e:
                    yield task, None, e
        finally:
            # A cancelled run does not wait for a drop nobody will use (it finishes alone).
            pool.shutdown(wait=False, cancel_futures=True)

    def cancel(self) -> None:  # optional hook: nothing to stop by default
        self._stop = True


class _ProcessPool(Executor):
    def __init__(self, workers: int) -> None:

        # spawn, not fork: the parent may hold OpenMP/TBB/Embree threads and a GL context.
        ctx = multiprocessing.get_context("spawn")
        self.pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx)
        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1
        self.threads_per_task = max(1, cores // workers)
        self._futures: list[Future[Any]] = []

    def run(self, fn: Callable[[Any], Any], items: Sequence[Any]) -> Iterator[Outcome]:

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


class _Dask(Executor):
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

    def run(self, fn: Callable[[Any], Any], items: Sequence[Any]) -> Iterator[Outcome]:
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


def make_executor(workers: int, scheduler: str | None) -> Executor:
    """The Dask executor of ``scheduler`` when given, else in-process (``workers`` 1) or a
    local pool of ``workers`` spawned processes."""
    if scheduler:
        return _Dask(scheduler)
    if workers == 1:
        return _InProcess()
    return _ProcessPool(workers)
