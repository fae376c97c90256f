#include "renderer/geometry/triangle4_packet.h"

#include <immintrin.h>

#include <limits>

#include "renderer/geometry/ray_packet.h"

namespace farm {

__attribute__((target("avx2"))) Triangle4PacketRays::Triangle4PacketRays(const Ray* rays, unsigned lanes,
                                                                         float t_epsilon) {
  static constexpr float kAbsent[8] = {};
  __m256 rows[8];
  load_ray_packet(rays, lanes, kAbsent, rows);
  for (int axis = 0; axis < 3; ++axis) {
    _mm256_store_ps(origin[axis], rows[kOriginX + axis]);
    _mm256_store_ps(direction[axis], rows[kDirectionX + axis]);
  }
  // triangle_t_lower and triangle_direction_dot (triangle4.h) lane by lane: the same compare and
  // the same products and sums in the same order.
  const __m256 epsilon = _mm256_set1_ps(t_epsilon), t_min = rows[kTMin];
  const __m256 in_packet = lane_mask(lanes);
  _mm256_store_ps(t_lower, _mm256_and_ps(in_packet, _mm256_blendv_ps(t_min, epsilon,
                                                                      _mm256_cmp_ps(t_min, epsilon, _CMP_LT_OS))));
  _mm256_store_ps(ray_t_max, rows[kTMax]);
  const __m256 dx = rows[kDirectionX], dy = rows[kDirectionY], dz = rows[kDirectionZ];
  _mm256_store_ps(direction_dot, _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                                               _mm256_mul_ps(dz, dz)));
}

