#pragma once
/// @file path_tracer.hpp  Physically based CPU path tracer on Embree.
///
/// Units and frames: lengths in metres, angles in radians, poses X_AB map frame B to frame A; the
/// world frame W is the frame of the mesh poses and of the camera pose X_WC. The camera model is
/// the one of camera.hpp (OpenCV frame: x right, y down, z forward; pixel (u, v) covers the square
/// [u, u+1) x [v, v+1) of continuous image coordinates and has its centre at (u + 0.5, v + 0.5)),
/// so the depth and instance-id passes equal the raster passes and mgn::camera_rays.
///
/// Radiance convention: linear RGB radiance in arbitrary but consistent units (W sr^-1 m^-2 per
/// unit colour). An emitter of radiance L seen directly shows L in the image; a white Lambertian
/// surface under irradiance E shows E / pi. Material colours are linear RGB reflectances in
/// [0, 1]. The rendered image is the mean radiance over the pixel's samples (before exposure);
/// develop() turns it into 8-bit sRGB.
///
/// Algorithm: unidirectional path tracing with next-event estimation (at every non-specular
/// vertex one shadow ray to a point on one area light chosen by power, and one to the
/// environment, sampled by a cosine lobe around the shading normal mixed with the sun cone) and
/// multiple importance sampling (power heuristic, beta = 2) between light and BSDF sampling for
/// the area lights, the emissive triangles (faces whose material has emission > 0, sampled
/// uniformly by area and chosen by power together with the area lights) and the environment;
/// Russian roulette from PathTraceOptions::rr_depth on (smooth glass vertices not counted).
/// Materials follow glTF 2.0 metallic-roughness: a Lambertian diffuse lobe under a GGX
/// (Trowbridge-Reitz) specular lobe with the height-correlated Smith masking-shadowing term and
/// visible-normal sampling; exact dielectric Fresnel (ior) for the specular layer of non-metals,
/// Schlick's Fresnel with F0 = base colour for metals; `transmission` blends in a dielectric
/// (Fresnel reflection, refraction, total internal reflection; each refraction tints by the square
/// root of the base colour, so light through a closed wall, in and out, is tinted by the base
/// colour once): smooth (a delta lobe) below roughness ~0.055 (GGX alpha 0.003), above it a rough
/// dielectric (GGX reflection and refraction after Walter et al. 2007, visible-normal sampling).
/// Every GGX lobe of roughness above ~0.055 gets the multiple-scattering energy compensation of
/// Kulla and Conty 2017 (metals coloured by the average Fresnel; the rough dielectric from both
/// sides, reciprocal), and the diffuse lobe is weighted by what the rough specular layer above it
/// does not reflect: a white material in a uniform environment shows that environment at any
/// roughness (docs/rendering.md, "Multiple scattering between microfacets"). Meshes
/// are closed or open triangle soups; a surface whose geometric normal faces the ray is entered,
/// otherwise left (for refraction). Shading normals are per-corner normals averaged over the
/// faces around a vertex whose normals are within 45 degrees (sharp creases keep flat normals);
/// where the shading normal would face away from the viewer the geometric normal is used.
/// At a smooth dielectric the reflected and the refracted ray are both followed: at the first
/// three such vertices of a camera sample as full paths (each weighted by its Fresnel share),
/// later only to the light they meet first, the path continuing along one chosen at random.
/// Samples come from an Owen-scrambled (hash-based nested uniform scrambling) 2-D Sobol sequence
/// per dimension pair, shared by the pixels of each 64 x 64 block in Morton order, so that the
/// samples of neighbouring pixels are stratified together (blue-noise error); seeded from (seed,
/// view_index, block): images are bit-identical for any number of threads.

#include <mgn/geometry/mesh.hpp>
#include <mgn/render/camera.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace mgn {

