#include "renderer/accel/cutout_intersector.h"

#include <bit>
#include <cmath>
#include <cstdint>

#include "renderer/accel/prepared_scene.h"
#include "renderer/texture/material_textures.h"
#include "renderer/util/mix64.h"

namespace farm {
namespace {

// A number uniform in [0, 1) for a ray meeting a triangle: the bits of the ray and the hit, mixed.
float ray_hash(const Ray& ray, const SurfaceHit& hit) {
  std::uint64_t h = mix64((static_cast<std::uint64_t>(hit.object) << 32) ^ hit.triangle);
  for (float f : {ray.origin.x, ray.origin.y, ray.origin.z, ray.direction.x, ray.direction.y, ray.direction.z}) {
    h = mix64(h ^ std::bit_cast<std::uint32_t>(f));
  }
  return unit_float(h);
}

class CutoutIntersector final : public SceneIntersector {
 public:
  explicit CutoutIntersector(std::unique_ptr<SceneIntersector> inner) : inner_(std::move(inner)) {}

  bool closest_hit(const Ray& ray, SurfaceHit& hit, TraversalStats* stats) const override {
    Ray rest = ray;
    for (int layer = 0;; ++layer) {
      if (!inner_->closest_hit(rest, hit, stats)) return false;
      if (layer == kMaxCutoutLayers || !cut_out(*hit.material, hit.uv, ray_hash(ray, hit))) return true;
      // On past this hit (Embree's interval includes its ends: the next float up excludes it).
      rest.t_min = std::nextafter(hit.t, INFINITY);
    }
  }

  bool occluded(const Ray& ray, TraversalStats* stats) const override {
    if (!inner_->occluded(ray, stats)) return false;  // nothing at all in the way
    SurfaceHit hit;
    return closest_hit(ray, hit, stats);
  }

 private:
  std::unique_ptr<SceneIntersector> inner_;
};

}  // namespace

bool has_cutouts(const PreparedScene& scene) {
  for (const PreparedObject& object : scene.objects())
    for (const Material& m : object.source->materials)
      if (m.alpha_mode != AlphaMode::Opaque) return true;
  return false;
}

std::unique_ptr<SceneIntersector> skip_cutouts(const PreparedScene& scene, std::unique_ptr<SceneIntersector> inner) {
  if (!has_cutouts(scene)) return inner;
  return std::make_unique<CutoutIntersector>(std::move(inner));
}

}  // namespace farm
