// The two baseline seal models of docs/models.md §2, one deterministic trial each.
//
// Strain model — follows the cone-of-springs contact model of Dex-Net 3.0 (Mahler et al., "Dex-Net
// 3.0: Computing Robust Vacuum Suction Grasp Targets in Point Clouds using a New Analytic Model and
// Deep Learning", ICRA 2018): the cup is a right pyramid whose base is an N-gon of circumradius r
// (N = 15) and whose apex sits at height H; perimeter (i, i+1), flexion (i, i+2) and cone (i, apex)
// springs; the perimeter is projected onto the surface along the approach axis and the seal holds
// when every spring stays within ±10 % of its rest length.
// Smoothness model — follows the seal score of SuctionNet-1Billion (Cao et al.,
// "SuctionNet-1Billion: A Large-Scale Benchmark for Suction Grasping", RA-L 2021): 72 angular bins
// of surface points in a 1 mm band around the contact ring; per bin a vertex at its ideal planar
// ring position with the bin's height; deform = min over ring edges of (ideal length / real
// length); fit = exp(−1e5 · mean squared deviation of the heights from their mean); score = deform
// × fit.
//
// mgn's own choices (not taken from either publication):
//   - r = cup.radius and H = cup.body_height of the mgn Cup (Dex-Net's reference values are 15 mm
//     and 30 mm; SuctionNet uses a 10 mm ring), so all models compare on the same cup;
//   - surfaces are sampled by casting rays along −n from cup.approach_height above the plane of c
//     (no point cloud): the first surface seen from the approaching cup;
//   - the pyramid's perimeter vertices sit at angles (k + ½)·2π/N like the spring model's ring;
//   - the apex of the deformed pyramid sits H above the centroid of the projected perimeter, i.e.
//     above the in-plane centre of the ring at (mean projected height + H) along n;
//   - the smoothness band is sampled on a fixed pattern: per bin 3 angles (at 1/6, 1/2, 5/6 of the
//     bin) × 3 radii (R − 0.5 mm, R, R + 0.5 mm); a bin's height is the mean height of its hits;
//     the ideal vertex of bin b is at angle (b + ½)·2π/72 on the ring of radius R;
//   - both models first require every projection ray to hit (SealFailure::Miss) and then run the
//     hole check of the spring model (rays over the disc of radius r, SealFailure::Hole);
//   - heights are measured along n relative to the plane of c (a constant shift of hit · n, which
//     changes neither the deviations nor the edge lengths);
//   - the smoothness trial seals when deform × fit >= detail::smoothness_threshold; a trial that
//     fails the Miss or Hole check reports quality 0.
#include <mgn/core/error.hpp>
#include <mgn/raytrace/ray_scene.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "grasp/detail/seal_trials.hpp"

