#include <cmath>
#include <glm/geometric.hpp>

#include "renderer/accel/prepared_scene.h"
#include "renderer/accel/scene_intersector.h"

namespace farm {

void complete_surface_hit(const PreparedScene& scene, const Ray& ray, SurfaceHit& hit) {
  const PreparedObject& object = scene.objects()[hit.object];
  const ModelTriangles& model = *object.triangles;
  const glm::uvec3& tri = model.triangles[hit.triangle];
  const glm::vec3 &p0 = model.positions[tri.x], &p1 = model.positions[tri.y],
                  &p2 = model.positions[tri.z];

  hit.position = ray.at(hit.t);
  // normal_to_world (inverse transpose) keeps the normal perpendicular to the world triangle
  // under non-uniform scale and on the same side of the surface under a mirroring transform.
  const glm::vec3 geometric = glm::normalize(object.normal_to_world * glm::cross(p1 - p0, p2 - p0));
  hit.geometric_normal = geometric;
  glm::vec3 shading = geometric;
  if (model.normals.size() == model.positions.size()) {
    const float w0 = 1.0f - hit.u - hit.v;
    const glm::vec3 n = w0 * model.normals[tri.x] + hit.u * model.normals[tri.y] +
                        hit.v * model.normals[tri.z];
    const glm::vec3 world = object.normal_to_world * n;
    // Opposed vertex normals can cancel; the geometric normal is the only sensible fallback.
    const float length = glm::length(world);
    if (length > 0.0f && std::isfinite(length)) shading = world / length;
  }
  hit.shading_normal = shading;
  hit.material = &object.source->materials[model.material[hit.triangle]];
}

}  // namespace farm
