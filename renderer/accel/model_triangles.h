#pragma once
// One model's triangles flattened across its meshes, in model space: the numbering every ray
// acceleration structure (ours and Embree) and every hit uses. Triangle t of a model is
// triangles[t]; its corners index the concatenated positions and normals.
#include <cstdint>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#include <vector>

#include "renderer/geometry/aabb.h"
#include "renderer/scene/model.h"

namespace farm {

struct ModelTriangles {
  std::vector<glm::vec3> positions;    // all meshes' vertices, concatenated
  std::vector<glm::vec3> normals;      // one per position, unit (normalised here)
  std::vector<glm::vec2> uvs;          // one per position when any mesh has them (0 elsewhere), else none
  std::vector<glm::vec4> tangents;     // the same for tangent frames (Mesh::tangents)
  std::vector<glm::uvec3> triangles;   // indices into positions
  std::vector<std::uint32_t> material; // per triangle: index into Model::materials
  // Per triangle, the unit normal its winding gives, cross(b - a, c - a) of its corners a, b, c
  // normalised (zero for a triangle of no area, which no ray hits). Worked out once, so that a
  // hit reads it instead of its three corners and a square root.
  std::vector<glm::vec3> face_normals;
  // Per triangle, 1 when its three corners share one unit normal (a flat face: its shading
  // normal is that normal wherever it is hit, nothing to interpolate or normalise), else 0.
  // Empty when the model has no normals.
  std::vector<std::uint8_t> flat_shaded;
  AABB bounds;

  explicit ModelTriangles(const Model& model);
  std::size_t size() const { return triangles.size(); }
  AABB triangle_bounds(std::uint32_t t) const;
};

}  // namespace farm
