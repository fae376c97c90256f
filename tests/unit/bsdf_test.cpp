#include "renderer/trace/bsdf.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <numbers>
#include <random>
#include <utility>

#include "renderer/trace/dielectric_coat.h"
#include "renderer/trace/fresnel.h"
#include "renderer/trace/ggx.h"

namespace farm {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

glm::vec3 direction_at(float theta_degrees) {
  const float t = theta_degrees * kPi / 180.0f;
  return {std::sin(t), 0.0f, std::cos(t)};
}

// Albedo (directional reflectance) by sampling the BSDF: the mean of the sample weights.
glm::vec3 albedo_by_bsdf_sampling(const Bsdf& bsdf, const glm::vec3& wo, int n, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  glm::vec3 sum(0.0f);
  for (int i = 0; i < n; ++i) {
    if (auto s = bsdf.sample(wo, u(rng), u(rng), u(rng))) sum += s->weight;
  }
  return sum / static_cast<float>(n);
}

// The same integral estimated independently, with directions uniform on the hemisphere.
glm::vec3 albedo_by_uniform_sampling(const Bsdf& bsdf, const glm::vec3& wo, int n, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  glm::vec3 sum(0.0f);
  for (int i = 0; i < n; ++i) {
    const float z = u(rng), phi = 2.0f * kPi * u(rng), r = std::sqrt(1.0f - z * z);
    const glm::vec3 wi{r * std::cos(phi), r * std::sin(phi), z};
    sum += bsdf.eval(wo, wi) * wi.z * (2.0f * kPi);
  }
  return sum / static_cast<float>(n);
}

TEST(Bsdf, WhiteLambertianReflectsAllEnergyAndItsSamplesMatchItsPdf) {
  Material white;
  white.diffuse = glm::vec3(1.0f);
  white.specular = glm::vec3(0.0f);
  const Bsdf bsdf(white);
  std::mt19937 rng(1);
  for (float theta : {0.0f, 45.0f, 85.0f}) {
    const glm::vec3 a = albedo_by_bsdf_sampling(bsdf, direction_at(theta), 20000, rng);
    EXPECT_NEAR(a.x, 1.0f, 1e-4f) << theta;  // every sample weighs exactly kd
    EXPECT_NEAR(albedo_by_uniform_sampling(bsdf, direction_at(theta), 200000, rng).x, 1.0f, 0.01f);
  }
}

TEST(Bsdf, ALambertianSampleWeighsItsColourAndItsDensityIsThePdfFunctions) {
  Material matte;
  matte.diffuse = glm::vec3(0.3f, 0.6f, 0.9f);
  matte.specular = glm::vec3(0.0f);
  const Bsdf bsdf(matte);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  double cos_sum = 0.0;
  constexpr int kSamples = 200000;
  for (int i = 0; i < kSamples; ++i) {
    const glm::vec3 wo = direction_at(80.0f * u(rng));
    const auto s = bsdf.sample(wo, u(rng), u(rng), u(rng));
    ASSERT_TRUE(s.has_value()) << i;
    ASSERT_GT(s->wi.z, 0.0f) << i;
    ASSERT_FALSE(s->specular);
    EXPECT_EQ(s->weight, matte.diffuse) << i;  // f cos / pdf, exactly kd
    EXPECT_EQ(s->pdf, bsdf.pdf(wo, s->wi)) << i;
    const glm::vec3 by_eval = bsdf.eval(wo, s->wi) * s->wi.z / s->pdf;
    EXPECT_NEAR(by_eval.y, matte.diffuse.y, 1e-6f) << i;
    cos_sum += s->wi.z;
  }
  // Cosine-weighted: the mean cosine is 2/3 (a uniform hemisphere's would be 1/2).
  EXPECT_NEAR(cos_sum / kSamples, 2.0 / 3.0, 0.003);
  // Seen from below, nothing is reflected.
  EXPECT_FALSE(bsdf.sample(glm::vec3(0.0f, 0.0f, -1.0f), 0.5f, 0.5f, 0.5f).has_value());
}

// The Lambertian case is answered inline (bsdf.h) and every other out of line: its answers must
// stay the layered BSDF's without a glossy layer, bit for bit (kd / pi, cos / pi, nothing below
// the surface on either side), or every path-traced image would move.
TEST(Bsdf, ALambertiansInlineAnswersAreTheLayeredFormulasBitForBit) {
  Material matte;
  matte.diffuse = glm::vec3(0.3f, 0.6f, 0.9f);
  matte.specular = glm::vec3(0.0f);
  const Bsdf bsdf(matte);
  const float inv_pi = 1.0f / kPi;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int i = 0; i < 10000; ++i) {
    const glm::vec3 wo = direction_at(89.0f * u(rng)), wi = direction_at(89.0f * u(rng));
    const glm::vec3 f = bsdf.eval(wo, wi);
    EXPECT_EQ(f, matte.diffuse * inv_pi) << i;
    EXPECT_EQ(bsdf.pdf(wo, wi), wi.z / kPi) << i;
    const glm::vec3 below{wi.x, wi.y, -wi.z};
    EXPECT_EQ(bsdf.eval(wo, below), glm::vec3(0.0f)) << i;
    EXPECT_EQ(bsdf.eval(below, wi), glm::vec3(0.0f)) << i;
    EXPECT_EQ(bsdf.pdf(wo, below), 0.0f) << i;
    EXPECT_EQ(bsdf.pdf(below, wi), 0.0f) << i;
  }
}

