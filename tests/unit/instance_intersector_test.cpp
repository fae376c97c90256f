// The instanced scene intersector (top-level BVH over objects, rays carried into model space)
// against a brute force over every triangle transformed into world space, under rotations,
// non-uniform and mirroring scales; and the SurfaceHit it completes.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <glm/geometric.hpp>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "renderer/accel/instance_intersector.h"
#include "renderer/accel/prepared_scene.h"
#include "renderer/geometry/traversal_isa.h"
#include "renderer/geometry/triangle_intersect.h"
#include "tests/support/ray_fixtures.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

#ifdef NDEBUG
constexpr std::size_t kRayDivisor = 1;
#else
constexpr std::size_t kRayDivisor = 10;
#endif

struct WorldTriangle {
  glm::vec3 a, b, c;
  std::uint32_t object, triangle;
};

std::vector<WorldTriangle> world_triangles(const PreparedScene& scene, AABB& bounds) {
  std::vector<WorldTriangle> out;
  for (std::uint32_t o = 0; o < scene.objects().size(); ++o) {
    const PreparedObject& object = scene.objects()[o];
    const ModelTriangles& model = *object.triangles;
    auto world = [&](std::uint32_t i) {
      const glm::vec3 p = glm::vec3(object.model_to_world * glm::vec4(model.positions[i], 1.0f));
      bounds.grow(p);
      return p;
    };
    for (std::uint32_t t = 0; t < model.size(); ++t) {
      const glm::uvec3& tri = model.triangles[t];
      out.push_back({world(tri.x), world(tri.y), world(tri.z), o, t});
    }
  }
  return out;
}

struct Reference {
  float t = 0.0f, u = 0.0f, v = 0.0f;
  std::uint32_t object = 0, triangle = 0;
};

bool brute_force(const std::vector<WorldTriangle>& triangles, Ray ray, Reference& nearest) {
  bool found = false;
  for (const WorldTriangle& w : triangles) {
    if (auto h = intersect_triangle(ray, w.a, w.b, w.c)) {
      nearest = {h->t, h->u, h->v, w.object, w.triangle};
      ray.t_max = h->t;
      found = true;
    }
  }
  return found;
}

// Within rounding of a triangle's edge, world- and model-space tests may decide differently.
bool near_edge(float u, float v) { return std::min({u, v, 1.0f - u - v}) < 1e-4f; }

SceneObject instance(std::shared_ptr<const Model> model, const glm::mat4& model_to_world,
                     float shade) {
  SceneObject object;
  object.name = "object";
  object.model = std::move(model);
  object.model_to_world = model_to_world;
  object.materials = object.model->materials;
  for (Material& m : object.materials) m.diffuse = glm::vec3(shade);
  return object;
}

// Overlapping spheres, boxes and a grid, rotated, scaled non-uniformly and mirrored; object
// o's material has diffuse o / 100, and object 7 is a model without triangles.
Scene mixed_scene() {
  const auto sphere = std::make_shared<const Model>(test::make_sphere(12, 24));
  const auto box = std::make_shared<const Model>(test::make_box({-0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, 0.5f}));
  const auto grid = std::make_shared<const Model>(test::make_grid(8));
  auto empty = std::make_shared<Model>();
  empty->materials.push_back(Material{});
  Scene scene;
  const std::vector<std::pair<std::shared_ptr<const Model>, glm::mat4>> placements = {
      {sphere, test::placed({0.0f, 0.0f, 0.0f}, {1, 1, 0}, 30.0f, {0.3f, 2.0f, 1.0f})},
      {sphere, test::placed({2.5f, 0.0f, 0.0f}, {0, 0, 1}, -20.0f, {-0.8f, 0.8f, 0.8f})},  // mirrored
      {box, test::placed({-2.0f, 0.0f, 1.0f}, {0, 1, 0}, 45.0f, {1.0f, 0.2f, 3.0f})},
      {grid, test::placed({0.0f, -2.5f, 0.0f}, {1, 0, 0}, -90.0f, {3.0f, 3.0f, 1.0f})},
      {sphere, test::placed({0.5f, 0.8f, 0.3f}, {0, 1, 0}, 10.0f, {1.0f, 1.0f, 1.0f})},  // overlaps 0
      {box, test::placed({0.0f, 1.5f, -1.5f}, {1, 0, 1}, 60.0f, {-1.0f, 1.0f, -0.5f})},  // two mirrors
      {sphere, test::placed({-1.0f, -1.0f, -1.0f}, {0, 1, 1}, 75.0f, {-1.5f, 0.4f, 1.0f})},
      {empty, glm::mat4(1.0f)},
  };
  for (std::size_t o = 0; o < placements.size(); ++o) {
    scene.objects.push_back(instance(placements[o].first, placements[o].second,
                                     static_cast<float>(o) / 100.0f));
  }
  return scene;
}

