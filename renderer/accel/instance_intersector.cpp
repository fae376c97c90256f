#include "renderer/accel/instance_intersector.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>
#include <xmmintrin.h>

#include "renderer/accel/cutout_intersector.h"
#include "renderer/accel/embree_intersector.h"
#include "renderer/accel/prepared_scene.h"
#include "renderer/geometry/bvh.h"
#include "renderer/geometry/ray_hit_order.h"

namespace farm {
namespace {

// How far below a model's BVH root the boxes lie that an instance's world box is made of when
// its vertices are too many to carry over (InstanceIntersector::kExactBoxVertices): up to four
// boxes, 32 corners an instance.
constexpr int kInstanceBoxLevels = 2;

// A matrix's columns in SSE registers, carrying points and directions as glm's operators do:
// each lane makes their products and sums in their order (a point: (c0 x + c1 y) + (c2 z + c3),
// c3 times w = 1 being c3; a direction: (c0 x + c1 y) + c2 z), so the same bits as
// `m * vec4(p, 1)` and `mat3(m) * d`, which glm works out one scalar at a time (66 instructions
// for both, an instance a ray entered, callgrind, the 100-cow grid). Lane 3 is not used.
class SseColumns {
 public:
  explicit SseColumns(const glm::mat4& m)
      : c0_(_mm_loadu_ps(&m[0][0])), c1_(_mm_loadu_ps(&m[1][0])), c2_(_mm_loadu_ps(&m[2][0])),
        c3_(_mm_loadu_ps(&m[3][0])) {}
  __m128 point(const glm::vec3& p) const {
    return _mm_add_ps(first_two(p), _mm_add_ps(_mm_mul_ps(c2_, _mm_set1_ps(p.z)), c3_));
  }
  __m128 direction(const glm::vec3& d) const { return _mm_add_ps(first_two(d), _mm_mul_ps(c2_, _mm_set1_ps(d.z))); }

