"""Procedural object library and tote of mgn.

- :func:`builtin_objects`, :func:`get_object`, :func:`object_names`: the built-in catalogue of
  watertight, textured household and warehouse objects (:class:`ObjectSpec`, SI units, object
  frame at the bounding-box centre, z up).
- :class:`ToteSpec`, :func:`make_tote`, :func:`default_tote`: the bin the objects fall into
  (tote frame at the centre of the inner floor, z up).
- :func:`load_objects_yaml`: user objects from mesh files plus a small YAML file.
"""

from .library import (
    ALLOWED_TAGS,
    NUM_COM_KEYPOINTS,
    Keypoint,
    MaterialSpec,
    ObjectSpec,
    builtin_objects,
    com_keypoints,
    get_object,
    object_names,
)
from .tote import ToteSpec, default_tote, make_tote, tote_mesh, tote_volume
from .user import load_objects_yaml

__all__ = [
    "ALLOWED_TAGS",
    "NUM_COM_KEYPOINTS",
    "Keypoint",
    "MaterialSpec",
    "ObjectSpec",
    "ToteSpec",
    "builtin_objects",
    "com_keypoints",
    "default_tote",
    "get_object",
    "load_objects_yaml",
    "make_tote",
    "tote_mesh",
    "object_names",
    "tote_volume",
]
