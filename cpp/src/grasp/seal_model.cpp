// SealModel: batch evaluation, trial perturbations and the force-based spring-mass model
// (docs/models.md §1). The two baselines live in seal_baselines.cpp.
#include <mgn/core/error.hpp>
#include <mgn/core/parallel.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/grasp/seal_model.hpp>
#include <mgn/raytrace/ray_scene.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <utility>

#include "grasp/detail/seal_trials.hpp"
#include "raytrace/parallel_rays.hpp"

namespace mgn {

const char* failure_name(SealFailure f) {
  switch (f) {
    case SealFailure::None:
      return "none";
    case SealFailure::Miss:
      return "miss";
    case SealFailure::Obstruction:
      return "obstruction";
    case SealFailure::Hill:
      return "hill";
    case SealFailure::Hole:
      return "hole";
    case SealFailure::Force:
      return "force";
    case SealFailure::Strain:
      return "strain";
    case SealFailure::Rough:
      return "rough";
  }
  return "unknown";
}

namespace detail {

void tangent_frame(const Vec3d& n, Vec3d& u, Vec3d& v) {
  // Branch-free orthonormal basis (Duff et al. 2017); continuous except at n.z = -1.
  const double sign = std::copysign(1.0, n.z());
  const double a = -1.0 / (sign + n.z());
  const double b = n.x() * n.y() * a;
  u = Vec3d(1.0 + sign * n.x() * n.x() * a, sign * b, -sign * n.x());
  v = Vec3d(b, sign + n.y() * n.y() * a, -n.y());
}

std::vector<Eigen::Vector2d> unit_ring(int num_points) {
  std::vector<Eigen::Vector2d> ring(static_cast<std::size_t>(num_points) + 1);
  for (int k = 0; k < num_points; ++k) {
    const double phi = (k + 0.5) * 2.0 * M_PI / num_points;
    ring[k] = Eigen::Vector2d(std::cos(phi), std::sin(phi));
  }
  ring[num_points] = Eigen::Vector2d::Zero();
  return ring;
}

HoleWalker::HoleWalker(const Mesh& mesh)
    : vertices_(mesh.vertices().cast<double>()), faces_(mesh.faces()) {
  const Eigen::Index nv = vertices_.rows(), nf = faces_.rows();
  // Vertices at the same position share one id, so that faces meeting at a seam of duplicated
  // vertices (e.g. where a texture or material region ends) are still neighbours.
  std::vector<std::int32_t> order(static_cast<std::size_t>(nv));
  for (Eigen::Index i = 0; i < nv; ++i) order[i] = static_cast<std::int32_t>(i);
  const Points3f& vf = mesh.vertices();
  auto less = [&](std::int32_t i, std::int32_t j) {
    for (int k = 0; k < 3; ++k) {
      if (vf(i, k) != vf(j, k)) return vf(i, k) < vf(j, k);
    }
    return i < j;
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<std::uint32_t> weld(static_cast<std::size_t>(nv));
  for (std::size_t r = 0; r < order.size(); ++r) {
    const bool same = r > 0 && vf.row(order[r]) == vf.row(order[r - 1]);
    weld[order[r]] = same ? weld[order[r - 1]] : static_cast<std::uint32_t>(order[r]);
  }
  // Every directed edge keyed by its unordered (welded) vertex pair; a pair shared by exactly
  // two faces links them.
  neighbour_ = Faces::Constant(nf, 3, -1);
  std::vector<std::pair<std::uint64_t, std::int64_t>> edges;
  edges.reserve(static_cast<std::size_t>(3 * nf));
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = weld[faces_(f, k)];
      const std::uint32_t b = weld[faces_(f, (k + 1) % 3)];
      if (a == b) continue;  // degenerate edge
      const std::uint64_t key = (static_cast<std::uint64_t>(std::min(a, b)) << 32) | std::max(a, b);
      edges.emplace_back(key, 3 * f + k);
    }
  }
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    if (j - i == 2) {
      const std::int64_t e0 = edges[i].second, e1 = edges[i + 1].second;
      neighbour_(e0 / 3, e0 % 3) = static_cast<std::int32_t>(e1 / 3);
      neighbour_(e1 / 3, e1 % 3) = static_cast<std::int32_t>(e0 / 3);
    }
    i = j;
  }
  max_abs_coord_ = vertices_.size() > 0 ? vertices_.cwiseAbs().maxCoeff() : 0.0;
  edge_length_.resize(nf, 3);
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      edge_length_(f, k) =
          (vertices_.row(faces_(f, (k + 1) % 3)) - vertices_.row(faces_(f, k))).norm();
    }
  }
}

