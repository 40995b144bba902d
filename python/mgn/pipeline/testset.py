"""Test-set builders: the unseen-object split and the difficulty-balanced view selection.

Both are driven by the config (``split`` and ``selection`` sections, :mod:`mgn.pipeline.config`) and
run inside :func:`mgn.pipeline.generate`; docs/testsets.md explains the design for users.

Unseen split (``split.name``):

- ``all``: no split (nothing is recorded; every category is "seen").
- ``train``: the ``split.unseen`` categories never appear. Random compositions draw from the
  other categories; an explicit ``objects.names`` / ``objects.categories`` entry that is unseen
  is a config error naming the entry.
- ``test``: unseen categories may appear, and every scene holds at least one when the pool
  allows it (the pool holds an unseen category and the objects are not an explicit
  ``objects.names`` list): if the seeded composition has none, its last drawn category (all
  the copies drawn in that block) is replaced by an unseen category drawn from the scene seed.

``dataset.json`` then records ``"split": {"name", "unseen_categories", "unseen_names"}``.

Difficulty-balanced selection (``selection.quota``): scenes are generated in batches of
``selection.batch_scenes``; batch ``b`` holds scenes ``b*B .. b*B+B-1`` (scene seeds as usual,
:func:`mgn.pipeline.scene_seed`). When every scene of a batch is complete, the views of the batch
are visited in (scene, view) order and a view of difficulty ``d`` (its ``{v}_layout.json``) is
selected while level ``d`` still lacks views, else rejected. The composition of each scene of
batch ``b`` is steered by :func:`plan_batch` towards the levels still missing after batches
``< b`` (see :func:`compose_scene` for the recipes), so the result depends only on the seed and
the config, never on the number of workers or the finishing order. The run stops when every
quota is met, or before starting a batch at scene index >= ``selection.max_scenes`` (the report
and ``dataset.json`` then list the unmet levels; ``--resume`` with a larger ``--max-scenes``
continues to the same result a larger limit would have given from the start).

After each batch ``dataset.json`` records ``"selection": {"quota", "views", "rejected",
"batch_scenes", "batches_done", "scenes_generated", "unmet", "complete", "pruned"}``; with
``selection.prune_rejected`` the files of rejected views are then deleted
(:func:`mgn.io.manifest.prune_scene`: manifest and ``scene_gt.json`` rewritten, a scene left
without views removed as a whole).
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from mgn.errors import InvalidArgumentError, IoError
from mgn.io.manifest import prune_scene, scene_view_ids
from mgn.objects import ObjectSpec
from mgn.pipeline.config import DIFFICULTY_LEVELS, Config, ConfigError, SelectionConfig
from mgn.pipeline.seeds import scene_seed
from mgn.scene.compose import compose_objects

__all__ = [
    "NOVEL_TAG",
    "RECIPES",
    "BalancedReport",
    "BalancedRun",
    "SceneOutcome",
    "SelectionState",
    "Split",
    "compose_scene",
    "parse_quota",
    "plan_batch",
    "resolve_split",
    "run_balanced",
    "select_views",
    "view_difficulty",
]

#: The library tag of the objects held out by default (``split.unseen: novel``).
NOVEL_TAG = "novel"

#: Composition recipe per target difficulty level: (min objects, max objects, copies (min, max))
#: drawn from the pool, or None = the config's own ``objects`` composition (MGN: 20 objects,
#: 2-5 copies per category). Levels 1-3 need unique classes (copies 1) and, for 1-2, few
#: objects (few layers, complete masks); level 3 needs an incomplete object (more objects);
#: level 4 needs repeated classes with complete masks (few objects, 2-3 copies).
RECIPES: dict[int, tuple[int, int, tuple[int, int]] | None] = {
    1: (1, 3, (1, 1)),
    2: (2, 5, (1, 1)),
    3: (5, 10, (1, 1)),
    4: (2, 6, (2, 3)),
    5: None,
}

_UNSEEN_STREAM = 0x756E7365  # "unse": the stream of the test split's unseen draw
_RECIPE_STREAM = 0x72656369  # "reci": the stream of a recipe's object count


# ------------------------------------------------------------------------------------ split


@dataclass(frozen=True)
class Split:
    """A resolved unseen-object split.

    Attributes:
        name: ``all``, ``train`` or ``test``.
        unseen_names: the held-out objects (catalogue order); unseen_categories: their ids.
    """

    name: str
    unseen_names: tuple[str, ...]
    unseen_categories: tuple[int, ...]

    def to_json(self) -> dict[str, Any]:
        """The ``dataset.json`` entry (split contract)."""
        return {
            "name": self.name,
            "unseen_categories": list(self.unseen_categories),
            "unseen_names": list(self.unseen_names),
        }


def _find(catalogue: Sequence[ObjectSpec], key: str | int) -> ObjectSpec | None:
    for s in catalogue:
        if isinstance(key, str) and s.name == key.strip():
            return s
    if isinstance(key, int) or (isinstance(key, str) and key.strip().isdigit()):
        for s in catalogue:
            if s.category_id == int(key):
                return s
    return None


def resolve_split(config: Config, catalogue: Sequence[ObjectSpec]) -> Split:
    """The split of ``config`` against ``catalogue`` (built-in + user objects).

    Raises:
        ConfigError: an unknown object in ``split.unseen``; ``unseen: novel`` with no object
            tagged ``novel``; a ``train`` split whose ``objects.names`` / ``objects.categories``
            holds an unseen object (the message names the key and the object).
    """
    sp = config.split
    if sp.unseen == NOVEL_TAG:
        chosen = [s for s in catalogue if NOVEL_TAG in s.tags]
        if not chosen and sp.name != "all":
            raise ConfigError(
                "config key 'split.unseen': 'novel' but no object of the catalogue is tagged "
                "'novel'; list the unseen objects by name"
            )
    else:
        chosen = []
        for i, key in enumerate(sp.unseen):
            spec = _find(catalogue, key)
            if spec is None:
                raise ConfigError(
                    f"config key 'split.unseen[{i}]': unknown object {key!r}; expected one of "
                    + ", ".join(s.name for s in catalogue)
                )
            chosen.append(spec)
    chosen.sort(key=lambda s: s.category_id)
    split = Split(sp.name, tuple(s.name for s in chosen), tuple(int(s.category_id) for s in chosen))
    if sp.name == "train":
        unseen = set(split.unseen_names)
        for field_name in ("names", "categories"):
            entries = getattr(config.objects, field_name)
            for i, key in enumerate(entries or ()):
                spec = _find(catalogue, key)
                if spec is not None and spec.name in unseen:
                    raise ConfigError(
                        f"config key 'objects.{field_name}[{i}]': {spec.name!r} is an unseen "
                        "category of the split (split.unseen); a train split must not contain it"
                    )
        if len(unseen) >= len(catalogue):
            raise ConfigError("config key 'split.unseen': every object is unseen; nothing to train")
    return split


# ------------------------------------------------------------------------------ composition


def _pool(config: Config, catalogue: Sequence[ObjectSpec], split: Split) -> list[ObjectSpec]:
    """The categories a scene may draw from (the split applied)."""
    if config.objects.categories is not None:
        out = []
        for i, key in enumerate(config.objects.categories):
            spec = _find(catalogue, key)
            if spec is None:
                raise ConfigError(f"config key 'objects.categories[{i}]': unknown object {key!r}")
            if spec not in out:
                out.append(spec)
    else:
        out = list(catalogue)
    if split.name == "train":
        out = [s for s in out if s.name not in split.unseen_names]
    return out


def compose_scene(
    config: Config,
    catalogue: Sequence[ObjectSpec],
    seed: int,
    split: Split,
    target_level: int | None = None,
) -> list[ObjectSpec]:
    """The objects of one scene (drop order), given the split and an optional target level.

    Without a target level this is the config's composition (:func:`mgn.scene.compose_objects`,
    seeded by the scene seed; an ``objects.count`` range draws the scene's count from the scene
    seed too) over the split's pool. A target level 1-4 replaces the config's
    ``count``/``copies`` by :data:`RECIPES` ``[level]`` (object count drawn from the scene seed,
    capped for unique classes at the pool size); level 5 keeps the config's composition. An
    explicit ``objects.names`` list is used as given. A ``test`` split then makes sure an
    unseen category is present (module doc).

    Raises:
        ConfigError: the composition is impossible (e.g. an unknown object).
    """

    if target_level is not None and target_level not in DIFFICULTY_LEVELS:
        raise InvalidArgumentError(f"compose_scene: target_level must be 1..5, got {target_level}")
    obj = config.objects
    if obj.names is not None:
        try:
            return compose_objects(names=list(obj.names), seed=seed, catalogue=catalogue)
        except InvalidArgumentError as e:
            raise ConfigError(f"config key 'objects': {e}") from e
    pool = _pool(config, catalogue, split)
    if not pool:
        raise ConfigError("config key 'objects': no category left to draw from (split.unseen)")
    recipe = RECIPES.get(target_level) if target_level is not None else None
    try:
        if recipe is not None:
            lo, hi, copies = recipe
            assert target_level is not None  # a recipe exists only for a level
            rng = np.random.default_rng([int(seed), _RECIPE_STREAM, int(target_level)])
            count = int(rng.integers(lo, hi + 1))
            if copies == (1, 1):
                count = min(count, len(pool))
            out = compose_objects(
                categories=[s.name for s in pool],
                count=count,
                copies=copies,
                seed=seed,
                catalogue=pool,
            )
        else:
            cat = [s for s in catalogue if s.name not in split.unseen_names]
            cat = cat if split.name == "train" else list(catalogue)
            out = compose_objects(**obj.compose_kwargs(seed), seed=seed, catalogue=cat)
    except InvalidArgumentError as e:
        raise ConfigError(f"config key 'objects': {e}") from e
    if split.name == "test":
        out = _ensure_unseen(out, pool, split, seed)
    return out


def _ensure_unseen(
    objects: list[ObjectSpec], pool: Sequence[ObjectSpec], split: Split, seed: int
) -> list[ObjectSpec]:
    unseen = set(split.unseen_names)
    if not objects or any(s.name in unseen for s in objects):
        return objects
    candidates = [s for s in pool if s.name in unseen]
    if not candidates:
        return objects
    rng = np.random.default_rng([int(seed), _UNSEEN_STREAM])
    pick = candidates[int(rng.integers(len(candidates)))]
    last = objects[-1].name
    k = len(objects)
    while k > 0 and objects[k - 1].name == last:
        k -= 1
    return objects[:k] + [pick] * (len(objects) - k)


# -------------------------------------------------------------------------------- selection


def plan_batch(remaining: Sequence[int], batch_scenes: int) -> list[int]:
    """The target difficulty level of each scene of a batch (ascending), given the views still
    missing per level (index 0 = level 1).

    Every missing level gets one scene (lowest levels first when the batch is smaller than the
    number of missing levels); the other scenes go one by one to the level with the largest
    ``remaining / (scenes given + 1)`` (ties: the lower level). Empty when nothing is missing.
    """
    if batch_scenes < 1:
        raise InvalidArgumentError(f"plan_batch: batch_scenes must be >= 1, got {batch_scenes}")
    missing = [lv for lv, n in zip(DIFFICULTY_LEVELS, remaining, strict=True) if n > 0]
    if not missing:
        return []
    given = dict.fromkeys(missing, 0)
    for lv in missing[:batch_scenes]:
        given[lv] = 1
    for _ in range(batch_scenes - sum(given.values())):
        best = max(missing, key=lambda lv: (remaining[lv - 1] / (given[lv] + 1), -lv))
        given[best] += 1
    return sorted(lv for lv, n in given.items() for _ in range(n))


def view_difficulty(folder: str | os.PathLike[str], view: int) -> int:
    """The difficulty level stored in ``folder/{view}_layout.json``.

    Raises:
        IoError: the file is missing or unreadable, or holds no level 1..5.
    """
    p = Path(folder) / f"{view}_layout.json"
    try:
        d = json.loads(p.read_text(encoding="utf-8"))["difficulty"]
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise IoError(f"cannot read the difficulty of '{p}': {e}") from e
    if isinstance(d, bool) or d not in DIFFICULTY_LEVELS:
        raise IoError(f"'{p}': difficulty must be 1..5, got {d!r}")
    return int(d)


def select_views(
    views: Sequence[tuple[int, int, int]], remaining: Sequence[int]
) -> tuple[list[dict[str, int]], list[dict[str, int]], list[int]]:
    """Keep/reject views in the given order: (scene, view, difficulty) is selected while its
    level still lacks views. Returns (selected, rejected, remaining after)."""
    left = list(remaining)
    selected, rejected = [], []
    for scene, view, d in views:
        entry = {"scene": int(scene), "view": int(view), "difficulty": int(d)}
        if left[d - 1] > 0:
            left[d - 1] -= 1
            selected.append(entry)
        else:
            rejected.append(entry)
    return selected, rejected, left


@dataclass
class SelectionState:
    """Progress of a difficulty-balanced run (recorded in ``dataset.json`` after each batch)."""

    quota: tuple[int, ...]
    batch_scenes: int
    views: list[dict[str, int]]
    rejected: list[dict[str, int]]
    batches_done: int = 0
    pruned: bool = False

    @property
    def remaining(self) -> list[int]:
        left = list(self.quota)
        for e in self.views:
            left[e["difficulty"] - 1] -= 1
        return left

    @property
    def unmet(self) -> dict[str, int]:
        return {
            str(lv): n for lv, n in zip(DIFFICULTY_LEVELS, self.remaining, strict=True) if n > 0
        }

    def to_json(self) -> dict[str, Any]:
        return {
            "quota": {str(lv): int(n) for lv, n in zip(DIFFICULTY_LEVELS, self.quota, strict=True)},
            "views": sorted(self.views, key=lambda e: (e["scene"], e["view"])),
            "rejected": sorted(self.rejected, key=lambda e: (e["scene"], e["view"])),
            "batch_scenes": self.batch_scenes,
            "batches_done": self.batches_done,
            "scenes_generated": self.batches_done * self.batch_scenes,
            "unmet": self.unmet,
            "complete": not self.unmet,
            "pruned": self.pruned,
        }

    @classmethod
    def from_json(
        cls, doc: Mapping[str, Any], quota: tuple[int, ...], batch: int
    ) -> SelectionState:
        """The recorded state of a resumed run (must match ``quota`` and ``batch``)."""
        q = tuple(int(doc.get("quota", {}).get(str(lv), 0)) for lv in DIFFICULTY_LEVELS)
        if q != tuple(quota) or int(doc.get("batch_scenes", -1)) != batch:
            raise InvalidArgumentError(
                "--resume: the recorded selection has another quota or batch size "
                f"({doc.get('quota')}, {doc.get('batch_scenes')}) than the config"
            )
        return cls(
            tuple(quota),
            batch,
            [dict(e) for e in doc.get("views", [])],
            [dict(e) for e in doc.get("rejected", [])],
            int(doc.get("batches_done", 0)),
            bool(doc.get("pruned", False)),
        )


# -------------------------------------------------------------------------------- the run


def _prune(out: Path, rejected: Sequence[Mapping[str, int]]) -> None:
    by_scene: dict[int, list[int]] = {}
    for e in rejected:
        by_scene.setdefault(int(e["scene"]), []).append(int(e["view"]))
    for scene, views in sorted(by_scene.items()):
        prune_scene(out / f"scene{scene}", views)


class SceneOutcome(Protocol):
    """What :func:`run_balanced` reads of one scene's result (:class:`mgn.pipeline.SceneResult`)."""

    @property
    def ok(self) -> bool:
        """The scene was written completely."""
        ...