struct Tally {
  std::size_t hits = 0, ties = 0, edge_cases = 0, failures = 0;
};

// One ray: ours against the world-space brute force, occluded() against closest_hit(), and
// the completed SurfaceHit against the world triangle it reports.
struct Expected {
  bool hit = false;
  Reference nearest;
};

std::vector<Expected> brute_force(const std::vector<WorldTriangle>& world, const std::vector<Ray>& rays) {
  std::vector<Expected> out(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) out[i].hit = brute_force(world, rays[i], out[i].nearest);
  return out;
}

void check_ray(const PreparedScene& scene, const SceneIntersector& ours,
               const std::vector<WorldTriangle>& world, const std::vector<std::size_t>& first_of,
               const Ray& ray, const Expected& expected, std::size_t i, const std::string& what,
               Tally& tally) {
  auto fail = [&](const std::string& why) {
    if (++tally.failures <= 5) ADD_FAILURE() << what << ", ray " << i << ": " << why;
  };
  const Reference& want = expected.nearest;
  const bool want_hit = expected.hit;
  SurfaceHit got;
  const bool got_hit = ours.closest_hit(ray, got);
  if (ours.occluded(ray) != got_hit) fail("occluded() disagrees with closest_hit()");
  // Hits that rounding decides differently in world and model space: near an edge, or by a ray
  // (nearly) in the triangle's plane.
  auto grazing = [&](const WorldTriangle& w) {
    const glm::vec3 n = glm::normalize(glm::cross(w.b - w.a, w.c - w.a));
    return std::abs(glm::dot(n, glm::normalize(ray.direction))) < 1e-4f;
  };
  const bool want_fragile =
      want_hit && (near_edge(want.u, want.v) || grazing(world[first_of[want.object] + want.triangle]));
  const bool got_fragile =
      got_hit && (near_edge(got.u, got.v) || grazing(world[first_of[got.object] + got.triangle]));
  if (want_hit != got_hit) {
    if (want_fragile || got_fragile) {
      ++tally.edge_cases;
    } else {
      fail(want_hit ? "missed object " + std::to_string(want.object) : "hit where nothing is");
    }
    return;
  }
  if (!want_hit) return;
  ++tally.hits;
  const bool same = want.object == got.object && want.triangle == got.triangle;
  // 1e-4 relative, and for hits very near the origin the rounding of world coordinates.
  const float tolerance = 1e-4f * want.t + 1e-5f * (1.0f + glm::length(ray.origin)) / glm::length(ray.direction);
  if (std::abs(got.t - want.t) > tolerance) {
    if (want_fragile || got_fragile) {
      ++tally.edge_cases;
    } else {
      fail("t " + std::to_string(got.t) + " instead of " + std::to_string(want.t) + " (object " +
           std::to_string(got.object) + " vs " + std::to_string(want.object) + ")");
    }
    return;
  }
  if (!same) ++tally.ties;

  Ray shadow = ray;
  shadow.t_max = got.t * (1.0f - 1e-3f);
  if (ours.occluded(shadow)) fail("occluded before the closest hit");

  // The SurfaceHit: unit normals, the geometric one perpendicular to the world triangle.
  const WorldTriangle& w = world[first_of[got.object] + got.triangle];
  ASSERT_EQ(w.object, got.object);
  ASSERT_EQ(w.triangle, got.triangle);
  if (std::abs(glm::length(got.geometric_normal) - 1.0f) > 1e-5f) fail("geometric normal not unit");
  if (std::abs(glm::length(got.shading_normal) - 1.0f) > 1e-5f) fail("shading normal not unit");
  const glm::vec3 e1 = glm::normalize(w.b - w.a), e2 = glm::normalize(w.c - w.a);
  if (std::abs(glm::dot(got.geometric_normal, e1)) > 1e-4f ||
      std::abs(glm::dot(got.geometric_normal, e2)) > 1e-4f) {
    fail("geometric normal not perpendicular to the world triangle");
  }
  if (glm::distance(got.position, ray.at(got.t)) > 1e-6f * glm::length(got.position) + 1e-6f) {
    fail("position is not ray.at(t)");
  }
  const float plane_distance = std::abs(glm::dot(got.geometric_normal, got.position - w.a));
  if (plane_distance > 1e-4f * (1.0f + glm::length(got.position))) fail("position off the triangle's plane");
  const PreparedObject& object = scene.objects()[got.object];
  if (got.material != &object.source->materials[object.triangles->material[got.triangle]] ||
      got.material->diffuse.x != static_cast<float>(got.object) / 100.0f) {
    fail("wrong material");
  }
  // The geometric and shading normals keep their model-space relation (same side or not)
  // under every transform, mirrors included.
  const ModelTriangles& model = *object.triangles;
  const glm::uvec3& tri = model.triangles[got.triangle];
  const glm::vec3 n_model = glm::cross(model.positions[tri.y] - model.positions[tri.x],
                                       model.positions[tri.z] - model.positions[tri.x]);
  const glm::vec3 s_model = (1.0f - got.u - got.v) * model.normals[tri.x] +
                            got.u * model.normals[tri.y] + got.v * model.normals[tri.z];
  if ((glm::dot(n_model, s_model) > 0.0f) != (glm::dot(got.geometric_normal, got.shading_normal) > 0.0f)) {
    fail("geometric and shading normals changed sides");
  }
}

