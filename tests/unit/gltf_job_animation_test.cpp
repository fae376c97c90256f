// glTF animations in jobs (scene_builder.cpp): an object plays its model's animation at the
// frame's time (frame - start) / fps, node by node, its parts shared by every frame; `animation`
// picks one by name or index, or turns them off. The file is tests/data/animated_nodes.gltf
// (make_gltf_assets.py describes it).
#include <gtest/gtest.h>

#include <filesystem>
#include <glm/vec4.hpp>
#include <nlohmann/json.hpp>

#include "renderer/job/job.h"
#include "renderer/job/scene_builder.h"
#include "renderer/loaders/model_library.h"
#include "renderer/util/input_error.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

// Frames 1-49 at 24 fps: frame 25 is t = 1 s, frame 37 t = 1.5 s.
Job job_with(const Json& animation) {
  Json object = {{"file", "animated_nodes.gltf"}, {"translate", {0, 0, 10}}};
  if (!animation.is_null()) object["animation"] = animation;
  const Json doc = {{"version", 1},
                    {"frames", {{"start", 1}, {"end", 49}, {"fps", 24}}},
                    {"scene", {{"objects", {object}}, {"camera", {{"position", {0, 0, 30}}}}}}};
  return parse_job(doc.dump(), fs::path(FARM_TEST_DATA) / "animated.json");
}

const SceneObject& object_named(const Scene& scene, const std::string& name) {
  for (const SceneObject& o : scene.objects) {
    if (o.name == name) return o;
  }
  ADD_FAILURE() << "no object " << name;
  return scene.objects.front();
}

glm::vec3 place(const SceneObject& o, glm::vec3 baked) { return glm::vec3(o.model_to_world * glm::vec4(baked, 1.0f)); }

void expect_near(glm::vec3 a, glm::vec3 b) {
  EXPECT_NEAR(a.x, b.x, 1e-5f);
  EXPECT_NEAR(a.y, b.y, 1e-5f);
  EXPECT_NEAR(a.z, b.z, 1e-5f);
}

TEST(GltfJobAnimation, AnObjectPlaysItsModelsFirstAnimationAtTheFramesTime) {
  const Job job = job_with(nullptr);
  ModelLibrary models(job.asset_root);
  // "walk": the arm (a child of base at (1,0,0), rest translation (0,2,0)) goes to (4,2,0) over
  // 2 s, so at 1 s its vertex baked at (1,2,0) is at (3,2,0), and the job's (0,0,10) on top.
  const Scene at_1s = build_scene(job_at_frame(job, 25), models);
  expect_near(place(object_named(at_1s, "animated_nodes/arm"), {1, 2, 0}), {3, 2, 10});
  // The head turns 0 -> 90 degrees about +Y over 2 s: 45 at 1 s. Its vertex baked at (2,0,0)
  // (the head sits at (1,0,0)) swings to (1 + cos45, 0, -sin45).
  const float c = std::sqrt(0.5f);
  expect_near(place(object_named(at_1s, "animated_nodes/head"), {2, 0, 0}), {1 + c, 0, 10 - c});
  // The fixed node does not move.
  expect_near(place(object_named(at_1s, "animated_nodes/fixed"), {0, 0, -3}), {0, 0, 7});
  // At frame 1 (t = 0) every node is at its first key: the rest pose here.
  const Scene at_0 = build_scene(job_at_frame(job, 1), models);
  expect_near(place(object_named(at_0, "animated_nodes/arm"), {1, 2, 0}), {1, 2, 10});
  // Every frame shares the parts: the same models, only the placements differ.
  EXPECT_EQ(object_named(at_0, "animated_nodes/arm").model, object_named(at_1s, "animated_nodes/arm").model);
}

TEST(GltfJobAnimation, AnIndexOrANamePicksTheAnimation) {
  // "hop" (index 1), STEP: base scale 1 -> 2 -> 0.5 at 0, 1, 2 s. At 1.5 s the scale is 2: the
  // arm's vertex baked at (1,2,0), (0,2,0) from base, goes to (1,4,0).
  for (const Json& pick : {Json(1), Json("hop")}) {
    const Scene scene = build_scene(job_at_frame(job_with(pick), 37));
    expect_near(place(object_named(scene, "animated_nodes/arm"), {1, 2, 0}), {1, 4, 10});
  }
  // "spline" (index 2), CUBICSPLINE on the hat: (1.75, -0.25, 1) at 1 s instead of linear's
  // (1, 0, 1): its vertex baked at (1,0,1) (rest translation (0,0,1)) moves by (1.75, -0.25, 0).
  const Scene spline = build_scene(job_at_frame(job_with("spline"), 25));
  expect_near(place(object_named(spline, "animated_nodes/hat"), {1, 0, 1}), {2.75, -0.25, 11});
}

TEST(GltfJobAnimation, FalseRendersTheModelAsAStill) {
  const Scene scene = build_scene(job_at_frame(job_with(false), 25));
  ASSERT_EQ(scene.objects.size(), 1u);
  EXPECT_EQ(scene.objects[0].name, "animated_nodes");
  expect_near(place(scene.objects[0], {1, 2, 0}), {1, 2, 10});  // baked, as loaded
}

TEST(GltfJobAnimation, AnAnimationTheModelLacksIsAnErrorNamingWhatItHas) {
  const auto error_of = [](const Json& pick) -> std::string {
    try {
      build_scene(job_with(pick));
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_NE(error_of("run").find("scene.objects[0].animation: 'animated_nodes.gltf' has no animation 'run' (it has "
                                 "'walk', 'hop', 'spline')"),
            std::string::npos)
      << error_of("run");
  EXPECT_NE(error_of(7).find("scene.objects[0].animation: 'animated_nodes.gltf' has 3 animation(s), no animation 7"),
            std::string::npos)
      << error_of(7);
  try {
    job_with(true);
    ADD_FAILURE() << "true was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("scene.objects[0].animation: expected an animation's name or index, or false"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace farm
