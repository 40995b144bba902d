// The centre-of-mass heat map predicted from a view's noise-free depth (view_labels.hpp). Built
// with -ffp-contract=off (cpp/CMakeLists.txt): every product and sum is rounded on its own, in
// the order written, so the bits equal mgn.io.scene_folder's definition on every machine.

#include <mgn/core/error.hpp>
#include <mgn/scene/view_labels.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace mgn {

void com_heatmap_prediction(const float* depth_m, const std::int32_t* instances, int width,
                            int height, const double X_WC[16], const double intrinsics[4],
                            const double* com_parameters, int num_objects, float* out) {
  const double fx = intrinsics[0], fy = intrinsics[1], cx = intrinsics[2], cy = intrinsics[3];
  if (width < 0 || height < 0 || num_objects < 0) {
    throw_error<InvalidArgument>("com_heatmap_prediction: image ", width, " x ", height, " and ",
                                 num_objects, " objects; expected sizes >= 0");
  }
  // u + 0.5 - cx per column and v + 0.5 - cy per row, rounded as written.
  std::vector<double> col(static_cast<std::size_t>(width)), row(static_cast<std::size_t>(height));
  for (int u = 0; u < width; ++u) col[u] = (static_cast<double>(u) + 0.5) - cx;
  for (int v = 0; v < height; ++v) row[v] = (static_cast<double>(v) + 0.5) - cy;
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const std::size_t p = static_cast<std::size_t>(v) * static_cast<std::size_t>(width) + u;
      out[p] = 0.0f;
      const std::int32_t id = instances[p];
      if (id <= 0) continue;
      if (id > num_objects) {
        throw_error<InvalidArgument>("com_heatmap_prediction: instance id ", id, " but only ",
                                     num_objects, " rows of com_parameters");
      }
      const double z = static_cast<double>(depth_m[p]);
      if (!(std::isfinite(z) && z > 0.0)) continue;
      double x = col[u] * z;
      x /= fx;
      double y = row[v] * z;
      y /= fy;
      const double* c = com_parameters + 5 * static_cast<std::size_t>(id - 1);
      double d2 = 0.0;
      for (int r = 0; r < 3; ++r) {
        // ((X_r0 x + X_r1 y) + X_r2 z) + X_r3 - c_r
        double a = x * X_WC[4 * r];
        a += y * X_WC[4 * r + 1];
        a += z * X_WC[4 * r + 2];
        a += X_WC[4 * r + 3];
        a -= c[r];
        if (r == 0) {
          d2 = a * a;
        } else {
          d2 += a * a;
        }
      }
      const double d = std::sqrt(d2);
      const double span = std::max(c[4] - c[3], 1e-12);
      out[p] = static_cast<float>(std::clamp((c[4] - d) / span, 0.0, 1.0));
    }
  }
}

}  // namespace mgn
