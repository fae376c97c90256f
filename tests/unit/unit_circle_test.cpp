// unit_circle_point (renderer/util/unit_circle.h) against double-precision cos and sin: the
// samplers' angles come from it, so its error bounds every sampled direction's.
#include "renderer/util/unit_circle.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace farm {
namespace {

TEST(UnitCircle, EveryFractionOfATurnIsWithinTwoUlpOfTheTrueCosineAndSine) {
  constexpr int kSteps = 1 << 22;  // every 2^-22 of a turn, and the floats between at the start
  double worst_cos = 0.0, worst_sin = 0.0, worst_norm = 0.0;
  for (int i = 0; i < kSteps; ++i) {
    const float u = static_cast<float>(i) / static_cast<float>(kSteps);
    const CosSin p = unit_circle_point(u);
    const double angle = 2.0 * std::numbers::pi * static_cast<double>(u);
    worst_cos = std::max(worst_cos, std::fabs(p.cos - std::cos(angle)));
    worst_sin = std::max(worst_sin, std::fabs(p.sin - std::sin(angle)));
    worst_norm = std::max(worst_norm, std::fabs(static_cast<double>(p.cos) * p.cos +
                                                static_cast<double>(p.sin) * p.sin - 1.0));
  }
  // Two float ulps at 1 are 2.4e-7; the fitted polynomials stay under 9e-8 with their rounding.
  EXPECT_LT(worst_cos, 1.2e-7);
  EXPECT_LT(worst_sin, 1.2e-7);
  EXPECT_LT(worst_norm, 3e-7);
}

TEST(UnitCircle, QuarterTurnsAreExactAndTheQuadrantsHaveTheirSigns) {
  const struct {
    float u, cos, sin;
  } exact[] = {{0.0f, 1.0f, 0.0f}, {0.25f, 0.0f, 1.0f}, {0.5f, -1.0f, 0.0f}, {0.75f, 0.0f, -1.0f}, {1.0f, 1.0f, 0.0f}};
  for (const auto& e : exact) {
    const CosSin p = unit_circle_point(e.u);
    EXPECT_EQ(p.cos, e.cos) << e.u;
    EXPECT_EQ(p.sin, e.sin) << e.u;
  }
  for (int k = 0; k < 4; ++k) {  // the middle of each quadrant: cos and sin both 1/sqrt(2) in size
    const CosSin p = unit_circle_point(0.125f + 0.25f * static_cast<float>(k));
    EXPECT_NEAR(p.cos, (k == 0 || k == 3) ? 0.70710678f : -0.70710678f, 1e-7f) << k;
    EXPECT_NEAR(p.sin, k < 2 ? 0.70710678f : -0.70710678f, 1e-7f) << k;
  }
  // Just below a full turn: the fourth quadrant, a hair short of (1, 0).
  const CosSin last = unit_circle_point(std::nextafter(1.0f, 0.0f));
  EXPECT_EQ(last.cos, 1.0f);
  EXPECT_LT(last.sin, 0.0f);
  EXPECT_GT(last.sin, -1e-6f);
}

}  // namespace
}  // namespace farm