 private:
  __m128 first_two(const glm::vec3& v) const {
    return _mm_add_ps(_mm_mul_ps(c0_, _mm_set1_ps(v.x)), _mm_mul_ps(c1_, _mm_set1_ps(v.y)));
  }
  __m128 c0_, c1_, c2_, c3_;
};

glm::vec3 first_three(__m128 v) {
  alignas(16) float lanes[4];
  _mm_store_ps(lanes, v);
  return {lanes[0], lanes[1], lanes[2]};
}

// The boxes of a model's BVH down to `levels` below its root (a leaf above that counts as it
// is): together they hold every triangle, more tightly than the root's box alone.
std::vector<AABB> frontier_boxes(const MeshAccel& accel, const AABB& whole, int levels) {
  const Bvh* bvh = accel.bvh();
  if (!bvh || bvh->nodes().empty()) return {whole};
  std::vector<AABB> out;
  std::vector<std::pair<std::uint32_t, int>> stack{{0u, 0}};
  while (!stack.empty()) {
    const auto [index, level] = stack.back();
    stack.pop_back();
    const BvhNode& node = bvh->nodes()[index];
    if (node.count != 0 || level == levels) {
      out.push_back(node.bounds);
      continue;
    }
    stack.push_back({node.offset, level + 1});
    stack.push_back({index + 1, level + 1});
  }
  return out;
}

// An object's world box: the union of its model's frontier boxes, each carried to the world by
// its eight corners. A turned object's box is tighter this way than its model box's
// corners carried over (the top level then sends fewer rays into an instance that they miss).
AABB world_bounds(const PreparedObject& object, const std::vector<AABB>& model_boxes) {
  AABB world;
  if (object.triangles->bounds.empty()) return world;
  for (const AABB& box : model_boxes) world.grow(transformed(box, object.model_to_world));
  return world;
}

// An object's world box as the box of its model's vertices carried to the world, grown by
// 2^-16 of its largest coordinate: the query carries the ray to the model instead, each rounding
// its own way, and a box that only just held the vertices could cut off a hit grazing one.
AABB vertex_world_bounds(const PreparedObject& object) {
  AABB world;
  if (object.triangles->bounds.empty()) return world;
  const SseColumns to_world(object.model_to_world);
  __m128 low = _mm_set1_ps(std::numeric_limits<float>::infinity()), high = _mm_sub_ps(_mm_setzero_ps(), low);
  for (const glm::vec3& p : object.triangles->positions) {
    const __m128 w = to_world.point(p);
    low = _mm_min_ps(low, w);
    high = _mm_max_ps(high, w);
  }
  world.min = first_three(low);
  world.max = first_three(high);
  const glm::vec3 largest = glm::max(glm::abs(world.min), glm::abs(world.max));
  const float margin = std::ldexp(std::max({largest.x, largest.y, largest.z}), -16);
  world.min -= margin;
  world.max += margin;
  return world;
}

// The ray in the object's model space (SseColumns: glm's bits). The direction is deliberately
// NOT renormalised: then world_to_model(origin + t*d) = origin' + t*d' for the same t, so hit
// distances compare across objects and stay right under non-uniform scale, with no conversion back.
Ray to_model(const glm::mat4& world_to_model, const Ray& ray, float t_max) {
  const SseColumns to_model_space(world_to_model);
  Ray local;
  local.origin = first_three(to_model_space.point(ray.origin));
  local.direction = first_three(to_model_space.direction(ray.direction));
  local.t_min = ray.t_min;
  local.t_max = t_max;
  return local;
}

}  // namespace

InstanceIntersector::InstanceIntersector(const PreparedScene& scene, AccelKind accel,
                                         const CancelFlag& cancel)
    : scene_(scene) {
  if (accel == AccelKind::Embree) {
    throw std::invalid_argument("InstanceIntersector: use build_embree_intersector for embree");
  }
  const std::vector<PreparedObject>& objects = scene.objects();
  std::map<const ModelTriangles*, const MeshAccel*> accel_of;
  object_accel_.reserve(objects.size());
  for (const PreparedObject& object : objects) {
    const MeshAccel*& shared = accel_of[object.triangles];
    if (!shared) {
      mesh_accels_.push_back(scene.geometry().mesh_accel(*object.triangles, accel, cancel));
      shared = mesh_accels_.back().get();
    }
    object_accel_.push_back(shared);
  }
  if (accel != AccelKind::Naive) {
    std::map<const ModelTriangles*, std::size_t> vertices_carried;  // per model, over its instances
    for (const PreparedObject& object : objects) vertices_carried[object.triangles] += object.triangles->positions.size();
    std::vector<AABB> bounds;
    bounds.reserve(objects.size());
    std::map<const MeshAccel*, std::vector<AABB>> boxes_of;
    for (std::size_t o = 0; o < objects.size(); ++o) {
      if (vertices_carried[objects[o].triangles] <= kExactBoxVertices) {
        bounds.push_back(vertex_world_bounds(objects[o]));
        continue;
      }
      std::vector<AABB>& boxes = boxes_of[object_accel_[o]];
      if (boxes.empty()) boxes = frontier_boxes(*object_accel_[o], objects[o].triangles->bounds, kInstanceBoxLevels);
      bounds.push_back(world_bounds(objects[o], boxes));
    }
    // One instance per leaf: an instance test is a whole bottom-level traversal.
    top_ = Bvh::build(bounds, Bvh::Options{BvhSplit::Sah, 1, &cancel});
    one_object_ = objects.size() == 1;
    one_object_untransformed_ = one_object_ && objects[0].world_to_model == glm::mat4(1.0f);
  }
  std::vector<std::uint32_t> in_order(objects.size());
  for (std::uint32_t o = 0; o < objects.size(); ++o) in_order[o] = o;
  // A scene of one object is queried without its top level (which holds it if its box is not empty).
  if (top_ && !one_object_) in_order = top_->order();
  placements_.reserve(in_order.size());
  for (const std::uint32_t o : in_order) placements_.push_back(Placement{objects[o].world_to_model, object_accel_[o], o});
}

bool InstanceIntersector::closest_in(const Placement& placement, const Ray& world_ray, float t_max,
                                     TriangleHit& hit, TraversalStats* stats) {
  return placement.accel->closest_hit(to_model(placement.world_to_model, world_ray, t_max), hit, stats);
}

bool InstanceIntersector::any_in(const Placement& placement, const Ray& world_ray, TraversalStats* stats) {
  return placement.accel->any_hit(to_model(placement.world_to_model, world_ray, world_ray.t_max), stats);
}

bool InstanceIntersector::closest_hit(const Ray& ray, SurfaceHit& hit, TraversalStats* stats) const {
  if (!find_closest(ray, hit, stats)) return false;
  complete_surface_hit(scene_, ray, hit);
  return true;
}

bool InstanceIntersector::find_closest(const Ray& ray, SurfaceHit& hit, TraversalStats* stats) const {
  // The nearest hit so far, with its object: one capture for the test below instead of three
  // (each capture is a store a query; the test is made for every ray of a scene of objects).
  struct Nearest {
    TriangleHit hit;
    std::uint32_t object = 0;
    bool found = false;
  } nearest;
  if (one_object_untransformed_) {
    nearest.found = object_accel_[0]->closest_hit(ray, nearest.hit, stats);
  } else if (one_object_) {
    nearest.found = closest_in(placements_[0], ray, ray.t_max, nearest.hit, stats);
  } else {
    // Made here and not above: built before the branches, the test's captures were stored on
    // every query, the one-object ones too (15 instructions a ray).
    // ray_hit_order.h's rule across objects: after a hit at t, objects are asked up to and
    // including t, and an equal t is taken from a lower object index only.
    auto test = [this, &ray, stats, &nearest](std::uint32_t, std::uint32_t entry, float& t_max) {
      const Placement& placement = placements_[entry];
      TriangleHit h;
      if (!closest_in(placement, ray, t_max, h, stats)) return false;
      if (nearest.found && !nearer_hit(h.t, placement.object, nearest.hit.t, nearest.object)) return false;
      nearest.hit = h;
      nearest.object = placement.object;
      nearest.found = true;
      t_max = limit_through(h.t);
      return true;
    };
    if (top_) {
      top_->closest(ray, test, stats);
    } else {
      float t_max = ray.t_max;
      for (std::uint32_t o = 0; o < placements_.size(); ++o) test(o, o, t_max);
    }
  }
  if (!nearest.found) return false;
  hit = SurfaceHit{};
  hit.t = nearest.hit.t;
  hit.object = nearest.object;
  hit.triangle = nearest.hit.triangle;
  hit.u = nearest.hit.u;
  hit.v = nearest.hit.v;
  return true;
}

unsigned InstanceIntersector::find_closest_packet(const Ray* rays, unsigned lanes, SurfaceHit* hits) const {
  lanes &= (1u << Bvh::kPacketWidth) - 1u;
  if (!top_ && !one_object_) return SceneIntersector::find_closest_packet(rays, lanes, hits);  // naive
  std::array<float, Bvh::kPacketWidth> t_max{};
  for (unsigned rest = lanes; rest; rest &= rest - 1) {
    const int i = __builtin_ctz(rest);
    t_max[static_cast<std::size_t>(i)] = rays[i].t_max;
  }
  std::array<TriangleHit, Bvh::kPacketWidth> nearest{};
  std::array<std::uint32_t, Bvh::kPacketWidth> nearest_object{};
  unsigned found = 0;
  if (one_object_untransformed_) {
    found = object_accel_[0]->closest_hit_packet(rays, lanes, t_max.data(), nearest.data());
  } else {
    // As find_closest's test, lane by lane: an object is asked up to and including the nearest
    // hit so far, and an equal t is taken from a lower object index only.
    std::array<Ray, Bvh::kPacketWidth> local;
    std::array<TriangleHit, Bvh::kPacketWidth> object_hits;
    const auto test_object = [&](const Placement& placement, unsigned object_lanes) {
      const std::uint32_t o = placement.object;
      for (unsigned rest = object_lanes; rest; rest &= rest - 1) {
        const auto i = static_cast<std::size_t>(__builtin_ctz(rest));
        local[i] = to_model(placement.world_to_model, rays[i], t_max[i]);
      }
      std::array<float, Bvh::kPacketWidth> bound = t_max;
      const unsigned object_found = placement.accel->closest_hit_packet(local.data(), object_lanes, bound.data(),
                                                                        object_hits.data());
      for (unsigned rest = object_found; rest; rest &= rest - 1) {
        const auto i = static_cast<std::size_t>(__builtin_ctz(rest));
        const unsigned bit = 1u << i;
        const TriangleHit& h = object_hits[i];
        if ((found & bit) && !nearer_hit(h.t, o, nearest[i].t, nearest_object[i])) continue;
        nearest[i] = h;
        nearest_object[i] = o;
        found |= bit;
        t_max[i] = limit_through(h.t);
      }
    };
    if (one_object_) {
      test_object(placements_[0], lanes);
    } else {
      top_->closest_packet(rays, lanes, t_max.data(), [&](const BvhLeafRef& leaf, unsigned leaf_lanes) {
        for (std::uint32_t k = 0; k < leaf.count; ++k) test_object(placements_[top_->leaf_entry(leaf, k)], leaf_lanes);
      });
    }
  }
  for (unsigned rest = found; rest; rest &= rest - 1) {
    const auto i = static_cast<std::size_t>(__builtin_ctz(rest));
    hits[i] = SurfaceHit{};
    hits[i].t = nearest[i].t;
    hits[i].object = nearest_object[i];
    hits[i].triangle = nearest[i].triangle;
    hits[i].u = nearest[i].u;
    hits[i].v = nearest[i].v;
  }
  return found;
}

unsigned InstanceIntersector::closest_hit_packet(const Ray* rays, unsigned lanes, SurfaceHit* hits) const {
  const unsigned found = find_closest_packet(rays, lanes, hits);
  for (unsigned rest = found; rest; rest &= rest - 1) {
    const int i = __builtin_ctz(rest);
    complete_surface_hit(scene_, rays[i], hits[i]);
  }
  return found;
}

bool InstanceIntersector::occluded(const Ray& ray, TraversalStats* stats) const {
  if (one_object_untransformed_) return object_accel_[0]->any_hit(ray, stats);
  auto test = [&](std::uint32_t, std::uint32_t entry) { return any_in(placements_[entry], ray, stats); };
  if (one_object_) return test(0, 0);
  if (top_) return top_->any(ray, test, stats);
  for (std::uint32_t o = 0; o < placements_.size(); ++o) {
    if (test(o, o)) return true;
  }
  return false;
}

unsigned InstanceIntersector::occluded_packet(const Ray* rays, unsigned lanes) const {
  lanes &= (1u << Bvh::kPacketWidth) - 1u;
  if (!top_ && !one_object_) return SceneIntersector::occluded_packet(rays, lanes);  // naive
  if (one_object_untransformed_) return object_accel_[0]->any_hit_packet(rays, lanes);
  // As occluded, lane by lane: a ray is blocked once any object it meets blocks it.
  std::array<Ray, Bvh::kPacketWidth> local;
  const auto blocked_in = [&](const Placement& placement, unsigned object_lanes) {
    for (unsigned rest = object_lanes; rest; rest &= rest - 1) {
      const auto i = static_cast<std::size_t>(__builtin_ctz(rest));
      local[i] = to_model(placement.world_to_model, rays[i], rays[i].t_max);
    }
    return placement.accel->any_hit_packet(local.data(), object_lanes);
  };
  if (one_object_) return blocked_in(placements_[0], lanes);
  return top_->any_packet(rays, lanes, [&](const BvhLeafRef& leaf, unsigned leaf_lanes) {
    unsigned blocked = 0;
    for (std::uint32_t k = 0; k < leaf.count && leaf_lanes != blocked; ++k) {
      blocked |= blocked_in(placements_[top_->leaf_entry(leaf, k)], leaf_lanes & ~blocked);
    }
    return blocked;
  });
}

void InstanceIntersector::visit_bvh_boxes(int max_level,
                                          const std::function<void(const BvhBox&)>& visit) const {
  if (!top_) return;
  top_->visit_levels(max_level, [&](const AABB& bounds, int level) {
    visit(BvhBox{bounds, glm::mat4(1.0f), level, -1});
  });
  for (std::uint32_t o = 0; o < object_accel_.size(); ++o) {
    const Bvh* bvh = object_accel_[o]->bvh();
    if (!bvh) continue;
    const glm::mat4& to_world = scene_.objects()[o].model_to_world;
    bvh->visit_levels(max_level, [&](const AABB& bounds, int level) {
      visit(BvhBox{bounds, to_world, level, static_cast<std::int64_t>(o)});
    });
  }
}

std::unique_ptr<InstanceIntersector> build_instance_intersector(const PreparedScene& scene,
                                                                AccelKind accel,
                                                                const CancelFlag& cancel) {
  return std::make_unique<InstanceIntersector>(scene, accel, cancel);
}

std::unique_ptr<SceneIntersector> build_scene_intersector(const PreparedScene& scene, AccelKind accel,
                                                          const CancelFlag& cancel) {
  return skip_cutouts(scene, accel == AccelKind::Embree ? build_embree_intersector(scene, cancel)
                                                      : build_instance_intersector(scene, accel, cancel));
}

}  // namespace farm
