#include "renderer/geometry/bvh.h"

#include <immintrin.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

namespace farm {
namespace {

constexpr int kBins = 16;
// Cost of visiting a node relative to one leaf test (of Options::test_group primitives at once).
// Leaves cost their tests, so a split must save more than this to be worth a level. Measured
// (farm bench rt and bench path, on every model): 0.125 with Triangle4 leaves; at 0.5 the
// Cornell box's walls shared leaves and its path tracing was 10% slower.
constexpr float kTraversalCost = 0.125f;
// Below this level every split halves the primitive count, so the tree stays shallower than
// Bvh::kMaxDepth (28 + at most 32 more levels for up to 2^32 primitives).
constexpr int kCountSplitLevel = 28;
constexpr std::uint32_t kNoParent = ~0u;
// A node's split reads each of its primitives a few times: about a millisecond's work between
// looks at the cancel flag.
constexpr int kPrimitivesPerPoll = 1 << 16;

struct Task {
  std::uint32_t begin, end;  // range of refs_ (and so of the order() built)
  std::uint32_t parent;      // the node whose second-child offset this node is, or kNoParent
  int level;
};

struct Bin {
  AABB bounds;
  std::uint32_t count = 0;
};

// A primitive as the build moves it: its box and centroid travel with its index, so that every
// pass over a node's range reads one contiguous run of memory (indices into the caller's boxes
// sent each read elsewhere). The ranges are partitioned as the indices were, with the same
// algorithms and predicates, so the tree and order() are what they were.
struct PrimRef {
  AABB box;
  glm::vec3 centroid;
  std::uint32_t index;
};

// A box as two SSE registers (lane 3 unused): growing it is one min and one max instead of six
// scalar ones, the same exact operations in AABB::grow's operand order (glm's min(x, y) is
// y < x ? y : x, which is minps(y, x)), so the boxes, and the tree, are those AABB gave.
struct SseBox {
  __m128 min, max;
  void grow(__m128 point) {
    min = _mm_min_ps(point, min);
    max = _mm_max_ps(point, max);
  }
  // 16 bytes from each corner: max's fourth is the centroid's x, PrimRef's next member.
  void grow(const PrimRef& ref) {
    min = _mm_min_ps(_mm_loadu_ps(&ref.box.min.x), min);
    max = _mm_max_ps(_mm_loadu_ps(&ref.box.max.x), max);
  }
  AABB aabb() const {
    alignas(16) float lo[4], hi[4];
    _mm_store_ps(lo, min);
    _mm_store_ps(hi, max);
    return AABB{{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
  }
};
const SseBox kEmptySseBox{_mm_set1_ps(std::numeric_limits<float>::infinity()),
                          _mm_set1_ps(-std::numeric_limits<float>::infinity())};

class Builder {
 public:
  Builder(std::span<const AABB> boxes, const Bvh::Options& options, std::vector<BvhNode>& nodes)
      : split_(options.split),
        max_leaf_(static_cast<std::uint32_t>(std::clamp(options.max_leaf_size, 1, 255))),
        group_(static_cast<std::uint32_t>(std::clamp(options.test_group, 1, 255))),
        nodes_(nodes),
        poll_(options.cancel ? *options.cancel : CancelFlag::never(), kPrimitivesPerPoll) {
    refs_.reserve(boxes.size());
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      if (boxes[i].empty()) continue;
      glm::vec3 c = boxes[i].center();
      // An infinite box has a NaN centre; NaN would break the orderings below.
      for (int a = 0; a < 3; ++a) {
        if (std::isnan(c[a])) c[a] = 0.0f;
      }
      refs_.push_back({boxes[i], c, static_cast<std::uint32_t>(i)});
    }
  }

  std::uint32_t max_leaf() const { return max_leaf_; }
  std::uint32_t group() const { return group_; }

  // The primitives in leaf order, once run() has built the tree.
  std::vector<std::uint32_t> order() const {
    std::vector<std::uint32_t> order(refs_.size());
    for (std::size_t i = 0; i < refs_.size(); ++i) order[i] = refs_[i].index;
    return order;
  }

  int run() {
    if (refs_.empty()) return -1;
    nodes_.reserve(2 * refs_.size());
    int depth = 0;
    // Depth-first with an explicit stack: pushing the second child before the first puts the
    // first child right after its parent, and no recursion depth limit applies.
    std::vector<Task> stack;
    stack.reserve(2 * static_cast<std::size_t>(Bvh::kMaxDepth));
    stack.push_back({0, static_cast<std::uint32_t>(refs_.size()), kNoParent, 0});
    while (!stack.empty()) {
      const Task task = stack.back();
      stack.pop_back();
      poll_.throw_if_stopped(static_cast<int>(task.end - task.begin));
      const auto index = static_cast<std::uint32_t>(nodes_.size());
      if (task.parent != kNoParent) nodes_[task.parent].offset = index;
      depth = std::max(depth, task.level);

      // The node's box and its centroids' box, grown as in the bins below.
      SseBox box = kEmptySseBox, centroid_box = kEmptySseBox;
      for (std::uint32_t i = task.begin; i < task.end; ++i) {
        box.grow(refs_[i]);
        centroid_box.grow(_mm_loadu_ps(&refs_[i].centroid.x));  // 4th lane: the index, unused
      }
      const AABB bounds = box.aabb(), centroid_bounds = centroid_box.aabb();
      BvhNode node;
      node.bounds = bounds;
      int axis = 0;
      std::uint32_t mid = 0;
      if (!split(task, bounds, centroid_bounds, axis, mid)) {
        node.offset = task.begin;
        node.count = static_cast<std::uint16_t>(task.end - task.begin);
        nodes_.push_back(node);
        continue;
      }
      node.axis = static_cast<std::uint8_t>(axis);
      nodes_.push_back(node);
      stack.push_back({mid, task.end, index, task.level + 1});
      stack.push_back({task.begin, mid, kNoParent, task.level + 1});
    }
    return depth;
  }

 private:
  // Chooses how to split refs_[task.begin, task.end): false for a leaf.
  bool split(const Task& task, const AABB& bounds, const AABB& centroid_bounds, int& axis,
             std::uint32_t& mid) {
    const std::uint32_t n = task.end - task.begin;
    if (n <= 1) return false;
    if (split_ == BvhSplit::Median || task.level >= kCountSplitLevel) {
      if (n <= max_leaf_) return false;
      split_at_median(task, centroid_bounds, axis, mid);
      return true;
    }
    if (n <= std::min<std::uint32_t>(2, max_leaf_)) return false;
    if (!sah_split(task, bounds, centroid_bounds, axis, mid)) {
      if (n <= max_leaf_) return false;
      // All centroids coincide (or SAH found nothing): only a split by count can help.
      split_at_median(task, centroid_bounds, axis, mid);
    }
    return true;
  }

  void split_at_median(const Task& task, const AABB& centroid_bounds, int& axis,
                       std::uint32_t& mid) {
    const glm::vec3 e = centroid_bounds.extent();
    axis = (e.x >= e.y && e.x >= e.z) ? 0 : (e.y >= e.z ? 1 : 2);
    mid = task.begin + (task.end - task.begin) / 2;
    const int a = axis;
    std::nth_element(refs_.begin() + task.begin, refs_.begin() + mid, refs_.begin() + task.end,
                     [&](const PrimRef& p, const PrimRef& q) { return p.centroid[a] < q.centroid[a]; });
  }

  static int bin_of(float c, float lo, float scale, float last_bin) {
    // std::max(0, NaN) is 0, so even a non-finite product lands in a valid bin.
    const float b = std::min(std::max(0.0f, (c - lo) * scale), last_bin);
    return static_cast<int>(b);
  }

  // Binned SAH over the three axes. False when no split is cheaper than a leaf (with n <= the
  // leaf cap) or no axis can be binned; otherwise partitions the range.
  bool sah_split(const Task& task, const AABB& bounds, const AABB& centroid_bounds, int& axis,
                 std::uint32_t& mid) {
    const std::uint32_t n = task.end - task.begin;
    const glm::vec3 lo = centroid_bounds.min, extent = centroid_bounds.extent();
    // Small nodes need fewer bins, and their per-node cost is what dominates the build.
    const int bin_count = static_cast<int>(std::min<std::uint32_t>(kBins, std::max<std::uint32_t>(4, n)));
    const float last_bin = static_cast<float>(bin_count - 1);
    std::array<float, 3> scale{};
    std::array<std::array<Bin, kBins>, 3> bins;
    bool any_axis = false;
    for (int a = 0; a < 3; ++a) {
      scale[a] = extent[a] > 0.0f ? static_cast<float>(bin_count) / extent[a] : 0.0f;
      if (!std::isfinite(scale[a])) scale[a] = 0.0f;
      any_axis = any_axis || scale[a] > 0.0f;
      for (int b = 0; b < bin_count; ++b) bins[a][b] = Bin{};
    }
    if (!any_axis) return false;
    std::array<std::array<SseBox, kBins>, 3> boxes;
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < bin_count; ++b) boxes[a][b] = kEmptySseBox;
    }
    for (std::uint32_t i = task.begin; i < task.end; ++i) {
      const PrimRef& ref = refs_[i];
      for (int a = 0; a < 3; ++a) {
        const int b = bin_of(ref.centroid[a], lo[a], scale[a], last_bin);
        boxes[a][b].grow(ref);
        ++bins[a][b].count;
      }
    }
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < bin_count; ++b) bins[a][b].bounds = boxes[a][b].aabb();
    }