TEST(Bsdf, GlossySamplingAgreesWithIndependentIntegrationAndNeverCreatesEnergy) {
  std::mt19937 rng(2);
  for (float shininess : {5.0f, 50.0f, 500.0f}) {
    Material m;
    m.diffuse = {0.6f, 0.5f, 0.4f};
    m.specular = glm::vec3(0.4f);
    m.shininess = shininess;
    const Bsdf bsdf(m);
    for (float theta : {10.0f, 50.0f, 80.0f}) {
      const glm::vec3 wo = direction_at(theta);
      const glm::vec3 sampled = albedo_by_bsdf_sampling(bsdf, wo, 200000, rng);
      const glm::vec3 uniform = albedo_by_uniform_sampling(bsdf, wo, 400000, rng);
      // Two unbiased estimators of one integral: they agree within Monte Carlo noise (the uniform
      // one is noisy for sharp lobes, hence the tolerance).
      EXPECT_NEAR(sampled.x, uniform.x, 0.03f) << "p " << shininess << " theta " << theta;
      EXPECT_LE(sampled.x, 1.0f + 1e-3f);
      EXPECT_LE(sampled.x, 0.6f * 0.6f + 0.4f + 0.01f);  // diffuse layer + at most all of ks
    }
  }
}

TEST(Bsdf, GlossyLayerReflectsExactlyKsAtEveryAngleAndRoughness) {
  // Single-scattering GGX alone would lose up to a third of a white metal's energy when rough
  // and grazing; with the multiple-scattering term the layer's albedo is ks everywhere, so a
  // white base under any coat reflects everything.
  std::mt19937 rng(5);
  for (float shininess : {2.0f, 8.0f, 30.0f, 198.0f, 900.0f}) {
    Material metal;
    metal.diffuse = glm::vec3(0.0f);
    metal.specular = glm::vec3(1.0f);
    metal.shininess = shininess;
    Material coated;
    coated.diffuse = glm::vec3(1.0f);
    coated.specular = glm::vec3(0.4f);
    coated.shininess = shininess;
    for (float theta : {0.0f, 30.0f, 60.0f, 80.0f, 88.0f}) {
      const glm::vec3 wo = direction_at(theta);
      const float a = albedo_by_bsdf_sampling(Bsdf(metal), wo, 100000, rng).x;
      const float b = albedo_by_bsdf_sampling(Bsdf(coated), wo, 100000, rng).x;
      EXPECT_NEAR(a, 1.0f, 0.005f) << "metal, p " << shininess << " theta " << theta;
      EXPECT_NEAR(b, 1.0f, 0.005f) << "coated, p " << shininess << " theta " << theta;
    }
  }
}

