#include <mgn/core/error.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/geometry/sampling.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace mgn {

namespace {

/// Area-weighted uniform points drawn from one random stream.
SurfaceSamples sample_random(const Mesh& mesh, std::int64_t count, std::uint64_t seed,
                             std::uint64_t stream) {
  const Eigen::VectorXd areas = mesh.face_areas();
  std::vector<double> cdf(static_cast<std::size_t>(areas.size()));
  double total = 0.0;
  for (Eigen::Index i = 0; i < areas.size(); ++i) cdf[i] = (total += areas[i]);
  const Points3f normals = mesh.face_normals();
  const auto& V = mesh.vertices();
  const auto& F = mesh.faces();
  SurfaceSamples out;
  out.points.resize(count, 3);
  out.normals.resize(count, 3);
  out.face_ids.resize(static_cast<std::size_t>(count));
  Rng rng(seed, stream);
  for (std::int64_t i = 0; i < count; ++i) {
    const double u = rng.uniform() * total;
    auto it = std::upper_bound(cdf.begin(), cdf.end(), u);
    if (it == cdf.end()) --it;
    const auto f = static_cast<std::int64_t>(it - cdf.begin());
    // Uniform point in a triangle: sqrt trick.
    const double r1 = std::sqrt(rng.uniform());
    const double r2 = rng.uniform();
    const Vec3d a = V.row(F(f, 0)).transpose().cast<double>();
    const Vec3d b = V.row(F(f, 1)).transpose().cast<double>();
    const Vec3d c = V.row(F(f, 2)).transpose().cast<double>();
    const Vec3d p = (1.0 - r1) * a + r1 * (1.0 - r2) * b + r1 * r2 * c;
    out.points.row(i) = p.cast<float>().transpose();
    out.normals.row(i) = normals.row(f);
    out.face_ids[i] = static_cast<std::int32_t>(f);
  }
  return out;
}

}  // namespace

SurfaceSamples sample_surface(const Mesh& mesh, std::int64_t count, const SampleOptions& options) {
  const char* fn = "sample_surface";
  if (count < 0) throw_error<InvalidArgument>(fn, ": count must be >= 0, got ", count);
  require_non_empty(mesh, fn);
  if (options.method == SampleMethod::Random) return sample_random(mesh, count, options.seed, 0);

  if (options.oversampling < 1) {
    throw_error<InvalidArgument>(fn, ": oversampling must be >= 1, got ", options.oversampling);
  }
  // Even: farthest-point selection from an area-weighted pool gives blue-noise spacing and
  // exactly `count` points. Ties go to the lowest candidate index, so it is deterministic.
  const std::int64_t pool_size = std::max<std::int64_t>(count, count * options.oversampling);
  SurfaceSamples pool = sample_random(mesh, pool_size, options.seed, 1);
  SurfaceSamples out;
  out.points.resize(count, 3);
  out.normals.resize(count, 3);
  out.face_ids.resize(static_cast<std::size_t>(count));
  if (count == 0) return out;
  // Structure of arrays: the distance update is a plain loop the compiler vectorises, and the
  // arg-max (first index of the largest value) is a second pass; same picks as one fused loop.
  const auto n_pool = static_cast<std::size_t>(pool_size);
  std::vector<float> xs(n_pool), ys(n_pool), zs(n_pool);
  for (std::size_t j = 0; j < n_pool; ++j) {
    const auto r = static_cast<Eigen::Index>(j);
    xs[j] = pool.points(r, 0);
    ys[j] = pool.points(r, 1);
    zs[j] = pool.points(r, 2);
  }
  std::vector<float> min_d2(n_pool, std::numeric_limits<float>::infinity());
  std::size_t pick = 0;
  for (std::int64_t i = 0; i < count; ++i) {
    const auto r = static_cast<Eigen::Index>(pick);
    out.points.row(i) = pool.points.row(r);
    out.normals.row(i) = pool.normals.row(r);
    out.face_ids[i] = pool.face_ids[pick];
    const float px = xs[pick], py = ys[pick], pz = zs[pick];
    const float* __restrict x = xs.data();
    const float* __restrict y = ys.data();
    const float* __restrict z = zs.data();
    float* __restrict m = min_d2.data();
    for (std::size_t j = 0; j < n_pool; ++j) {
      const float dx = x[j] - px, dy = y[j] - py, dz = z[j] - pz;
      const float d2 = dx * dx + dy * dy + dz * dz;
      m[j] = d2 < m[j] ? d2 : m[j];
    }
    pick =
        static_cast<std::size_t>(std::max_element(min_d2.begin(), min_d2.end()) - min_d2.begin());
  }
  return out;
}

}  // namespace mgn
