// generate_tangents: the frames a normal map is read in when the file gives none, built the way
// MikkTSpace builds them (mesh.h): a mirrored island's seam split so each side keeps its own
// frame, and corners weighted by their angle, not by their triangle's size or uv scale.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <numbers>
#include <vector>

#include "renderer/scene/mesh.h"

namespace farm {
namespace {

glm::vec3 bitangent(const Mesh& m, std::uint32_t i) {
  return m.tangents[i].w * glm::cross(m.normals[i], glm::vec3(m.tangents[i]));
}

// A plane on z = 0 whose texture is mirrored about x = 0 (u = |x|, as artists map symmetric
// models to save texture space), v falling as y grows; the seam's vertices are shared. Each
// side's triangles must see u's direction on their own side (+x right, -x left) and the bitangent
// up (+y) on both; summed across the seam, u's directions would cancel there.
TEST(MeshTangents, AMirroredIslandsSeamIsSplitAndEachSideKeepsItsFrame) {
  Mesh m;
  m.positions = {{-1, -1, 0}, {0, -1, 0}, {1, -1, 0}, {-1, 1, 0}, {0, 1, 0}, {1, 1, 0}};
  for (const glm::vec3& p : m.positions) {
    m.normals.emplace_back(0, 0, 1);
    m.uvs.emplace_back(std::fabs(p.x), (1.0f - p.y) / 2.0f);
  }
  m.triangles = {{0, 1, 4}, {0, 4, 3}, {1, 2, 5}, {1, 5, 4}};
  std::vector<glm::vec3> corners;  // where each triangle's corners were, to hold the split to
  for (const glm::uvec3& t : m.triangles)
    for (int k = 0; k < 3; ++k) corners.push_back(m.positions[t[k]]);
  generate_tangents(m);
  ASSERT_EQ(m.positions.size(), 8u) << "the two seam vertices split";
  ASSERT_EQ(m.tangents.size(), m.positions.size());
  for (std::size_t f = 0; f < m.triangles.size(); ++f) {
    const bool right = f >= 2;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t i = m.triangles[f][k];
      EXPECT_EQ(m.positions[i], corners[f * 3 + static_cast<std::size_t>(k)]);
      EXPECT_NEAR(m.tangents[i].x, right ? 1.0f : -1.0f, 1e-6f) << "triangle " << f << " corner " << k;
      EXPECT_NEAR(bitangent(m, i).y, 1.0f, 1e-6f) << "triangle " << f << " corner " << k;
    }
  }
}

// Two triangles on z = 0 meet at the origin with corners of 90 and 45 degrees; their uv maps
// differ (u along +x on one, along +y on the other, the second stretched 5 times). The origin's
// tangent is the angle-weighted mean of the two unit directions, 2:1, whatever the stretch
// (summing area-weighted, unnormalised directions, the classic way, would lean on the stretch).
TEST(MeshTangents, CornersAreWeightedByTheirAngleNotByTheirTrianglesSizeOrUvScale) {
  Mesh m;
  const float s = std::numbers::sqrt2_v<float> / 2.0f;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 1, 0}, {-s, s, 0}};
  // Triangle 0 (0, 1, 2): a 90 degree corner at the origin, u = x, v = y.
  // Triangle 1 (0, 3, 4): a 45 degree corner there, u = 5 y (its own copy of (0, 1) holds it).
  m.uvs = {{0, 0}, {1, 0}, {0, 1}, {5, 0}, {5 * s, 5 * s}};
  for (std::size_t i = 0; i < m.positions.size(); ++i) m.normals.emplace_back(0, 0, 1);
  m.triangles = {{0, 1, 2}, {0, 3, 4}};
  generate_tangents(m);
  ASSERT_EQ(m.positions.size(), 5u);
  // Triangle 1's u: e = du U + dv V with (0,1,0) -> (5, 0) and (-s, s, 0) -> (5s, 5s): U = (0, 0.2, 0) (+y).
  const glm::vec3 expected = glm::normalize(static_cast<float>(std::numbers::pi / 2) * glm::vec3(1, 0, 0) +
                                            static_cast<float>(std::numbers::pi / 4) * glm::vec3(0, 1, 0));
  EXPECT_NEAR(m.tangents[0].x, expected.x, 1e-5f);
  EXPECT_NEAR(m.tangents[0].y, expected.y, 1e-5f);
}

}  // namespace
}  // namespace farm