// AVX2 alone has no fused multiply-add, so nothing here can be contracted: every product and sum
// rounds as intersect_triangle4's do.
__attribute__((target("avx2"))) unsigned intersect_triangle4_packet(const Triangle4PacketRays& rays,
                                                                    const Triangle4& tri, int count,
                                                                    const std::uint32_t* ids, const float* t_max,
                                                                    unsigned lanes, Triangle4PacketHits& hits) {
  const __m256 ox = _mm256_load_ps(rays.origin[0]), oy = _mm256_load_ps(rays.origin[1]),
               oz = _mm256_load_ps(rays.origin[2]);
  const __m256 dx = _mm256_load_ps(rays.direction[0]), dy = _mm256_load_ps(rays.direction[1]),
               dz = _mm256_load_ps(rays.direction[2]);
  const __m256 t_lower = _mm256_load_ps(rays.t_lower), t_upper = _mm256_loadu_ps(t_max);
  const __m256 direction_dot = _mm256_load_ps(rays.direction_dot);
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), tiny = _mm256_set1_ps(1e-24f);
  const __m256i sign = _mm256_set1_epi32(static_cast<int>(0x80000000u));  // unsigned order as signed
  const __m256 in_packet = lane_mask(lanes);
  __m256 best_t = _mm256_set1_ps(std::numeric_limits<float>::infinity()), best_u = zero, best_v = zero;
  __m256i best_id = _mm256_setzero_si256();
  __m256 any = zero;
  for (int k = 0; k < count; ++k) {
    const __m256 ax = _mm256_broadcast_ss(&tri.a[0][k]), ay = _mm256_broadcast_ss(&tri.a[1][k]),
                 az = _mm256_broadcast_ss(&tri.a[2][k]);
    const __m256 e1x = _mm256_broadcast_ss(&tri.e1[0][k]), e1y = _mm256_broadcast_ss(&tri.e1[1][k]),
                 e1z = _mm256_broadcast_ss(&tri.e1[2][k]);
    const __m256 e2x = _mm256_broadcast_ss(&tri.e2[0][k]), e2y = _mm256_broadcast_ss(&tri.e2[1][k]),
                 e2z = _mm256_broadcast_ss(&tri.e2[2][k]);
    // intersect_triangle4's expressions, term for term (products and sums commute exactly).
    const __m256 px = _mm256_sub_ps(_mm256_mul_ps(dy, e2z), _mm256_mul_ps(e2y, dz));
    const __m256 py = _mm256_sub_ps(_mm256_mul_ps(dz, e2x), _mm256_mul_ps(e2z, dx));
    const __m256 pz = _mm256_sub_ps(_mm256_mul_ps(dx, e2y), _mm256_mul_ps(e2x, dy));
    const __m256 det =
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(e1x, px), _mm256_mul_ps(e1y, py)), _mm256_mul_ps(e1z, pz));
    const __m256 inv_det = _mm256_div_ps(one, det);
    const __m256 sx = _mm256_sub_ps(ox, ax), sy = _mm256_sub_ps(oy, ay), sz = _mm256_sub_ps(oz, az);
    const __m256 u = _mm256_mul_ps(
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(sx, px), _mm256_mul_ps(sy, py)), _mm256_mul_ps(sz, pz)), inv_det);
    const __m256 qx = _mm256_sub_ps(_mm256_mul_ps(sy, e1z), _mm256_mul_ps(e1y, sz));
    const __m256 qy = _mm256_sub_ps(_mm256_mul_ps(sz, e1x), _mm256_mul_ps(e1z, sx));
    const __m256 qz = _mm256_sub_ps(_mm256_mul_ps(sx, e1y), _mm256_mul_ps(e1x, sy));
    const __m256 v = _mm256_mul_ps(
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, qx), _mm256_mul_ps(dy, qy)), _mm256_mul_ps(dz, qz)), inv_det);
    const __m256 t = _mm256_mul_ps(
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(e2x, qx), _mm256_mul_ps(e2y, qy)), _mm256_mul_ps(e2z, qz)),
        inv_det);
    // The same predicates: SSE's cmpneq, cmpnlt and cmpngt are the unordered ones (a NaN passes
    // them, as it passes the scalar test), cmpgt and cmplt the ordered ones.
    __m256 ok = _mm256_and_ps(in_packet, _mm256_cmp_ps(det, zero, _CMP_NEQ_UQ));
    ok = _mm256_and_ps(ok, _mm256_and_ps(_mm256_cmp_ps(u, zero, _CMP_NLT_UQ), _mm256_cmp_ps(u, one, _CMP_NGT_UQ)));
    ok = _mm256_and_ps(ok, _mm256_and_ps(_mm256_cmp_ps(v, zero, _CMP_NLT_UQ),
                                         _mm256_cmp_ps(_mm256_add_ps(u, v), one, _CMP_NGT_UQ)));
    ok = _mm256_and_ps(ok, _mm256_and_ps(_mm256_cmp_ps(t, t_lower, _CMP_GT_OS), _mm256_cmp_ps(t, t_upper, _CMP_LT_OS)));
    const __m256 scale2 = _mm256_mul_ps(_mm256_broadcast_ss(&tri.edge_scale[k]), direction_dot);
    ok = _mm256_and_ps(ok, _mm256_cmp_ps(_mm256_mul_ps(det, det), _mm256_mul_ps(tiny, scale2), _CMP_GT_OS));
    // Kept when nearer than the ray's best in this leaf, or as near with a lower id.
    const __m256i id = _mm256_set1_epi32(static_cast<int>(ids[k]));
    const __m256 lower_id = _mm256_castsi256_ps(
        _mm256_cmpgt_epi32(_mm256_xor_si256(best_id, sign), _mm256_xor_si256(id, sign)));
    const __m256 nearer = _mm256_or_ps(_mm256_cmp_ps(t, best_t, _CMP_LT_OS),
                                       _mm256_and_ps(_mm256_cmp_ps(t, best_t, _CMP_EQ_OQ), lower_id));
    const __m256 take = _mm256_and_ps(ok, nearer);
    best_t = _mm256_blendv_ps(best_t, t, take);
    best_u = _mm256_blendv_ps(best_u, u, take);
    best_v = _mm256_blendv_ps(best_v, v, take);
    best_id = _mm256_castps_si256(_mm256_blendv_ps(_mm256_castsi256_ps(best_id), _mm256_castsi256_ps(id), take));
    any = _mm256_or_ps(any, take);
  }
  _mm256_store_ps(hits.t, best_t);
  _mm256_store_ps(hits.u, best_u);
  _mm256_store_ps(hits.v, best_v);
  _mm256_store_si256(reinterpret_cast<__m256i*>(hits.id), best_id);
  return static_cast<unsigned>(_mm256_movemask_ps(any));
}

}  // namespace farm
