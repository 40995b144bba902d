#pragma once
/// @file sampling.hpp  Points on the surface of a mesh.

#include <mgn/geometry/mesh.hpp>

#include <cstdint>
#include <vector>

namespace mgn {

enum class SampleMethod {
  Random,  ///< area-weighted uniform random points
  Even,    ///< blue-noise: farthest-point selection from an area-weighted candidate pool
};

struct SampleOptions {
  SampleMethod method = SampleMethod::Random;
  std::uint64_t seed = 0;
  /// Even: candidates drawn per requested point (>= 1); more gives more even spacing.
  int oversampling = 6;
};

/// Samples on the surface, in the mesh frame.
struct SurfaceSamples {
  Points3f points;                     ///< (n,3) m
  Points3f normals;                    ///< (n,3) unit outward face normals
  std::vector<std::int32_t> face_ids;  ///< (n) index of the face each point lies on
};

/// Draws `count` points. Deterministic for (mesh, count, options). Throws InvalidArgument for an
/// empty mesh or a negative count.
SurfaceSamples sample_surface(const Mesh& mesh, std::int64_t count,
                              const SampleOptions& options = {});

}  // namespace mgn