std::vector<std::size_t> first_triangle_of(const PreparedScene& scene) {
  std::vector<std::size_t> first;
  std::size_t n = 0;
  for (const PreparedObject& o : scene.objects()) {
    first.push_back(n);
    n += o.triangles->size();
  }
  return first;
}

TEST(InstanceIntersector, MatchesWorldSpaceBruteForceUnderRotationNonUniformScaleAndMirrors) {
  const PreparedScene scene(mixed_scene());
  AABB bounds;
  const std::vector<WorldTriangle> world = world_triangles(scene, bounds);
  const std::vector<std::size_t> first_of = first_triangle_of(scene);
  std::vector<glm::vec3> planes;
  for (std::size_t i = 0; i < world.size(); i += 17) planes.push_back(world[i].a);
  const std::vector<Ray> rays = test::random_rays(bounds, 20000 / kRayDivisor, 5, planes);
  const std::vector<Expected> expected = brute_force(world, rays);
  for (const AccelKind kind : {AccelKind::Bvh, AccelKind::BvhMedian, AccelKind::Naive}) {
    const std::string what(to_string(kind));
    const auto ours = build_scene_intersector(scene, kind);
    Tally tally;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      check_ray(scene, *ours, world, first_of, rays[i], expected[i], i, what, tally);
    }
    EXPECT_EQ(tally.failures, 0u) << what;
    std::printf("%s: %zu rays, %zu hits, %zu ties, %zu edge cases\n", what.c_str(), rays.size(), tally.hits, tally.ties, tally.edge_cases);
    EXPECT_GT(tally.hits, rays.size() / 4) << what;
    // Only the rays placed on vertex coordinates meet edges that exactly (about 0.1%).
    EXPECT_LE(tally.edge_cases, rays.size() / 200 + 5) << what << ": rounding at edges should be rare";
    EXPECT_LE(tally.ties, tally.hits / 50) << what;
  }
}

TEST(InstanceIntersector, HitDistanceIsInUnitsOfTheWorldDirectionUnderNonUniformScale) {
  // A unit sphere stretched to y radius 2 and x radius 0.3: along +y from y = -5 the surface is
  // at y = -2, so t = 3 / |d|-units whatever the model-space direction's length.
  Scene s;
  s.objects.push_back(instance(std::make_shared<const Model>(test::make_sphere(32, 64)),
                               test::placed({0, 0, 0}, {0, 1, 0}, 0.0f, {0.3f, 2.0f, 1.0f}), 0.0f));
  const PreparedScene scene(std::move(s));
  for (const AccelKind kind : {AccelKind::Bvh, AccelKind::BvhMedian, AccelKind::Naive}) {
    const auto ours = build_scene_intersector(scene, kind);
    Ray ray;
    ray.origin = {0.0f, -5.0f, 0.0f};
    ray.direction = {0.0f, 0.5f, 0.0f};
    SurfaceHit hit;
    ASSERT_TRUE(ours->closest_hit(ray, hit));
    EXPECT_NEAR(hit.t, 6.0f, 1e-4f);
    EXPECT_NEAR(hit.position.y, -2.0f, 1e-4f);
    EXPECT_LT(hit.geometric_normal.y, -0.9f);  // a facet of the pole's fan
    // Along x the stretched sphere is 0.3 thick: hit at x = -0.3 from x = -1, t = 0.7.
    ray.origin = {-1.0f, 0.0f, 0.0f};
    ray.direction = {1.0f, 0.0f, 0.0f};
    ASSERT_TRUE(ours->closest_hit(ray, hit));
    EXPECT_NEAR(hit.t, 0.7f, 1e-3f);
    EXPECT_LT(hit.shading_normal.x, -0.99f);
  }
}

