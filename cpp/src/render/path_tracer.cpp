#include <mgn/core/error.hpp>
#include <mgn/core/parallel.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/render/path_tracer.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <atomic>
#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <tuple>

#include "raytrace/detail/ray_scene_impl.hpp"
#include "render/detail/pt_adaptive.hpp"
#include "render/detail/pt_math.hpp"

namespace mgn {

using pt::F3;

namespace {

bool finite3(const Vec3f& v) { return v.allFinite(); }

void check_unit_range(const std::string& what, const char* name, float v) {
  if (!(v >= 0.0f && v <= 1.0f))
    throw_error<InvalidArgument>(what, ": PbrMaterial.", name, " must be in [0, 1], got ", v);
}

void check_colour(const std::string& what, const char* cls, const char* name, const Vec3f& c,
                  bool unit) {
  if (!finite3(c) || c.minCoeff() < 0.0f || (unit && c.maxCoeff() > 1.0f)) {
    throw_error<InvalidArgument>(what, ": ", cls, ".", name, " must be ",
                                 unit ? "3 values in [0, 1]" : "3 finite values >= 0", ", got (",
                                 c.x(), ", ", c.y(), ", ", c.z(), ")");
  }
}

void check_rigid(const std::string& what, const char* name, const Pose& X) {
  const Mat3d R = X.linear();
  if (!X.matrix().allFinite() ||
      (R.transpose() * R - Mat3d::Identity()).cwiseAbs().maxCoeff() > 1e-5 ||
      R.determinant() < 0.0) {
    throw_error<InvalidArgument>(what, ": ", name,
                                 " must be a finite rigid transform (orthonormal rotation)");
  }
}

F3 f3(const Vec3f& v) { return {v.x(), v.y(), v.z()}; }
F3 f3(const Vec3d& v) {
  return {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
}

float srgb_to_linear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

float linear_to_srgb(float c) {
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

struct SrgbLut {
  float v[256];
  SrgbLut() {
    for (int i = 0; i < 256; ++i) v[i] = srgb_to_linear(static_cast<float>(i) / 255.0f);
  }
};
const SrgbLut& srgb_lut() {
  static const SrgbLut lut;
  return lut;
}

constexpr float kMinAlpha = 2e-3f;         // GGX alpha floor (float precision of D near a delta)
constexpr float kCreaseCos = 0.70710678f;  // 45 degrees: normals are not smoothed across

}  // namespace

// ---------------------------------------------------------------------------------------------
// Validation.

void PbrMaterial::validate(const std::string& what) const {
  check_colour(what, "PbrMaterial", "base_color", base_color, true);
  check_unit_range(what, "metallic", metallic);
  check_unit_range(what, "roughness", roughness);
  check_unit_range(what, "transmission", transmission);
  if (!(ior >= 1.0f && ior <= 10.0f))
    throw_error<InvalidArgument>(what, ": PbrMaterial.ior must be in [1, 10], got ", ior);
  check_colour(what, "PbrMaterial", "emission", emission, false);
  if (texture_width < 0 || texture_height < 0 ||
      texture.size() != static_cast<std::size_t>(texture_width) * texture_height * 3) {
    throw_error<InvalidArgument>(what, ": PbrMaterial.base_color_texture has ", texture.size(),
                                 " bytes; expected width*height*3 = ", texture_width, "*",
                                 texture_height, "*3");
  }
}

void AreaLight::validate(const std::string& what) const {
  check_rigid(what, "AreaLight.X_WL", X_WL);
  if (!size.allFinite() || !(size.x() > 0.0) || !(size.y() > 0.0)) {
    throw_error<InvalidArgument>(what, ": AreaLight.size must be 2 values > 0 (m), got (", size.x(),
                                 ", ", size.y(), ")");
  }
  check_colour(what, "AreaLight", "color", color, false);
  if (!(intensity >= 0.0f) || !std::isfinite(intensity))
    throw_error<InvalidArgument>(what, ": AreaLight.intensity must be finite and >= 0, got ",
                                 intensity);
}

void Environment::validate(const std::string& what) const {
  check_colour(what, "Environment", "color", color, false);
  check_colour(what, "Environment", "zenith", zenith, false);
  check_colour(what, "Environment", "horizon", horizon, false);
  check_colour(what, "Environment", "ground", ground, false);
  if (!(intensity >= 0.0f) || !std::isfinite(intensity))
    throw_error<InvalidArgument>(what, ": Environment.intensity must be finite and >= 0, got ",
                                 intensity);
  if (kind == Kind::Sky) {
    if (!sun_direction.allFinite() || sun_direction.norm() == 0.0)
      throw_error<InvalidArgument>(what,
                                   ": Environment.sun_direction must be a finite non-zero vector");
    if (!(sun_strength >= 0.0f) || !std::isfinite(sun_strength))
      throw_error<InvalidArgument>(what, ": Environment.sun_strength must be finite and >= 0, got ",
                                   sun_strength);
    if (!(sun_angular_radius > 0.0f && sun_angular_radius < 0.5f))
      throw_error<InvalidArgument>(what,
                                   ": Environment.sun_angular_radius must be in (0, 0.5) rad, got ",
                                   sun_angular_radius);
  }
}

void PathTraceOptions::validate() const {
  const char* w = "PathTraceOptions";
  if (spp < 1) throw_error<InvalidArgument>(w, ".spp must be >= 1, got ", spp);
  if (max_bounces < 0 || max_bounces > 1000)
    throw_error<InvalidArgument>(w, ".max_bounces must be in [0, 1000], got ", max_bounces);
  if (num_threads < 0)
    throw_error<InvalidArgument>(w, ".num_threads must be >= 0 (0 = all), got ", num_threads);
  if (rr_depth < 0) throw_error<InvalidArgument>(w, ".rr_depth must be >= 0, got ", rr_depth);
  if (!(aperture_radius >= 0.0) || !std::isfinite(aperture_radius))
    throw_error<InvalidArgument>(w, ".aperture_radius must be finite and >= 0 (m), got ",
                                 aperture_radius);
  if (!(focus_distance >= 0.0) || !std::isfinite(focus_distance))
    throw_error<InvalidArgument>(w, ".focus_distance must be finite and >= 0 (m), got ",
                                 focus_distance);
  if (!(clamp >= 0.0) || !std::isfinite(clamp))
    throw_error<InvalidArgument>(w, ".clamp must be finite and >= 0 (0 = off), got ", clamp);
  if (!(clamp_indirect >= 0.0) || !std::isfinite(clamp_indirect))
    throw_error<InvalidArgument>(w, ".clamp_indirect must be finite and >= 0 (0 = off), got ",
                                 clamp_indirect);
  if (!(fresnel_split_min >= 0.0) || !std::isfinite(fresnel_split_min))
    throw_error<InvalidArgument>(
        w, ".fresnel_split_min must be finite and >= 0 (path throughput, 0 = always split), got ",
        fresnel_split_min);
  if (!(guide_split_min >= 0.0) || !std::isfinite(guide_split_min))
    throw_error<InvalidArgument>(
        w, ".guide_split_min must be finite and >= 0 (share of a pixel's guide, 0 = always), got ",
        guide_split_min);
  if (!(adaptive_samples >= 0.0) || !std::isfinite(adaptive_samples))
    throw_error<InvalidArgument>(
        w, ".adaptive_samples must be finite and >= 0 (extra samples per pixel, 0 = off), got ",
        adaptive_samples);
  if (adaptive_max < 1 || adaptive_max > 64)
    throw_error<InvalidArgument>(
        w, ".adaptive_max must be in [1, 64] (extra samples of one pixel), got ", adaptive_max);
}

void FilmOptions::validate() const {
  const char* w = "FilmOptions";
  if (!std::isfinite(exposure))
    throw_error<InvalidArgument>(w, ".exposure must be finite (EV), got ", exposure);
  if (!(shot_noise >= 0.0) || !std::isfinite(shot_noise))
    throw_error<InvalidArgument>(w, ".shot_noise must be finite and >= 0, got ", shot_noise);
  if (!(read_noise >= 0.0) || !std::isfinite(read_noise))
    throw_error<InvalidArgument>(w, ".read_noise must be finite and >= 0, got ", read_noise);
  if (num_threads < 0)
    throw_error<InvalidArgument>(w, ".num_threads must be >= 0 (0 = all), got ", num_threads);
}

// ---------------------------------------------------------------------------------------------
// Scene data.

namespace {

/// A material prepared for shading.
struct MaterialData {
  F3 base;
  float metallic, alpha, ior, transmission;
  F3 emission;
  bool emissive;
  const std::uint8_t* tex = nullptr;  // points into `texture` of the owning PbrMaterial copy
  int tw = 0, th = 0;
  const pt::MsTables* ms = nullptr;  // multiple-scattering compensation; owned by Geometry
};

/// What shading needs of one triangle, in one record (one or two cache lines instead of one per
/// array: vertices, faces, normals, materials).
struct TriShade {
  F3 p[3];                // vertices, world
  F3 ng;                  // unit geometric normal (front side), world
  F3 cn[3];               // unit shading normals of the corners, world
  std::int32_t material;  // global material index
};

struct GeometryData {
  Points3f vertices;                        // world (while building; then in `tri`)
  Faces faces;                              // (F,3) vertex indices of the faces, for the uvs
  std::vector<F3> corner_normals;           // (F*3) shading normals per corner (while building)
  std::vector<TriShade> tri;                // (F) the per-face shading records
  Points2f uvs;                             // (V,2) or empty
  std::vector<std::int32_t> face_material;  // (F) global material index (while building)
  std::vector<std::int32_t> face_emitter;   // (F) index into Geometry::emitters or -1; or empty
  std::int32_t instance_id = 0;
};

/// One emissive triangle (a face whose material has emission > 0), sampled by next-event
/// estimation like an area light. It emits from its front (CCW) side.
struct TriEmitter {
  F3 p0, e1, e2;  // vertex 0 and the edges to vertices 1 and 2, world
  F3 n;           // unit geometric normal (front side)
  float area;
  F3 radiance;
};

/// Per-corner shading normals: at each corner, the angle-weighted mean of the normals of the
/// faces around the (position-welded) vertex that are within the crease angle of this face.
std::vector<F3> corner_normals(const Mesh& world) {
  const auto nf = world.num_faces();
  const auto nv = world.num_vertices();
  const Points3f fn = world.face_normals();
  const auto& V = world.vertices();
  const auto& F = world.faces();
  const std::vector<std::int32_t> weld = world.weld_map();
  std::vector<float> angle(static_cast<std::size_t>(3 * nf));
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3f p = V.row(F(f, k)).transpose();
      const Eigen::Vector3f a = V.row(F(f, (k + 1) % 3)).transpose() - p;
      const Eigen::Vector3f b = V.row(F(f, (k + 2) % 3)).transpose() - p;
      const float c = a.normalized().dot(b.normalized());
      angle[3 * f + k] = std::acos(std::min(1.0f, std::max(-1.0f, c)));
    }
  }
  // CSR of (face) per welded vertex.
  std::vector<std::int64_t> start(static_cast<std::size_t>(nv) + 1, 0);
  for (Eigen::Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) ++start[weld[F(f, k)] + 1];
  for (Eigen::Index i = 0; i < nv; ++i) start[i + 1] += start[i];
  std::vector<std::int64_t> fill(start.begin(), start.end() - 1);
  std::vector<std::int64_t> corners(static_cast<std::size_t>(3 * nf));
  for (Eigen::Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) corners[fill[weld[F(f, k)]]++] = 3 * f + k;
  std::vector<F3> out(static_cast<std::size_t>(3 * nf));
  for (Eigen::Index f = 0; f < nf; ++f) {
    const F3 nf3(fn(f, 0), fn(f, 1), fn(f, 2));
    for (int k = 0; k < 3; ++k) {
      const std::int32_t w = weld[F(f, k)];
      F3 sum(0.0f);
      for (std::int64_t j = start[w]; j < start[w + 1]; ++j) {
        const std::int64_t c = corners[j];
        const std::int64_t g = c / 3;
        const F3 ng(fn(g, 0), fn(g, 1), fn(g, 2));
        if (dot(ng, nf3) >= kCreaseCos) sum += ng * angle[c];
      }
      const float l = length(sum);
      out[3 * f + k] = l > 0.0f ? sum / l : nf3;
    }
  }
  return out;
}

}  // namespace

struct PathScene::Geometry {
  std::unique_ptr<RayScene> rays;  // robust BVH: camera rays (labels, first hits)
  detail::OwnedScene bounce;       // non-robust BVH of the same geometry: bounce and shadow rays
  std::vector<GeometryData> geoms;
  std::vector<PbrMaterial> materials;  // owns the textures
  std::vector<MaterialData> mats;
  std::deque<pt::MsTables> ms_tables;  // shared by the materials of equal (alpha, ior, lobes)
  std::vector<TriEmitter> emitters;    // the emissive triangles, for next-event estimation
  std::int64_t triangles = 0;
  Eigen::Matrix<double, 2, 3, Eigen::RowMajor> bounds;
};

namespace {

struct LightData {
  F3 centre, ex, ey, n;  // unit axes, normal = +z_L
  float hx, hy;          // rect half sizes; disc: radius in hx
  bool disc;
  float area;
  F3 radiance;
};

}  // namespace

struct PathScene::Lighting {
  std::vector<AreaLight> lights;
  Environment environment;
  std::vector<LightData> light_data;
  std::vector<TriEmitter> tris;  // the scene's emissive triangles (copied from the geometry)
  // Light selection: one "local" emitter per shading point, chosen by power among the area
  // lights (entries 0 .. lights-1) and the emissive triangles (entries lights .. n_local-1)
  // (cdf, pmf); then entry n_local for the environment (pmf 1 when it is on: sampled at every
  // shading point).
  std::size_t n_local = 0;
  std::vector<float> cdf;
  std::vector<float> pmf;
  bool env_on = false;
  bool area_on = false;
  // Environment.
  int kind = 0;  // 0 uniform, 1 gradient, 2 sky
  F3 color, zenith, horizon, ground;
  F3 sun_dir;
  float sun_cos = 1.0f;
  F3 sun_radiance;
  float p_sun = 0.0f;  // probability of sampling the sun cone in environment sampling

