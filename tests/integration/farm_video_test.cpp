// output.video through the real binaries: `farm render` of a small animated job writes a video
// ffprobe reads as its frames at their size, `farm submit --wait` on a scheduler and a worker
// downloads the video the scheduler made, and without ffmpeg `farm render` exits 2 before any
// frame is written and the scheduler refuses the job at submit. Every wait is bounded.
#include <fmt/format.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <stdlib.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>

#include "renderer/image/png_reader.h"
#include "server/common/job_state.h"
#include "tests/support/background_process.h"
#include "tests/support/farm_cli_fixture.h"
#include "tests/support/job_specs.h"
#include "tests/support/run_command.h"
#include "tests/support/scheduler_client.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Json = nlohmann::json;

constexpr int kFrames = 4;

// What ffprobe says of a video's first stream: its codec, size and decoded frame count.
struct Probe {
  std::string codec, pix_fmt;
  int width = 0, height = 0, frames = 0;
  std::string problem;  // empty when ffprobe read it
};

Probe probe(const fs::path& video) {
  const test::CommandResult r = test::run_command(
      "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
      "stream=codec_name,pix_fmt,width,height,nb_read_frames -of json " +
      test::shell_quote(video.string()) + " 2>&1");
  Probe p;
  if (r.exit_code != 0) {
    p.problem = r.output;
    return p;
  }
  const Json doc = Json::parse(r.output, nullptr, false);
  if (doc.is_discarded() || !doc.contains("streams") || doc["streams"].empty()) {
    p.problem = "no video stream: " + r.output;
    return p;
  }
  const Json& s = doc["streams"][0];
  p.codec = s.value("codec_name", "");
  p.pix_fmt = s.value("pix_fmt", "");
  p.width = s.value("width", 0);
  p.height = s.value("height", 0);
  p.frames = std::stoi(s.value("nb_read_frames", "0"));
  return p;
}

DecodedImage read_png_file(const fs::path& file) {
  std::FILE* f = std::fopen(file.c_str(), "rb");
  if (!f) throw std::runtime_error("cannot open " + file.string());
  DecodedImage image = read_png(f, file, 4096);
  std::fclose(f);
  return image;
}

// Mean absolute difference of the RGB of two images of one size, 0 to 1.
double mean_rgb_difference(const DecodedImage& a, const DecodedImage& b) {
  double sum = 0.0;
  const std::size_t pixels = static_cast<std::size_t>(a.width) * a.height;
  for (std::size_t i = 0; i < pixels; ++i) {
    for (int c = 0; c < 3; ++c) {
      sum += std::abs(a.values[i * a.channels + c] - b.values[i * b.channels + c]);
    }
  }
  return sum / (3.0 * static_cast<double>(pixels));
}

// The Cornell box turning over frames 1-4, rastered small, its files under `out`.
Json animated_cornell(int width, int height, const fs::path& out, const std::string& video) {
  Json job = Json::parse(test::cornell_job_json("raster", width, height, 1));
  job["render"]["tile_size"] = 16;
  job["frames"] = {{"start", 1}, {"end", kFrames}, {"fps", 12}};
  job["output"] = {{"image", (out / "cornell.####.exr").string()},
                   {"preview", (out / "cornell.####.png").string()},
                   {"video", (out / video).string()}};
  job["animate"] = {{{"value", "scene.objects[0].rotate.degrees"},
                     {"keys", {{{"frame", 1}, {"value", 0}}, {{"frame", kFrames}, {"value", 60}}}}}};
  return job;
}

// The job id `farm submit` printed: a line of 16 hex digits (stdout and stderr interleave).
std::string job_id_in(const std::string& output) {
  std::size_t begin = 0;
  while (begin < output.size()) {
    const std::size_t end = std::min(output.find('\n', begin), output.size());
    const std::string line = output.substr(begin, end - begin);
    if (line.size() == 16 && line.find_first_not_of("0123456789abcdef") == std::string::npos) return line;
    begin = end + 1;
  }
  return {};
}

// Sets an environment variable for the test's scope (the children it starts inherit it).
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (old_) {
      ::setenv(name_, old_->c_str(), 1);
    } else {
      ::unsetenv(name_);
    }
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

class FarmVideoTest : public test::FarmCliFixture {
 protected:
  // The job file and its assets in a folder of their own, as a user has them.
  fs::path write_job(const Json& job) {
    const fs::path dir = dir_ / "job";
    fs::create_directories(dir / "assets");
    for (const auto& [path, file] : test::cornell_assets()) {
      fs::copy_file(file, dir / path, fs::copy_options::skip_existing);
    }
    std::ofstream(dir / "cornell.json") << job.dump(2);
    return dir / "cornell.json";
  }

