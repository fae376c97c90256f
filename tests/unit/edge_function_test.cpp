#include "renderer/raster/edge_function.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace farm::raster {
namespace {

FixedPoint px(double x, double y) {
  return {static_cast<std::int64_t>(x * kSubpixelScale), static_cast<std::int64_t>(y * kSubpixelScale)};
}

bool covers(const FixedPoint& a, const FixedPoint& b, const FixedPoint& c, const FixedPoint& p) {
  FixedPoint v0 = a, v1 = b, v2 = c;
  if (edge_function(v0, v1, v2) < 0) std::swap(v1, v2);
  return edge_function(v1, v2, p) + fill_rule_bias(v1, v2) >= 0 &&
         edge_function(v2, v0, p) + fill_rule_bias(v2, v0) >= 0 &&
         edge_function(v0, v1, p) + fill_rule_bias(v0, v1) >= 0;
}

TEST(EdgeFunction, SnappingToTheGridRoundsAsLlroundForEveryFloat) {
  // Every 61st float of either sign, from 0 to the magnitude where llround itself takes over, and
  // the ties (an odd number of 512ths, which lands exactly on half a subpixel).
  int checked = 0;
  for (std::uint32_t bits = 0; bits < 0x5f000000u; bits += 61) {
    for (const float f : {std::bit_cast<float>(bits), -std::bit_cast<float>(bits)}) {
      ASSERT_EQ(to_fixed(f), std::llround(static_cast<double>(f) * kSubpixelScale)) << f;
      ++checked;
    }
  }
  for (int k = -4001; k <= 4001; k += 2) {
    const float tie = static_cast<float>(k) / 512.0f;
    ASSERT_EQ(to_fixed(tie), std::llround(static_cast<double>(tie) * kSubpixelScale)) << tie;
  }
  EXPECT_EQ(to_fixed(1.0f / 512.0f), 1);    // half a subpixel: away from zero
  EXPECT_EQ(to_fixed(-1.0f / 512.0f), -1);
  EXPECT_EQ(to_fixed(3.0f / 512.0f), 2);
  EXPECT_GT(checked, 50'000'000);
}

TEST(EdgeFunction, SignTellsWhichSideOfTheEdgeAPointIs) {
  const FixedPoint a = px(0, 0), b = px(10, 0);
  // y points down the image: below the edge a->b is the positive side.
  EXPECT_GT(edge_function(a, b, px(5, 3)), 0);
  EXPECT_LT(edge_function(a, b, px(5, -3)), 0);
  EXPECT_EQ(edge_function(a, b, px(7, 0)), 0);
  // Twice the triangle area.
  EXPECT_EQ(edge_function(a, b, px(0, 4)), 2 * (10 * 4 / 2) * kSubpixelScale * kSubpixelScale);
}

TEST(FillRule, TopAndLeftEdgesOwnTheirSamplesBottomAndRightDoNot) {
  // Axis-aligned square [2,6]x[2,6] as two triangles; samples exactly on its border.
  const FixedPoint a = px(2, 2), b = px(6, 2), c = px(6, 6), d = px(2, 6);
  auto in_square = [&](FixedPoint p) { return covers(a, b, c, p) || covers(a, c, d, p); };
  EXPECT_TRUE(in_square(px(4, 2)));   // top edge
  EXPECT_TRUE(in_square(px(2, 4)));   // left edge
  EXPECT_FALSE(in_square(px(4, 6)));  // bottom edge
  EXPECT_FALSE(in_square(px(6, 4)));  // right edge
  EXPECT_TRUE(in_square(px(2, 2)));   // top-left corner
  EXPECT_FALSE(in_square(px(6, 6)));  // bottom-right corner
  EXPECT_TRUE(in_square(px(4, 4)));   // on the shared diagonal: exactly one triangle
  EXPECT_NE(covers(a, b, c, px(4, 4)), covers(a, c, d, px(4, 4)));
}

TEST(FillRule, SharedEdgesOfAFanCoverEverySampleExactlyOnce) {
  // A fan of triangles around a centre, vertices on the sample grid so that many samples fall
  // exactly on shared edges and on the shared centre vertex.
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coord(-40, 40);
  for (int trial = 0; trial < 20; ++trial) {
    const FixedPoint centre = px(0.5, 0.5);
    // Convex ring: points on a square's boundary in angular order.
    std::vector<FixedPoint> ring = {px(-20.5, -20.5), px(coord(rng) * 0.5 / 2 + 0.5, -20.5),
                                    px(20.5, -20.5),  px(20.5, coord(rng) * 0.5 / 2 + 0.5),
                                    px(20.5, 20.5),   px(coord(rng) * 0.5 / 2 + 0.5, 20.5),
                                    px(-20.5, 20.5),  px(-20.5, coord(rng) * 0.5 / 2 + 0.5)};
    for (int y = -19; y <= 19; ++y) {
      for (int x = -19; x <= 19; ++x) {
        const FixedPoint sample = px(x + 0.5, y + 0.5);
        int hits = 0;
        for (std::size_t i = 0; i < ring.size(); ++i) {
          hits += covers(centre, ring[i], ring[(i + 1) % ring.size()], sample) ? 1 : 0;
        }
        ASSERT_EQ(hits, 1) << "sample (" << x << "," << y << ") trial " << trial;
      }
    }
  }
}

TEST(Barycentric, WeightsSumToOneAndReconstructThePoint) {
  const FixedPoint a = px(1, 1), b = px(11, 3), c = px(4, 9);
  const FixedPoint p = px(5.25, 4.5);
  const glm::dvec3 l = barycentric(a, b, c, p);
  EXPECT_NEAR(l.x + l.y + l.z, 1.0, 1e-12);
  EXPECT_NEAR(l.x * a.x + l.y * b.x + l.z * c.x, static_cast<double>(p.x), 1e-9);
  EXPECT_NEAR(l.x * a.y + l.y * b.y + l.z * c.y, static_cast<double>(p.y), 1e-9);
  // At a vertex the weight is 1 for it and 0 for the others.
  const glm::dvec3 at_b = barycentric(a, b, c, b);
  EXPECT_DOUBLE_EQ(at_b.y, 1.0);
  EXPECT_DOUBLE_EQ(at_b.x, 0.0);
  EXPECT_DOUBLE_EQ(at_b.z, 0.0);
}

}  // namespace
}  // namespace farm::raster