class BalancedReport(Protocol):
    """The run report that :func:`run_balanced` reads and fills
    (:class:`mgn.pipeline.GenerateReport`)."""

    skipped: list[int]  # scenes already complete (resumed run)
    not_run: list[int]  # scenes not attempted (full disk)
    num_scenes: int  # scenes attempted
    selection: dict[str, Any] | None  # the dataset.json ``selection`` record
    unmet: dict[int, int]  # difficulty level -> views still missing

    @property
    def results(self) -> Mapping[int, SceneOutcome]:
        """The results of the scenes run so far, by scene index."""
        ...


class BalancedRun(Protocol):
    """The run context that :func:`run_balanced` drives: the scene loop of
    :func:`mgn.pipeline.generate`, which labels objects, runs scenes and writes
    ``dataset.json``."""

    @property
    def cfg(self) -> Config:
        """The run's config."""
        ...

    @property
    def seed(self) -> int:
        """The dataset seed (scene ``i`` uses :func:`mgn.pipeline.scene_seed` of it)."""
        ...

    @property
    def out(self) -> Path:
        """The dataset folder."""
        ...

    @property
    def extra(self) -> dict[str, Any]:
        """Extra top-level ``dataset.json`` keys, written by :meth:`write_doc`."""
        ...

    @property
    def report(self) -> BalancedReport:
        """The report of the run."""
        ...

    def ensure_labels(self, specs: Sequence[ObjectSpec]) -> None:
        """Label the objects of ``specs`` not labelled yet in this run."""
        ...

    def run_scenes(self, scenes: Sequence[tuple[int, list[ObjectSpec]]], total: int) -> None:
        """Run the scenes (index, objects); their results go to :attr:`report`."""
        ...

    def write_doc(self, num_scenes: int, status: str) -> None:
        """Write ``dataset.json`` with ``num_scenes`` and ``status``."""
        ...

    def export_missing(self, indices: Sequence[int]) -> None:
        """Write the exports (``output.formats``) the complete scenes ``indices`` lack."""
        ...


