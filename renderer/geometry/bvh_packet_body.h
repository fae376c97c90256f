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
// packet's first ray; a stacked node keeps the rays that met it.
template <typename Test>
void Bvh::traverse_packet_avx2(const Ray* rays, unsigned lanes, float* t_max, Test& test) const {
  // The rays axis by axis (lanes outside `lanes` get a harmless direction, never read back).
  alignas(32) float lane_values[7][kPacketWidth];
  for (int i = 0; i < kPacketWidth; ++i) {
    const bool in = (lanes >> i & 1u) != 0;
    for (int a = 0; a < 3; ++a) {
      lane_values[a][i] = in ? rays[i].origin[a] : 0.0f;
      lane_values[3 + a][i] = in ? rays[i].direction[a] : 1.0f;
    }
    lane_values[6][i] = in ? rays[i].t_min : 0.0f;
  }
  // 1 / d and its widened copy, each lane rounded as traverse rounds its ray's (a correctly
  // rounded division and one product, whatever the width).
  const __m256 one = _mm256_set1_ps(1.0f), widen = _mm256_set1_ps(kSlabExitWiden);
  __m256 origin[3], inv[3], inv_far[3];
  unsigned negative[3];
  for (int a = 0; a < 3; ++a) {
    origin[a] = _mm256_load_ps(lane_values[a]);
    inv[a] = _mm256_div_ps(one, _mm256_load_ps(lane_values[3 + a]));
    inv_far[a] = _mm256_mul_ps(inv[a], widen);
    negative[a] = static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(inv[a], _mm256_setzero_ps(), _CMP_LT_OS)));
  }
  const __m256 t_min = _mm256_load_ps(lane_values[6]);
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
    walk_packet_avx2(group, near_row, origin, inv, inv_far, &t_min, t_max, test);
  }
}

template <typename Test>
void Bvh::walk_packet_avx2(unsigned lanes, const std::size_t* near_row, const __m256* origin, const __m256* inv,
                           const __m256* inv_far, const __m256* t_min, float* t_max, Test& test) const {
  alignas(32) float bound[kPacketWidth];
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
  for (;;) {
    const WideBvhNode& node = wide_[index];
    for (int i = 0; i < kPacketWidth; ++i) bound[i] = (active >> i & 1u) ? t_max[i] : -INFINITY;
    const __m256 t_far_start = _mm256_load_ps(bound);  // lanes outside the walk: met by nothing
    // A ray whose bound is -inf (any_packet's, once hit) meets nothing more: when no ray is
    // left, the node is skipped.
    active &= static_cast<unsigned>(
        _mm256_movemask_ps(_mm256_cmp_ps(t_far_start, _mm256_set1_ps(-INFINITY), _CMP_NEQ_OQ)));
    if (active == 0) {
      if (!pop()) break;
      continue;
    }
    alignas(32) float entry[kWideBvhWidth][kPacketWidth];
    unsigned met[kWideBvhWidth];
    int used = 0;
    for (; used < kWideBvhWidth; ++used) {
      const auto c = static_cast<std::size_t>(used);
      if (node.bounds[0][c] == INFINITY) break;  // the unused slots, all after the used ones
      __m256 t_near = *t_min, t_far = t_far_start;
      for (int a = 0; a < 3; ++a) {
        const std::size_t near = near_row[a], far = near ^ 1u;
        const __m256 enter = _mm256_mul_ps(_mm256_sub_ps(_mm256_broadcast_ss(&node.bounds[near][c]), origin[a]), inv[a]);
        const __m256 leave =
            _mm256_mul_ps(_mm256_sub_ps(_mm256_broadcast_ss(&node.bounds[far][c]), origin[a]), inv_far[a]);
        t_near = _mm256_max_ps(enter, t_near);
        t_far = _mm256_min_ps(leave, t_far);
      }
      _mm256_store_ps(entry[c], t_near);
      met[c] = static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(t_near, t_far, _CMP_LE_OS))) & active;
    }
    // The packet's first ray orders the children (any order finds the same hits).
    const int first = __builtin_ctz(active);
    unsigned leaves_met = 0, inner_met = 0;
    for (int c = 0; c < used; ++c) {
      if (met[c] == 0) continue;
      if (node.leaf_mask >> c & 1u) {
        leaves_met |= 1u << c;
      } else {
        inner_met |= 1u << c;
      }
    }
    while (leaves_met) {
      int c = __builtin_ctz(leaves_met);
      for (unsigned rest = leaves_met & (leaves_met - 1); rest; rest &= rest - 1) {
        const int other = __builtin_ctz(rest);
        if (entry[other][first] < entry[c][first]) c = other;
      }
      leaves_met &= ~(1u << c);
      const auto k = static_cast<std::size_t>(c);
      test(BvhLeafRef{node.child[k], node.count[k]}, met[k]);
    }
    if (inner_met != 0) {
      // Stacked farthest first, the nearest entered now.
      std::array<int, kWideBvhWidth> order;
      int n = 0;
      for (; inner_met; inner_met &= inner_met - 1) {
        const int i = __builtin_ctz(inner_met);
        int j = n++;
        while (j > 0 && entry[order[static_cast<std::size_t>(j - 1)]][first] < entry[i][first]) {
          order[static_cast<std::size_t>(j)] = order[static_cast<std::size_t>(j - 1)];
          --j;
        }
        order[static_cast<std::size_t>(j)] = i;
      }
      for (int k = 0; k + 1 < n; ++k) {
        const auto c = static_cast<std::size_t>(order[static_cast<std::size_t>(k)]);
        stack[top++] = {node.child[c], met[c]};
      }
      const auto nearest = static_cast<std::size_t>(order[static_cast<std::size_t>(n - 1)]);
      index = node.child[nearest];
      active = met[nearest];
      continue;
    }
    if (!pop()) break;
  }
}