TEST(InstanceIntersector, HundredInstancesShareOneMeshAccel) {
  const auto sphere = std::make_shared<const Model>(test::make_sphere(8, 16));
  Scene s;
  for (int i = 0; i < 100; ++i) {
    const glm::vec3 at{static_cast<float>(i % 10) * 2.5f, 0.0f, static_cast<float>(i / 10) * 2.5f};
    const glm::vec3 scale{1.0f + 0.05f * static_cast<float>(i % 7), 1.0f - 0.05f * static_cast<float>(i % 5),
                          i % 3 == 0 ? -1.0f : 1.0f};
    s.objects.push_back(instance(sphere, test::placed(at, {0, 1, 0}, 3.6f * static_cast<float>(i), scale),
                                 static_cast<float>(i) / 100.0f));
  }
  const PreparedScene scene(std::move(s));
  for (const AccelKind kind : {AccelKind::Bvh, AccelKind::BvhMedian, AccelKind::Naive}) {
    const InstanceIntersector ours(scene, kind);
    EXPECT_EQ(ours.mesh_accel_count(), 1u);
    EXPECT_EQ(&ours.mesh_accel_of(0), &ours.mesh_accel_of(99));
  }
  // And it still finds the right instance.
  const auto ours = build_scene_intersector(scene, AccelKind::Bvh);
  AABB bounds;
  const std::vector<WorldTriangle> world = world_triangles(scene, bounds);
  const std::vector<std::size_t> first_of = first_triangle_of(scene);
  const std::vector<Ray> rays = test::random_rays(bounds, 1500 / kRayDivisor, 9);
  const std::vector<Expected> expected = brute_force(world, rays);
  Tally tally;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    check_ray(scene, *ours, world, first_of, rays[i], expected[i], i, "100 spheres", tally);
  }
  EXPECT_EQ(tally.failures, 0u);
  EXPECT_GT(tally.hits, rays.size() / 10);
}

TEST(InstanceIntersector, CountsTopAndBottomLevelWork) {
  const PreparedScene scene(mixed_scene());
  const auto bvh = build_scene_intersector(scene, AccelKind::Bvh);
  const auto naive = build_scene_intersector(scene, AccelKind::Naive);
  Ray ray;
  ray.origin = {0.0f, 0.0f, 10.0f};
  ray.direction = {0.0f, 0.0f, -1.0f};
  TraversalStats bvh_stats, naive_stats;
  SurfaceHit hit;
  ASSERT_TRUE(bvh->closest_hit(ray, hit, &bvh_stats));
  ASSERT_TRUE(naive->closest_hit(ray, hit, &naive_stats));
  EXPECT_GT(bvh_stats.nodes, 2u);
  EXPECT_GT(bvh_stats.triangles, 0u);
  EXPECT_EQ(naive_stats.nodes, 0u);
  EXPECT_EQ(naive_stats.triangles, scene.triangle_count());
  EXPECT_LT(bvh_stats.cost(), naive_stats.cost());
}

TEST(InstanceIntersector, VisitsTopLevelAndPerObjectBoxesForDrawing) {
  const PreparedScene scene(mixed_scene());
  AABB bounds;
  const std::vector<WorldTriangle> world = world_triangles(scene, bounds);
  const InstanceIntersector ours(scene, AccelKind::Bvh);
  ASSERT_NE(ours.top_level(), nullptr);
  std::size_t top = 0;
  std::vector<std::size_t> roots(scene.objects().size(), 0);
  ours.visit_bvh_boxes(100, [&](const BvhBox& box) {
    if (box.object < 0) {
      ++top;
      EXPECT_EQ(box.to_world, glm::mat4(1.0f));
      if (box.level == 0) {
        const glm::vec3 slack(1e-4f);
        EXPECT_TRUE(box.bounds.contains(AABB{bounds.min + slack, bounds.max - slack}));
      }
      return;
    }
    const auto o = static_cast<std::size_t>(box.object);
    EXPECT_EQ(box.to_world, scene.objects()[o].model_to_world);
    if (box.level != 0) return;
    ++roots[o];
    // The root box, carried to world space, holds every world vertex of the object.
    AABB w = transformed(box.bounds, box.to_world);
    w.min -= glm::vec3(1e-4f);
    w.max += glm::vec3(1e-4f);
    for (const WorldTriangle& t : world) {
      if (t.object != o) continue;
      AABB tb;
      tb.grow(t.a);
      tb.grow(t.b);
      tb.grow(t.c);
      EXPECT_TRUE(w.contains(tb));
    }
  });
  EXPECT_EQ(top, ours.top_level()->nodes().size());
  for (std::size_t o = 0; o < scene.objects().size(); ++o) {
    EXPECT_EQ(roots[o], scene.objects()[o].triangles->size() > 0 ? 1u : 0u) << "object " << o;
  }
  std::size_t shallow = 0;
  ours.visit_bvh_boxes(0, [&](const BvhBox& box) {
    EXPECT_EQ(box.level, 0);
    ++shallow;
  });
  EXPECT_EQ(shallow, 1u + 7u);  // the top-level root and one root per object with triangles

  const InstanceIntersector naive(scene, AccelKind::Naive);
  std::size_t none = 0;
  naive.visit_bvh_boxes(100, [&](const BvhBox&) { ++none; });
  EXPECT_EQ(none, 0u);
}

