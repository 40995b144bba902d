#pragma once
// Private: the path integrator (pt_integrator.cpp): the path of one camera sample through a
// PathScene, with BSDF sampling, next-event estimation of the lights and the environment
// (multiple importance sampling), Fresnel splitting at smooth glass, Russian roulette, and the
// denoiser's albedo and normal guides.
#include <mgn/render/path_tracer.hpp>

#include <cstddef>
#include <cstdint>
#include <limits>

#include "render/detail/pt_math.hpp"
#include "render/detail/pt_scene.hpp"

namespace mgn::pt {

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

inline void set_ray(RTCRay& r, F3 o, F3 d, float tfar) {
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

struct Counters {
  std::int64_t rays = 0;
};

/// The path integrator of one thread (its Embree context and ray counter).
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
    full_.set(L, 2, true);
    reduced_.set(L, o.shadow_rays, o.sample_sky_dome);
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
           const RTCRayHit* first = nullptr);

  Counters counters;

 private:
  /// How next-event estimation samples the lights at a path vertex.
  struct NeeMode {
    /// Environment sampling: the sun's cone with probability p_sun, the dome (cosine-weighted)
    /// with p_dome (Lighting::p_sun and 1 - p_sun; without the dome: 1 or 0, and 0).
    float p_sun = 0.0f, p_dome = 1.0f;
    bool env_nee = false;     // a shadow ray towards the environment
    bool one_shadow = false;  // one shadow ray: the environment (env_sel) or a light (area_sel)
    float env_sel = 1.0f;     // probability that the environment is sampled
    float area_sel = 1.0f;    // probability that a light (area or emissive triangle) is sampled
    void set(const Lighting& L, int shadow_rays, bool sky_dome) {
      p_sun = L.p_sun;
      p_dome = 1.0f - L.p_sun;
      env_nee = L.env_on;
      if (!sky_dome) {
        p_dome = 0.0f;
        p_sun = L.p_sun > 0.0f ? 1.0f : 0.0f;
        env_nee = L.env_on && p_sun > 0.0f;
      }
      if (shadow_rays == 1 && L.area_on && env_nee) {
        one_shadow = true;
        env_sel = 0.5f;
        area_sel = 0.5f;
      }
    }
  };
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
            std::size_t k, pt::Sample2 u, const NeeMode& mode);

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
  F3 emitted(const Hit& h, F3 d, F3* aux_albedo = nullptr, F3* aux_normal = nullptr);

  /// The denoiser guides along a ray whose first hit is `rh` (direction d): the first surface that
  /// is not see-through glass, followed through up to 8 smooth glass interfaces by refraction
  /// (total internal reflection: reflection), as the camera sees through a bottle's walls; a
  /// light or the environment gives its clamped radiance (normal unchanged).
  void aux_behind_glass(RTCRayHit rh, F3 d, F3& albedo, F3& normal);

  /// A BSDF sample (sample_bsdf).
  struct BsdfSample {
    F3 wi_w;             // direction, world frame
    F3 weight;           // f*cos/pdf, including the lobe choice
    float pdf = 0.0f;    // solid-angle pdf of the non-delta part (for MIS)
    bool delta = false;  // a delta lobe was chosen
    float eta2 = 1.0f;   // eta^2 of a refraction, else 1
  };

  /// Samples the BSDF into `out`; false when the sample is lost (below the surface, zero pdf).
  /// At a smooth dielectric, `split` (when given) receives the Fresnel split (see Split).
  bool sample_bsdf(const Hit& h, const pt::Frame& frame, F3 wo, const pt::ShadingMaterial& sm,
                   float u_lobe, float u_fresnel, pt::Sample2 u, BsdfSample& out,
                   Split* split = nullptr);

  /// Smooth-dielectric vertices per camera sample whose two branches are both traced in full
  /// (the first ones along the path, depth first); later ones are split as in `Split`.
  static constexpr int kMaxBranches = 3;

  /// One path of a camera sample: the ray it follows next and what it carries along. A branch of
  /// a smooth dielectric waiting its turn is a PathState too (trace()).
  struct PathState {
    F3 o, d;             // the ray to the next vertex (world)
    F3 beta = F3(1.0f);  // throughput
    /// Throughput for the light (area light, emissive triangle, environment) found at the next
    /// vertex: beta, except after a smooth dielectric whose other direction was followed to its
    /// first light only (Fresnel splitting, see Split): the chosen direction's expected share.
    F3 beta_e = F3(1.0f);
    bool prev_delta = true;  // the ray was sampled from a delta lobe (or is a camera ray)
    float prev_pdf = 0.0f;   // solid-angle pdf of the BSDF sample that made the ray
    F3 prev_n;               // shading normal at the previous vertex (environment pdf)
    float eta_scale = 1.0f;  // product of eta^2 over the refractions so far
    /// The denoiser guides (albedo, normal) of this path so far, weighted aov_w in the pixel's
    /// guides; still open (aov_open) while the path has met only see-through glass.
    F3 aov_a, aov_n;
    float aov_w = 1.0f;
    bool aov_open = true;
    int depth = 0;        // vertex index of the next hit (0 = the camera ray's)
    int rr_vertices = 0;  // vertices so far that count for Russian roulette
  };

  /// What a camera sample gathers over its paths: radiance, the denoiser guides of the paths
  /// done, and the branches waiting their turn: `pending`, a stack of kMaxBranches entries that
  /// trace() owns (kept apart from the sums, so that these can stay in registers).
  struct SampleSum {
    F3 L, aov_a, aov_n;
    PathState* pending = nullptr;
    int n_pending = 0;
    int branches_left = kMaxBranches;
  };

  // The stages of trace()'s bounce loop. Defined in pt_integrator.cpp and used there only;
  // always inlined into trace(), so that the hot loop compiles as the one function it is.

  /// Follows path p to its end (an emitter or the environment, max_bounces, a lost sample or
  /// Russian roulette), adding to sum; `first` as in trace().
  __attribute__((always_inline)) inline void trace_path(PathState& p, const pt::PixelSampler& s,
                                                        const RTCRayHit* first, SampleSum& sum);
  /// Traces p's ray into rh. Where it meets an area light or leaves to the environment, adds their
  /// light (MIS against next-event estimation) and guide and returns false; true at a surface.
  __attribute__((always_inline)) inline bool find_surface(PathState& p, const RTCRayHit* first,
                                                          RTCRayHit& rh, F3& L);
  /// At surface h (hit rh of p's ray): the emission of an emissive triangle's front side (MIS
  /// against its next-event estimation) and the denoiser guides.
  __attribute__((always_inline)) inline void add_surface_emission(PathState& p, const RTCRayHit& rh,
                                                                  const Hit& h, F3& L);
  /// Continues p at surface h: next-event estimation, BSDF sampling (with the Fresnel split of a
  /// smooth dielectric), Russian roulette; false when the path ends there.
  __attribute__((always_inline)) inline bool scatter(PathState& p, const Hit& h,
                                                     const pt::PixelSampler& s, SampleSum& sum);
  /// Next-event estimation at h: a light (area light or emissive triangle) and the environment,
  /// each with its own shadow ray, or (NeeMode::one_shadow) one of the two.
  __attribute__((always_inline)) inline void next_event(const PathState& p, const Hit& h,
                                                        const pt::Frame& frame, F3 wo,
                                                        const pt::ShadingMaterial& sm,
                                                        const pt::PixelSampler& s,
                                                        std::uint32_t base_pair, float u_light,
                                                        F3& L);
  /// The Fresnel split of BSDF sample bs at a smooth dielectric (split.on): the other direction
  /// waits in sum.pending as a branch, or is followed to its first light. Sets p.beta_e and the
  /// guide weights; returns the weight of the chosen direction.
  __attribute__((always_inline)) inline F3 take_split(PathState& p, const Hit& h,
                                                      const pt::ShadingMaterial& sm,
                                                      const BsdfSample& bs, const Split& split,
                                                      SampleSum& sum);
  /// Russian roulette at a vertex (smooth: at a smooth dielectric, not counted); false when the
  /// path is ended, else p's throughputs are rescaled.
  __attribute__((always_inline)) inline bool roulette(PathState& p, bool smooth, float u);

  const Geometry& G_;
  const Lighting& L_;
  const PathTraceOptions& opt_;
  RTCScene primary_;  // robust: camera rays
  RTCScene scene_;    // bounce and shadow rays
  float clamp_indirect_;
  float split_min_;        // PathTraceOptions::fresnel_split_min
  float guide_split_min_;  // PathTraceOptions::guide_split_min
  /// The mode of the vertex at `depth` (0 = the camera ray's hit): both shadow rays before
  /// PathTraceOptions::reduced_nee_depth, then PathTraceOptions::shadow_rays and
  /// sample_sky_dome.
  const NeeMode& nee(int depth) const { return depth >= reduce_from_ ? reduced_ : full_; }
  NeeMode full_, reduced_;
  int reduce_from_ = opt_.reduced_nee_depth;
  RTCIntersectContext ctx_;
};

}  // namespace mgn::pt
