// The slab test: flat boxes, rays parallel to faces (zero direction components, where
// 0 * inf = NaN can appear), rays through edges and from inside.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "renderer/geometry/aabb.h"

namespace farm {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

AABB box(glm::vec3 lo, glm::vec3 hi) {
  AABB b;
  b.grow(lo);
  b.grow(hi);
  return b;
}

// Returns whether the ray hits, and checks t_entry is never NaN on a hit.
bool hits(const AABB& b, glm::vec3 origin, glm::vec3 direction, float t_min = 0.0f,
          float t_max = kInf, float* entry = nullptr) {
  float t = -1.0f;
  const bool hit = b.intersect(origin, 1.0f / direction, t_min, t_max, t);
  if (hit) {
    EXPECT_FALSE(std::isnan(t)) << "t_entry is NaN";
  }
  if (entry) *entry = t;
  return hit;
}

const AABB kUnit = box(glm::vec3(0.0f), glm::vec3(1.0f));

TEST(Aabb, RayThroughTheMiddleEntersAtTheNearFace) {
  float t = 0.0f;
  EXPECT_TRUE(hits(kUnit, {-1.0f, 0.5f, 0.5f}, {1.0f, 0.0f, 0.0f}, 0.0f, kInf, &t));
  EXPECT_FLOAT_EQ(t, 1.0f);
  EXPECT_TRUE(hits(kUnit, {0.5f, 3.0f, 0.5f}, {0.0f, -2.0f, 0.0f}, 0.0f, kInf, &t));
  EXPECT_FLOAT_EQ(t, 1.0f);
}

TEST(Aabb, RayPointingAwayOrBeyondTMaxMisses) {
  EXPECT_FALSE(hits(kUnit, {-1.0f, 0.5f, 0.5f}, {-1.0f, 0.0f, 0.0f}));
  EXPECT_FALSE(hits(kUnit, {-1.0f, 0.5f, 0.5f}, {1.0f, 0.0f, 0.0f}, 0.0f, 0.5f));
  EXPECT_FALSE(hits(kUnit, {-1.0f, 0.5f, 0.5f}, {1.0f, 0.0f, 0.0f}, 2.5f, kInf));
}

TEST(Aabb, RayStartingInsideHitsWithEntryAtTMin) {
  float t = -1.0f;
  EXPECT_TRUE(hits(kUnit, {0.5f, 0.5f, 0.5f}, {0.3f, -0.7f, 0.2f}, 0.0f, kInf, &t));
  EXPECT_EQ(t, 0.0f);
  EXPECT_TRUE(hits(kUnit, {0.5f, 0.5f, 0.5f}, {0.0f, 0.0f, 1.0f}, 0.25f, kInf, &t));
  EXPECT_EQ(t, 0.25f);
}

TEST(Aabb, RayParallelToAFaceHitsInsideTheSlabAndMissesOutside) {
  // Direction has zero y and z: those slabs decide by the origin alone.
  EXPECT_TRUE(hits(kUnit, {-1.0f, 0.5f, 0.5f}, {1.0f, 0.0f, 0.0f}));
  EXPECT_FALSE(hits(kUnit, {-1.0f, 1.5f, 0.5f}, {1.0f, 0.0f, 0.0f}));
  EXPECT_FALSE(hits(kUnit, {-1.0f, -0.5f, 0.5f}, {1.0f, 0.0f, 0.0f}));
  EXPECT_FALSE(hits(kUnit, {-1.0f, 0.5f, -1e-6f}, {1.0f, 0.0f, 0.0f}));
  // Negative zero components (inv = -inf) behave the same.
  EXPECT_TRUE(hits(kUnit, {2.0f, 0.5f, 0.5f}, {-1.0f, -0.0f, -0.0f}));
  EXPECT_FALSE(hits(kUnit, {2.0f, 1.5f, 0.5f}, {-1.0f, -0.0f, -0.0f}));
}

TEST(Aabb, RayLyingInAFacePlaneCountsAsHittingTheClosedBox) {
  // origin.y == max.y and d.y == 0: (max.y - o.y) * inf is NaN, which must not decide.
  for (const float y : {0.0f, 1.0f}) {
    EXPECT_TRUE(hits(kUnit, {-1.0f, y, 0.5f}, {1.0f, 0.0f, 0.0f})) << y;
    EXPECT_TRUE(hits(kUnit, {-1.0f, y, 0.5f}, {1.0f, -0.0f, 0.0f})) << y;
    EXPECT_TRUE(hits(kUnit, {2.0f, y, 0.5f}, {-1.0f, 0.0f, -0.0f})) << y;
  }
  // In the face's plane but beside the box: still a miss, decided by the other slabs.
  EXPECT_FALSE(hits(kUnit, {-1.0f, 1.0f, 1.5f}, {1.0f, 0.0f, 0.0f}));
  EXPECT_FALSE(hits(kUnit, {-1.0f, 1.0f, 0.5f}, {-1.0f, 0.0f, 0.0f}));
}

TEST(Aabb, RayAlongAnEdgeHits) {
  EXPECT_TRUE(hits(kUnit, {-1.0f, 1.0f, 1.0f}, {1.0f, 0.0f, 0.0f}));
  EXPECT_TRUE(hits(kUnit, {0.0f, 0.0f, -3.0f}, {0.0f, 0.0f, 1.0f}));
}

TEST(Aabb, DiagonalRayThroughAnEdgeOrCornerHits) {
  // Through the edge x = 1, y = 1 at z = 0.5.
  EXPECT_TRUE(hits(kUnit, {2.0f, 2.0f, 0.5f}, {-1.0f, -1.0f, 0.0f}));
  // Through the corner (1, 1, 1).
  EXPECT_TRUE(hits(kUnit, {2.0f, 2.0f, 2.0f}, {-1.0f, -1.0f, -1.0f}));
  // Touching the edge x = 1, y = 1 from a grazing direction, and passing just beside it.
  EXPECT_TRUE(hits(kUnit, {2.0f, 0.0f, 0.5f}, {-1.0f, 1.0f, 0.0f}));
  EXPECT_FALSE(hits(kUnit, {2.0f, 0.01f, 0.5f}, {-1.0f, 1.0f, 0.0f}));
  EXPECT_FALSE(hits(kUnit, {2.0f, 2.0f, 1.5f}, {-1.0f, -1.0f, 0.0f}));
}

TEST(Aabb, FlatBoxIsHitByRaysCrossingItsPlane) {
  const AABB flat = box({0.0f, 2.0f, 0.0f}, {1.0f, 2.0f, 1.0f});  // zero thickness in y
  float t = 0.0f;
  EXPECT_TRUE(hits(flat, {0.5f, 0.0f, 0.5f}, {0.0f, 1.0f, 0.0f}, 0.0f, kInf, &t));
  EXPECT_FLOAT_EQ(t, 2.0f);
  EXPECT_TRUE(hits(flat, {0.0f, 0.0f, 0.0f}, {0.25f, 1.0f, 0.25f}));
  EXPECT_TRUE(hits(flat, {0.3f, 5.0f, 0.7f}, {0.1f, -1.0f, -0.2f}));
  EXPECT_FALSE(hits(flat, {0.5f, 0.0f, 0.5f}, {0.0f, -1.0f, 0.0f}));
  EXPECT_FALSE(hits(flat, {1.5f, 0.0f, 0.5f}, {0.0f, 1.0f, 0.0f}));
  // Stopping just short of the plane misses it.
  EXPECT_FALSE(hits(flat, {0.5f, 0.0f, 0.5f}, {0.0f, 1.0f, 0.0f}, 0.0f, 1.99f));
}

TEST(Aabb, FlatBoxIsHitByRaysLyingInItsPlane) {
  const AABB flat = box({0.0f, 2.0f, 0.0f}, {1.0f, 2.0f, 1.0f});
  EXPECT_TRUE(hits(flat, {-1.0f, 2.0f, 0.5f}, {1.0f, 0.0f, 0.0f}));
  EXPECT_TRUE(hits(flat, {-1.0f, 2.0f, -1.0f}, {1.0f, 0.0f, 1.0f}));
  EXPECT_FALSE(hits(flat, {-1.0f, 2.0f, 1.5f}, {1.0f, 0.0f, 0.0f}));
  EXPECT_FALSE(hits(flat, {-1.0f, 2.0001f, 0.5f}, {1.0f, 0.0f, 0.0f}));
  // A point-sized box on the ray's path, and one beside it.
  const AABB point = box({0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f});
  EXPECT_TRUE(hits(point, {0.5f, 0.5f, -2.0f}, {0.0f, 0.0f, 1.0f}));
  EXPECT_FALSE(hits(point, {0.5f, 0.6f, -2.0f}, {0.0f, 0.0f, 1.0f}));
}

TEST(Aabb, EmptyBoxIsNeverHit) {
  const AABB empty;
  EXPECT_FALSE(hits(empty, {0.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}));
  EXPECT_FALSE(hits(empty, {0.0f, 0.0f, 0.0f}, {-1.0f, 0.5f, 0.25f}));
  EXPECT_FALSE(hits(empty, {0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, -0.0f}));
}

// Random rays against random boxes, some flat, many with zero direction components: the slab
// result must match a direct test of the clipped segment in exact-ish double arithmetic.
TEST(Aabb, AgreesWithADoublePrecisionReferenceAndNeverReturnsNaN) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coord(-2.0f, 2.0f);
  std::uniform_int_distribution<int> pick(0, 3);
  int checked = 0, hit_count = 0;
  for (int i = 0; i < 20000; ++i) {
    glm::vec3 lo{coord(rng), coord(rng), coord(rng)}, hi = lo + glm::vec3(std::abs(coord(rng)),
                                                                           std::abs(coord(rng)),
                                                                           std::abs(coord(rng)));
    if (pick(rng) == 0) hi.y = lo.y;  // flat
    const AABB b = box(lo, hi);
    glm::vec3 o{coord(rng), coord(rng), coord(rng)}, d{coord(rng), coord(rng), coord(rng)};
    for (int a = 0; a < 3; ++a) {
      if (pick(rng) == 0) d[a] = 0.0f;
      if (pick(rng) == 0) o[a] = pick(rng) < 2 ? lo[a] : hi[a];  // on a face plane
    }
    if (d == glm::vec3(0.0f)) continue;
    // Reference in double; zero components decide by the origin alone (closed slabs).
    double t0 = 0.0, t1 = 1e30;
    bool inside_flat_slabs = true;
    for (int a = 0; a < 3; ++a) {
      if (d[a] == 0.0f) {
        inside_flat_slabs = inside_flat_slabs && o[a] >= lo[a] && o[a] <= hi[a];
        continue;
      }
      double ta = (double(lo[a]) - o[a]) / d[a], tb = (double(hi[a]) - o[a]) / d[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    // Grazing rays are decided by rounding: skip them.
    if (inside_flat_slabs && std::abs(t1 - t0) < 1e-5 * std::max(1.0, std::abs(t0))) continue;
    const bool ref = inside_flat_slabs && t0 <= t1;
    float t = 0.0f;
    const bool got = hits(b, o, d, 0.0f, kInf, &t);
    ASSERT_EQ(got, ref) << "ray " << i;
    ++checked;
    if (got) {
      ++hit_count;
      EXPECT_NEAR(t, t0, 1e-5 * std::max(1.0, t0)) << "ray " << i;
    }
  }
  EXPECT_GT(checked, 15000);
  EXPECT_GT(hit_count, 1000);
}

}  // namespace
}  // namespace farm
