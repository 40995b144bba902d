#pragma once
/// @file half_resolution.hpp  The image arithmetic around a half-resolution denoise.
///
/// The path tracer's denoiser can run on the means of 2 x 2 pixel blocks (a quarter of the
/// pixels) and bring the result back to full size: the denoised blocks are interpolated
/// bilinearly and multiplied, per pixel and channel, by the ratio of the full-size albedo to the
/// blocks' interpolated albedo, so that texture and print stay sharp; where the pixel's normal
/// turns away from its blocks' (silhouettes, creases) the ratio fades to 1. docs/rendering.md
/// ("Where the time of a view goes", the denoiser resolution) describes the method and
/// docs/decisions/0036-denoise-at-half-resolution.md why it was chosen.
///
/// Images are row-major float32 arrays of (height, width, channels), channels innermost. Every
/// function works row by row on up to `num_threads` threads (0 = all hardware threads); results
/// do not depend on the thread count.

#include <cstddef>
#include <vector>

namespace mgn {

/// A float32 image: `data` holds height * width * channels values, row-major, channels last.
struct FloatImage {
  int height = 0;
  int width = 0;
  int channels = 0;
  std::vector<float> data;
};

/// A read-only view of a float32 image laid out like FloatImage (`data` == nullptr: no image).
struct ImageView {
  const float* data = nullptr;
  int height = 0;
  int width = 0;
  int channels = 0;
  ImageView() = default;
  ImageView(const float* d, int h, int w, int c) : data(d), height(h), width(w), channels(c) {}
  ImageView(const FloatImage& img)  // NOLINT(google-explicit-constructor): a view of it
      : data(img.data.data()), height(img.height), width(img.width), channels(img.channels) {}
  bool empty() const { return data == nullptr; }
};

/// Means of the 2 x 2 pixel blocks of `img` (the pixels of an odd last row or column repeated):
/// a (ceil(H / 2), ceil(W / 2), C) image. Throws InvalidArgument for an empty image or a data
/// null data.
FloatImage block_means_2x2(ImageView img, int num_threads = 0);

/// Bilinear doubling of a block image to (height, width) (height <= 2 * blocks' height, width
/// alike): block centres at the centres of their 2 x 2 pixels, so pixel 2i takes 3/4 of block i
/// and 1/4 of block i - 1, pixel 2i + 1 3/4 of block i and 1/4 of block i + 1 (border blocks
/// repeated outwards); rows first, then columns.
FloatImage double_blocks(ImageView blocks, int height, int width, int num_threads = 0);

/// Separable 3 x 3 Gaussian of standard deviation `sigma` pixels (border pixels repeated
/// outwards); weights (e, 1, e) / (1 + 2e) with e = exp(-1 / (2 sigma^2)). Rows first, then
/// columns.
FloatImage gaussian_3x3(ImageView img, double sigma = 0.5, int num_threads = 0);

/// Settings of restore_half_resolution().
struct HalfRestoreOptions {
  /// Albedo floor of the ratio max(a, floor) / max(a_blocks, floor), in [0, 1].
  float albedo_floor = 0.02f;
  /// Cosines between a pixel's normal and its blocks' interpolated normal: below `edge_cos_lo`
  /// the albedo ratio is not applied, above `edge_cos_hi` fully, linearly in between.
  double edge_cos_lo = 0.85;
  double edge_cos_hi = 0.97;
  int num_threads = 0;
};

/// The full-size image of a half-resolution denoise:
/// `out = max(0, double(denoised) * (1 + g (max(a, floor) / max(double(a_blocks), floor) - 1)))`
/// per channel, with g from the cosine between `normal` and double(`normal_blocks`) (g = 1 without
/// normals; a zero normal gives g = 0). `albedo` and `normal` are full size (height, width, 3),
/// `albedo_blocks` and `normal_blocks` block size like `denoised`; either pair may be empty
/// (ImageView::empty()): without albedo the interpolation alone is returned. Throws InvalidArgument
/// naming the image whose shape does not fit.
FloatImage restore_half_resolution(ImageView denoised, int height, int width, ImageView albedo,
                                   ImageView albedo_blocks, ImageView normal,
                                   ImageView normal_blocks, const HalfRestoreOptions& options = {});

}  // namespace mgn