  F3 env(F3 d) const {
    if (kind == 0) return color;
    F3 c = d.z >= 0.0f ? pt::lerp(horizon, zenith, std::sqrt(d.z)) : ground;
    if (kind == 2 && dot(d, sun_dir) >= sun_cos) c += sun_radiance;
    return c;
  }
};

namespace {

std::shared_ptr<PathScene::Lighting> make_lighting(const std::vector<AreaLight>& lights,
                                                   const Environment& environment,
                                                   const std::vector<TriEmitter>& tris) {
  for (std::size_t i = 0; i < lights.size(); ++i)
    lights[i].validate("PathScene: light " + std::to_string(i));
  environment.validate("PathScene: environment");
  auto L = std::make_shared<PathScene::Lighting>();
  L->lights = lights;
  L->environment = environment;
  std::vector<float> w;
  for (const AreaLight& a : lights) {
    LightData d;
    const Mat3d R = a.X_WL.linear();
    d.centre = f3(Vec3d(a.X_WL.translation()));
    d.ex = f3(Vec3d(R.col(0)));
    d.ey = f3(Vec3d(R.col(1)));
    d.n = f3(Vec3d(R.col(2)));
    d.disc = a.shape == AreaLight::Shape::Disc;
    d.hx = static_cast<float>(d.disc ? a.size.x() : 0.5 * a.size.x());
    d.hy = static_cast<float>(d.disc ? a.size.x() : 0.5 * a.size.y());
    d.area = d.disc ? pt::kPi * d.hx * d.hx : 4.0f * d.hx * d.hy;
    d.radiance = f3(a.color) * a.intensity;
    L->light_data.push_back(d);
    w.push_back(pt::kPi * d.area * luminance(d.radiance));
  }
  L->tris = tris;
  for (const TriEmitter& t : tris) w.push_back(pt::kPi * t.area * luminance(t.radiance));
  const float I = environment.intensity;
  L->kind = static_cast<int>(environment.kind);
  L->color = f3(environment.color) * I;
  L->zenith = f3(environment.zenith) * I;
  L->horizon = f3(environment.horizon) * I;
  L->ground = f3(environment.ground) * I;
  float sky_lum = 0.0f;  // rough mean luminance of the dome (without the sun)
  if (environment.kind == Environment::Kind::Uniform) {
    sky_lum = luminance(L->color);
  } else {
    sky_lum = 0.5f * luminance((L->zenith + L->horizon * 2.0f) * (1.0f / 3.0f)) +
              0.5f * luminance(L->ground);
  }
  float e_sun = 0.0f;
  if (environment.kind == Environment::Kind::Sky) {
    L->sun_dir = normalize(f3(environment.sun_direction));
    const float r = environment.sun_angular_radius;
    L->sun_cos = std::cos(r);
    const float s = std::sin(r);
    L->sun_radiance = F3(environment.sun_strength * luminance(L->zenith) / (s * s));
    e_sun = environment.sun_strength * pt::kPi * luminance(L->zenith);
    // Share of environment samples aimed at the sun: its share of the irradiance, in [0.2, 0.9].
    if (e_sun > 0.0f)
      L->p_sun = std::min(0.9f, std::max(0.2f, e_sun / (e_sun + pt::kPi * sky_lum)));
  }
  L->env_on = sky_lum > 0.0f || e_sun > 0.0f;
  // Area lights and emissive triangles: one is chosen per shading point with probability
  // proportional to its power;
  // the environment is sampled at every shading point as well (its own shadow ray).
  float total = 0.0f;
  for (float x : w) total += x;
  const std::size_t n = w.size();
  L->n_local = n;
  L->pmf.assign(n + 1, 0.0f);
  L->cdf.assign(n + 1, 0.0f);
  float acc = 0.0f;
  for (std::size_t i = 0; i < n; ++i) {
    L->pmf[i] = total > 0.0f ? w[i] / total : 0.0f;
    acc += L->pmf[i];
    L->cdf[i] = acc;
  }
  if (n > 0 && total > 0.0f) L->cdf[n - 1] = 1.0f;
  L->area_on = n > 0 && total > 0.0f;
  L->pmf[n] = L->env_on ? 1.0f : 0.0f;  // the environment's "selection" probability
  L->cdf[n] = 1.0f;
  return L;
}

using MsKey = std::tuple<float, float, bool, bool, bool>;

/// The multiple-scattering compensation tables of a material (pt::MsTables), built once per
/// distinct (alpha, ior, lobes) of the scene: none for a nearly smooth material (alpha at most
/// ShadingMaterial::kRoughAlpha), whose single scattering keeps (all but ~1e-4 of) the energy.
const pt::MsTables* ms_tables_for(PathScene::Geometry& G,
                                  std::map<MsKey, const pt::MsTables*>& cache,
                                  const MaterialData& d) {
  if (!(d.alpha > pt::ShadingMaterial::kRoughAlpha)) return nullptr;
  const bool conductor = d.metallic > 0.0f;
  const bool coat = (1.0f - d.metallic) * (1.0f - d.transmission) > 0.0f && d.ior > 1.0f;
  const bool dielectric = (1.0f - d.metallic) * d.transmission > 0.0f && d.ior > 1.0f;
  if (!conductor && !coat && !dielectric) return nullptr;
  const MsKey key{d.alpha, d.ior, conductor, coat, dielectric};
  const auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  G.ms_tables.push_back(pt::make_ms_tables(d.alpha, d.ior, conductor, coat, dielectric));
  return cache[key] = &G.ms_tables.back();
}

}  // namespace

PathScene::PathScene(const std::vector<PathGeometry>& geometries,
                     const std::vector<AreaLight>& lights, const Environment& environment) {
  const char* fn = "PathScene";
  if (geometries.empty())
    throw_error<InvalidArgument>(fn, ": no geometry given; expected at least one mesh");
  auto G = std::make_shared<Geometry>();
  std::vector<RayGeometry> rg;
  std::size_t n_mats = 0;
  for (std::size_t g = 0; g < geometries.size(); ++g) {
    const PathGeometry& item = geometries[g];
    if (item.mesh == nullptr) throw_error<InvalidArgument>(fn, ": geometry ", g, " has no mesh");
    const std::size_t want = std::max<std::size_t>(1, item.mesh->materials().size());
    if (item.materials.size() != want) {
      throw_error<InvalidArgument>(fn, ": geometry ", g, " (mesh '", item.mesh->name(), "') has ",
                                   item.materials.size(),
                                   " materials; expected one per mesh material slot: ", want);
    }
    for (std::size_t k = 0; k < item.materials.size(); ++k)
      item.materials[k].validate(std::string(fn) + ": geometry " + std::to_string(g) +
                                 " material " + std::to_string(k));
    rg.push_back({item.mesh, item.X_WO, item.instance_id});
    n_mats += want;
  }
  // Validates meshes, poses and ids; builds the BVH (first hits and occlusion only: without
  // the all-hits filter support Embree's queries are a few percent faster, same results).
  G->rays = std::make_unique<RayScene>(rg, /*all_hits=*/false);
  // A second BVH over the same Embree geometries (shared buffers; +~75 bytes per triangle)
  // without Embree's robust flag, for the bounce and shadow rays: ~10 % less CPU per sample.
  // The camera rays (depth, ids and first hits) keep the robust one, so the labels stay
  // aligned with the raster engine's. The non-robust test is not watertight for rays aimed
  // exactly at edges and vertices; for the random directions of bounces and shadow rays its
  // slits have (nearly) zero measure (tests: NonRobustScene.*, test_path_tracer.py's sealed box).
  G->bounce = detail::non_robust_scene(*G->rays);
  G->materials.reserve(n_mats);
  for (std::size_t g = 0; g < geometries.size(); ++g) {
    const PathGeometry& item = geometries[g];
    const std::int32_t base = static_cast<std::int32_t>(G->materials.size());
    for (const PbrMaterial& m : item.materials) G->materials.push_back(m);
    const Mesh world = item.mesh->transformed(item.X_WO);
    GeometryData d;
    d.vertices = world.vertices();
    d.faces = world.faces();
    d.corner_normals = corner_normals(world);
    if (world.uvs().rows() == world.num_vertices()) d.uvs = world.uvs();
    d.face_material.assign(static_cast<std::size_t>(world.num_faces()), base);
    const auto& fm = world.face_materials();
    if (!fm.empty()) {
      for (std::size_t f = 0; f < fm.size(); ++f)
        d.face_material[f] = base + std::max<std::int32_t>(0, fm[f]);
    }
    d.instance_id = item.instance_id;
    G->geoms.push_back(std::move(d));
  }
  std::map<MsKey, const pt::MsTables*> ms_cache;
  for (const PbrMaterial& m : G->materials) {
    MaterialData d;
    d.base = f3(m.base_color);
    d.metallic = m.metallic;
    d.alpha = std::max(kMinAlpha, m.roughness * m.roughness);
    d.ior = m.ior;
    d.transmission = m.transmission;
    d.emission = f3(m.emission);
    d.emissive = m.emission.maxCoeff() > 0.0f;
    if (!m.texture.empty()) {
      d.tex = m.texture.data();
      d.tw = m.texture_width;
      d.th = m.texture_height;
    }
    d.ms = ms_tables_for(*G, ms_cache, d);
    G->mats.push_back(d);
  }
  for (GeometryData& d : G->geoms) {
    for (Eigen::Index f = 0; f < d.faces.rows(); ++f) {
      const MaterialData& m = G->mats[d.face_material[f]];
      if (!m.emissive) continue;
      auto vert = [&](int k) {
        const auto i = d.faces(f, k);
        return F3(d.vertices(i, 0), d.vertices(i, 1), d.vertices(i, 2));
      };
      TriEmitter t;
      t.p0 = vert(0);
      t.e1 = vert(1) - t.p0;
      t.e2 = vert(2) - t.p0;
      const F3 c = pt::cross(t.e1, t.e2);
      t.area = 0.5f * length(c);
      if (!(t.area > 0.0f)) continue;  // degenerate: never hit, never sampled
      t.n = c / (2.0f * t.area);
      t.radiance = m.emission;
      if (d.face_emitter.empty())
        d.face_emitter.assign(static_cast<std::size_t>(d.faces.rows()), -1);
      d.face_emitter[f] = static_cast<std::int32_t>(G->emitters.size());
      G->emitters.push_back(t);
    }
  }
  for (std::size_t g = 0; g < G->geoms.size(); ++g) {
    GeometryData& d = G->geoms[g];
    const Points3f& fnr = G->rays->impl().world_normals[g];
    d.tri.resize(static_cast<std::size_t>(d.faces.rows()));
    for (Eigen::Index f = 0; f < d.faces.rows(); ++f) {
      TriShade& t = d.tri[f];
      for (int k = 0; k < 3; ++k) {
        const auto i = d.faces(f, k);
        t.p[k] = F3(d.vertices(i, 0), d.vertices(i, 1), d.vertices(i, 2));
        t.cn[k] = d.corner_normals[3 * static_cast<std::size_t>(f) + k];
      }
      t.ng = F3(fnr(f, 0), fnr(f, 1), fnr(f, 2));
      t.material = d.face_material[f];
    }
    // Now in `tri`: nothing reads them after this.
    std::vector<F3>().swap(d.corner_normals);
    std::vector<std::int32_t>().swap(d.face_material);
    d.vertices = Points3f();
  }
  G->triangles = G->rays->num_triangles();
  G->bounds = G->rays->bounds();
  lighting_ = make_lighting(lights, environment, G->emitters);
  geometry_ = std::move(G);
}

PathScene::~PathScene() = default;
PathScene::PathScene(const PathScene&) = default;
PathScene& PathScene::operator=(const PathScene&) = default;
PathScene::PathScene(PathScene&&) noexcept = default;
PathScene& PathScene::operator=(PathScene&&) noexcept = default;

PathScene PathScene::with_lighting(const std::vector<AreaLight>& lights,
                                   const Environment& environment) const {
  PathScene s(*this);
  s.lighting_ = make_lighting(lights, environment, geometry_->emitters);
  return s;
}

std::int64_t PathScene::num_triangles() const { return geometry_->triangles; }
const std::vector<AreaLight>& PathScene::lights() const { return lighting_->lights; }
const Environment& PathScene::environment() const { return lighting_->environment; }

// ---------------------------------------------------------------------------------------------
// The integrator.

namespace {

using Geometry = PathScene::Geometry;
using Lighting = PathScene::Lighting;

/// Surface interaction at a ray hit.
struct Hit {
  F3 p;        // world position
  F3 ng;       // geometric normal, towards the side the ray came from
  F3 ns;       // shading normal, same side as ng and facing wo
  bool front;  // the ray hit the outward (CCW) side
  const MaterialData* mat;
  F3 base;  // textured base colour
  std::int32_t instance_id;
};

F3 texture_lookup(const MaterialData& m, float u, float v) {
  const float x = u * static_cast<float>(m.tw) - 0.5f;
  const float y = (1.0f - v) * static_cast<float>(m.th) - 0.5f;
  const float fx = std::floor(x), fy = std::floor(y);
  const float ax = x - fx, ay = y - fy;
  auto wrap = [](long i, int n) {
    if (i >= 0 && i < n) return static_cast<int>(i);  // the usual case: no division
    long r = i % n;
    return static_cast<int>(r < 0 ? r + n : r);
  };
  const long ix = static_cast<long>(fx), iy = static_cast<long>(fy);
  const int x0 = wrap(ix, m.tw), x1 = wrap(ix + 1, m.tw);
  const int y0 = wrap(iy, m.th), y1 = wrap(iy + 1, m.th);
  const float* lut = srgb_lut().v;
  auto texel = [&](int xx, int yy) {
    const std::uint8_t* t = m.tex + 3 * (static_cast<std::size_t>(yy) * m.tw + xx);
    return F3(lut[t[0]], lut[t[1]], lut[t[2]]);
  };
  return pt::lerp(pt::lerp(texel(x0, y0), texel(x1, y0), ax),
                  pt::lerp(texel(x0, y1), texel(x1, y1), ax), ay);
}

/// The denoiser's albedo guide where a path sees an emitter: its radiance clamped to [0, 1]
/// (per channel for the environment, grey for a lamp).
F3 emitter_guide(F3 Le) {
  return F3(std::min(1.0f, Le.x), std::min(1.0f, Le.y), std::min(1.0f, Le.z));
}
F3 lamp_guide(F3 Le) { return F3(std::min(1.0f, max_comp(Le))); }

/// Smooth, mostly transmissive glass: the denoiser's guides are taken behind it (trace()).
bool see_through(const MaterialData& m) {
  return m.transmission * (1.0f - m.metallic) >= 0.5f &&
         m.alpha <= pt::ShadingMaterial::kRoughAlpha;
}

void make_hit(const Geometry& G, const RTCRayHit& rh, F3 dir, Hit& h) {
  const GeometryData& g = G.geoms[rh.hit.geomID];
  const unsigned f = rh.hit.primID;
  const float b1 = rh.hit.u, b2 = rh.hit.v, b0 = 1.0f - b1 - b2;
  const TriShade& t = g.tri[f];
  h.p = t.p[0] * b0 + t.p[1] * b1 + t.p[2] * b2;
  F3 ng = t.ng;
  F3 ns = normalize(t.cn[0] * b0 + t.cn[1] * b1 + t.cn[2] * b2);
  h.front = dot(dir, ng) < 0.0f;
  if (!h.front) {
    ng = -ng;
    ns = -ns;
  }
  if (dot(ns, ng) <= 0.0f || dot(ns, -dir) <= 1e-4f) ns = ng;  // fall back at flips
  h.ng = ng;
  h.ns = ns;
  h.mat = &G.mats[t.material];
  h.base = h.mat->base;
  if (h.mat->tex != nullptr && g.uvs.rows() > 0) {
    const std::int32_t i0 = g.faces(f, 0), i1 = g.faces(f, 1), i2 = g.faces(f, 2);
    const float u = g.uvs(i0, 0) * b0 + g.uvs(i1, 0) * b1 + g.uvs(i2, 0) * b2;
    const float v = g.uvs(i0, 1) * b0 + g.uvs(i1, 1) * b1 + g.uvs(i2, 1) * b2;
    h.base = h.base * texture_lookup(*h.mat, u, v);
  }
  h.instance_id = g.instance_id;
}

void set_ray(RTCRay& r, F3 o, F3 d, float tfar) {
  r.org_x = o.x;
  r.org_y = o.y;
  r.org_z = o.z;
  r.dir_x = d.x;
  r.dir_y = d.y;
  r.dir_z = d.z;
  r.tnear = 0.0f;
  r.tfar = tfar;
  r.time = 0.0f;
  r.mask = 0xFFFFFFFFu;
  r.id = 0;
  r.flags = 0;
}

/// Ray origin moved off the surface to the side of direction d.
F3 offset_origin(const Hit& h, F3 d) {
  const float scale =
      2e-5f * (1.0f + std::max(std::abs(h.p.x), std::max(std::abs(h.p.y), std::abs(h.p.z))));
  return h.p + h.ng * (dot(d, h.ng) >= 0.0f ? scale : -scale);
}

/// Nearest front-facing area light along the ray within (0, tmax). Returns its index or -1.
int hit_light(const Lighting& L, F3 o, F3 d, float tmax, float& t_out) {
  int best = -1;
  for (std::size_t i = 0; i < L.light_data.size(); ++i) {
    const LightData& l = L.light_data[i];
    const float dn = dot(d, l.n);
    if (dn >= 0.0f) continue;  // back side or parallel: one-sided emitter
    const float t = dot(l.centre - o, l.n) / dn;
    if (!(t > 0.0f && t < tmax)) continue;
    const F3 q = o + d * t - l.centre;
    const float x = dot(q, l.ex), y = dot(q, l.ey);
    const bool inside =
        l.disc ? (x * x + y * y <= l.hx * l.hx) : (std::abs(x) <= l.hx && std::abs(y) <= l.hy);
    if (!inside) continue;
    tmax = t;
    best = static_cast<int>(i);
  }
  t_out = tmax;
  return best;
}

/// Pdf (solid angle, at the shading point with normal n) of environment sampling.
float env_pdf(const Lighting& L, F3 n, F3 w) {
  float p = (1.0f - L.p_sun) * std::max(0.0f, dot(n, w)) * pt::kInvPi;
  if (L.p_sun > 0.0f && dot(w, L.sun_dir) >= L.sun_cos)
    p += L.p_sun / (2.0f * pt::kPi * (1.0f - L.sun_cos));
  return p;
}

/// Lane `l` of a 16-ray packet: the ray o + t d for t in [0, inf), no hit yet; `on` false
/// leaves the lane inactive (valid[l] = 0) for a tile narrower than the packet.
inline void set_packet_lane(RTCRayHit16& rh, int* valid, int l, bool on, const F3& o, const F3& d) {
  valid[l] = on ? -1 : 0;
  rh.ray.org_x[l] = o.x;
  rh.ray.org_y[l] = o.y;
  rh.ray.org_z[l] = o.z;
  rh.ray.dir_x[l] = d.x;
  rh.ray.dir_y[l] = d.y;
  rh.ray.dir_z[l] = d.z;
  rh.ray.tnear[l] = 0.0f;
  rh.ray.tfar[l] = std::numeric_limits<float>::infinity();
  rh.ray.time[l] = 0.0f;
  rh.ray.mask[l] = 0xFFFFFFFFu;
  rh.ray.id[l] = static_cast<unsigned>(l);
  rh.ray.flags[l] = 0;
  rh.hit.geomID[l] = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0][l] = RTC_INVALID_GEOMETRY_ID;
}

inline float power_heuristic(float a, float b) {
  const float a2 = a * a, b2 = b * b;
  return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

struct Camera {
  float fx, fy, cx, cy;
  F3 o;
  F3 r0, r1, r2;  // columns of R_WC
  F3 to_world(F3 v) const { return r0 * v.x + r1 * v.y + r2 * v.z; }
};

struct Counters {
  std::int64_t rays = 0;
};

class Integrator {
 public:
  Integrator(const Geometry& G, const Lighting& L, const PathTraceOptions& o)
      : G_(G),
        L_(L),
        opt_(o),
        primary_(G.rays->impl().scene),
        scene_(G.bounce.get()),
        clamp_indirect_(static_cast<float>(o.clamp_indirect)),
        split_min_(static_cast<float>(o.fresnel_split_min)),
        guide_split_min_(static_cast<float>(o.guide_split_min)) {
    rtcInitIntersectContext(&ctx_);
  }

  /// First hit of a bounce ray (the non-robust BVH).
  bool intersect(F3 o, F3 d, float tfar, RTCRayHit& rh) {
    return intersect(scene_, o, d, tfar, rh);
  }
  /// First hit of a camera ray (the robust BVH, as the labels).
  bool intersect_primary(F3 o, F3 d, float tfar, RTCRayHit& rh) {
    return intersect(primary_, o, d, tfar, rh);
  }
  bool intersect(RTCScene scene, F3 o, F3 d, float tfar, RTCRayHit& rh) {
    set_ray(rh.ray, o, d, tfar);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene, &ctx_, &rh);
    ++counters.rays;
    return rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
  }

  bool occluded(F3 o, F3 d, float tfar) {
    RTCRay r;
    set_ray(r, o, d, tfar);
    rtcOccluded1(scene_, &ctx_, &r);
    ++counters.rays;
    return r.tfar == -std::numeric_limits<float>::infinity();
  }

  /// Radiance along a camera ray; first-hit albedo and normal are written to aov_*. `first`,
  /// when given, is the camera ray's hit already found (a packet of camera rays): its tfar,
  /// geomID, primID, u and v are used instead of tracing the ray again.
  F3 trace(F3 o, F3 d, const pt::PixelSampler& s, F3& aov_albedo, F3& aov_normal,
           const RTCRayHit* first = nullptr) {
    F3 L(0.0f), beta(1.0f);
    // Throughput for the light (area light, emissive triangle, environment) found at the next
    // vertex: beta, except after a smooth dielectric, where both the reflected and the refracted
    // ray are traced to the light they meet first (Fresnel splitting: each weighted by its
    // expected share F or 1 - F instead of the random choice of one; the lamps and the sky seen
    // in and through glass are the noisiest part of a glass object otherwise) and only the
    // chosen ray continues the path (it carries the indirect light of both, unbiased).
    F3 beta_e(1.0f);
    bool prev_delta = true;
    float prev_pdf = 0.0f;   // solid-angle pdf of the BSDF sample that made the current ray
    F3 prev_n(0.0f);         // shading normal at the previous vertex (for the environment pdf)
    float eta_scale = 1.0f;  // product of eta^2 over the refractions so far
    // The albedo and normal for the denoiser are those of the first surface that is not smooth
    // glass: through (or in) a smooth dielectric they are taken at the next hit, so that the
    // denoiser keeps what is seen through glass instead of smoothing it into a flat surface.
    // At a split smooth dielectric both branches contribute, weighted by their Fresnel shares:
    // the other branch's first hit goes into aov_acc_* now, the continuing one's guide (aov_a,
    // aov_n, what it shows so far) is weighted aov_w at the end. About the expectation of
    // following the randomly chosen branch only (the other branch is followed through further
    // glass by refraction alone), without its noise: a pixel no longer shows the reflection's
    // guide or the transmission's at random.
    bool aov_open = true;
    F3 aov_a(0.0f), aov_n(0.0f), aov_acc_a(0.0f), aov_acc_n(0.0f);
    float aov_w = 1.0f;
    int rr_vertices = 0;  // vertices so far that count for roulette (see below)
    RTCRayHit rh;
    Hit h;
    // Branches of smooth dielectrics traced in full (see the split below), waiting their turn.
    struct Branch {
      F3 o, d, beta, prev_n, aov_a, aov_n;
      float prev_pdf, eta_scale, aov_w;
      int depth, rr_vertices;
      bool aov_open;
    };
    Branch pending[kMaxBranches];
    int n_pending = 0, branches_left = kMaxBranches;
    int depth = 0;
    for (;;) {
      for (;; ++depth) {
        bool hit;
        if (depth == 0 && first != nullptr) {
          rh = *first;
          hit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
        } else if (depth == 0) {
          hit = intersect_primary(o, d, std::numeric_limits<float>::infinity(), rh);
        } else {
          hit = intersect(o, d, std::numeric_limits<float>::infinity(), rh);
        }
        const float t_geom = hit ? rh.ray.tfar : std::numeric_limits<float>::infinity();
        float t_light;
        const int li = L_.light_data.empty() ? -1 : hit_light(L_, o, d, t_geom, t_light);
        if (li >= 0) {
          const LightData& l = L_.light_data[li];
          float w = 1.0f;
          if (!prev_delta) {
            const float cos_l = -dot(d, l.n);
            const float pl = L_.pmf[li] * t_light * t_light / (l.area * cos_l);
            w = power_heuristic(prev_pdf, pl);
          }
          add(L, beta_e * l.radiance * w, depth >= 2);
          if (aov_open) aov_a = lamp_guide(l.radiance);
          break;
        }
        if (!hit) {
          if (L_.env_on || aov_open) {
            const F3 Le = L_.env(d);
            float w = 1.0f;
            if (!prev_delta && L_.env_on)
              w = power_heuristic(prev_pdf, L_.pmf.back() * env_pdf(L_, prev_n, d));
            add(L, beta_e * Le * w, depth >= 2);
            if (aov_open) aov_a = emitter_guide(Le);
          }
          break;
        }
        make_hit(G_, rh, d, h);
        const MaterialData& m = *h.mat;
        const F3 wo_w = -d;
        if (m.emissive && h.front) {
          // An emissive triangle found by BSDF sampling: MIS against its next-event estimation.
          float w = 1.0f;
          if (!prev_delta) {
            const auto& fe = G_.geoms[rh.hit.geomID].face_emitter;
            const std::int32_t e = fe.empty() ? -1 : fe[rh.hit.primID];
            if (e >= 0) {
              const float cos_l = std::abs(dot(d, h.ng));
              const float t = rh.ray.tfar;
              const float pl = L_.pmf[L_.light_data.size() + e] * t * t /
                               (L_.tris[e].area * std::max(cos_l, 1e-7f));
              w = power_heuristic(prev_pdf, pl);
            }
          }
          add(L, beta_e * m.emission * w, depth >= 2);
        }
        if (aov_open) {
          aov_a = h.base;
          aov_n = h.ns;
          aov_open = see_through(m);
        }
        if (depth >= opt_.max_bounces) break;

        const pt::Frame frame(h.ns);
        const F3 wo = frame.to_local(wo_w);
        pt::ShadingMaterial sm{h.base, m.metallic, m.alpha, m.ior, m.transmission, m.ms};
        sm.prepare(wo.z, h.front);
        const std::uint32_t base_pair = 2 + 5 * static_cast<std::uint32_t>(depth);
        // Dimension pairs of this vertex: light point, BSDF direction, (light choice, lobe),
        // (roulette, Fresnel choice), environment direction.
        const pt::Sample2 u_bsdf = s.get(base_pair + 1);
        const pt::Sample2 u_sel = s.get(base_pair + 2);
        const pt::Sample2 u_rr = s.get(base_pair + 3);

        // Next-event estimation.
        if (sm.has_nondelta) {
          if (L_.area_on) {
            const std::size_t n = L_.n_local;
            const auto k = static_cast<std::size_t>(
                std::upper_bound(L_.cdf.begin(), L_.cdf.begin() + (n - 1), u_sel.x) -
                L_.cdf.begin());
            add(L, beta * direct(h, frame, wo, sm, k, s.get(base_pair)), depth >= 1);
          }
          if (L_.env_on)
            add(L, beta * direct(h, frame, wo, sm, L_.n_local, s.get(base_pair + 4)), depth >= 1);
        }

        // BSDF sampling.
        F3 wi_w;
        F3 weight;
        bool delta;
        float pdf;
        float eta2;
        Split split;
        // Fresnel splitting (and the branches) only while the throughput is worth the other
        // direction's ray: deeper, dim paths take the random direction alone (unbiased; the
        // choice does not depend on the Fresnel draw).
        const bool may_split = branches_left > 0 || max_comp(beta) >= split_min_;
        if (!sample_bsdf(h, frame, wo, sm, u_sel.y, u_rr.y, u_bsdf, wi_w, weight, pdf, delta, eta2,
                         may_split ? &split : nullptr))
          break;
        bool branched = false;
        if (split.on && branches_left > 0) {
          branched = true;
          // Both branches traced in full (the first kMaxBranches smooth-dielectric vertices of a
          // camera sample): the other one waits in `pending`; each carries its expected weight
          // (F or 1 - F times its lobe weight) instead of the random choice's, so nothing seen in
          // or through the first walls of a glass object depends on the reflect/refract draw
          // (a lamp reflected by the far wall of a bottle and seen through the near one was found
          // by a path only with probability F: a bright speckle, now a clean highlight).
          --branches_left;
          const float eta_v = h.front ? sm.ior : 1.0f / sm.ior;
          Branch& b = pending[n_pending++];
          b.o = offset_origin(h, split.other_dir);
          b.d = split.other_dir;
          b.beta = beta * split.other_weight;
          b.prev_pdf = 0.0f;
          b.prev_n = h.ns;
          b.eta_scale = eta_scale * (eta2 == 1.0f ? eta_v * eta_v : 1.0f);
          b.aov_a = aov_a;
          b.aov_n = aov_n;
          b.aov_w = aov_w * split.other_share;
          b.aov_open = aov_open;
          b.depth = depth + 1;
          b.rr_vertices = rr_vertices;
          aov_w *= 1.0f - split.other_share;
          weight = split.weight;
          if (max_comp(b.beta) <= 0.0f || !all_finite(b.beta)) --n_pending;
        } else if (split.on) {
          if (aov_open && aov_w * split.other_share >= guide_split_min_) {
            // The other branch's guide (followed through further smooth glass by refraction),
            // weighted by its share; the continuing branch keeps the rest.
            F3 oa = aov_a, on = aov_n;
            const F3 Le = emitted(h, split.other_dir, &oa, &on);
            if (max_comp(split.other_weight) > 0.0f)
              add(L, beta * split.other_weight * Le, depth >= 1);
            aov_acc_a += oa * (aov_w * split.other_share);
            aov_acc_n += on * (aov_w * split.other_share);
            aov_w *= 1.0f - split.other_share;
          } else if (max_comp(split.other_weight) > 0.0f) {
            add(L, beta * split.other_weight * emitted(h, split.other_dir), depth >= 1);
          }
          beta_e = beta * split.weight;
        }
        beta *= weight;
        if (!split.on || branched) beta_e = beta;
        eta_scale *= eta2;
        if (!all_finite(beta) || max_comp(beta) <= 0.0f) break;
        // Roulette counts the vertices where the path did not pass a smooth dielectric: behind a
        // glass wall (two such vertices, each keeping nearly all the throughput) the first rough
        // surface is rouletted as if seen directly. Those paths (what is seen in and through
        // glass) carry most of a glass object's noise and few of them are long.
        if (!(delta && !sm.rough)) ++rr_vertices;
        if (rr_vertices >= opt_.rr_depth) {
          // Roulette on the throughput without the 1/eta^2 radiance scaling of refractions, so
          // that paths inside glass are not killed more often than outside.
          const float q = std::min(1.0f, max_comp(beta) * eta_scale);
          if (u_rr.x >= q) break;
          beta *= 1.0f / q;
          beta_e *= 1.0f / q;
        }
        prev_delta = delta;
        prev_pdf = pdf;
        prev_n = h.ns;
        o = offset_origin(h, wi_w);
        d = wi_w;
      }
      aov_acc_a += aov_a * aov_w;
      aov_acc_n += aov_n * aov_w;
      if (n_pending == 0) break;
      const Branch& b = pending[--n_pending];
      o = b.o;
      d = b.d;
      beta = beta_e = b.beta;
      prev_delta = true;
      prev_pdf = b.prev_pdf;
      prev_n = b.prev_n;
      eta_scale = b.eta_scale;
      aov_a = b.aov_a;
      aov_n = b.aov_n;
      aov_w = b.aov_w;
      aov_open = b.aov_open;
      depth = b.depth;
      rr_vertices = b.rr_vertices;
    }
    aov_albedo = aov_acc_a;
    aov_normal = aov_acc_n;
    return L;
  }

  Counters counters;

 private:
  /// Adds a contribution; indirect ones (light that has bounced at least twice: found at the
  /// second path vertex or later) are clamped to clamp_indirect in luminance.
  void add(F3& L, F3 c, bool indirect) const {
    if (indirect && clamp_indirect_ > 0.0f) {
      const float lum = luminance(c);
      if (lum > clamp_indirect_) c *= clamp_indirect_ / lum;
    }
    L += c;
  }

  /// One sample of light k (k = number of area lights: the environment) with MIS; returns the
  /// contribution (without beta).
  F3 direct(const Hit& h, const pt::Frame& frame, F3 wo, const pt::ShadingMaterial& sm,
            std::size_t k, pt::Sample2 u) {
    const std::size_t n = L_.pmf.size();
    const float p_sel = L_.pmf[k];
    if (p_sel <= 0.0f) return F3(0.0f);
    F3 wi_w, Le;
    float pdf_light, dist;
    if (k + 1 == n) {  // environment
      float pu = u.x;
      if (L_.p_sun > 0.0f && pu < L_.p_sun) {
        pu /= L_.p_sun;
        const pt::Frame sf(L_.sun_dir);
        wi_w = sf.to_world(pt::uniform_cone(pu, u.y, L_.sun_cos));
      } else {
        if (L_.p_sun > 0.0f) pu = (pu - L_.p_sun) / (1.0f - L_.p_sun);
        wi_w = frame.to_world(pt::cosine_hemisphere(std::min(pu, 0.99999994f), u.y));
      }
      pdf_light = env_pdf(L_, h.ns, wi_w);
      if (pdf_light <= 0.0f) return F3(0.0f);
      dist = std::numeric_limits<float>::infinity();
      Le = L_.env(wi_w);
    } else {
      // A point q on an emissive triangle or an area light (normal n, area), uniform in area.
      F3 q, n;
      float area;
      if (k >= L_.light_data.size()) {
        const TriEmitter& t = L_.tris[k - L_.light_data.size()];
        const float su = std::sqrt(u.x);
        q = t.p0 + t.e1 * (1.0f - su) + t.e2 * (u.y * su);
        n = t.n;
        area = t.area;
        Le = t.radiance;
      } else {
        const LightData& l = L_.light_data[k];
        if (l.disc) {
          const pt::Sample2 dd = pt::concentric_disc(u.x, u.y);
          q = l.centre + l.ex * (dd.x * l.hx) + l.ey * (dd.y * l.hx);
        } else {
          q = l.centre + l.ex * ((2.0f * u.x - 1.0f) * l.hx) + l.ey * ((2.0f * u.y - 1.0f) * l.hy);
        }
        n = l.n;
        area = l.area;
        Le = l.radiance;
      }
      const F3 v = q - h.p;
      const float d2 = dot(v, v);
      if (!(d2 > 0.0f)) return F3(0.0f);
      dist = std::sqrt(d2);
      wi_w = v / dist;
      const float cos_l = -dot(wi_w, n);
      if (cos_l <= 0.0f) return F3(0.0f);
      pdf_light = d2 / (area * cos_l);
    }
    if (dot(wi_w, h.ng) <= 0.0f) return F3(0.0f);
    const F3 wi = frame.to_local(wi_w);
    F3 f;
    float pdf_bsdf;
    sm.eval(wo, wi, f, pdf_bsdf);
    if (max_comp(f) <= 0.0f || max_comp(Le) <= 0.0f) return F3(0.0f);
    const F3 o = offset_origin(h, wi_w);
    const float tfar = std::isinf(dist) ? dist : dist * (1.0f - 1e-4f);
    if (occluded(o, wi_w, tfar)) return F3(0.0f);
    const float pl = p_sel * pdf_light;
    const float w = power_heuristic(pl, pdf_bsdf);
    return f * Le * (wi.z * w / pl);
  }

  /// Fresnel splitting at a smooth dielectric: the expected weight of the chosen direction (F
  /// or 1 - F times its lobe weight, instead of the weight of the random choice) and the other
  /// direction with its expected weight.
  struct Split {
    bool on = false;
    F3 weight;
    F3 other_dir;
    F3 other_weight;
    float other_share = 0.0f;  // the other direction's probability: F or 1 - F
  };

  /// Radiance arriving at h.p from direction d (world), emitted by the first thing the ray from
  /// h.p meets: an area light, an emissive triangle's front side or the environment (0 for
  /// anything else). Unweighted: it is the light seen through a delta lobe (no MIS). When given,
  /// aux_albedo / aux_normal receive the denoiser guides of what the ray meets, as trace() takes
  /// them (the normal is left as given for a light or the environment; see aux_behind_glass).
  F3 emitted(const Hit& h, F3 d, F3* aux_albedo = nullptr, F3* aux_normal = nullptr) {
    const F3 o = offset_origin(h, d);
    RTCRayHit rh;
    const bool hit = intersect(o, d, std::numeric_limits<float>::infinity(), rh);
    const float t_geom = hit ? rh.ray.tfar : std::numeric_limits<float>::infinity();
    float t_light;
    const int li = L_.light_data.empty() ? -1 : hit_light(L_, o, d, t_geom, t_light);
    if (li >= 0) {
      if (aux_albedo) *aux_albedo = lamp_guide(L_.light_data[li].radiance);
      return L_.light_data[li].radiance;
    }
    if (!hit) {
      const F3 Le = L_.env(d);
      if (aux_albedo) *aux_albedo = emitter_guide(Le);
      return L_.env_on ? Le : F3(0.0f);
    }
    if (aux_albedo) aux_behind_glass(rh, d, *aux_albedo, *aux_normal);
    const TriShade& t = G_.geoms[rh.hit.geomID].tri[rh.hit.primID];
    const MaterialData& m = G_.mats[t.material];
    if (!m.emissive) return F3(0.0f);
    return dot(d, t.ng) < 0.0f ? m.emission : F3(0.0f);
  }

  /// The denoiser guides along a ray whose first hit is `rh` (direction d): the first surface that
  /// is not see-through glass, followed through up to 8 smooth glass interfaces by refraction
  /// (total internal reflection: reflection), as the camera sees through a bottle's walls; a
  /// light or the environment gives its clamped radiance (normal unchanged).
  void aux_behind_glass(RTCRayHit rh, F3 d, F3& albedo, F3& normal) {
    Hit g;
    for (int k = 0;; ++k) {
      make_hit(G_, rh, d, g);
      if (!see_through(*g.mat) || k == 8) {
        albedo = g.base;
        normal = g.ns;
        return;
      }
      // ns faces the side d came from; eta = n_incident / n_transmitted.
      const float eta = g.front ? 1.0f / g.mat->ior : g.mat->ior;
      const float ci = std::min(1.0f, std::max(0.0f, -dot(d, g.ns)));
      const float sin2_t = eta * eta * (1.0f - ci * ci);
      d = sin2_t >= 1.0f ? normalize(d + g.ns * (2.0f * ci))
                         : normalize(d * eta + g.ns * (eta * ci - std::sqrt(1.0f - sin2_t)));
      const F3 o = offset_origin(g, d);
      const bool hit = intersect(o, d, std::numeric_limits<float>::infinity(), rh);
      float t_light;
      const float t_geom = hit ? rh.ray.tfar : std::numeric_limits<float>::infinity();
      const int li = L_.light_data.empty() ? -1 : hit_light(L_, o, d, t_geom, t_light);
      if (li >= 0 || !hit) {
        albedo = li >= 0 ? lamp_guide(L_.light_data[li].radiance) : emitter_guide(L_.env(d));
        return;
      }
    }
  }

  /// Samples the BSDF: direction, weight f*cos/pdf (including lobe choice), solid-angle pdf of
  /// the non-delta part (for MIS) and whether a delta lobe was chosen. At a smooth dielectric,
  /// `split` (when given) receives the Fresnel split (see Split).
  bool sample_bsdf(const Hit& h, const pt::Frame& frame, F3 wo, const pt::ShadingMaterial& sm,
                   float u_lobe, float u_fresnel, pt::Sample2 u, F3& wi_w, F3& weight, float& pdf,
                   bool& delta, float& eta2, Split* split = nullptr) {
    eta2 = 1.0f;
    if (split != nullptr) split->on = false;
    if (u_lobe < sm.p_delta && sm.rough) {
      // Rough dielectric: refraction (no light is sampled below the surface, so the light this
      // ray finds is weighted 1, as after a delta lobe) or reflection (weighed by the whole
      // non-delta BSDF and its pdf, as the other lobes' samples).
      F3 wi;
      if (sm.sample_rough(wo, u_fresnel, u.x, u.y, wi, weight)) {
        if (wi.z >= 0.0f) return false;
        wi_w = frame.to_world(wi);
        if (dot(wi_w, h.ng) >= 0.0f) return false;
        delta = true;
        pdf = 0.0f;
        eta2 = sm.eta * sm.eta;
        return true;
      }
      delta = false;
      if (wi.z <= 0.0f) return false;
      wi_w = frame.to_world(wi);
      if (dot(wi_w, h.ng) <= 0.0f) return false;
      F3 f;
      sm.eval(wo, wi, f, pdf);
      if (!(pdf > 0.0f)) return false;
      weight = f * (wi.z / pdf);
      return true;
    }
    if (u_lobe < sm.p_delta) {
      // Smooth dielectric: reflect with probability F, otherwise refract.
      delta = true;
      pdf = 0.0f;
      const float eta = h.front ? sm.ior : 1.0f / sm.ior;  // n_t / n_i
      // The interface normal is the shading normal (smooth curved glass); where it would send
      // the reflected or refracted ray to the wrong side of the surface, the geometric normal.
      const F3 wo_w = frame.to_world(wo);
      F3 n = h.ns;
      float ci = std::max(0.0f, dot(wo_w, n));
      const float F = pt::fresnel_dielectric(ci, eta);
      const float scale = sm.w_trans / sm.p_delta;
      auto refract = [&](F3 nn, float c) {
        const float sin2_t = (1.0f - c * c) / (eta * eta);
        const float ct = std::sqrt(std::max(0.0f, 1.0f - sin2_t));
        return normalize(-wo_w * (1.0f / eta) + nn * (c / eta - ct));
      };
      auto reflected = [&] {
        const F3 r = pt::reflect(wo_w, n);
        return dot(r, h.ng) <= 0.0f ? pt::reflect(wo_w, h.ng) : r;
      };
      auto refracted = [&] {
        const F3 t = refract(n, ci);
        return dot(t, h.ng) >= 0.0f ? refract(h.ng, std::max(0.0f, dot(wo_w, h.ng))) : t;
      };
      // Tint sqrt(base) at each interface: a pass through a closed wall (in and out) is
      // tinted by the base colour once, as in Blender's Principled BSDF. Radiance is scaled
      // by 1/eta^2 on refraction (the solid angle compresses); it cancels on a closed shell.
      const F3 w_refract = sm.sqrt_base() * (scale / (eta * eta));
      const bool split_on = split != nullptr && F > 0.0f && F < 1.0f;
      if (u_fresnel < F) {
        wi_w = reflected();
        weight = F3(scale);
        if (split_on) *split = {true, F3(F * scale), refracted(), w_refract * (1.0f - F), 1.0f - F};
      } else {
        wi_w = refracted();
        weight = w_refract;
        eta2 = eta * eta;
        if (split_on) *split = {true, w_refract * (1.0f - F), reflected(), F3(F * scale), F};
      }
      return true;
    }
    delta = false;
    if (!sm.has_other) return false;
    const float ul = (u_lobe - sm.p_delta) / (1.0f - sm.p_delta);
    F3 wi;
    if (ul < sm.p_spec) {
      const F3 m = pt::ggx_sample_vndf(wo, sm.alpha, u.x, u.y);
      wi = pt::reflect(wo, m);
    } else {
      wi = pt::cosine_hemisphere(u.x, u.y);
    }
    if (wi.z <= 0.0f) return false;
    wi_w = frame.to_world(wi);
    if (dot(wi_w, h.ng) <= 0.0f) return false;
    F3 f;
    sm.eval(wo, wi, f, pdf);
    if (!(pdf > 0.0f)) return false;
    weight = f * (wi.z / pdf);
    return true;
  }

  const Geometry& G_;
  const Lighting& L_;
  const PathTraceOptions& opt_;
  RTCScene primary_;  // robust: camera rays
  RTCScene scene_;    // bounce and shadow rays
  float clamp_indirect_;
  float split_min_;        // PathTraceOptions::fresnel_split_min
  float guide_split_min_;  // PathTraceOptions::guide_split_min
  /// Smooth-dielectric vertices per camera sample whose two branches are both traced in full
  /// (the first ones along the path, depth first); later ones are split as in `Split`.
  static constexpr int kMaxBranches = 3;
  RTCIntersectContext ctx_;
};

}  // namespace

