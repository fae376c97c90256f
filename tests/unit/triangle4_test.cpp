// Triangle4 (renderer/geometry/triangle4.h) against intersect_triangle, lane by lane and bit for
// bit: the BVH's leaves are tested four at a time, and no hit may move by an ulp for it.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

#include "renderer/geometry/triangle4.h"
#include "renderer/geometry/triangle_intersect.h"

namespace farm {
namespace {

std::uint32_t bits(float f) { return std::bit_cast<std::uint32_t>(f); }

constexpr std::uint32_t kLaneIds[4] = {0, 1, 2, 3};  // the ids in lane order: a tie goes to the first

struct Corners {
  glm::vec3 a, b, c;
};

// Random triangles with every case the scalar test branches on: hits, misses on each side,
// edges and corners shared exactly, zero area, a plane the ray lies in, tiny and huge sizes.
Corners random_triangle(std::mt19937& rng, const Ray& ray) {
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::uniform_int_distribution<int> kind(0, 5);
  const glm::vec3 centre = ray.origin + ray.direction * (1.0f + 4.0f * std::abs(unit(rng)));
  auto near = [&](float size) { return centre + size * glm::vec3(unit(rng), unit(rng), unit(rng)); };
  switch (kind(rng)) {
    case 0: {  // a corner exactly on the ray
      const glm::vec3 a = centre;
      return {a, near(1.0f), near(1.0f)};
    }
    case 1: {  // zero area: all three on a line
      const glm::vec3 a = near(1.0f), d = near(1.0f) - a;
      return {a, a + d, a + 2.0f * d};
    }
    case 2: {  // in a plane holding the ray
      const glm::vec3 side = glm::vec3(unit(rng), unit(rng), unit(rng));
      return {ray.origin + side, ray.origin + side + 3.0f * ray.direction, ray.origin + ray.direction};
    }
    case 3:
      return {near(1e-4f), near(1e-4f), near(1e-4f)};
    case 4:
      return {near(1e4f), near(1e4f), near(1e4f)};
    default:
      return {near(1.0f), near(1.0f), near(1.0f)};
  }
}

TEST(Triangle4, EveryLaneGivesTheBitsOfTheScalarTestAndTheNearestLaneIsTheScalarLoopsPick) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  int hits = 0, lanes_compared = 0, ties = 0;
  for (int trial = 0; trial < 200000; ++trial) {
    Ray ray;
    ray.origin = glm::vec3(unit(rng), unit(rng), unit(rng));
    ray.direction = glm::vec3(unit(rng), unit(rng), unit(rng));
    if (trial % 7 == 0) ray.direction.x = 0.0f;  // an axis-parallel plane of directions
    if (trial % 11 == 0) ray.t_min = 0.5f;
    if (trial % 13 == 0) ray.t_max = 2.0f;
    const int count = 1 + trial % 4;  // lanes past it stay empty
    std::array<Corners, 4> tris{};
    Triangle4 packet;
    for (int lane = 0; lane < count; ++lane) {
      tris[static_cast<std::size_t>(lane)] = random_triangle(rng, ray);
      if (trial % 17 == 0 && lane == 1) tris[1] = tris[0];  // the same triangle twice: a tie
      const Corners& c = tris[static_cast<std::size_t>(lane)];
      packet.set(lane, c.a, c.b, c.c);
    }
    __m128 t4, u4, v4;
    const int mask = intersect_triangle4(Triangle4Ray(ray), packet, ray.t_max, t4, u4, v4);
    alignas(16) float t[4], u[4], v[4];
    _mm_store_ps(t, t4);
    _mm_store_ps(u, u4);
    _mm_store_ps(v, v4);
    // The scalar loop a leaf used to run: keep a hit only when strictly nearer.
    Ray scalar = ray;
    int picked = -1;
    for (int lane = 0; lane < 4; ++lane) {
      const auto k = static_cast<std::size_t>(lane);
      const std::optional<TriangleHit> one = lane < count ? intersect_triangle(ray, tris[k].a, tris[k].b, tris[k].c)
                                                          : std::nullopt;
      ASSERT_EQ(one.has_value(), ((mask >> lane) & 1) != 0) << "trial " << trial << " lane " << lane;
      ++lanes_compared;
      if (!one) continue;
      ++hits;
      EXPECT_EQ(bits(one->t), bits(t[k])) << "trial " << trial << " lane " << lane;
      EXPECT_EQ(bits(one->u), bits(u[k])) << "trial " << trial << " lane " << lane;
      EXPECT_EQ(bits(one->v), bits(v[k])) << "trial " << trial << " lane " << lane;
      if (one->t < scalar.t_max) {
        scalar.t_max = one->t;
        picked = lane;
      } else if (one->t == scalar.t_max) {
        ++ties;
      }
    }
    if (mask != 0) {
      EXPECT_EQ(nearest_lane(mask, t4, kLaneIds), picked) << "trial " << trial;
    }
  }
  // The cases were all met: hits, misses and ties.
  EXPECT_GT(hits, 10000);
  EXPECT_LT(hits, lanes_compared / 2);
  EXPECT_GT(ties, 100);
}

}  // namespace
}  // namespace farm
