// The path integrator (cpp/src/render/pt_integrator.cpp, through mgn::PathScene::render) on tiny
// scenes whose radiance is known in closed form or by quadrature: furnaces (an enclosure that
// emits and reflects uniformly; a glass shell and a white box in a uniform dome), and a Lambertian
// plane under a sky with a sun, an emissive quad, and rect and disc area lights. Together they
// take every stage of the bounce loop: emitters found by BSDF sampling and by next-event
// estimation (both shadow rays, one, the sun only), Fresnel splitting with its branches, Russian
// roulette. Built under AddressSanitizer and UndefinedBehaviorSanitizer by scripts/test.sh.
#include <gtest/gtest.h>
#include <mgn/geometry/primitives.hpp>
#include <mgn/render/camera.hpp>
#include <mgn/render/path_tracer.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace {

constexpr double kPi = 3.14159265358979323846;

mgn::CameraView camera(const mgn::Vec3d& eye, const mgn::Vec3d& target, int size, double fov_deg) {
  const double f = 0.5 * size / std::tan(fov_deg * kPi / 360.0);
  mgn::CameraView view;
  view.K = {size, size, f, f, 0.5 * size, 0.5 * size};
  view.X_WC = mgn::look_at(eye, target, mgn::Vec3d::UnitZ());
  return view;
}

/// Square of side `size` in the plane z = 0 centred at the origin, normal +z.
mgn::Mesh quad(double size) {
  const auto h = static_cast<float>(size / 2);
  mgn::Points3f v(4, 3);
  v << -h, -h, 0, h, -h, 0, h, h, 0, -h, h, 0;
  mgn::Faces f(2, 3);
  f << 0, 1, 2, 0, 2, 3;
  return {v, f};
}

mgn::Pose at(double x, double y, double z) {
  mgn::Pose X = mgn::Pose::Identity();
  X.translation() << x, y, z;
  return X;
}

/// The pose of a horizontal light or emitter at height z facing down (-z; rigid: x kept, y and z
/// reversed).
mgn::Pose facing_down(double x, double y, double z) {
  mgn::Pose X = at(x, y, z);
  X.linear() = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();
  return X;
}

mgn::PbrMaterial lambert(float albedo) {
  mgn::PbrMaterial m;
  m.base_color = mgn::Vec3f::Constant(albedo);
  m.ior = 1.0f;  // no specular layer
  m.roughness = 1.0f;
  return m;
}

mgn::Environment uniform(float radiance) {
  mgn::Environment e;
  e.kind = mgn::Environment::Kind::Uniform;
  e.color = mgn::Vec3f::Ones();
  e.intensity = radiance;
  return e;
}

mgn::PathTraceOptions options(int spp, int max_bounces, int rr_depth) {
  mgn::PathTraceOptions o;
  o.spp = spp;
  o.max_bounces = max_bounces;
  o.rr_depth = rr_depth;
  o.seed = 11;
  o.num_threads = 1;
  return o;
}

/// Mean over pixels of (radiance - expected) (channel mean) and its standard error.
struct Error {
  double mean = 0.0, sem = 0.0, expected_mean = 0.0;
  std::size_t n = 0;
};

Error error_of(const mgn::PathTraceOutput& out, const std::function<bool(int, int)>& use,
               const std::function<double(int, int)>& expected) {
  double s = 0.0, s2 = 0.0, se = 0.0;
  std::size_t n = 0;
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      if (!use(x, y)) continue;
      const std::size_t i = 3 * (static_cast<std::size_t>(y) * out.width + x);
      const double v =
          (static_cast<double>(out.radiance[i]) + out.radiance[i + 1] + out.radiance[i + 2]) / 3.0;
      const double e = expected(x, y);
      s += v - e;
      s2 += (v - e) * (v - e);
      se += e;
      ++n;
    }
  }
  Error r;
  r.n = n;
  if (n < 2) return r;
  const double dn = static_cast<double>(n);
  r.mean = s / dn;
  r.expected_mean = se / dn;
  const double var = std::max(0.0, (s2 - s * s / dn) / (dn - 1.0));
  r.sem = std::sqrt(var / dn);
  return r;
}