namespace {

/// One face projected along the ray direction onto the plane of the ray origins (see
/// HoleWalker): a point (x, y) of that plane lies on the side of the face of edge k (vertex k to
/// k + 1) when a[k] x + b[k] y + c[k] > 0 (|e_k| times its distance from the edge), and is
/// proven when that value exceeds t[k] = margin |e_k|_3D >= margin |e_k| for every edge (the
/// projection shortens the edges). t is infinite when the face proves nothing (degenerate in
/// projection, or not wholly in front of the origins).
struct ProjectedFace {
  int face = -1;
  double a[3] = {0, 0, 0}, b[3] = {0, 0, 0}, c[3] = {0, 0, 0}, t[3] = {0, 0, 0};

  void load(const Points3d& vertices, const Faces& faces, const Points3d& edge_length,
            const ParallelRays& rays, int f, double margin) {
    face = f;
    double x[3], y[3];
    double depth_min = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
      const Vec3d w = vertices.row(faces(f, k)).transpose() - rays.base;
      x[k] = w.dot(rays.u);
      y[k] = w.dot(rays.v);
      depth_min = std::min(depth_min, w.dot(rays.dir));
    }
    const double area2 = (x[1] - x[0]) * (y[2] - y[1]) - (y[1] - y[0]) * (x[2] - x[1]);
    const double sign = area2 > 0.0 ? 1.0 : -1.0;
    const bool ok = area2 != 0.0 && depth_min > margin;
    for (int k = 0; k < 3; ++k) {
      const int l = (k + 1) % 3;
      const double ex = x[l] - x[k], ey = y[l] - y[k];
      // sign * cross(e, p - q_k)
      a[k] = -ey * sign;
      b[k] = ex * sign;
      c[k] = (ey * x[k] - ex * y[k]) * sign;
      t[k] = ok ? margin * edge_length(f, k) : std::numeric_limits<double>::infinity();
    }
  }
};

}  // namespace

bool HoleWalker::all_hit(const RayScene& scene, const ParallelRays& rays, int start_face) const {
  const double margin = 1e-5 * (max_abs_coord_ + rays.base.cwiseAbs().maxCoeff());
  constexpr int kMaxSteps = 32;
  std::vector<Eigen::Vector2d> rest;
  const bool have = start_face >= 0 && start_face < faces_.rows();
  // Projected faces, direct-mapped by face index (a walk revisits the faces of the disc).
  constexpr int kCache = 64;
  std::array<ProjectedFace, kCache> cache;
  auto get = [&](int f) -> const ProjectedFace& {
    ProjectedFace& slot = cache[static_cast<std::size_t>(f) % kCache];
    if (slot.face != f) slot.load(vertices_, faces_, edge_length_, rays, f, margin);
    return slot;
  };
  int cur = start_face, good = start_face;
  for (int i = 0; i < rays.count; ++i) {
    const Eigen::Vector2d p = rays.scale * rays.offsets[i];
    bool proven = false;
    if (have) {
      int previous = -1;
      bool relocated = false;
      for (int step = 0;; ++step) {
        const ProjectedFace& pf = get(cur);
        double d[3];
        for (int k = 0; k < 3; ++k) d[k] = pf.a[k] * p.x() + pf.b[k] * p.y() + pf.c[k];
        if (d[0] > pf.t[0] && d[1] > pf.t[1] && d[2] > pf.t[2]) {
          proven = true;
          break;
        }
        // Not proven here: walk across the edge p lies (farthest) beyond; none: p is inside
        // but within the margin of an edge, or the face proves nothing.
        const int k = d[0] <= d[1] ? (d[0] <= d[2] ? 0 : 2) : (d[1] <= d[2] ? 1 : 2);
        if (!(d[k] < 0.0)) break;
        int next = neighbour_(cur, k);
        if (next < 0 || next == previous || step >= kMaxSteps) {
          // The walk is stuck (a mesh boundary, a non-manifold edge, a fold seen edge-on): find
          // the face this ray hits first and walk on from there (once per ray). The ray itself
          // stays unproven unless that face proves it.
          if (relocated) break;
          relocated = true;
          ParallelRays one = rays;
          one.offsets = &rays.offsets[i];
          one.count = 1;
          float t_hit;
          Vec3f normal;
          parallel_first_hits(scene, one, &t_hit, &normal, &next);
          if (next < 0 || next == cur) break;
          previous = -1;
          step = 0;
        } else {
          previous = cur;
        }
        cur = next;
      }
      if (proven) {
        good = cur;
      } else {
        cur = good;
      }
    }
    if (!proven) rest.push_back(rays.offsets[i]);
  }
  if (rest.empty()) return true;
  ParallelRays traced = rays;
  traced.offsets = rest.data();
  traced.count = static_cast<int>(rest.size());
  return parallel_all_hit(scene, traced);
}