// An instance's hit is its mesh's hit for the ray glm carries into model space (the point by
// `world_to_model * vec4(origin, 1)`, the direction by `mat3(world_to_model)`), bit for bit: the
// intersector carries it over with SSE, each lane glm's products and sums in their order, so
// images rendered before that change keep their bits. Rotated, scaled and mirrored objects.
TEST(InstanceIntersector, AnInstancesHitIsItsMeshsHitOnTheRayGlmCarriesToModelSpaceBitForBit) {
  const PreparedScene scene(mixed_scene());
  const InstanceIntersector ours(scene, AccelKind::Bvh);
  AABB bounds;
  world_triangles(scene, bounds);
  const std::vector<Ray> rays = test::random_rays(bounds, 20000 / kRayDivisor, 17);
  std::size_t hits = 0, differing = 0;
  for (const Ray& ray : rays) {
    SurfaceHit hit;
    if (!ours.find_closest(ray, hit)) continue;
    ++hits;
    const glm::mat4& to_model = scene.objects()[hit.object].world_to_model;
    Ray local = ray;
    local.origin = glm::vec3(to_model * glm::vec4(ray.origin, 1.0f));
    local.direction = glm::mat3(to_model) * ray.direction;
    TriangleHit alone;
    const bool found = ours.mesh_accel_of(hit.object).closest_hit(local, alone, nullptr);
    const bool same = found && std::bit_cast<std::uint32_t>(alone.t) == std::bit_cast<std::uint32_t>(hit.t) &&
                      std::bit_cast<std::uint32_t>(alone.u) == std::bit_cast<std::uint32_t>(hit.u) &&
                      std::bit_cast<std::uint32_t>(alone.v) == std::bit_cast<std::uint32_t>(hit.v) &&
                      alone.triangle == hit.triangle;
    if (!same && ++differing <= 5) {
      ADD_FAILURE() << fmt::format("object {} triangle {} t {}: alone on glm's model-space ray {}", hit.object,
                                   hit.triangle, hit.t, found ? fmt::format("t {}", alone.t) : "no hit");
    }
  }
  EXPECT_EQ(differing, 0u);
  EXPECT_GT(hits, rays.size() / 10);
}

// A rod (a staircase of small boxes) along the model's xz diagonal, turned 45 degrees about y,
// lies along world x: a box made of its model box's corners would span its whole length in z.
Model diagonal_rod() {
  Model rod;
  for (int i = 0; i < 64; ++i) {
    const float a = 0.125f * static_cast<float>(i), b = a + 0.125f;
    rod.meshes.push_back(test::make_box({a, 0.0f, a}, {b, 0.1f, b}).meshes[0]);
  }
  rod.materials.push_back(Material{});
  return rod;
}

// The top-level box of `copies` turned rods placed in the same spot (the root's box, each
// copy's box being the same), and the box of their world vertices.
std::pair<AABB, AABB> turned_rods_boxes(std::size_t copies) {
  Scene s;
  s.objects.push_back(test::object_of(diagonal_rod(), test::placed(glm::vec3(0.0f), {0, 1, 0}, 45.0f, glm::vec3(1.0f))));
  s.objects.resize(copies, s.objects[0]);  // one model, placed `copies` times
  const PreparedScene scene(std::move(s));
  AABB vertices;
  world_triangles(scene, vertices);
  const InstanceIntersector ours(scene, AccelKind::Bvh);
  AABB top;
  ours.visit_bvh_boxes(0, [&](const BvhBox& box) {
    if (box.object < 0) top = box.bounds;
  });
  return {top, vertices};
}

std::size_t vertex_count(const Model& model) {
  std::size_t n = 0;
  for (const Mesh& mesh : model.meshes) n += mesh.positions.size();
  return n;
}

