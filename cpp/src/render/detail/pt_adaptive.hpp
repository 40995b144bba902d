#pragma once
// Adaptive sampling of the path tracer (docs/rendering.md, "Adaptive sampling"): where a first
// pass looks noisy, and how many extra samples each pixel gets under a fixed total.

#include <cstdint>
#include <vector>

namespace mgn::pt {

/// Per-pixel noise estimate of a first-pass image, in the units of a perceptual variance
/// (relative values only matter). `radiance` and `albedo` are (H,W,3) row-major means of the
/// first pass. For each pixel: the variance over the 9x9 neighbourhood of the luminance divided
/// by the albedo guide's luminance (so that textures and edges between materials count less
/// than noise), each value first clamped to 4x its neighbourhood mean (a single firefly must not
/// decide its own pixel's samples: that would dim it, a bias), times the pixel's albedo
/// luminance squared (back to radiance units) and times the slope of a display curve at the
/// neighbourhood's exposed luminance, (E * mean)^-1.1 with E = 1 / the image's 99.5th
/// luminance percentile (noise in dark regions is seen more than the same noise in bright ones).
std::vector<float> noise_estimate(const std::vector<float>& radiance,
                                  const std::vector<float>& albedo, int width, int height);

/// Extra samples per pixel: e_i = min(max_extra, floor(estimate_i / t)) with the smallest
/// threshold t whose total sum_i e_i is <= round(mean_extra * pixels). Deterministic (no
/// threads); pixels with estimate 0 get none.
std::vector<std::uint8_t> allocate_extra_samples(const std::vector<float>& estimate,
                                                 double mean_extra, int max_extra);

}  // namespace mgn::pt
