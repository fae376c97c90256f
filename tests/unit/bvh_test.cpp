// Bvh builds (SAH and median) and the MeshAccel queries over them, checked against brute
// force: the naive accel tests every triangle with the same triangle test, so a correct BVH
// gives exactly its hits (up to which of several triangles at the same t wins).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <random>
#include <stdexcept>
#include <span>
#include <string>
#include <vector>

#include "renderer/accel/mesh_accel.h"
#include "renderer/accel/model_triangles.h"
#include "renderer/geometry/bvh.h"
#include "renderer/geometry/traversal_isa.h"
#include "renderer/geometry/triangle_intersect.h"
#include "renderer/scene/model.h"
#include "tests/support/ray_fixtures.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

#ifdef NDEBUG
constexpr std::size_t kRayDivisor = 1;
#else
constexpr std::size_t kRayDivisor = 10;  // unoptimised builds: fewer rays, the same kinds
#endif

std::vector<AABB> bounds_of(const ModelTriangles& triangles) {
  std::vector<AABB> out(triangles.size());
  for (std::uint32_t t = 0; t < triangles.size(); ++t) out[t] = triangles.triangle_bounds(t);
  return out;
}

// Every promise of bvh.h: each non-empty primitive exactly once in order(); depth-first layout
// with the first child right after its parent; leaves of 1..max_leaf entries covering order()
// exactly once; every box containing its children's and its primitives' boxes.
void expect_well_formed(const Bvh& bvh, const std::vector<AABB>& primitives, int max_leaf) {
  const std::vector<BvhNode>& nodes = bvh.nodes();
  const std::vector<std::uint32_t>& order = bvh.order();
  std::vector<int> seen(primitives.size(), 0);
  for (const std::uint32_t p : order) {
    ASSERT_LT(p, primitives.size());
    ++seen[p];
  }
  for (std::size_t p = 0; p < primitives.size(); ++p) {
    ASSERT_EQ(seen[p], primitives[p].empty() ? 0 : 1) << "primitive " << p;
  }
  if (order.empty()) {
    EXPECT_TRUE(nodes.empty());
    EXPECT_EQ(bvh.depth(), -1);
    return;
  }
  std::vector<int> visits(nodes.size(), 0), covered(order.size(), 0);
  int deepest = 0;
  std::vector<std::pair<std::uint32_t, int>> stack{{0u, 0}};
  while (!stack.empty()) {
    const auto [index, level] = stack.back();
    stack.pop_back();
    ASSERT_LT(index, nodes.size());
    ++visits[index];
    deepest = std::max(deepest, level);
    const BvhNode& node = nodes[index];
    if (node.count > 0) {
      EXPECT_LE(node.count, max_leaf) << "leaf " << index;
      ASSERT_LE(node.offset + node.count, order.size());
      for (std::uint32_t i = node.offset; i < node.offset + node.count; ++i) {
        ++covered[i];
        EXPECT_TRUE(node.bounds.contains(primitives[order[i]])) << "leaf " << index << " entry " << i;
      }
    } else {
      ASSERT_GT(node.offset, index + 1) << "second child must follow the first child's subtree";
      ASSERT_LT(node.offset, nodes.size());
      EXPECT_LT(node.axis, 3);
      EXPECT_TRUE(node.bounds.contains(nodes[index + 1].bounds)) << "node " << index;
      EXPECT_TRUE(node.bounds.contains(nodes[node.offset].bounds)) << "node " << index;
      stack.push_back({node.offset, level + 1});
      stack.push_back({index + 1, level + 1});
    }
  }
  EXPECT_TRUE(std::all_of(visits.begin(), visits.end(), [](int v) { return v == 1; }))
      << "every node reachable exactly once";
  EXPECT_TRUE(std::all_of(covered.begin(), covered.end(), [](int c) { return c == 1; }))
      << "leaves cover order() exactly once";
  EXPECT_EQ(bvh.depth(), deepest);
  EXPECT_LT(bvh.depth(), Bvh::kMaxDepth);
}

// One slot of a wide node: its box, and whether it is used.
AABB slot_box(const WideBvhNode& node, int i) {
  AABB box;
  box.min = {node.bounds[0][i], node.bounds[2][i], node.bounds[4][i]};
  box.max = {node.bounds[1][i], node.bounds[3][i], node.bounds[5][i]};
  return box;
}

