#include "renderer/trace/emitter_facing.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <map>
#include <utility>

#include "renderer/accel/prepared_scene.h"
#include "renderer/accel/scene_intersector.h"
#include "renderer/trace/ray_offset.h"
#include "renderer/trace/sample_warp.h"

namespace farm {
namespace {

// Bounds on the work, so a huge scene is checked in a moment: emissive triangles checked per
// group and in all, and rays per side of each (a kGrid x kGrid stratified pattern).
constexpr std::size_t kMaxCheckedPerGroup = 64;
constexpr std::size_t kMaxCheckedInAll = 2048;
constexpr int kGrid = 4;
// A group whose area-weighted normals sum to less than this fraction of its area is closed.
constexpr double kClosedBelow = 0.5;
// An open emitter faces away when its front's mean free distance is below this fraction of its
// back's.
constexpr double kHemmedIn = 0.25;

struct EmissiveTriangle {
  glm::vec3 p0, e1, e2;  // world corner and edges
  glm::vec3 normal;      // unit, world: the front, as complete_surface_hit gives it
  float area;
};

// What the rays from one side of some emissive triangles met.
struct Side {
  std::size_t rays = 0, hits = 0;
  double distance = 0.0;  // summed; a miss adds the scene's diagonal
  double mean() const { return rays > 0 ? distance / static_cast<double>(rays) : 0.0; }
};

// An open emitter (a panel).
bool panel_faces_away(const Side& front, const Side& back) {
  if (back.hits == 0) return false;  // nothing behind it: whatever it faces, it is not away
  if (front.hits == 0) return true;  // it shines into the void with the scene behind it
  return front.mean() < kHemmedIn * back.mean();
}

// A closed emitter, whose back is its own inside: it faces away when its normals point inwards,
// its front the more hemmed-in side. Alone in the scene, one side meets nothing, and which way
// it should face cannot be told (a glowing ball, or a dome around the scene).
bool closed_faces_away(const Side& front, const Side& back) {
  return front.hits > 0 && back.hits > 0 && front.mean() < back.mean();
}

// Both hemispheres of `t` as seen from kGrid^2 points on it, one cosine-weighted direction each.
// Rays whose first hit `skip` accepts are left out.
template <typename Skip>
void trace_both_sides(const SceneIntersector& intersector, const EmissiveTriangle& t,
                      float diagonal, Skip&& skip, Side& front, Side& back) {
  const glm::vec3& n = t.normal;
  const ShadingFrame frame(n);
  for (int i = 0; i < kGrid; ++i) {
    for (int j = 0; j < kGrid; ++j) {
      const float u1 = (static_cast<float>(i) + 0.5f) / kGrid, u2 = (static_cast<float>(j) + 0.5f) / kGrid;
      // The point: uniform on the triangle, from the pattern read the other way round so that
      // points and directions do not line up.
      const glm::vec2 w = uniform_triangle_weights(u2, u1);
      const glm::vec3 p = t.p0 + w.x * t.e1 + w.y * t.e2;
      // The direction: cosine-weighted about the normal, on the side being looked at.
      const glm::vec3 local = cosine_hemisphere(u1, u2);
      for (const float side : {1.0f, -1.0f}) {
        const glm::vec3 d = frame.to_world({local.x, local.y, side * local.z});
        Ray ray{offset_ray_origin(p, n, d), d};
        SurfaceHit hit;
        Side& out = side > 0.0f ? front : back;
        const bool hit_something = intersector.closest_hit(ray, hit);
        if (hit_something && skip(hit)) continue;
        ++out.rays;
        if (hit_something) {
          ++out.hits;
          out.distance += hit.t;
        } else {
          out.distance += diagonal;
        }
      }
    }
  }
}

}  // namespace

std::vector<EmitterFacingAway> find_emitters_facing_away(const PreparedScene& scene) {
  // The front-only emissive triangles, by (object, material), in scene order.
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::size_t> group_of;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> keys;
  std::vector<std::vector<EmissiveTriangle>> groups;
  AABB bounds;
  for (std::uint32_t o = 0; o < scene.objects().size(); ++o) {
    const PreparedObject& object = scene.objects()[o];
    const ModelTriangles& mesh = *object.triangles;
    for (std::uint32_t t = 0; t < mesh.size(); ++t) {
      const glm::uvec3& tri = mesh.triangles[t];
      const auto world = [&](std::uint32_t i) {
        return glm::vec3(object.model_to_world * glm::vec4(mesh.positions[i], 1.0f));
      };
      const glm::vec3 p0 = world(tri.x), p1 = world(tri.y), p2 = world(tri.z);
      bounds.grow(p0);
      bounds.grow(p1);
      bounds.grow(p2);
      const Material& material = object.source->materials[mesh.material[t]];
      const float most = std::max({material.emission.x, material.emission.y, material.emission.z});
      if (!(most > 0.0f) || !std::isfinite(most) || material.emission_sides != EmissionSides::Front) continue;
      EmissiveTriangle e{p0, p1 - p0, p2 - p0, glm::vec3(0.0f), 0.0f};
      e.area = 0.5f * glm::length(glm::cross(e.e1, e.e2));
      e.normal = glm::normalize(object.normal_to_world * mesh.face_normals[t]);
      if (!(e.area > 0.0f) || !std::isfinite(e.normal.x)) continue;
      const auto [it, added] = group_of.emplace(std::make_pair(o, mesh.material[t]), groups.size());
      if (added) {
        keys.push_back(it->first);
        groups.emplace_back();
      }
      groups[it->second].push_back(e);
    }
  }
  if (groups.empty()) return {};
  const auto intersector = cached_scene_intersector(scene, AccelKind::Bvh);
  const float diagonal = std::max(1e-6f, glm::length(bounds.extent()));
  const std::size_t per_group = std::clamp<std::size_t>(kMaxCheckedInAll / groups.size(), 1, kMaxCheckedPerGroup);

  std::vector<EmitterFacingAway> out;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const std::vector<EmissiveTriangle>& group = groups[g];
    const SceneObject& object = *scene.objects()[keys[g].first].source;
    EmitterFacingAway report{object.name, object.materials.at(keys[g].second).name, 0, 0};
    double area = 0.0;
    glm::dvec3 normals(0.0);
    for (const EmissiveTriangle& t : group) {
      area += t.area;
      normals += glm::dvec3(t.normal) * static_cast<double>(t.area);
    }
    const bool closed = glm::length(normals) < kClosedBelow * area;
    report.checked = std::min(group.size(), per_group);
    // A panel is judged by what lies around it: rays that meet the group itself (the rest of a
    // glowing open shell, seen from inside) say nothing about that. A closed group's back is its
    // own inside, which is what tells its sides apart.
    const auto [object_index, material_index] = keys[g];
    const ModelTriangles& mesh = *scene.objects()[object_index].triangles;
    // Init-captures: clang before 16 cannot capture structured bindings (the fuzz preset's clang-14).
    const auto own = [&, object = object_index, material = material_index](const SurfaceHit& hit) {
      return !closed && hit.object == object && mesh.material[hit.triangle] == material;
    };
    Side front_of_all, back_of_all;
    for (std::size_t k = 0; k < report.checked; ++k) {
      Side front, back;
      trace_both_sides(*intersector, group[k * group.size() / report.checked], diagonal, own, front, back);
      if (!closed && panel_faces_away(front, back)) ++report.facing_away;
      front_of_all.rays += front.rays;
      front_of_all.hits += front.hits;
      front_of_all.distance += front.distance;
      back_of_all.rays += back.rays;
      back_of_all.hits += back.hits;
      back_of_all.distance += back.distance;
    }
    if (closed && closed_faces_away(front_of_all, back_of_all)) report.facing_away = report.checked;
    if (report.facing_away > 0) out.push_back(std::move(report));
  }
  return out;
}

}  // namespace farm