SealFailure spring_trial(const SealContext& ctx, const Vec3d& c, const Vec3d& n, SealTrial* detail,
                         const Vec3d* nominal) {
  const Cup& cup = ctx.cup;
  const int N = cup.num_points;
  const double r = cup.radius;
  Vec3d u, v;
  tangent_frame(n, u, v);

  // 1-2. Ring (and centre) projected onto the surface along -n from the approach height.
  std::vector<Eigen::Vector2d> own_ring;
  if (ctx.ring_pattern == nullptr) own_ring = unit_ring(N);
  const std::vector<Eigen::Vector2d>& ring = ctx.ring_pattern ? *ctx.ring_pattern : own_ring;
  const Vec3d lift_base = c + cup.approach_height * n;
  ParallelRays rays{lift_base, u, v, -n, ring.data(), N + 1, r};
  std::vector<float> t(static_cast<std::size_t>(N) + 1);
  std::vector<Vec3f> m(static_cast<std::size_t>(N) + 1);
  std::vector<int> face(static_cast<std::size_t>(N) + 1);
  parallel_first_hits(ctx.scene, rays, t.data(), m.data(), face.data());
  for (int k = 0; k < N; ++k) {
    if (!std::isfinite(t[k])) return SealFailure::Miss;
  }
  // Projected points rebuilt in double from the exact ray origins and the hit distances, so the
  // chord lengths carry no float32 coordinate noise (a plane gives exactly zero stretch).
  Points3d x(N, 3);
  Eigen::VectorXd s(N);
  for (int k = 0; k < N; ++k) {
    const Vec3d origin = lift_base + r * (ring[k].x() * u + ring[k].y() * v);
    x.row(k) = (origin - static_cast<double>(t[k]) * n).transpose();
    s[k] = x.row(k).dot(n.transpose());
  }
  const bool centre_hit = std::isfinite(t[N]);
  const double s_c = centre_hit ? lift_base.dot(n) - t[N] : 0.0;
  if (detail) {
    detail->ring_points = x.cast<float>();
    detail->ring_normals.resize(N, 3);
    for (int k = 0; k < N; ++k) detail->ring_normals.row(k) = m[k].transpose();
    detail->center = centre_hit ? Vec3d(lift_base - t[N] * n) : Vec3d(c);
  }

  // 3a. Obstruction: material above the ring, or the centre ray stopped by material standing
  //     more than the compensable height above the (nominal) contact point (a roof below the
  //     cup). Measured from the unperturbed contact: the jitter moves the cup, not the surface.
  ParallelRays up{lift_base, u, v, n, ring.data(), N, r};
  if (parallel_any_hit(ctx.scene, up)) return SealFailure::Obstruction;
  const Vec3d& c_roof = nominal ? *nominal : c;
  if (centre_hit && s_c - c_roof.dot(n) > cup.compensable_height) return SealFailure::Obstruction;

  // 3b. Hill: the centre sticks up above the lowest ring point by more than h.
  if (centre_hit && s_c - s.minCoeff() > cup.compensable_height) return SealFailure::Hill;

  // 3c. Hole: every ray over the disc (and the centre ray) must hit the object.
  if (!centre_hit) return SealFailure::Hole;
  ParallelRays disc{
      lift_base, u, v, -n, ctx.disc_pattern.data(), static_cast<int>(ctx.disc_pattern.size()), r};
  const bool no_hole = ctx.hole_walker ? ctx.hole_walker->all_hit(ctx.scene, disc, face[N])
                                       : parallel_all_hit(ctx.scene, disc);
  if (!no_hole) return SealFailure::Hole;

  // 4. Compression springs: global equilibrium sum_k k_c (delta - d_k) = F_p.
  const double F_p = cup.pressure_force();
  const double k_c = cup.compression_stiffness();
  const Eigen::VectorXd d = s.maxCoeff() - s.array();
  const double delta = (F_p / k_c + d.sum()) / N;
  const Eigen::VectorXd elastic = k_c * (delta - d.array());

  // 5. Ring springs between projected points: neighbour, second neighbour and opposite point.
  const std::array<int, 3> offsets = {1, 2, N / 2};
  Points3d F = Points3d::Zero(N, 3);
  for (int j : offsets) {
    const double rest = 2.0 * r * std::sin(M_PI * j / N);
    const double k_spring = cup.ring_stiffness(rest);  // c2 in MetaGraspNet's convention
    // Each unordered pair once: for the opposite springs of an even ring only half the points.
    const int pairs = (2 * j == N) ? N / 2 : N;
    for (int k = 0; k < pairs; ++k) {
      const int l = (k + j) % N;
      const Eigen::RowVector3d chord = x.row(l) - x.row(k);
      const double len = chord.norm();
      if (len <= 0.0) continue;
      const Eigen::RowVector3d f =
          k_spring * (len - rest) / len * chord;  // pulls k towards l when stretched
      F.row(k) += f;
      F.row(l) -= f;
    }
  }
  if (detail) {
    detail->elastic_force = elastic;
    detail->ring_force = F;
    detail->total_elastic_force = elastic.sum();
  }

  // 6. Local equilibrium: the lip lifts off where it cannot reach the surface (negative
  //    compression) or where the ring force along the surface normal beats the elastic force.
  for (int k = 0; k < N; ++k) {
    if (elastic[k] < 0.0) return SealFailure::Force;
    const Eigen::RowVector3d mk = m[k].cast<double>().transpose();
    const double lift = F.row(k).dot(mk);
    const double press = elastic[k] * n.dot(mk.transpose());
    if (lift > press) return SealFailure::Force;
  }
  return SealFailure::None;
}

}  // namespace detail

