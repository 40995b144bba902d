"""Procedural object library and tote of mgn.

- :func:`builtin_objects`, :func:`get_object`, :func:`object_names`: the built-in catalogue of
  watertight, textured household and warehouse objects (:class:`ObjectSpec`, SI units, object
  frame at the bounding-box centre, z up).
- :class:`ToteSpec`, :func:`make_tote`, :func:`default_tote`: the bin the objects fall into
  (tote frame at the centre of the inner floor, z up).
"""

from .library import (
    ALLOWED_TAGS,
    Keypoint,
    MaterialSpec,
    ObjectSpec,
    builtin_objects,
    get_object,
    object_names,
)
from .tote import ToteSpec, default_tote, make_tote, tote_volume

__all__ = [
    "ALLOWED_TAGS",
    "Keypoint",
    "MaterialSpec",
    "ObjectSpec",
    "ToteSpec",
    "builtin_objects",
    "default_tote",
    "get_object",
    "make_tote",
    "object_names",
    "tote_volume",
]
