#include "renderer/accel/mesh_accel.h"

#include <array>
#include <stdexcept>
#include <string>
#include <vector>

#include "renderer/geometry/bvh.h"
#include "renderer/geometry/ray_hit_order.h"
#include "renderer/geometry/triangle4.h"
#include "renderer/geometry/triangle_intersect.h"

namespace farm {
namespace {

// The lab's build: every triangle, in order.
class NaiveAccel final : public MeshAccel {
 public:
  explicit NaiveAccel(const ModelTriangles& triangles) : triangles_(triangles) {}

  bool closest_hit(const Ray& ray, TriangleHit& hit, TraversalStats* stats) const override {
    Ray r = ray;
    bool found = false;
    for (std::uint32_t t = 0; t < triangles_.size(); ++t) {
      const glm::uvec3& tri = triangles_.triangles[t];
      if (auto h = intersect_triangle(r, triangles_.positions[tri.x], triangles_.positions[tri.y],
                                      triangles_.positions[tri.z])) {
        hit = *h;
        hit.triangle = t;
        r.t_max = h->t;
        found = true;
      }
    }
    if (stats) stats->triangles += triangles_.size();
    return found;
  }

  bool any_hit(const Ray& ray, TraversalStats* stats) const override {
    for (std::uint32_t t = 0; t < triangles_.size(); ++t) {
      const glm::uvec3& tri = triangles_.triangles[t];
      if (intersect_triangle(ray, triangles_.positions[tri.x], triangles_.positions[tri.y],
                             triangles_.positions[tri.z])) {
        if (stats) stats->triangles += t + 1;
        return true;
      }
    }
    if (stats) stats->triangles += triangles_.size();
    return false;
  }

 private:
  const ModelTriangles& triangles_;
};

class BvhAccel final : public MeshAccel {
 public:
  BvhAccel(const ModelTriangles& triangles, BvhSplit split, const CancelFlag& cancel) {
    std::vector<AABB> bounds(triangles.size());
    for (std::uint32_t t = 0; t < triangles.size(); ++t) bounds[t] = triangles.triangle_bounds(t);
    // Leaves of up to 4 triangles, one Triangle4 each: measured (farm bench rt) faster than 8 on
    // incoherent rays, and one SIMD test a leaf.
    bvh_ = Bvh::build(bounds, Bvh::Options{split, kLeafSize, &cancel, kLeafSize});
    // Corners copied per leaf, axis by axis (triangle4.h): a leaf is one contiguous read and one
    // test instead of an index lookup and three scattered position reads per triangle. Same
    // float values and arithmetic, so hits equal the naive ones exactly.
    const std::vector<std::uint32_t>& order = bvh_.order();
    packets_.resize(bvh_.leaves().size());
    ids_.resize(bvh_.leaves().size());
    for (std::size_t k = 0; k < bvh_.leaves().size(); ++k) {
      const BvhLeaf& leaf = bvh_.leaves()[k];
      if (leaf.count > kLeafSize) throw std::logic_error("BvhAccel: a leaf larger than one Triangle4");
      for (std::uint32_t lane = 0; lane < leaf.count; ++lane) {
        const std::uint32_t t = order[leaf.first + lane];
        const glm::uvec3& tri = triangles.triangles[t];
        packets_[k].set(static_cast<int>(lane), triangles.positions[tri.x], triangles.positions[tri.y],
                        triangles.positions[tri.z]);
        ids_[k][lane] = t;
      }
    }
  }

  // The nearest hit by ray_hit_order.h's rule: after a hit at t the leaves are tested up to and
  // including t, and an equal t is taken from a lower triangle index only.
  bool closest_hit(const Ray& ray, TriangleHit& hit, TraversalStats* stats) const override {
    const Triangle4Ray packet_ray(ray);
    bool found = false;
    bvh_.closest(
        ray,
        [&](const BvhLeafRef& leaf, float& t_max) {
          __m128 t, u, v;
          const int mask = intersect_triangle4(packet_ray, packets_[leaf.number], t_max, t, u, v);
          if (mask == 0) return false;
          const std::uint32_t* ids = ids_[leaf.number].data();
          const int lane = nearest_lane(mask, t, ids);
          alignas(16) float ts[4], us[4], vs[4];
          _mm_store_ps(ts, t);
          if (found && !nearer_hit(ts[lane], ids[lane], hit.t, hit.triangle)) return false;
          _mm_store_ps(us, u);
          _mm_store_ps(vs, v);
          hit = TriangleHit{ts[lane], us[lane], vs[lane], ids[lane]};
          found = true;
          t_max = limit_through(hit.t);
          return true;
        },
        stats);
    return found;
  }

  bool any_hit(const Ray& ray, TraversalStats* stats) const override {
    const Triangle4Ray packet_ray(ray);
    return bvh_.any(
        ray,
        [&](const BvhLeafRef& leaf) {
          __m128 t, u, v;
          return intersect_triangle4(packet_ray, packets_[leaf.number], ray.t_max, t, u, v) != 0;
        },
        stats);
  }

  const Bvh* bvh() const override { return &bvh_; }

 private:
  static constexpr int kLeafSize = 4;  // one Triangle4
  Bvh bvh_;
  std::vector<Triangle4> packets_;                     // per leaf (Bvh::leaves())
  std::vector<std::array<std::uint32_t, 4>> ids_;      // per leaf, its triangles' ModelTriangles indices
};

}  // namespace

std::unique_ptr<MeshAccel> build_mesh_accel(const ModelTriangles& triangles, AccelKind accel,
                                            const CancelFlag& cancel) {
  switch (accel) {
    case AccelKind::Naive:
      return std::make_unique<NaiveAccel>(triangles);
    case AccelKind::BvhMedian:
      return std::make_unique<BvhAccel>(triangles, BvhSplit::Median, cancel);
    case AccelKind::Bvh:
      return std::make_unique<BvhAccel>(triangles, BvhSplit::Sah, cancel);
    case AccelKind::Embree:
      break;
  }
  throw std::invalid_argument("build_mesh_accel: accel '" + std::string(to_string(accel)) +
                              "' works on whole scenes, not on one model's triangles");
}

}  // namespace farm
