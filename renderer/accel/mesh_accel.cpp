#include "renderer/accel/mesh_accel.h"

#include <stdexcept>
#include <string>
#include <vector>

#include "renderer/geometry/bvh.h"
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
    // Leaves of up to 4 triangles: measured (farm bench rt) faster than 8 on incoherent rays.
    bvh_ = Bvh::build(bounds, Bvh::Options{split, 4, &cancel});
    // Corners copied per triangle, in the BVH's leaf order: a leaf's triangles are one
    // contiguous read instead of an index lookup and three scattered position reads. Same float
    // values, so hits equal the naive ones exactly.
    const std::vector<std::uint32_t>& order = bvh_.order();
    corners_.resize(order.size());
    for (std::size_t i = 0; i < order.size(); ++i) {
      const glm::uvec3& tri = triangles.triangles[order[i]];
      corners_[i] = {triangles.positions[tri.x], triangles.positions[tri.y], triangles.positions[tri.z]};
    }
  }

  bool closest_hit(const Ray& ray, TriangleHit& hit, TraversalStats* stats) const override {
    Ray r = ray;
    return bvh_.closest(
        ray,
        [&](std::uint32_t t, std::uint32_t leaf_entry, float& t_max) {
          r.t_max = t_max;
          const Corners& c = corners_[leaf_entry];
          const auto h = intersect_triangle(r, c.a, c.b, c.c);
          if (!h) return false;
          hit = *h;
          hit.triangle = t;
          t_max = h->t;
          return true;
        },
        stats);
  }

  bool any_hit(const Ray& ray, TraversalStats* stats) const override {
    return bvh_.any(
        ray,
        [&](std::uint32_t, std::uint32_t leaf_entry) {
          const Corners& c = corners_[leaf_entry];
          return intersect_triangle(ray, c.a, c.b, c.c).has_value();
        },
        stats);
  }

  const Bvh* bvh() const override { return &bvh_; }

 private:
  struct Corners {
    glm::vec3 a, b, c;
  };
  Bvh bvh_;
  std::vector<Corners> corners_;  // indexed by leaf entry (position in bvh_.order())
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