// ---------------------------------------------------------------------------------------------
// Furnaces.

TEST(PathIntegrator, InteriorFurnaceCollectsTheSeriesOfBounces) {
  // Inside a closed box whose inner walls emit E and reflect with albedo a (Lambert), every
  // point receives radiance L from every direction with L = E + a L: a path of k segments after
  // the camera ray collects E (1 - a^(k+1)) / (1 - a), with unlimited bounces E / (1 - a) (here
  // with Russian roulette from the first vertex: unbiased). Flat walls: the shading normal is the
  // geometric one, no direction is lost below a facet.
  const float E = 0.6f, a = 0.5f;
  const mgn::Mesh box = mgn::make_box(mgn::Vec3d(1.0, 0.8, 0.6)).flipped();
  mgn::PbrMaterial wall = lambert(a);
  wall.emission = mgn::Vec3f::Constant(E);
  const mgn::PathScene scene({{&box, at(0, 0, 0), 1, {wall}}}, {}, uniform(0.0f));
  const mgn::CameraView view = camera({0.1, -0.05, 0.02}, {1.0, 0.3, 0.1}, 16, 100);
  const auto all = [](int, int) { return true; };
  struct Case {
    int max_bounces, rr_depth;
    double expected;
  };
  for (const Case& c :
       {Case{0, 100, E}, Case{2, 100, E * (1 + a + a * a)}, Case{200, 1, E / (1 - a)}}) {
    const mgn::PathTraceOutput out = scene.render(view, options(16, c.max_bounces, c.rr_depth));
    const Error err = error_of(out, all, [&](int, int) { return c.expected; });
    ASSERT_EQ(err.n, 256u);
    EXPECT_LE(std::abs(err.mean), 4 * err.sem + 1e-4 * c.expected)
        << "max_bounces " << c.max_bounces << " rr_depth " << c.rr_depth << ": mean "
        << err.mean + c.expected << ", expected " << c.expected << ", sem " << err.sem;
  }
}