    const float parent_area = bounds.half_area();
    float best_cost = std::numeric_limits<float>::infinity();
    int best_axis = -1, best_bin = 0;
    for (int a = 0; a < 3; ++a) {
      if (scale[a] == 0.0f) continue;
      // right_cost[b]: area * count of bins b+1.. (the right side of a split after bin b).
      std::array<float, kBins> right_cost{};
      AABB right;
      std::uint32_t right_count = 0;
      for (int b = bin_count - 1; b > 0; --b) {
        right.grow(bins[a][b].bounds);
        right_count += bins[a][b].count;
        right_cost[b - 1] = right.half_area() * groups(right_count);
      }
      AABB left;
      std::uint32_t left_count = 0;
      for (int b = 0; b < bin_count - 1; ++b) {
        left.grow(bins[a][b].bounds);
        left_count += bins[a][b].count;
        if (left_count == 0 || left_count == n) continue;
        const float cost = left.half_area() * groups(left_count) + right_cost[b];
        if (cost < best_cost) {
          best_cost = cost;
          best_axis = a;
          best_bin = b;
        }
      }
    }
    if (best_axis < 0) return false;
    // Leaf cost against kTraversalCost + (A_L cost_L + A_R cost_R) / A, without the division so a
    // flat (zero-area) node compares sensibly too.
    if (n <= max_leaf_ && kTraversalCost * parent_area + best_cost >= groups(n) * parent_area) {
      return false;
    }
    axis = best_axis;
    const float a_lo = lo[axis], a_scale = scale[axis];
    const auto first = refs_.begin();
    const auto split_it = std::partition(first + task.begin, first + task.end, [&](const PrimRef& p) {
      return bin_of(p.centroid[axis], a_lo, a_scale, last_bin) <= best_bin;
    });
    mid = static_cast<std::uint32_t>(split_it - first);
    return mid > task.begin && mid < task.end;  // cannot fail: both sides were counted non-empty
  }

  // What testing `count` primitives costs: one test per group of Options::test_group.
  float groups(std::uint32_t count) const { return static_cast<float>((count + group_ - 1) / group_); }

  BvhSplit split_;
  std::uint32_t max_leaf_;
  std::uint32_t group_;
  std::vector<BvhNode>& nodes_;
  CancelPoll poll_;  // counts the primitives each node's split goes over
  std::vector<PrimRef> refs_;  // the non-empty primitives, partitioned node by node
};

}  // namespace

