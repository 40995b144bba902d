"""The built-in object library: the catalogue's objects built, finished and cached, and looked up
by name or category id.

Every built-in :class:`ObjectSpec` comes from one builder of :mod:`mgn.objects.catalogue`; it is
re-centred on its bounding-box centre (the object frame), gets its size tags
(:func:`mgn.objects.spec.size_tags`) and, when printed, its texture and the ``textured`` tag.
The library is built on first use and cached; the build is deterministic, so every call in
every process returns the same bytes. Category ids are 1..N in catalogue order.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from mgn.errors import InvalidTypeError

from .catalogue import Entry, catalogue_entries
from .spec import Keypoint, ObjectSpec, size_tags

__all__ = ["builtin_objects", "get_object", "object_names"]


def _finish(category_id: int, entry: Entry) -> ObjectSpec:
    built = entry.build()
    mesh = built.mesh
    centre = 0.5 * (mesh.vertices.min(axis=0) + mesh.vertices.max(axis=0))
    vertices = mesh.vertices - centre
    keypoints = tuple(
        Keypoint(k + 1, name, tuple(float(c) for c in np.asarray(pos) - centre))  # type: ignore[arg-type]
        for k, (name, pos) in enumerate(built.keypoints)
    )
    material = entry.material
    tags = set(entry.tags) | size_tags(vertices.max(axis=0) - vertices.min(axis=0))
    if built.texture is not None:
        material = dataclasses.replace(material, texture=built.texture)
        tags.add("textured")
    return ObjectSpec(
        category_id=category_id,
        name=entry.name,
        description=entry.description,
        vertices=vertices,
        faces=mesh.faces,
        uvs=mesh.uvs if built.texture is not None else None,
        material=material,
        density=entry.density,
        friction=entry.friction,
        keypoints=keypoints,
        tags=frozenset(tags),
    )


@functools.lru_cache(maxsize=1)
def builtin_objects() -> tuple[ObjectSpec, ...]:
    """All built-in objects in category-id order (ids 1..N). Built once, then cached."""
    return tuple(_finish(i + 1, e) for i, e in enumerate(catalogue_entries()))


def object_names() -> list[str]:
    """Names of the built-in objects in category-id order (cheap: does not build meshes)."""
    return [e.name for e in catalogue_entries()]


def get_object(name_or_id: str | int) -> ObjectSpec:
    """Look up a built-in object by name (``"mug"``) or category id (``12`` or ``"12"``).

    Raises:
        KeyError: unknown name or id (the message lists the valid names).
        TypeError: ``name_or_id`` is neither a str nor an int.
    """
    names = object_names()
    if isinstance(name_or_id, bool) or not isinstance(name_or_id, (str, int, np.integer)):
        raise InvalidTypeError(
            "get_object expects a name (str) or a category id (int), "
            f"got {type(name_or_id).__name__}"
        )
    if isinstance(name_or_id, str) and not name_or_id.strip().isdigit():
        if name_or_id not in names:
            raise KeyError(f"unknown object name {name_or_id!r}; valid names: {', '.join(names)}")
        return builtin_objects()[names.index(name_or_id)]
    cid = int(name_or_id)
    if not 1 <= cid <= len(names):
        raise KeyError(
            f"unknown object id {name_or_id!r}: valid ids are 1..{len(names)} ({', '.join(names)})"
        )
    return builtin_objects()[cid - 1]
