#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include "renderer/accel/prepared_scene.h"
#include "renderer/accel/scene_intersector.h"
#include "renderer/texture/material_textures.h"

namespace farm {

namespace {

// A normal map bends the shading normal in the hit's tangent frame, carried to world space by the
// object's transform (a tangent lies in the surface), its handedness flipped with a mirror. Kept
// out of line: every untextured hit passes by it.
[[gnu::noinline]] void bend_by_normal_map(const PreparedObject& object, const ModelTriangles& model,
                                          const glm::uvec3& tri, SurfaceHit& hit) {
  const MaterialTextures& textures = *hit.material->textures;
  if (!textures.normal) return;
  const float w0 = 1.0f - hit.u - hit.v;
  const glm::vec4 t = w0 * model.tangents[tri.x] + hit.u * model.tangents[tri.y] + hit.v * model.tangents[tri.z];
  const glm::mat3 linear(object.model_to_world);
  const float w = (t.w < 0.0f) != (glm::determinant(linear) < 0.0f) ? -1.0f : 1.0f;
  hit.shading_normal = mapped_normal(textures, hit.uv, hit.shading_normal, glm::vec4(linear * glm::vec3(t), w));
}

}  // namespace

void complete_surface_hit(const PreparedScene& scene, const Ray& ray, SurfaceHit& hit) {
  const PreparedObject& object = scene.objects()[hit.object];
  const ModelTriangles& model = *object.triangles;
  const glm::uvec3& tri = model.triangles[hit.triangle];

  hit.position = ray.at(hit.t);
  // normal_to_world (inverse transpose) keeps the normal perpendicular to the world triangle
  // under non-uniform scale and on the same side of the surface under a mirroring transform.
  const glm::vec3& face = model.face_normals[hit.triangle];
  const glm::vec3 geometric = object.normals_untransformed ? face : glm::normalize(object.normal_to_world * face);
  hit.geometric_normal = geometric;
  glm::vec3 shading = geometric;
  if (model.normals.size() == model.positions.size()) {
    const bool flat = model.flat_shaded[hit.triangle] != 0;
    if (flat && object.normals_untransformed) {
      shading = model.normals[tri.x];  // unit, the same at all three corners
    } else {
      glm::vec3 n = model.normals[tri.x];
      if (!flat) {
        const float w0 = 1.0f - hit.u - hit.v;
        n = w0 * n + hit.u * model.normals[tri.y] + hit.v * model.normals[tri.z];
      }
      const glm::vec3 world = object.normals_untransformed ? n : object.normal_to_world * n;
      // Opposed vertex normals can cancel; the geometric normal is the only sensible fallback.
      const float length = glm::length(world);
      if (length > 0.0f && std::isfinite(length)) shading = world / length;
    }
  }
  hit.shading_normal = shading;
  if (!model.uvs.empty()) {
    const float w0 = 1.0f - hit.u - hit.v;
    hit.uv = w0 * model.uvs[tri.x] + hit.u * model.uvs[tri.y] + hit.v * model.uvs[tri.z];
  }
  hit.material = &object.source->materials[model.material[hit.triangle]];
  if (hit.material->textures && !model.tangents.empty()) bend_by_normal_map(object, model, tri, hit);
}

float texture_footprint(const PreparedScene& scene, const SurfaceHit& hit, const glm::vec3& ray_direction,
                        float cone_width) {
  const PreparedObject& object = scene.objects()[hit.object];
  const ModelTriangles& model = *object.triangles;
  if (model.uvs.empty() || !(cone_width > 0.0f)) return 0.0f;
  const glm::uvec3& tri = model.triangles[hit.triangle];
  const auto world = [&](std::uint32_t i) {
    return glm::vec3(object.model_to_world * glm::vec4(model.positions[i], 1.0f));
  };
  const glm::vec3 p0 = world(tri.x);
  const float world_area = glm::length(glm::cross(world(tri.y) - p0, world(tri.z) - p0));
  const glm::vec2 a = model.uvs[tri.y] - model.uvs[tri.x], b = model.uvs[tri.z] - model.uvs[tri.x];
  const float uv_area = std::fabs(a.x * b.y - a.y * b.x);
  if (!(world_area > 0.0f) || !(uv_area > 0.0f)) return 0.0f;
  // At grazing incidence the footprint grows without bound; a tenth keeps it to ten widths.
  const float incidence = std::max(0.1f, std::fabs(glm::dot(glm::normalize(ray_direction), hit.geometric_normal)));
  const float footprint = cone_width / incidence * std::sqrt(uv_area / world_area);
  return std::isfinite(footprint) ? footprint : 0.0f;
}

const Material& textured_hit_material(const PreparedScene& scene, const glm::vec3& ray_direction,
                                      const SurfaceHit& hit, float cone_width, Material& scratch) {
  return material_at(*hit.material, hit.uv, texture_footprint(scene, hit, ray_direction, cone_width), scratch);
}

}  // namespace farm
