#pragma once
// Template definitions for bvh.h (included at its end).
#include <array>
#include <cmath>
#include <cstdint>
#include <immintrin.h>
#include <limits>
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

// Both traversals walk the wide nodes: one SSE slab test gives the entry distances of all four
// children; leaf children are tested at once, nearest first, and inner ones are stacked so the
// nearest is entered next. A stacked node is dropped when it starts beyond the closest hit found
// since. `nodes` counts the wide nodes entered.
// kAnyHit: stop at the first primitive hit (t_max never shrinks); otherwise keep the nearest.
template <bool kAnyHit, typename Test>
bool Bvh::traverse(const Ray& ray, Test& test, TraversalStats* stats) const {
  if (wide_.empty()) return false;
  constexpr bool kLeafTest = kAnyHit ? std::is_invocable_r_v<bool, Test&, const BvhLeafRef&>
                                     : std::is_invocable_r_v<bool, Test&, const BvhLeafRef&, float&>;
  // Per axis, the plane a ray enters a slab by depends only on the direction's sign, so it is
  // picked once per ray: entry = (near plane - o) / d, exit = (far plane - o) / d, no min/max
  // needed. A zero component gives +-inf, and 0 * inf = NaN for a ray lying in a slab's plane;
  // the max/min below keep their running value when handed a NaN first (SSE returns the second
  // operand), so such a ray counts as inside the closed slab, as in AABB::intersect.
  const glm::vec3 inv_dir = 1.0f / ray.direction;
  const __m128 inv[3] = {_mm_set1_ps(inv_dir.x), _mm_set1_ps(inv_dir.y), _mm_set1_ps(inv_dir.z)};
  int near_plane[3], far_plane[3];
  for (int a = 0; a < 3; ++a) {
    const bool negative = inv_dir[a] < 0.0f;
    near_plane[a] = negative ? 3 + a : a;
    far_plane[a] = negative ? a : 3 + a;
  }
  const __m128 origin[3] = {_mm_set1_ps(ray.origin.x), _mm_set1_ps(ray.origin.y),
                            _mm_set1_ps(ray.origin.z)};
  // Far distances are widened by a few ulps so rounding never culls a hit on a box boundary
  // (pbrt's 1 + 2 gamma(3), which covers the four roundings of (far - o) * (inv * widen): the
  // widening goes into the reciprocal once per ray instead of into every distance).
  constexpr float kWiden = 1.0f + 2.0f * (3.0f * std::numeric_limits<float>::epsilon() * 0.5f) /
                                      (1.0f - 3.0f * std::numeric_limits<float>::epsilon() * 0.5f);
  const __m128 inv_far[3] = {_mm_mul_ps(inv[0], _mm_set1_ps(kWiden)), _mm_mul_ps(inv[1], _mm_set1_ps(kWiden)),
                             _mm_mul_ps(inv[2], _mm_set1_ps(kWiden))};
  const __m128 t_min4 = _mm_set1_ps(ray.t_min);
  float t_max = ray.t_max;
  bool hit = false;
  std::uint64_t nodes_visited = 0, primitives_tested = 0;
  struct Pending {
    std::uint32_t index;
    float t_entry;
  };
  std::array<Pending, 3 * kMaxDepth> stack;
  int top = 0;
  std::uint32_t index = 0;
  for (;;) {
    const WideBvhNode& node = wide_[index];
    ++nodes_visited;
    __m128 t_near = t_min4, t_far = _mm_set1_ps(t_max);
    for (int a = 0; a < 3; ++a) {
      const __m128 enter = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node.bounds[near_plane[a]]), origin[a]), inv[a]);
      const __m128 leave = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node.bounds[far_plane[a]]), origin[a]), inv_far[a]);
      t_near = _mm_max_ps(enter, t_near);
      t_far = _mm_min_ps(leave, t_far);
    }
    alignas(16) float entry[4];
    _mm_store_ps(entry, t_near);
    int mask = _mm_movemask_ps(_mm_cmple_ps(t_near, t_far)) & ((1 << node.children) - 1);
    // One inner child met, the commonest case: entered at once, without the stack.
    if (mask != 0 && (mask & (mask - 1)) == 0) {
      const int only = __builtin_ctz(static_cast<unsigned>(mask));
      if (node.count[only] == 0) {
        index = node.child[only];
        continue;
      }
    }

    // Visit the children that the ray meets, nearest first.
    std::array<int, 4> order{};
    int n = 0;
    while (mask) {
      const int i = __builtin_ctz(static_cast<unsigned>(mask));
      mask &= mask - 1;
      int j = n++;
      while (j > 0 && entry[order[static_cast<std::size_t>(j - 1)]] > entry[i]) {
        order[static_cast<std::size_t>(j)] = order[static_cast<std::size_t>(j - 1)];
        --j;
      }
      order[static_cast<std::size_t>(j)] = i;
    }
    // Inner children go on the stack farthest first, so the nearest is popped next.
    for (int k = n - 1; k >= 0; --k) {
      const auto c = static_cast<std::size_t>(order[static_cast<std::size_t>(k)]);
      if (node.count[c] == 0) stack[top++] = {node.child[c], entry[c]};
    }
    for (int k = 0; k < n; ++k) {
      const auto c = static_cast<std::size_t>(order[static_cast<std::size_t>(k)]);
      if (node.count[c] == 0 || entry[c] > t_max) continue;
      if constexpr (kLeafTest) {
        primitives_tested += node.count[c];
        const BvhLeafRef leaf{node.child[c], node.count[c]};
        if constexpr (kAnyHit) {
          hit = test(leaf);
        } else if (test(leaf, t_max)) {
          hit = true;
        }
      } else {
        const std::uint32_t first = leaves_[node.child[c]].first;
        for (std::uint32_t i = first; i < first + node.count[c]; ++i) {
          ++primitives_tested;
          if constexpr (kAnyHit) {
            if (call_primitive_test(test, order_[i], i)) {
              hit = true;
              break;
            }
          } else {
            if (call_primitive_test(test, order_[i], i, t_max)) hit = true;
          }
        }
      }
      if (kAnyHit && hit) break;
    }
    if (kAnyHit && hit) break;
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
