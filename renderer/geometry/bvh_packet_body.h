// Bvh::traverse_packet_avx2, included once by bvh_traversal.h inside its region compiled for AVX2
// (so no include guard). Included inside namespace farm.

// The rays of `lanes` share one octant: every ray enters each axis's slab by the same plane, so
// a node's row of near planes serves all of them, as in traverse (bvh_traverse_body.h). A lane is
// a ray: each child box is tested against all the packet's rays at once, its planes broadcast,
// with the very operations closest() does for one ray and that box (entry = (near plane - o) *
// 1/d, exit = (far plane - o) * widened 1/d, the max and min in the same order and operand order,
// the same predicate). So a ray meets a box here exactly when it would meet it in closest() at
// the same t_max; only the order the boxes are visited in is the packet's, which the hit rule
// (ray_hit_order.h) makes irrelevant to the hit found. Children are taken nearest first for the
// packet's first ray (any hit: unsorted, its leaves in slot order); a stacked node keeps the rays
// that met it.
template <bool kAnyHit, typename Test>
void Bvh::traverse_packet_avx2(const Ray* rays, unsigned lanes, float* t_max, Test& test) const {
  // The rays axis by axis (lanes outside `lanes` get a harmless direction, never read back).
  static constexpr float kAbsent[8] = {0.0f, 0.0f, 0.0f, 1.0f, 1.0f, 1.0f, 0.0f, 0.0f};
  __m256 rows[8];
  load_ray_packet(rays, lanes, kAbsent, rows);
  // 1 / d and its widened copy, each lane rounded as traverse rounds its ray's (a correctly
  // rounded division and one product, whatever the width).
  const __m256 one = _mm256_set1_ps(1.0f), widen = _mm256_set1_ps(kSlabExitWiden);
  __m256 origin[3], inv[3], inv_far[3];
  unsigned negative[3];
  for (int a = 0; a < 3; ++a) {
    origin[a] = rows[kOriginX + a];
    inv[a] = _mm256_div_ps(one, rows[kDirectionX + a]);
    inv_far[a] = _mm256_mul_ps(inv[a], widen);
    negative[a] = static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(inv[a], _mm256_setzero_ps(), _CMP_LT_OS)));
  }
  const __m256 t_min = rows[kTMin];
  if constexpr (kAnyHit) _mm256_storeu_ps(t_max, rows[kTMax]);  // any_packet's bounds, set here
  // One walk per octant met (the sign of each axis's 1/d, by which traverse picks its planes).
  while (lanes != 0) {
    const int lead = __builtin_ctz(lanes);
    unsigned group = lanes;
    std::size_t near_row[3];
    for (int a = 0; a < 3; ++a) {
      const bool lead_negative = (negative[a] >> lead & 1u) != 0;
      group &= lead_negative ? negative[a] : ~negative[a];
      near_row[a] = 2 * static_cast<std::size_t>(a) + (lead_negative ? 1 : 0);
    }
    lanes &= ~group;
    walk_packet_avx2<kAnyHit>(group, near_row, origin, inv, inv_far, &t_min, t_max, test);
  }
}

template <bool kAnyHit, typename Test>
void Bvh::walk_packet_avx2(unsigned lanes, const std::size_t* near_row, const __m256* origin, const __m256* inv,
                           const __m256* inv_far, const __m256* t_min, float* t_max, Test& test) const {
  struct Pending {
    std::uint32_t index;
    unsigned lanes;
  };
  std::array<Pending, (kWideBvhWidth - 1) * kMaxDepth> stack;
  int top = 0;
  std::uint32_t index = 0;
  unsigned active = lanes;
  // The next stacked node and its rays; false when none is left.
  const auto pop = [&] {
    if (top == 0) return false;
    --top;
    index = stack[top].index;
    active = stack[top].lanes;
    return true;
  };
  const __m256 gone = _mm256_set1_ps(-INFINITY);
  for (;;) {
    // Each ray's bound, -inf for those outside the node's rays: met by nothing. A ray whose bound
    // is -inf (any hit's, once hit) meets nothing more: when no ray is left, the node is skipped,
    // and any hit's walk ends when all its rays are hit.
    const __m256 bounds = _mm256_loadu_ps(t_max);
    const unsigned alive = static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(bounds, gone, _CMP_NEQ_OQ)));
    if (kAnyHit && (alive & lanes) == 0) break;
    active &= alive;
    if (active == 0) {
      if (!pop()) break;
      continue;
    }
    const __m256 t_far_start = _mm256_blendv_ps(gone, bounds, lane_mask(active));
    const WideBvhNode& node = wide_[index];
    alignas(32) float entry[kWideBvhWidth][kPacketWidth];  // the closest hit's order only
    // Byte c: the rays that meet slot c. Kept in a register: eight byte stores read back as one
    // word are not forwarded (9% of the walk's time stalled on it).
    std::uint64_t met = 0;
    const auto met_by = [&met](std::size_t slot) { return static_cast<unsigned>(met >> (8 * slot)) & 0xFFu; };
    // All eight slots, without a branch: an unused slot's box (min +inf, max -inf) is met by no ray.