TEST(PathIntegrator, GlassShellAndWhiteBoxInAUniformDomeShowTheDome) {
  // A clear glass shell (outer sphere, inner sphere wound inwards: a closed wall) and a white
  // Lambertian box neither absorb nor emit, so in a uniform dome L both show L. The glass takes
  // the smooth-dielectric path: Fresnel splitting, the branches traced in full and, deeper, the
  // other direction followed to its first light, refraction's 1/eta^2 scaling undone on leaving,
  // roulette on the throughput without that scaling. The box sees the dome and the shell.
  const float L = 0.7f;
  const mgn::Mesh outer = mgn::make_sphere(0.3, 48, 24);
  const mgn::Mesh inner = mgn::make_sphere(0.29, 48, 24).flipped();
  const mgn::Mesh box = mgn::make_box(mgn::Vec3d(0.4, 0.4, 0.4));
  mgn::PbrMaterial glass;
  glass.base_color = mgn::Vec3f::Ones();
  glass.transmission = 1.0f;
  glass.roughness = 0.0f;
  glass.ior = 1.5f;
  const mgn::PathScene scene({{&outer, at(0, 0, 0), 1, {glass}},
                              {&inner, at(0, 0, 0), 1, {glass}},
                              {&box, at(0.6, 0.4, 0), 2, {lambert(1.0f)}}},
                             {}, uniform(L));
  const mgn::PathTraceOutput out =
      scene.render(camera({0.3, -2.0, 0.2}, {0.25, 0.1, 0}, 24, 36), options(16, 64, 3));
  const auto id = [&](int x, int y) { return out.instance_ids[y * out.width + x]; };
  // Pixels whose 3 x 3 neighbourhood shows one instance only (no silhouette pixels).
  const auto inside = [&](std::int32_t want) {
    return [&, want](int x, int y) {
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = x + dx, yy = y + dy;
          if (xx < 0 || yy < 0 || xx >= out.width || yy >= out.height) return false;
          if (id(xx, yy) != want) return false;
        }
      return true;
    };
  };
  const auto dome = [&](int, int) { return static_cast<double>(L); };
  const Error g = error_of(out, inside(1), dome);
  const Error b = error_of(out, inside(2), dome);
  const Error bg = error_of(out, inside(0), dome);
  ASSERT_GT(g.n, 40u);
  ASSERT_GT(b.n, 20u);
  ASSERT_GT(bg.n, 100u);
  EXPECT_LE(std::abs(g.mean), 4 * g.sem + 1e-4) << "glass: mean " << L + g.mean << " sem " << g.sem;
  EXPECT_GT(g.sem, 0.0);  // Fresnel splitting makes single samples differ from L
  EXPECT_LE(std::abs(b.mean), 4 * b.sem + 1e-4) << "box: mean " << L + b.mean << " sem " << b.sem;
  EXPECT_NEAR(bg.mean, 0.0, 1e-6);  // the dome seen directly (float sums of the samples)
  EXPECT_LE(bg.sem, 1e-6);
  // The box's albedo guide is its base colour; every seen pixel has a unit normal guide.
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      if (!inside(2)(x, y)) continue;
      const std::size_t i = 3 * (static_cast<std::size_t>(y) * out.width + x);
      EXPECT_NEAR(out.albedo[i + 1], 1.0f, 1e-5f);
      const double n2 = out.normal[i] * out.normal[i] + out.normal[i + 1] * out.normal[i + 1] +
                        out.normal[i + 2] * out.normal[i + 2];
      EXPECT_NEAR(n2, 1.0, 1e-4);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// A Lambertian plane (albedo a, z = 0) under emitters: radiance a E / pi for irradiance E.

/// The camera looking down at the plane around the origin from the side (no emitter in view).
mgn::CameraView plane_camera() { return camera({1.0, -0.75, 0.6}, {0, 0, 0}, 20, 14); }

/// Where the ray through image point (u, v) (continuous pixel coordinates) meets the plane z = 0.
mgn::Vec3d plane_point(const mgn::CameraView& view, double u, double v) {
  const mgn::Vec3d d_c((u - view.K.cx) / view.K.fx, (v - view.K.cy) / view.K.fy, 1.0);
  const mgn::Vec3d d = view.X_WC.linear() * d_c;
  const mgn::Vec3d o = view.X_WC.translation();
  return o + d * (-o.z() / d.z());
}

/// Mean of f over the plane points seen by pixel (x, y) (3 x 3 points spread over the pixel,
/// whose samples are uniform over it).
double pixel_mean(const mgn::CameraView& view, int x, int y,
                  const std::function<double(const mgn::Vec3d&)>& f) {
  double sum = 0.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) sum += f(plane_point(view, x + (i + 0.5) / 3, y + (j + 0.5) / 3));
  return sum / 9.0;
}

/// A horizontal emitter at height h facing down, as midpoint quadrature points (x, y, area): a
/// rect of sides sx, sy centred at (cx, cy), or (disc) a disc of radius sx.
struct Emitter {
  double h;
  std::vector<Eigen::Vector3d> points;
  Emitter(double cx, double cy, double h_, double sx, double sy, bool disc) : h(h_) {
    const int n = 48;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        if (disc) {
          const double r = (i + 0.5) / n * sx, phi = (j + 0.5) / n * 2.0 * kPi;
          points.emplace_back(cx + r * std::cos(phi), cy + r * std::sin(phi),
                              r * (sx / n) * (2.0 * kPi / n));
        } else {
          points.emplace_back(cx + ((i + 0.5) / n - 0.5) * sx, cy + ((j + 0.5) / n - 0.5) * sy,
                              (sx / n) * (sy / n));
        }
      }
    }
  }
  /// Projected solid angle (sr) seen from p on the plane: the integral of
  /// cos_p cos_l / r^2 = h^2 / r^4 over the emitter.
  double projected_solid_angle(const mgn::Vec3d& p) const {
    double sum = 0.0;
    for (const Eigen::Vector3d& q : points) {
      const double r2 =
          (q.x() - p.x()) * (q.x() - p.x()) + (q.y() - p.y()) * (q.y() - p.y()) + h * h;
      sum += h * h / (r2 * r2) * q.z();
    }
    return sum;
  }
};