// The wide tree's promises: every node reached once from the root; a leaf slot names a leaf of
// leaves() holding 1..max_leaf entries, each leaf named once; leaves() cover order() once, in
// order; a slot's box holds its leaf's primitives or its child node's slots; an unused slot
// holds an empty box and no leaf bit.
void expect_wide_well_formed(const Bvh& bvh, const std::vector<AABB>& primitives, int max_leaf) {
  const std::span<const WideBvhNode> wide = bvh.wide_nodes();
  const std::vector<BvhLeaf>& leaves = bvh.leaves();
  const std::vector<std::uint32_t>& order = bvh.order();
  ASSERT_EQ(wide.empty(), order.empty());
  if (wide.empty()) return;
  std::uint32_t next = 0;
  for (const BvhLeaf& leaf : leaves) {
    ASSERT_EQ(leaf.first, next) << "leaves cover order() once, in order";
    ASSERT_GE(leaf.count, 1u);
    ASSERT_LE(leaf.count, static_cast<std::uint32_t>(max_leaf));
    next += leaf.count;
  }
  ASSERT_EQ(next, order.size());
  std::vector<int> node_seen(wide.size(), 0), leaf_seen(leaves.size(), 0);
  std::vector<std::uint32_t> stack{0};
  while (!stack.empty()) {
    const std::uint32_t w = stack.back();
    stack.pop_back();
    ASSERT_LT(w, wide.size());
    ++node_seen[w];
    const WideBvhNode& node = wide[w];
    for (int i = 0; i < kWideBvhWidth; ++i) {
      const AABB box = slot_box(node, i);
      const bool leaf = (node.leaf_mask >> i & 1) != 0;
      if (box.empty()) {
        EXPECT_FALSE(leaf) << "node " << w << " slot " << i;
        continue;
      }
      if (leaf) {
        ASSERT_LT(node.child[i], leaves.size());
        ++leaf_seen[node.child[i]];
        const BvhLeaf& l = leaves[node.child[i]];
        EXPECT_EQ(node.count[i], l.count);
        for (std::uint32_t e = l.first; e < l.first + l.count; ++e) {
          EXPECT_TRUE(box.contains(primitives[order[e]])) << "node " << w << " slot " << i;
        }
      } else {
        EXPECT_EQ(node.count[i], 0) << "node " << w << " slot " << i;
        ASSERT_LT(node.child[i], wide.size());
        for (int j = 0; j < kWideBvhWidth; ++j) {
          const AABB inner = slot_box(wide[node.child[i]], j);
          if (!inner.empty()) {
            EXPECT_TRUE(box.contains(inner)) << "node " << w << " slot " << i;
          }
        }
        stack.push_back(node.child[i]);
      }
    }
  }
  EXPECT_TRUE(std::all_of(node_seen.begin(), node_seen.end(), [](int v) { return v == 1; }))
      << "every wide node reached exactly once";
  EXPECT_TRUE(std::all_of(leaf_seen.begin(), leaf_seen.end(), [](int v) { return v == 1; }))
      << "every leaf named exactly once";
}

// The collapse's measure of a wide tree (bvh.cpp): each slot's area, once for an inner node and
// once per test of `group` primitives for a leaf.
double wide_cost(const Bvh& bvh, std::uint32_t group) {
  double cost = 0.0;
  for (const WideBvhNode& node : bvh.wide_nodes()) {
    for (int i = 0; i < kWideBvhWidth; ++i) {
      const AABB box = slot_box(node, i);
      if (box.empty()) continue;
      const bool leaf = (node.leaf_mask >> i & 1) != 0;
      cost += box.half_area() * (leaf ? static_cast<double>((node.count[i] + group - 1) / group) : 1.0);
    }
  }
  return cost;
}

// The same measure of the collapse the tree had before: each wide node takes its binary node's
// two children and opens its largest inner child until it has eight, leaves as the build left them.
double largest_first_cost(const Bvh& bvh, std::uint32_t group) {
  const std::vector<BvhNode>& nodes = bvh.nodes();
  double cost = 0.0;
  std::vector<std::uint32_t> roots{0};
  while (!roots.empty()) {
    const std::uint32_t b = roots.back();
    roots.pop_back();
    std::vector<std::uint32_t> slots{b + 1, nodes[b].offset};
    while (slots.size() < static_cast<std::size_t>(kWideBvhWidth)) {
      int widest = -1;
      for (std::size_t i = 0; i < slots.size(); ++i) {
        const BvhNode& n = nodes[slots[i]];
        if (n.count == 0 && (widest < 0 || n.bounds.half_area() > nodes[slots[static_cast<std::size_t>(widest)]].bounds.half_area())) {
          widest = static_cast<int>(i);
        }
      }
      if (widest < 0) break;
      const std::uint32_t opened = slots[static_cast<std::size_t>(widest)];
      slots[static_cast<std::size_t>(widest)] = opened + 1;
      slots.push_back(nodes[opened].offset);
    }
    for (const std::uint32_t s : slots) {
      const BvhNode& n = nodes[s];
      cost += n.bounds.half_area() * (n.count != 0 ? static_cast<double>((n.count + group - 1) / group) : 1.0);
      if (n.count == 0) roots.push_back(s);
    }
  }
  return cost;
}

std::uint32_t subtree_size(const Bvh& bvh, std::uint32_t index) {
  const BvhNode& node = bvh.nodes()[index];
  if (node.count > 0) return node.count;
  return subtree_size(bvh, index + 1) + subtree_size(bvh, node.offset);
}

