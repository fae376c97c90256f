// The body of Bvh's traversal, included three times by bvh_traversal.h (so no include guard): as
// traverse_sse for any x86-64, as traverse_avx2 inside a region compiled for AVX2, and as
// traverse_avx512 inside one compiled for AVX-512VL. FARM_BVH_TRAVERSE names the member defined,
// FARM_BVH_AVX2 picks the slab test; both are undefined again at the end. The two slab tests do
// the same operations on each child's box: the same bits, the same mask. Included inside
// namespace farm.

// Every build walks the wide nodes: the slab tests give the entry distances of all eight
// children; leaf children are tested at once, nearest first (any hit: in slot order), and the
// nearest inner one is entered next (docs/architecture.md 8, "The tree"). A stacked node is
// dropped when it starts beyond the closest hit found since. `nodes` counts the wide nodes entered.
// kAnyHit: stop at the first primitive hit (t_max never shrinks); otherwise keep the nearest.
// kCount: count into `stats` (a query without them runs without the two counters, whose
// registers the node loop wants: the planes' offsets stayed on the stack with them).
template <bool kAnyHit, bool kCount, typename Test>
bool Bvh::FARM_BVH_TRAVERSE(const Ray& ray, Test& test, TraversalStats* stats) const {
  if (wide_.empty()) return false;
  constexpr bool kLeafTest = kAnyHit ? std::is_invocable_r_v<bool, Test&, const BvhLeafRef&>
                                     : std::is_invocable_r_v<bool, Test&, const BvhLeafRef&, float&>;
  // Per axis, the plane a ray enters a slab by depends only on the direction's sign, so it is
  // picked once per ray: entry = (near plane - o) / d, exit = (far plane - o) / d, no min/max
  // needed. A zero component gives +-inf, and 0 * inf = NaN for a ray lying in a slab's plane;
  // the max/min below keep their running value when handed a NaN first (SSE returns the second
  // operand), so such a ray counts as inside the closed slab, as in AABB::intersect.
  //
  // The three reciprocals in one division (each lane the IEEE quotient: the bits of 1.0f / d),
  // the octant read off their signs, and each axis's row offsets from a table of the eight
  // octants: the set-up every walk pays (every instance a ray enters among them) took 45
  // instructions as three scalar divisions, compares and shifts.
  const __m128 inv_lanes = _mm_div_ps(_mm_set1_ps(1.0f), _mm_loadu_ps(&ray.direction.x));  // lane 3: t_min's, unused
  const auto octant = static_cast<unsigned>(_mm_movemask_ps(_mm_cmplt_ps(inv_lanes, _mm_setzero_ps()))) & 7u;
  // The byte offset in a node of the row of planes the ray enters each axis's slab by (its min
  // row, or its max row for a negative direction); it leaves by the other, kRowBytes away.
  constexpr std::size_t kRowBytes = sizeof(float) * kWideBvhWidth;
  const std::array<std::uint32_t, 4>& near_row = kWideBvhNearRows[octant];
  const auto row = [](const WideBvhNode& node, std::size_t offset) {
    return reinterpret_cast<const float*>(reinterpret_cast<const char*>(node.bounds) + offset);
  };
  // Far distances are widened (kSlabExitWiden, aabb.h: 1 + 2 gamma(3) covers the four roundings
  // of (far - o) * (inv * widen)): the widening goes into the reciprocal once per ray instead of
  // into every distance.
  alignas(16) float inv_dir[4], inv_far_dir[4];
  _mm_store_ps(inv_dir, inv_lanes);
  _mm_store_ps(inv_far_dir, _mm_mul_ps(inv_lanes, _mm_set1_ps(kSlabExitWiden)));
#if FARM_BVH_AVX2
  const __m256 inv[3] = {_mm256_set1_ps(inv_dir[0]), _mm256_set1_ps(inv_dir[1]), _mm256_set1_ps(inv_dir[2])};
  const __m256 inv_far[3] = {_mm256_set1_ps(inv_far_dir[0]), _mm256_set1_ps(inv_far_dir[1]),
                             _mm256_set1_ps(inv_far_dir[2])};
  const __m256 origin[3] = {_mm256_set1_ps(ray.origin.x), _mm256_set1_ps(ray.origin.y), _mm256_set1_ps(ray.origin.z)};
  const __m256 t_min_lanes = _mm256_set1_ps(ray.t_min);
#else
  const __m128 inv[3] = {_mm_set1_ps(inv_dir[0]), _mm_set1_ps(inv_dir[1]), _mm_set1_ps(inv_dir[2])};
  const __m128 inv_far[3] = {_mm_set1_ps(inv_far_dir[0]), _mm_set1_ps(inv_far_dir[1]), _mm_set1_ps(inv_far_dir[2])};
  const __m128 origin[3] = {_mm_set1_ps(ray.origin.x), _mm_set1_ps(ray.origin.y), _mm_set1_ps(ray.origin.z)};
  const __m128 t_min_lanes = _mm_set1_ps(ray.t_min);
#endif
  float t_max = ray.t_max;
  bool hit = false;
  std::uint64_t nodes_visited = 0, primitives_tested = 0;
  struct Pending {
    std::uint32_t index;
    float t_entry;
  };
  std::array<Pending, (kWideBvhWidth - 1) * kMaxDepth> stack;
  int top = 0;
  std::uint32_t index = 0;
  for (;;) {
    const WideBvhNode& node = wide_[index];
    if constexpr (kCount) ++nodes_visited;
    alignas(32) float entry[kWideBvhWidth];
    int mask = 0;
#if FARM_BVH_AVX2
    {
      __m256 t_near = t_min_lanes, t_far = _mm256_set1_ps(t_max);
      for (int a = 0; a < 3; ++a) {
        const __m256 enter = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(row(node, near_row[a])), origin[a]), inv[a]);
        const __m256 leave =
            _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(row(node, near_row[a] ^ kRowBytes)), origin[a]), inv_far[a]);
        t_near = _mm256_max_ps(enter, t_near);  // the second operand on a NaN, as SSE's max
        t_far = _mm256_min_ps(leave, t_far);
      }
      _mm256_store_ps(entry, t_near);
      mask = _mm256_movemask_ps(_mm256_cmp_ps(t_near, t_far, _CMP_LE_OS));  // cmple_ps's predicate
    }
