// output.video in job files (renderer/job/job.h) and its command-line overrides
// (server/client/render_overrides.h): a video needs frames and the previews and a type ffmpeg is
// asked to make, and each refusal names the JSON path or the option.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "renderer/job/job.h"
#include "renderer/job/video_format.h"
#include "renderer/util/input_error.h"
#include "server/client/render_overrides.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

// A job beside jobs/cornell.json, reading its Cornell box.
const fs::path kJobFile = fs::path(FARM_SOURCE_DIR) / "jobs" / "video.json";

Json animated() {
  return Json{{"version", 1},
              {"frames", {{"start", 1}, {"end", 4}}},
              {"scene", {{"objects", {{{"file", "assets/cornell_box.obj"}}}}}},
              {"render", {{"width", 64}, {"height", 48}}},
              {"output", {{"image", "out/v.####.exr"}, {"preview", "out/v.####.png"}, {"video", "out/v.mp4"}}}};
}

std::string error_of(const Json& doc) {
  try {
    parse_job(doc.dump(), kJobFile);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an InputError for " << doc.dump();
  return {};
}

std::string override_error(const RenderOverrides& o) {
  Job job = parse_job(animated().dump(), kJobFile);
  try {
    apply_overrides(job, o);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an InputError";
  return {};
}

TEST(JobVideo, AVideoIsKeptAsWrittenForEveryFrame) {
  const Job job = parse_job(animated().dump(), kJobFile);
  EXPECT_EQ(job.output.video, fs::path("out/v.mp4"));
  EXPECT_EQ(job_at_frame(job, 3).output.video, fs::path("out/v.mp4"));
  Json upper = animated();
  upper["output"]["video"] = "out/V.WEBM";
  EXPECT_EQ(video_format_of(parse_job(upper.dump(), kJobFile).output.video), VideoFormat::WebM);
  Json none = animated();
  none["output"].erase("video");
  EXPECT_TRUE(parse_job(none.dump(), kJobFile).output.video.empty());
}

TEST(JobVideo, AVideoWithoutFramesNamesOutputVideo) {
  Json doc = animated();
  doc.erase("frames");
  doc["output"] = {{"video", "out/v.mp4"}};
  EXPECT_EQ(error_of(doc), kJobFile.string() +
                               ": output.video: a video needs a frame range: give \"frames\": {\"start\": 1, \"end\": 48}");
}

TEST(JobVideo, AVideoOfAnotherTypeNamesOutputVideo) {
  for (const std::string name : {"out/v.avi", "out/v", "out/v.mp4.png"}) {
    Json doc = animated();
    doc["output"]["video"] = name;
    EXPECT_NE(error_of(doc).find(": output.video: '" + name + "': cannot make videos of type"), std::string::npos)
        << name;
  }
  Json doc = animated();
  doc["output"]["video"] = "out/v.gif";
  EXPECT_NE(error_of(doc).find("cannot make videos of type '.gif' (expected .mp4, .mkv or .webm)"), std::string::npos);
  doc["output"]["video"] = "";
  EXPECT_NE(error_of(doc).find(": output.video: expected a file path, got an empty string"), std::string::npos);
  doc["output"]["video"] = 7;
  EXPECT_NE(error_of(doc).find(": output.video: "), std::string::npos);
}

TEST(JobVideo, AVideoWithThePreviewOffNamesOutputVideo) {
  Json doc = animated();
  doc["output"]["preview"] = "";
  EXPECT_NE(error_of(doc).find(": output.video: a video is made from the frames' previews, and output.preview is "
                               "\"\" (none)"),
            std::string::npos)
      << error_of(doc);
}

TEST(JobVideo, OverridesKeepTheVideoMakeable) {
  RenderOverrides no_preview;
  no_preview.preview = fs::path();
  EXPECT_NE(override_error(no_preview).find("--preview none: the video out/v.mp4 is made from the frames' previews"),
            std::string::npos);
  RenderOverrides avi;
  avi.video = fs::path("x.avi");
  EXPECT_NE(override_error(avi).find("--video x.avi: cannot make videos of type '.avi'"), std::string::npos);

  // --video none, with or without previews; --video FILE replaces the job's.
  Job job = parse_job(animated().dump(), kJobFile);
  RenderOverrides none;
  none.video = fs::path();
  none.preview = fs::path();
  apply_overrides(job, none);
  EXPECT_TRUE(job.output.video.empty());
  job = parse_job(animated().dump(), kJobFile);
  RenderOverrides other;
  other.video = fs::path("elsewhere/v.mkv");
  apply_overrides(job, other);
  EXPECT_EQ(job.output.video, fs::path("elsewhere/v.mkv"));

  // A still has no video to make.
  Json still = animated();
  still.erase("frames");
  still["output"] = Json::object();
  job = parse_job(still.dump(), kJobFile);
  EXPECT_THROW(apply_overrides(job, other), InputError);
}

}  // namespace
}  // namespace farm
