"""Choose the objects of a scene: explicit names, categories with 2-5 copies each (MetaGraspNet),
or a total count. Deterministic for a seed."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from mgn.errors import InvalidArgumentError
from mgn.objects import ObjectSpec, builtin_objects

__all__ = ["MGN_COPIES", "compose_objects"]

#: Copies per chosen category in MetaGraspNet: 2 to 5 (inclusive).
MGN_COPIES: tuple[int, int] = (2, 5)


def _lookup(catalogue: Sequence[ObjectSpec], key: str | int) -> ObjectSpec:
    by_name = {s.name: s for s in catalogue}
    by_id = {s.category_id: s for s in catalogue}
    k = key.strip() if isinstance(key, str) else key
    if isinstance(k, str) and k in by_name:
        return by_name[k]
    if isinstance(k, (int, np.integer)) or (isinstance(k, str) and k.isdigit()):
        cid = int(k)
        if cid in by_id:
            return by_id[cid]
    raise InvalidArgumentError(
        f"unknown object {key!r}; valid names: {', '.join(s.name for s in catalogue)}"
    )


def compose_objects(
    *,
    names: Sequence[str | int] | None = None,
    categories: Sequence[str | int] | None = None,
    count: int | None = None,
    copies: tuple[int, int] = MGN_COPIES,
    seed: int = 0,
    catalogue: Sequence[ObjectSpec] | None = None,
) -> list[ObjectSpec]:
    """The objects to drop, in drop order.

    Exactly one way of choosing:

    - ``names``: these objects, as listed (repeat a name for several copies);
    - ``categories``: each gets ``copies`` (min, max) copies drawn uniformly (MetaGraspNet:
      2-5); with ``count``, categories are cycled (in a seeded random order) with their drawn
      copies until ``count`` objects are chosen;
    - ``count`` alone: categories drawn at random from the whole catalogue, each with
      ``copies`` copies, until ``count`` objects are chosen.

    Args:
        catalogue: where names are looked up (default: the built-in objects).
        seed: the choice depends only on the seed and the arguments.

    Raises:
        InvalidArgumentError: no way or two ways of choosing, an empty list, an unknown name,
            ``count`` < 1 or bad ``copies``.
    """
    cat = list(catalogue) if catalogue is not None else list(builtin_objects())
    if not cat:
        raise InvalidArgumentError("compose_objects: the catalogue is empty")
    if names is not None and (categories is not None or count is not None):
        raise InvalidArgumentError("compose_objects: give names, or categories/count, not both")
    if names is not None:
        if len(names) == 0:
            raise InvalidArgumentError("compose_objects: names is empty; expected >= 1 object")
        return [_lookup(cat, n) for n in names]
    if categories is None and count is None:
        raise InvalidArgumentError("compose_objects: give names, categories or count")
    lo, hi = (int(copies[0]), int(copies[1])) if len(copies) == 2 else (0, -1)
    if not 1 <= lo <= hi:
        raise InvalidArgumentError(
            f"compose_objects: copies must be (min, max) with 1 <= min <= max, got {copies!r}"
        )
    if count is not None and (isinstance(count, bool) or int(count) < 1):
        raise InvalidArgumentError(f"compose_objects: count must be >= 1, got {count!r}")
    rng = np.random.default_rng([int(seed), 0x636F6D70])  # own stream for the composition
    if categories is not None:
        if len(categories) == 0:
            raise InvalidArgumentError("compose_objects: categories is empty")
        pool = [_lookup(cat, c) for c in categories]
        if count is None:
            out: list[ObjectSpec] = []
            for spec in pool:
                out += [spec] * int(rng.integers(lo, hi + 1))
            return out
    else:
        pool = list(cat)
    out = []
    while len(out) < int(count):  # type: ignore[arg-type]
        for k in rng.permutation(len(pool)):
            n = int(rng.integers(lo, hi + 1))
            out += [pool[k]] * n
            if len(out) >= int(count):  # type: ignore[arg-type]
                break
    return out[: int(count)]  # type: ignore[arg-type]