TEST(PathIntegrator, PlaneUnderSkyAndSunShowsTheirIrradiance) {
  // The gradient sky (horizon colour at the horizon to zenith colour straight up, linear in
  // sqrt(cos theta)) gives an upward plane E = 2 pi int_0^1 (h + (z - h) sqrt(mu)) mu dmu
  // = pi (0.2 h + 0.8 z); the sun, a cone of uniform radiance whose irradiance at normal
  // incidence is sun_strength * pi * luminance(zenith), adds that times cos(sun angle) (exact for
  // a cap above the horizon). Each way of sampling them must give a E / pi: both shadow rays,
  // shadow rays at the sun only (the dome left to the bounce ray), from the first bounce on.
  const float a = 0.6f;
  const mgn::Mesh plane = quad(20.0);
  mgn::Environment sky;
  sky.kind = mgn::Environment::Kind::Sky;
  sky.zenith = mgn::Vec3f(0.3f, 0.5f, 0.9f);
  sky.horizon = mgn::Vec3f(0.9f, 0.8f, 0.7f);
  sky.ground = mgn::Vec3f(0.2f, 0.2f, 0.2f);
  sky.sun_direction = mgn::Vec3d(0.4, 0.3, 0.8);
  sky.sun_strength = 4.0f;
  sky.intensity = 1.5f;
  const mgn::PathScene scene({{&plane, at(0, 0, 0), 1, {lambert(a)}}}, {}, sky);
  const double I = sky.intensity;
  const mgn::Vec3f lum_w(0.2126f, 0.7152f, 0.0722f);
  const double sun_cos = sky.sun_direction.normalized().z();
  double expected = 0.0;  // channel mean of a E / pi
  for (int c = 0; c < 3; ++c)
    expected += a * I *
                (0.2 * sky.horizon[c] + 0.8 * sky.zenith[c] +
                 sky.sun_strength * lum_w.dot(sky.zenith) * sun_cos) /
                3.0;
  const mgn::CameraView view = plane_camera();
  const auto all = [](int, int) { return true; };
  for (int variant = 0; variant < 3; ++variant) {
    mgn::PathTraceOptions o = options(16, 2, 100);
    if (variant >= 1) o.sample_sky_dome = false;
    if (variant == 2) o.reduced_nee_depth = 1;
    const mgn::PathTraceOutput out = scene.render(view, o);
    const Error err = error_of(out, all, [&](int, int) { return expected; });
    EXPECT_LE(std::abs(err.mean), 4 * err.sem + 1e-3 * expected)
        << "variant " << variant << ": mean " << expected + err.mean << ", expected " << expected
        << ", sem " << err.sem;
  }
}