PathTraceOutput PathScene::render(const CameraView& view, const PathTraceOptions& options) const {
  options.validate();
  view.validate("PathScene::render: view");
  const Geometry& G = *geometry_;
  const Lighting& L = *lighting_;
  const int W = view.K.width, H = view.K.height;
  PathTraceOutput out;
  out.width = W;
  out.height = H;
  const std::size_t np = static_cast<std::size_t>(W) * H;
  out.radiance.assign(3 * np, 0.0f);
  out.albedo.assign(3 * np, 0.0f);
  out.normal.assign(3 * np, 0.0f);
  out.depth.assign(np, 0.0f);
  out.instance_ids.assign(np, 0);

  Camera cam;
  cam.fx = static_cast<float>(view.K.fx);
  cam.fy = static_cast<float>(view.K.fy);
  cam.cx = static_cast<float>(view.K.cx);
  cam.cy = static_cast<float>(view.K.cy);
  const Mat3d R = view.X_WC.linear();
  cam.o = f3(Vec3d(view.X_WC.translation()));
  cam.r0 = f3(Vec3d(R.col(0)));
  cam.r1 = f3(Vec3d(R.col(1)));
  cam.r2 = f3(Vec3d(R.col(2)));

  float focus = static_cast<float>(options.focus_distance);
  const float aperture = static_cast<float>(options.aperture_radius);
  std::atomic<std::int64_t> total_rays{0};
  if (aperture > 0.0f && focus == 0.0f) {
    detail::FtzDazGuard guard;
    Integrator it(G, L, options);
    RTCRayHit rh;
    // Depth at the image centre through the principal point.
    const F3 dc = F3((0.5f * W - cam.cx) / cam.fx, (0.5f * H - cam.cy) / cam.fy, 1.0f);
    const float len = length(dc);
    focus = it.intersect_primary(cam.o, cam.to_world(dc / len),
                                 std::numeric_limits<float>::infinity(), rh)
                ? rh.ray.tfar / len
                : 1.0f;
    total_rays += it.counters.rays;
  }

  constexpr int kTile = 16;
  const int tiles_x = (W + kTile - 1) / kTile, tiles_y = (H + kTile - 1) / kTile;
  const std::size_t n_tiles = static_cast<std::size_t>(tiles_x) * tiles_y;
  const std::uint64_t stream =
      mix64(options.seed ^ mix64(options.view_index + 0x5851F42D4C957F2DULL));
  const float clamp = static_cast<float>(options.clamp);
  const float inv_spp = 1.0f / static_cast<float>(options.spp);
  const int spp_log2 = pt::ceil_log2(static_cast<std::uint32_t>(options.spp));

  // The camera ray of one sample of pixel (u, v): jittered in the pixel (sampler dimension 0)
  // and, with an aperture, leaving a point of the lens (dimension 1) towards the focus plane.
  auto camera_ray = [&](const pt::PixelSampler& s, int u, int v, F3& o, F3& d) {
    const pt::Sample2 j = s.get(0);
    F3 dc(((u + j.x) - cam.cx) / cam.fx, ((v + j.y) - cam.cy) / cam.fy, 1.0f);
    o = cam.o;
    if (aperture > 0.0f) {
      const pt::Sample2 ls = s.get(1);
      const pt::Sample2 dd = pt::concentric_disc(ls.x, ls.y);
      const F3 lens(dd.x * aperture, dd.y * aperture, 0.0f);
      dc = dc * focus - lens;
      o = cam.o + cam.to_world(lens);
    }
    d = normalize(cam.to_world(dc));
  };
  // The path of lane l of a traced camera packet, continued from the packet's first hit; its
  // radiance (non-finite -> 0, clamped to `clamp` luminance if set) and guides a, n.
  auto trace_lane = [&](Integrator& it, const RTCRayHit16& rh16, int l, F3 o, F3 d,
                        const pt::PixelSampler& s, F3& a, F3& n) {
    RTCRayHit first;
    first.ray.tfar = rh16.ray.tfar[l];
    first.hit.geomID = rh16.hit.geomID[l];
    first.hit.primID = rh16.hit.primID[l];
    first.hit.u = rh16.hit.u[l];
    first.hit.v = rh16.hit.v[l];
    F3 c = it.trace(o, d, s, a, n, &first);
    if (!all_finite(c)) c = F3(0.0f);
    if (clamp > 0.0f) {
      const float lum = luminance(c);
      if (lum > clamp) c *= clamp / lum;
    }
    return c;
  };

  // The Embree context of the camera-ray packets (coherent rays from one tile row).
  auto coherent_context = [] {
    RTCIntersectContext c;
    rtcInitIntersectContext(&c);
    c.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    return c;
  };

  // Threads take tiles one at a time (parallel_workers_dynamic); a tile's pixels depend only on
  // their indices.
  auto worker = [&](BlockQueue& tiles) {
    detail::FtzDazGuard guard;
    Integrator it(G, L, options);
    RTCIntersectContext coherent = coherent_context();
    const RTCScene scene = G.rays->impl().scene;  // camera rays: the robust BVH, as the labels
    alignas(64) RTCRayHit16 rh16;
    alignas(64) int valid16[16];
    pt::PairSeeds pair_seeds;  // the sampler's per-pair seeds of the current pixel block
    for (std::size_t tile, tile_end; tiles.next(tile, tile_end);) {
      const int tx = static_cast<int>(tile % tiles_x), ty = static_cast<int>(tile / tiles_x);
      const int u1 = std::min(W, (tx + 1) * kTile), v1 = std::min(H, (ty + 1) * kTile);
      for (int v = ty * kTile; v < v1; ++v) {
        // Labels: the pinhole rays through the pixel centres of this tile row, as one coherent
        // packet (at most kTile = 16 rays).
        if (options.labels) {
          const int u0 = tx * kTile, m = u1 - u0;
          float len[kTile];
          for (int k = 0; k < kTile; ++k) {
            const int u = u0 + std::min(k, m - 1);
            const F3 dc((u + 0.5f - cam.cx) / cam.fx, (v + 0.5f - cam.cy) / cam.fy, 1.0f);
            len[k] = length(dc);
            const F3 d = cam.to_world(dc / len[k]);
            set_packet_lane(rh16, valid16, k, k < m, cam.o, d);
          }
          rtcIntersect16(valid16, scene, &coherent, &rh16);
          it.counters.rays += m;
          for (int k = 0; k < m; ++k) {
            if (rh16.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) continue;
            const std::size_t pix = static_cast<std::size_t>(v) * W + u0 + k;
            out.depth[pix] = rh16.ray.tfar[k] / len[k];
            out.instance_ids[pix] = G.geoms[rh16.hit.geomID[k]].instance_id;
          }
        }
        // Camera rays: sample k of the (at most kTile = 16) pixels of this tile row as one
        // coherent packet; each path then continues on its own. Per pixel the samples are
        // summed in the order k = 0, 1, ... as before.
        const int u0 = tx * kTile, m = u1 - u0;
        pt::PixelStream pixel_stream[kTile];
        F3 sum[kTile], alb[kTile], nrm[kTile];
        F3 org[kTile], dir[kTile];
        for (int l = 0; l < m; ++l) {
          pixel_stream[l] = pt::pixel_stream(stream, static_cast<std::uint32_t>(u0 + l),
                                             static_cast<std::uint32_t>(v), spp_log2);
          sum[l] = alb[l] = nrm[l] = F3(0.0f);
        }
        for (int k = 0; k < options.spp; ++k) {
          for (int l = 0; l < kTile; ++l) {
            const int ll = std::min(l, m - 1);
            const pt::PixelSampler s(pixel_stream[ll].seed,
                                     pixel_stream[ll].base | static_cast<std::uint32_t>(k),
                                     &pair_seeds);
            camera_ray(s, u0 + ll, v, org[l], dir[l]);
            set_packet_lane(rh16, valid16, l, l < m, org[l], dir[l]);
          }
          rtcIntersect16(valid16, scene, &coherent, &rh16);
          it.counters.rays += m;
          for (int l = 0; l < m; ++l) {
            const pt::PixelSampler s(pixel_stream[l].seed,
                                     pixel_stream[l].base | static_cast<std::uint32_t>(k),
                                     &pair_seeds);
            F3 a, n;
            sum[l] += trace_lane(it, rh16, l, org[l], dir[l], s, a, n);
            alb[l] += a;
            nrm[l] += n;
          }
        }
        for (int l = 0; l < m; ++l) {
          const std::size_t pix = static_cast<std::size_t>(v) * W + u0 + l;
          float* r = &out.radiance[3 * pix];
          r[0] = sum[l].x * inv_spp;
          r[1] = sum[l].y * inv_spp;
          r[2] = sum[l].z * inv_spp;
          float* a = &out.albedo[3 * pix];
          a[0] = alb[l].x * inv_spp;
          a[1] = alb[l].y * inv_spp;
          a[2] = alb[l].z * inv_spp;
          const F3 nn = normalize(nrm[l]);
          float* n = &out.normal[3 * pix];
          n[0] = nn.x;
          n[1] = nn.y;
          n[2] = nn.z;
        }
      }
    }
    total_rays += it.counters.rays;
  };
  parallel_workers_dynamic(n_tiles, options.num_threads, 1, worker);

  // Adaptive sampling: extra samples where the first pass looks noisy. The decision depends on
  // the first pass only (deterministic); sample j of pixel (u, v) is index base | j of a second
  // stream, so the image is the same for any number of threads.
  if (options.adaptive_samples > 0.0) {
    const std::vector<std::uint8_t> extra =
        pt::allocate_extra_samples(pt::noise_estimate(out.radiance, out.albedo, W, H),
                                   options.adaptive_samples, options.adaptive_max);
    const std::uint64_t stream2 = mix64(stream ^ 0xA0761D6478BD642FULL);
    const int extra_log2 = pt::ceil_log2(static_cast<std::uint32_t>(options.adaptive_max));
    auto extra_worker = [&](BlockQueue& tiles) {
      detail::FtzDazGuard guard;
      Integrator it(G, L, options);
      RTCIntersectContext coherent = coherent_context();
      const RTCScene scene = G.rays->impl().scene;
      alignas(64) RTCRayHit16 rh16;
      alignas(64) int valid16[16];
      pt::PairSeeds pair_seeds;
      struct Job {
        std::size_t pix;
        int u, v, j;
        pt::PixelStream ps;
      };
      std::vector<Job> jobs;
      std::vector<F3> sum, alb, nrm;  // per pixel of the tile
      for (std::size_t tile, tile_end; tiles.next(tile, tile_end);) {
        const int tx = static_cast<int>(tile % tiles_x), ty = static_cast<int>(tile / tiles_x);
        const int u0 = tx * kTile, v0 = ty * kTile;
        const int u1 = std::min(W, u0 + kTile), v1 = std::min(H, v0 + kTile);
        // The tile's extra samples (pixel by pixel, j = 0, 1, ...), traced 16 at a time with
        // their camera rays as one packet; each pixel sums its samples in the order j.
        jobs.clear();
        for (int v = v0; v < v1; ++v) {
          for (int u = u0; u < u1; ++u) {
            const std::size_t pix = static_cast<std::size_t>(v) * W + u;
            if (extra[pix] == 0) continue;
            const pt::PixelStream ps = pt::pixel_stream(stream2, static_cast<std::uint32_t>(u),
                                                        static_cast<std::uint32_t>(v), extra_log2);
            for (int j = 0; j < extra[pix]; ++j) jobs.push_back({pix, u, v, j, ps});
          }
        }
        if (jobs.empty()) continue;
        sum.assign(static_cast<std::size_t>(kTile) * kTile, F3(0.0f));
        alb = nrm = sum;
        for (std::size_t b0 = 0; b0 < jobs.size(); b0 += 16) {
          const int m = static_cast<int>(std::min<std::size_t>(16, jobs.size() - b0));
          F3 org[16], dir[16];
          for (int l = 0; l < 16; ++l) {
            const Job& jb = jobs[b0 + std::min(l, m - 1)];
            const pt::PixelSampler s(jb.ps.seed, jb.ps.base | static_cast<std::uint32_t>(jb.j),
                                     &pair_seeds);
            camera_ray(s, jb.u, jb.v, org[l], dir[l]);
            set_packet_lane(rh16, valid16, l, l < m, org[l], dir[l]);
          }
          rtcIntersect16(valid16, scene, &coherent, &rh16);
          it.counters.rays += m;
          for (int l = 0; l < m; ++l) {
            const Job& jb = jobs[b0 + l];
            const pt::PixelSampler s(jb.ps.seed, jb.ps.base | static_cast<std::uint32_t>(jb.j),
                                     &pair_seeds);
            F3 a, n;
            const F3 c = trace_lane(it, rh16, l, org[l], dir[l], s, a, n);
            const std::size_t t = static_cast<std::size_t>(jb.v - v0) * kTile + (jb.u - u0);
            sum[t] += c;
            alb[t] += a;
            nrm[t] += n;
          }
        }
        const float n1 = static_cast<float>(options.spp);
        for (int v = v0; v < v1; ++v) {
          for (int u = u0; u < u1; ++u) {
            const std::size_t pix = static_cast<std::size_t>(v) * W + u;
            if (extra[pix] == 0) continue;
            const std::size_t t = static_cast<std::size_t>(v - v0) * kTile + (u - u0);
            const float inv_n = 1.0f / (n1 + static_cast<float>(extra[pix]));
            float* r = &out.radiance[3 * pix];
            float* a = &out.albedo[3 * pix];
            float* n = &out.normal[3 * pix];
            r[0] = (r[0] * n1 + sum[t].x) * inv_n;
            r[1] = (r[1] * n1 + sum[t].y) * inv_n;
            r[2] = (r[2] * n1 + sum[t].z) * inv_n;
            a[0] = (a[0] * n1 + alb[t].x) * inv_n;
            a[1] = (a[1] * n1 + alb[t].y) * inv_n;
            a[2] = (a[2] * n1 + alb[t].z) * inv_n;
            const F3 nn = normalize(F3(n[0], n[1], n[2]) * n1 + nrm[t]);
            n[0] = nn.x;
            n[1] = nn.y;
            n[2] = nn.z;
          }
        }
      }
      total_rays += it.counters.rays;
    };
    parallel_workers_dynamic(n_tiles, options.num_threads, 1, extra_worker);
  }
  out.rays = total_rays.load();
  return out;
}

