"""mgn: bin-picking datasets with ambidextrous grasp labels, synthesised on the CPU.

The public API is typed and documented here; the compiled core (``mgn._core``) is private.
Units are SI (m, kg, s, N, rad); poses are (4, 4) float64 homogeneous transforms named after
their frames, e.g. ``X_WO`` is the pose of object O in the world W.
"""

from mgn import _core
from mgn._core import __version__
from mgn.errors import BackendError, InvalidArgumentError, IoError, MgnError, UnsupportedError
from mgn.geometry.collision import CollisionModel, DistanceResult, collide, distance
from mgn.geometry.convex import convex_decomposition, convex_hull
from mgn.geometry.mesh import (
    MassProperties,
    Material,
    Mesh,
    MeshReport,
    SurfaceSamples,
    load_mesh,
    make_box,
    make_cylinder,
    make_sphere,
    mass_properties,
    sample_surface,
)
from mgn.geometry.raytrace import RayAllHits, RayHits, RayScene, camera_rays
from mgn.io.dataset import Dataset
from mgn.io.view_images import render_views
from mgn.render import Renderer
from mgn.scene.cameras import CameraView, Intrinsics, mgn_rig

__all__ = [
    "__version__",
    "BackendError",
    "CameraView",
    "Intrinsics",
    "Renderer",
    "mgn_rig",
    "render_views",
    "CollisionModel",
    "Dataset",
    "DistanceResult",
    "InvalidArgumentError",
    "IoError",
    "MassProperties",
    "Material",
    "Mesh",
    "MeshReport",
    "MgnError",
    "RayAllHits",
    "RayHits",
    "RayScene",
    "SurfaceSamples",
    "UnsupportedError",
    "build_info",
    "camera_rays",
    "collide",
    "convex_decomposition",
    "convex_hull",
    "distance",
    "load_mesh",
    "make_box",
    "make_cylinder",
    "make_sphere",
    "mass_properties",
    "sample_surface",
]


def build_info() -> dict[str, str]:
    """Versions of mgn and of every C++ library the core was built against."""

    return dict(_core.build_info())
