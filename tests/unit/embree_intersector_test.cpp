// Embree behind SceneIntersector: every hit checked against a brute-force test of every
// triangle transformed to world space (in double precision), on instanced scenes whose
// transforms rotate, scale non-uniformly and mirror.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat4x4.hpp>
#include <limits>
#include <random>
#include <thread>
#include <vector>

#include "renderer/accel/embree_intersector.h"
#include "renderer/accel/prepared_scene.h"
#include "renderer/accel/scene_intersector.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

glm::mat4 trs(glm::vec3 translate, float degrees, glm::vec3 axis, glm::vec3 scale) {
  glm::mat4 m = glm::translate(glm::mat4(1.0f), translate);
  m = glm::rotate(m, glm::radians(degrees), glm::normalize(axis));
  return glm::scale(m, scale);
}

// Five objects over three models: two share the sphere (one of them mirrored), an empty model
// sits in the middle so object numbering has a gap in Embree's instances, and the floor grid is
// mirrored too.
Scene instanced_scene() {
  Scene scene;
  scene.objects.push_back(test::object_of(test::make_box({-0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, 0.5f}),
                                          trs({-2, 0, 0}, 30, {1, 1, 0}, {1, 2, 0.5f})));
  SceneObject sphere = test::object_of(test::make_sphere(12, 16), trs({2, 0.5f, 0}, 0, {0, 1, 0},
                                                                      {0.5f, 1.5f, 1}));
  scene.objects.push_back(sphere);
  Model empty;
  scene.objects.push_back(test::object_of(empty));
  sphere.model_to_world = trs({0, 0, -2}, 70, {0, 0, 1}, {-1, 0.7f, 1.3f});
  scene.objects.push_back(sphere);
  scene.objects.push_back(test::object_of(test::make_grid(6), trs({0, -2, 0}, -90, {1, 0, 0},
                                                                  {-4, 3, 1})));
  return scene;
}

struct WorldTriangle {
  glm::dvec3 a, b, c;
};

WorldTriangle world_triangle(const PreparedScene& scene, std::uint32_t object, std::uint32_t t) {
  const PreparedObject& o = scene.objects()[object];
  const glm::uvec3 i = o.triangles->triangles[t];
  const glm::dmat4 m(o.model_to_world);
  auto world = [&](std::uint32_t v) { return glm::dvec3(m * glm::dvec4(glm::dvec3(o.triangles->positions[v]), 1.0)); };
  return {world(i.x), world(i.y), world(i.z)};
}

struct BruteHit {
  bool hit = false;
  double t = 0.0, u = 0.0, v = 0.0;
  std::uint32_t object = 0, triangle = 0;
};

// Möller-Trumbore against every world-space triangle, in double.
BruteHit brute_force(const PreparedScene& scene, const Ray& ray) {
  const glm::dvec3 o(ray.origin), d(ray.direction);
  BruteHit best;
  best.t = ray.t_max;
  for (std::uint32_t object = 0; object < scene.objects().size(); ++object) {
    for (std::uint32_t t = 0; t < scene.objects()[object].triangles->size(); ++t) {
      const WorldTriangle w = world_triangle(scene, object, t);
      const glm::dvec3 e1 = w.b - w.a, e2 = w.c - w.a, p = glm::cross(d, e2);
      const double det = glm::dot(e1, p);
      if (std::fabs(det) < 1e-14 * glm::length(e1) * glm::length(e2) * glm::length(d)) continue;
      const glm::dvec3 s = o - w.a, q = glm::cross(s, e1);
      const double u = glm::dot(s, p) / det, v = glm::dot(d, q) / det, hit_t = glm::dot(e2, q) / det;
      if (u < 0 || v < 0 || u + v > 1 || !(hit_t > ray.t_min && hit_t < best.t)) continue;
      best = {true, hit_t, u, v, object, t};
    }
  }
  return best;
}

// Random rays from around the scene plus rays aimed at points inside random triangles, with
// directions of random length (t is in units of the direction, not of distance).
std::vector<Ray> test_rays(const PreparedScene& scene, int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), box(-5.0f, 5.0f), length(0.2f, 5.0f);
  std::vector<Ray> rays;
  for (int i = 0; i < count; ++i) {
    Ray ray;
    ray.origin = {box(rng), box(rng), box(rng)};
    if (i % 2 == 0) {
      const float z = 1.0f - 2.0f * unit(rng), phi = 6.2831853f * unit(rng);
      const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
      ray.direction = length(rng) * glm::vec3(r * std::cos(phi), r * std::sin(phi), z);
    } else {
      std::uint32_t object;
      do {
        object = static_cast<std::uint32_t>(rng() % scene.objects().size());
      } while (scene.objects()[object].triangles->size() == 0);
      const auto t = static_cast<std::uint32_t>(rng() % scene.objects()[object].triangles->size());
      const WorldTriangle w = world_triangle(scene, object, t);
      float u = 0.02f + 0.96f * unit(rng), v = 0.02f + 0.96f * unit(rng);
      if (u + v > 0.98f) u = 0.98f - u, v = 0.98f - v;
      u = std::max(u, 0.01f), v = std::max(v, 0.01f);
      const glm::vec3 target(w.a + double(u) * (w.b - w.a) + double(v) * (w.c - w.a));
      ray.direction = (target - ray.origin) * length(rng);
    }
    rays.push_back(ray);
  }
  return rays;
}

