"""Layer 1, geometry: meshes, collision, ray casting and convex decomposition.

- :mod:`mgn.geometry.mesh`: :class:`Mesh`, loading, primitives, mass properties, surface samples.
- :mod:`mgn.geometry.collision`: FCL collision and distance queries.
- :mod:`mgn.geometry.raytrace`: Embree ray casting (:class:`RayScene`, :func:`camera_rays`).
- :mod:`mgn.geometry.convex`: convex hulls and the (cached) convex decomposition physics uses.

The mesh API is re-exported here (``from mgn.geometry import Mesh``) and at the top level.
"""

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
    mesh_from_arrays,
    sample_surface,
)

__all__ = [
    "MassProperties",
    "Material",
    "Mesh",
    "MeshReport",
    "SurfaceSamples",
    "load_mesh",
    "make_box",
    "make_cylinder",
    "make_sphere",
    "mass_properties",
    "mesh_from_arrays",
    "sample_surface",
]
