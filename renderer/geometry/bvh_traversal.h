#pragma once
// Template definitions for bvh.h (included at its end).
#include <array>
#include <cmath>
#include <cstdint>
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

template <typename Test>
bool Bvh::closest(const Ray& ray, Test&& test, TraversalStats* stats) const {
  if (nodes_.empty()) return false;
  const glm::vec3 inv_dir = 1.0f / ray.direction;
  // Which child is nearer depends only on the direction's sign along the split axis.
  const std::array<bool, 3> negative{std::signbit(ray.direction.x), std::signbit(ray.direction.y),
                                     std::signbit(ray.direction.z)};
  float t_max = ray.t_max;
  bool hit = false;
  std::uint64_t nodes_visited = 0, primitives_tested = 0;
  std::array<std::uint32_t, kMaxDepth> stack;
  int top = 0;
  std::uint32_t index = 0;
  for (;;) {
    const BvhNode& node = nodes_[index];
    ++nodes_visited;
    float t_entry;
    // Testing against the current t_max skips any node that starts beyond the closest hit.
    if (node.bounds.intersect(ray.origin, inv_dir, ray.t_min, t_max, t_entry)) {
      if (node.count == 0) {
        std::uint32_t near_child = index + 1, far_child = node.offset;
        if (negative[node.axis]) std::swap(near_child, far_child);
        stack[top++] = far_child;
        index = near_child;
        continue;
      }
      for (std::uint32_t i = node.offset; i < node.offset + node.count; ++i) {
        ++primitives_tested;
        if (test(order_[i], t_max)) hit = true;
      }
    }
    if (top == 0) break;
    index = stack[--top];
  }
  if (stats) {
    stats->nodes += nodes_visited;
    stats->triangles += primitives_tested;
  }
  return hit;
}

template <typename Test>
bool Bvh::any(const Ray& ray, Test&& test, TraversalStats* stats) const {
  if (nodes_.empty()) return false;
  const glm::vec3 inv_dir = 1.0f / ray.direction;
  const std::array<bool, 3> negative{std::signbit(ray.direction.x), std::signbit(ray.direction.y),
                                     std::signbit(ray.direction.z)};
  bool hit = false;
  std::uint64_t nodes_visited = 0, primitives_tested = 0;
  std::array<std::uint32_t, kMaxDepth> stack;
  int top = 0;
  std::uint32_t index = 0;
  for (;;) {
    const BvhNode& node = nodes_[index];
    ++nodes_visited;
    float t_entry;
    if (node.bounds.intersect(ray.origin, inv_dir, ray.t_min, ray.t_max, t_entry)) {
      if (node.count == 0) {
        std::uint32_t near_child = index + 1, far_child = node.offset;
        if (negative[node.axis]) std::swap(near_child, far_child);
        stack[top++] = far_child;
        index = near_child;
        continue;
      }
      for (std::uint32_t i = node.offset; i < node.offset + node.count; ++i) {
        ++primitives_tested;
        if (test(order_[i])) {
          hit = true;
          break;
        }
      }
      if (hit) break;
    }
    if (top == 0) break;
    index = stack[--top];
  }
  if (stats) {
    stats->nodes += nodes_visited;
    stats->triangles += primitives_tested;
  }
  return hit;
}

}  // namespace farm
