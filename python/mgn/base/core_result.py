"""Python dataclasses and the classes of the compiled core, copied field by field both ways."""

from __future__ import annotations

import dataclasses
from collections.abc import Collection
from typing import Any, TypeVar

from mgn.errors import InvalidArgumentError

__all__ = ["from_core", "to_core"]

T = TypeVar("T")
C = TypeVar("C")


def from_core(cls: type[T], result: object, **extra: Any) -> T:
    """An instance of the dataclass ``cls`` whose fields are the attributes of the same name of
    ``result`` (a class bound in ``mgn._core``), except those given in ``extra``. A field the
    core result lacks is an AttributeError naming it: the two definitions drifted apart."""
    values = dict(extra)
    for f in dataclasses.fields(cls):  # type: ignore[arg-type]
        if f.name not in values:
            values[f.name] = getattr(result, f.name)
    return cls(**values)


def to_core(options: object, core: C, skip: Collection[str] = ()) -> C:
    """``core`` (a default-built options class of ``mgn._core``) with every field of the
    dataclass ``options`` but those in ``skip`` set on it. A value the core cannot take is an
    InvalidArgumentError naming ``<Options>.<field>`` and the expected type; the ranges are the
    core's ``validate()``'s to check."""
    name = type(options).__name__
    for f in dataclasses.fields(options):  # type: ignore[arg-type]
        if f.name in skip:
            continue
        value = getattr(options, f.name)
        try:
            setattr(core, f.name, value)
        except TypeError as e:
            raise InvalidArgumentError(f"{name}.{f.name} must be {f.type}, got {value!r}") from e
    return core
