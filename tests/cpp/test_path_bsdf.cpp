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

// ---------------------------------------------------------------------------------------------
// Reciprocity.

F3 random_dir(std::mt19937& rng, bool upper) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float z = 0.02f + 0.98f * u(rng);
  return dir(upper ? z : -z, 2.0f * kPi * u(rng));
}

void expect_rel(float a, float b, float rel, const char* what) {
  EXPECT_NEAR(a, b, rel * std::max(std::abs(a), std::abs(b)) + 1e-6f) << what;
}

TEST(PathBsdf, ReflectionIsSymmetricInItsDirections) {
  // f(wo, wi) = f(wi, wo) for the compensated conductor (coloured: F_ms from the base colour)
  // and the reflection of the compensated rough dielectric on either side.
  std::mt19937 rng(7);
  for (float r : {0.1f, 0.3f, 0.7f, 1.0f}) {
    const Mat gold{F3(1.0f, 0.78f, 0.34f), 1.0f, r};
    const Mat glass{F3(0.9f, 0.95f, 0.8f), 0.0f, r, 1.5f, 1.0f};
    const auto tm = gold.tables(), tg = glass.tables();
    for (int k = 0; k < 400; ++k) {
      const F3 a = random_dir(rng, true), b = random_dir(rng, true);
      F3 fab, fba;
      float p;
      gold.at(a.z, true, tm.get()).eval(a, b, fab, p);
      gold.at(b.z, true, tm.get()).eval(b, a, fba, p);
      for (int c = 0; c < 3; ++c) expect_rel(fab[c], fba[c], 2e-4f, "conductor");
      for (int side = 0; side < 2; ++side) {
        glass.at(a.z, side == 0, tg.get()).eval(a, b, fab, p);
        glass.at(b.z, side == 0, tg.get()).eval(b, a, fba, p);
        expect_rel(fab.y, fba.y, 2e-4f, "dielectric reflection");
      }
    }
  }
}