Bvh Bvh::build(std::span<const AABB> primitive_bounds, const Options& options) {
  Bvh bvh;
  Builder builder(primitive_bounds, options, bvh.nodes_);
  bvh.depth_ = builder.run();
  bvh.order_ = builder.order();
  bvh.build_wide(builder.max_leaf(), builder.group());
  return bvh;
}

namespace {

// The collapse's costs, per unit of surface area: entering a wide node (its eight slab tests)
// and one leaf test (a Triangle4, or one primitive where leaves test one at a time) take about as
// long.
constexpr float kWideNodeCost = 1.0f;
constexpr float kLeafTestCost = 1.0f;

// What the collapse works out for one binary node's subtree.
struct Spread {
  // cost[k - 1]: the least cost of the subtree given at most k slots of a wide node, its area
  // times kWideNodeCost for each wide node it needs and times kLeafTestCost for each leaf test.
  std::array<float, kWideBvhWidth> cost;
  // first_slots[k - 1]: of those k slots, how many the first child's subtree takes; 0: the subtree
  // takes one slot itself. first_slots[kWideBvhWidth - 1]: how a wide node made of this
  // subtree shares its slots between the two children.
  std::array<std::uint8_t, kWideBvhWidth> first_slots;
  bool leaf;                   // one slot as a leaf: a binary leaf, or a subtree merged into one
  std::uint32_t first, count;  // its primitives: order()[first, first + count)
};

// Bottom-up over the binary tree (a node's children lie after it in `nodes`).
std::vector<Spread> spread_costs(const std::vector<BvhNode>& nodes, std::uint32_t max_leaf, std::uint32_t group) {
  std::vector<Spread> spread(nodes.size());
  const auto tests = [group](std::uint32_t count) { return static_cast<float>((count + group - 1) / group); };
  for (std::size_t i = nodes.size(); i-- > 0;) {
    const BvhNode& node = nodes[i];
    Spread& s = spread[i];
    const float area = node.bounds.half_area();
    if (node.count != 0) {
      s.cost.fill(area * kLeafTestCost * tests(node.count));
      s.first_slots.fill(0);
      s.leaf = true;
      s.first = node.offset;
      s.count = node.count;
      continue;
    }
    const Spread& a = spread[i + 1];
    const Spread& b = spread[node.offset];
    s.first = a.first;
    s.count = a.count + b.count;
    // The children over k slots: j for the first, k - j for the second.
    std::array<float, kWideBvhWidth> split{};
    for (int k = 2; k <= kWideBvhWidth; ++k) {
      float best = std::numeric_limits<float>::infinity();
      int best_j = 1;
      for (int j = 1; j < k; ++j) {
        const float cost = a.cost[static_cast<std::size_t>(j - 1)] + b.cost[static_cast<std::size_t>(k - j - 1)];
        if (cost < best) {
          best = cost;
          best_j = j;
        }
      }
      split[static_cast<std::size_t>(k - 1)] = best;
      s.first_slots[static_cast<std::size_t>(k - 1)] = static_cast<std::uint8_t>(best_j);
    }
    // One slot: a wide node of its own, or a leaf of all its primitives where they fit one.
    float one = area * kWideNodeCost + split[kWideBvhWidth - 1];
    s.leaf = false;
    if (s.count <= max_leaf) {
      const float leaf = area * kLeafTestCost * tests(s.count);
      if (leaf <= one) {
        one = leaf;
        s.leaf = true;
      }
    }
    s.cost[0] = one;
    s.first_slots[0] = 0;
    for (std::size_t k = 1; k + 1 < kWideBvhWidth; ++k) {
      if (split[k] < one) {
        s.cost[k] = split[k];
      } else {
        s.cost[k] = one;
        s.first_slots[k] = 0;
      }
    }
    // Never read as a spread over eight slots (a parent gives a child at most seven).
    s.cost[kWideBvhWidth - 1] = std::min(one, split[kWideBvhWidth - 1]);
  }
  return spread;
}

}  // namespace