TEST(Bsdf, PdfOfSampledDirectionsMatchesThePdfFunction) {
  Material m;
  m.diffuse = glm::vec3(0.5f);
  m.specular = glm::vec3(0.5f);
  m.shininess = 80.0f;
  const Bsdf bsdf(m);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const glm::vec3 wo = direction_at(35.0f);
  for (int i = 0; i < 1000; ++i) {
    const auto s = bsdf.sample(wo, u(rng), u(rng), u(rng));
    if (!s) continue;
    EXPECT_FALSE(s->specular);
    EXPECT_NEAR(s->pdf, bsdf.pdf(wo, s->wi), 1e-4f * s->pdf);
    const glm::vec3 expected = bsdf.eval(wo, s->wi) * s->wi.z / s->pdf;
    EXPECT_NEAR(s->weight.x, expected.x, 1e-4f);
  }
  // The density integrates to at most 1 over the sphere (samples below the surface are lost).
  double integral = 0.0;
  const int n = 400000;
  for (int i = 0; i < n; ++i) {
    const float z = 2.0f * u(rng) - 1.0f, phi = 2.0f * kPi * u(rng), r = std::sqrt(1.0f - z * z);
    integral += bsdf.pdf(wo, {r * std::cos(phi), r * std::sin(phi), z}) * 4.0 * kPi;
  }
  EXPECT_NEAR(integral / n, 1.0, 0.03);
}

TEST(Bsdf, MirrorReflectsAboutTheNormalWithItsReflectance) {
  Material m;
  m.shininess = 1000;
  m.specular = {0.9f, 0.8f, 0.7f};
  const Bsdf bsdf(m);
  EXPECT_TRUE(bsdf.is_specular());
  const auto s = bsdf.sample(glm::normalize(glm::vec3(0.3f, -0.2f, 0.9f)), 0.5f, 0.5f, 0.5f);
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->specular);
  EXPECT_NEAR(s->wi.x, -0.3f / glm::length(glm::vec3(0.3f, -0.2f, 0.9f)), 1e-6f);
  EXPECT_EQ(s->weight, glm::vec3(0.9f, 0.8f, 0.7f));
  Material white_mirror;
  white_mirror.shininess = 5000;
  EXPECT_EQ(Bsdf(white_mirror).sample({0, 0, 1}, 0.1f, 0.2f, 0.3f)->weight, glm::vec3(1.0f));
}

TEST(Bsdf, DielectricSplitsByFresnelFollowsSnellAndConservesEnergy) {
  Material glass;
  glass.transmission = 1.0f;
  glass.ior = 1.5f;
  const Bsdf bsdf(glass);
  EXPECT_TRUE(bsdf.is_specular());
  const glm::vec3 wo = direction_at(40.0f);
  const float reflectance = fresnel_dielectric(wo.z, 1.0f, 1.5f);
  const auto reflected = bsdf.sample(wo, reflectance * 0.5f, 0.0f, 0.0f);
  const auto refracted = bsdf.sample(wo, reflectance + 0.5f * (1.0f - reflectance), 0.0f, 0.0f);
  ASSERT_TRUE(reflected && refracted);
  EXPECT_NEAR(reflected->pdf, reflectance, 1e-6f);
  EXPECT_NEAR(refracted->pdf, 1.0f - reflectance, 1e-6f);
  EXPECT_GT(reflected->wi.z, 0.0f);
  EXPECT_LT(refracted->wi.z, 0.0f);
  // Snell: sin(theta_i) = 1.5 sin(theta_t).
  const float sin_t = std::sqrt(1.0f - refracted->wi.z * refracted->wi.z);
  EXPECT_NEAR(std::sin(40.0f * kPi / 180.0f), 1.5f * sin_t, 1e-5f);
  // Power: everything is either reflected or transmitted (the weight's (1/1.5)^2 is the radiance
  // compression, not a loss).
  EXPECT_NEAR(reflected->pdf * reflected->weight.x + refracted->pdf * refracted->weight.x * 1.5f * 1.5f, 1.0f, 1e-5f);
  // From inside beyond the critical angle: always reflected.
  const glm::vec3 inside{std::sin(0.8f), 0.0f, -std::cos(0.8f)};  // 45.8 degrees > 41.8
  for (float u : {0.0f, 0.5f, 0.999f}) {
    const auto s = bsdf.sample(inside, u, 0.0f, 0.0f);
    ASSERT_TRUE(s);
    EXPECT_LT(s->wi.z, 0.0f) << "total internal reflection stays inside";
  }
}

