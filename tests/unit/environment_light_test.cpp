// The environment light by itself: where a direction reads the map, the turn about +y, the
// sampling density (integrating to one, agreeing with pdf(), landing where the light is) and the
// irradiance of nine harmonics against cases whose answer is known in closed form.
#include "renderer/texture/environment_light.h"

#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <numbers>
#include <vector>

#include "renderer/trace/sampler.h"

namespace farm {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

// The direction of map point (u, v), written from the layout's definition: u = atan2(x, -z) / 2pi,
// v = acos(y) / pi.
glm::vec3 direction_at(double u, double v) {
  const double phi = 2.0 * std::numbers::pi * u, theta = std::numbers::pi * v;
  return glm::vec3(glm::dvec3(std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi)));
}

template <typename Value>
std::shared_ptr<const Texture> map_of(int width, int height, Value&& value) {
  std::vector<glm::vec4> texels;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) texels.push_back(glm::vec4(value(x, y), 1.0f));
  return std::make_shared<const Texture>(width, height, std::move(texels));
}

glm::vec3 distinct(int x, int y) { return {static_cast<float>(x) + 1.0f, static_cast<float>(y) + 1.0f, static_cast<float>(x * y)}; }

void expect_near(const glm::vec3& got, const glm::vec3& want, float tolerance, const std::string& what) {
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], tolerance) << what << ", channel " << c;
}

TEST(EnvironmentLight, AConstantOneIsTheSameRadianceEverywhereAndPiTimesItsIrradiance) {
  const EnvironmentLight light(glm::vec3(0.5f, 0.25f, 2.0f), 2.0f, 33.0f, nullptr);
  for (const glm::vec3& d : {glm::vec3(0, 1, 0), glm::vec3(0.3f, -0.2f, 0.9f), glm::vec3(-4, 0, 0)}) {
    EXPECT_EQ(light.radiance(d), glm::vec3(1.0f, 0.5f, 4.0f));
    expect_near(light.irradiance(glm::normalize(d)), kPi * glm::vec3(1.0f, 0.5f, 4.0f), 1e-5f, "irradiance");
    EXPECT_FLOAT_EQ(light.pdf(glm::normalize(d)), 1.0f / (4.0f * kPi));
  }
  const auto s = light.sample(0.3f, 0.8f);
  ASSERT_TRUE(s.has_value());
  EXPECT_NEAR(glm::length(s->direction), 1.0f, 1e-6f);
  EXPECT_EQ(s->radiance, glm::vec3(1.0f, 0.5f, 4.0f));
}

TEST(EnvironmentLight, DirectionsReadTheMapInMitsubasLatLongLayout) {
  constexpr int kW = 8, kH = 4;
  const EnvironmentLight light(glm::vec3(1.0f), 1.0f, 0.0f, map_of(kW, kH, distinct));
  // Each texel's centre reads that texel alone.
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      expect_near(light.radiance(direction_at((x + 0.5) / kW, (y + 0.5) / kH)), distinct(x, y), 1e-4f,
                  "texel " + std::to_string(x) + "," + std::to_string(y));
    }
  // -z is u = 0, the seam: half the last column, half the first; +x is u = 1/4, between columns
  // 1 and 2; the horizon, v = 1/2, between rows 1 and 2. Near a pole the first row alone counts
  // (clamped, not wrapped over the pole).
  expect_near(light.radiance(glm::vec3(0, 0, -1)),
              0.25f * (distinct(kW - 1, 1) + distinct(0, 1) + distinct(kW - 1, 2) + distinct(0, 2)), 1e-4f, "-z");
  expect_near(light.radiance(glm::vec3(3, 0, 0)), 0.25f * (distinct(1, 1) + distinct(2, 1) + distinct(1, 2) + distinct(2, 2)),
              1e-4f, "+x");
  expect_near(light.radiance(direction_at(0.1, 0.01)), 0.7f * distinct(0, 0) + 0.3f * distinct(1, 0), 1e-3f, "near +y");
  expect_near(light.radiance(direction_at(0.1, 0.99)), 0.7f * distinct(0, kH - 1) + 0.3f * distinct(1, kH - 1), 1e-3f,
              "near -y");
}

TEST(EnvironmentLight, ARotationTurnsTheMapAboutUpRightHanded) {
  const auto map = map_of(16, 8, distinct);
  const EnvironmentLight still(glm::vec3(1.0f), 1.0f, 0.0f, map), turned(glm::vec3(1.0f), 1.0f, 90.0f, map);
  // A right-handed quarter turn about +y takes (x, y, z) to (z, y, -x): what the unturned map
  // shows along d, the turned one shows along the turned d.
  for (const glm::vec3& d : {glm::vec3(0.2f, 0.5f, -0.8f), glm::vec3(0.9f, -0.1f, 0.3f), glm::vec3(-0.4f, 0.2f, 0.6f)}) {
    expect_near(turned.radiance(glm::vec3(d.z, d.y, -d.x)), still.radiance(d), 1e-4f, "turned");
  }
}

// A map with a bright patch, a dark band and an ordinary rest: what importance sampling is for.
glm::vec3 patchy(int x, int y) {
  if (y == 3) return glm::vec3(0.0f);
  if (x >= 20 && x < 23 && y >= 5 && y < 7) return glm::vec3(50.0f, 40.0f, 30.0f);
  return glm::vec3(0.1f + 0.01f * static_cast<float>(x), 0.2f, 0.05f * static_cast<float>(y % 5));
}