struct SealModel::Impl {
  std::unique_ptr<RayScene> scene;
  Points3f vertices;  // kept for bounds / tolerances
  std::unique_ptr<detail::HoleWalker> hole_walker;
};

namespace {

/// Position of (x, y) (16 bits each) along a Hilbert curve over the 2^16 x 2^16 grid.
std::uint64_t hilbert2(std::uint32_t x, std::uint32_t y) {
  std::uint64_t d = 0;
  for (std::uint32_t s = 1u << 15; s > 0; s >>= 1) {
    const std::uint32_t rx = (x & s) ? 1 : 0;
    const std::uint32_t ry = (y & s) ? 1 : 0;
    d += static_cast<std::uint64_t>(s) * s * ((3 * rx) ^ ry);
    if (ry == 0) {  // rotate the quadrant
      if (rx == 1) {
        x = 0xFFFF - x;
        y = 0xFFFF - y;
      }
      std::swap(x, y);
    }
  }
  return d;
}

/// Vogel (sunflower) spiral: n points evenly spread over the unit disc, deterministic, ordered
/// along a Hilbert curve so that consecutive rays are neighbours: every packet of 8 covers a
/// small patch (coherent packets trace several times faster than packets spread over the whole
/// disc) and the hole check's walk from ray to ray (HoleWalker) crosses few faces.
std::vector<Eigen::Vector2d> disc_pattern(int n) {
  std::vector<std::pair<std::uint64_t, Eigen::Vector2d>> keyed(static_cast<std::size_t>(n));
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double rho = std::sqrt((i + 0.5) / n);
    const Eigen::Vector2d p(rho * std::cos(i * golden), rho * std::sin(i * golden));
    const auto qx = static_cast<std::uint32_t>((p.x() + 1.0) * 32767.0);
    const auto qy = static_cast<std::uint32_t>((p.y() + 1.0) * 32767.0);
    keyed[i] = {hilbert2(qx, qy), p};
  }
  std::stable_sort(keyed.begin(), keyed.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Eigen::Vector2d> pts(keyed.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) pts[i] = keyed[i].second;
  return pts;
}

SealFailure run_trial(SealModelKind kind, const detail::SealContext& ctx, const Vec3d& c,
                      const Vec3d& n, float& quality, const Vec3d* nominal = nullptr) {
  switch (kind) {
    case SealModelKind::Spring: {
      const SealFailure f = detail::spring_trial(ctx, c, n, nullptr, nominal);
      quality = f == SealFailure::None ? 1.0f : 0.0f;
      return f;
    }
    case SealModelKind::Strain:
      return detail::strain_trial(ctx, c, n, &quality);
    case SealModelKind::Smoothness:
      return detail::smoothness_trial(ctx, c, n, &quality);
  }
  throw_error<InvalidArgument>("SealModel: unknown model kind ", static_cast<int>(kind));
}

}  // namespace

