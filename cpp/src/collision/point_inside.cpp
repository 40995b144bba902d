#include <mgn/collision/point_inside.hpp>
#include <mgn/core/error.hpp>
#include <mgn/raytrace/ray_scene.hpp>

#include <algorithm>
#include <limits>

namespace mgn {

Vec3d PointInsideTest::ray_direction() {
  // Off every axis and diagonal, so that rays from points of axis-aligned or symmetric geometry
  // do not run along its edges or faces.
  static const Vec3d d = Vec3d(0.5773, 0.6213, 0.5297).normalized();
  return d;
}

PointInsideTest::PointInsideTest(const Mesh& mesh) {
  if (mesh.empty()) {
    throw_error<InvalidArgument>("PointInsideTest: expected a mesh with faces, got an empty mesh");
  }
  rays_ = std::make_unique<RayScene>(std::vector<RayGeometry>{{&mesh, Pose::Identity(), 0}});
  const auto b = mesh.bounds();
  lo_ = b.row(0).transpose();
  hi_ = b.row(1).transpose();
  // Every crossing is on a distinct face: with this cap no crossing is ever dropped.
  max_hits_ =
      static_cast<int>(std::min<std::int64_t>(mesh.num_faces(), std::numeric_limits<int>::max()));
}

PointInsideTest::~PointInsideTest() = default;

std::vector<std::uint8_t> PointInsideTest::contains_each(const Points3d& points) const {
  const Eigen::Index n = points.rows();
  std::vector<std::uint8_t> inside(static_cast<std::size_t>(n), 0);
  if (!points.allFinite()) {
    throw_error<InvalidArgument>(
        "PointInsideTest::contains: expected finite points (mesh frame, m)");
  }
  // Only points inside the bounding box (bounds included) need a ray.
  std::vector<Eigen::Index> cast;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Vec3d p = points.row(i).transpose();
    if ((p.array() >= lo_.array()).all() && (p.array() <= hi_.array()).all()) cast.push_back(i);
  }
  if (cast.empty()) return inside;
  const auto m = static_cast<Eigen::Index>(cast.size());
  Points3f origins(m, 3), directions(m, 3);
  const Eigen::RowVector3f d = ray_direction().cast<float>().transpose();
  for (Eigen::Index k = 0; k < m; ++k) {
    origins.row(k) = points.row(cast[static_cast<std::size_t>(k)]).cast<float>();
    directions.row(k) = d;
  }
  CastOptions options;
  options.num_threads = 1;
  const RayAllHits hits = rays_->intersect_all(origins, directions, max_hits_, options);
  for (Eigen::Index k = 0; k < m; ++k) {
    const auto crossings = hits.offsets[k + 1] - hits.offsets[k];
    inside[static_cast<std::size_t>(cast[static_cast<std::size_t>(k)])] = crossings % 2 == 1;
  }
  return inside;
}

bool PointInsideTest::contains(const Vec3d& p) const {
  Points3d points(1, 3);
  points.row(0) = p.transpose();
  return contains_each(points)[0] != 0;
}

bool PointInsideTest::contains_any(const Points3d& points) const {
  const std::vector<std::uint8_t> inside = contains_each(points);
  return std::any_of(inside.begin(), inside.end(), [](std::uint8_t v) { return v != 0; });
}

}  // namespace mgn
