"""Python dataclasses filled from the result classes of the compiled core, field by field."""

from __future__ import annotations

import dataclasses
from typing import Any, TypeVar

__all__ = ["from_core"]

T = TypeVar("T")


def from_core(cls: type[T], result: object, **extra: Any) -> T:
    """An instance of the dataclass ``cls`` whose fields are the attributes of the same name of
    ``result`` (a class bound in ``mgn._core``), except those given in ``extra``. A field the
    core result lacks is an AttributeError naming it: the two definitions drifted apart."""
    values = dict(extra)
    for f in dataclasses.fields(cls):  # type: ignore[arg-type]
        if f.name not in values:
            values[f.name] = getattr(result, f.name)
    return cls(**values)