// Compares one query with the brute force; returns an empty string when they agree.
std::string compare(const PreparedScene& scene, const SceneIntersector& embree, const Ray& ray) {
  const BruteHit expected = brute_force(scene, ray);
  SurfaceHit hit;
  const bool got = embree.closest_hit(ray, hit);
  const std::string where =
      fmt::format("ray ({}, {}, {}) dir ({}, {}, {}) in ({}, {})", ray.origin.x, ray.origin.y,
                  ray.origin.z, ray.direction.x, ray.direction.y, ray.direction.z, ray.t_min, ray.t_max);
  if (got != expected.hit) return "hit/miss differs for " + where;
  if (embree.occluded(ray) != expected.hit) return "occluded differs for " + where;
  if (!got) return {};
  const double rel = std::fabs(hit.t - expected.t) / expected.t;
  if (hit.object != expected.object || hit.triangle != expected.triangle) {
    if (rel > 1e-5) return "different triangle for " + where;  // else a tie on an edge
  } else if (rel > 1e-4) {
    return fmt::format("t {} vs {} for {}", hit.t, expected.t, where);
  } else {
    // u, v name the hit point on the triangle; compare points, as grazing rays make the weights
    // ill-conditioned. Both points lie on the ray, as far apart as the 1e-4 in t allows.
    const WorldTriangle w = world_triangle(scene, hit.object, hit.triangle);
    auto at = [&](double u, double v) { return (1 - u - v) * w.a + u * w.b + v * w.c; };
    const double gap = glm::length(at(hit.u, hit.v) - at(expected.u, expected.v));
    const double size = std::max({glm::length(w.b - w.a), glm::length(w.c - w.a), glm::length(w.c - w.b)});
    if (gap > 1e-4 * (size + expected.t * glm::length(glm::dvec3(ray.direction)))) {
      return fmt::format("barycentrics ({}, {}) vs ({}, {}), {} apart on a triangle {} wide, at t {} for {}",
                         hit.u, hit.v, expected.u, expected.v, gap, size, hit.t, where);
    }
  }
  if (!(hit.t > ray.t_min && hit.t < ray.t_max)) return "t outside (t_min, t_max) for " + where;
  if (std::fabs(glm::length(hit.geometric_normal) - 1.0f) > 1e-4f ||
      std::fabs(glm::length(hit.shading_normal) - 1.0f) > 1e-4f) {
    return "normal not unit for " + where;
  }
  const WorldTriangle w = world_triangle(scene, hit.object, hit.triangle);
  const glm::dvec3 plane = glm::normalize(glm::cross(w.b - w.a, w.c - w.a));
  if (std::fabs(glm::dot(plane, glm::dvec3(hit.geometric_normal))) < 0.9999) {
    return "geometric normal not perpendicular to the world triangle for " + where;
  }
  if (glm::length(hit.position - ray.at(hit.t)) > 1e-4f * (1.0f + glm::length(hit.position))) {
    return "position is not at t for " + where;
  }
  const PreparedObject& o = scene.objects()[hit.object];
  if (hit.material != &o.source->materials[o.triangles->material[hit.triangle]]) {
    return "wrong material for " + where;
  }
  return {};
}

TEST(EmbreeIntersector, ClosestHitsMatchBruteForceUnderRotationScaleAndMirroring) {
  const PreparedScene scene(instanced_scene());
  const auto embree = build_embree_intersector(scene);
  int hits = 0;
  for (const Ray& ray : test_rays(scene, 3000, 1)) {
    ASSERT_EQ(compare(scene, *embree, ray), "");
    SurfaceHit hit;
    hits += embree->closest_hit(ray, hit) ? 1 : 0;
  }
  EXPECT_GT(hits, 1500);  // the aimed half nearly always hits something
}

TEST(EmbreeIntersector, EveryObjectIsHitUnderItsOwnIndex) {
  const PreparedScene scene(instanced_scene());
  const auto embree = build_embree_intersector(scene);
  std::vector<int> hits(scene.objects().size(), 0);
  for (const Ray& ray : test_rays(scene, 2000, 2)) {
    SurfaceHit hit;
    if (embree->closest_hit(ray, hit)) ++hits.at(hit.object);
  }
  for (std::size_t i = 0; i < hits.size(); ++i) {
    if (scene.objects()[i].triangles->size() == 0) {
      EXPECT_EQ(hits[i], 0) << i;
    } else {
      EXPECT_GT(hits[i], 0) << i;
    }
  }
}

