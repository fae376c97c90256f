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

// The traversal, written once (bvh_traverse_body.h) and compiled twice: for any x86-64 (SSE,
// a node's eight slabs as two halves) and for AVX2 (all eight at once), the one for this CPU
// picked per query (traversal_isa.h). Both compute every slab distance with the same operations
// in the same order, so they enter the same nodes in the same order and find the same hits:
// results, and the nodes counted for bvh_cost, do not depend on the machine.
#define FARM_BVH_TRAVERSE traverse_sse
#define FARM_BVH_AVX2 0
#include "renderer/geometry/bvh_traverse_body.h"
#undef FARM_BVH_TRAVERSE
#undef FARM_BVH_AVX2

// The functions defined here are compiled for AVX2 (GCC's pragma; clang, the fuzz build's
// compiler, spells it as an attribute pushed on every function).
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx2")
#endif
#define FARM_BVH_TRAVERSE traverse_avx2
#define FARM_BVH_AVX2 1
#include "renderer/geometry/bvh_traverse_body.h"
#undef FARM_BVH_TRAVERSE
#undef FARM_BVH_AVX2
#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif

template <typename Test>
bool Bvh::closest(const Ray& ray, Test&& test, TraversalStats* stats) const {
  return traversal_isa() == TraversalIsa::Avx2 ? traverse_avx2<false>(ray, test, stats)
                                               : traverse_sse<false>(ray, test, stats);
}

template <typename Test>
bool Bvh::any(const Ray& ray, Test&& test, TraversalStats* stats) const {
  return traversal_isa() == TraversalIsa::Avx2 ? traverse_avx2<true>(ray, test, stats)
                                               : traverse_sse<true>(ray, test, stats);
}

}  // namespace farm