std::vector<AABB> random_boxes(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> s(-10.0f, 10.0f), e(0.0f, 1.0f);
  std::vector<AABB> boxes(n);
  for (AABB& b : boxes) {
    const glm::vec3 lo{s(rng), s(rng), s(rng)};
    b.grow(lo);
    b.grow(lo + glm::vec3(e(rng), e(rng), e(rng) < 0.2f ? 0.0f : e(rng)));
  }
  return boxes;
}

TEST(BvhBuild, SahTreeIsWellFormed) {
  const std::vector<AABB> boxes = random_boxes(5000, 1);
  for (const int leaf : {1, 2, 4, 8, 16}) {
    SCOPED_TRACE(leaf);
    const Bvh bvh = Bvh::build(boxes, {BvhSplit::Sah, leaf});
    expect_well_formed(bvh, boxes, leaf);
    expect_wide_well_formed(bvh, boxes, leaf);
    EXPECT_GT(bvh.nodes().size(), 5000u / leaf);
  }
}

TEST(BvhBuild, MedianTreeSplitsEveryNodeIntoHalves) {
  const std::vector<AABB> boxes = random_boxes(3001, 2);
  for (const int leaf : {1, 4, 8}) {
    SCOPED_TRACE(leaf);
    const Bvh bvh = Bvh::build(boxes, {BvhSplit::Median, leaf});
    expect_well_formed(bvh, boxes, leaf);
    for (std::uint32_t i = 0; i < bvh.nodes().size(); ++i) {
      const BvhNode& node = bvh.nodes()[i];
      if (node.count > 0) continue;
      const std::uint32_t left = subtree_size(bvh, i + 1), right = subtree_size(bvh, node.offset);
      EXPECT_LE(left, right);
      EXPECT_LE(right - left, 1u) << "node " << i;
      EXPECT_GT(left + right, static_cast<std::uint32_t>(leaf)) << "only nodes over the cap split";
    }
    // The median tree is balanced: ceil(log2(n / leaf)) levels.
    EXPECT_EQ(bvh.depth(), static_cast<int>(std::ceil(std::log2(3001.0 / leaf))));
  }
}

TEST(BvhBuild, HandlesNoneOneAndCoincidentPrimitives) {
  for (const BvhSplit split : {BvhSplit::Sah, BvhSplit::Median}) {
    const Bvh none = Bvh::build({}, {split, 4});
    EXPECT_TRUE(none.nodes().empty());
    EXPECT_EQ(none.depth(), -1);
    Ray ray;
    EXPECT_FALSE(none.closest(ray, [](std::uint32_t, float&) { return true; }, nullptr));
    EXPECT_FALSE(none.any(ray, [](std::uint32_t) { return true; }, nullptr));

    std::vector<AABB> one(1);
    one[0].grow(glm::vec3(1.0f));
    const Bvh single = Bvh::build(one, {split, 4});
    expect_well_formed(single, one, 4);
    EXPECT_EQ(single.depth(), 0);

    // 1000 identical boxes, and 1000 identical points: no axis to bin, so splits by count.
    for (const float size : {1.0f, 0.0f}) {
      std::vector<AABB> same(1000);
      for (AABB& b : same) {
        b.grow(glm::vec3(0.5f));
        b.grow(glm::vec3(0.5f + size));
      }
      const Bvh bvh = Bvh::build(same, {split, 4});
      expect_well_formed(bvh, same, 4);
    }
  }
}

TEST(BvhBuild, LeavesEmptyBoxesOutOfTheTree) {
  std::vector<AABB> boxes = random_boxes(200, 3);
  for (std::size_t i = 0; i < boxes.size(); i += 3) boxes[i] = AABB{};
  for (const BvhSplit split : {BvhSplit::Sah, BvhSplit::Median}) {
    const Bvh bvh = Bvh::build(boxes, {split, 4});
    expect_well_formed(bvh, boxes, 4);
    EXPECT_EQ(bvh.order().size(), 200u - 67u);
  }
  const Bvh all_empty = Bvh::build(std::vector<AABB>(10), {BvhSplit::Sah, 4});
  EXPECT_TRUE(all_empty.nodes().empty());
}

TEST(BvhBuild, StaysShallowWhenSahWouldPeelOnePrimitiveAtATime) {
  // Boxes at exponentially growing distances: each SAH split separates the farthest one, which
  // would make a tree as deep as the box count; the build bounds the depth instead.
  std::vector<AABB> boxes(400);
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    const float x = std::pow(1.2f, static_cast<float>(i));
    boxes[i].grow(glm::vec3(x, 0.0f, 0.0f));
    boxes[i].grow(glm::vec3(x + 0.1f, 1.0f, 1.0f));
  }
  const Bvh bvh = Bvh::build(boxes, {BvhSplit::Sah, 1});
  expect_well_formed(bvh, boxes, 1);
  EXPECT_GE(bvh.depth(), 20);  // it did peel for a while
  // Traversal over the deep tree still finds every box along the x axis.
  Ray ray;
  ray.origin = {0.0f, 0.5f, 0.5f};
  ray.direction = {1.0f, 0.0f, 0.0f};
  std::vector<int> tested(boxes.size(), 0);
  bvh.closest(
      ray,
      [&](std::uint32_t p, float&) {
        ++tested[p];
        return false;
      },
      nullptr);
  EXPECT_TRUE(std::all_of(tested.begin(), tested.end(), [](int t) { return t == 1; }));
}