// A turned instance's top-level box is the box of its vertices carried to the world (grown by
// 2^-16 of its largest coordinate), not its model box's corners carried over: it holds every
// world vertex, is no larger, and rays still find what brute force finds.
TEST(InstanceIntersector, ATurnedInstancesTopLevelBoxIsTheBoxOfItsWorldVertices) {
  const auto [top, vertices] = turned_rods_boxes(1);
  const glm::vec3 slack(1e-3f);
  EXPECT_TRUE(top.contains(vertices));
  EXPECT_TRUE((AABB{vertices.min - slack, vertices.max + slack}.contains(top)));
  // The rod is 8 * sqrt(2) = 11.3 long along x; its model box's corners turned would span 11.3
  // in z too, its vertices 0.125 * sqrt(2) = 0.18.
  EXPECT_GT(top.extent().x, 11.0f);
  EXPECT_LT(top.extent().z, 0.2f);

  Scene s;
  Material shade;  // check_ray's mark of object 0
  shade.diffuse = glm::vec3(0.0f);
  s.objects.push_back(test::object_of(diagonal_rod(), test::placed(glm::vec3(0.0f), {0, 1, 0}, 45.0f, glm::vec3(1.0f)), shade));
  const PreparedScene scene(std::move(s));
  AABB box;
  const std::vector<WorldTriangle> world = world_triangles(scene, box);
  const InstanceIntersector ours(scene, AccelKind::Bvh);
  const std::vector<Ray> rays = test::random_rays(box, 20000 / kRayDivisor, 5);
  const std::vector<Expected> expected = brute_force(world, rays);
  const std::vector<std::size_t> first_of = first_triangle_of(scene);
  Tally tally;
  for (std::size_t i = 0; i < rays.size(); ++i) check_ray(scene, ours, world, first_of, rays[i], expected[i], i, "bvh", tally);
  EXPECT_EQ(tally.failures, 0u);
  EXPECT_GT(tally.hits, rays.size() / 20);
}

// Past kExactBoxVertices over a model's instances, each instance's box is made of its model's
// upper BVH boxes (four, each a quarter of the rod) carried to the world by their corners:
// looser than the vertices' box, still far tighter than the model box's corners, and holding
// every vertex.
TEST(InstanceIntersector, ManyInstancesOfAModelTakeTheBoxesOfItsUpperBvhNodes) {
  const std::size_t copies = InstanceIntersector::kExactBoxVertices / vertex_count(diagonal_rod()) + 1;
  const auto [top, vertices] = turned_rods_boxes(copies);
  const glm::vec3 slack(1e-4f);
  EXPECT_TRUE(top.contains(AABB{vertices.min + slack, vertices.max - slack}));
  EXPECT_GT(top.extent().x, 11.0f);
  EXPECT_GT(top.extent().z, 2.0f * vertices.extent().z);
  EXPECT_LT(top.extent().z, 0.3f * top.extent().x);
  const auto [half, half_vertices] = turned_rods_boxes(copies / 2);
  EXPECT_LT(half.extent().z, 0.2f);  // a model placed half as often: its vertices' box
}

// Objects in the same place (a model placed twice, as a job's copy-paste leaves it) are hit at
// the same t: the lowest object index wins under every accel, whatever the top-level tree's
// order (ray_hit_order.h), and within it the lowest triangle.
TEST(InstanceIntersector, CoincidentObjectsGoToTheLowestObjectIndexUnderEveryAccel) {
  const auto sphere = std::make_shared<const Model>(test::make_sphere(8, 16));
  // The same sphere with a speck far off: its box is larger, so rays enter it first and the
  // top level meets the higher index first.
  Model with_speck = test::make_sphere(8, 16);
  Mesh speck;
  speck.positions = {{-4.0f, -4.0f, -4.0f}, {-3.99f, -4.0f, -4.0f}, {-4.0f, -3.99f, -4.0f}};
  speck.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  speck.triangles = {{0, 1, 2}};
  with_speck.meshes.push_back(speck);
  const auto specked = std::make_shared<const Model>(std::move(with_speck));
  Scene s;
  for (int i = 0; i < 12; ++i) {
    // Pairs 2k and 2k+1 coincide where the sphere is; the pairs lie apart, so the top-level tree
    // is not a list.
    const glm::vec3 at{static_cast<float>(i / 2) * 2.5f, 0.0f, 0.0f};
    s.objects.push_back(instance(i % 2 ? specked : sphere,
                                 test::placed(at, {0, 1, 0}, 10.0f * static_cast<float>(i / 2), {1, 1, 1}),
                                 static_cast<float>(i) / 12.0f));
  }
  const PreparedScene scene(std::move(s));
  AABB bounds;
  world_triangles(scene, bounds);
  const std::vector<Ray> rays = test::random_rays(bounds, 3000 / kRayDivisor, 17);
  const std::uint32_t speck_index = static_cast<std::uint32_t>(scene.objects()[1].triangles->size() - 1);
  std::size_t hits = 0;
  std::vector<std::vector<SurfaceHit>> by_accel;
  for (const AccelKind kind : {AccelKind::Naive, AccelKind::Bvh, AccelKind::BvhMedian}) {
    const auto ours = build_scene_intersector(scene, kind);
    std::vector<SurfaceHit> found(rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i) {
      if (!ours->find_closest(rays[i], found[i])) continue;
      if (kind == AccelKind::Naive) ++hits;
      if (found[i].object % 2 == 1) {  // only its speck, which the other lacks
        EXPECT_EQ(found[i].triangle, speck_index) << to_string(kind) << " ray " << i << ": object " << found[i].object;
      }
    }
    by_accel.push_back(std::move(found));
  }
  for (std::size_t k = 1; k < by_accel.size(); ++k) {
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const SurfaceHit &a = by_accel[0][i], &b = by_accel[k][i];
      EXPECT_TRUE(a.object == b.object && a.triangle == b.triangle && a.t == b.t && a.u == b.u && a.v == b.v)
          << "accel " << k << " ray " << i;
    }
  }
  EXPECT_GT(hits, rays.size() / 10);
}

