#pragma once
/// @file primitives.hpp  Closed, outward-wound analytic shapes (for tests, totes, tools).
/// All are centred at the origin of their frame; units metres.

#include <mgn/geometry/mesh.hpp>

namespace mgn {

/// Axis-aligned box with edge lengths (x, y, z) > 0; 12 triangles.
Mesh make_box(const Vec3d& extents);
/// UV sphere of `radius`; `segments` around the z axis (>= 3), `rings` from pole to pole (>= 2).
Mesh make_sphere(double radius, int segments = 64, int rings = 32);
/// Cylinder along z of `radius` and `height`, `segments` around the axis (>= 3), capped.
Mesh make_cylinder(double radius, double height, int segments = 64);

}  // namespace mgn