  test::CommandResult render(const fs::path& job_file, const std::string& extra = "") {
    return test::run_command(farm("render " + test::shell_quote(job_file.string()) + " --quiet " + extra));
  }
};

TEST_F(FarmVideoTest, FarmRenderWritesAnMp4OfEveryFrameAtTheFramesSize) {
  const fs::path out = dir_ / "out";
  const test::CommandResult r = render(write_job(animated_cornell(64, 48, out, "cornell.mp4")));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path video = out / "cornell.mp4";
  EXPECT_NE(r.output.find("wrote " + video.string() + " (H.264, 4 frames at 12 fps)"), std::string::npos) << r.output;

  const Probe p = probe(video);
  ASSERT_TRUE(p.problem.empty()) << p.problem;
  EXPECT_EQ(p.codec, "h264");
  EXPECT_EQ(p.pix_fmt, "yuv420p");
  EXPECT_EQ(p.width, 64);
  EXPECT_EQ(p.height, 48);
  EXPECT_EQ(p.frames, kFrames);
  // Nothing left beside it: the temporary name was renamed, the frames' links are gone.
  for (const fs::directory_entry& e : fs::directory_iterator(out)) {
    EXPECT_FALSE(e.path().filename().string().starts_with(".")) << e.path();
  }

  // The video's frames are the previews in frame order: the last decoded frame looks like the
  // last preview (H.264 is lossy: roughly), and not like the first.
  const fs::path decoded = dir_ / "decoded.png";
  const test::CommandResult d = test::run_command(
      "ffmpeg -nostdin -v error -i " + test::shell_quote(video.string()) +
      " -vf " + test::shell_quote("select=eq(n\\,3)") + " -frames:v 1 -pix_fmt rgb24 " + test::shell_quote(decoded.string()) + " 2>&1");
  ASSERT_EQ(d.exit_code, 0) << d.output;
  const DecodedImage last = read_png_file(decoded);
  const DecodedImage preview_4 = read_png_file(out / "cornell.0004.png");
  const DecodedImage preview_1 = read_png_file(out / "cornell.0001.png");
  ASSERT_EQ(last.width, preview_4.width);
  ASSERT_EQ(last.height, preview_4.height);
  const double to_own = mean_rgb_difference(last, preview_4), to_first = mean_rgb_difference(last, preview_1);
  EXPECT_LT(to_own, 0.03);
  EXPECT_LT(to_own, to_first);
}

TEST_F(FarmVideoTest, OddSizedFramesArePaddedToEvenAndWebmIsVp9) {
  const fs::path out = dir_ / "out";
  const test::CommandResult r = render(write_job(animated_cornell(33, 25, out, "cornell.webm")), "--frames 2-4");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Probe p = probe(out / "cornell.webm");
  ASSERT_TRUE(p.problem.empty()) << p.problem;
  EXPECT_EQ(p.codec, "vp9");
  EXPECT_EQ(p.width, 34);
  EXPECT_EQ(p.height, 26);
  EXPECT_EQ(p.frames, 3);  // the frames rendered
}

