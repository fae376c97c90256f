#pragma once
// Ray queries against a whole prepared scene in world space: what the ray engines call. Ours
// is a top-level BVH over object instances, each pointing at its model's bottom-level structure
// (the ray is carried into model space, so an object's BVH is built once per model); the other
// implementation is Embree, with the same triangle numbering, for validation and as a backend.
#include <cstdint>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <memory>
#include <string_view>

#include "renderer/geometry/ray.h"
#include "renderer/geometry/traversal_stats.h"
#include "renderer/geometry/accel_kind.h"
#include "renderer/scene/material.h"
#include "renderer/util/cancel_flag.h"

namespace farm {

class PreparedScene;

struct SurfaceHit {
  float t = 0.0f;                // along the world ray, in units of its direction
  std::uint32_t object = 0;      // index into the scene's objects
  std::uint32_t triangle = 0;    // index into that object's ModelTriangles
  float u = 0.0f, v = 0.0f;      // barycentric weights of corners 1 and 2
  glm::vec3 position{0.0f};      // world space
  glm::vec3 geometric_normal{0.0f};  // world, unit, as the triangle's winding gives it
  glm::vec3 shading_normal{0.0f};    // world, unit, interpolated vertex normals
  glm::vec2 uv{0.0f};                // texture coordinates, interpolated (0 where the model has none)
  const Material* material = nullptr;
};

class SceneIntersector {
 public:
  virtual ~SceneIntersector() = default;
  // Nearest hit with t in (ray.t_min, ray.t_max), completed into a SurfaceHit.
  virtual bool closest_hit(const Ray& ray, SurfaceHit& hit, TraversalStats* stats = nullptr) const = 0;
  // The nearest hit as the structure finds it: t, object, triangle, u and v, the rest of `hit`
  // default (closest_hit is this and complete_surface_hit). What a caller needing no more than
  // the hit asks; farm bench rt times it against Embree called directly, which does no more.
  virtual bool find_closest(const Ray& ray, SurfaceHit& hit, TraversalStats* stats = nullptr) const {
    return closest_hit(ray, hit, stats);
  }
  // find_closest for up to 8 rays at once, rays[i] for each bit i of `lanes` (hits[i] filled
  // for the lanes returned, which are those hit): the same hits, bit for bit, as find_closest
  // ray by ray, which this one asks. Ours walks a packet's rays through each BVH together
  // (Bvh::closest_packet): coherent rays (a block of camera rays) share the nodes' loads and tests.
  virtual unsigned find_closest_packet(const Ray* rays, unsigned lanes, SurfaceHit* hits) const;
  // closest_hit for such a packet: each hit completed, the same bits as closest_hit ray by ray
  // (which this one asks). What the engines trace a pixel's camera rays with.
  virtual unsigned closest_hit_packet(const Ray* rays, unsigned lanes, SurfaceHit* hits) const;
  // Whether anything blocks the ray within (ray.t_min, ray.t_max): shadow rays.
  virtual bool occluded(const Ray& ray, TraversalStats* stats = nullptr) const = 0;
  // occluded for up to 8 rays at once (rays[i] for each bit i of `lanes`): returns the lanes
  // blocked, each ray's answer occluded's (which this one asks ray by ray). Ours walks the rays
  // through each BVH together (Bvh::any_packet): shadow rays from a pixel's hits toward one light.
  virtual unsigned occluded_packet(const Ray* rays, unsigned lanes) const;
};

// Builds the intersector for `accel` (Embree included), polling `cancel` as it goes: throws
// RenderStopped when it asks.
std::unique_ptr<SceneIntersector> build_scene_intersector(const PreparedScene& scene, AccelKind accel,
                                                          const CancelFlag& cancel = CancelFlag::never());

// The same, built once per prepared scene and accel and then shared by every tile (cached in
// the scene's frame cache).
std::shared_ptr<const SceneIntersector> cached_scene_intersector(
    const PreparedScene& scene, AccelKind accel, const CancelFlag& cancel = CancelFlag::never());

// Fills position, normals and material of a hit given (object, triangle, u, v, t): shared by
// every implementation so they agree on everything but the hit itself.
void complete_surface_hit(const PreparedScene& scene, const Ray& ray, SurfaceHit& hit);

// How much of the texture a pixel's footprint spans at a hit (Texture::sample's footprint), for a
// ray cone `cone_width` wide there across the ray: the width stretched by the incidence, times the
// triangle's uv length per world length (the square root of its uv area over its world area).
// 0 when the hit's model has no texture coordinates or the triangle none to speak of.
float texture_footprint(const PreparedScene& scene, const SurfaceHit& hit, const glm::vec3& ray_direction,
                        float cone_width);

// The material a hit is shaded with (material_at): its own when it has no textures, else `scratch`
// holding it with its textures read at the hit's uv over a ray cone `cone_width` wide there (0: the
// textures' finest level).
const Material& textured_hit_material(const PreparedScene& scene, const glm::vec3& ray_direction,
                                      const SurfaceHit& hit, float cone_width, Material& scratch);
// Inline, so that an untextured hit (every Phong scene's) costs the engines no call.
inline const Material& hit_material(const PreparedScene& scene, const glm::vec3& ray_direction, const SurfaceHit& hit,
                                    float cone_width, Material& scratch) {
  return hit.material->textures ? textured_hit_material(scene, ray_direction, hit, cone_width, scratch)
                                : *hit.material;
}

}  // namespace farm