TEST(PathBsdf, RoughDielectricTransmissionIsReciprocalUpToTheSquaredIndices) {
  // Radiance convention (transmitted radiance scaled by (n_o / n_i)^2): f(wo, wi) / n_o^2 =
  // f(wi, wo) / n_i^2 with n_o the index on wo's side. Seen from inside, the local frame's +z
  // is the inward normal: a direction d outside is -d there.
  std::mt19937 rng(11);
  for (float ior : {1.33f, 1.5f, 2.4f}) {
    for (float r : {0.1f, 0.3f, 0.7f, 1.0f}) {
      const Mat glass{F3(0.9f, 0.95f, 0.8f), 0.0f, r, ior, 1.0f};
      const auto t = glass.tables();
      for (int k = 0; k < 400; ++k) {
        const F3 a = random_dir(rng, true), b = random_dir(rng, false);  // a outside, b inside
        F3 f_out, f_in;
        float p;
        glass.at(a.z, true, t.get()).eval_rough_dielectric(a, b, f_out, p);
        glass.at(-b.z, false, t.get()).eval_rough_dielectric(-b, -a, f_in, p);
        // Near the specular peak of alpha = 0.01, D is steep: float rounding of the half vector.
        const float rel = r < 0.2f ? 3e-3f : 1e-3f;
        for (int c = 0; c < 3; ++c) expect_rel(f_out[c] / 1.0f, f_in[c] / (ior * ior), rel, "T");
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Sampling.

TEST(PathBsdf, SamplingPdfIntegratesToTheFractionOfValidSamples) {
  // The density eval_rough_dielectric reports, integrated over the sphere, is at most 1 and is
  // the fraction of sample_rough's draws that give a direction (reflections that end below the
  // surface and refractions that end above it are lost), counted over a 128^3 grid of inputs.
  for (float r : {0.3f, 0.6f, 1.0f}) {
    const Mat glass{F3(1.0f), 0.0f, r, 1.5f, 1.0f};
    const auto t = glass.tables();
    for (int side = 0; side < 2; ++side) {
      for (float mu : {0.1f, 0.5f, 0.9f}) {
        const ShadingMaterial s = glass.at(mu, side == 0, t.get());
        const F3 wo = dir(mu, 0.0f);
        const double up = sphere_integral(F3(-wo.x, -wo.y, wo.z), [&](F3 wi) {
          F3 f;
          float pdf;
          s.eval_rough_dielectric(wo, wi, f, pdf);
          return wi.z > 0.0f ? static_cast<double>(pdf) : 0.0;
        });
        const double down = sphere_integral(refracted(wo, s.eta), [&](F3 wi) {
          F3 f;
          float pdf;
          s.eval_rough_dielectric(wo, wi, f, pdf);
          return wi.z < 0.0f ? static_cast<double>(pdf) : 0.0;
        });
        const int n = 128;
        double valid = 0.0;
        for (int i = 0; i < n; ++i)
          for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k) {
              F3 wi, w;
              const bool tr =
                  s.sample_rough(wo, (i + 0.5f) / n, (j + 0.5f) / n, (k + 0.5f) / n, wi, w);
              valid += tr ? (wi.z < 0.0f) : (wi.z > 0.0f);
            }
        valid /= static_cast<double>(n) * n * n;
        EXPECT_LE(up + down, 1.0 + 2e-3) << r << " " << mu << " side " << side;
        EXPECT_NEAR(up + down, valid, 3e-3) << r << " " << mu << " side " << side;
      }
    }
  }
}

/// A second implementation of the rough dielectric, written from Walter et al. 2007 in their
/// notation: o the direction radiance leaves along (wo, index n_o), i the direction it comes
/// from (wi, index n_i), radiance-form BSDF
///   reflection:   F(i.h) D(h) G(i, o) / (4 |i.n| |o.n|),  h = normalize(i + o)
///   transmission: |i.h| |o.h| / (|i.n| |o.n|) n_o^2 (1 - F(i.h)) D(h) G(i, o)
///                 / (n_i (i.h) + n_o (o.h))^2,           h = -normalize(n_i i + n_o o)
/// with D and Lambda of GGX in their trigonometric form, the height-correlated G, the exact
/// Fresnel equations; plus the compensation lobes of the tables, and the sampling density of
/// the mixture (visible normals, Walter's Jacobian for refraction, cosine lobes).
struct Walter {
  float alpha, n_o, n_i, q, t, cr, ct;
  const mgn::pt::AlbedoTable *e_o, *e_i;
  double d(double cos_h) const {
    if (cos_h <= 0) return 0;
    const double c2 = cos_h * cos_h, t2 = (1 - c2) / c2, a2 = double(alpha) * alpha;
    return a2 / (kPi * c2 * c2 * (a2 + t2) * (a2 + t2));
  }
  double lambda(double cos_t) const {
    const double c2 = cos_t * cos_t, t2 = (1 - c2) / c2;
    return (std::sqrt(1 + double(alpha) * alpha * t2) - 1) / 2;
  }
  double fresnel(double c, double n1, double n2) const {
    const double s2 = (1 - c * c) * (n1 / n2) * (n1 / n2);
    if (s2 >= 1) return 1;
    const double ct2 = std::sqrt(1 - s2);
    const double rs = (n1 * c - n2 * ct2) / (n1 * c + n2 * ct2);
    const double rp = (n1 * ct2 - n2 * c) / (n1 * ct2 + n2 * c);
    return (rs * rs + rp * rp) / 2;
  }
  /// f and pdf (of sampling i given o) for o.z > 0.
  void eval(F3 o, F3 i, double& f, double& pdf) const {
    const double ox = o.x, oy = o.y, oz = o.z, ix = i.x, iy = i.y, iz = i.z;
    const double g = 1 / (1 + lambda(oz) + lambda(iz)), g1 = 1 / (1 + lambda(oz));
    if (iz > 0) {
      double hx = ix + ox, hy = iy + oy, hz = iz + oz;
      const double l = std::sqrt(hx * hx + hy * hy + hz * hz);
      hx /= l, hy /= l, hz /= l;
      const double oh = ox * hx + oy * hy + oz * hz;
      const double F = fresnel(oh, n_o, n_i);
      f = F * d(hz) * g / (4 * iz * oz) + cr * (1 - (*e_o)(oz)) * (1 - (*e_o)(iz)) / kPi;
      pdf = (1 - q) * F * g1 * oh * d(hz) / oz / (4 * oh) + q * (1 - t) * iz / kPi;
      return;
    }
    double hx = -(n_i * ix + n_o * ox), hy = -(n_i * iy + n_o * oy), hz = -(n_i * iz + n_o * oz);
    const double l = std::sqrt(hx * hx + hy * hy + hz * hz);
    const double sg = hz < 0 ? -1 : 1;
    hx *= sg / l, hy *= sg / l, hz *= sg / l;
    const double ih = ix * hx + iy * hy + iz * hz, oh = ox * hx + oy * hy + oz * hz;
    f = ct * (1 - (*e_o)(oz)) * (1 - (*e_i)(-iz)) / kPi;
    pdf = q * t * -iz / kPi;
    if (oh > 0 && ih < 0) {
      const double F = fresnel(oh, n_o, n_i), den = n_i * ih + n_o * oh;
      f += std::abs(ih) * oh / (-iz * oz) * n_o * n_o * (1 - F) * d(hz) * g / (den * den);
      pdf += (1 - q) * (1 - F) * g1 * oh * d(hz) / oz * n_i * n_i * std::abs(ih) / (den * den);
    }
  }
};

TEST(PathBsdf, RoughDielectricSampleWeightsAreFCosOverPdfOfASecondImplementation) {
  // Every transmitted sample's weight equals f |cos| / pdf of the Walter implementation above
  // (times the sqrt(base) tint); every reflected sample is weighed by the caller with eval,
  // whose f and pdf must equal it too.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (float ior : {1.33f, 1.5f}) {
    for (float r : {0.1f, 0.3f, 0.6f, 1.0f}) {
      const Mat glass{F3(0.81f, 0.64f, 1.0f), 0.0f, r, ior, 1.0f};
      const auto t = glass.tables();
      int n_t = 0, n_r = 0;
      for (int k = 0; k < 2000; ++k) {
        const int side = k % 2;
        const F3 wo = random_dir(rng, true);
        const ShadingMaterial s = glass.at(wo.z, side == 0, t.get());
        const float n_o = side == 0 ? 1.0f : ior, n_i = side == 0 ? ior : 1.0f;
        const Walter w{s.alpha,           n_o,         n_i,         s.q_ms,
                       t->t[side],        t->cr[side], t->ct[side], &t->diel[side],
                       &t->diel[1 - side]};
        F3 wi, weight;
        const bool tr = s.sample_rough(wo, u(rng), u(rng), u(rng), wi, weight);
        if (tr ? wi.z >= 0.0f : wi.z <= 0.0f) continue;
        double f, pdf;
        w.eval(wo, wi, f, pdf);
        ASSERT_GT(pdf, 0.0);
        const float rel = r < 0.2f ? 1e-2f : 1e-3f;  // alpha = 0.01: float rounding at the peak
        if (tr) {
          ++n_t;
          const double expect = f * -wi.z / pdf;
          expect_rel(weight.x, static_cast<float>(expect * 0.9), rel, "T weight");
          expect_rel(weight.y, static_cast<float>(expect * 0.8), rel, "T weight");
          expect_rel(weight.z, static_cast<float>(expect), rel, "T weight");
        } else {
          ++n_r;
          F3 fe;
          float pe;
          s.eval(wo, wi, fe, pe);
          expect_rel(fe.y, static_cast<float>(f), rel, "R f");
          expect_rel(pe, static_cast<float>(pdf), rel, "R pdf");
        }
      }
      EXPECT_GT(n_t, 500);
      EXPECT_GT(n_r, 50);
    }
  }
}

}  // namespace
