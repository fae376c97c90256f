#pragma once
// Template definitions for bvh.h (included at its end).
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <immintrin.h>
#include <limits>
#include <type_traits>
#include <utility>

#include "renderer/geometry/bvh.h"
#include "renderer/geometry/ray_packet.h"

namespace farm {

// The walk loads a ray's direction as four floats (bvh_traverse_body.h); the fourth, t_min, must
// be the Ray's own.
static_assert(offsetof(Ray, t_min) == offsetof(Ray, direction) + 3 * sizeof(float));

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

// The traversal, written once (bvh_traverse_body.h) and compiled three times: for any x86-64
// (SSE, a node's eight slabs as two halves), for AVX2 (all eight at once) and for AVX-512's VL
// subset (that AVX2 code on 32 vector registers instead of 16: with 16, a node's slab state,
// ten registers, was stored and loaded again around every leaf test, 26 instructions a node with
// leaves met). The one for this CPU is picked per query (traversal_isa.h). All compute every slab
// distance with the same operations in the same order, so they enter the same nodes in the same
// order and find the same hits: results, and the nodes counted for bvh_cost, do not depend on
// the machine.
//
// A region compiled for `isa` (GCC's pragmas; clang, the fuzz build's compiler, spells it as an
// attribute pushed on every function). No fused multiply-add in it: AVX-512 has its own forms,
// which GCC contracts products and sums into unless told not to (the leaf tests and instance
// transforms inlined here must round each product as the SSE build does); clang fuses only
// within one source expression, which intrinsics never are.
#define FARM_PRAGMA(text) _Pragma(#text)
#if defined(__clang__)
#define FARM_BVH_TARGET_PUSH(isa) FARM_PRAGMA(clang attribute push(__attribute__((target(isa))), apply_to = function))
#define FARM_BVH_TARGET_POP FARM_PRAGMA(clang attribute pop)
#else
#define FARM_BVH_TARGET_PUSH(isa) \
  FARM_PRAGMA(GCC push_options) FARM_PRAGMA(GCC target(isa)) FARM_PRAGMA(GCC optimize("fp-contract=off"))
#define FARM_BVH_TARGET_POP FARM_PRAGMA(GCC pop_options)
#endif

#define FARM_BVH_TRAVERSE traverse_sse
#define FARM_BVH_AVX2 0
#include "renderer/geometry/bvh_traverse_body.h"

FARM_BVH_TARGET_PUSH("avx2")
#define FARM_BVH_TRAVERSE traverse_avx2
#define FARM_BVH_AVX2 1
#include "renderer/geometry/bvh_traverse_body.h"
FARM_BVH_TARGET_POP

FARM_BVH_TARGET_PUSH("avx2,avx512f,avx512vl")
#define FARM_BVH_TRAVERSE traverse_avx512
#define FARM_BVH_AVX2 1
#include "renderer/geometry/bvh_traverse_body.h"
FARM_BVH_TARGET_POP

FARM_BVH_TARGET_PUSH("avx2")
#include "renderer/geometry/bvh_packet_body.h"
FARM_BVH_TARGET_POP

#undef FARM_BVH_TARGET_PUSH
#undef FARM_BVH_TARGET_POP
#undef FARM_PRAGMA

// The build for this CPU, with or without counting.
template <bool kAnyHit, typename Test>
bool Bvh::traverse(const Ray& ray, Test& test, TraversalStats* stats) const {
  switch (traversal_isa()) {
    case TraversalIsa::Avx512:
      return stats ? traverse_avx512<kAnyHit, true>(ray, test, stats) : traverse_avx512<kAnyHit, false>(ray, test, stats);
    case TraversalIsa::Avx2:
      return stats ? traverse_avx2<kAnyHit, true>(ray, test, stats) : traverse_avx2<kAnyHit, false>(ray, test, stats);
    case TraversalIsa::Sse:
      break;
  }
  return stats ? traverse_sse<kAnyHit, true>(ray, test, stats) : traverse_sse<kAnyHit, false>(ray, test, stats);
}

template <typename Test>
bool Bvh::closest(const Ray& ray, Test&& test, TraversalStats* stats) const {
  return traverse<false>(ray, test, stats);
}

template <typename Test>
bool Bvh::any(const Ray& ray, Test&& test, TraversalStats* stats) const {
  return traverse<true>(ray, test, stats);
}

template <typename Test>
void Bvh::closest_packet(const Ray* rays, unsigned lanes, float* t_max, Test&& test) const {
  lanes &= (1u << kPacketWidth) - 1u;
  if (wide_.empty() || lanes == 0) return;
  if (traversal_isa() == TraversalIsa::Sse) {
    // One ray at a time through closest(), its leaf test the packet's on that lane alone.
    for (unsigned rest = lanes; rest; rest &= rest - 1) {
      const int i = __builtin_ctz(rest);
      Ray ray = rays[i];
      ray.t_max = t_max[i];
      auto one = [&](const BvhLeafRef& leaf, float& bound) {
        const float before = t_max[i];
        test(leaf, 1u << i);
        bound = t_max[i];
        return t_max[i] != before;
      };
      traverse<false>(ray, one, nullptr);
    }
    return;
  }
  traverse_packet_avx2<false>(rays, lanes, t_max, test);
}

template <typename Test>
unsigned Bvh::any_packet(const Ray* rays, unsigned lanes, Test&& test) const {
  lanes &= (1u << kPacketWidth) - 1u;
  if (wide_.empty() || lanes == 0) return 0;
  unsigned hit = 0;
  if (traversal_isa() == TraversalIsa::Sse) {
    for (unsigned rest = lanes; rest; rest &= rest - 1) {
      const int i = __builtin_ctz(rest);
      auto one = [&](const BvhLeafRef& leaf) { return (test(leaf, 1u << i) >> i & 1u) != 0; };
      if (traverse<true>(rays[i], one, nullptr)) hit |= 1u << i;
    }
    return hit;
  }
  // The closest-hit walk with bounds that never shrink, but for a ray hit: its bound drops to
  // -inf, which no box's slab test meets, so it leaves the walk. The walk sets each ray's bound
  // from its t_max.
  alignas(32) float t_max[kPacketWidth];
  auto leaf_test = [&](const BvhLeafRef& leaf, unsigned leaf_lanes) {
    // A ray hit at an earlier leaf of the same node met this one before it left the walk.
    leaf_lanes &= ~hit;
    if (leaf_lanes == 0) return;
    const unsigned met = test(leaf, leaf_lanes) & leaf_lanes;
    hit |= met;
    for (unsigned rest = met; rest; rest &= rest - 1) t_max[__builtin_ctz(rest)] = -INFINITY;
  };
  traverse_packet_avx2<true>(rays, lanes, t_max, leaf_test);
  return hit;
}

}  // namespace farm
