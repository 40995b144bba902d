"""The seed of each scene of a dataset, derived from the dataset seed (docs/architecture.md).

Scene ``i`` of a dataset with seed ``seed`` uses :func:`scene_seed` (``SCENE_SEED_RULE``), so any
scene can be regenerated alone and the result does not depend on the order or the worker that runs
the scenes.
"""

from __future__ import annotations

import numpy as np

from mgn.errors import InvalidArgumentError

__all__ = ["SCENE_SEED_RULE", "scene_seed"]

SCENE_SEED_RULE = "numpy.random.SeedSequence([seed, i]).generate_state(1, numpy.uint32)[0] >> 1"


def scene_seed(seed: int, index: int) -> int:
    """The seed of scene ``index`` of a dataset with seed ``seed`` (see the module doc)."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InvalidArgumentError(f"scene_seed: seed must be an integer >= 0, got {seed!r}")
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or index < 0:
        raise InvalidArgumentError(f"scene_seed: index must be an integer >= 0, got {index!r}")
    state = np.random.SeedSequence([int(seed), int(index)]).generate_state(1, np.uint32)
    return int(state[0]) >> 1