// The collapse chooses over every way of spreading the binary tree into eight-slot nodes and of
// merging small subtrees into one leaf, so it never costs more than opening each node's largest
// child did; on these inputs it costs less, and merges some of the SAH build's leaves of four.
TEST(BvhCollapse, CostsLessThanOpeningTheLargestChildAndMergesSmallSubtrees) {
  const std::vector<AABB> boxes = random_boxes(5000, 3);
  for (const BvhSplit split : {BvhSplit::Sah, BvhSplit::Median}) {
    for (const int leaf : {1, 4}) {
      SCOPED_TRACE(testing::Message() << (split == BvhSplit::Sah ? "sah" : "median") << ", leaves of " << leaf);
      const Bvh bvh = Bvh::build(boxes, {split, leaf, nullptr, leaf});
      expect_wide_well_formed(bvh, boxes, leaf);
      const auto group = static_cast<std::uint32_t>(leaf);
      const double chosen = wide_cost(bvh, group), largest_first = largest_first_cost(bvh, group);
      EXPECT_LT(chosen, largest_first * 0.99) << chosen << " vs " << largest_first;
      const auto binary_leaves = static_cast<std::size_t>(
          std::count_if(bvh.nodes().begin(), bvh.nodes().end(), [](const BvhNode& n) { return n.count != 0; }));
      // The median build splits only what does not fit one leaf: it leaves nothing to merge.
      if (split == BvhSplit::Sah && leaf > 1) {
        EXPECT_LT(bvh.leaves().size(), binary_leaves) << "small subtrees merged into one leaf";
      } else {
        EXPECT_EQ(bvh.leaves().size(), binary_leaves);
      }
    }
  }
}

TEST(BvhVisit, VisitsEachNodeOnceUpToTheLevelAsked) {
  const std::vector<AABB> boxes = random_boxes(1000, 4);
  const Bvh bvh = Bvh::build(boxes, {BvhSplit::Sah, 4});
  std::size_t all = 0;
  bvh.visit_levels(bvh.depth(), [&](const AABB&, int level) {
    EXPECT_LE(level, bvh.depth());
    ++all;
  });
  EXPECT_EQ(all, bvh.nodes().size());
  std::vector<int> per_level(3, 0);
  bvh.visit_levels(2, [&](const AABB& box, int level) {
    ASSERT_LE(level, 2);
    ++per_level[level];
    if (level == 0) {
      EXPECT_TRUE(box.contains(bvh.nodes()[0].bounds) && bvh.nodes()[0].bounds.contains(box));
    }
  });
  EXPECT_EQ(per_level[0], 1);
  EXPECT_EQ(per_level[1], 2);
  EXPECT_EQ(per_level[2], 4);
  int none = 0;
  bvh.visit_levels(-1, [&](const AABB&, int) { ++none; });
  EXPECT_EQ(none, 0);
}

struct Expected {
  bool hit = false;
  TriangleHit nearest;
};

std::vector<Expected> closest_hits(const MeshAccel& reference, const std::vector<Ray>& rays) {
  std::vector<Expected> out(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) out[i].hit = reference.closest_hit(rays[i], out[i].nearest, nullptr);
  return out;
}

// Compares `tested` with the reference's closest hits on every ray: hit or miss, and then the
// same triangle, t, u and v to the bit (ties at shared edges and duplicates go to the lower
// triangle index whatever the structure: ray_hit_order.h), and any_hit, including shadow rays
// stopped just short of and just past the hit.
void expect_same_hits(const MeshAccel& tested, const std::vector<Expected>& expected,
                      const std::vector<Ray>& rays, const std::string& what) {
  std::size_t hits = 0, failures = 0;
  auto fail = [&](std::size_t i, const std::string& why) {
    if (++failures <= 5) ADD_FAILURE() << what << ", ray " << i << ": " << why;
  };
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Ray& ray = rays[i];
    const TriangleHit& want = expected[i].nearest;
    const bool want_hit = expected[i].hit;
    TriangleHit got;
    const bool got_hit = tested.closest_hit(ray, got, nullptr);
    if (want_hit != got_hit) {
      fail(i, want_hit ? "missed triangle " + std::to_string(want.triangle) : "hit nothing there");
      continue;
    }
    if (tested.any_hit(ray, nullptr) != want_hit) fail(i, "any_hit disagrees with closest_hit");
    if (!want_hit) continue;
    ++hits;
    if (got.triangle != want.triangle) {
      fail(i, "triangle " + std::to_string(got.triangle) + " (t " + std::to_string(got.t) + ") instead of " +
                  std::to_string(want.triangle) + " (t " + std::to_string(want.t) + ")");
    } else if (got.t != want.t || got.u != want.u || got.v != want.v) {
      fail(i, "same triangle, different t or barycentrics");
    }
    Ray shadow = ray;
    shadow.t_max = want.t * (1.0f - 1e-4f);
    if (tested.any_hit(shadow, nullptr)) fail(i, "any_hit before the closest hit");
    shadow.t_max = want.t * (1.0f + 1e-4f);
    if (!tested.any_hit(shadow, nullptr)) fail(i, "any_hit misses up to just past the closest hit");
  }
  EXPECT_EQ(failures, 0u) << what;
  EXPECT_GT(hits, rays.size() / 10) << what << ": the rays should mostly hit something";
}

