// The image arithmetic around a half-resolution denoise (mgn/render/half_resolution.hpp).
#include <mgn/core/error.hpp>
#include <mgn/core/parallel.hpp>
#include <mgn/render/half_resolution.hpp>

#include <algorithm>
#include <cmath>

namespace mgn {

namespace {

constexpr float kQuarter = 0.25f;
constexpr float kThreeQuarters = 0.75f;

void check_image(const ImageView& img, const char* name) {
  if (img.data == nullptr || img.height <= 0 || img.width <= 0 || img.channels <= 0)
    throw_error<InvalidArgument>(name,
                                 ": expected an image with height, width and channels > 0, "
                                 "got ",
                                 img.height, " x ", img.width, " x ", img.channels);
}

void check_shape(const ImageView& img, const char* name, int h, int w, int c) {
  check_image(img, name);
  if (img.height != h || img.width != w || img.channels != c)
    throw_error<InvalidArgument>(name, ": expected shape (", h, ", ", w, ", ", c, "), got (",
                                 img.height, ", ", img.width, ", ", img.channels, ")");
}

FloatImage shaped_like(int h, int w, int c) {
  FloatImage out;
  out.height = h;
  out.width = w;
  out.channels = c;
  out.data.resize(static_cast<std::size_t>(h) * static_cast<std::size_t>(w) *
                  static_cast<std::size_t>(c));
  return out;
}

/// The two source indices and their weights (3/4 own block, 1/4 neighbour) of doubled index y
/// over n blocks.
struct Tap {
  int own, other;
};

Tap tap(int y, int n) {
  const int i = y / 2;
  const int other = (y % 2 == 0) ? std::max(i - 1, 0) : std::min(i + 1, n - 1);
  return {i, other};
}

/// One output row of double_blocks(): `vertical` (scratch, blocks' width * C) receives the rows'
/// interpolation, `row` (width * C) the result.
void doubled_row(const ImageView& blocks, int y, int width, float* vertical, float* row) {
  const int wb = blocks.width, c = blocks.channels;
  const Tap ty = tap(y, blocks.height);
  const float* own = blocks.data + static_cast<std::size_t>(ty.own) * wb * c;
  const float* other = blocks.data + static_cast<std::size_t>(ty.other) * wb * c;
  for (int k = 0; k < wb * c; ++k) vertical[k] = kThreeQuarters * own[k] + kQuarter * other[k];
  for (int x = 0; x < width; ++x) {
    const Tap tx = tap(x, wb);
    for (int ch = 0; ch < c; ++ch)
      row[x * c + ch] =
          kThreeQuarters * vertical[tx.own * c + ch] + kQuarter * vertical[tx.other * c + ch];
  }
}

void check_doubling(const ImageView& blocks, const char* name, int height, int width) {
  check_image(blocks, name);
  if (height <= 0 || width <= 0 || height > 2 * blocks.height || width > 2 * blocks.width ||
      height < 2 * blocks.height - 1 || width < 2 * blocks.width - 1)
    throw_error<InvalidArgument>(name, ": a (", blocks.height, ", ", blocks.width,
                                 ") block image doubles to (", 2 * blocks.height - 1, " or ",
                                 2 * blocks.height, ", ", 2 * blocks.width - 1, " or ",
                                 2 * blocks.width, "), not (", height, ", ", width, ")");
}

}  // namespace

FloatImage block_means_2x2(ImageView img, int num_threads) {
  check_image(img, "block_means_2x2: image");
  const int h = img.height, w = img.width, c = img.channels;
  const int hb = (h + 1) / 2, wb = (w + 1) / 2;
  FloatImage out = shaped_like(hb, wb, c);
  parallel_for(static_cast<std::size_t>(hb), num_threads, 16, [&](std::size_t b, std::size_t e) {
    for (std::size_t bi = b; bi < e; ++bi) {
      const int y0 = 2 * static_cast<int>(bi), y1 = std::min(y0 + 1, h - 1);
      const float* r0 = img.data + static_cast<std::size_t>(y0) * w * c;
      const float* r1 = img.data + static_cast<std::size_t>(y1) * w * c;
      float* o = out.data.data() + bi * static_cast<std::size_t>(wb) * c;
      for (int bj = 0; bj < wb; ++bj) {
        const int x0 = 2 * bj, x1 = std::min(x0 + 1, w - 1);
        for (int ch = 0; ch < c; ++ch)
          o[bj * c + ch] =
              (((r0[x0 * c + ch] + r0[x1 * c + ch]) + r1[x0 * c + ch]) + r1[x1 * c + ch]) *
              kQuarter;
      }
    }
  });
  return out;
}

FloatImage double_blocks(ImageView blocks, int height, int width, int num_threads) {
  check_doubling(blocks, "double_blocks: blocks", height, width);
  const int c = blocks.channels;
  FloatImage out = shaped_like(height, width, c);
  parallel_for(static_cast<std::size_t>(height), num_threads, 16,
               [&](std::size_t b, std::size_t e) {
                 std::vector<float> vertical(static_cast<std::size_t>(blocks.width) * c);
                 for (std::size_t y = b; y < e; ++y)
                   doubled_row(blocks, static_cast<int>(y), width, vertical.data(),
                               out.data.data() + y * static_cast<std::size_t>(width) * c);
               });
  return out;
}

FloatImage gaussian_3x3(ImageView img, double sigma, int num_threads) {
  check_image(img, "gaussian_3x3: image");
  if (!(sigma > 0.0) || !std::isfinite(sigma))
    throw_error<InvalidArgument>("gaussian_3x3: sigma must be a finite number > 0, got ", sigma);
  const double e = std::exp(-0.5 / (sigma * sigma));
  const float side = static_cast<float>(e / (1.0 + 2.0 * e));
  const float mid = static_cast<float>(1.0 / (1.0 + 2.0 * e));
  const int h = img.height, w = img.width, c = img.channels;
  const std::size_t stride = static_cast<std::size_t>(w) * c;
  FloatImage out = shaped_like(h, w, c);
  parallel_for(static_cast<std::size_t>(h), num_threads, 16, [&](std::size_t b, std::size_t e2) {
    std::vector<float> v(stride);
    for (std::size_t y = b; y < e2; ++y) {
      const float* up = img.data + (y == 0 ? 0 : y - 1) * stride;
      const float* at = img.data + y * stride;
      const float* down = img.data + std::min<std::size_t>(y + 1, h - 1) * stride;
      for (std::size_t k = 0; k < stride; ++k) v[k] = mid * at[k] + side * (up[k] + down[k]);
      float* o = out.data.data() + y * stride;
      for (int x = 0; x < w; ++x) {
        const int xl = std::max(x - 1, 0), xr = std::min(x + 1, w - 1);
        for (int ch = 0; ch < c; ++ch)
          o[x * c + ch] = mid * v[x * c + ch] + side * (v[xl * c + ch] + v[xr * c + ch]);
      }
    }
  });
  return out;
}

FloatImage restore_half_resolution(ImageView denoised, int height, int width, ImageView albedo,
                                   ImageView albedo_blocks, ImageView normal,
                                   ImageView normal_blocks, const HalfRestoreOptions& options) {
  check_doubling(denoised, "restore_half_resolution: denoised", height, width);
  const int c = denoised.channels;
  const bool with_albedo = !albedo.empty() || !albedo_blocks.empty();
  const bool with_normal = with_albedo && (!normal.empty() || !normal_blocks.empty());
  if (with_albedo) {
    check_shape(albedo, "restore_half_resolution: albedo", height, width, c);
    check_shape(albedo_blocks, "restore_half_resolution: albedo_blocks", denoised.height,
                denoised.width, c);
  }
  if (with_normal) {
    check_shape(normal, "restore_half_resolution: normal", height, width, 3);
    check_shape(normal_blocks, "restore_half_resolution: normal_blocks", denoised.height,
                denoised.width, 3);
  }
  if (!(options.albedo_floor >= 0.0f && options.albedo_floor <= 1.0f))
    throw_error<InvalidArgument>("restore_half_resolution: albedo_floor must be in [0, 1], got ",
                                 options.albedo_floor);
  if (!(options.edge_cos_lo < options.edge_cos_hi))
    throw_error<InvalidArgument>("restore_half_resolution: edge_cos_lo (", options.edge_cos_lo,
                                 ") must be below edge_cos_hi (", options.edge_cos_hi, ")");
  const float floor = options.albedo_floor;
  const auto lo = static_cast<float>(options.edge_cos_lo);
  const auto span = static_cast<float>(options.edge_cos_hi - options.edge_cos_lo);
  FloatImage out = shaped_like(height, width, c);
  const std::size_t stride = static_cast<std::size_t>(width) * c;
  parallel_for(static_cast<std::size_t>(height), options.num_threads, 16,
               [&](std::size_t b, std::size_t e) {
                 std::vector<float> vertical(static_cast<std::size_t>(denoised.width) * c);
                 std::vector<float> ab(stride), nb(static_cast<std::size_t>(width) * 3);
                 std::vector<float> nvert(static_cast<std::size_t>(denoised.width) * 3);
                 for (std::size_t y = b; y < e; ++y) {
                   const int yi = static_cast<int>(y);
                   float* o = out.data.data() + y * stride;
                   doubled_row(denoised, yi, width, vertical.data(), o);
                   if (with_albedo) {
                     doubled_row(albedo_blocks, yi, width, vertical.data(), ab.data());
                     if (with_normal)
                       doubled_row(normal_blocks, yi, width, nvert.data(), nb.data());
                     const float* a = albedo.data + y * stride;
                     const float* n = with_normal ? normal.data + y * width * 3 : nullptr;
                     for (int x = 0; x < width; ++x) {
                       float g = 1.0f;
                       if (n != nullptr) {
                         const float* p = n + x * 3;
                         const float* q = nb.data() + x * 3;
                         const float dot = p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
                         const float pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
                         const float qq = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
                         const float norms = std::sqrt(pp * qq);
                         const float cosine = dot / std::max(norms, 1e-12f);
                         g = std::clamp((cosine - lo) / span, 0.0f, 1.0f);
                         if (!(g == g)) g = 0.0f;  // NaN normals: no ratio
                       }
                       for (int ch = 0; ch < c; ++ch) {
                         const std::size_t k = static_cast<std::size_t>(x) * c + ch;
                         const float ratio = std::max(a[k], floor) / std::max(ab[k], floor);
                         o[k] *= n != nullptr ? 1.0f + g * (ratio - 1.0f) : ratio;
                       }
                     }
                   }
                   for (std::size_t k = 0; k < stride; ++k) o[k] = std::max(o[k], 0.0f);
                 }
               });
  return out;
}

}  // namespace mgn
