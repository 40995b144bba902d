#include <mgn/core/error.hpp>
#include <mgn/render/path_tracer.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <tuple>

#include "render/detail/pt_math.hpp"
#include "render/detail/pt_scene.hpp"

namespace mgn {

using pt::f3;
using pt::F3;
using pt::GeometryData;
using pt::LightData;
using pt::MaterialData;
using pt::TriEmitter;
using pt::TriShade;

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

constexpr float kMinAlpha = 2e-3f;         // GGX alpha floor (float precision of D near a delta)
constexpr float kCreaseCos = 0.70710678f;  // 45 degrees: normals are not smoothed across

}  // namespace

// ---------------------------------------------------------------------------------------------
// Validation of the scene's inputs.

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

// ---------------------------------------------------------------------------------------------
// Scene data.

namespace {

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
// Textures.

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