TEST(PathIntegrator, PlaneUnderAnEmissiveQuadAndAUniformDomeShowsTheirIrradiance) {
  // An emissive quad (radiance Le towards the plane, black) at height h in a uniform dome L
  // hides the dome behind it: E = L (pi - P) + Le P with P its projected solid angle seen from
  // the point. Light from the quad is found by its shadow rays and by the bounce rays that hit
  // it (MIS between the two); with one shadow ray per vertex, the quad or the dome is chosen.
  const float a = 0.5f, L = 0.4f, Le = 6.0f;
  const double h = 0.3, side = 0.25;
  const mgn::Mesh plane = quad(20.0);
  const mgn::Mesh lamp = quad(side);
  mgn::PbrMaterial emitter = lambert(0.0f);
  emitter.emission = mgn::Vec3f::Constant(Le);
  const mgn::PathScene scene(
      {{&plane, at(0, 0, 0), 1, {lambert(a)}}, {&lamp, facing_down(0.05, 0.0, h), 2, {emitter}}},
      {}, uniform(L));
  const mgn::CameraView view = plane_camera();
  const Emitter lamp_area(0.05, 0.0, h, side, side, false);
  std::vector<double> expected(static_cast<std::size_t>(view.K.width) * view.K.height);
  for (int y = 0; y < view.K.height; ++y)
    for (int x = 0; x < view.K.width; ++x) {
      expected[y * view.K.width + x] = pixel_mean(view, x, y, [&](const mgn::Vec3d& p) {
        const double P = lamp_area.projected_solid_angle(p);
        return a / kPi * (L * (kPi - P) + Le * P);
      });
    }
  const auto want = [&](int x, int y) { return expected[y * view.K.width + x]; };
  const auto all = [](int, int) { return true; };
  for (int shadow_rays : {2, 1}) {
    mgn::PathTraceOptions o = options(16, 2, 100);
    o.shadow_rays = shadow_rays;
    const mgn::PathTraceOutput out = scene.render(view, o);
    const Error err = error_of(out, all, want);
    ASSERT_EQ(err.n, 400u);
    EXPECT_GT(err.expected_mean, 1.5 * a * L);  // the quad's light counts
    EXPECT_LE(std::abs(err.mean), 4 * err.sem + 1e-3 * err.expected_mean)
        << "shadow_rays " << shadow_rays << ": mean " << err.expected_mean + err.mean
        << ", expected " << err.expected_mean << ", sem " << err.sem;
  }
}

TEST(PathIntegrator, PlaneUnderRectAndDiscLightsShowsTheirIrradiance) {
  // One-sided area lights (not geometry) in a black dome: E = Le P for each, P by quadrature.
  const float a = 0.7f;
  const mgn::Mesh plane = quad(20.0);
  const mgn::PathScene base({{&plane, at(0, 0, 0), 1, {lambert(a)}}}, {}, uniform(0.0f));
  const mgn::CameraView view = plane_camera();
  const auto all = [](int, int) { return true; };
  struct Lamp {
    mgn::AreaLight::Shape shape;
    double x, h, sx, sy;
    float Le;
  };
  for (const Lamp& l : {Lamp{mgn::AreaLight::Shape::Rect, -0.05, 0.4, 0.3, 0.2, 5.0f},
                        Lamp{mgn::AreaLight::Shape::Disc, 0.1, 0.25, 0.08, 0.08, 20.0f}}) {
    mgn::AreaLight light;
    light.X_WL = facing_down(l.x, 0.0, l.h);
    light.shape = l.shape;
    light.size = Eigen::Vector2d(l.sx, l.sy);
    light.intensity = l.Le;
    const bool disc = l.shape == mgn::AreaLight::Shape::Disc;
    const Emitter emitter(l.x, 0.0, l.h, l.sx, l.sy, disc);
    const mgn::PathScene scene = base.with_lighting({light}, uniform(0.0f));
    const mgn::PathTraceOutput out = scene.render(view, options(16, 2, 100));
    const Error err = error_of(out, all, [&](int x, int y) {
      return pixel_mean(view, x, y, [&](const mgn::Vec3d& p) {
        return a / kPi * l.Le * emitter.projected_solid_angle(p);
      });
    });
    EXPECT_GT(err.expected_mean, 0.05);
    EXPECT_LE(std::abs(err.mean), 4 * err.sem + 1e-3 * err.expected_mean)
        << (disc ? "disc" : "rect") << ": mean " << err.expected_mean + err.mean << ", expected "
        << err.expected_mean << ", sem " << err.sem;
  }
}

}  // namespace
