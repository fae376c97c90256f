#include "renderer/scene/mesh.h"

#include <glm/geometric.hpp>
#include <map>
#include <tuple>

namespace farm {

AABB Mesh::bounds() const {
  AABB box;
  for (const glm::vec3& p : positions) box.grow(p);
  return box;
}

void generate_smooth_normals(Mesh& mesh) {
  // Weld by exact position so split vertices (a de-indexed mesh) share their normal.
  auto key = [](const glm::vec3& p) { return std::make_tuple(p.x, p.y, p.z); };
  std::map<std::tuple<float, float, float>, glm::vec3> accumulated;
  for (const glm::uvec3& t : mesh.triangles) {
    const glm::vec3 &a = mesh.positions[t.x], &b = mesh.positions[t.y], &c = mesh.positions[t.z];
    const glm::vec3 area_weighted = glm::cross(b - a, c - a);  // length = 2 * area
    for (unsigned i : {t.x, t.y, t.z}) accumulated[key(mesh.positions[i])] += area_weighted;
  }
  mesh.normals.assign(mesh.positions.size(), glm::vec3(0.0f, 0.0f, 1.0f));
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    auto it = accumulated.find(key(mesh.positions[i]));
    if (it == accumulated.end()) continue;
    const float len = glm::length(it->second);
    if (len > 0.0f) mesh.normals[i] = it->second / len;
  }
}

}  // namespace farm
