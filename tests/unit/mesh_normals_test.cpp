#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include "renderer/scene/mesh.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

// Strips a fixture's normals and de-indexes it (one vertex per corner), as some loaders deliver.
Mesh without_normals_deindexed(const Mesh& m) {
  Mesh out;
  for (const glm::uvec3& t : m.triangles) {
    const auto base = static_cast<unsigned>(out.positions.size());
    for (int k = 0; k < 3; ++k) out.positions.push_back(m.positions[t[k]]);
    out.triangles.push_back({base, base + 1, base + 2});
  }
  return out;
}

TEST(MeshNormals, DeindexedSphereGetsSmoothNormalsCloseToTheTrueOnes) {
  Mesh mesh = without_normals_deindexed(test::make_sphere(16, 32).meshes[0]);
  generate_smooth_normals(mesh);
  ASSERT_EQ(mesh.normals.size(), mesh.positions.size());
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    EXPECT_NEAR(glm::length(mesh.normals[i]), 1.0f, 1e-5f);
    // The true normal of a unit sphere is the position itself; smoothing gets within a few degrees.
    EXPECT_GT(glm::dot(mesh.normals[i], glm::normalize(mesh.positions[i])), 0.99f) << i;
  }
}

TEST(MeshNormals, BoxKeepsHardEdgesAtItsCorners) {
  Mesh mesh = without_normals_deindexed(test::make_box({-1, -1, -1}, {1, 1, 1}).meshes[0]);
  generate_smooth_normals(mesh);
  for (const glm::uvec3& t : mesh.triangles) {
    const glm::vec3 face = glm::normalize(glm::cross(mesh.positions[t.y] - mesh.positions[t.x],
                                                     mesh.positions[t.z] - mesh.positions[t.x]));
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(glm::dot(mesh.normals[t[k]], face), 1.0f, 1e-5f);
  }
  EXPECT_EQ(mesh.positions.size(), 24u);  // 8 corners x 3 faces, welded within each face
}

}  // namespace
}  // namespace farm