/// glTF 2.0 metallic-roughness material (+ KHR_materials_transmission / KHR_materials_ior).
struct PbrMaterial {
  Vec3f base_color = Vec3f(0.8f, 0.8f, 0.8f);  ///< linear RGB in [0, 1]
  float metallic = 0.0f;                       ///< [0, 1]
  float roughness = 0.5f;                      ///< perceptual roughness [0, 1]; GGX alpha = r^2
  /// Index of refraction (>= 1) of the specular layer and of the dielectric; 1 = no specular
  /// layer (a pure Lambertian surface when metallic = 0).
  float ior = 1.5f;
  float transmission = 0.0f;       ///< [0, 1]; 1 = clear dielectric (glass)
  Vec3f emission = Vec3f::Zero();  ///< emitted radiance (front side), linear RGB >= 0
  /// Base colour texture: 8-bit sRGB RGB, row-major, top row first, `texture_width` x
  /// `texture_height` (empty = none). Multiplies base_color; looked up at the mesh uvs with
  /// (u, v) -> column u * width, row (1 - v) * height, bilinear, repeating.
  std::vector<std::uint8_t> texture;
  int texture_width = 0;
  int texture_height = 0;

  /// Throws InvalidArgument naming `what` and the setting if a value is out of range or
  /// non-finite, or the texture size does not match.
  void validate(const std::string& what) const;
};

/// One-sided area light emitting uniformly (Lambertian) towards +z of its frame L.
struct AreaLight {
  enum class Shape { Rect, Disc };
  Pose X_WL = Pose::Identity();  ///< pose of the light frame in the world (rigid)
  Shape shape = Shape::Rect;
  /// Rect: full side lengths along x_L and y_L (m). Disc: radius in size.x() (m).
  Eigen::Vector2d size = Eigen::Vector2d(0.5, 0.5);
  Vec3f color = Vec3f(1.0f, 1.0f, 1.0f);  ///< linear RGB >= 0
  float intensity = 10.0f;                ///< radiance = color * intensity (>= 0)

  void validate(const std::string& what) const;
};

/// Infinitely distant environment seen by rays that escape. World +z is "up".
struct Environment {
  enum class Kind { Uniform, Gradient, Sky };
  Kind kind = Kind::Uniform;
  Vec3f color = Vec3f(1.0f, 1.0f, 1.0f);  ///< Uniform: radiance colour
  /// Gradient / Sky: radiance straight up, at the horizon and below the horizon. Above the
  /// horizon the colour goes linearly in sqrt(d.z) from horizon to zenith; below it is `ground`.
  Vec3f zenith = Vec3f(0.6f, 0.7f, 0.9f);
  Vec3f horizon = Vec3f(0.9f, 0.9f, 0.9f);
  Vec3f ground = Vec3f(0.3f, 0.3f, 0.3f);
  /// Sky only: direction towards the sun (world, need not be unit). The sun is a disc of angular
  /// radius `sun_angular_radius` whose irradiance at normal incidence is `sun_strength` times
  /// pi * luminance(zenith) (white, times intensity), plus the gradient sky.
  Vec3d sun_direction = Vec3d(0.3, 0.2, 0.93);
  float sun_strength = 3.0f;
  float sun_angular_radius = 0.035f;  ///< rad (about 2 degrees: soft sun shadows)
  float intensity = 1.0f;             ///< scales everything (>= 0)

  void validate(const std::string& what) const;
};

/// One mesh placed in the path-traced scene.
struct PathGeometry {
  const Mesh* mesh = nullptr;    ///< copied at build time
  Pose X_WO = Pose::Identity();  ///< pose of the mesh in the world
  std::int32_t instance_id = 0;  ///< >= 0; reported in the instance pass (0 = background)
  /// One material per mesh material slot: max(1, mesh->materials().size()) entries; face f uses
  /// materials[mesh->face_materials()[f]] (or [0] without face materials).
  std::vector<PbrMaterial> materials;
};

