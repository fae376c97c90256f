#include "renderer/accel/mesh_accel.h"

#include <array>
#include <new>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "renderer/geometry/bvh.h"
#include "renderer/geometry/ray_hit_order.h"
#include "renderer/geometry/ray_packet.h"
#include "renderer/geometry/traversal_isa.h"
#include "renderer/geometry/triangle4.h"
#include "renderer/geometry/triangle4_packet.h"
#include "renderer/geometry/triangle_intersect.h"
#include "renderer/util/huge_pages.h"

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

// A lone ray's Triangle4Ray, made when a leaf first asks for it: a closest-hit query that meets
// no leaf box (as most of the instances a ray enters and misses) skips its eight broadcasts.
// callgrind, farm bench rt's 1M rays, 1 thread, closest hit: the cow's primary 387.2M -> 364.3M
// instructions, its incoherent 624.3M -> 615.1M, the 100-cow grid's primary 503.7M -> 498.5M
// and incoherent 1,257.5M -> 1,239.2M. Any hit's walk took more with it (the cow's incoherent
// rays 526.6M -> 535.1M), and LaneRays' bit mask for a lone ray more than it saved.
class LazyTriangle4Ray {
 public:
  explicit LazyTriangle4Ray(const Ray& ray) : ray_(ray) {}
  const Triangle4Ray& get() {
    if (!made_) made_ = new (storage_) Triangle4Ray(ray_);
    return *made_;
  }

 private:
  const Ray& ray_;
  const Triangle4Ray* made_ = nullptr;
  alignas(Triangle4Ray) unsigned char storage_[sizeof(Triangle4Ray)];
};

// Each lane's Triangle4Ray, made when a leaf first asks for it: a packet's rays that meet
// leaves only together (tested a ray per lane) never need theirs.
class LaneRays {
 public:
  explicit LaneRays(const Ray* rays) : rays_(rays) {}
  const Triangle4Ray& operator[](int lane) {
    if (!(made_ >> lane & 1u)) {
      new (storage_[lane]) Triangle4Ray(rays_[lane]);
      made_ |= 1u << lane;
    }
    return *std::launder(reinterpret_cast<const Triangle4Ray*>(storage_[lane]));
  }

