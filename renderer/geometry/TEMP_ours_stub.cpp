// TEMPORARY, deleted when the `embree` branch merges with the BVH branch: stand-ins for
// build_scene_intersector (instance_intersector.cpp) and complete_surface_hit (surface_hit.cpp)
// so this branch links. Only Embree is available here.
#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <stdexcept>

#include "renderer/geometry/embree_intersector.h"
#include "renderer/geometry/scene_intersector.h"
#include "renderer/prepared_scene.h"

namespace farm {

std::unique_ptr<SceneIntersector> build_scene_intersector(const PreparedScene& scene, AccelKind accel) {
  if (accel == AccelKind::Embree) return build_embree_intersector(scene);
  throw std::logic_error(fmt::format("build_scene_intersector({}): only Embree exists on this branch", to_string(accel)));
}

void complete_surface_hit(const PreparedScene& scene, const Ray& ray, SurfaceHit& hit) {
  const PreparedObject& object = scene.objects()[hit.object];
  const ModelTriangles& model = *object.triangles;
  const glm::uvec3 corners = model.triangles[hit.triangle];
  const glm::vec3 p0 = model.positions[corners.x], p1 = model.positions[corners.y],
                  p2 = model.positions[corners.z];
  const float w = 1.0f - hit.u - hit.v;
  hit.position = ray.at(hit.t);
  hit.geometric_normal = glm::normalize(object.normal_to_world * glm::cross(p1 - p0, p2 - p0));
  hit.shading_normal = glm::normalize(
      object.normal_to_world * (w * model.normals[corners.x] + hit.u * model.normals[corners.y] +
                                hit.v * model.normals[corners.z]));
  hit.material = &object.source->materials[model.material[hit.triangle]];
}

}  // namespace farm