Material metal_roughness(glm::vec3 base, float metallic, float roughness) {
  Material m;
  set_metal_roughness(m, base, metallic, roughness);
  m.ior = 1.5f;
  return m;
}

// A nearly smooth coat: its transmittance is 1 - Fresnel, and its internal reflectance the
// diffuse reflectance of the inside of a glass surface, 0.596 at 1.5 (the cosine-weighted mean
// of the Fresnel reflectance from inside, total beyond 41.8 degrees, integrated in the test).
TEST(DielectricCoat, ASmoothCoatTransmitsWhatFresnelDoesNotReflect) {
  const DielectricCoat coat(1.5f, 1e-3f);
  for (float mu : {1.0f, 0.8f, 0.5f, 0.2f}) {
    EXPECT_NEAR(coat.transmittance(mu), 1.0f - fresnel_dielectric(mu, 1.0f, 1.5f), 0.003f) << mu;
  }
  double internal = 0.0;
  const int n = 100000;
  for (int k = 0; k < n; ++k) {
    const double mu = (k + 0.5) / n;
    internal += 2.0 * fresnel_dielectric(static_cast<float>(mu), 1.5f, 1.0f) * mu / n;
  }
  EXPECT_NEAR(coat.internal_reflectance(), internal, 0.003);
  EXPECT_NEAR(internal, 0.596, 0.001);
  // Between the grid's indices the tables are interpolated; eta 1 is no coat at all.
  EXPECT_NEAR(DielectricCoat(1.0f, 1e-3f).transmittance(0.7f), 1.0f, 0.003f);
  const float between = DielectricCoat(1.525f, 1e-3f).transmittance(1.0f);
  EXPECT_NEAR(between, 1.0f - fresnel_dielectric(1.0f, 1.0f, 1.525f), 0.003f);
}

// glTF's metal-roughness BSDF: its sampling and its eval/pdf agree (two independent estimates of
// the albedo), it never reflects more than arrives, and white bases reflect what they should: a
// white dielectric under a nearly smooth coat all of it, a white metal (whose Fresnel is 1) all
// but what single scattering loses, the tabulated GGX albedo.
TEST(Bsdf, MetalRoughnessSamplingAgreesWithIntegrationAndConservesEnergy) {
  std::mt19937 rng(7);
  for (float metallic : {0.0f, 0.5f, 1.0f})
    for (float roughness : {0.1f, 0.4f, 0.9f}) {
      const Bsdf bsdf(metal_roughness({0.9f, 0.6f, 0.3f}, metallic, roughness));
      EXPECT_FALSE(bsdf.is_specular()) << "roughness below 0.21 is not a mirror";
      for (float theta : {10.0f, 50.0f, 80.0f}) {
        const glm::vec3 wo = direction_at(theta);
        const glm::vec3 sampled = albedo_by_bsdf_sampling(bsdf, wo, 200000, rng);
        if (roughness >= 0.4f) {  // the uniform estimate is too noisy for sharp lobes
          const glm::vec3 uniform = albedo_by_uniform_sampling(bsdf, wo, 400000, rng);
          for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(sampled[c], uniform[c], 0.02f) << metallic << " " << roughness << " " << theta;
        }
        for (int c = 0; c < 3; ++c) EXPECT_LE(sampled[c], 1.0f + 2e-3f);
      }
    }
  for (float theta : {0.0f, 40.0f, 75.0f}) {
    const glm::vec3 wo = direction_at(theta);
    const float plastic = albedo_by_bsdf_sampling(Bsdf(metal_roughness(glm::vec3(1.0f), 0.0f, 0.05f)), wo, 200000, rng).x;
    EXPECT_NEAR(plastic, 1.0f, 0.01f) << theta;
    const float metal = albedo_by_bsdf_sampling(Bsdf(metal_roughness(glm::vec3(1.0f), 1.0f, 0.5f)), wo, 200000, rng).x;
    EXPECT_NEAR(metal, ggx::directional_albedo(0.25f, wo.z), 0.005f) << theta;
  }
  // A smooth gold metal reflects its base colour at normal incidence (Schlick's F0).
  const glm::vec3 gold{1.0f, 0.78f, 0.34f};
  const glm::vec3 head_on = albedo_by_bsdf_sampling(Bsdf(metal_roughness(gold, 1.0f, 0.05f)), direction_at(0.0f), 100000, rng);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(head_on[c], gold[c], 0.01f);
}