// The binary tree collapsed into wide nodes by the least total cost (spread_costs): which binary
// nodes to open into a wide node's slots, and which small subtrees to merge into one leaf, is
// chosen over the whole tree by dynamic programming, the optimal collapse of the wide-BVH
// literature (Ylitie, Karras and Laine, 2017), instead of opening each node's largest child.
void Bvh::build_wide(std::uint32_t max_leaf, std::uint32_t group) {
  wide_.clear();
  leaves_.clear();
  if (nodes_.empty()) return;
  const std::vector<Spread> spread = spread_costs(nodes_, max_leaf, group);
  // Each wide node's slots as binary nodes, depth-first from the root.
  struct Slots {
    std::array<std::uint32_t, kWideBvhWidth> binary{};
    int used = 0;
  };
  std::vector<Slots> layout(1);
  // The wide node a binary node's children fill, where it is one (the root's: 0).
  std::vector<std::uint32_t> wide_of(nodes_.size(), 0);
  std::vector<std::uint8_t> is_leaf_slot(nodes_.size(), 0);
  std::vector<std::uint32_t> work;  // binary nodes whose wide nodes are still to fill
  if (spread[0].leaf) {
    layout[0].binary[static_cast<std::size_t>(layout[0].used++)] = 0;  // the whole tree one leaf
    is_leaf_slot[0] = 1;
  } else {
    work.push_back(0);
  }
  while (!work.empty()) {
    const std::uint32_t parent = work.back();
    work.pop_back();
    Slots slots;
    // (binary node, slots it may take), first child first.
    std::array<std::pair<std::uint32_t, int>, 2 * kWideBvhWidth> todo;
    int pending = 0;
    const int first = spread[parent].first_slots[kWideBvhWidth - 1];
    todo[static_cast<std::size_t>(pending++)] = {nodes_[parent].offset, kWideBvhWidth - first};
    todo[static_cast<std::size_t>(pending++)] = {parent + 1, first};
    while (pending > 0) {
      const auto [binary, k] = todo[static_cast<std::size_t>(--pending)];
      const int j = spread[binary].first_slots[static_cast<std::size_t>(k - 1)];
      if (j == 0) {
        slots.binary[static_cast<std::size_t>(slots.used++)] = binary;
        continue;
      }
      todo[static_cast<std::size_t>(pending++)] = {nodes_[binary].offset, k - j};
      todo[static_cast<std::size_t>(pending++)] = {binary + 1, j};
    }
    for (int i = 0; i < slots.used; ++i) {
      const std::uint32_t binary = slots.binary[static_cast<std::size_t>(i)];
      if (spread[binary].leaf) {
        is_leaf_slot[binary] = 1;
        continue;
      }
      wide_of[binary] = static_cast<std::uint32_t>(layout.size());
      work.push_back(binary);
      layout.emplace_back();
    }
    layout[wide_of[parent]] = slots;
  }
  // Leaves numbered depth-first, as their primitives lie in order().
  std::vector<std::uint32_t> leaf_number(nodes_.size(), 0);
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    if (!is_leaf_slot[i]) continue;
    leaf_number[i] = static_cast<std::uint32_t>(leaves_.size());
    leaves_.push_back({spread[i].first, spread[i].count});
  }
  wide_.resize(layout.size());
  for (std::size_t w = 0; w < layout.size(); ++w) {
    WideBvhNode& node = wide_[w];
    for (int i = 0; i < kWideBvhWidth; ++i) {
      const auto k = static_cast<std::size_t>(i);
      if (i >= layout[w].used) {
        for (int a = 0; a < 3; ++a) {
          node.bounds[2 * a][k] = INFINITY;
          node.bounds[2 * a + 1][k] = -INFINITY;
        }
        node.child[k] = 0;
        node.count[k] = 0;
        continue;
      }
      const std::uint32_t binary = layout[w].binary[k];
      const BvhNode& n = nodes_[binary];
      for (int a = 0; a < 3; ++a) {
        node.bounds[2 * a][k] = n.bounds.min[a];
        node.bounds[2 * a + 1][k] = n.bounds.max[a];
      }
      if (spread[binary].leaf) {
        node.count[k] = static_cast<std::uint8_t>(spread[binary].count);
        node.leaf_mask = static_cast<std::uint8_t>(node.leaf_mask | (1u << i));
        node.child[k] = leaf_number[binary];
      } else {
        node.count[k] = 0;
        node.child[k] = wide_of[binary];
      }
    }
  }
}

}  // namespace farm
