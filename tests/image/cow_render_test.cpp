// The lab's cow job, checked against an independent computation: one ray per pixel centre,
// intersected with every triangle by brute force (no rasterizer code involved).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <atomic>
#include <filesystem>
#include <glm/geometric.hpp>
#include <thread>
#include <vector>

#include "renderer/accel/prepared_scene.h"
#include "renderer/geometry/triangle_intersect.h"
#include "renderer/job/job.h"
#include "renderer/job/scene_builder.h"
#include "renderer/render_frame.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

struct WorldTriangle {
  glm::vec3 a, b, c;
};

std::vector<WorldTriangle> world_triangles(const Scene& scene, AABB& bounds) {
  std::vector<WorldTriangle> out;
  for (const SceneObject& o : scene.objects) {
    for (const Mesh& m : o.model->meshes) {
      for (const glm::uvec3& t : m.triangles) {
        WorldTriangle w;
        w.a = glm::vec3(o.model_to_world * glm::vec4(m.positions[t.x], 1.0f));
        w.b = glm::vec3(o.model_to_world * glm::vec4(m.positions[t.y], 1.0f));
        w.c = glm::vec3(o.model_to_world * glm::vec4(m.positions[t.z], 1.0f));
        bounds.grow(w.a);
        bounds.grow(w.b);
        bounds.grow(w.c);
        out.push_back(w);
      }
    }
  }
  return out;
}

bool ray_hits_box(const Ray& ray, const AABB& box) {
  float t0 = 0.0f, t1 = INFINITY;
  for (int axis = 0; axis < 3; ++axis) {
    const float inv = 1.0f / ray.direction[axis];
    float a = (box.min[axis] - ray.origin[axis]) * inv, b = (box.max[axis] - ray.origin[axis]) * inv;
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  return t0 <= t1;
}

TEST(CowImage, SilhouetteAndDepthMatchABruteForceRayCast) {
  const fs::path job_file = fs::path(FARM_SOURCE_DIR) / "jobs" / "cow.json";
  const fs::path shared = fs::path(FARM_SHARED_ASSETS) / "dae" / "cow.dae";
  if (!fs::exists(shared)) GTEST_SKIP() << "needs the lab's cow at " << shared;

  JobLoadOptions load;
  load.asset_root = fs::canonical(FARM_SHARED_ASSETS);  // as the README runs it
  Job job = load_job(job_file, load);
  ASSERT_EQ(job.render.width, 640);
  ASSERT_EQ(job.render.height, 480);
  job.render.aovs.depth = true;
  const PreparedScene prepared(build_scene(job));
  ASSERT_EQ(prepared.triangle_count(), 5856u);
  const TileBuffer image = render_frame(prepared, job.render);

  const Camera& camera = prepared.scene().camera;
  AABB bounds;
  const std::vector<WorldTriangle> triangles = world_triangles(prepared.scene(), bounds);
  const int width = job.render.width, height = job.render.height;

  // Reference depth per pixel: nearest hit along the viewing axis within [near, far].
  std::vector<float> reference(static_cast<std::size_t>(width * height), INFINITY);
  std::atomic<int> next_row{0};
  auto cast_rows = [&] {
    for (int y = next_row++; y < height; y = next_row++) {
      for (int x = 0; x < width; ++x) {
        const Ray ray = camera.primary_ray(x + 0.5f, y + 0.5f, width, height);
        if (!ray_hits_box(ray, bounds)) continue;
        float nearest = INFINITY;
        for (const WorldTriangle& t : triangles) {
          if (auto hit = intersect_triangle(ray, t.a, t.b, t.c)) nearest = std::min(nearest, hit->t);
        }
        if (nearest >= camera.near && nearest <= camera.far) reference[y * width + x] = nearest;
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned i = 1; i < std::max(1u, std::thread::hardware_concurrency()); ++i) pool.emplace_back(cast_rows);
  cast_rows();
  for (auto& t : pool) t.join();

  int agree = 0, covered = 0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const float ref = reference[y * width + x];
      const bool raster_hit = image.rgba(x, y).w == 1.0f;
      covered += raster_hit ? 1 : 0;
      if (raster_hit != std::isfinite(ref)) continue;
      if (raster_hit && std::abs(image.depth(x, y) - ref) > 1e-3f * ref) continue;
      ++agree;
    }
  }
  const double fraction = static_cast<double>(agree) / (width * height);
  std::printf("cow: %d of %d pixels agree (%.3f%%), %d covered by the rasterizer\n", agree,
              width * height, 100.0 * fraction, covered);
  EXPECT_GT(covered, width * height / 20) << "the cow should fill a good part of the frame";
  EXPECT_GE(fraction, 0.995) << agree << " of " << width * height << " pixels agree";
}

}  // namespace
}  // namespace farm