// Rays from one eye through a grid of points on a square facing it: a camera's coherent packets
// (8 in a row share an octant but near the square's centre lines).
std::vector<Ray> eye_rays(const AABB& bounds, int side) {
  const glm::vec3 centre = bounds.center(), extent = bounds.extent();
  const glm::vec3 eye = centre + glm::vec3(0.3f, 0.4f, 1.0f) * (2.0f * glm::length(extent));
  std::vector<Ray> rays;
  for (int y = 0; y < side; ++y) {
    for (int x = 0; x < side; ++x) {
      const glm::vec3 target = centre + extent * glm::vec3((static_cast<float>(x) + 0.5f) / static_cast<float>(side) - 0.5f,
                                                           (static_cast<float>(y) + 0.5f) / static_cast<float>(side) - 0.5f, 0.0f);
      Ray ray;
      ray.origin = eye;
      ray.direction = target - eye;
      rays.push_back(ray);
    }
  }
  return rays;
}

// What the packet tests walk: many objects turned, scaled and mirrored; one object placed as it
// is; one moved.
std::vector<std::pair<std::string, Scene>> packet_scenes() {
  const auto sphere = std::make_shared<const Model>(test::make_sphere(12, 24));
  Scene one_untransformed, one_moved;
  one_untransformed.objects.push_back(instance(sphere, glm::mat4(1.0f), 0.5f));
  one_moved.objects.push_back(instance(sphere, test::placed({1, 2, 3}, {1, 1, 0}, 30.0f, {0.5f, 2.0f, 1.0f}), 0.5f));
  std::vector<std::pair<std::string, Scene>> scenes;
  scenes.emplace_back("mixed", mixed_scene());
  scenes.emplace_back("one untransformed", std::move(one_untransformed));
  scenes.emplace_back("one moved", std::move(one_moved));
  return scenes;
}

// Coherent rays from an eye and random ones (whose octants split packets), a whole number of
// packets of 8.
std::vector<Ray> packet_rays(const PreparedScene& scene, std::uint32_t seed) {
  AABB bounds;
  world_triangles(scene, bounds);
  std::vector<Ray> rays = eye_rays(bounds, 64);
  const std::vector<Ray> incoherent = test::random_rays(bounds, 4096 / kRayDivisor, seed);
  rays.insert(rays.end(), incoherent.begin(), incoherent.end());
  rays.resize(rays.size() / 8 * 8);
  return rays;
}

