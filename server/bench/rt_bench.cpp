#include "server/bench/rt_bench.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>
#include <numbers>
#include <optional>
#include <vector>

#include "renderer/accel/prepared_scene.h"
#include "renderer/accel/scene_intersector.h"
#include "renderer/trace/sampler.h"
#include "renderer/util/input_error.h"
#include "server/bench/bench_scenes.h"
#include "server/bench/bench_support.h"

namespace farm {
namespace {

using Clock = std::chrono::steady_clock;
using bench::seconds_since;


AABB world_bounds(const PreparedScene& scene) {
  AABB box;
  for (const PreparedObject& o : scene.objects()) {
    const AABB& b = o.triangles->bounds;
    for (int i = 0; i < 8; ++i) {
      const glm::vec3 corner{(i & 1) ? b.max.x : b.min.x, (i & 2) ? b.max.y : b.min.y,
                             (i & 4) ? b.max.z : b.min.z};
      box.grow(glm::vec3(o.model_to_world * glm::vec4(corner, 1.0f)));
    }
  }
  return box;
}

// Coherent rays: a square grid of camera rays that frames the whole scene.
std::vector<Ray> primary_rays(const AABB& bounds, std::uint64_t count) {
  const int side = static_cast<int>(std::sqrt(static_cast<double>(count)));
  Camera camera;
  const glm::vec3 centre = bounds.center();
  const float radius = 0.5f * glm::length(bounds.extent());
  camera.target = centre;
  camera.position = centre + glm::normalize(glm::vec3(0.6f, 0.5f, 1.0f)) * (radius / std::tan(glm::radians(20.0f)));
  std::vector<Ray> rays;
  rays.reserve(static_cast<std::size_t>(side) * static_cast<std::size_t>(side));
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x)
      rays.push_back(camera.primary_ray(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f, side, side));
  return rays;
}

// Incoherent rays: origins uniform in the bounds, directions uniform on the sphere.
std::vector<Ray> incoherent_rays(const AABB& bounds, std::uint64_t count) {
  std::vector<Ray> rays(count);
  for (std::uint64_t i = 0; i < count; ++i) {
    const SampleKey key{7, i, 0};
    const glm::vec3 u{sample_uniform(key, 0), sample_uniform(key, 1), sample_uniform(key, 2)};
    const float z = 1.0f - 2.0f * sample_uniform(key, 3);
    const float phi = 2.0f * std::numbers::pi_v<float> * sample_uniform(key, 4);
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    rays[i].origin = bounds.min + u * bounds.extent();
    rays[i].direction = {r * std::cos(phi), r * std::sin(phi), z};
  }
  return rays;
}

struct RayRates {
  double closest = 0.0, any = 0.0;  // Mrays/s, single thread
};

RayRates measure(const SceneIntersector& intersector, const std::vector<Ray>& rays) {
  RayRates r;
  std::uint64_t hits = 0;
  Clock::time_point t = Clock::now();
  for (const Ray& ray : rays) {
    SurfaceHit hit;
    hits += intersector.closest_hit(ray, hit) ? 1 : 0;
  }
  r.closest = static_cast<double>(rays.size()) / seconds_since(t) / 1e6;
  t = Clock::now();
  for (const Ray& ray : rays) hits += intersector.occluded(ray) ? 1 : 0;
  r.any = static_cast<double>(rays.size()) / seconds_since(t) / 1e6;
  if (hits == std::uint64_t(-1)) fmt::print("");  // keeps the loops from being optimised away
  return r;
}

struct Row {
  AccelKind accel;
  double build_ms = 0.0;
  RayRates primary, incoherent;
};

void bench_scene(const std::string& name, Scene scene, const RtBenchOptions& o, bool with_naive) {
  const PreparedScene prepared(std::move(scene));
  const AABB bounds = world_bounds(prepared);
  std::vector<AccelKind> accels{AccelKind::Bvh, AccelKind::BvhMedian, AccelKind::Embree};
  if (with_naive) accels.push_back(AccelKind::Naive);

  std::vector<Row> rows;
  for (AccelKind accel : accels) {
    const std::uint64_t n = accel == AccelKind::Naive ? o.naive_rays : o.rays;
    const std::vector<Ray> primary = primary_rays(bounds, n), incoherent = incoherent_rays(bounds, n);
    Row row;
    row.accel = accel;
    const Clock::time_point t = Clock::now();
    const auto intersector = build_scene_intersector(prepared, accel);
    row.build_ms = seconds_since(t) * 1e3;
    row.primary = measure(*intersector, primary);
    row.incoherent = measure(*intersector, incoherent);
    rows.push_back(row);
  }

  fmt::print("\n{}: {} triangles, {} object(s); {} rays per set ({} for naive), 1 thread, Mrays/s\n",
             name, prepared.triangle_count(), prepared.objects().size(), o.rays, o.naive_rays);
  fmt::print("{:<18} {:>9} {:>16} {:>12} {:>19} {:>15}\n", "accel", "build ms", "primary closest",
             "primary any", "incoherent closest", "incoherent any");
  for (const Row& r : rows) {
    fmt::print("{:<18} {:>9.2f} {:>16.2f} {:>12.2f} {:>19.2f} {:>15.2f}\n", to_string(r.accel),
               r.build_ms, r.primary.closest, r.primary.any, r.incoherent.closest, r.incoherent.any);
  }
  const Row& embree = rows[2];
  for (const Row& r : rows) {
    if (r.accel == AccelKind::Embree) continue;
    fmt::print("{:<18} {:>9} {:>15.2f}x {:>11.2f}x {:>18.2f}x {:>14.2f}x\n",
               fmt::format("{}/embree", to_string(r.accel)), "",
               r.primary.closest / embree.primary.closest, r.primary.any / embree.primary.any,
               r.incoherent.closest / embree.incoherent.closest,
               r.incoherent.any / embree.incoherent.any);
  }
}

std::shared_ptr<const Model> load(const std::filesystem::path& file) {
  if (!std::filesystem::exists(file)) {
    throw InputError(fmt::format("{}: no such model (pass --assets DIR, the lab's assets folder)",
                                 file.string()));
  }
  return std::make_shared<const Model>(load_model(file));
}

Scene single(const std::shared_ptr<const Model>& model) {
  Scene scene;
  SceneObject object;
  object.name = model->source.stem().string();
  object.model = model;
  object.materials = model->materials;
  scene.objects.push_back(object);
  return scene;
}

}  // namespace

void run_rt_bench(const RtBenchOptions& options) {
  const std::filesystem::path assets =
      options.assets.empty() ? bench::default_cow_path().parent_path().parent_path() : options.assets;
  const auto cow = load(assets / "dae/cow.dae");
  fmt::print("farm bench rt ({} build), models from {}\n", FARM_BUILD_TYPE, assets.string());
  bench_scene("cow.dae", single(cow), options, true);
  bench_scene("bunny.dae", single(load(assets / "dae/bunny.dae")), options, false);
  bench_scene("CBbunny.dae", single(load(assets / "dae/CBbunny.dae")), options, false);
  bench_scene("cow-grid-100", bench::cow_grid(cow, 10), options, false);
}

}  // namespace farm