std::vector<glm::vec3> some_vertices(const ModelTriangles& triangles, std::size_t n) {
  std::vector<glm::vec3> out;
  const std::size_t step = std::max<std::size_t>(1, triangles.positions.size() / n);
  for (std::size_t i = 0; i < triangles.positions.size(); i += step) out.push_back(triangles.positions[i]);
  return out;
}

TEST(MeshAccel, BvhClosestAndAnyHitMatchBruteForceOnRandomSoups) {
  // 100k rays through a small soup, fewer through a larger, deeper one (brute force is slow).
  for (const auto& [size, ray_count] : {std::pair<std::size_t, std::size_t>{200, 100000},
                                        std::pair<std::size_t, std::size_t>{1000, 30000}}) {
    const auto seed = static_cast<std::uint32_t>(size);
    const ModelTriangles triangles(test::random_soup(size, seed));
    const auto sah = build_mesh_accel(triangles, AccelKind::Bvh);
    const auto median = build_mesh_accel(triangles, AccelKind::BvhMedian);
    expect_well_formed(*sah->bvh(), bounds_of(triangles), 8);
    expect_well_formed(*median->bvh(), bounds_of(triangles), 8);
    expect_wide_well_formed(*sah->bvh(), bounds_of(triangles), 4);
    expect_wide_well_formed(*median->bvh(), bounds_of(triangles), 4);
    const std::vector<Ray> rays = test::random_rays(triangles.bounds, ray_count / kRayDivisor, seed,
                                                    some_vertices(triangles, 64));
    const auto expected = closest_hits(*build_mesh_accel(triangles, AccelKind::Naive), rays);
    expect_same_hits(*sah, expected, rays, "sah, soup of " + std::to_string(size));
    expect_same_hits(*median, expected, rays, "median, soup of " + std::to_string(size));
  }
}

// Where several triangles are hit at the same t (the soup's duplicates, shared edges and
// vertices), every structure picks the lowest triangle index (ray_hit_order.h), found here by
// testing every triangle of every ray in the test itself. Before the rule the pick followed the
// tree's order: a new tree shape moved the corners of the Cornell box's walls.
TEST(MeshAccel, TiesGoToTheLowestTriangleIndexWhateverTheTree) {
  const ModelTriangles triangles(test::random_soup(200, 5));
  const std::vector<Ray> rays = test::random_rays(triangles.bounds, 50000 / kRayDivisor, 5, some_vertices(triangles, 64));
  const auto sah = build_mesh_accel(triangles, AccelKind::Bvh);
  const auto median = build_mesh_accel(triangles, AccelKind::BvhMedian);
  const auto naive = build_mesh_accel(triangles, AccelKind::Naive);
  std::size_t ties = 0, mismatches = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    float least = std::numeric_limits<float>::infinity();
    std::uint32_t lowest = 0;
    int at_least = 0;
    for (std::uint32_t t = 0; t < triangles.size(); ++t) {
      const glm::uvec3& tri = triangles.triangles[t];
      const auto h = intersect_triangle(rays[i], triangles.positions[tri.x], triangles.positions[tri.y],
                                        triangles.positions[tri.z]);
      if (!h) continue;
      if (h->t < least) {
        least = h->t;
        lowest = t;
        at_least = 1;
      } else if (h->t == least) {
        ++at_least;  // t only grows, so the first at this t has the lowest index
      }
    }
    if (at_least == 0) continue;
    if (at_least > 1) ++ties;
    for (const MeshAccel* accel : {sah.get(), median.get(), naive.get()}) {
      TriangleHit got;
      if (!accel->closest_hit(rays[i], got, nullptr) || got.triangle != lowest || got.t != least) {
        if (++mismatches <= 5) ADD_FAILURE() << "ray " << i << ": triangle " << got.triangle << " instead of " << lowest;
      }
    }
  }
  EXPECT_EQ(mismatches, 0u);
  EXPECT_GT(ties, 20u) << "the soup's duplicates and shared vertices should give ties";
}