TEST(EnvironmentLight, SamplesAgreeWithPdfAndTheDensityIntegratesToOne) {
  const EnvironmentLight light(glm::vec3(1.0f), 1.5f, 40.0f, map_of(32, 16, patchy));
  for (std::uint32_t i = 0; i < 2000; ++i) {
    const SampleKey key{7, i, 0};
    const auto s = light.sample(sample_uniform(key, 0), sample_uniform(key, 1));
    ASSERT_TRUE(s.has_value());
    ASSERT_NEAR(glm::length(s->direction), 1.0f, 1e-5f);
    EXPECT_NEAR(light.pdf(s->direction), s->pdf, 2e-3f * s->pdf) << "sample " << i;
    expect_near(s->radiance, light.radiance(s->direction), 1e-3f * (1.0f + s->radiance.x), "sample radiance");
  }
  // The density over the whole sphere, by the midpoint rule in (phi, cos theta): one.
  double integral = 0.0;
  constexpr int kPhi = 1024, kCos = 1024;
  for (int j = 0; j < kCos; ++j) {
    const double cos_theta = 1.0 - 2.0 * (j + 0.5) / kCos, sin_theta = std::sqrt(1.0 - cos_theta * cos_theta);
    for (int i = 0; i < kPhi; ++i) {
      const double phi = 2.0 * std::numbers::pi * (i + 0.5) / kPhi;
      integral += light.pdf(glm::vec3(glm::dvec3(sin_theta * std::sin(phi), cos_theta, -sin_theta * std::cos(phi))));
    }
  }
  integral *= 4.0 * std::numbers::pi / (kPhi * kCos);
  EXPECT_NEAR(integral, 1.0, 0.01);
}

TEST(EnvironmentLight, SamplesLandOnlyWhereTheMapIsBright) {
  // One lit texel, (5, 2) of 16 x 8: every sample's direction lies within it.
  const EnvironmentLight light(glm::vec3(1.0f), 1.0f, 0.0f, map_of(16, 8, [](int x, int y) {
    return x == 5 && y == 2 ? glm::vec3(3.0f) : glm::vec3(0.0f);
  }));
  for (std::uint32_t i = 0; i < 500; ++i) {
    const SampleKey key{3, i, 0};
    const auto s = light.sample(sample_uniform(key, 0), sample_uniform(key, 1));
    ASSERT_TRUE(s.has_value());
    float u = std::atan2(s->direction.x, -s->direction.z) / (2.0f * kPi);
    if (u < 0.0f) u += 1.0f;
    const float v = std::acos(s->direction.y) / kPi;
    EXPECT_EQ(static_cast<int>(u * 16.0f), 5) << "sample " << i;
    EXPECT_EQ(static_cast<int>(v * 8.0f), 2) << "sample " << i;
  }
  const EnvironmentLight black(glm::vec3(1.0f), 1.0f, 0.0f, map_of(16, 8, [](int, int) { return glm::vec3(0.0f); }));
  EXPECT_FALSE(black.sample(0.5f, 0.5f).has_value());
  EXPECT_EQ(black.pdf(glm::vec3(0, 0, 1)), 0.0f);
  EXPECT_FALSE(EnvironmentLight(glm::vec3(0.0f), 1.0f, 0.0f, nullptr).sample(0.5f, 0.5f).has_value());
}

TEST(EnvironmentLight, NineHarmonicsGiveTheIrradianceOfAConstantMapAndOfASkyOverAHorizon) {
  // A map of one value: pi times it, whichever way the surface faces.
  const EnvironmentLight grey(glm::vec3(1.0f), 1.0f, 0.0f, map_of(64, 32, [](int, int) { return glm::vec3(0.3f, 0.6f, 0.9f); }));
  for (const glm::vec3& n : {glm::vec3(0, 1, 0), glm::vec3(0, -1, 0), glm::normalize(glm::vec3(1, 1, 1))}) {
    expect_near(grey.irradiance(n), kPi * glm::vec3(0.3f, 0.6f, 0.9f), 2e-3f, "constant map");
  }
  // White above the horizon, black below: E(n) = pi (1 + n.y) / 2, which the first two bands hold
  // exactly (band 2 of a step in cos theta is zero). The map's half-texel blur at the horizon is
  // all that differs.
  const EnvironmentLight sky(glm::vec3(1.0f), 1.0f, 25.0f, map_of(256, 128, [](int, int y) {
    return y < 64 ? glm::vec3(1.0f) : glm::vec3(0.0f);
  }));
  for (const glm::vec3& n : {glm::vec3(0, 1, 0), glm::vec3(0, -1, 0), glm::vec3(1, 0, 0), glm::normalize(glm::vec3(0.3f, 0.8f, -0.5f)),
                             glm::normalize(glm::vec3(-0.6f, -0.4f, 0.2f))}) {
    const float want = kPi * (1.0f + n.y) / 2.0f;
    expect_near(sky.irradiance(n), glm::vec3(want), 0.01f * kPi, "sky, n.y " + std::to_string(n.y));
  }
}

TEST(EnvironmentLight, NegativeOrNonFiniteValuesAreRefused) {
  EXPECT_THROW(EnvironmentLight(glm::vec3(-1.0f), 1.0f, 0.0f, nullptr), std::invalid_argument);
  EXPECT_THROW(EnvironmentLight(glm::vec3(1.0f), NAN, 0.0f, nullptr), std::invalid_argument);
  EXPECT_THROW(EnvironmentLight(glm::vec3(1.0f), 1.0f, INFINITY, nullptr), std::invalid_argument);
}

}  // namespace
}  // namespace farm
