#pragma once
/// @file mass_properties.hpp  Volume, centre of mass and inertia of a mesh for a density.

#include <mgn/geometry/mesh.hpp>

namespace mgn {

/// What to do when a mesh is not closed (volume integrals are then not defined).
enum class OpenMeshPolicy {
  Error,  ///< throw InvalidArgument
  Shell,  ///< treat the surface as a thin shell of `shell_thickness` (mass = density*area*t)
};

struct MassOptions {
  double density = 1000.0;  ///< kg/m^3, > 0
  OpenMeshPolicy open_mesh = OpenMeshPolicy::Shell;
  double shell_thickness = 0.002;  ///< m, used by OpenMeshPolicy::Shell, > 0
};

/// Mass properties in the mesh frame O.
struct MassProperties {
  double volume = 0.0;                   ///< m^3 (enclosed volume; for a shell: area * thickness)
  double mass = 0.0;                     ///< kg
  Vec3d center_of_mass = Vec3d::Zero();  ///< p_OCm, m
  /// Inertia tensor about the centre of mass, axes of frame O, kg m^2.
  Mat3d inertia = Mat3d::Zero();
  /// True for a closed mesh (exact integrals); false when the shell fallback was used.
  bool is_exact = false;
};

/// Computes mass properties. Closed, consistently wound meshes use the exact divergence-theorem
/// integrals over signed tetrahedra (a mesh wound inward is handled: its volume is taken
/// positive). Open meshes follow options.open_mesh. Throws InvalidArgument on a non-positive or
/// non-finite density/thickness, an empty mesh, or zero volume.
MassProperties compute_mass_properties(const Mesh& mesh, const MassOptions& options = {});

}  // namespace mgn