// ---------------------------------------------------------------------------------------------
// Development.

std::vector<std::uint8_t> develop(const std::vector<float>& radiance, int width, int height,
                                  const FilmOptions& film) {
  film.validate();
  if (width <= 0 || height <= 0 ||
      radiance.size() != static_cast<std::size_t>(width) * height * 3) {
    throw_error<InvalidArgument>(
        "develop: radiance has ", radiance.size(),
        " values; expected an (H, W, 3) image with H, W > 0, got H=", height, " W=", width);
  }
  const std::size_t np = static_cast<std::size_t>(width) * height;
  std::vector<std::uint8_t> out(3 * np);
  const float gain = static_cast<float>(std::exp2(film.exposure));
  const bool noisy = film.shot_noise > 0.0 || film.read_noise > 0.0;
  const std::uint64_t stream = mix64(film.seed ^ mix64(film.view_index + 0x2545F4914F6CDD1DULL));
  const float shot = static_cast<float>(film.shot_noise),
              read = static_cast<float>(film.read_noise);
  const bool filmic = film.tone == FilmOptions::Tone::Filmic;
  parallel_for(np, film.num_threads, 16384, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      float x[3];
      for (int c = 0; c < 3; ++c) {
        const float r = radiance[3 * i + c];
        x[c] = std::isfinite(r) ? std::max(0.0f, r) * gain : 0.0f;
      }
      if (noisy) {
        Rng rng(stream, i);
        float n[6];  // N1, N2 per channel (Rng::normals: no libm, same values everywhere)
        rng.normals(n, 6);
        for (int c = 0; c < 3; ++c) {
          x[c] = std::max(0.0f, x[c] + shot * std::sqrt(x[c]) * n[2 * c] + read * n[2 * c + 1]);
        }
      }
      for (int c = 0; c < 3; ++c) {
        const float y = filmic ? 1.0f - std::exp(-x[c]) : std::min(1.0f, x[c]);
        const float s = linear_to_srgb(std::min(1.0f, std::max(0.0f, y)));
        out[3 * i + c] = static_cast<std::uint8_t>(std::lround(s * 255.0f));
      }
    }
  });
  return out;
}

