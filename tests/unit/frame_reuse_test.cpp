// The frames of one job share what only transforms leave alone (renderer/loaders/model_library.h,
// renderer/accel/model_geometry.h): each model is loaded once, its triangles flattened once
// and its BVH built once; only the top level is built per frame. And sharing changes no bit.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "renderer/accel/instance_intersector.h"
#include "renderer/accel/prepared_scene.h"
#include "renderer/job/job.h"
#include "renderer/job/scene_builder.h"
#include "renderer/loaders/model_library.h"
#include "renderer/render_frame.h"
#include "tests/support/pixel_diff.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

// Two Cornell boxes, the second turning over frames 1-10.
Job turning_boxes(const std::string& engine) {
  const nlohmann::json doc = {
      {"version", 1},
      {"frames", {{"start", 1}, {"end", 10}}},
      {"scene",
       {{"objects", {{{"file", "assets/cornell_box.obj"}},
                     {{"file", "assets/cornell_box.obj"}, {"translate", {0.5, 0, -3}}}}},
        {"camera", {{"position", {0, 0, 4}}, {"target", {0, 0, 0}}}}}},
      {"animate",
       {{{"value", "scene.objects[1].rotate.degrees"},
         {"keys", {{{"frame", 1}, {"value", 0}}, {{"frame", 10}, {"value", 90}}}}}}},
      {"render", {{"engine", engine}, {"width", 32}, {"height", 24}, {"spp", 2}}}};
  return parse_job(doc.dump(), fs::path(FARM_SOURCE_DIR) / "jobs" / "boxes.json");
}

TEST(FrameReuse, AModelIsLoadedOnceForEveryFrame) {
  const Job job = turning_boxes("raster");
  ModelLibrary models(job.asset_root);
  const Scene a = build_scene(job_at_frame(job, 1), models);
  const Scene b = build_scene(job_at_frame(job, 7), models);
  EXPECT_EQ(a.objects[0].model.get(), a.objects[1].model.get());  // one file, one load
  EXPECT_EQ(a.objects[0].model.get(), b.objects[0].model.get());  // and across frames
  EXPECT_NE(a.objects[1].model_to_world, b.objects[1].model_to_world);
}

TEST(FrameReuse, FramesShareTrianglesAndMeshBvhsAndBuildOnlyTheTopLevel) {
  const Job job = turning_boxes("whitted");
  ModelLibrary models(job.asset_root);
  auto geometry = std::make_shared<ModelGeometry>();
  const PreparedScene f1(build_scene(job_at_frame(job, 1), models), geometry);
  const PreparedScene f9(build_scene(job_at_frame(job, 9), models), geometry);
  EXPECT_EQ(f1.objects()[1].triangles, f9.objects()[1].triangles);
  const InstanceIntersector i1(f1, AccelKind::Bvh), i9(f9, AccelKind::Bvh);
  EXPECT_EQ(&i1.mesh_accel_of(1), &i9.mesh_accel_of(1));  // the model's BVH, built once
  EXPECT_EQ(&i1.mesh_accel_of(0), &i9.mesh_accel_of(1));  // and shared by both objects
  EXPECT_NE(i1.top_level(), i9.top_level());              // the top level is each frame's own
}

class SharedFrame : public ::testing::TestWithParam<EngineKind> {};

TEST_P(SharedFrame, RendersTheSameBitsAsAFrameBuiltAlone) {
  const Job job = turning_boxes(std::string(to_string(GetParam())));
  ModelLibrary models(job.asset_root);
  auto geometry = std::make_shared<ModelGeometry>();
  for (int frame : {1, 4, 10}) {
    const Job at = job_at_frame(job, frame);
    const PreparedScene shared(build_scene(at, models), geometry);
    const PreparedScene alone(build_scene(at));
    EXPECT_EQ(test::differing_pixels(render_frame(shared, at.render), render_frame(alone, at.render)), 0) << frame;
  }
}

INSTANTIATE_TEST_SUITE_P(EveryEngine, SharedFrame,
                         ::testing::Values(EngineKind::Raster, EngineKind::Whitted, EngineKind::Path),
                         [](const auto& p) { return std::string(to_string(p.param)); });

}  // namespace
}  // namespace farm
