#pragma once
/// @file renderer.hpp  Off-screen RGB-D and instance-id rendering (OSMesa, llvmpipe, GL 4.5 core).
///
/// A Renderer owns one OSMesa GL context, created once and reused for every render. Meshes are
/// uploaded once (add_mesh) and then placed as instances (set_instances). Each render() produces,
/// for one CameraView (camera.hpp, OpenCV frame):
///   - rgb: (H, W, 3) uint8 sRGB, Blinn-Phong shading of the materials (diffuse texture times base
///     colour, specular highlight), a main point light with shadow mapping plus ambient light,
///     transparent materials (opacity < 1) alpha-blended over what is behind them;
///   - depth: (H, W) float32 metric z-depth in metres (the camera-frame z of the first surface
///     through the pixel centre), 0 where nothing is seen; transparent surfaces are seen;
///   - instance_ids: (H, W) int32 instance id of the first surface, 0 = background.
/// All images are row-major, top row first (row v, column u = pixel (u, v) of the camera model).
///
/// Thread safety: a Renderer may be used by one thread at a time (calls are serialised by an
/// internal mutex). Separate processes may each run their own Renderer in parallel. Several
/// Renderers in one process work too (each makes its context current for the duration of a call).

#include <mgn/geometry/mesh.hpp>
#include <mgn/render/camera.hpp>

#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

namespace mgn {

/// One placed copy of an uploaded mesh.
struct Instance {
  int mesh_id = 0;               ///< id returned by Renderer::add_mesh
  Pose X_WO = Pose::Identity();  ///< pose of the mesh (object frame O) in the world
  std::int32_t instance_id = 0;  ///< written to the instance pass (>= 0; 0 = background/no label)
  /// Domain randomisation of this instance's colour (e.g. tote, floor): when
  /// RenderOptions::randomize is on, its base colour is replaced by a random one per view.
  bool randomize_color = false;
};

/// The main light as used for one view (input when not randomised, output in RenderOutput).
struct LightSample {
  /// Point light position, world frame, m. NaN = default: 1.5 m above the centre of the drawn
  /// geometry, offset 0.3 m along x and -0.2 m along y.
  Vec3d position_W = Vec3d::Constant(std::numeric_limits<double>::quiet_NaN());
  double intensity = 1.0;             ///< scale of the light's radiance (1 = nominal)
  double color_temperature = 6500.0;  ///< K (white at 6500)
  double ambient = 0.25;              ///< ambient light level relative to white
};

/// What to render and how.
struct RenderOptions {
  bool rgb = true;        ///< produce the colour image
  bool depth = true;      ///< produce the z-depth image
  bool instances = true;  ///< produce the instance-id image
  /// If non-empty, only instances with these instance ids are drawn (e.g. one object alone for its
  /// amodal mask). An instance-id-only pass of a subset skips shading and shadows.
  std::vector<std::int32_t> visible_instances;
  bool shadows = true;  ///< shadow mapping from the main light (RGB only)
  /// Domain randomisation: when true the light (position, intensity, colour temperature,
  /// ambient) and the colours of instances marked randomize_color are drawn from
  /// Rng(seed, view_index); when false `light` is used as given.
  bool randomize = false;
  std::uint64_t seed = 0;
  std::uint64_t view_index = 0;
  /// Light used when randomize is false.
  LightSample light;
  Vec3f background = Vec3f(0.0f, 0.0f, 0.0f);  ///< linear RGB of empty pixels
  /// Check that the camera centre is not inside a closed mesh of the scene (e.g. a tote wall);
  /// the check costs one ray-parity test per mesh whose bounds contain the camera.
  bool check_camera_inside = true;
  /// Throws InvalidArgument "RenderOptions.<field> must be ...": at least one pass requested,
  /// a finite background, and (when randomize is false) light.intensity and light.ambient finite
  /// and >= 0.
  void validate() const;
};

/// Images of one render; empty vectors for passes not requested.
struct RenderOutput {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;           ///< (H*W*3) sRGB, top row first
  std::vector<float> depth;                ///< (H*W) z-depth, m, 0 = nothing
  std::vector<std::int32_t> instance_ids;  ///< (H*W), 0 = background
  LightSample light;                       ///< the light actually used
};

/// Off-screen renderer owning one OSMesa context and framebuffers of at most max_width x
/// max_height pixels.
class Renderer {
 public:
  /// Creates the GL context and framebuffers. Throws InvalidArgument for a size outside
  /// 1..16384, BackendError if OSMesa cannot create a GL 4.5 core context.
  Renderer(int max_width, int max_height);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  int max_width() const;
  int max_height() const;

  /// Uploads a mesh (vertices, smooth normals, uvs, per-material face groups, textures decoded
  /// from Material::texture_data or Material::texture_path with OpenCV) and returns its id.
  /// Throws InvalidArgument for an empty mesh, IoError for an unreadable texture.
  int add_mesh(const Mesh& mesh);
  int num_meshes() const;

  /// Replaces the placed instances. Throws InvalidArgument for an unknown mesh id, a negative
  /// instance id or a pose that is not a finite rigid transform.
  void set_instances(std::vector<Instance> instances);
  const std::vector<Instance>& instances() const;

  /// Renders one view. Throws InvalidArgument if the view is invalid (zero focal length, NaN
  /// pose), larger than the framebuffers, if nothing is to be drawn (no instances, or none of
  /// visible_instances), if no pass is requested, or if the camera centre is inside a closed
  /// mesh (check_camera_inside).
  RenderOutput render(const CameraView& view, const RenderOptions& options = {});

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// Linear RGB (max component 1) of a black body at `kelvin` (1000..40000 K), from Planck's law
/// sampled at 610, 550 and 465 nm and normalised to 6500 K = white.
Vec3d color_temperature_rgb(double kelvin);

}  // namespace mgn