def run_balanced(
    run: BalancedRun,
    catalogue: Sequence[ObjectSpec],
    split: Split,
    recorded: Mapping[str, Any] | None,
) -> None:
    """The batch loop of a difficulty-balanced run (called by :func:`mgn.pipeline.generate`
    with its run context; see the module doc). Fills ``run.report`` (``selection``,
    ``unmet``, ``num_scenes``) and records the selection in ``dataset.json`` after each batch.
    ``recorded`` is the ``dataset.json`` of a resumed run (None: a new run).
    """

    cfg, report = run.cfg, run.report
    sel = cfg.selection
    assert sel.quota is not None
    batch = sel.batch_scenes
    state = SelectionState(tuple(sel.quota), batch, [], [], pruned=sel.prune_rejected)
    if isinstance(recorded, Mapping) and isinstance(recorded.get("selection"), Mapping):
        state = SelectionState.from_json(recorded["selection"], tuple(sel.quota), batch)
        state.pruned = sel.prune_rejected
    attempted = state.batches_done * batch
    report.skipped += list(range(attempted))  # recorded batches of a resumed run

    def record(status: str) -> None:
        run.extra["selection"] = state.to_json()
        report.selection = run.extra["selection"]
        report.num_scenes = attempted
        report.unmet = {int(k): v for k, v in state.unmet.items()}
        run.write_doc(attempted, status)

    if sel.prune_rejected and state.rejected:  # finish a pruning a kill interrupted
        _prune(run.out, state.rejected)
    run.export_missing(range(attempted))  # the recorded batches' scenes (pruned first)
    record("running")
    while state.unmet:
        first = state.batches_done * batch
        if first >= sel.max_scenes:
            break
        targets = plan_batch(state.remaining, batch)
        indices = list(range(first, first + batch))
        scenes = [
            (i, compose_scene(cfg, catalogue, scene_seed(run.seed, i), split, t))
            for i, t in zip(indices, targets, strict=True)
        ]
        run.ensure_labels([s for _, specs in scenes for s in specs])
        attempted = first + batch
        run.run_scenes(scenes, attempted)
        if any(not report.results[i].ok for i in indices if i in report.results) or any(
            i in report.not_run for i in indices
        ):
            break  # failures are reported; --resume redoes the batch
        views = []
        for i in indices:
            folder = run.out / f"scene{i}"
            views += [(i, v, view_difficulty(folder, v)) for v in scene_view_ids(folder)]
        chosen, rejected, _ = select_views(views, state.remaining)
        state.views += chosen
        state.rejected += rejected
        state.batches_done += 1
        record("running")
        if sel.prune_rejected and rejected:
            _prune(run.out, rejected)
        run.export_missing(indices)  # after the pruning: the exports hold the views kept
    record("running")


def parse_quota(text: str) -> tuple[int, ...]:
    """``"1=20,2=20,3=20,4=20,5=20"`` -> (20, 20, 20, 20, 20) (missing levels: 0).

    Raises:
        ConfigError: naming ``--difficulty-quota``, the text and the expected form.
    """

    mapping: dict[str, Any] = {}
    for part in str(text).split(","):
        level, sep, n = part.partition("=")
        try:
            count = int(n)
        except ValueError:
            count = None
        if not sep or count is None or level.strip() in mapping:
            raise ConfigError(
                f"--difficulty-quota: expected LEVEL=COUNT,... (e.g. 1=20,2=20,3=20,4=20,5=20) "
                f"with distinct levels, got {text!r}"
            )
        mapping[level.strip()] = count
    try:
        quota: tuple[int, ...] = SelectionConfig.from_dict({"quota": mapping}, "selection").quota
        return quota
    except ConfigError as e:
        raise ConfigError(f"--difficulty-quota {text!r}: {e}") from None
