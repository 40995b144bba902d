"""mgn: bin-picking datasets with ambidextrous grasp labels, synthesised on the CPU.

The public API is typed and documented here; the compiled core (``mgn._core``) is private.
Units are SI (m, kg, s, N, rad); poses are (4, 4) float64 homogeneous transforms named after
their frames, e.g. ``X_WO`` is the pose of object O in the world W.
"""

from typing import TYPE_CHECKING

from mgn import _core

if getattr(_core, "__file__", None) is None:  # only the stub folder python/mgn/_core/ was found
    raise ImportError(
        f"mgn's compiled core (mgn/_core*.so) is missing beside {__file__}: install mgn with "
        "`pip install .` or copy the built bindings/_core*.so into python/mgn/"
    )

from mgn._core import __version__
from mgn.base.lazy import lazy_exports
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

#: The dataset pipeline and the scene, imported on first use (``import mgn`` stays light):
#: ``mgn.generate(out, scenes, config=...)``, ``mgn.load_config(path)``, ``mgn.Config``,
#: ``mgn.drop_scene(objects, seed=...)``, ``mgn.Scene``.
_EXPORTS = {
    "generate": "pipeline.runner",
    "GenerateReport": "pipeline.report",
    "Config": "pipeline.config",
    "load_config": "pipeline.config",
    "Scene": "scene.scene",
    "drop_scene": "scene.drop",
}

__getattr__, __dir__ = lazy_exports("mgn", _EXPORTS, globals())

if TYPE_CHECKING:
    from mgn.pipeline.config import Config, load_config
    from mgn.pipeline.report import GenerateReport
    from mgn.pipeline.runner import generate
    from mgn.scene.drop import drop_scene
    from mgn.scene.scene import Scene

__all__ = [
    "BackendError",
    "CameraView",
    "CollisionModel",
    "Config",
    "Dataset",
    "DistanceResult",
    "GenerateReport",
    "Intrinsics",
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
    "Renderer",
    "Scene",
    "SurfaceSamples",
    "UnsupportedError",
    "__version__",
    "build_info",
    "camera_rays",
    "collide",
    "convex_decomposition",
    "convex_hull",
    "distance",
    "drop_scene",
    "generate",
    "load_config",
    "load_mesh",
    "make_box",
    "make_cylinder",
    "make_sphere",
    "mass_properties",
    "mgn_rig",
    "render_views",
    "sample_surface",
]


def build_info() -> dict[str, str]:
    """Versions of mgn and of every C++ library the core was built against."""

    return dict(_core.core.build_info())