SealModel::SealModel(const Mesh& mesh, const Cup& cup, SealModelKind kind)
    : cup_(cup), kind_(kind) {
  require_non_empty(mesh, "SealModel");
  cup.validate();
  auto impl = std::make_shared<Impl>();
  impl->scene =
      std::make_unique<RayScene>(std::vector<RayGeometry>{RayGeometry{&mesh, Pose::Identity(), 0}});
  impl->vertices = mesh.vertices();
  impl->hole_walker = std::make_unique<detail::HoleWalker>(mesh);
  impl_ = std::move(impl);
}

SealModel::SealModel(std::shared_ptr<const Impl> impl, const Cup& cup, SealModelKind kind)
    : impl_(std::move(impl)), cup_(cup), kind_(kind) {
  cup.validate();
}

SealModel::~SealModel() = default;

std::shared_ptr<const SealModel> SealModel::with_cup(const Cup& cup) const {
  return std::shared_ptr<const SealModel>(new SealModel(impl_, cup, kind_));
}

SealTrial SealModel::trial(const Vec3d& point, const Vec3d& normal) const {
  if (!point.allFinite() || !normal.allFinite() || normal.norm() == 0.0) {
    throw_error<InvalidArgument>(
        "SealModel::trial: expected a finite point and a finite non-zero normal");
  }
  const auto pattern = disc_pattern(cup_.hole_rays);
  const auto ring = detail::unit_ring(cup_.num_points);
  const detail::SealContext ctx{*impl_->scene, cup_, pattern, &ring, impl_->hole_walker.get()};
  SealTrial out;
  const Vec3d n = normal.normalized();
  float quality = 0.0f;
  out.failure = kind_ == SealModelKind::Spring ? detail::spring_trial(ctx, point, n, &out)
                                               : run_trial(kind_, ctx, point, n, quality);
  return out;
}

void SealOptions::validate() const {
  auto require = [](bool ok, const char* field, double value, const char* expected) {
    if (!ok)
      throw_error<InvalidArgument>("SealOptions.", field, " must be ", expected, ", got ", value);
  };
  require(num_trials >= 1, "num_trials", num_trials, ">= 1");
  require(std::isfinite(angle_sigma) && angle_sigma >= 0.0, "angle_sigma", angle_sigma,
          "finite and >= 0 (rad)");
  require(std::isfinite(position_sigma), "position_sigma", position_sigma,
          "finite (m; < 0: cup radius / 4)");
  require(std::isfinite(on_surface_tolerance) && on_surface_tolerance > 0.0, "on_surface_tolerance",
          on_surface_tolerance, "finite and > 0 (m)");
  require(num_threads >= 0, "num_threads", num_threads, "0 (all) or a thread count >= 1");
}

