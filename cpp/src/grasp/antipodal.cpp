// Antipodal robust sampling of parallel-jaw grasps (MODELS.md §5).
#include <mgn/collision/collision_model.hpp>
#include <mgn/core/error.hpp>
#include <mgn/core/parallel.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/grasp/antipodal.hpp>
#include <mgn/raytrace/ray_scene.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>

#include "grasp/detail/seal_trials.hpp"

namespace mgn {

void AntipodalOptions::validate() const {
  auto fail = [](const char* field, double value, const char* expected) {
    throw_error<InvalidArgument>("AntipodalOptions.", field, ": expected ", expected, ", got ",
                                 value);
  };
  if (probes < 1) fail("probes", probes, "an integer >= 1");
  if (!(tilt >= 0.0) || !(tilt < M_PI / 2)) fail("tilt", tilt, "an angle in [0, pi/2) rad");
  if (!(offset >= 0.0) || !std::isfinite(offset)) fail("offset", offset, "a finite value >= 0 m");
  if (!(start_offset > 0.0) || !std::isfinite(start_offset))
    fail("start_offset", start_offset, "a finite value > 0 m");
  if (!(friction_coef > 0.0) || !std::isfinite(friction_coef))
    fail("friction_coef", friction_coef, "a finite value > 0");
  if (approaches_tried < 0) fail("approaches_tried", approaches_tried, "an integer >= 0");
  if (approaches_kept < 0) fail("approaches_kept", approaches_kept, "an integer >= 0");
  if (num_threads < 0) fail("num_threads", num_threads, "0 (all) or a positive thread count");
}

struct AntipodalSampler::Impl {
  ParallelJawGripper gripper;
  std::unique_ptr<RayScene> scene;
  std::unique_ptr<CollisionModel> object;
  // Gripper parts at opening 0 in the hand frame: palm, left finger, right finger.
  std::array<std::unique_ptr<CollisionModel>, 3> parts;
  std::array<Vec3d, 3> part_vertex;  // one vertex of each part (for the inside test), frame H
};

AntipodalSampler::AntipodalSampler(const Mesh& object, const ParallelJawGripper& gripper)
    : impl_(std::make_unique<Impl>()) {
  require_non_empty(object, "AntipodalSampler");
  const MeshReport report = object.validate();
  if (!report.is_watertight) {
    throw_error<InvalidArgument>(
        "AntipodalSampler: the object mesh '", object.name(), "' has no closed volume (",
        report.num_boundary_edges, " boundary and ", report.num_nonmanifold_edges,
        " non-manifold edges); expected a watertight mesh (antipodal probes need an inside)");
  }
  gripper.validate();
  impl_->gripper = gripper;
  impl_->scene =
      std::make_unique<RayScene>(std::vector<RayGeometry>{{&object, Pose::Identity(), 0}});
  impl_->object = std::make_unique<CollisionModel>(object);
  const GripperMeshes meshes = gripper_meshes(gripper, 0.0);
  const std::array<const Mesh*, 3> parts = {&meshes.palm, &meshes.finger_left,
                                            &meshes.finger_right};
  for (int k = 0; k < 3; ++k) {
    impl_->parts[k] = std::make_unique<CollisionModel>(*parts[k]);
    impl_->part_vertex[k] = parts[k]->vertices().row(0).transpose().cast<double>();
  }
}

AntipodalSampler::~AntipodalSampler() = default;

const ParallelJawGripper& AntipodalSampler::gripper() const { return impl_->gripper; }

namespace {

/// Rotation by Euler angles about x, then y, then z (fixed axes): Rz * Ry * Rx.
Mat3d euler_xyz(double ax, double ay, double az) {
  return (Eigen::AngleAxisd(az, Vec3d::UnitZ()) * Eigen::AngleAxisd(ay, Vec3d::UnitY()) *
          Eigen::AngleAxisd(ax, Vec3d::UnitX()))
      .toRotationMatrix();
}

// A fixed direction off every axis and diagonal, for the ray-parity inside test.
const Vec3d kParityDirection = Vec3d(0.5773, 0.6213, 0.5297).normalized();

}  // namespace

bool AntipodalSampler::collides(const Pose& X_OH, double opening) const {
  const Impl& m = *impl_;
  if (!X_OH.matrix().allFinite()) {
    throw_error<InvalidArgument>("AntipodalSampler::collides: X_OH must be finite");
  }
  if (!std::isfinite(opening) || opening < 0.0 || opening > m.gripper.max_opening + 1e-12) {
    throw_error<InvalidArgument>("AntipodalSampler::collides: opening must be in [0, ",
                                 m.gripper.max_opening, "] m, got ", opening);
  }
  const std::array<Pose, 3> X = {X_OH, X_OH * finger_offset(0, opening),
                                 X_OH * finger_offset(1, opening)};
  // Fingers first: they are the parts nearest to the object.
  for (int k : {1, 2, 0}) {
    if (collide(*m.parts[k], X[k], *m.object, Pose::Identity())) return true;
  }
  // No surface contact: a part is either fully outside or fully inside the closed object.
  Points3f origins(3, 3), directions(3, 3);
  for (int k = 0; k < 3; ++k) {
    origins.row(k) = (X[k] * m.part_vertex[k]).cast<float>().transpose();
    directions.row(k) = kParityDirection.cast<float>().transpose();
  }
  CastOptions cast;
  cast.num_threads = 1;
  const RayAllHits hits = m.scene->intersect_all(origins, directions, 1024, cast);
  for (int k = 0; k < 3; ++k) {
    if ((hits.offsets[k + 1] - hits.offsets[k]) % 2 == 1) return true;
  }
  return false;
}

AntipodalResult AntipodalSampler::sample(const Points3d& points, const Points3d& normals,
                                         const AntipodalOptions& o) const {
  o.validate();
  const Impl& m = *impl_;
  const Eigen::Index n = points.rows();
  if (normals.rows() != n) {
    throw_error<InvalidArgument>("sample_antipodal_grasps: points has ", n,
                                 " rows but normals has ", normals.rows(),
                                 "; expected the same count");
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!points.row(i).allFinite() || !normals.row(i).allFinite() ||
        !(normals.row(i).norm() > 1e-12)) {
      throw_error<InvalidArgument>("sample_antipodal_grasps: point/normal ", i,
                                   " is not finite or the normal is zero; expected finite points "
                                   "and non-zero normals");
    }
  }
  const ParallelJawGripper& g = m.gripper;
  const double cos_cone = std::cos(std::atan(o.friction_coef));
  const int P = o.probes;

