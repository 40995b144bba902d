#pragma once
/// @file mesh_io.hpp  Loading meshes from files (assimp).

#include <mgn/geometry/mesh.hpp>

#include <string>

namespace mgn {

/// Options for load_mesh().
struct LoadOptions {
  /// Multiplies every coordinate, e.g. 0.001 for a file in millimetres (result in metres).
  double scale = 1.0;
  /// Merge all sub-meshes (with their node transforms applied) into one mesh. When false, only
  /// files with a single mesh are accepted.
  bool merge = true;
  /// Remove zero-area faces found in the file. When false, such a file is rejected.
  bool drop_degenerate = true;
};

/// Loads OBJ, STL, PLY, GLB/GLTF, DAE (anything assimp reads) into one mesh in metres.
/// Texture coordinates and the first material of each sub-mesh (base colour, texture image,
/// specular, shininess, opacity) are kept. Throws IoError if the file is missing, unreadable or
/// not a mesh; InvalidArgument if it holds no triangles, non-finite vertices, or degenerate faces
/// with drop_degenerate = false; every message names the path.
Mesh load_mesh(const std::string& path, const LoadOptions& options = {});

}  // namespace mgn
