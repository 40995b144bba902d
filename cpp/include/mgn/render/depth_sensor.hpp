#pragma once
/// @file depth_sensor.hpp  Depth sensor models applied to an ideal rendered z-depth image.
///
/// Input: the renderer's metric z-depth (m, 0 = nothing seen), its instance ids and per-instance
/// surface flags (transparent / dark / mirror-like, see surface_flags). Output: the sensor's
/// depth in metres with **invalid pixels = NaN** (nothing seen, out of range, projector shadow,
/// transparent / dark / mirror surfaces), plus the noise-free input kept unchanged.
///
/// Presets:
///   - Ideal: the rendered depth; only pixels where nothing is seen (or out of range) are invalid.
///   - StructuredLight: an industrial projector-camera sensor: sub-millimetre noise growing with
///     z^2, invalid pixels where the projector (offset by `baseline` along camera +x) cannot see
///     the surface (shadows beside depth discontinuities), and on transparent, dark and
///     mirror-like surfaces.
///   - ToF: a Kinect-like time-of-flight camera: axial noise sigma(z) = a + b (z - z0)^2 with
///     a = 1.2 mm, b = 1.9 mm/m^2, z0 = 0.4 m (the model fitted by Nguyen, Izadi and Lovell, 2012),
///     flying pixels (depths between foreground and background) at depth edges, invalid on
///     transparent, dark and mirror-like surfaces.
/// Randomness: row v draws from Rng(seed, v) (its flying-pixel uniforms, then its pixels' normals
/// from Rng::normals), so results do not depend on the thread count.

#include <mgn/geometry/mesh.hpp>
#include <mgn/render/camera.hpp>

#include <cstdint>
#include <vector>

namespace mgn {

enum class DepthSensorPreset { Ideal, StructuredLight, ToF };

/// Bits of a surface's flags.
enum SurfaceFlag : std::uint8_t {
  /// opacity * base alpha < 0.5, or (PBR) transmission >= 0.5
  kSurfaceTransparent = 1,
  kSurfaceDark = 2,  ///< untextured, base colour luminance < 0.03 (linear)
  /// specular luminance >= 0.8 and shininess >= 200, or (PBR) metallic >= 0.5 and
  /// roughness <= 0.25 (polished metal)
  kSurfaceMirror = 4,
};

/// Flags of a material by the thresholds documented on SurfaceFlag.
std::uint8_t surface_flags(const Material& material);
/// Flags of a mesh: the union over its materials (0 if it has none).
std::uint8_t surface_flags(const Mesh& mesh);

/// Parameters of a depth sensor model (SI units).
struct DepthSensorParams {
  DepthSensorPreset preset = DepthSensorPreset::Ideal;
  double min_range = 0.0;  ///< m; closer pixels are invalid
  double max_range = 1e9;  ///< m; farther pixels are invalid
  double sigma_a = 0.0;    ///< m; axial noise sigma(z) = sigma_a + sigma_b (z - sigma_z0)^2
  double sigma_b = 0.0;    ///< 1/m
  double sigma_z0 = 0.0;   ///< m
  double baseline = 0.0;   ///< m; projector offset along camera +x (0 = no projector shadows)
  double shadow_tolerance_px = 0.0;       ///< px; slack of the projector visibility test
  double edge_threshold = 0.0;            ///< m; depth jump to a neighbour that makes an edge pixel
  double flying_pixel_probability = 0.0;  ///< chance that an edge pixel becomes a flying pixel
  /// m; the sensor reports z on this grid (round to nearest; 0 = continuous). Real sensors
  /// quantise (sub-pixel disparity, phase); a grid of 1/256 cm lets the files store the depth
  /// exactly in fewer bytes (docs/format.md).
  double depth_step = 0.0;
  /// The reported grid grows with the noise, as a triangulating sensor's does (its depth step is a
  /// fixed fraction of a pixel of disparity, z^2 / (f b) of it, like the z^2 noise): at a pixel
  /// whose noise is sigma the grid is the largest 2^k depth_step (k >= 0) not above
  /// `depth_step_noise_fraction` * sigma (0 = the fixed depth_step). 0.5 adds at most
  /// sigma^2 / 48 of variance (+1 % of sigma) and keeps every value on the depth_step grid.
  double depth_step_noise_fraction = 0.0;
  bool invalid_transparent = false;
  bool invalid_dark = false;
  bool invalid_mirror = false;

  /// Default parameters of a preset:
  ///   Ideal: no noise, no invalidation except nothing seen.
  ///   StructuredLight: range 0.3..2.0 m, sigma = 0.1 mm + 0.2 mm/m^2 * z^2 (0.3 mm at 1 m),
  ///     baseline 0.1 m, invalid on transparent/dark/mirror surfaces, z on a power-of-two
  ///     multiple of 1/256 cm (0.039 mm) not above half the noise (depth_step_noise_fraction
  ///     0.5: 1/128 cm at 0.53..1.03 m, 1/64 cm to 1.62 m).
  ///   ToF: range 0.5..4.5 m, sigma = 1.2 mm + 1.9 mm/m^2 (z - 0.4 m)^2, edges at 2 cm jumps,
  ///     flying pixel probability 0.5, invalid on transparent/dark/mirror surfaces, z on a
  ///     power-of-two multiple of 1/64 cm (0.156 mm) not above half the noise.
  static DepthSensorParams preset_defaults(DepthSensorPreset preset);
  /// Throws InvalidArgument for negative or non-finite values, min_range > max_range or a
  /// probability outside [0, 1].
  void validate() const;
};

/// Output of a sensor model.
struct DepthImage {
  int width = 0;
  int height = 0;
  std::vector<float> depth;         ///< (H*W) sensor z-depth, m, NaN = invalid
  std::vector<float> depth_ideal;   ///< (H*W) the input, m, 0 = nothing seen
  std::vector<std::uint8_t> valid;  ///< (H*W) 1 where depth is valid
};

/// Applies a sensor model. `depth` and `instance_ids` are (H*W) row-major images of
/// K.width x K.height; flags_by_id[id] are the SurfaceFlag bits of instance id `id` (ids beyond the
/// vector have no flags). Throws InvalidArgument for mismatched sizes, negative or non-finite
/// depths, or invalid intrinsics / parameters. Rows run on up to `num_threads` threads (0 = all);
/// the result is the same for any thread count.
DepthImage apply_depth_sensor(const std::vector<float>& depth,
                              const std::vector<std::int32_t>& instance_ids,
                              const std::vector<std::uint8_t>& flags_by_id, const Intrinsics& K,
                              const DepthSensorParams& params, std::uint64_t seed,
                              int num_threads = 0);

}  // namespace mgn
