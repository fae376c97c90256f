// Frame ranges and keyframes in job files (renderer/job/job.h): frame k of an animated job is
// the still a user would write by hand with the values at k, and bad ranges, paths and keys are
// InputErrors naming the JSON path.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "renderer/accel/prepared_scene.h"
#include "renderer/job/job.h"
#include "renderer/job/scene_builder.h"
#include "renderer/render_frame.h"
#include "renderer/util/input_error.h"
#include "tests/support/pixel_diff.h"
#include "tests/support/print_values.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

// A job beside jobs/cornell.json, reading its Cornell box.
const fs::path kJobFile = fs::path(FARM_SOURCE_DIR) / "jobs" / "animated.json";

Job parse(const Json& doc) { return parse_job(doc.dump(), kJobFile); }

std::string error_of(const Json& doc) {
  try {
    parse(doc);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an InputError for " << doc.dump();
  return {};
}

Json still(const std::string& engine) {
  return Json{{"version", 1},
              {"scene",
               {{"objects", {{{"file", "assets/cornell_box.obj"}, {"rotate", {{"degrees", 0}}},
                              {"material", {{"diffuse", {0.25, 0.5, 0.75}}}}}}},
                {"camera", {{"position", {0, 0, 4}}, {"target", {0, 0, 0}}, {"fov_y", 40}}},
                {"lights", {{{"position", {0, 0.6, 0.5}}, {"intensity", 1.5}}}},
                {"ambient", {0.125, 0.125, 0.125}},
                {"background", {0, 0, 0}}}},
              {"render", {{"engine", engine}, {"width", 40}, {"height", 32}, {"spp", 2}, {"tile_size", 8}}}};
}

// Keys at frames 1 and 25: frame 13 is halfway, where every value below is exact in binary.
Json animated(const std::string& engine) {
  Json doc = still(engine);
  doc["frames"] = {{"start", 1}, {"end", 25}};
  doc["output"] = {{"image", "out/anim.####.exr"}};
  const auto linear = [](const std::string& path, Json a, Json b) {
    return Json{{"value", path}, {"keys", {{{"frame", 1}, {"value", a}}, {{"frame", 25}, {"value", b}}}}};
  };
  doc["animate"] = {linear("scene.objects[0].rotate.degrees", 0, 90),
                    linear("scene.objects[0].material.diffuse", Json{0.25, 0.5, 0.75}, Json{0.75, 0.5, 0.25}),
                    linear("scene.camera.position", Json{0, 0, 4}, Json{1, 0, 4}),
                    linear("scene.camera.fov_y", 40, 50),
                    linear("scene.lights[0].intensity", 1.5, 0.5),
                    linear("scene.ambient", Json{0.125, 0.125, 0.125}, Json{0.375, 0.125, 0.125}),
                    linear("scene.background", Json{0, 0, 0}, Json{0.5, 0.25, 0})};
  return doc;
}

// The values of `animated` at frame 13, written in by hand, as a job of that one frame.
Json frame_13_by_hand(const std::string& engine) {
  Json doc = still(engine);
  doc["frames"] = {{"start", 13}, {"end", 13}};
  doc["output"] = {{"image", "out/hand.####.exr"}};
  Json& scene = doc["scene"];
  scene["objects"][0]["rotate"]["degrees"] = 45;
  scene["objects"][0]["material"]["diffuse"] = {0.5, 0.5, 0.5};
  scene["camera"]["position"] = {0.5, 0, 4};
  scene["camera"]["fov_y"] = 45;
  scene["lights"][0]["intensity"] = 1.0;
  scene["ambient"] = {0.25, 0.125, 0.125};
  scene["background"] = {0.25, 0.125, 0};
  return doc;
}

TileBuffer render(const Job& job) {
  const PreparedScene scene(build_scene(job));
  return render_frame(scene, job.render);
}

class AnimatedFrame : public ::testing::TestWithParam<EngineKind> {};

TEST_P(AnimatedFrame, IsBitIdenticalToTheStillWrittenByHand) {
  const std::string engine(to_string(GetParam()));
  const Job job = parse(animated(engine));
  const Job at_13 = job_at_frame(job, 13);
  const Job by_hand = parse(frame_13_by_hand(engine));
  EXPECT_EQ(at_13.render.frame, 13);
  EXPECT_EQ(by_hand.render.frame, 13);
  EXPECT_EQ(at_13.output.image, fs::path("out/anim.0013.exr"));
  const TileBuffer a = render(at_13), b = render(by_hand);
  EXPECT_EQ(test::differing_pixels(a, b), 0);
  // And the animation does move things: frame 14 is another image.
  EXPECT_GT(test::differing_pixels(render(job_at_frame(job, 14)), b), 0);
}

INSTANTIATE_TEST_SUITE_P(EveryEngine, AnimatedFrame,
                         ::testing::Values(EngineKind::Raster, EngineKind::Whitted, EngineKind::Path),
                         [](const auto& p) { return std::string(to_string(p.param)); });

TEST(JobFrames, AParsedJobIsItsFirstFrameWithNumberedOutputs) {
  Json doc = animated("raster");
  doc["frames"]["step"] = 4;
  doc["frames"]["fps"] = 12;
  const Job job = parse(doc);
  ASSERT_TRUE(job.frames);
  EXPECT_EQ(job_frames(job), (std::vector<int>{1, 5, 9, 13, 17, 21, 25}));
  EXPECT_EQ(job.frame, 1);
  EXPECT_EQ(job.output.image, fs::path("out/anim.0001.exr"));
  EXPECT_EQ(job.output_patterns.image, fs::path("out/anim.####.exr"));
  // The default preview follows the pattern too.
  EXPECT_EQ(job.output.preview, fs::path("out/animated.0001.png"));
  EXPECT_FLOAT_EQ(job.scene.objects[0].transform.rotate_degrees, 0.0f);
  const Job at_9 = job_at_frame(job, 9);
  EXPECT_FLOAT_EQ(at_9.scene.objects[0].transform.rotate_degrees, 30.0f);  // 90 * 8 / 24
  EXPECT_FLOAT_EQ(at_9.scene.camera->fov_y_degrees, 40.0f + 10.0f / 3.0f);
  EXPECT_EQ(at_9.output.image, fs::path("out/anim.0009.exr"));
  EXPECT_DOUBLE_EQ(job.frames->seconds_at(9), 8.0 / 12.0);
}

TEST(JobFrames, WithoutFramesAJobIsTheStillOfFrameZero) {
  const Job job = parse(still("raster"));
  EXPECT_FALSE(job.frames);
  EXPECT_EQ(job_frames(job), std::vector<int>{0});
  EXPECT_EQ(job.render.frame, 0);
  EXPECT_EQ(job.output.image, fs::path("out/animated.exr"));
}

TEST(JobFrames, OnlyPicksFramesOfTheRange) {
  Json doc = animated("raster");
  doc["frames"]["step"] = 2;
  doc["frames"]["only"] = {4, 9};
  const Job job = parse(doc);
  EXPECT_EQ(job_frames(job), (std::vector<int>{5, 7, 9}));
  EXPECT_EQ(job.frame, 5);
}

TEST(JobFrames, BadRangesNameTheirPlace) {
  Json doc = animated("raster");
  doc["frames"]["end"] = 0;
  EXPECT_NE(error_of(doc).find("frames.end: expected an end >= start (1), got 0"), std::string::npos) << error_of(doc);
  doc = animated("raster");
  doc["frames"]["step"] = 0;
  EXPECT_NE(error_of(doc).find("frames.step: expected an integer >= 1, got 0"), std::string::npos) << error_of(doc);
  doc = animated("raster");
  doc["frames"]["fps"] = 0;
  EXPECT_NE(error_of(doc).find("frames.fps:"), std::string::npos) << error_of(doc);
  doc = animated("raster");
  doc["frames"]["only"] = {30, 40};
  EXPECT_NE(error_of(doc).find("frames.only[0]: expected an integer <= 25, got 30"), std::string::npos) << error_of(doc);
  doc = animated("raster");
  doc["frames"]["end"] = 20000;
  EXPECT_NE(error_of(doc).find("frames: 20000 frames; a job renders at most 10000"), std::string::npos)
      << error_of(doc);
}

TEST(JobFrames, AnOutputWithoutAFrameNumberIsRefused) {
  Json doc = animated("raster");
  doc["output"]["image"] = "out/anim.exr";
  EXPECT_NE(error_of(doc).find("output.image: 'out/anim.exr' has no '#' for the frame number"), std::string::npos)
      << error_of(doc);
  doc = animated("raster");
  doc["output"]["preview"] = "out/anim.png";
  EXPECT_NE(error_of(doc).find("output.preview: 'out/anim.png' has no '#'"), std::string::npos) << error_of(doc);
}

TEST(JobFrames, BadAnimatePathsAndKeysNameTheirPlace) {
  const auto with_track = [](Json track) {
    Json doc = animated("raster");
    doc["animate"] = {std::move(track)};
    return doc;
  };
  const auto keys = [](Json a, Json b) { return Json{{{"frame", 1}, {"value", a}}, {{"frame", 9}, {"value", b}}}; };
  const auto expect = [&](const Json& doc, const std::string& wanted) {
    const std::string e = error_of(doc);
    EXPECT_NE(e.find(wanted), std::string::npos) << e;
  };
  expect(with_track({{"value", "scene.objects[3].translate"}, {"keys", keys(Json{0, 0, 0}, Json{1, 1, 1})}}),
         "animate[0].value: 'scene.objects[3].translate' names nothing in the job");
  expect(with_track({{"value", "scene.lamps[0].position"}, {"keys", keys(1, 2)}}),
         "animate[0].value: 'scene.lamps[0].position' names nothing in the job");
  expect(with_track({{"value", "scene.lights[1].position"}, {"keys", keys(Json{0, 0, 0}, Json{1, 1, 1})}}),
         "animate[0].value: 'scene.lights[1].position' names nothing in the job");
  expect(with_track({{"value", "scene.objects[0].file"}, {"keys", keys(1, 2)}}),
         "animate[0].value: 'scene.objects[0].file' is a string (\"assets/cornell_box.obj\"), not a number or a vector");
  expect(with_track({{"value", "render.width"}, {"keys", keys(1, 2)}}),
         "animate[0].value: 'render.width': only values under scene can be animated");
  expect(with_track({{"value", "scene..ambient"}, {"keys", keys(1, 2)}}), "is not a JSON path");
  expect(with_track({{"value", "scene.ambient"},
                     {"keys", {{{"frame", 5}, {"value", Json{0, 0, 0}}}, {{"frame", 2}, {"value", Json{1, 1, 1}}}}}}),
         "animate[0].keys[1].frame: expected a frame after 5 (keys in frame order), got 2");
  expect(with_track({{"value", "scene.ambient"}, {"keys", keys(1, 2)}}),
         "animate[0].keys[0].value: expected 3 numbers like scene.ambient, got a number");
  expect(with_track({{"value", "scene.ambient"}, {"keys", keys(Json{0, 0, 0}, "x")}}),
         "animate[0].keys[1].value: expected a number or up to 4 numbers");
  expect(with_track({{"value", "scene.ambient"}, {"interpolation", "cubic"}, {"keys", keys(Json{0, 0, 0}, Json{1, 1, 1})}}),
         "animate[0].interpolation: unknown interpolation 'cubic' (expected step, linear or smooth)");
  expect(with_track({{"value", "scene.ambient"}, {"keys", Json::array()}}), "animate[0].keys: expected at least one key");
  // A value the animation reaches that the job refuses fails at load, naming the frame.
  expect(with_track({{"value", "scene.camera.fov_y"}, {"keys", keys(40, 200)}}),
         "scene.camera.fov_y: expected a number < 180, got 180.0 (at frame 8, with the animated values)");
  Json twice = animated("raster");
  twice["animate"].push_back(twice["animate"][0]);
  expect(twice, "animate[7].value: 'scene.objects[0].rotate.degrees' is animated twice");
  Json no_frames = animated("raster");
  no_frames.erase("frames");
  no_frames["output"].erase("image");
  expect(no_frames, "animate: keyframes need a frame range");
}

TEST(JobFrames, CheckingEveryFrameOfAnAnimationIsBounded) {
  Json doc = animated("raster");
  doc["frames"] = {{"start", 1}, {"end", 10000}};
  // 7 tracks and 4 on each object added: over 1000, at 10000 frames.
  for (int i = 1; i <= 249; ++i) {
    doc["scene"]["objects"].push_back({{"file", "assets/cornell_box.obj"}});
    for (const char* value : {"translate", "scale", "rotate.degrees", "material.diffuse"}) {
      const bool vector = std::string(value) != "rotate.degrees";
      const Json key = vector ? Json{1, 1, 1} : Json(1);
      doc["animate"].push_back({{"value", fmt::format("scene.objects[{}].{}", i, value)},
                                {"keys", {{{"frame", 1}, {"value", key}}}}});
    }
  }
  const std::string e = error_of(doc);
  EXPECT_NE(e.find("animate: 10000 frames of 1003 keyframed values are too many to check: at most 10000000 values "
                   "over all frames"),
            std::string::npos)
      << e;
  // The bound is on tracks times frames: the same tracks over 1000 frames are checked.
  doc["frames"]["end"] = 1000;
  EXPECT_EQ(parse(doc).scene.objects.size(), 250u);
}

TEST(JobFrames, KeysTheJobDoesNotWriteCanBeAnimated) {
  Json doc = animated("raster");
  doc["scene"]["objects"][0].erase("rotate");  // animated, so added back at each frame
  EXPECT_FLOAT_EQ(job_at_frame(parse(doc), 13).scene.objects[0].transform.rotate_degrees, 45.0f);
  doc["animate"] = {{{"value", "scene.camera.up"},
                     {"keys", {{{"frame", 1}, {"value", {0, 1, 0}}}, {{"frame", 25}, {"value", {1, 1, 0}}}}}}};
  const Job at_13 = job_at_frame(parse(doc), 13);
  EXPECT_FLOAT_EQ(at_13.scene.camera->up.x, 0.5f);
  // An absent key the format does not have is refused as the job is read, naming the path.
  doc["animate"][0]["value"] = "scene.camera.upp";
  EXPECT_NE(error_of(doc).find("animate[0].value: 'scene.camera.upp': scene.camera has no key 'upp' (expected "
                               "position, target, up, fov_y, near, far or aspect)"),
            std::string::npos)
      << error_of(doc);
}

}  // namespace
}  // namespace farm