// The traversals built for AVX2 and AVX-512 against the one for any x86-64 (traversal_isa.h):
// the same hits to the bit, and the same nodes and triangles counted (the bvh_cost AOV), ray by
// ray, so a farm of mixed machines renders one image. A build this CPU cannot run is skipped
// (all of them: the test is skipped).
TEST(BvhTraversalIsa, EveryBuildFindsTheSameHitsThroughTheSameNodesAsSse) {
  if (!cpu_has_avx2()) GTEST_SKIP() << "this CPU has no AVX2";
  const ModelTriangles triangles(test::random_soup(3000, 9));
  const std::vector<Ray> rays = test::random_rays(triangles.bounds, 20000 / kRayDivisor, 9, some_vertices(triangles, 64));
  const auto sah = build_mesh_accel(triangles, AccelKind::Bvh);
  struct Answer {
    bool hit = false, any = false, hit_uncounted = false, any_uncounted = false;
    TriangleHit nearest, nearest_uncounted;
    TraversalStats closest_work, any_work;
  };
  auto answers = [&](TraversalIsa isa) {
    const ForcedTraversalIsa forced(isa);
    std::vector<Answer> out(rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i) {
      out[i].hit = sah->closest_hit(rays[i], out[i].nearest, &out[i].closest_work);
      out[i].any = sah->any_hit(rays[i], &out[i].any_work);
      // And without counting (a build of its own: Bvh::traverse).
      out[i].hit_uncounted = sah->closest_hit(rays[i], out[i].nearest_uncounted, nullptr);
      out[i].any_uncounted = sah->any_hit(rays[i], nullptr);
    }
    return out;
  };
  const std::vector<Answer> sse = answers(TraversalIsa::Sse);
  const auto same_hit = [](bool hit_a, const TriangleHit& a, bool hit_b, const TriangleHit& b) {
    return hit_a == hit_b && (!hit_a || (a.triangle == b.triangle && a.t == b.t && a.u == b.u && a.v == b.v));
  };
  int builds = 0;
  for (TraversalIsa isa : {TraversalIsa::Avx2, TraversalIsa::Avx512}) {
    if (!cpu_runs(isa)) continue;
    ++builds;
    SCOPED_TRACE(std::string(to_string(isa)));
    const std::vector<Answer> wide = answers(isa);
    std::size_t hits = 0, failures = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const Answer &a = sse[i], &b = wide[i];
      hits += a.hit;
      const bool same = same_hit(a.hit, a.nearest, b.hit, b.nearest) &&
                        same_hit(a.hit, a.nearest, b.hit_uncounted, b.nearest_uncounted) &&
                        same_hit(a.hit, a.nearest, a.hit_uncounted, a.nearest_uncounted) && a.any == b.any &&
                        a.any == b.any_uncounted && a.any == a.any_uncounted &&
                        a.closest_work.nodes == b.closest_work.nodes &&
                        a.closest_work.triangles == b.closest_work.triangles &&
                        a.any_work.nodes == b.any_work.nodes && a.any_work.triangles == b.any_work.triangles;
      if (!same && ++failures <= 5) ADD_FAILURE() << "ray " << i << ": sse and " << to_string(isa) << " differ";
    }
    EXPECT_EQ(failures, 0u);
    EXPECT_GT(hits, rays.size() / 10);
  }
  EXPECT_GE(builds, 1);
}

