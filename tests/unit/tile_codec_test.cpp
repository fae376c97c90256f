#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "renderer/util/input_error.h"
#include "server/common/tile_codec.h"

namespace farm {
namespace {

TEST(TileCodec, RoundTripIsBitExactWithEveryAov) {
  AovSet aovs;
  aovs.depth = aovs.normal = aovs.albedo = aovs.bvh_cost = aovs.variance = true;
  TileBuffer t(Rect{3, 5, 8, 9}, aovs);
  float v = 0.0f;
  for (int y = 5; y < 9; ++y) {
    for (int x = 3; x < 8; ++x, v += 1.0f) {
      t.rgba(x, y) = {v, -v, v * 0.1f, 1.0f};
      t.depth(x, y) = x == 3 ? TileBuffer::kNoDepth : v;
      t.normal(x, y) = {0.0f, -0.0f, 1.0f};
      t.albedo(x, y) = {v, v, std::numeric_limits<float>::denorm_min()};
      t.bvh_cost(x, y) = v * 3.0f;
      // Variances are tiny: subnormals and values far below half's range must survive.
      t.variance(x, y) = {v * 1e-9f, std::numeric_limits<float>::denorm_min() * v, 1.0f / (v + 3.0f)};
    }
  }
  v1::TileData d;
  encode_tile(t, d);
  EXPECT_EQ(d.width(), 5);
  EXPECT_EQ(d.height(), 4);
  EXPECT_EQ(d.rgba().size(), 5u * 4u * 16u);
  EXPECT_EQ(d.normal().size(), 5u * 4u * 12u);
  EXPECT_EQ(d.variance().size(), 5u * 4u * 12u);
  const TileBuffer back = decode_tile(d);
  ASSERT_EQ(back.rect(), t.rect());
  for (int y = 5; y < 9; ++y) {
    for (int x = 3; x < 8; ++x) {
      EXPECT_EQ(std::memcmp(&back.rgba(x, y), &t.rgba(x, y), 16), 0);
      EXPECT_EQ(std::memcmp(&back.normal(x, y), &t.normal(x, y), 12), 0);
      EXPECT_EQ(std::memcmp(&back.albedo(x, y), &t.albedo(x, y), 12), 0);
      EXPECT_EQ(back.depth(x, y), t.depth(x, y));
      EXPECT_EQ(back.bvh_cost(x, y), t.bvh_cost(x, y));
      EXPECT_EQ(std::memcmp(&back.variance(x, y), &t.variance(x, y), 12), 0);
    }
  }
  // Row-major from (x0, y0): the second float of the rgba plane is pixel (3, 5)'s green.
  float g;
  std::memcpy(&g, d.rgba().data() + 4, 4);
  EXPECT_EQ(g, t.rgba(3, 5).y);
}

TEST(TileCodec, AbsentAovsStayAbsentAndShortPlanesAreRejected) {
  TileBuffer t(Rect{0, 0, 2, 2}, AovSet{});
  v1::TileData d;
  encode_tile(t, d);
  EXPECT_TRUE(d.depth().empty());
  EXPECT_TRUE(d.variance().empty());
  EXPECT_FALSE(decode_tile(d).aovs().depth);
  EXPECT_FALSE(decode_tile(d).aovs().variance);
  d.mutable_rgba()->pop_back();
  EXPECT_THROW(decode_tile(d), InputError);
}

}  // namespace
}  // namespace farm
