#include "renderer/accel/accel_validation.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>
#include <numbers>
#include <vector>

#include "renderer/accel/embree_intersector.h"

#include "renderer/accel/prepared_scene.h"
#include "renderer/geometry/aabb.h"
#include "renderer/util/thread_pool.h"

namespace farm {
namespace {

// Two hits this close in t are the same surface point reached through different triangles (a
// shared edge or vertex), not a disagreement.
constexpr double kTieTolerance = 1e-5;
// Rays per chunk: partial results are kept per chunk and summed in chunk order, so the totals
// (the mean included) do not depend on the thread count.
constexpr std::size_t kChunk = 4096;
// Keeps the validation rays apart from other users of the job's seed.
constexpr std::uint64_t kStream = 0x76616c6964617465ull;  // "validate"

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Counter-based: the value for (ray, dimension) needs no state shared between rays.
double uniform(std::uint64_t seed, std::uint64_t ray, std::uint64_t dimension) {
  const std::uint64_t h = splitmix64(splitmix64(splitmix64(seed ^ kStream) ^ ray) ^ dimension);
  return static_cast<double>(h >> 11) * 0x1.0p-53;  // [0, 1)
}

// The scene's world box, or a unit box around the origin for a scene without triangles.
AABB bounds_to_aim_at(const PreparedScene& scene) {
  const AABB world = scene.world_bounds();
  return world.empty() ? AABB{glm::vec3(-1.0f), glm::vec3(1.0f)} : world;
}

struct RaySet {
  const Camera& camera;
  int width, height;
  std::uint64_t seed;
  std::uint64_t primary;  // rays [0, primary) go through the image, the rest are secondary
  AABB bounds;

  Ray operator()(std::uint64_t i) const {
    if (i < primary) {
      // Spread the primary rays evenly over the pixels, jittered inside each pixel.
      const auto pixels = static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height);
      const auto pixel = std::min(
          pixels - 1, static_cast<std::uint64_t>((static_cast<double>(i) + 0.5) *
                                                  static_cast<double>(pixels) /
                                                  static_cast<double>(primary)));
      const double px = static_cast<double>(pixel % static_cast<std::uint64_t>(width)) + uniform(seed, i, 0);
      const double py = static_cast<double>(pixel / static_cast<std::uint64_t>(width)) + uniform(seed, i, 1);
      return camera.primary_ray(static_cast<float>(px), static_cast<float>(py), width, height);
    }
    Ray ray;
    const glm::vec3 extent = bounds.extent();
    ray.origin = bounds.min + glm::vec3(static_cast<float>(uniform(seed, i, 0)),
                                        static_cast<float>(uniform(seed, i, 1)),
                                        static_cast<float>(uniform(seed, i, 2))) * extent;
    // Uniform on the sphere: z uniform in [-1, 1], azimuth uniform.
    const double z = 1.0 - 2.0 * uniform(seed, i, 3);
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = 2.0 * std::numbers::pi * uniform(seed, i, 4);
    ray.direction = glm::vec3(static_cast<float>(r * std::cos(phi)),
                              static_cast<float>(r * std::sin(phi)), static_cast<float>(z));
    return ray;
  }
};

struct Tally {
  std::uint64_t hit_miss = 0, triangle = 0, compared = 0;
  double max_t = 0.0, sum_t = 0.0;
};

}  // namespace

std::string AccelValidation::summary() const {
  return fmt::format("embree validation: {} rays, {} hit/miss and {} triangle disagreements, "
                     "max relative t difference {:.2g} (mean {:.2g})",
                     rays, hit_miss_disagreements, triangle_disagreements,
                     max_relative_t_difference, mean_relative_t_difference);
}

AccelValidation validate_accel(const PreparedScene& scene, const RenderSettings& settings,
                               const SceneIntersector& ours, const SceneIntersector& reference,
                               std::uint64_t rays) {
  const RaySet ray_set{scene.scene().camera, std::max(1, settings.width),
                       std::max(1, settings.height), settings.seed, rays / 2, bounds_to_aim_at(scene)};

  const double scale = glm::length(ray_set.bounds.extent());
  const std::size_t chunks = (rays + kChunk - 1) / kChunk;
  std::vector<Tally> tallies(chunks);
  ThreadPool pool(settings.threads);
  pool.parallel_for(rays, kChunk, [&](std::size_t begin, std::size_t end, int) {
    Tally& tally = tallies[begin / kChunk];
    for (std::size_t i = begin; i < end; ++i) {
      const Ray ray = ray_set(i);
      SurfaceHit a, b;
      const bool hit_a = ours.closest_hit(ray, a);
      const bool hit_b = reference.closest_hit(ray, b);
      if (hit_a != hit_b) {
        ++tally.hit_miss;
        continue;
      }
      if (!hit_a) continue;
      // Below the scene's size, float noise in t is a fixed fraction of that size, not of t: a
      // ray starting 1e-7 from a surface has t errors of 1e-3 relative to its t.
      const double near_scale = scale / static_cast<double>(glm::length(ray.direction));
      double difference = std::fabs(static_cast<double>(a.t) - static_cast<double>(b.t)) /
                          std::max({std::fabs(static_cast<double>(b.t)), near_scale, 1e-30});
      if (std::isnan(difference)) difference = std::numeric_limits<double>::infinity();
      if ((a.object != b.object || a.triangle != b.triangle) && !(difference <= kTieTolerance)) {
        ++tally.triangle;  // its t difference would only repeat this count
        continue;
      }
      ++tally.compared;
      tally.max_t = std::max(tally.max_t, difference);
      tally.sum_t += difference;
    }
  });

  AccelValidation result;
  result.rays = rays;
  std::uint64_t compared = 0;
  double sum = 0.0;
  for (const Tally& t : tallies) {
    result.hit_miss_disagreements += t.hit_miss;
    result.triangle_disagreements += t.triangle;
    result.max_relative_t_difference = std::max(result.max_relative_t_difference, t.max_t);
    compared += t.compared;
    sum += t.sum_t;
  }
  result.mean_relative_t_difference = compared > 0 ? sum / static_cast<double>(compared) : 0.0;
  return result;
}

AccelKind accel_to_validate(AccelKind accel) {
  return accel == AccelKind::Embree ? AccelKind::Bvh : accel;
}

AccelValidation validate_against_embree(const PreparedScene& scene, const RenderSettings& settings,
                                        AccelKind accel, std::uint64_t rays) {
  const auto ours = cached_scene_intersector(scene, accel);
  const std::unique_ptr<SceneIntersector> embree = build_embree_intersector(scene);
  return validate_accel(scene, settings, *ours, *embree, rays);
}

bool validation_passes(const AccelValidation& v) {
  return static_cast<double>(v.hit_miss_disagreements) <=
         kHitMissTolerance * static_cast<double>(v.rays);
}

}  // namespace farm