TEST(EmbreeIntersector, RespectsTMinAndTMax) {
  const PreparedScene scene(instanced_scene());
  const auto embree = build_embree_intersector(scene);
  int checked = 0;
  for (const Ray& ray : test_rays(scene, 1000, 3)) {
    SurfaceHit first;
    if (!embree->closest_hit(ray, first)) continue;
    ++checked;
    Ray before = ray;
    before.t_max = first.t * 0.999f;  // the first hit lies beyond the segment
    ASSERT_EQ(compare(scene, *embree, before), "");
    SurfaceHit hit;
    EXPECT_FALSE(embree->closest_hit(before, hit) && hit.t >= before.t_max);
    Ray after = ray;
    after.t_min = first.t * 1.001f;  // starts past the first hit: finds what lies behind it
    ASSERT_EQ(compare(scene, *embree, after), "");
    if (embree->closest_hit(after, hit)) {
      EXPECT_GT(hit.t, after.t_min);
    }
  }
  EXPECT_GT(checked, 300);
}

TEST(EmbreeIntersector, TScalesInverselyWithTheDirectionsLength) {
  Scene s;
  s.objects.push_back(test::object_of(test::make_quad({-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}),
                                      trs({0, 0, -3}, 0, {0, 1, 0}, {2, 2, 2})));
  const PreparedScene scene(std::move(s));
  const auto embree = build_embree_intersector(scene);
  SurfaceHit a, b;
  ASSERT_TRUE(embree->closest_hit(Ray{{0.1f, 0.2f, 0}, {0, 0, -1}}, a));
  ASSERT_TRUE(embree->closest_hit(Ray{{0.1f, 0.2f, 0}, {0, 0, -4}}, b));
  EXPECT_NEAR(a.t, 3.0f, 1e-5f);
  EXPECT_NEAR(b.t, 0.75f, 1e-5f);
  EXPECT_NEAR(b.position.z, -3.0f, 1e-5f);
  EXPECT_NEAR(glm::length(b.shading_normal), 1.0f, 1e-5f);
}

TEST(EmbreeIntersector, EmptySceneAndEmptyModelsMissEverything) {
  const PreparedScene nothing{Scene{}};
  const auto embree = build_embree_intersector(nothing);
  SurfaceHit hit;
  EXPECT_FALSE(embree->closest_hit(Ray{{0, 0, 5}, {0, 0, -1}}, hit));
  EXPECT_FALSE(embree->occluded(Ray{{0, 0, 5}, {0, 0, -1}}));

  Scene s;
  s.objects.push_back(test::object_of(Model{}));
  const PreparedScene empty_model(std::move(s));
  const auto embree2 = build_embree_intersector(empty_model);
  EXPECT_FALSE(embree2->closest_hit(Ray{{0, 0, 5}, {0, 0, -1}}, hit));
}

TEST(EmbreeIntersector, NonFiniteRaysMissInsteadOfMisbehaving) {
  const PreparedScene scene(instanced_scene());
  const auto embree = build_embree_intersector(scene);
  SurfaceHit hit;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(embree->closest_hit(Ray{{nan, 0, 0}, {0, 0, -1}}, hit));
  EXPECT_FALSE(embree->occluded(Ray{{0, 0, 5}, {0, kInf, -1}}));
}

TEST(EmbreeIntersector, ConcurrentQueriesGiveTheSameHitsAsOneThread) {
  const PreparedScene scene(instanced_scene());
  const auto embree = build_embree_intersector(scene);
  const std::vector<Ray> rays = test_rays(scene, 2000, 4);
  std::vector<SurfaceHit> expected(rays.size());
  std::vector<char> expected_hit(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) expected_hit[i] = embree->closest_hit(rays[i], expected[i]);

  std::vector<int> mismatches(4, 0);
  std::vector<std::thread> threads;
  for (int k = 0; k < 4; ++k) {
    threads.emplace_back([&, k] {
      for (std::size_t i = 0; i < rays.size(); ++i) {
        SurfaceHit hit;
        const bool got = embree->closest_hit(rays[i], hit);
        if (got != static_cast<bool>(expected_hit[i]) ||
            (got && (hit.t != expected[i].t || hit.triangle != expected[i].triangle))) {
          ++mismatches[k];
        }
      }
    });
  }
  for (std::thread& t : threads) t.join();
  for (int m : mismatches) EXPECT_EQ(m, 0);
}

TEST(EmbreeIntersector, BuildSceneIntersectorGivesEmbreeForTheEmbreeAccel) {
  const PreparedScene scene(instanced_scene());
  const auto embree = build_scene_intersector(scene, AccelKind::Embree);
  for (const Ray& ray : test_rays(scene, 200, 5)) ASSERT_EQ(compare(scene, *embree, ray), "");
}

}  // namespace
}  // namespace farm