 private:
  const Ray* rays_;
  alignas(Triangle4Ray) unsigned char storage_[Bvh::kPacketWidth][sizeof(Triangle4Ray)];
  unsigned made_ = 0;
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
    blocks_.resize(bvh_.leaves().size());
    for (std::size_t k = 0; k < bvh_.leaves().size(); ++k) {
      const BvhLeaf& leaf = bvh_.leaves()[k];
      if (leaf.count > kLeafSize) throw std::logic_error("BvhAccel: a leaf larger than one Triangle4");
      for (std::uint32_t lane = 0; lane < leaf.count; ++lane) {
        const std::uint32_t t = order[leaf.first + lane];
        const glm::uvec3& tri = triangles.triangles[t];
        blocks_[k].triangles.set(static_cast<int>(lane), triangles.positions[tri.x], triangles.positions[tri.y],
                                 triangles.positions[tri.z]);
        blocks_[k].ids[lane] = t;
      }
    }
  }

  // The nearest hit by ray_hit_order.h's rule: after a hit at t the leaves are tested up to and
  // including t, and an equal t is taken from a lower triangle index only.
  bool closest_hit(const Ray& ray, TriangleHit& hit, TraversalStats* stats) const override {
    LazyTriangle4Ray packet_ray(ray);
    bool found = false;
    bvh_.closest(
        ray, [&](const BvhLeafRef& leaf, float& t_max) { return test_leaf(packet_ray.get(), leaf, t_max, hit, found); },
        stats);
    return found;
  }

  unsigned closest_hit_packet(const Ray* rays, unsigned lanes, float* t_max, TriangleHit* hits) const override {
    // A leaf that most of the packet meets is tested a ray per lane (triangle4_packet.h, AVX2:
    // the packet walk runs only there); one that a few rays meet, ray by ray, each lane's
    // Triangle4Ray made when a leaf first asks for it. Both give each ray the same hit.
    const bool transposed = traversal_isa() != TraversalIsa::Sse;
    std::optional<Triangle4PacketRays> packet_rays;
    if (transposed) packet_rays.emplace(rays, lanes);
    LaneRays lane_rays(rays);
    unsigned found = 0;
    bvh_.closest_packet(rays, lanes, t_max, [&](const BvhLeafRef& leaf, unsigned leaf_lanes) {
      if (transposed && lane_count(leaf_lanes) >= kTransposedFrom) {
        Triangle4PacketHits leaf_hits;
        const std::uint32_t* ids = blocks_[leaf.number].ids.data();
        const unsigned met = intersect_triangle4_packet(*packet_rays, blocks_[leaf.number].triangles,
                                                        static_cast<int>(leaf.count), ids, t_max, leaf_lanes,
                                                        leaf_hits);
        for (unsigned rest = met; rest; rest &= rest - 1) {
          const int i = __builtin_ctz(rest);
          const unsigned bit = 1u << i;
          if ((found & bit) && !nearer_hit(leaf_hits.t[i], leaf_hits.id[i], hits[i].t, hits[i].triangle)) continue;
          hits[i] = TriangleHit{leaf_hits.t[i], leaf_hits.u[i], leaf_hits.v[i], leaf_hits.id[i]};
          found |= bit;
          t_max[i] = limit_through(hits[i].t);
        }
        return;
      }
      for (; leaf_lanes; leaf_lanes &= leaf_lanes - 1) {
        const int i = __builtin_ctz(leaf_lanes);
        const unsigned bit = 1u << i;
        bool lane_found = (found & bit) != 0;
        if (test_leaf(lane_rays[i], leaf, t_max[i], hits[i], lane_found)) found |= bit;
      }
    });
    return found;
  }

  bool any_hit(const Ray& ray, TraversalStats* stats) const override {
    const Triangle4Ray packet_ray(ray);  // not LazyTriangle4Ray: any hit's walk took more instructions with it
    return bvh_.any(
        ray,
        [&](const BvhLeafRef& leaf) {
          __m128 t, u, v;
          return intersect_triangle4(packet_ray, blocks_[leaf.number].triangles, ray.t_max, t, u, v) != 0;
        },
        stats);
  }

  unsigned any_hit_packet(const Ray* rays, unsigned lanes) const override {
    // As closest_hit_packet: a leaf most of the packet meets tested a ray per lane, else ray by
    // ray; either way a ray is hit when intersect_triangle4 finds a hit for it, as in any_hit.
    const bool transposed = traversal_isa() != TraversalIsa::Sse;
    std::optional<Triangle4PacketRays> packet_rays;
    if (transposed) packet_rays.emplace(rays, lanes);
    LaneRays lane_rays(rays);
    return bvh_.any_packet(rays, lanes, [&](const BvhLeafRef& leaf, unsigned leaf_lanes) {
      if (transposed && lane_count(leaf_lanes) >= kTransposedFrom) {
        Triangle4PacketHits leaf_hits;
        const LeafBlock& block = blocks_[leaf.number];
        return intersect_triangle4_packet(*packet_rays, block.triangles, static_cast<int>(leaf.count), block.ids.data(),
                                          packet_rays->ray_t_max, leaf_lanes, leaf_hits);
      }
      unsigned met = 0;
      for (; leaf_lanes; leaf_lanes &= leaf_lanes - 1) {
        const int i = __builtin_ctz(leaf_lanes);
        __m128 t, u, v;
        if (intersect_triangle4(lane_rays[i], blocks_[leaf.number].triangles, rays[i].t_max, t, u, v) != 0) {
          met |= 1u << i;
        }
      }
      return met;
    });
  }

  const Bvh* bvh() const override { return &bvh_; }

 private:
  // One leaf's Triangle4 against a ray, keeping the nearest hit by ray_hit_order.h's rule: after
  // a hit at t the leaves are tested up to and including t, and an equal t is taken from a lower
  // triangle index only. Lowers t_max past a hit kept.
  bool test_leaf(const Triangle4Ray& ray, const BvhLeafRef& leaf, float& t_max, TriangleHit& hit,
                 bool& found) const {
    __m128 t, u, v;
    const int mask = intersect_triangle4(ray, blocks_[leaf.number].triangles, t_max, t, u, v);
    if (mask == 0) return false;
    const std::uint32_t* ids = blocks_[leaf.number].ids.data();
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
  }

  static constexpr int kLeafSize = 4;  // one Triangle4
  static constexpr int kTransposedFrom = 4;  // rays of a packet meeting a leaf
  Bvh bvh_;
  // A leaf's Triangle4 and its triangles' ModelTriangles indices in three whole cache lines: the
  // test reads three lines, never four, and a hit's index comes from a line the test read.
  struct alignas(64) LeafBlock {
    Triangle4 triangles;
    std::array<std::uint32_t, 4> ids{};
  };
  static_assert(sizeof(LeafBlock) == 192);
  std::vector<LeafBlock, LargeArrayAllocator<LeafBlock>> blocks_;  // per leaf (Bvh::leaves()); huge pages when large
};

}  // namespace

unsigned MeshAccel::closest_hit_packet(const Ray* rays, unsigned lanes, float* t_max, TriangleHit* hits) const {
  unsigned found = 0;
  for (; lanes; lanes &= lanes - 1) {
    const int i = __builtin_ctz(lanes);
    Ray ray = rays[i];
    ray.t_max = t_max[i];
    if (closest_hit(ray, hits[i], nullptr)) {
      found |= 1u << i;
      t_max[i] = limit_through(hits[i].t);
    }
  }
  return found;
}

unsigned MeshAccel::any_hit_packet(const Ray* rays, unsigned lanes) const {
  unsigned hit = 0;
  for (; lanes; lanes &= lanes - 1) {
    const int i = __builtin_ctz(lanes);
    if (any_hit(rays[i], nullptr)) hit |= 1u << i;
  }
  return hit;
}

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