// A packet's rays find, bit for bit, the hits find_closest finds for each alone: over many
// objects turned, scaled and mirrored, over one object placed as it is and one moved, for
// coherent and incoherent rays (whose octants split a packet), under every traversal build this
// CPU runs and every accel. Lanes left out of a packet are neither traced nor written.
TEST(InstanceIntersector, APacketsRaysFindTheHitsEachFindsAloneBitForBit) {
  std::vector<std::pair<std::string, Scene>> scenes = packet_scenes();
  const unsigned partial = 0b10110101u;
  for (auto& [name, built] : scenes) {
    const PreparedScene scene(std::move(built));
    std::vector<Ray> rays = packet_rays(scene, 23);
    for (const AccelKind kind : {AccelKind::Bvh, AccelKind::BvhMedian, AccelKind::Naive}) {
      const auto ours = build_scene_intersector(scene, kind);
      for (const TraversalIsa isa : {TraversalIsa::Sse, TraversalIsa::Avx2, TraversalIsa::Avx512}) {
        if (!cpu_runs(isa)) continue;
        const ForcedTraversalIsa forced(isa);
        std::size_t hits = 0;
        for (std::size_t first = 0; first < rays.size(); first += 8) {
          const unsigned lanes = (first / 8) % 2 ? partial : 0xFFu;
          std::array<SurfaceHit, 8> packet;
          for (SurfaceHit& h : packet) h.t = -1.0f;  // what a lane left out keeps
          const unsigned found = ours->find_closest_packet(&rays[first], lanes, packet.data());
          EXPECT_EQ(found & ~lanes, 0u);
          for (std::size_t i = 0; i < 8; ++i) {
            const std::string where = name + ", " + std::string(to_string(kind)) + ", " +
                                      std::string(to_string(isa)) + ", ray " + std::to_string(first + i);
            if (!(lanes >> i & 1u)) {
              EXPECT_EQ(packet[i].t, -1.0f) << where;
              continue;
            }
            SurfaceHit alone;
            const bool hit = ours->find_closest(rays[first + i], alone);
            ASSERT_EQ((found >> i & 1u) != 0, hit) << where;
            if (!hit) continue;
            ++hits;
            const SurfaceHit& p = packet[i];
            ASSERT_TRUE(std::bit_cast<std::uint32_t>(p.t) == std::bit_cast<std::uint32_t>(alone.t) &&
                        std::bit_cast<std::uint32_t>(p.u) == std::bit_cast<std::uint32_t>(alone.u) &&
                        std::bit_cast<std::uint32_t>(p.v) == std::bit_cast<std::uint32_t>(alone.v) &&
                        p.object == alone.object && p.triangle == alone.triangle)
                << where << ": t " << p.t << " vs " << alone.t << ", object " << p.object << " vs " << alone.object
                << ", triangle " << p.triangle << " vs " << alone.triangle;
          }
        }
        EXPECT_GT(hits, rays.size() / 8) << name << ", " << to_string(kind) << ", " << to_string(isa);
      }
    }
  }
}

// A packet of shadow rays is blocked, lane by lane, exactly where occluded says each ray alone
// is: rays ending just short of their nearest hit, just past it, or never, so that packets mix
// rays blocked and free and lanes leave the walk at different times; under every traversal
// build this CPU runs and every accel. Lanes left out are reported free.
TEST(InstanceIntersector, APacketOfShadowRaysIsBlockedWhereEachRayAloneIs) {
  std::vector<std::pair<std::string, Scene>> scenes = packet_scenes();
  const unsigned partial = 0b01101101u;
  for (auto& [name, built] : scenes) {
    const PreparedScene scene(std::move(built));
    std::vector<Ray> rays = packet_rays(scene, 29);
    {
      const auto reference = build_scene_intersector(scene, AccelKind::Bvh);
      for (std::size_t i = 0; i < rays.size(); ++i) {
        SurfaceHit hit;
        if (i % 3 == 2 || !reference->find_closest(rays[i], hit)) continue;  // every third: unbounded
        rays[i].t_max = i % 3 == 0 ? std::nextafter(hit.t, 0.0f) * 0.999f : hit.t * 1.001f;
      }
    }
    for (const AccelKind kind : {AccelKind::Bvh, AccelKind::BvhMedian, AccelKind::Naive}) {
      const auto ours = build_scene_intersector(scene, kind);
      for (const TraversalIsa isa : {TraversalIsa::Sse, TraversalIsa::Avx2, TraversalIsa::Avx512}) {
        if (!cpu_runs(isa)) continue;
        const ForcedTraversalIsa forced(isa);
        std::size_t blocked = 0, free = 0;
        for (std::size_t first = 0; first < rays.size(); first += 8) {
          const unsigned lanes = (first / 8) % 2 ? partial : 0xFFu;
          const unsigned packet = ours->occluded_packet(&rays[first], lanes);
          EXPECT_EQ(packet & ~lanes, 0u);
          for (std::size_t i = 0; i < 8; ++i) {
            if (!(lanes >> i & 1u)) continue;
            const bool alone = ours->occluded(rays[first + i]);
            ASSERT_EQ((packet >> i & 1u) != 0, alone)
                << name << ", " << to_string(kind) << ", " << to_string(isa) << ", ray " << first + i;
            ++(alone ? blocked : free);
          }
        }
        EXPECT_GT(blocked, rays.size() / 8) << name << ", " << to_string(kind) << ", " << to_string(isa);
        EXPECT_GT(free, rays.size() / 8) << name << ", " << to_string(kind) << ", " << to_string(isa);
      }
    }
  }
}

TEST(InstanceIntersector, EmptySceneIsNeverHit) {
  const PreparedScene scene{Scene{}};
  for (const AccelKind kind : {AccelKind::Bvh, AccelKind::BvhMedian, AccelKind::Naive}) {
    const auto ours = build_scene_intersector(scene, kind);
    SurfaceHit hit;
    EXPECT_FALSE(ours->closest_hit(Ray{}, hit));
    EXPECT_FALSE(ours->occluded(Ray{}));
  }
}

}  // namespace
}  // namespace farm