SealResult SealModel::evaluate(const Points3f& points, const Points3f& normals,
                               const SealOptions& options) const {
  const char* fn = "SealModel::evaluate";
  if (points.rows() != normals.rows()) {
    throw_error<InvalidArgument>(fn, ": points has ", points.rows(), " rows but normals has ",
                                 normals.rows(), "; expected one normal per point");
  }
  options.validate();
  const Eigen::Index n_cand = points.rows();
  Points3f unit(n_cand, 3);
  for (Eigen::Index i = 0; i < n_cand; ++i) {
    const float len = normals.row(i).norm();
    if (!points.row(i).allFinite() || !normals.row(i).allFinite() || !(len > 0.0f)) {
      throw_error<InvalidArgument>(fn, ": candidate ", i,
                                   " has a non-finite point or a zero/non-finite normal (",
                                   normals(i, 0), ", ", normals(i, 1), ", ", normals(i, 2), ")");
    }
    unit.row(i) = normals.row(i) / len;
  }
  // Candidates must lie on the mesh: a short ray along the normal through the point hits it.
  if (n_cand > 0) {
    const float tol = static_cast<float>(options.on_surface_tolerance);
    Points3f o = points + tol * unit;
    Points3f d = -unit;
    CastOptions opt;
    opt.tfar = 2.0f * tol;
    opt.num_threads = options.num_threads;
    const auto down = impl_->scene->occluded(o, d, opt);
    for (Eigen::Index i = 0; i < n_cand; ++i) {
      if (!down[i]) {
        throw_error<InvalidArgument>(fn, ": candidate ", i, " at (", points(i, 0), ", ",
                                     points(i, 1), ", ", points(i, 2),
                                     ") is not on the mesh surface (no surface within ",
                                     options.on_surface_tolerance, " m along its normal)");
      }
    }
  }

  const int T = options.perturb ? options.num_trials : 1;
  const double pos_sigma =
      options.position_sigma < 0.0 ? cup_.radius / 4.0 : options.position_sigma;
  SealResult out;
  out.num_trials = T;
  out.score.assign(static_cast<std::size_t>(n_cand), 0.0f);
  out.quality.assign(static_cast<std::size_t>(n_cand), 0.0f);
  out.reason.assign(static_cast<std::size_t>(n_cand), 0);
  out.trial_sealed.assign(static_cast<std::size_t>(n_cand) * T, 0);
  out.trial_reason.assign(static_cast<std::size_t>(n_cand) * T, 0);
  const auto pattern = disc_pattern(cup_.hole_rays);
  const auto ring = detail::unit_ring(cup_.num_points);
  const detail::SealContext ctx{*impl_->scene, cup_, pattern, &ring, impl_->hole_walker.get()};

  // Dynamic scheduling over blocks of candidates (a candidate's cost varies several-fold with
  // the checks its trials reach); every candidate's result depends only on its index.
  parallel_for_dynamic(
      static_cast<std::size_t>(n_cand), options.num_threads, 8,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
          Rng rng(options.seed, options.first_index + i);
          const Vec3d c0 = points.row(static_cast<Eigen::Index>(i)).transpose().cast<double>();
          const Vec3d n0 = unit.row(static_cast<Eigen::Index>(i)).transpose().cast<double>();
          int sealed = 0;
          double quality_sum = 0.0;
          std::array<int, 8> counts{};
          for (int t = 0; t < T; ++t) {
            Vec3d c = c0, n = n0;
            if (options.perturb) {
              const double ax = rng.normal(0.0, options.angle_sigma);
              const double ay = rng.normal(0.0, options.angle_sigma);
              const double az = rng.normal(0.0, options.angle_sigma);
              const Mat3d R =
                  (Eigen::AngleAxisd(az, Vec3d::UnitZ()) * Eigen::AngleAxisd(ay, Vec3d::UnitY()) *
                   Eigen::AngleAxisd(ax, Vec3d::UnitX()))
                      .toRotationMatrix();
              n = (R * n0).normalized();
              // Named draws: the order of function arguments is unspecified in C++, and the
              // random stream must not depend on the compiler.
              const double jx = rng.normal(0.0, pos_sigma);
              const double jy = rng.normal(0.0, pos_sigma);
              const double jz = rng.normal(0.0, pos_sigma);
              c = c0 + Vec3d(jx, jy, jz);
            }
            float q = 0.0f;
            const SealFailure f = run_trial(kind_, ctx, c, n, q, &c0);
            const std::size_t slot = i * T + static_cast<std::size_t>(t);
            out.trial_sealed[slot] = f == SealFailure::None;
            out.trial_reason[slot] = static_cast<std::uint8_t>(f);
            sealed += f == SealFailure::None;
            quality_sum += q;
            ++counts[static_cast<std::size_t>(f)];
          }
          out.score[i] = static_cast<float>(sealed) / T;
          out.quality[i] = static_cast<float>(quality_sum / T);
          // Most frequent failure among the failed trials; ties go to the earlier check.
          int best = 0, best_count = 0;
          for (int f = 1; f < static_cast<int>(counts.size()); ++f) {
            if (counts[f] > best_count) {
              best = f;
              best_count = counts[f];
            }
          }
          out.reason[i] = static_cast<std::uint8_t>(best);
        }
      });
  return out;
}

}  // namespace mgn
