// complete_surface_hit (renderer/accel/surface_hit.cpp) against the normals worked out again in
// double from the model: flat faces (read, not interpolated, where the object is untransformed)
// and smooth ones, on objects placed as they are and rotated, scaled non-uniformly and mirrored.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <memory>
#include <vector>

#include "renderer/accel/instance_intersector.h"
#include "renderer/accel/prepared_scene.h"
#include "tests/support/ray_fixtures.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

glm::dvec3 unit(const glm::dvec3& v) { return v / glm::length(v); }

TEST(SurfaceHit, FlatAndSmoothNormalsAreTheModelsCarriedToWorldSpace) {
  const auto box = std::make_shared<const Model>(test::make_box({-0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, 0.5f}));
  const auto sphere = std::make_shared<const Model>(test::make_sphere(10, 20));
  Scene scene;
  scene.objects.push_back(test::object_of(*box, test::placed({-1.5f, 0.0f, 0.0f}, {0, 1, 0}, 0.0f, {1, 1, 1})));
  scene.objects.push_back(test::object_of(*box, test::placed({1.5f, 0.2f, 0.0f}, {1, 1, 0}, 35.0f, {-0.7f, 1.6f, 0.9f})));
  scene.objects.push_back(test::object_of(*sphere, test::placed({0.0f, 0.0f, 2.0f}, {0, 1, 0}, 0.0f, {1, 1, 1})));
  scene.objects.push_back(test::object_of(*sphere, test::placed({0.0f, 1.8f, -1.0f}, {0, 0, 1}, -50.0f, {1.4f, -0.5f, 0.8f})));
  const PreparedScene prepared(std::move(scene));
  ASSERT_TRUE(prepared.objects()[0].normals_untransformed);
  ASSERT_FALSE(prepared.objects()[1].normals_untransformed);
  ASSERT_TRUE(prepared.objects()[2].normals_untransformed);
  // The box's faces are flat; the sphere's smooth triangles are not.
  const ModelTriangles& box_triangles = *prepared.objects()[0].triangles;
  const ModelTriangles& sphere_triangles = *prepared.objects()[2].triangles;
  for (const std::uint8_t flat : box_triangles.flat_shaded) EXPECT_EQ(flat, 1);
  std::size_t sphere_flat = 0;
  for (const std::uint8_t flat : sphere_triangles.flat_shaded) sphere_flat += flat;
  EXPECT_LT(sphere_flat, sphere_triangles.size() / 10);

  AABB bounds;
  for (const PreparedObject& o : prepared.objects()) {
    for (const glm::vec3& p : o.triangles->positions) bounds.grow(glm::vec3(o.model_to_world * glm::vec4(p, 1.0f)));
  }
  const auto intersector = build_instance_intersector(prepared, AccelKind::Bvh, CancelFlag{});
  std::size_t hits[4] = {};
  for (const Ray& ray : test::random_rays(bounds, 20000, 3)) {
    SurfaceHit hit;
    if (!intersector->closest_hit(ray, hit)) continue;
    ++hits[hit.object];
    const PreparedObject& object = prepared.objects()[hit.object];
    const ModelTriangles& model = *object.triangles;
    const glm::uvec3& tri = model.triangles[hit.triangle];
    const glm::dmat3 to_world = glm::transpose(glm::inverse(glm::dmat3(glm::dmat4(object.model_to_world))));
    const glm::dvec3 a(model.positions[tri.x]), b(model.positions[tri.y]), c(model.positions[tri.z]);
    const glm::dvec3 geometric = unit(to_world * glm::cross(b - a, c - a));
    const double w0 = 1.0 - hit.u - hit.v;
    const glm::dvec3 smooth = w0 * glm::dvec3(model.normals[tri.x]) + double(hit.u) * glm::dvec3(model.normals[tri.y]) +
                              double(hit.v) * glm::dvec3(model.normals[tri.z]);
    const glm::dvec3 shading = unit(to_world * smooth);
    EXPECT_LT(glm::length(glm::dvec3(hit.geometric_normal) - geometric), 2e-6) << "object " << hit.object;
    EXPECT_LT(glm::length(glm::dvec3(hit.shading_normal) - shading), 2e-6) << "object " << hit.object;
  }
  for (const std::size_t n : hits) EXPECT_GT(n, 200u);
}

}  // namespace
}  // namespace farm
