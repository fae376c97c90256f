#pragma once
// A bounding volume hierarchy over primitives given by their boxes: triangles of a model (the
// bottom level) or object instances (the top level). Built top-down by the surface area
// heuristic over binned centroids, or by splitting at the median of the longest axis (the
// lab's build); stored as one flat array, depth-first, the first child right after its parent.
// Traversal runs over an 8-wide collapse of the tree (WideBvhNode), the one of least surface
// area cost, visiting nearer children first and skipping nodes farther than the closest hit so
// far. The collapse may merge a small subtree into one leaf (up to Options::max_leaf_size
// primitives), so leaves() are the wide tree's, not the binary nodes'. Leaves are numbered in the
// order of order(), so that a caller may keep a leaf's primitives together (mesh_accel's
// Triangle4s).
#include <array>
#include <cstdint>
#include <immintrin.h>
#include <span>
#include <vector>

#include "renderer/geometry/aabb.h"
#include "renderer/geometry/ray.h"
#include "renderer/geometry/traversal_isa.h"
#include "renderer/geometry/traversal_stats.h"
#include "renderer/util/cancel_flag.h"
#include "renderer/util/huge_pages.h"

namespace farm {

enum class BvhSplit { Sah, Median };

struct BvhNode {
  AABB bounds;
  std::uint32_t offset = 0;  // inner: index of the second child; leaf: first index into order()
  std::uint16_t count = 0;   // leaf: number of primitives; 0 marks an inner node
  std::uint8_t axis = 0;     // inner: the split axis, which decides the near child
};

// Children of a wide node.
inline constexpr int kWideBvhWidth = 8;

// The traversal form of a Bvh: the binary tree collapsed into nodes of up to kWideBvhWidth
// children, whose boxes are stored plane by plane so that SIMD instructions test the children
// together (eight at a time with AVX2, two halves of four with SSE).
struct alignas(32) WideBvhNode {
  // Per child: min x, max x, min y, max y, min z, max z. An unused slot holds an empty box (min
  // +inf, max -inf), which every ray misses: the traversal needs no count or mask of the slots. Each
  // axis's min and max side by side, so the plane a ray leaves by is the one it enters by with
  // one address bit flipped (a row is 32 bytes): one offset a ray per axis.
  float bounds[6][kWideBvhWidth];
  std::uint32_t child[kWideBvhWidth];    // inner child: its WideBvhNode index; leaf child: its number in leaves()
  std::uint8_t count[kWideBvhWidth];     // leaf child: primitives; 0: an inner child
  std::uint8_t leaf_mask = 0;            // bit i: child i is a leaf
};

// Per octant of a ray's direction (bit a: it runs toward -a), the byte offset in a WideBvhNode of
// the row of planes it enters each axis's slab by: axis a's min row, or its max row (one row on)
// for the rays running toward -a. Lane 3 is not used.
inline constexpr std::array<std::array<std::uint32_t, 4>, 8> kWideBvhNearRows = [] {
  std::array<std::array<std::uint32_t, 4>, 8> rows{};
  constexpr std::uint32_t kRowBytes = sizeof(float) * kWideBvhWidth;
  for (std::uint32_t octant = 0; octant < 8; ++octant) {
    for (std::uint32_t a = 0; a < 3; ++a) rows[octant][a] = (2 * a + (octant >> a & 1u)) * kRowBytes;
  }
  return rows;
}();

// A leaf of the wide tree: entries [first, first + count) of Bvh::order().
struct BvhLeaf {
  std::uint32_t first = 0;
  std::uint32_t count = 0;
};

// What a leaf test is handed: the leaf's number in Bvh::leaves() and its primitive count.
struct BvhLeafRef {
  std::uint32_t number = 0;
  std::uint32_t count = 0;
};

class Bvh {
 public:
  // Deeper than any sane tree: builds switch to splitting by count well before it, so the
  // traversal stack (one entry per level) can be a fixed array.
  static constexpr int kMaxDepth = 64;

  struct Options {
    BvhSplit split = BvhSplit::Sah;
    int max_leaf_size = 8;
    // Polled as the build goes (every few tens of thousands of primitives split): a stop throws
    // RenderStopped. Null: never stops.
    const CancelFlag* cancel = nullptr;
    // How many of a leaf's primitives one test takes at once (mesh leaves: a Triangle4): the
    // surface area heuristic counts a leaf's cost in such tests, so it fills them. Clamped to
    // [1, 255].
    int test_group = 1;
  };

  // Primitive i has bounds primitive_bounds[i]. Empty boxes (e.g. objects without triangles)
  // can never be hit and are left out of the tree. max_leaf_size is clamped to [1, 255]. The
  // tree has fewer than kMaxDepth levels whatever the input.
  static Bvh build(std::span<const AABB> primitive_bounds, const Options& options);

  const std::vector<BvhNode>& nodes() const { return nodes_; }
  // Leaf entries: primitive indices in the order leaves refer to them.
  const std::vector<std::uint32_t>& order() const { return order_; }
  // The leaves, depth-first (so in the order of their entries in order(), each covered once).
  const std::vector<BvhLeaf>& leaves() const { return leaves_; }
  // What closest() and any() walk: the binary tree collapsed into wide nodes, the root first.
  std::span<const WideBvhNode> wide_nodes() const { return wide_; }
  // The deepest level (a lone root leaf: 0; no nodes at all: -1).
  int depth() const { return depth_; }