TEST_F(FarmVideoTest, SubmitWaitDownloadsTheVideoTheSchedulerMade) {
  test::LocalFarm local = test::start_local_farm(dir_.path(), 1);
  ASSERT_TRUE(local.problem.empty()) << local.problem;
  const fs::path out = dir_ / "fetched";
  const fs::path job_file = write_job(animated_cornell(64, 48, out, "cornell.mp4"));
  const test::CommandResult r = test::run_command(farm("submit " + test::shell_quote(job_file.string()) +
                                                       " --wait --scheduler " + local.address()));
  ASSERT_EQ(r.exit_code, 0) << r.output << local.scheduler->process().output();
  const fs::path video = out / "cornell.mp4";
  EXPECT_NE(r.output.find("wrote " + video.string()), std::string::npos) << r.output;
  const Probe p = probe(video);
  ASSERT_TRUE(p.problem.empty()) << p.problem;
  EXPECT_EQ(p.codec, "h264");
  EXPECT_EQ(p.width, 64);
  EXPECT_EQ(p.height, 48);
  EXPECT_EQ(p.frames, kFrames);
  for (int f = 1; f <= kFrames; ++f) EXPECT_TRUE(fs::exists(out / fmt::format("cornell.{:04}.png", f))) << f;

  // `farm fetch` of the finished job gets it too, under the scheduler's name for it.
  const std::string id = job_id_in(r.output);
  ASSERT_FALSE(id.empty()) << r.output;
  const test::CommandResult fetched = test::run_command(
      farm("fetch " + id + " --scheduler " + local.address() + " -o " + test::shell_quote((dir_ / "f2").string())));
  ASSERT_EQ(fetched.exit_code, 0) << fetched.output;
  EXPECT_EQ(probe(dir_ / "f2" / "cornell.mp4").frames, kFrames) << fetched.output;

  // A video is the whole job's: asked with a frame, it is refused.
  auto stub = test::scheduler_stub(local.address());
  const grpc::Status with_frame = test::fetch_result(*stub, id, v1::RESULT_KIND_VIDEO, dir_ / "x.mp4", 1);
  EXPECT_EQ(with_frame.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << with_frame.error_message();
}

TEST_F(FarmVideoTest, AFailedEncodeFailsTheJobWithFfmpegsWordsAndKeepsTheFrames) {
  const fs::path out = dir_ / "out";
  const fs::path job_file = write_job(animated_cornell(64, 48, out, "cornell.mp4"));
  // An "ffmpeg" that refuses, as one without an H.264 encoder would.
  const fs::path fake = dir_.write("fake-ffmpeg", "#!/bin/sh\necho 'Unknown encoder libx264' >&2\nexit 1\n");
  fs::permissions(fake, fs::perms::owner_all);
  const test::CommandResult r = test::run_command("FARM_FFMPEG=" + test::shell_quote(fake.string()) + " " +
                                                  farm("render " + test::shell_quote(job_file.string()) + " --quiet"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("the render failed: making the video (output.video " + (out / "cornell.mp4").string() +
                          "): ffmpeg failed (exit code 1): Unknown encoder libx264"),
            std::string::npos)
      << r.output;
  EXPECT_TRUE(fs::exists(out / "cornell.0004.png"));
  for (const fs::directory_entry& e : fs::directory_iterator(out)) {
    EXPECT_FALSE(e.path().filename().string().starts_with(".")) << e.path();
    EXPECT_NE(e.path().extension(), ".mp4") << e.path();
  }
}

// The video is made on a thread of its own: with one worker of one slot, a job submitted while
// another's video is being made renders and succeeds meanwhile (the "ffmpeg" here waits for the
// test's word before it runs the real one). SIGTERM during an encode stops it at once and fails
// nothing; the restarted scheduler makes the video and the job succeeds.
TEST_F(FarmVideoTest, AVideoBeingMadeHoldsNoSlotAndAStoppedOneIsMadeByTheNextScheduler) {
  const fs::path go = dir_ / "go";
  const fs::path started = dir_ / "started";
  // Waits at most a minute for `go`, then runs ffmpeg; says it started by touching `started`.
  const fs::path held = dir_.write(
      "held-ffmpeg", "#!/bin/sh\ntouch " + test::shell_quote(started.string()) + "\ni=0\nwhile [ ! -e " +
                         test::shell_quote(go.string()) +
                         " ] && [ $i -lt 1200 ]; do sleep 0.05; i=$((i+1)); done\nexec ffmpeg \"$@\"\n");
  fs::permissions(held, fs::perms::owner_all);
  const ScopedEnv held_ffmpeg("FARM_FFMPEG", held.string());
  test::LocalFarm local = test::start_local_farm(dir_.path(), 1, {"--tiles-per-worker", "1"});
  ASSERT_TRUE(local.problem.empty()) << local.problem;
  auto stub = test::scheduler_stub(local.address());
  ASSERT_TRUE(test::upload_assets(*stub, test::cornell_assets()).ok());
  const auto submit = [&](const Json& job) {
    v1::Job submitted;
    const grpc::Status status =
        test::submit(*stub, test::make_job_spec(job.dump(), test::cornell_assets(), "cornell.json"), submitted);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return submitted.job_id();
  };
  Json with_video = animated_cornell(64, 48, dir_ / "unused", "cornell.mp4");
  with_video["output"] = {{"video", "cornell.mp4"}};  // kept by the scheduler, under results/
  const std::string video_job = submit(with_video);
  const auto wait_for_file = [](const fs::path& file) {
    for (int i = 0; i < 6000 && !fs::exists(file); ++i) std::this_thread::sleep_for(10ms);
    return fs::exists(file);
  };
  ASSERT_TRUE(wait_for_file(started)) << local.scheduler->process().output();

  Json still = Json::parse(test::cornell_job_json("raster", 32, 32, 1));
  const std::string other = submit(still);
  const auto other_done = test::wait_for_job(*stub, other, [](const v1::Job& j) { return is_final(j.state()); }, 60s);
  ASSERT_TRUE(other_done) << "the job behind the video never ended";
  EXPECT_EQ(other_done->state(), v1::JOB_STATE_SUCCEEDED) << other_done->failure_reason();
  EXPECT_FALSE(fs::exists(go));
  const auto encoding = test::get_job(*stub, video_job);
  ASSERT_TRUE(encoding);
  EXPECT_EQ(encoding->state(), v1::JOB_STATE_RUNNING) << "the video job ended before its video was made";

  // SIGTERM while "ffmpeg" waits: the scheduler stops within its bound, the job not failed.
  local.scheduler->process().send_signal(SIGTERM);
  const std::optional<int> code = local.scheduler->process().wait_exit(15s);
  ASSERT_TRUE(code.has_value()) << "the scheduler waited for the encode: " << local.scheduler->process().output();
  EXPECT_EQ(*code, 0) << local.scheduler->process().output();
  std::ofstream(go.string()) << "go\n";
  test::SchedulerProcess restarted(dir_ / "data", {});
  ASSERT_FALSE(restarted.address().empty()) << restarted.process().output();
  auto stub2 = test::scheduler_stub(restarted.address());
  const auto ended = test::wait_for_job(*stub2, video_job, [](const v1::Job& j) { return is_final(j.state()); }, 60s);
  ASSERT_TRUE(ended) << restarted.process().output();
  EXPECT_EQ(ended->state(), v1::JOB_STATE_SUCCEEDED) << ended->failure_reason();
  const grpc::Status fetched = test::fetch_result(*stub2, video_job, v1::RESULT_KIND_VIDEO, dir_ / "v.mp4");
  ASSERT_TRUE(fetched.ok()) << fetched.error_message();
  EXPECT_EQ(probe(dir_ / "v.mp4").frames, kFrames);
}

TEST_F(FarmVideoTest, WithoutFfmpegRenderExitsTwoBeforeAnyFrameAndSubmitIsRefused) {
  const fs::path out = dir_ / "out";
  const fs::path job_file = write_job(animated_cornell(64, 48, out, "cornell.mp4"));
  const fs::path missing = dir_ / "no-such-ffmpeg";
  // FARM_FFMPEG naming nothing, and a PATH without ffmpeg: both are "no ffmpeg".
  for (const std::string& env : {"FARM_FFMPEG=" + test::shell_quote(missing.string()) + " ",
                                 std::string("PATH=") + test::shell_quote(dir_.path().string()) + " "}) {
    const test::CommandResult r = test::run_command(env + farm("render " + test::shell_quote(job_file.string()) + " --quiet"));
    EXPECT_EQ(r.exit_code, 2) << env << r.output;
    EXPECT_NE(r.output.find("cornell.json: output.video: making the video " + (out / "cornell.mp4").string() +
                            " needs ffmpeg"),
              std::string::npos)
        << r.output;
    EXPECT_FALSE(fs::exists(out)) << env << "frames were written";
  }
  // --video none renders the frames without it.
  const test::CommandResult without = test::run_command("FARM_FFMPEG=" + test::shell_quote(missing.string()) + " " +
                                                        farm("render " + test::shell_quote(job_file.string()) +
                                                             " --quiet --video none"));
  EXPECT_EQ(without.exit_code, 0) << without.output;
  EXPECT_TRUE(fs::exists(out / "cornell.0004.png"));
  EXPECT_FALSE(fs::exists(out / "cornell.mp4"));

  // A scheduler without ffmpeg refuses the job when it is submitted.
  const ScopedEnv no_ffmpeg("FARM_FFMPEG", missing.string());
  test::LocalFarm local = test::start_local_farm(dir_.path(), 0);
  ASSERT_TRUE(local.problem.empty()) << local.problem;
  // (Without --wait: a scheduler that took the job would leave it queued, with no worker.)
  const test::CommandResult r =
      test::run_command(farm("submit " + test::shell_quote(job_file.string()) + " --scheduler " + local.address()));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("cornell.json: output.video: this scheduler cannot make videos: FARM_FFMPEG=" +
                          missing.string() + " is not an executable program"),
            std::string::npos)
      << r.output;
  auto stub = test::scheduler_stub(local.address());
  v1::Job job;
  const grpc::Status status =
      test::submit(*stub, test::make_job_spec(animated_cornell(64, 48, out, "x.mp4").dump(), test::cornell_assets(),
                                              "cornell.json"),
                   job);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << status.error_message();
}

}  // namespace
}  // namespace farm
