"""Procedural object library and tote of mgn.

- :func:`builtin_objects`, :func:`get_object`, :func:`object_names`: the built-in catalogue of
  watertight, textured household and warehouse objects (:class:`ObjectSpec`, SI units, object
  frame at the bounding-box centre, z up).
- :class:`ToteSpec`, :func:`make_tote`, :func:`default_tote`: the bin the objects fall into
  (tote frame at the centre of the inner floor, z up).
- :func:`load_objects_yaml`: user objects from mesh files plus a small YAML file.
- :func:`com_keypoints`: the centre-of-mass keypoints of an object's mesh.

Modules: :mod:`~mgn.objects.spec` (what an object is: :class:`ObjectSpec`, :class:`MaterialSpec`,
:class:`Keypoint`, tags), :mod:`~mgn.objects.library` (the built-in objects, built and cached),
:mod:`~mgn.objects.catalogue` (one builder per built-in object), :mod:`~mgn.objects.blocks` and
:mod:`~mgn.objects.materials` (the builders' parts and materials), :mod:`~mgn.objects.shapes`
and :mod:`~mgn.objects.textures` (meshes and printed textures), :mod:`~mgn.objects.com`
(centre-of-mass keypoints), :mod:`~mgn.objects.tote` and :mod:`~mgn.objects.user`.
"""

from .com import NUM_COM_KEYPOINTS, com_keypoints
from .library import builtin_objects, get_object, object_names
from .spec import ALLOWED_TAGS, Keypoint, MaterialSpec, ObjectSpec
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
    "object_names",
    "tote_mesh",
    "tote_volume",
]
