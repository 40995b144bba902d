// The path tracer's BSDF (cpp/src/render/detail/pt_math.hpp): GGX conductor, specular layer over
// Lambert, rough dielectric (Walter et al. 2007) and their multiple-scattering compensation.
// Truth: brute-force quadrature over the sphere of the evaluated BSDF (albedo, energy
// conservation, pdf normalisation), the symmetry of the BSDF (reciprocity; for transmission in
// the radiance convention f(wo, wi) / n_o^2 = f(wi, wo) / n_i^2, n_o the refractive index on wo's
// side), and a second implementation of the rough dielectric written here from the paper's
// formulas for the sampled weights.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <random>

#include "render/detail/pt_math.hpp"

namespace {

using mgn::pt::F3;
using mgn::pt::kPi;
using mgn::pt::MsTables;
using mgn::pt::ShadingMaterial;

struct Mat {
  F3 base{1.0f};
  float metallic = 0.0f, roughness = 0.5f, ior = 1.5f, transmission = 0.0f;
  bool compensate = true;
  std::shared_ptr<MsTables> tables() const {
    const float a = roughness * roughness;
    return std::make_shared<MsTables>(mgn::pt::make_ms_tables(
        a, ior, metallic > 0.0f, (1.0f - metallic) * (1.0f - transmission) > 0.0f,
        (1.0f - metallic) * transmission > 0.0f));
  }
  /// The material prepared for wo at cos theta = mu on side `front`.
  ShadingMaterial at(float mu, bool front, const MsTables* t) const {
    ShadingMaterial s{base, metallic,     roughness * roughness,
                      ior,  transmission, compensate ? t : nullptr};
    s.prepare(mu, front);
    return s;
  }
};

F3 dir(float mu, float phi) {
  const float s = std::sqrt(std::max(0.0f, 1.0f - mu * mu));
  return {s * std::cos(phi), s * std::sin(phi), mu};
}

/// int over the sphere of g(w) dw by the midpoint rule in polar coordinates (theta, phi) about
/// `axis`, theta = pi s^2 (cells shrink towards the axis, where a glossy lobe is concentrated
/// when the axis is its peak): dw = sin(theta) 2 pi s ds dphi.
template <class G>
double sphere_integral(F3 axis, G&& g, int ns = 1024, int nphi = 256) {
  const mgn::pt::Frame fr(mgn::pt::normalize(axis));
  double s = 0.0;
  for (int i = 0; i < ns; ++i) {
    const double u = (i + 0.5) / ns;
    const double th = kPi * u * u;
    const double w = std::sin(th) * 2.0 * kPi * u / ns * (2.0 * kPi / nphi);
    double row = 0.0;
    for (int j = 0; j < nphi; ++j) {
      const double ph = (j + 0.5) * 2.0 * kPi / nphi;
      const F3 d(static_cast<float>(std::sin(th) * std::cos(ph)),
                 static_cast<float>(std::sin(th) * std::sin(ph)), static_cast<float>(std::cos(th)));
      row += g(fr.to_world(d));
    }
    s += row * w;
  }
  return s;
}

/// The peak of the transmission lobe: wo refracted through the normal (+z), or -z at total
/// internal reflection.
F3 refracted(F3 wo, float eta) {
  if ((1.0f - wo.z * wo.z) >= eta * eta) return {0.0f, 0.0f, -1.0f};
  return mgn::pt::refract_m(wo, F3(0.0f, 0.0f, 1.0f), wo.z, eta);
}

/// Energy albedo of the BSDF for wo (local, wo.z > 0): int f |cos| over the upper hemisphere plus
/// eta^2 int f |cos| over the lower one (undoing the 1/eta^2 radiance scaling of transmission),
/// per channel `c`. Transmission is evaluated with eval_rough_dielectric (times w_trans).
double energy(const ShadingMaterial& s, F3 wo, int c = 1) {
  const double r = sphere_integral(F3(-wo.x, -wo.y, wo.z), [&](F3 wi) {
    if (wi.z <= 0.0f) return 0.0;
    F3 f;
    float pdf;
    s.eval(wo, wi, f, pdf);
    return static_cast<double>(f[c]) * wi.z;
  });
  if (!s.rough) return r;
  return r + sphere_integral(refracted(wo, s.eta), [&](F3 wi) {
           if (wi.z >= 0.0f) return 0.0;
           F3 f;
           float pdf;
           s.eval_rough_dielectric(wo, wi, f, pdf);
           return static_cast<double>(f[c]) * s.w_trans * s.eta * s.eta * -wi.z;
         });
}

// ---------------------------------------------------------------------------------------------
// Albedo tables and energy conservation.

TEST(PathBsdf, SingleScatteringAlbedoTablesMatchQuadratureOfFCos) {
  // The tables (visible-normal quadrature) against int f cos of the single-scattering lobes.
  for (float r : {0.3f, 0.6f, 1.0f}) {
    for (float mu : {0.08f, 0.4f, 0.95f}) {
      const F3 wo = dir(mu, 0.0f);
      Mat metal{F3(1.0f), 1.0f, r};
      const auto tm = metal.tables();
      metal.compensate = false;
      EXPECT_NEAR(energy(metal.at(mu, true, nullptr), wo), tm->cond(mu), 2e-3) << r << " " << mu;
      Mat coat{F3(0.0f), 0.0f, r, 1.5f};  // black base: the specular layer alone
      const auto tc = coat.tables();
      coat.compensate = false;
      EXPECT_NEAR(energy(coat.at(mu, true, nullptr), wo), tc->spec(mu), 2e-3) << r << " " << mu;
      Mat glass{F3(1.0f), 0.0f, r, 1.5f, 1.0f};
      const auto tg = glass.tables();
      glass.compensate = false;
      for (int side = 0; side < 2; ++side) {
        EXPECT_NEAR(energy(glass.at(mu, side == 0, nullptr), wo), tg->diel[side](mu), 2e-3)
            << r << " " << mu << " side " << side;
      }
    }
  }
}

TEST(PathBsdf, CompensatedLobesReflectOrTransmitAllEnergyOfAWhiteMaterial) {
  for (float r : {0.1f, 0.3f, 0.6f, 1.0f}) {
    for (float mu : {0.05f, 0.3f, 0.7f, 1.0f}) {
      const F3 wo = dir(mu, 0.3f);
      Mat metal{F3(1.0f), 1.0f, r};
      const auto tm = metal.tables();
      EXPECT_NEAR(energy(metal.at(mu, true, tm.get()), wo), 1.0, 3e-3)
          << "metal " << r << " " << mu;
      Mat plastic{F3(1.0f), 0.0f, r, 1.5f};
      const auto tp = plastic.tables();
      EXPECT_NEAR(energy(plastic.at(mu, true, tp.get()), wo), 1.0, 3e-3)
          << "plastic " << r << " " << mu;
      Mat glass{F3(1.0f), 0.0f, r, 1.5f, 1.0f};
      const auto tg = glass.tables();
      for (int side = 0; side < 2; ++side) {
        EXPECT_NEAR(energy(glass.at(mu, side == 0, tg.get()), wo), 1.0, 3e-3)
            << "glass " << r << " " << mu << " side " << side;
      }
    }
  }
}

}  // namespace