  // Calls visit(bounds, level) for every node of level <= max_level (the root is level 0).
  template <typename Visit>
  void visit_levels(int max_level, Visit&& visit) const;

  // Closest-hit traversal. `test(primitive, t_max)` intersects one primitive and, on a hit
  // nearer than t_max, lowers t_max and returns true. Returns whether anything was hit. A test
  // may also take (primitive, leaf_entry, t_max), leaf_entry being the index into order(); or
  // test a whole leaf at once as test(BvhLeafRef, t_max), lowering t_max to its nearest hit.
  template <typename Test>
  bool closest(const Ray& ray, Test&& test, TraversalStats* stats) const;

  // Any-hit traversal: stops at the first primitive for which test(primitive) (or
  // test(primitive, leaf_entry), or test(BvhLeafRef) for a whole leaf) is true.
  template <typename Test>
  bool any(const Ray& ray, Test&& test, TraversalStats* stats) const;

  // Closest-hit traversal of up to kPacketWidth rays at once: rays[i] for each bit i of `lanes`.
  // t_max holds kPacketWidth floats (those of lanes left out are read, never used); t_max[i]
  // starts as the ray's bound and is lowered by `test(leaf, leaf_lanes)`, which tests
  // the leaf against each ray of `leaf_lanes` (those whose slab test met the leaf's box) and
  // lowers their t_max on a hit. Each ray meets exactly the boxes its own closest() would meet
  // at the same t_max (the same slab arithmetic, lane by lane), so with a leaf test that keeps
  // the nearest hit by ray_hit_order.h's rule, every ray finds the hit closest() finds for it.
  // Rays whose directions' signs differ are walked as separate packets (each sign pattern, an
  // octant, one). Nodes are shared where the rays are coherent (a block of camera rays): one
  // load and one pass of slab tests for all. Without AVX2, each ray goes through closest().
  static constexpr int kPacketWidth = 8;
  template <typename Test>
  void closest_packet(const Ray* rays, unsigned lanes, float* t_max, Test&& test) const;

  // Any-hit traversal of up to kPacketWidth rays at once (shadow rays toward one light from
  // neighbouring points): `test(leaf, leaf_lanes)` tests the leaf against each ray of
  // `leaf_lanes` within its own (t_min, t_max) and returns those it hit. Returns the rays of
  // `lanes` hit. A ray takes part until its first hit, meeting the boxes any() would meet (the
  // packet walk's slab arithmetic, t_max never lowered), so with the leaf test any() uses, each
  // ray's answer is any()'s. Without AVX2, each ray goes through any().
  template <typename Test>
  unsigned any_packet(const Ray* rays, unsigned lanes, Test&& test) const;

  // Where a leaf's entry `i` (< leaf.count) lies in order(): what a packet's leaf test resolves
  // (order()[leaf_entry] is the primitive; a caller may keep its primitives' data in that order).
  std::uint32_t leaf_entry(const BvhLeafRef& leaf, std::uint32_t i) const { return leaves_[leaf.number].first + i; }

 private:
  // The traversal for any x86-64, for AVX2 and for AVX-512 (bvh_traversal.h), with or without
  // counting nodes and primitives into `stats`.
  template <bool kAnyHit, bool kCount, typename Test>
  bool traverse_sse(const Ray& ray, Test& test, TraversalStats* stats) const;
  template <bool kAnyHit, bool kCount, typename Test>
  bool traverse_avx2(const Ray& ray, Test& test, TraversalStats* stats) const;
  template <bool kAnyHit, bool kCount, typename Test>
  bool traverse_avx512(const Ray& ray, Test& test, TraversalStats* stats) const;
  template <bool kAnyHit, typename Test>
  bool traverse(const Ray& ray, Test& test, TraversalStats* stats) const;
  // closest_packet with AVX2 (bvh_packet_body.h): the rays' set-up, then one walk per octant.
  // t_max: kPacketWidth bounds. kAnyHit: the walk sets them from the rays' t_max, ray i's drops
  // to -inf when it is hit, and children are taken unsorted.
  template <bool kAnyHit, typename Test>
  void traverse_packet_avx2(const Ray* rays, unsigned lanes, float* t_max, Test& test) const;
  template <bool kAnyHit, typename Test>
  void walk_packet_avx2(unsigned lanes, const std::size_t* near_row, const __m256* origin, const __m256* inv,
                        const __m256* inv_far, const __m256* t_min, float* t_max, Test& test) const;
  void build_wide(std::uint32_t max_leaf, std::uint32_t group);

  std::vector<BvhNode> nodes_;
  // What closest() and any() walk (nodes_ is for drawing); a large tree's on huge pages.
  std::vector<WideBvhNode, LargeArrayAllocator<WideBvhNode>> wide_;
  std::vector<std::uint32_t> order_;
  std::vector<BvhLeaf> leaves_;
  int depth_ = -1;
};

}  // namespace farm

#include "renderer/geometry/bvh_traversal.h"  // the template definitions