TEST(Bsdf, MetalRoughnessPdfOfSampledDirectionsMatchesThePdfFunction) {
  const Bsdf bsdf(metal_roughness({0.5f, 0.7f, 0.2f}, 0.3f, 0.45f));
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const glm::vec3 wo = direction_at(60.0f);
  for (int i = 0; i < 1000; ++i) {
    const auto s = bsdf.sample(wo, u(rng), u(rng), u(rng));
    if (!s) continue;
    EXPECT_NEAR(s->pdf, bsdf.pdf(wo, s->wi), 1e-4f * s->pdf);
    const glm::vec3 expected = bsdf.eval(wo, s->wi) * s->wi.z / s->pdf;
    EXPECT_NEAR(s->weight.y, expected.y, 1e-4f);
  }
}

// KHR_materials_transmission: a share t (1 - metallic) of the surface is smooth glass, tinted by
// the base colour's square root at each crossing; the rest, with its metallic renormalised, must
// make up exactly the metal's share and the opaque dielectric's (1 - metallic)(1 - t), so that
// the average over the parts is glTF's mix.
TEST(Bsdf, APartlyTransmissiveMaterialsPartsAddUpToGltfsMix) {
  const glm::vec3 base{0.95f, 0.64f, 0.54f};
  Material m = metal_roughness(base, 0.5f, 0.5f);
  m.transmission = 0.8f;
  const float glass_share = m.transmitted_share();
  EXPECT_FLOAT_EQ(glass_share, 0.4f);
  const Bsdf rest(m, false), metal(metal_roughness(base, 1.0f, 0.5f)), plastic(metal_roughness(base, 0.0f, 0.5f));
  EXPECT_FALSE(rest.is_specular());
  for (float theta_o : {10.0f, 60.0f})
    for (float theta_i : {-70.0f, 5.0f, 45.0f}) {
      const glm::vec3 wo = direction_at(theta_o), wi = direction_at(theta_i);
      const glm::vec3 mixed = (1.0f - glass_share) * rest.eval(wo, wi);
      const glm::vec3 gltf = 0.5f * metal.eval(wo, wi) + 0.5f * 0.2f * plastic.eval(wo, wi);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(mixed[c], gltf[c], 1e-5f * (1.0f + gltf[c])) << theta_o << " " << theta_i;
    }

  // Smooth glass (roughness 0): tinted refraction, untinted reflection.
  Material smooth = metal_roughness(base, 0.5f, 0.0f);
  smooth.transmission = 0.8f;
  const Bsdf glass(smooth, true);
  EXPECT_TRUE(glass.is_specular());
  EXPECT_FALSE(Bsdf(m, true).is_specular()) << "roughness 0.5: rough glass";
  const glm::vec3 wo = direction_at(30.0f);
  const auto refracted = glass.sample(wo, 0.999f, 0.0f, 0.0f);
  ASSERT_TRUE(refracted);
  EXPECT_LT(refracted->wi.z, 0.0f);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(refracted->weight[c], std::sqrt(base[c]) / (1.5f * 1.5f), 1e-6f);
  EXPECT_EQ(glass.sample(wo, 0.0f, 0.0f, 0.0f)->weight, glm::vec3(1.0f)) << "reflection is not tinted";

  // Phong glass (MTL's d, a job's transmission) is clear, and all of it glass at t = 1.
  Material phong;
  phong.transmission = 0.3f;
  phong.ior = 1.5f;
  EXPECT_FLOAT_EQ(phong.transmitted_share(), 0.3f);
  EXPECT_NEAR(Bsdf(phong, true).sample(wo, 0.999f, 0.0f, 0.0f)->weight.y, 1.0f / 2.25f, 1e-7f);
  phong.ior = 1.0f;
  EXPECT_EQ(phong.transmitted_share(), 0.0f) << "no ior, no glass";
}

