#pragma once
/// @file types.hpp  Eigen aliases used across the mgn public API.
///
/// Conventions (see docs/architecture.md): SI units (m, kg, s, N, rad). Poses are 4x4 homogeneous
/// transforms in double precision named after their frames, e.g. `X_WO` maps object-frame
/// coordinates to world-frame coordinates. Geometry arrays are float32, row-major (N,3), so they
/// map to numpy without copies.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

namespace mgn {

using Vec2f = Eigen::Vector2f;
using Vec3f = Eigen::Vector3f;
using Vec4f = Eigen::Vector4f;
using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;
using Mat4d = Eigen::Matrix4d;
/// Rigid transform (rotation + translation), double precision.
using Pose = Eigen::Isometry3d;

/// (N,3) float32 row-major array of points or vectors.
using Points3f = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// (N,2) float32 row-major array (texture coordinates).
using Points2f = Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor>;
/// (N,3) double row-major array.
using Points3d = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// (F,3) int32 row-major triangle vertex indices.
using Faces = Eigen::Matrix<std::int32_t, Eigen::Dynamic, 3, Eigen::RowMajor>;

}  // namespace mgn
