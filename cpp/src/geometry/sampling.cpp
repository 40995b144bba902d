#include <mgn/core/error.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/geometry/sampling.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

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
  // Structure of arrays in the order of a uniform grid's cells (stable: pool order within a
  // cell). Each cell keeps the largest distance to the picks so far and the lowest pool index
  // holding it, so the next pick (the first pool index of the largest distance, as a plain scan
  // would choose) is found over the cells. A pick updates only the cells its distance can lower:
  // a cell is skipped when the squared distance from the pick to the cell's bounding box, less
  // a 1e-5 relative margin (the float rounding of a squared distance is ~1e-7 relative), is at
  // least the cell's largest distance, since then no distance of the cell can decrease. Same
  // picks as updating every pool point.
  const auto n_pool = static_cast<std::size_t>(pool_size);
  Eigen::Array3d lo = pool.points.colwise().minCoeff().transpose().cast<double>();
  Eigen::Array3d hi = pool.points.colwise().maxCoeff().transpose().cast<double>();
  const Eigen::Array3d extent = (hi - lo).max(1e-12);
  // About 32 points per cell, cells shaped like the bounding box.
  const double cells_wanted = std::max(1.0, static_cast<double>(n_pool) / 32.0);
  const double cell = std::cbrt(extent.prod() / cells_wanted);
  Eigen::Array3i dims;
  for (int k = 0; k < 3; ++k) {
    dims[k] = static_cast<int>(std::clamp(std::ceil(extent[k] / std::max(cell, 1e-12)), 1.0, 64.0));
  }
  const std::size_t n_cells = static_cast<std::size_t>(dims.prod());
  std::vector<std::uint32_t> cell_of(n_pool);
  std::vector<std::size_t> start(n_cells + 1, 0);
  for (std::size_t j = 0; j < n_pool; ++j) {
    const auto r = static_cast<Eigen::Index>(j);
    std::size_t c = 0;
    for (int k = 2; k >= 0; --k) {
      const double t = (pool.points(r, k) - lo[k]) / extent[k] * dims[k];
      const int q = std::clamp(static_cast<int>(t), 0, dims[k] - 1);
      c = c * static_cast<std::size_t>(dims[k]) + static_cast<std::size_t>(q);
    }
    cell_of[j] = static_cast<std::uint32_t>(c);
    ++start[c + 1];
  }
  for (std::size_t c = 0; c < n_cells; ++c) start[c + 1] += start[c];
  std::vector<std::size_t> fill(start.begin(), start.end() - 1);
  std::vector<std::uint32_t> index(n_pool);  // pool index of each slot
  std::vector<float> xs(n_pool), ys(n_pool), zs(n_pool);
  for (std::size_t j = 0; j < n_pool; ++j) {
    const std::size_t slot = fill[cell_of[j]]++;
    const auto r = static_cast<Eigen::Index>(j);
    index[slot] = static_cast<std::uint32_t>(j);
    xs[slot] = pool.points(r, 0);
    ys[slot] = pool.points(r, 1);
    zs[slot] = pool.points(r, 2);
  }
  std::vector<double> box(6 * n_cells);             // per cell: min xyz, max xyz of its points
  std::vector<float> cell_max(n_cells, -1.0f);      // -1: empty cell
  std::vector<std::uint32_t> cell_arg(n_cells, 0);  // lowest pool index at cell_max
  for (std::size_t c = 0; c < n_cells; ++c) {
    double* bx = &box[6 * c];
    for (int k = 0; k < 3; ++k) {
      bx[k] = std::numeric_limits<double>::infinity();
      bx[3 + k] = -std::numeric_limits<double>::infinity();
    }
    for (std::size_t s = start[c]; s < start[c + 1]; ++s) {
      const double p[3] = {xs[s], ys[s], zs[s]};
      for (int k = 0; k < 3; ++k) {
        bx[k] = std::min(bx[k], p[k]);
        bx[3 + k] = std::max(bx[3 + k], p[k]);
      }
    }
    if (start[c + 1] > start[c]) {
      cell_max[c] = std::numeric_limits<float>::infinity();
      cell_arg[c] = index[start[c]];
    }
  }
  std::vector<float> min_d2(n_pool, std::numeric_limits<float>::infinity());
  std::vector<std::uint32_t> slot_of(n_pool);
  for (std::size_t s = 0; s < n_pool; ++s) slot_of[index[s]] = static_cast<std::uint32_t>(s);
  std::size_t pick = 0;
  for (std::int64_t i = 0; i < count; ++i) {
    const auto r = static_cast<Eigen::Index>(pick);
    out.points.row(i) = pool.points.row(r);
    out.normals.row(i) = pool.normals.row(r);
    out.face_ids[i] = pool.face_ids[pick];
    const std::size_t ps = slot_of[pick];
    const float px = xs[ps], py = ys[ps], pz = zs[ps];
    for (std::size_t c = 0; c < n_cells; ++c) {
      if (cell_max[c] < 0.0f) continue;
      const double* bx = &box[6 * c];
      const double gx = std::max({bx[0] - px, 0.0, px - bx[3]});
      const double gy = std::max({bx[1] - py, 0.0, py - bx[4]});
      const double gz = std::max({bx[2] - pz, 0.0, pz - bx[5]});
      const double lower = (gx * gx + gy * gy + gz * gz) * (1.0 - 1e-5);
      if (lower >= static_cast<double>(cell_max[c])) continue;
      const float* __restrict x = xs.data();
      const float* __restrict y = ys.data();
      const float* __restrict z = zs.data();
      float* __restrict m = min_d2.data();
      float best = -1.0f;
      std::uint32_t arg = 0;
      for (std::size_t s = start[c]; s < start[c + 1]; ++s) {
        const float dx = x[s] - px, dy = y[s] - py, dz = z[s] - pz;
        const float d2 = dx * dx + dy * dy + dz * dz;
        m[s] = d2 < m[s] ? d2 : m[s];
        // Slots of a cell are in pool order: the first largest is the lowest pool index.
        if (m[s] > best) {
          best = m[s];
          arg = index[s];
        }
      }
      cell_max[c] = best;
      cell_arg[c] = arg;
    }
    float best = -1.0f;
    std::uint32_t arg = 0;
    for (std::size_t c = 0; c < n_cells; ++c) {
      if (cell_max[c] > best || (cell_max[c] == best && cell_arg[c] < arg)) {
        best = cell_max[c];
        arg = cell_arg[c];
      }
    }
    pick = arg;
  }
  return out;
}

}  // namespace mgn