// A packet's walk, by counting the leaves it hands its test (Bvh::any_packet, a test that never
// hits, so that every box a ray meets is walked): each ray of a packet is handed exactly the
// leaves any() hands it alone, once each; and eight copies of one ray share one walk, every leaf
// handed once with all eight lanes (AVX2: the walk tests a box against the packet at once; the
// build for any x86-64 runs each ray alone). Coherent rays from an eye, rows of eight, and
// random ones, whose octants split a packet; full and partial packets.
TEST(BvhPacket, EachRayMeetsTheLeavesItMeetsAloneAndCopiesShareOneWalk) {
  const ModelTriangles triangles(test::random_soup(2000, 17));
  const Bvh bvh = Bvh::build(bounds_of(triangles), {BvhSplit::Sah, 4, nullptr, 4});
  const AABB& box = triangles.bounds;
  std::vector<Ray> rays;
  const glm::vec3 eye = box.center() + glm::vec3(0.3f, 0.4f, 2.5f) * glm::length(box.extent());
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 64; ++x) {
      const glm::vec3 at = box.min + box.extent() * glm::vec3((x + 0.5f) / 64.0f, (y + 0.5f) / 16.0f, 0.5f);
      rays.push_back(Ray{eye, at - eye});
    }
  }
  const std::vector<Ray> random = test::random_rays(box, 1024 / kRayDivisor, 17);
  rays.insert(rays.end(), random.begin(), random.end());
  rays.resize(rays.size() / 8 * 8);
  const auto alone = [&](const Ray& ray) {
    std::vector<std::uint32_t> leaves;
    bvh.any(ray, [&](const BvhLeafRef& leaf) { leaves.push_back(leaf.number); return false; }, nullptr);
    std::sort(leaves.begin(), leaves.end());
    return leaves;
  };
  for (const TraversalIsa isa : {TraversalIsa::Sse, TraversalIsa::Avx2}) {
    if (!cpu_runs(isa)) continue;
    SCOPED_TRACE(std::string(to_string(isa)));
    const ForcedTraversalIsa forced(isa);
    std::size_t leaves_met = 0;
    for (std::size_t first = 0; first < rays.size(); first += 8) {
      const unsigned lanes = (first / 8) % 3 == 2 ? 0b01011101u : 0xFFu;
      std::array<std::vector<std::uint32_t>, 8> handed;
      const unsigned hit = bvh.any_packet(&rays[first], lanes, [&](const BvhLeafRef& leaf, unsigned leaf_lanes) {
        EXPECT_EQ(leaf_lanes & ~lanes, 0u) << "ray " << first;
        for (unsigned rest = leaf_lanes; rest; rest &= rest - 1) handed[__builtin_ctz(rest)].push_back(leaf.number);
        return 0u;
      });
      EXPECT_EQ(hit, 0u);
      for (std::size_t i = 0; i < 8; ++i) {
        if (!(lanes >> i & 1u)) {
          EXPECT_TRUE(handed[i].empty()) << "ray " << first + i << ", left out";
          continue;
        }
        std::sort(handed[i].begin(), handed[i].end());
        ASSERT_EQ(handed[i], alone(rays[first + i])) << "ray " << first + i;
        leaves_met += handed[i].size();
      }
      // Eight copies of this packet's first ray.
      const std::array<Ray, 8> copies = {rays[first], rays[first], rays[first], rays[first],
                                         rays[first], rays[first], rays[first], rays[first]};
      std::vector<std::uint32_t> shared;
      bvh.any_packet(copies.data(), 0xFFu, [&](const BvhLeafRef& leaf, unsigned leaf_lanes) {
        if (isa != TraversalIsa::Sse) {
          EXPECT_EQ(leaf_lanes, 0xFFu) << "ray " << first;
        }
        shared.push_back(leaf.number);
        return 0u;
      });
      const std::vector<std::uint32_t> one = alone(rays[first]);
      if (isa == TraversalIsa::Sse) {
        EXPECT_EQ(shared.size(), 8 * one.size()) << "ray " << first;  // eight walks, one a ray
        continue;
      }
      std::sort(shared.begin(), shared.end());
      ASSERT_EQ(shared, one) << "ray " << first;
    }
    EXPECT_GT(leaves_met, rays.size());  // the rays meet leaves: the walks were not empty
  }
}

// A build the CPU cannot run is refused by name; the best one is what runs unless forced.
TEST(BvhTraversalIsa, TheBestBuildRunsByDefaultAndOneTheCpuLacksIsRefused) {
  EXPECT_EQ(traversal_isa(), best_traversal_isa());
  EXPECT_TRUE(cpu_runs(TraversalIsa::Sse));
  EXPECT_EQ(cpu_runs(TraversalIsa::Avx512), cpu_has_avx512());
  EXPECT_TRUE(!cpu_has_avx512() || cpu_has_avx2());
  for (TraversalIsa isa : {TraversalIsa::Sse, TraversalIsa::Avx2, TraversalIsa::Avx512}) {
    if (cpu_runs(isa)) {
      force_traversal_isa(isa);
      EXPECT_EQ(traversal_isa(), isa);
    } else {
      EXPECT_THROW(force_traversal_isa(isa), std::invalid_argument);
    }
  }
  force_traversal_isa(std::nullopt);
  EXPECT_EQ(traversal_isa(), best_traversal_isa());
}

// The lab's models: SAH against the median tree on 100k rays (two independent trees), and both
// against brute force on as many of those rays as keep the suite fast.
TEST(MeshAccel, BvhClosestAndAnyHitMatchBruteForceOnLabModels) {
  const fs::path shared = FARM_SHARED_ASSETS;
  int checked = 0;
  for (const char* name : {"dae/cow.dae", "dae/bunny.dae", "dae/CBbunny.dae"}) {
    if (!fs::exists(shared / name)) continue;
    SCOPED_TRACE(name);
    const ModelTriangles triangles(load_model(shared / name));
    const auto sah = build_mesh_accel(triangles, AccelKind::Bvh);
    const auto median = build_mesh_accel(triangles, AccelKind::BvhMedian);
    expect_well_formed(*sah->bvh(), bounds_of(triangles), 8);
    expect_well_formed(*median->bvh(), bounds_of(triangles), 8);
    expect_wide_well_formed(*sah->bvh(), bounds_of(triangles), 4);
    expect_wide_well_formed(*median->bvh(), bounds_of(triangles), 4);
    std::vector<Ray> rays = test::random_rays(triangles.bounds, 100000 / kRayDivisor, 21,
                                              some_vertices(triangles, 256));
    expect_same_hits(*sah, closest_hits(*median, rays), rays, std::string(name) + ", sah vs median");
    rays.resize(std::min(rays.size(), 20'000'000 / kRayDivisor / triangles.size()));
    const auto expected = closest_hits(*build_mesh_accel(triangles, AccelKind::Naive), rays);
    expect_same_hits(*sah, expected, rays, std::string(name) + ", sah");
    expect_same_hits(*median, expected, rays, std::string(name) + ", median");
    ++checked;
  }
  if (checked == 0) GTEST_SKIP() << "needs the lab's models under " << shared;
}

