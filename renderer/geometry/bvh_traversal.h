#pragma once
// Template definitions for bvh.h (included at its end).
#include <array>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <utility>

#include "renderer/geometry/bvh.h"

namespace farm {

template <typename Visit>
void Bvh::visit_levels(int max_level, Visit&& visit) const {
  if (nodes_.empty() || max_level < 0) return;
  std::array<std::pair<std::uint32_t, int>, kMaxDepth> stack;
  int top = 0;
  stack[top++] = {0u, 0};
  while (top > 0) {
    const auto [index, level] = stack[--top];
    const BvhNode& node = nodes_[index];
    visit(node.bounds, level);
    if (node.count == 0 && level < max_level) {
      stack[top++] = {node.offset, level + 1};
      stack[top++] = {index + 1, level + 1};
    }
  }
}

// Calls a primitive test either as test(primitive, ...) or, if it takes the extra argument, as
// test(primitive, leaf_entry, ...): leaf_entry is the position in order(), which lets a caller
// keep its primitive data in leaf order for locality.
template <typename Test, typename... Rest>
bool call_primitive_test(Test& test, std::uint32_t primitive, std::uint32_t leaf_entry, Rest&... rest) {
  if constexpr (std::is_invocable_v<Test&, std::uint32_t, std::uint32_t, Rest&...>) {
    return test(primitive, leaf_entry, rest...);
  } else {
    return test(primitive, rest...);
  }
}

// Both traversals test a node's two children together and descend into the nearer one that the
// ray meets, keeping the farther one (with its entry distance) on a stack; a stacked node is
// dropped when it starts beyond the closest hit found since. `nodes` counts the nodes entered.
// kAnyHit: stop at the first primitive hit (t_max never shrinks); otherwise keep the nearest.
template <bool kAnyHit, typename Test>
bool Bvh::traverse(const Ray& ray, Test& test, TraversalStats* stats) const {
  if (nodes_.empty()) return false;
  const glm::vec3 inv_dir = 1.0f / ray.direction;
  float t_max = ray.t_max;
  float t_entry;
  if (!nodes_[0].bounds.intersect(ray.origin, inv_dir, ray.t_min, t_max, t_entry)) return false;
  bool hit = false;
  std::uint64_t nodes_visited = 0, primitives_tested = 0;
  struct Pending {
    std::uint32_t index;
    float t_entry;
  };
  std::array<Pending, kMaxDepth> stack;
  int top = 0;
  std::uint32_t index = 0;
  for (;;) {
    const BvhNode& node = nodes_[index];
    ++nodes_visited;
    if (node.count == 0) {
      std::uint32_t first = index + 1, second = node.offset;
      float t_first, t_second;
      const bool hit_first = nodes_[first].bounds.intersect(ray.origin, inv_dir, ray.t_min, t_max, t_first);
      const bool hit_second = nodes_[second].bounds.intersect(ray.origin, inv_dir, ray.t_min, t_max, t_second);
      if (hit_first && hit_second) {
        if (t_second < t_first) {
          std::swap(first, second);
          std::swap(t_first, t_second);
        }
        stack[top++] = {second, t_second};
        index = first;
        continue;
      }
      if (hit_first || hit_second) {
        index = hit_first ? first : second;
        continue;
      }
    } else {
      for (std::uint32_t i = node.offset; i < node.offset + node.count; ++i) {
        ++primitives_tested;
        if constexpr (kAnyHit) {
          hit = call_primitive_test(test, order_[i], i);
          if (hit) break;
        } else {
          if (call_primitive_test(test, order_[i], i, t_max)) hit = true;
        }
      }
      if (kAnyHit && hit) break;
    }
    // Next: the nearest pending node that still starts before the closest hit.
    while (top > 0 && stack[top - 1].t_entry > t_max) --top;
    if (top == 0) break;
    index = stack[--top].index;
  }
  if (stats) {
    stats->nodes += nodes_visited;
    stats->triangles += primitives_tested;
  }
  return hit;
}

template <typename Test>
bool Bvh::closest(const Ray& ray, Test&& test, TraversalStats* stats) const {
  return traverse<false>(ray, test, stats);
}

template <typename Test>
bool Bvh::any(const Ray& ray, Test&& test, TraversalStats* stats) const {
  return traverse<true>(ray, test, stats);
}

}  // namespace farm