// The same integral over the whole sphere of directions (glass sends light below the surface too).
glm::vec3 albedo_by_uniform_sphere_sampling(const Bsdf& bsdf, const glm::vec3& wo, int n, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  glm::vec3 sum(0.0f);
  for (int i = 0; i < n; ++i) {
    const float z = 2.0f * u(rng) - 1.0f, phi = 2.0f * kPi * u(rng), r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    const glm::vec3 wi{r * std::cos(phi), r * std::sin(phi), z};
    sum += bsdf.eval(wo, wi) * std::fabs(wi.z) * (4.0f * kPi);
  }
  return sum / static_cast<float>(n);
}

// glTF's rough glass (GGX microfacets, each a smooth boundary): from outside and from inside (where
// beyond 41.8 degrees most light is turned back), its samples' densities are pdf()'s and their
// weights eval()'s over it; sampling and plain integration of eval agree; it never makes energy
// (the refracted share counted in power, undoing the radiance compression) and loses what
// Mitsuba's loses; nearly smooth, it reflects what Fresnel says.
TEST(Bsdf, RoughGlassSamplesMatchItsPdfAndEvalAndTendToSmoothGlass) {
  Material m = metal_roughness(glm::vec3(1.0f), 0.0f, 0.5f);
  m.transmission = 1.0f;
  const Bsdf rough(m, true);
  ASSERT_FALSE(rough.is_specular());
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  // What Mitsuba 3.9.1's roughdielectric (GGX, alpha 0.25, ior 1.5) sends on from these angles,
  // its sample weights averaged over 200000 samples, in power: single scattering loses what
  // bounces between facets, most from inside at 60 degrees, where total internal reflection
  // keeps light among them.
  const std::pair<float, double> angles_and_mitsubas_power[] = {{30.0f, 0.9878}, {160.0f, 0.9215}, {120.0f, 0.8244}};
  for (const auto& [theta, mitsubas_power] : angles_and_mitsubas_power) {
    const glm::vec3 wo = direction_at(theta);
    const bool inside = wo.z < 0.0f;
    double power = 0.0;
    int taken = 0;
    const int n = 200000;
    for (int k = 0; k < n; ++k) {
      const auto s = rough.sample(wo, u(rng), u(rng), u(rng));
      if (!s) continue;
      ++taken;
      if (k < 2000) {
        EXPECT_NEAR(s->pdf, rough.pdf(wo, s->wi), 1e-3f * s->pdf);
        EXPECT_NEAR(s->weight.x, rough.eval(wo, s->wi).x * std::fabs(s->wi.z) / s->pdf, 1e-4f);
      }
      const bool crossed = (s->wi.z < 0.0f) != inside;
      const float compression = crossed ? (inside ? 1.0f / 2.25f : 2.25f) : 1.0f;
      power += s->weight.x * compression;
    }
    power /= n;
    std::printf("rough glass from %.0f degrees: power %.4f (Mitsuba %.4f)\n", theta, power, mitsubas_power);
    EXPECT_GT(taken, n * 3 / 4);
    EXPECT_LE(power, 1.0 + 5e-3) << theta;
    EXPECT_NEAR(power, mitsubas_power, 0.006) << theta;
    const float sampled = albedo_by_bsdf_sampling(rough, wo, 200000, rng).x;
    const float integrated = albedo_by_uniform_sphere_sampling(rough, wo, 800000, rng).x;
    EXPECT_NEAR(sampled, integrated, 0.02f * sampled) << wo.z;
  }
  Material nearly_smooth = metal_roughness(glm::vec3(1.0f), 0.0f, 0.04f);
  nearly_smooth.transmission = 1.0f;
  const Bsdf fine(nearly_smooth, true);
  for (float theta : {0.0f, 50.0f, 75.0f}) {
    const glm::vec3 wo = direction_at(theta);
    int reflected = 0;
    const int n = 100000;
    for (int k = 0; k < n; ++k) {
      const auto s = fine.sample(wo, u(rng), u(rng), u(rng));
      if (s && s->wi.z > 0.0f) ++reflected;
    }
    EXPECT_NEAR(static_cast<float>(reflected) / n, fresnel_dielectric(wo.z, 1.0f, 1.5f), 0.01f) << theta;
  }
}

}  // namespace
}  // namespace farm