namespace mgn::detail {

namespace {

constexpr int kStrainVertices = 15;        // N of the Dex-Net pyramid
constexpr double kStrainLimit = 0.10;      // allowed relative length change of every spring
constexpr int kSmoothBins = 72;            // SuctionNet angular bins
constexpr int kSmoothAnglesPerBin = 3;     // sample angles per bin (mgn)
constexpr double kBandHalfWidth = 0.0005;  // half of the 1 mm band, m
constexpr double kFitGain = 1e5;  // SuctionNet fit: exp(-1e5 * mean squared deviation), m^-2

/// Validates a trial's inputs; returns the unit normal. Throws InvalidArgument for impossible ones.
Vec3d checked_normal(const char* fn, const SealContext& ctx, const Vec3d& c, const Vec3d& n) {
  if (!c.allFinite()) {
    throw_error<InvalidArgument>(fn, ": contact point must be finite, got (", c.x(), ", ", c.y(),
                                 ", ", c.z(), ")");
  }
  const double len = n.norm();
  if (!n.allFinite() || !(len > 0.0)) {
    throw_error<InvalidArgument>(fn, ": normal must be finite and non-zero, got (", n.x(), ", ",
                                 n.y(), ", ", n.z(), ")");
  }
  const Cup& cup = ctx.cup;
  if (!(cup.radius > 0.0) || !std::isfinite(cup.radius)) {
    throw_error<InvalidArgument>(fn, ": cup radius must be finite and > 0 m, got ", cup.radius);
  }
  if (!(cup.approach_height > 0.0) || !std::isfinite(cup.approach_height)) {
    throw_error<InvalidArgument>(fn, ": cup approach_height must be finite and > 0 m, got ",
                                 cup.approach_height);
  }
  return n / len;
}

CastOptions trial_cast_options() {
  CastOptions opt;
  opt.coherent = true;  // parallel rays from one plane
  opt.num_threads = 1;  // trials already run on worker threads
  return opt;
}

/// Origins of rays from in-plane offsets (x, y) (m, in the (u, v) frame) at the approach height
/// above the plane of c, and the common direction -n.
void plane_rays(const Vec3d& c, const Vec3d& n, const Vec3d& u, const Vec3d& v, double height,
                const std::vector<Eigen::Vector2d>& offsets, Points3f& origins,
                Points3f& directions) {
  const auto m = static_cast<Eigen::Index>(offsets.size());
  origins.resize(m, 3);
  directions.resize(m, 3);
  const Vec3d base = c + height * n;
  const Eigen::RowVector3f down = (-n).cast<float>().transpose();
  for (Eigen::Index i = 0; i < m; ++i) {
    const Eigen::Vector2d& q = offsets[static_cast<std::size_t>(i)];
    origins.row(i) = (base + q.x() * u + q.y() * v).cast<float>().transpose();
    directions.row(i) = down;
  }
}

/// The hole check: rays over the disc of radius r (ctx.disc_pattern scaled by r) cast along -n
/// from the approach height must all hit the object. An empty pattern checks nothing.
bool disc_has_hole(const SealContext& ctx, const Vec3d& c, const Vec3d& n, const Vec3d& u,
                   const Vec3d& v) {
  if (ctx.disc_pattern.empty()) return false;
  std::vector<Eigen::Vector2d> disc(ctx.disc_pattern.size());
  for (std::size_t i = 0; i < disc.size(); ++i) disc[i] = ctx.cup.radius * ctx.disc_pattern[i];
  Points3f o, d;
  plane_rays(c, n, u, v, ctx.cup.approach_height, disc, o, d);
  const std::vector<std::uint8_t> hit = ctx.scene.occluded(o, d, trial_cast_options());
  return std::any_of(hit.begin(), hit.end(), [](std::uint8_t h) { return h == 0; });
}

}  // namespace

SealFailure strain_trial(const SealContext& ctx, const Vec3d& c, const Vec3d& n_in,
                         float* quality) {
  const char* fn = "strain_trial";
  const Vec3d n = checked_normal(fn, ctx, c, n_in);
  const double H = ctx.cup.body_height;
  if (!(H > 0.0) || !std::isfinite(H)) {
    throw_error<InvalidArgument>(
        fn, ": cup body_height (pyramid height H) must be finite and > 0 m, got ", H);
  }
  if (quality) *quality = 0.0f;
  const int N = kStrainVertices;
  const double r = ctx.cup.radius;
  const double a = ctx.cup.approach_height;
  Vec3d u, v;
  tangent_frame(n, u, v);

  // Perimeter of the pyramid's base, projected onto the surface along -n (one batch of N rays).
  std::vector<Eigen::Vector2d> ring(static_cast<std::size_t>(N));
  for (int k = 0; k < N; ++k) {
    const double phi = (k + 0.5) * 2.0 * M_PI / N;
    ring[static_cast<std::size_t>(k)] = Eigen::Vector2d(r * std::cos(phi), r * std::sin(phi));
  }
  Points3f o, d;
  plane_rays(c, n, u, v, a, ring, o, d);
  const RayHits hits = ctx.scene.intersect(o, d, trial_cast_options());
  for (int k = 0; k < N; ++k) {
    if (hits.instance_ids[static_cast<std::size_t>(k)] < 0) return SealFailure::Miss;
  }
  if (disc_has_hole(ctx, c, n, u, v)) return SealFailure::Hole;

  // Projected vertices in the cup frame (u, v, n) with origin c: the in-plane position is unchanged
  // by the projection; the height along n is a - t (double origins, float distance).
  std::vector<Vec3d> x(static_cast<std::size_t>(N));
  for (int k = 0; k < N; ++k) {
    const auto i = static_cast<std::size_t>(k);
    x[i] = Vec3d(ring[i].x(), ring[i].y(), a - static_cast<double>(hits.distance[i]));
  }
  // Apex: H above the centroid of the projected perimeter, i.e. at the in-plane centroid (the ring
  // centre) and at height (mean projected height + H) along n.
  Vec3d centroid = Vec3d::Zero();
  for (const Vec3d& p : x) centroid += p;
  centroid /= N;
  const Vec3d apex = centroid + H * Vec3d::UnitZ();

  // Rest lengths of the undeformed pyramid.
  const double rest_perimeter = 2.0 * r * std::sin(M_PI / N);
  const double rest_flexion = 2.0 * r * std::sin(2.0 * M_PI / N);
  const double rest_cone = std::sqrt(r * r + H * H);
  auto strained = [](double length, double rest) {
    return std::abs(length / rest - 1.0) > kStrainLimit;
  };
  for (int k = 0; k < N; ++k) {
    const Vec3d& p = x[static_cast<std::size_t>(k)];
    if (strained((x[static_cast<std::size_t>((k + 1) % N)] - p).norm(), rest_perimeter) ||
        strained((x[static_cast<std::size_t>((k + 2) % N)] - p).norm(), rest_flexion) ||
        strained((apex - p).norm(), rest_cone)) {
      return SealFailure::Strain;
    }
  }
  if (quality) *quality = 1.0f;
  return SealFailure::None;
}

SealFailure smoothness_trial(const SealContext& ctx, const Vec3d& c, const Vec3d& n_in,
                             float* quality) {
  const char* fn = "smoothness_trial";
  const Vec3d n = checked_normal(fn, ctx, c, n_in);
  if (quality) *quality = 0.0f;
  const double R = ctx.cup.radius;
  const double a = ctx.cup.approach_height;
  Vec3d u, v;
  tangent_frame(n, u, v);

  // Band samples: bin b, sub-angle j, radius i -> ray (b * A + j) * 3 + i.
  const double bin_angle = 2.0 * M_PI / kSmoothBins;
  const std::array<double, 3> radii = {std::max(0.0, R - kBandHalfWidth), R, R + kBandHalfWidth};
  const int per_bin = kSmoothAnglesPerBin * static_cast<int>(radii.size());
  std::vector<Eigen::Vector2d> band(static_cast<std::size_t>(kSmoothBins * per_bin));
  std::size_t idx = 0;
  for (int b = 0; b < kSmoothBins; ++b) {
    for (int j = 0; j < kSmoothAnglesPerBin; ++j) {
      const double phi = (b + (j + 0.5) / kSmoothAnglesPerBin) * bin_angle;
      for (double rad : radii)
        band[idx++] = Eigen::Vector2d(rad * std::cos(phi), rad * std::sin(phi));
    }
  }
  Points3f o, d;
  plane_rays(c, n, u, v, a, band, o, d);
  const RayHits hits = ctx.scene.intersect(o, d, trial_cast_options());

  // Per-bin mean height along n (relative to the plane of c); an empty bin is a miss.
  std::array<double, kSmoothBins> height{};
  for (int b = 0; b < kSmoothBins; ++b) {
    double sum = 0.0;
    int count = 0;
    for (int s = 0; s < per_bin; ++s) {
      const auto i = static_cast<std::size_t>(b) * per_bin + s;
      if (hits.instance_ids[i] < 0) continue;
      sum += a - static_cast<double>(hits.distance[i]);
      ++count;
    }
    if (count == 0) return SealFailure::Miss;
    height[static_cast<std::size_t>(b)] = sum / count;
  }
  if (disc_has_hole(ctx, c, n, u, v)) return SealFailure::Hole;

  // deform: the ideal vertices are equally spaced on the planar ring, so every edge has the same
  // ideal length; the real length adds the height difference of its two bins.
  const double ideal = 2.0 * R * std::sin(0.5 * bin_angle);
  double deform = 1.0;
  double mean = 0.0;
  for (int b = 0; b < kSmoothBins; ++b) {
    const double dh = height[static_cast<std::size_t>((b + 1) % kSmoothBins)] -
                      height[static_cast<std::size_t>(b)];
    deform = std::min(deform, ideal / std::sqrt(ideal * ideal + dh * dh));
    mean += height[static_cast<std::size_t>(b)];
  }
  mean /= kSmoothBins;
  double msd = 0.0;
  for (double h : height) msd += (h - mean) * (h - mean);
  msd /= kSmoothBins;
  const double fit = std::exp(-kFitGain * msd);
  const double q = std::clamp(deform * fit, 0.0, 1.0);
  if (quality) *quality = static_cast<float>(q);
  return static_cast<float>(q) >= smoothness_threshold ? SealFailure::None : SealFailure::Rough;
}

}  // namespace mgn::detail