#else
    for (int h = 0; h < kWideBvhWidth; h += 4) {
      __m128 t_near = t_min_lanes, t_far = _mm_set1_ps(t_max);
      for (int a = 0; a < 3; ++a) {
        const __m128 enter = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(row(node, near_row[a]) + h), origin[a]), inv[a]);
        const __m128 leave =
            _mm_mul_ps(_mm_sub_ps(_mm_load_ps(row(node, near_row[a] ^ kRowBytes) + h), origin[a]), inv_far[a]);
        t_near = _mm_max_ps(enter, t_near);
        t_far = _mm_min_ps(leave, t_far);
      }
      _mm_store_ps(entry + h, t_near);
      mask |= _mm_movemask_ps(_mm_cmple_ps(t_near, t_far)) << h;
    }
#endif
    // The children met, leaves and inner nodes apart (bits by slot).
    unsigned leaves_met = static_cast<unsigned>(mask) & node.leaf_mask;
    unsigned inner_met = static_cast<unsigned>(mask) & ~static_cast<unsigned>(node.leaf_mask);
    // Any hit enters the lowest inner slot met next (below). When leaves come first, that node's
    // lines are asked for before the leaf tests, so that its misses overlap theirs: incoherent
    // any hit on the bunny and the cow 4-6% faster, timed in turns against Embree. The closest
    // hit, whose leaves may rule the next node out, gained nothing from the same.
    if (kAnyHit && leaves_met != 0 && inner_met != 0) {
      const char* next = reinterpret_cast<const char*>(&wide_[node.child[__builtin_ctz(inner_met)]]);
      for (std::size_t line = 0; line < sizeof(WideBvhNode); line += 64) _mm_prefetch(next + line, _MM_HINT_T0);
    }
    // Leaf children first. Primitives tested one at a time (the top level's instances, each a
    // whole walk of its model) are taken nearest first for the closest hit, so that the hit found
    // shortens the rest. A leaf tested at once (a mesh's Triangle4) costs little more than
    // picking the nearest did: such leaves, and any hit's (which any occluder ends), are taken in
    // slot order, those that start beyond a hit found skipped (incoherent closest hit on the cow
    // and the bunny 3-6% faster than nearest first, timed in turns against Embree; any hit, farm
    // bench rt, 16-19% faster). The instances taken in slot order cost the grid's camera rays 8%.
    while (leaves_met) {
      int c = __builtin_ctz(leaves_met);
      if constexpr (!kAnyHit && !kLeafTest) {
        for (unsigned rest = leaves_met & (leaves_met - 1); rest; rest &= rest - 1) {
          const int other = __builtin_ctz(rest);
          if (entry[other] < entry[c]) c = other;  // the lower slot of equals: ctz order
        }
        if (entry[c] > t_max) break;  // and so are the others
      }
      leaves_met &= ~(1u << c);
      if constexpr (!kAnyHit && kLeafTest) {
        if (entry[c] > t_max) continue;  // beyond a hit an earlier leaf of the node found
      }
      const auto k = static_cast<std::size_t>(c);
      if constexpr (kLeafTest) {
        if constexpr (kCount) primitives_tested += node.count[k];
        const BvhLeafRef leaf{node.child[k], node.count[k]};
        if constexpr (kAnyHit) {
          hit = test(leaf);
        } else if (test(leaf, t_max)) {
          hit = true;
        }
      } else {
        const std::uint32_t first = leaves_[node.child[k]].first;
        for (std::uint32_t i = first; i < first + node.count[k]; ++i) {
          if constexpr (kCount) ++primitives_tested;
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
    if (inner_met != 0) {
      const int first = __builtin_ctz(inner_met);
      inner_met &= inner_met - 1;
      if (inner_met == 0) {  // one inner child met, the commonest case: entered at once
        if (kAnyHit || entry[first] <= t_max) {
          index = node.child[first];
          continue;
        }
      } else if ((inner_met & (inner_met - 1)) == 0) {  // two: the nearer entered, the other stacked
        const int second = __builtin_ctz(inner_met);
        const bool swap = !kAnyHit && entry[second] < entry[first];
        const int nearer = swap ? second : first, farther = swap ? first : second;
        if (kAnyHit || entry[nearer] <= t_max) {
          stack[top++] = {node.child[farther], entry[farther]};
          index = node.child[nearer];
          continue;
        }
      } else {
        // More: stacked farthest first, so the nearest is popped next.
        std::array<int, kWideBvhWidth> order;
        order[0] = first;
        int n = 1;
        for (; inner_met; inner_met &= inner_met - 1) {
          const int i = __builtin_ctz(inner_met);
          int j = n++;
          while (!kAnyHit && j > 0 && entry[order[static_cast<std::size_t>(j - 1)]] > entry[i]) {
            order[static_cast<std::size_t>(j)] = order[static_cast<std::size_t>(j - 1)];
            --j;
          }
          order[static_cast<std::size_t>(j)] = i;
        }
        for (int k = n - 1; k >= 0; --k) {
          const auto c = static_cast<std::size_t>(order[static_cast<std::size_t>(k)]);
          stack[top++] = {node.child[c], entry[c]};
        }
      }
    }
    // Next: the nearest pending node that still starts before the closest hit.
    while (top > 0 && stack[top - 1].t_entry > t_max) --top;
    if (top == 0) break;
    index = stack[--top].index;
  }
  if (kCount && stats) {
    stats->nodes += nodes_visited;
    stats->triangles += primitives_tested;
  }
  return hit;
}

#undef FARM_BVH_TRAVERSE
#undef FARM_BVH_AVX2