#pragma GCC unroll 8
    for (int slot = 0; slot < kWideBvhWidth; ++slot) {
      const auto c = static_cast<std::size_t>(slot);
      __m256 t_near = *t_min, t_far = t_far_start;
      for (int a = 0; a < 3; ++a) {
        const std::size_t near = near_row[a], far = near ^ 1u;
        const __m256 enter = _mm256_mul_ps(_mm256_sub_ps(_mm256_broadcast_ss(&node.bounds[near][c]), origin[a]), inv[a]);
        const __m256 leave =
            _mm256_mul_ps(_mm256_sub_ps(_mm256_broadcast_ss(&node.bounds[far][c]), origin[a]), inv_far[a]);
        t_near = _mm256_max_ps(enter, t_near);
        t_far = _mm256_min_ps(leave, t_far);
      }
      if constexpr (!kAnyHit) _mm256_store_ps(entry[c], t_near);
      met |= static_cast<std::uint64_t>(static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(t_near, t_far, _CMP_LE_OS))) &
                                        active)
             << (8 * c);
    }
    // The slots some ray meets: the bytes of `met` that are not zero.
    const unsigned children_met =
        ~static_cast<unsigned>(_mm_movemask_epi8(_mm_cmpeq_epi8(_mm_cvtsi64_si128(static_cast<long long>(met)),
                                                               _mm_setzero_si128()))) & 0xFFu;
    // The packet's first ray orders the children (any order finds the same hits).
    const int first = __builtin_ctz(active);
    unsigned leaves_met = children_met & node.leaf_mask;
    unsigned inner_met = children_met & ~static_cast<unsigned>(node.leaf_mask);
    while (leaves_met) {
      int c = __builtin_ctz(leaves_met);
      for (unsigned rest = leaves_met & (leaves_met - 1); !kAnyHit && rest; rest &= rest - 1) {
        const int other = __builtin_ctz(rest);
        if (entry[other][first] < entry[c][first]) c = other;
      }
      leaves_met &= ~(1u << c);
      const auto k = static_cast<std::size_t>(c);
      test(BvhLeafRef{node.child[k], node.count[k]}, met_by(k));
    }
    if (inner_met != 0) {
      // Stacked farthest first, the nearest entered now.
      std::array<int, kWideBvhWidth> order;
      int n = 0;
      for (; inner_met; inner_met &= inner_met - 1) {
        const int i = __builtin_ctz(inner_met);
        int j = n++;
        while (!kAnyHit && j > 0 && entry[order[static_cast<std::size_t>(j - 1)]][first] < entry[i][first]) {
          order[static_cast<std::size_t>(j)] = order[static_cast<std::size_t>(j - 1)];
          --j;
        }
        order[static_cast<std::size_t>(j)] = i;
      }
      for (int k = 0; k + 1 < n; ++k) {
        const auto c = static_cast<std::size_t>(order[static_cast<std::size_t>(k)]);
        stack[top++] = {node.child[c], met_by(c)};
      }
      const auto nearest = static_cast<std::size_t>(order[static_cast<std::size_t>(n - 1)]);
      index = node.child[nearest];
      active = met_by(nearest);
      continue;
    }
    if (!pop()) break;
  }
}