TEST(MeshAccel, BvhVisitsFarLessThanEveryTriangle) {
  const Model soup = test::random_soup(4000, 31);
  const ModelTriangles triangles(soup);
  const std::vector<Ray> rays = test::random_rays(triangles.bounds, 2000 / kRayDivisor, 31);
  for (const AccelKind kind : {AccelKind::Naive, AccelKind::Bvh, AccelKind::BvhMedian}) {
    const auto accel = build_mesh_accel(triangles, kind);
    TraversalStats closest, any;
    for (const Ray& ray : rays) {
      TriangleHit hit;
      accel->closest_hit(ray, hit, &closest);
      accel->any_hit(ray, &any);
    }
    const double per_ray = static_cast<double>(closest.cost()) / rays.size();
    if (kind == AccelKind::Naive) {
      EXPECT_EQ(closest.triangles, rays.size() * triangles.size());
      EXPECT_EQ(closest.nodes, 0u);
      EXPECT_LE(any.triangles, closest.triangles);
    } else {
      EXPECT_GT(closest.nodes, rays.size());
      EXPECT_GT(closest.triangles, 0u);
      EXPECT_LT(per_ray, triangles.size() / 20.0) << to_string(kind);
      EXPECT_LE(any.cost(), closest.cost()) << "any-hit stops at the first hit";
    }
  }
}

TEST(MeshAccel, HonoursTheRaysInterval) {
  // Two parallel quads at z = 1 and z = 2, seen along +z.
  Mesh mesh;
  mesh.positions = {{-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1},
                    {-1, -1, 2}, {1, -1, 2}, {1, 1, 2}, {-1, 1, 2}};
  mesh.normals.assign(8, {0, 0, -1});
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  Model model;
  model.meshes.push_back(mesh);
  model.materials.push_back(Material{});
  const ModelTriangles triangles(model);
  for (const AccelKind kind : {AccelKind::Naive, AccelKind::Bvh, AccelKind::BvhMedian}) {
    SCOPED_TRACE(std::string(to_string(kind)));
    const auto accel = build_mesh_accel(triangles, kind);
    Ray ray;
    ray.origin = {0.2f, 0.3f, 0.0f};
    ray.direction = {0.0f, 0.0f, 2.0f};  // t in units of |direction|: the quads at t 0.5 and 1
    TriangleHit hit;
    ASSERT_TRUE(accel->closest_hit(ray, hit, nullptr));
    EXPECT_FLOAT_EQ(hit.t, 0.5f);
    EXPECT_LT(hit.triangle, 2u);
    ray.t_min = 0.6f;
    ASSERT_TRUE(accel->closest_hit(ray, hit, nullptr));
    EXPECT_FLOAT_EQ(hit.t, 1.0f);
    EXPECT_GE(hit.triangle, 2u);
    ray.t_max = 0.99f;
    EXPECT_FALSE(accel->closest_hit(ray, hit, nullptr));
    EXPECT_FALSE(accel->any_hit(ray, nullptr));
    ray.t_min = 0.0f;
    ray.direction = -ray.direction;
    ray.t_max = std::numeric_limits<float>::infinity();
    EXPECT_FALSE(accel->closest_hit(ray, hit, nullptr));
    EXPECT_FALSE(accel->any_hit(ray, nullptr));
  }
}

TEST(MeshAccel, ModelWithoutTrianglesIsNeverHit) {
  Model model;
  model.materials.push_back(Material{});
  const ModelTriangles triangles(model);
  for (const AccelKind kind : {AccelKind::Naive, AccelKind::Bvh, AccelKind::BvhMedian}) {
    const auto accel = build_mesh_accel(triangles, kind);
    TriangleHit hit;
    EXPECT_FALSE(accel->closest_hit(Ray{}, hit, nullptr));
    EXPECT_FALSE(accel->any_hit(Ray{}, nullptr));
  }
}

TEST(MeshAccel, EmbreeIsNotAMeshAccel) {
  const ModelTriangles triangles(test::random_soup(10, 1));
  EXPECT_THROW(build_mesh_accel(triangles, AccelKind::Embree), std::invalid_argument);
}

}  // namespace
}  // namespace farm