  AntipodalResult out;
  out.point_score.assign(static_cast<std::size_t>(n), 0.0f);
  out.num_kept.assign(static_cast<std::size_t>(n), 0);
  std::vector<std::vector<AntipodalGrasp>> per_point(static_cast<std::size_t>(n));
  std::vector<std::int32_t> accepted_count(static_cast<std::size_t>(n), 0);
  std::vector<std::int64_t> colliding(static_cast<std::size_t>(n), 0);

  parallel_for(
      static_cast<std::size_t>(n), o.num_threads, 16, [&](std::size_t begin, std::size_t end) {
        const auto count = static_cast<Eigen::Index>(end - begin);
        // 1. Probes of the whole chunk, drawn per point from its own stream, cast in one batch.
        std::vector<Rng> rngs;
        rngs.reserve(end - begin);
        Points3f origins(count * P, 3), directions(count * P, 3);
        Points3d origins_d(count * P, 3), directions_d(count * P, 3);
        for (std::size_t i = begin; i < end; ++i) {
          rngs.emplace_back(o.seed, o.first_index + i);
          Rng& rng = rngs.back();
          const Vec3d p = points.row(i).transpose();
          const Vec3d nrm = normals.row(i).transpose().normalized();
          for (int k = 0; k < P; ++k) {
            const double ax = rng.uniform(-o.tilt, o.tilt);
            const double ay = rng.uniform(-o.tilt, o.tilt);
            const double az = rng.uniform(-o.tilt, o.tilt);
            Vec3d shift;
            for (int c = 0; c < 3; ++c) shift[c] = rng.uniform(-o.offset, o.offset);
            const Vec3d d = (euler_xyz(ax, ay, az) * -nrm).normalized();
            const Vec3d start = p + shift - o.start_offset * d;
            const Eigen::Index r = static_cast<Eigen::Index>(i - begin) * P + k;
            origins_d.row(r) = start.transpose();
            directions_d.row(r) = d.transpose();
          }
        }
        origins = origins_d.cast<float>();
        directions = directions_d.cast<float>();
        CastOptions cast;
        cast.num_threads = 1;
        const RayAllHits hits = m.scene->intersect_all(origins, directions, 2, cast);

        // 2. Per point: antipodal test of each probe, then approaches and collision.
        for (std::size_t i = begin; i < end; ++i) {
          Rng& rng = rngs[i - begin];
          std::vector<ParallelJawGrasp> accepted;
          std::vector<int> accepted_probe;
          for (int k = 0; k < P; ++k) {
            const Eigen::Index r = static_cast<Eigen::Index>(i - begin) * P + k;
            const std::int64_t h0 = hits.offsets[r];
            if (hits.offsets[r + 1] - h0 < 2) continue;
            const Vec3d start = origins.row(r).transpose().cast<double>();
            const Vec3d d = directions.row(r).transpose().cast<double>();
            const Vec3d q1 = start + static_cast<double>(hits.distance[h0]) * d;
            const Vec3d q2 = start + static_cast<double>(hits.distance[h0 + 1]) * d;
            const double w = (q2 - q1).norm();
            if (!(w > 1e-9) || !(w < g.max_opening)) continue;
            const Vec3d v = (q2 - q1) / w;
            const Vec3d n1 = hits.normals.row(h0).transpose().cast<double>().normalized();
            const Vec3d n2 = hits.normals.row(h0 + 1).transpose().cast<double>().normalized();
            if (-n1.dot(v) < cos_cone || n2.dot(v) < cos_cone) continue;
            ParallelJawGrasp grasp;
            grasp.p1 = q1;
            grasp.closing = v;
            grasp.width = w;
            accepted.push_back(grasp);
            accepted_probe.push_back(k);
          }
          const float score = static_cast<float>(accepted.size()) / static_cast<float>(P);
          out.point_score[i] = score;
          accepted_count[i] = static_cast<std::int32_t>(accepted.size());
          std::vector<AntipodalGrasp>& kept = per_point[i];
          for (std::size_t j = 0; j < accepted.size(); ++j) {
            ParallelJawGrasp grasp = accepted[j];
            Vec3d e1, e2;
            detail::tangent_frame(grasp.closing, e1, e2);
            const double opening = g.collision_opening(grasp.width);
            int num_kept = 0;
            // All angles are drawn even when the loop stops early, so the stream of the next probe
            // does not depend on collision outcomes.
            std::vector<double> angles(static_cast<std::size_t>(o.approaches_tried));
            for (double& t : angles) t = rng.uniform(0.0, 2.0 * M_PI);
            for (double t : angles) {
              if (num_kept >= o.approaches_kept) break;
              grasp.approach = (std::cos(t) * e1 + std::sin(t) * e2).normalized();
              if (o.check_collision && collides(hand_pose(grasp, g), opening)) {
                ++colliding[i];
                continue;
              }
              kept.push_back({grasp, static_cast<std::int64_t>(i), accepted_probe[j], score});
              ++num_kept;
            }
          }
          out.num_kept[i] = static_cast<std::int32_t>(kept.size());
        }
      });

  std::size_t total = 0;
  for (const auto& v : per_point) total += v.size();
  out.grasps.reserve(total);
  for (std::size_t i = 0; i < per_point.size(); ++i) {
    out.grasps.insert(out.grasps.end(), per_point[i].begin(), per_point[i].end());
    out.num_accepted_probes += accepted_count[i];
    out.num_colliding += colliding[i];
  }
  return out;
}

AntipodalResult sample_antipodal_grasps(const Mesh& object, const Points3d& points,
                                        const Points3d& normals, const ParallelJawGripper& gripper,
                                        const AntipodalOptions& options) {
  options.validate();
  return AntipodalSampler(object, gripper).sample(points, normals, options);
}

}  // namespace mgn
