// Frame ranges through the real binaries: a keyframed job on a scheduler with two workers, one
// killed mid-job, gives every frame bit-identical to `farm render` of the same frames, and its
// frames can be fetched as they are merged, before the job ends. `farm render --frames` picks
// frames; bad ranges and keys exit 2 naming the JSON path. Every wait is bounded.
#include <fmt/format.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "renderer/image/exr_io.h"
#include "server/common/asset_store.h"
#include "tests/support/background_process.h"
#include "tests/support/farm_cli_fixture.h"
#include "tests/support/job_specs.h"
#include "tests/support/pixel_diff.h"
#include "tests/support/run_command.h"
#include "tests/support/scheduler_client.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Json = nlohmann::json;

constexpr int kFrames = 24;

bool done(const v1::Job& job) {
  return job.state() == v1::JOB_STATE_SUCCEEDED || job.state() == v1::JOB_STATE_FAILED ||
         job.state() == v1::JOB_STATE_CANCELLED;
}

// The Cornell box turning and its light moving over frames 1-24, path traced: heavy enough per
// frame that a worker can be killed while frames remain.
std::string animated_cornell(const std::string& engine, int spp) {
  Json job = Json::parse(test::cornell_job_json(engine, 48, 32, spp));
  job["render"]["tile_size"] = 16;
  job["frames"] = {{"start", 1}, {"end", kFrames}};
  job["output"] = {{"image", "out/cornell.####.exr"}, {"preview", "out/cornell.####.png"}, {"aovs", {"depth"}}};
  job["animate"] = {
      {{"value", "scene.objects[0].rotate.degrees"},
       {"keys", {{{"frame", 1}, {"value", 0}}, {{"frame", kFrames}, {"value", 40}}}}},
      {{"value", "scene.lights[0].position"},
       {"interpolation", "smooth"},
       {"keys", {{{"frame", 1}, {"value", {-0.5, 0.6, 0.5}}}, {{"frame", 12}, {"value", {0.5, 0.2, 0.5}}},
                 {{"frame", kFrames}, {"value", {0, 0.6, 0.2}}}}}}};
  return job.dump(2);
}

class FarmFramesTest : public test::FarmCliFixture {
 protected:
  // The job file and its assets in a folder of their own, as a user has them.
  fs::path write_job(const std::string& json) {
    const fs::path dir = dir_ / "job";
    fs::create_directories(dir / "assets");
    for (const auto& [path, file] : test::cornell_assets()) fs::copy_file(file, dir / path, fs::copy_options::skip_existing);
    std::ofstream(dir / "cornell.json") << json;
    return dir / "cornell.json";
  }

  std::unique_ptr<test::WorkerProcess> start_worker(const std::string& name, const std::string& scheduler) {
    auto worker = std::make_unique<test::WorkerProcess>(
        std::vector<std::string>{"--threads", "1", "--cache-dir", (dir_ / name).string(), "--scheduler", scheduler});
    EXPECT_TRUE(worker->process().wait_for_line("registered with the scheduler", 20s)) << worker->process().output();
    return worker;
  }
};

