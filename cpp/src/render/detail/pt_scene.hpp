#pragma once
// Private: the path tracer's scene (pt_scene.cpp builds it; pt_integrator.cpp and pt_film.cpp read
// it): the shading records of the triangles, the prepared materials, the emissive triangles and
// lights, and the two Embree BVHs (PathScene::Geometry, PathScene::Lighting).
#include <mgn/render/path_tracer.hpp>

#include <cstdint>
#include <deque>
#include <memory>
#include <vector>

#include "raytrace/ray_scene_impl.hpp"
#include "render/detail/pt_math.hpp"

namespace mgn {

namespace pt {

inline F3 f3(const Vec3f& v) { return {v.x(), v.y(), v.z()}; }
inline F3 f3(const Vec3d& v) {
  return {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
}

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

struct LightData {
  F3 centre, ex, ey, n;  // unit axes, normal = +z_L
  float hx, hy;          // rect half sizes; disc: radius in hx
  bool disc;
  float area;
  F3 radiance;
};

}  // namespace pt

struct PathScene::Geometry {
  std::unique_ptr<RayScene> rays;  // robust BVH: camera rays (labels, first hits)
  detail::OwnedScene bounce;       // non-robust BVH of the same geometry: bounce and shadow rays
  std::vector<pt::GeometryData> geoms;
  std::vector<PbrMaterial> materials;  // owns the textures
  std::vector<pt::MaterialData> mats;
  std::deque<pt::MsTables> ms_tables;    // shared by the materials of equal (alpha, ior, lobes)
  std::vector<pt::TriEmitter> emitters;  // the emissive triangles, for next-event estimation
  std::int64_t triangles = 0;
  Eigen::Matrix<double, 2, 3, Eigen::RowMajor> bounds;
};

struct PathScene::Lighting {
  std::vector<AreaLight> lights;
  Environment environment;
  std::vector<pt::LightData> light_data;
  std::vector<pt::TriEmitter> tris;  // the scene's emissive triangles (copied from the geometry)
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
  pt::F3 color, zenith, horizon, ground;
  pt::F3 sun_dir;
  float sun_cos = 1.0f;
  pt::F3 sun_radiance;
  float p_sun = 0.0f;  // probability of sampling the sun cone in environment sampling

  pt::F3 env(pt::F3 d) const {
    if (kind == 0) return color;
    pt::F3 c = d.z >= 0.0f ? pt::lerp(horizon, zenith, std::sqrt(d.z)) : ground;
    if (kind == 2 && dot(d, sun_dir) >= sun_cos) c += sun_radiance;
    return c;
  }
};

}  // namespace mgn