struct PathTraceOptions {
  int spp = 16;                  ///< samples per pixel (>= 1)
  int max_bounces = 6;           ///< path segments after the camera ray (>= 0; 0 = emission only)
  std::uint64_t seed = 0;        ///< scene seed
  std::uint64_t view_index = 0;  ///< view number; sample streams derive from (seed, view, pixel)
  int num_threads = 0;           ///< 0 = all hardware threads; image identical for any value
  /// Russian roulette from this bounce on (>= 0), not counting the vertices where the path was
  /// reflected or refracted by a smooth dielectric (what is seen through glass is rouletted as
  /// late as what is seen directly). Default 2 (docs/decisions/0024-path-tracer-glass-sampling.md).
  int rr_depth = 2;
  double aperture_radius = 0.0;  ///< thin-lens aperture radius, m (>= 0; 0 = pinhole)
  /// Distance of the plane in focus along the optical axis, m (>= 0; 0 = the depth at the image
  /// centre, or 1 m if nothing is seen there).
  double focus_distance = 0.0;
  double clamp = 0.0;  ///< max luminance of one sample (>= 0; 0 = no clamping)
  /// Max luminance of one indirect contribution of a sample (light found at the second path
  /// vertex or later, e.g. caustics through glass) (>= 0; 0 = off). The default 10 leaves
  /// ordinary indirect light alone (contributions of order 1) and removes the fireflies of
  /// caustic paths (diffuse -> glass -> sun), at the cost of a small bias (caustics are dimmed).
  double clamp_indirect = 10.0;
  /// Fresnel splitting at a smooth dielectric (both the reflected and the refracted ray meet
  /// their first light, docs/rendering.md) after the first glass walls, whose two branches are
  /// traced in full, only while the path's throughput (largest channel) is at least this (>= 0;
  /// 0 = always). Below it the path follows its random direction alone: unbiased, one ray fewer
  /// per glass vertex of dim paths (deep inside bottles, behind reflections). Default 0.1
  /// (docs/decisions/0024-path-tracer-glass-sampling.md).
  double fresnel_split_min = 0.1;
  /// The denoiser guides of the other direction at a split smooth dielectric are followed
  /// behind further glass only when that direction's share of the pixel's guide is at least
  /// this (>= 0; 0 = always); otherwise the continuing path's guide takes its share. Guides
  /// only: the radiance is unchanged.
  double guide_split_min = 0.1;
  /// Shadow rays per path vertex for next-event estimation (1 or 2). 2: one to a light (area
  /// light or emissive triangle, chosen by power) and one to the environment. 1: one ray, to
  /// the environment or to a light, each chosen with probability 1/2 (when the scene has both).
  int shadow_rays = 2;
  /// Next-event estimation of the environment's dome (all of it but the sun). true: a shadow
  /// ray per path vertex towards a cosine-weighted direction of the dome (with the sun's cone,
  /// if any); false: the dome is found by the BSDF-sampled ray that continues the path (the
  /// same cosine-weighted distribution at a diffuse surface), and shadow rays aim at the sun
  /// only (none without a sun).
  bool sample_sky_dome = true;
  /// Path vertices from this depth on (0 = the camera ray's hit, 1 = the first bounce's hit,
  /// ...; >= 0) follow shadow_rays and sample_sky_dome; the vertices before it cast both shadow
  /// rays.
  int reduced_nee_depth = 0;
  /// Label images (PathTraceOutput::depth and instance_ids): one coherent packet of pinhole rays
  /// through the pixel centres per tile row. false skips those rays (both images stay 0): the
  /// dataset pipeline takes its labels from the ray-cast label pass and keeps only the image.
  bool labels = true;
  /// Adaptive sampling (docs/rendering.md): after the `spp` samples of every pixel, this many
  /// extra samples per pixel on average (>= 0; 0 = off) go where the first pass looks noisiest
  /// (9x9 neighbourhood variance weighted by a display curve), at most `adaptive_max` per pixel
  /// (1..64). The extra samples come from their own stream of (seed, view, pixel, index), so the
  /// image stays identical for any num_threads. Slightly biased at low spp: a pixel's own first
  /// samples take part in the decision (clamped so that one firefly does not decide alone).
  /// Off by default (docs/decisions/0028-path-adaptive-sampling-off.md).
  double adaptive_samples = 0.0;
  int adaptive_max = 3;

