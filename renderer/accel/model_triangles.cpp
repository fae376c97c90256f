#include "renderer/accel/model_triangles.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>

namespace farm {

ModelTriangles::ModelTriangles(const Model& model) {
  const bool any_uvs = std::any_of(model.meshes.begin(), model.meshes.end(),
                                   [](const Mesh& m) { return !m.uvs.empty(); });
  const bool any_tangents = std::any_of(model.meshes.begin(), model.meshes.end(),
                                        [](const Mesh& m) { return !m.tangents.empty(); });
  for (const Mesh& mesh : model.meshes) {
    const auto base = static_cast<std::uint32_t>(positions.size());
    positions.insert(positions.end(), mesh.positions.begin(), mesh.positions.end());
    normals.insert(normals.end(), mesh.normals.begin(), mesh.normals.end());
    if (any_uvs) {
      if (mesh.uvs.size() == mesh.positions.size()) {
        uvs.insert(uvs.end(), mesh.uvs.begin(), mesh.uvs.end());
      } else {
        uvs.resize(positions.size(), glm::vec2(0.0f));
      }
    }
    if (any_tangents) {
      if (mesh.tangents.size() == mesh.positions.size()) {
        tangents.insert(tangents.end(), mesh.tangents.begin(), mesh.tangents.end());
      } else {
        tangents.resize(positions.size(), glm::vec4(0.0f));
      }
    }
    for (const glm::uvec3& t : mesh.triangles) {
      triangles.push_back(t + glm::uvec3(base));
      material.push_back(mesh.material);
    }
  }
  for (const glm::vec3& p : positions) bounds.grow(p);
  for (glm::vec3& n : normals) {
    const float length = glm::length(n);
    if (length > 0.0f && std::isfinite(length)) n *= 1.0f / length;
  }
  if (normals.size() == positions.size()) {
    flat_shaded.reserve(triangles.size());
    for (const glm::uvec3& t : triangles) {
      const glm::vec3& n = normals[t.x];
      const bool unit = glm::length(n) > 0.5f;  // normalised above; not zero, not NaN
      flat_shaded.push_back(unit && n == normals[t.y] && n == normals[t.z] ? 1 : 0);
    }
  }
  face_normals.reserve(triangles.size());
  for (const glm::uvec3& t : triangles) {
    const glm::vec3& a = positions[t.x];
    const glm::vec3 winding = glm::cross(positions[t.y] - a, positions[t.z] - a);
    const float length = glm::length(winding);
    face_normals.push_back(length > 0.0f && std::isfinite(length) ? winding * (1.0f / length) : glm::vec3(0.0f));
  }
}

AABB ModelTriangles::triangle_bounds(std::uint32_t t) const {
  AABB box;
  const glm::uvec3& tri = triangles[t];
  box.grow(positions[tri.x]);
  box.grow(positions[tri.y]);
  box.grow(positions[tri.z]);
  return box;
}

}  // namespace farm