TEST_F(FarmFramesTest, AJobOfFramesOnTwoWorkersOneKilledGivesTheFramesOfFarmRender) {
  test::SchedulerProcess scheduler(dir_ / "data", {"--float", "--heartbeat-interval", "0.2"});
  ASSERT_FALSE(scheduler.address().empty()) << scheduler.process().output();
  auto stub = test::scheduler_stub(scheduler.address());
  ASSERT_TRUE(test::upload_assets(*stub, test::cornell_assets()).ok());
  auto w1 = start_worker("w1", scheduler.address());
  auto w2 = start_worker("w2", scheduler.address());

  const std::string json = animated_cornell("path", 96);
  v1::Job job;
  const grpc::Status submitted = test::submit(*stub, test::make_job_spec(json, test::cornell_assets(), "cornell.json"), job);
  ASSERT_TRUE(submitted.ok()) << submitted.error_message();
  EXPECT_EQ(job.frames_total(), static_cast<std::uint32_t>(kFrames));
  EXPECT_EQ(job.frame_first(), 1);
  EXPECT_EQ(job.frame_last(), kFrames);
  EXPECT_EQ(job.tiles_total(), 6u * kFrames);

  // Frames come out while others render: once two are merged, the first is fetched, and one
  // worker is killed.
  const auto early = test::wait_for_job(*stub, job.job_id(), [](const v1::Job& j) { return j.frames_done() >= 2 || done(j); }, 90s);
  ASSERT_TRUE(early);
  EXPECT_FALSE(done(*early)) << "the job ended before a worker could be killed";
  const fs::path first = dir_ / "early-frame-1.exr";
  const grpc::Status early_fetch = test::fetch_result(*stub, job.job_id(), v1::RESULT_KIND_EXR, first, 1);
  EXPECT_TRUE(early_fetch.ok()) << early_fetch.error_message();
  w1->process().send_signal(SIGKILL);

  grpc::Status watch_status;
  const std::vector<v1::JobEvent> events = test::watch_job(*stub, job.job_id(), 120s, &watch_status);
  ASSERT_TRUE(watch_status.ok()) << watch_status.error_message();
  ASSERT_FALSE(events.empty());
  const v1::Job& final_job = events.back().job();
  ASSERT_EQ(final_job.state(), v1::JOB_STATE_SUCCEEDED) << final_job.failure_reason() << scheduler.process().output();
  EXPECT_EQ(final_job.frames_done(), static_cast<std::uint32_t>(kFrames));
  // Every frame not merged before the watch began is announced once, before the job's end.
  std::set<int> announced;
  for (std::size_t i = 0; i < events.size(); ++i) {
    if (!events[i].has_frame_finished()) continue;
    EXPECT_TRUE(announced.insert(events[i].frame_finished().frame()).second) << "frame announced twice";
    EXPECT_LT(i + 1, events.size());
  }
  EXPECT_GE(announced.size(), static_cast<std::size_t>(kFrames) - early->frames_done() - 2);

  // `farm render` of the same job file: every frame bit-identical.
  const fs::path job_file = write_job(json);
  const test::CommandResult r = test::run_command(
      farm("render " + test::shell_quote(job_file.string()) + " --quiet --float --out " +
           test::shell_quote((dir_ / "local" / "f.####.exr").string()) + " --preview none"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (int f = 1; f <= kFrames; ++f) {
    const fs::path fetched = dir_ / fmt::format("farm-{}.exr", f);
    const grpc::Status status = test::fetch_result(*stub, job.job_id(), v1::RESULT_KIND_EXR, fetched, f);
    ASSERT_TRUE(status.ok()) << "frame " << f << ": " << status.error_message();
    const TileBuffer local = read_exr(dir_ / "local" / fmt::format("f.{:04}.exr", f));
    EXPECT_EQ(test::differing_pixels(read_exr(fetched), local), 0) << "frame " << f;
    if (f == 1) {
      EXPECT_EQ(test::differing_pixels(read_exr(first), local), 0) << "the frame fetched early";
    }
  }
  // Frames differ from each other: the animation reached the workers.
  EXPECT_GT(test::differing_pixels(read_exr(dir_ / "farm-1.exr"), read_exr(dir_ / "farm-24.exr")), 0);

  // A frame the job does not render is refused, naming the range.
  grpc::Status outside = test::fetch_result(*stub, job.job_id(), v1::RESULT_KIND_EXR, dir_ / "x.exr", kFrames + 1);
  EXPECT_EQ(outside.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(outside.error_message().find("renders no frame 25 (its frames are 1 to 24 by 1)"), std::string::npos)
      << outside.error_message();
}

TEST_F(FarmFramesTest, FarmRenderFramesPicksFramesAndFetchGetsEveryFrame) {
  const fs::path job_file = write_job(animated_cornell("raster", 1));
  const fs::path out = dir_ / "out";
  const test::CommandResult r = test::run_command(farm("render " + test::shell_quote(job_file.string()) +
                                                       " --quiet --frames 3-5 --out " +
                                                       test::shell_quote((out / "c.##.exr").string()) + " --preview " +
                                                       test::shell_quote((out / "p.#.png").string())));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("wrote 3 frames, " + (out / "c.03.exr").string() + " .. " + (out / "c.05.exr").string()),
            std::string::npos)
      << r.output;
  std::set<std::string> written;
  for (const fs::directory_entry& e : fs::directory_iterator(out)) written.insert(e.path().filename().string());
  EXPECT_EQ(written, (std::set<std::string>{"c.03.exr", "c.04.exr", "c.05.exr", "p.3.png", "p.4.png", "p.5.png"}));
}

TEST_F(FarmFramesTest, BadFramesAndKeysExitTwoNamingTheJsonPath) {
  const auto run_with = [&](const std::function<void(Json&)>& edit, const std::string& extra = "") {
    Json job = Json::parse(animated_cornell("raster", 1));
    edit(job);
    return test::run_command(farm("render " + test::shell_quote(write_job(job.dump()).string()) + " --quiet " + extra));
  };
  const auto expect_exit_2 = [](const test::CommandResult& r, const std::string& wanted) {
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(wanted), std::string::npos) << r.output;
  };
  expect_exit_2(run_with([](Json& j) { j["frames"]["end"] = 0; }), "cornell.json: frames.end: expected an end >= start (1), got 0");
  expect_exit_2(run_with([](Json& j) { j["frames"]["step"] = 0; }), "cornell.json: frames.step: expected an integer >= 1, got 0");
  expect_exit_2(run_with([](Json& j) { j["animate"][0]["value"] = "scene.objects[1].rotate.degrees"; }),
                "cornell.json: animate[0].value: 'scene.objects[1].rotate.degrees' names nothing in the job");
  expect_exit_2(run_with([](Json& j) { j["animate"][0]["value"] = "scene.objects[0].file"; }),
                "animate[0].value: 'scene.objects[0].file' is a string");
  expect_exit_2(run_with([](Json& j) { j["animate"][0]["keys"][1]["frame"] = 0; }),
                "animate[0].keys[1].frame: expected a frame after 1 (keys in frame order), got 0");
  expect_exit_2(run_with([](Json& j) { j["output"]["image"] = "out/cornell.exr"; }),
                "output.image: 'out/cornell.exr' has no '#' for the frame number");
  expect_exit_2(run_with([](Json&) {}, "--frames 30-40"), "--frames 30-40: the job's frames are 1 to 24 by 1");
  expect_exit_2(run_with([](Json&) {}, "--out single.exr"), "--out single.exr: the job renders frames");
  expect_exit_2(run_with([](Json&) {}, "--frames 7-x"), "--frames");
}

}  // namespace
}  // namespace farm
