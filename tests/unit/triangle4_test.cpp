// Triangle4 (renderer/geometry/triangle4.h) against intersect_triangle, lane by lane and bit for
// bit: the BVH's leaves are tested four at a time, and no hit may move by an ulp for it.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

#include "renderer/geometry/traversal_isa.h"
#include "renderer/geometry/triangle4.h"
#include "renderer/geometry/triangle4_packet.h"
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

// A leaf tested a ray per lane gives each ray of the packet the hit its own Triangle4 test and
// nearest_lane give it, bit for bit: rays near one another and apart, each its own t range, ties
// between copies of a triangle (to the lower id, ids above 2^31 included), lanes left out.
TEST(Triangle4, APacketsRaysEachGetTheHitTheirOwnTestGivesBitForBit) {
  if (!cpu_has_avx2()) GTEST_SKIP() << "the packet test needs AVX2";
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::uniform_int_distribution<unsigned> subset(1, 255);
  int hits = 0, ties = 0;
  for (int trial = 0; trial < 40000; ++trial) {
    Ray base;
    base.origin = glm::vec3(unit(rng), unit(rng), unit(rng));
    base.direction = glm::vec3(unit(rng), unit(rng), unit(rng));
    const int count = 1 + trial % 4;
    std::array<Corners, 4> tris{};
    Triangle4 leaf;
    for (int k = 0; k < count; ++k) {
      tris[static_cast<std::size_t>(k)] = random_triangle(rng, base);
      if (trial % 5 == 0 && k == 1) tris[1] = tris[0];  // a tie: the lower id must win
      const Corners& c = tris[static_cast<std::size_t>(k)];
      leaf.set(k, c.a, c.b, c.c);
    }
    const std::uint32_t ids[4] = {trial % 2 ? 0x80000003u : 9u, trial % 3 ? 4u : 0x80000001u, 2u, 7u};
    std::array<Ray, 8> rays;
    std::array<float, 8> t_max;
    Triangle4PacketRays packet;
    for (int i = 0; i < 8; ++i) {
      Ray& ray = rays[static_cast<std::size_t>(i)];
      ray = base;
      if (i % 4 != 0) {  // a neighbour of the base ray, or (1 in 4 trials) a stranger
        const float spread = trial % 4 == 0 ? 1.0f : 1e-3f;
        ray.origin += spread * glm::vec3(unit(rng), unit(rng), unit(rng));
        ray.direction += spread * glm::vec3(unit(rng), unit(rng), unit(rng));
      }
      if (i == 3) ray.t_min = 0.5f;
      t_max[static_cast<std::size_t>(i)] = i == 5 ? 2.0f : ray.t_max;
      packet.set(i, ray);
    }
    const unsigned lanes = trial % 3 == 0 ? 0xFFu : subset(rng);
    Triangle4PacketHits got;
    const unsigned met = intersect_triangle4_packet(packet, leaf, count, ids, t_max.data(), lanes, got);
    ASSERT_EQ(met & ~lanes, 0u) << "trial " << trial;
    for (int i = 0; i < 8; ++i) {
      if (!(lanes >> i & 1u)) continue;
      const auto k = static_cast<std::size_t>(i);
      __m128 t4, u4, v4;
      const int mask = intersect_triangle4(Triangle4Ray(rays[k]), leaf, t_max[k], t4, u4, v4);
      ASSERT_EQ(mask != 0, (met >> i & 1u) != 0) << "trial " << trial << " ray " << i;
      if (mask == 0) continue;
      ++hits;
      if (std::popcount(static_cast<unsigned>(mask)) > 1) ++ties;
      const int lane = nearest_lane(mask, t4, ids);
      alignas(16) float t[4], u[4], v[4];
      _mm_store_ps(t, t4);
      _mm_store_ps(u, u4);
      _mm_store_ps(v, v4);
      const auto l = static_cast<std::size_t>(lane);
      EXPECT_EQ(bits(got.t[k]), bits(t[l])) << "trial " << trial << " ray " << i;
      EXPECT_EQ(bits(got.u[k]), bits(u[l])) << "trial " << trial << " ray " << i;
      EXPECT_EQ(bits(got.v[k]), bits(v[l])) << "trial " << trial << " ray " << i;
      EXPECT_EQ(got.id[k], ids[l]) << "trial " << trial << " ray " << i;
    }
  }
  EXPECT_GT(hits, 10000);
  EXPECT_GT(ties, 1000);  // rays meeting more than one of a leaf's triangles: the nearest picked
}

// A whole packet's rays loaded at once (an 8x8 transpose for a full packet) are, byte for byte,
// what set() writes lane by lane: every lane of a full packet, and for a partial one the lanes
// asked, the others left zero. Rays with t_min below, at and above the test's epsilon, NaN and
// infinite components included.
TEST(Triangle4, APacketLoadedWholeHoldsWhatSetWritesLaneByLane) {
  if (!cpu_has_avx2()) GTEST_SKIP() << "the packet test needs AVX2";
  std::mt19937 rng(31);
  std::uniform_real_distribution<float> unit(-4.0f, 4.0f);
  const float specials[] = {0.0f, -0.0f, 1e-6f, 2e-6f, 1e-7f, std::numeric_limits<float>::infinity(),
                            std::numeric_limits<float>::quiet_NaN()};
  const auto pick = [&](int k) { return k % 5 == 0 ? specials[static_cast<std::size_t>(k / 5) % 7] : unit(rng); };
  for (int trial = 0; trial < 2000; ++trial) {
    std::array<Ray, 8> rays;
    for (std::size_t i = 0; i < 8; ++i) {
      const int k = trial * 8 + static_cast<int>(i);
      rays[i].origin = glm::vec3(unit(rng), pick(k), unit(rng));
      rays[i].direction = glm::vec3(pick(k + 1), unit(rng), pick(k + 3));
      rays[i].t_min = k % 3 == 0 ? pick(k) : std::abs(unit(rng)) * 1e-5f;
      rays[i].t_max = k % 4 == 0 ? std::numeric_limits<float>::infinity() : std::abs(unit(rng));
    }
    const unsigned lanes = trial % 2 ? 0xFFu : static_cast<unsigned>(trial * 37 % 255 + 1);
    const Triangle4PacketRays whole(rays.data(), lanes);
    Triangle4PacketRays by_lane;
    for (int i = 0; i < 8; ++i) {
      if (lanes >> i & 1u) by_lane.set(i, rays[static_cast<std::size_t>(i)]);
    }
    const auto* got = reinterpret_cast<const unsigned char*>(&whole);
    const auto* want = reinterpret_cast<const unsigned char*>(&by_lane);
    for (std::size_t b = 0; b < sizeof(Triangle4PacketRays); ++b) {
      ASSERT_EQ(got[b], want[b]) << "trial " << trial << ", lanes " << lanes << ", byte " << b << " (row "
                                 << b / 32 << ", lane " << b % 32 / 4 << ")";
    }
  }
}

}  // namespace
}  // namespace farm