bool decode_base_color_texture(const Material& material, std::vector<std::uint8_t>& rgb, int& width,
                               int& height) {
  cv::Mat img;
  if (!material.texture_data.empty()) {
    const cv::Mat buf(1, static_cast<int>(material.texture_data.size()), CV_8U,
                      const_cast<std::uint8_t*>(material.texture_data.data()));
    img = cv::imdecode(buf, cv::IMREAD_COLOR);
    if (img.empty()) {
      throw_error<IoError>("decode_base_color_texture: embedded texture of material '",
                           material.name, "' could not be decoded (", material.texture_data.size(),
                           " bytes; expected PNG or JPEG)");
    }
  } else if (!material.texture_path.empty()) {
    img = cv::imread(material.texture_path, cv::IMREAD_COLOR);
    if (img.empty()) {
      throw_error<IoError>("decode_base_color_texture: texture '", material.texture_path,
                           "' of material '", material.name, "' could not be read");
    }
  } else {
    return false;
  }
  cv::Mat out;
  cv::cvtColor(img, out, cv::COLOR_BGR2RGB);
  if (!out.isContinuous()) out = out.clone();
  width = out.cols;
  height = out.rows;
  rgb.assign(out.data, out.data + static_cast<std::size_t>(3) * width * height);
  return true;
}

}  // namespace mgn