  void validate() const;
};

/// Images of one view, row-major, top row first.
struct PathTraceOutput {
  int width = 0, height = 0;
  std::vector<float> radiance;  ///< (H,W,3) mean linear radiance
  std::vector<float> albedo;    ///< (H,W,3) mean first-hit albedo (denoiser auxiliary)
  std::vector<float> normal;    ///< (H,W,3) unit mean first-hit shading normal, world (0 = none)
  std::vector<float> depth;     ///< (H,W) z-depth (m) through the pixel centre, 0 = none
  std::vector<std::int32_t> instance_ids;  ///< (H,W) instance id at the pixel centre, 0 = none
  std::int64_t rays = 0;                   ///< rays cast (camera, bounce and shadow rays)
};

/// Immutable path-traced scene: Embree geometry (through mgn::RayScene) plus per-corner shading
/// normals, uvs and materials; thread-safe.
class PathScene {
 public:
  /// Throws InvalidArgument (naming the geometry index and the setting) for an empty list, a null
  /// or empty mesh, a non-finite pose, a negative instance id, a wrong number of materials, an
  /// invalid material, light or environment.
  PathScene(const std::vector<PathGeometry>& geometries, const std::vector<AreaLight>& lights = {},
            const Environment& environment = {});
  ~PathScene();
  PathScene(const PathScene&);
  PathScene& operator=(const PathScene&);
  PathScene(PathScene&&) noexcept;
  PathScene& operator=(PathScene&&) noexcept;

  /// A scene sharing this one's geometry (no copy) with other lights and environment.
  PathScene with_lighting(const std::vector<AreaLight>& lights,
                          const Environment& environment) const;

  std::int64_t num_triangles() const;
  const std::vector<AreaLight>& lights() const;
  const Environment& environment() const;

  /// Renders one view. Throws InvalidArgument for invalid options or view.
  PathTraceOutput render(const CameraView& view, const PathTraceOptions& options = {}) const;

  struct Geometry;
  struct Lighting;

 private:
  std::shared_ptr<const Geometry> geometry_;
  std::shared_ptr<const Lighting> lighting_;
};

/// Film / sensor development of a radiance image.
struct FilmOptions {
  double exposure = 0.0;  ///< EV stops: radiance is multiplied by 2^exposure
  /// "filmic": y = 1 - exp(-x) per channel (an exponential film response: about linear in the
  /// shadows, a soft shoulder, never clips), then the sRGB OETF. "linear": clip to [0, 1], sRGB.
  enum class Tone { Filmic, Linear };
  Tone tone = Tone::Filmic;
  /// Sensor noise added to the exposed linear value x before the tone curve:
  /// x + shot_noise * sqrt(max(x, 0)) * N1 + read_noise * N2, with N1, N2 standard normal
  /// variates drawn per pixel and channel from (seed, view_index, pixel).
  double shot_noise = 0.0;
  double read_noise = 0.0;
  std::uint64_t seed = 0;
  std::uint64_t view_index = 0;
  int num_threads = 0;

  void validate() const;
};

/// (H,W,3) linear radiance -> (H,W,3) 8-bit sRGB (row-major). Throws InvalidArgument for a size
/// mismatch or invalid options. Non-finite radiance becomes 0.
std::vector<std::uint8_t> develop(const std::vector<float>& radiance, int width, int height,
                                  const FilmOptions& film = {});

/// Decodes the base colour texture of a mesh material (embedded bytes or file) to 8-bit sRGB RGB,
/// row-major, top row first. Returns false if the material has no texture; throws IoError if it
/// cannot be decoded or read.
bool decode_base_color_texture(const Material& material, std::vector<std::uint8_t>& rgb, int& width,
                               int& height);

}  // namespace mgn
