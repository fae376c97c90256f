// Sample passes through the real binaries: a path job of two frames in eight passes each gives the
// same bits with every unit on one worker, spread over two, and with one of two killed mid-job,
// and those bits are render_frame's in this process (and `farm render`'s). Progressive previews are announced in pass order (every
// pass, in order, on one worker), can be fetched while the frame renders, and `farm watch
// --preview` keeps a PNG up to date. Every wait is bounded.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <future>
#include <map>
#include <nlohmann/json.hpp>

#include "renderer/accel/prepared_scene.h"
#include "renderer/image/exr_io.h"
#include "renderer/job/job.h"
#include "renderer/job/scene_builder.h"
#include "renderer/render_frame.h"
#include "server/common/job_state.h"
#include "server/common/read_whole_file.h"
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

constexpr int kPasses = 8;
constexpr int kFrames = 2;
constexpr std::uint32_t kTilesPerPass = 24;  // 96x64 in tiles of 16

// The Cornell box path traced at 256 spp in passes of 32, its light moving over two frames.
std::string cornell_in_passes() {
  Json job = Json::parse(test::cornell_job_json("path", 96, 64, 256));
  job["render"]["tile_size"] = 16;
  job["render"]["pass_spp"] = 32;
  job["frames"] = {{"start", 1}, {"end", kFrames}};
  job["output"] = {{"image", "out/cornell.####.exr"}, {"preview", "out/cornell.####.png"}, {"aovs", {"variance"}}};
  job["animate"] = {{{"value", "scene.lights[0].position"},
                     {"keys", {{{"frame", 1}, {"value", {-0.5, 0.6, 0.5}}}, {{"frame", 2}, {"value", {0.5, 0.2, 0.5}}}}}}};
  return job.dump(2);
}

// The passes announced for each frame, in the order they came.
std::map<int, std::vector<int>> announced_passes(const std::vector<v1::JobEvent>& events) {
  std::map<int, std::vector<int>> out;
  for (const v1::JobEvent& e : events) {
    if (!e.has_pass_finished()) continue;
    EXPECT_EQ(e.pass_finished().passes(), kPasses);
    out[e.pass_finished().frame()].push_back(e.pass_finished().pass());
  }
  return out;
}

// PNG's width and height, from its IHDR chunk (bytes 16..23, big-endian).
std::pair<int, int> png_size(const fs::path& file) {
  const std::string bytes = read_whole_file(file, "png");
  if (bytes.size() < 24 || bytes.compare(1, 3, "PNG") != 0) return {0, 0};
  const auto be32 = [&](std::size_t at) {
    int v = 0;
    for (std::size_t i = 0; i < 4; ++i) v = (v << 8) | static_cast<unsigned char>(bytes[at + i]);
    return v;
  };
  return {be32(16), be32(20)};
}

class FarmPassesTest : public test::FarmCliFixture {
 protected:
  std::unique_ptr<test::WorkerProcess> start_worker(const std::string& name, const std::string& scheduler) {
    auto worker = std::make_unique<test::WorkerProcess>(
        std::vector<std::string>{"--threads", "1", "--cache-dir", (dir_ / name).string(), "--scheduler", scheduler});
    EXPECT_TRUE(worker->process().wait_for_line("registered with the scheduler", 20s)) << worker->process().output();
    return worker;
  }

  // Each frame as render_frame gives it in this process (folding its passes, no worker involved):
  // the bits every run must give. `farm render --float` of the job file must give them too.
  void render_reference() {
    const fs::path job_dir = dir_ / "job";
    fs::create_directories(job_dir / "assets");
    for (const auto& [path, file] : test::cornell_assets()) {
      fs::copy_file(file, job_dir / path, fs::copy_options::skip_existing);
    }
    std::ofstream(job_dir / "cornell.json") << cornell_in_passes();
    const Job job = parse_job(cornell_in_passes(), job_dir / "cornell.json");
    ASSERT_EQ(pass_count(job.render), kPasses);
    for (int f = 1; f <= kFrames; ++f) {
      const Job at = job_at_frame(job, f);
      const PreparedScene scene(build_scene(at));
      reference_[f] = render_frame(scene, at.render);
    }
    EXPECT_GT(test::differing_pixels(reference_[1], reference_[2]), 0) << "the light did not move";
    const test::CommandResult r = test::run_command(
        farm("render " + test::shell_quote((job_dir / "cornell.json").string()) + " --quiet --float --out " +
             test::shell_quote((dir_ / "local" / "f.####.exr").string()) + " --preview none"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    for (int f = 1; f <= kFrames; ++f) {
      EXPECT_EQ(test::differing_pixels(read_exr(dir_ / "local" / fmt::format("f.{:04}.exr", f)), reference_[f]), 0)
          << "farm render, frame " << f;
    }
  }

  std::map<int, TileBuffer> reference_;

  // One run on its own scheduler: submits the job and watches it (no worker is up before the watch
  // begins, so it sees every event), starts `workers`, kills the first once frame 1 has two passes done when asked, and
  // checks every frame against render_reference(). Returns the job's events.
  std::vector<v1::JobEvent> run_farm(const std::string& name, int workers, bool kill_one,
                                     const fs::path& watch_preview = {}) {
    SCOPED_TRACE(name);
    test::SchedulerProcess scheduler(dir_ / name / "data", {"--float", "--heartbeat-interval", "0.2"});
    EXPECT_FALSE(scheduler.address().empty()) << scheduler.process().output();
    auto stub = test::scheduler_stub(scheduler.address());
    EXPECT_TRUE(test::upload_assets(*stub, test::cornell_assets()).ok());
    v1::Job job;
    const grpc::Status submitted =
        test::submit(*stub, test::make_job_spec(cornell_in_passes(), test::cornell_assets(), "cornell.json"), job);
    EXPECT_TRUE(submitted.ok()) << submitted.error_message();
    if (!submitted.ok()) return {};
    EXPECT_EQ(job.passes(), static_cast<std::uint32_t>(kPasses));
    EXPECT_EQ(job.tiles_total(), kTilesPerPass * kPasses * kFrames);

    grpc::Status watch_status;
    std::promise<void> subscribed;
    auto watch = std::async(std::launch::async, [&] {
      return test::watch_job(*stub, job.job_id(), 180s, &watch_status, [&] { subscribed.set_value(); });
    });
    // No worker is up before the watch is subscribed: it sees every unit's event.
    EXPECT_EQ(subscribed.get_future().wait_for(60s), std::future_status::ready) << "the watch did not begin";
    std::future<test::CommandResult> cli_watch;
    if (!watch_preview.empty()) {
      cli_watch = std::async(std::launch::async, [&] {
        return test::run_command(farm("watch " + job.job_id() + " --scheduler " + scheduler.address() + " --preview " +
                                      test::shell_quote(watch_preview.string())));
      });
    }
    std::vector<std::unique_ptr<test::WorkerProcess>> up;
    for (int i = 0; i < workers; ++i) up.push_back(start_worker(fmt::format("{}-w{}", name, i + 1), scheduler.address()));

    if (kill_one) {
      const auto two_passes = test::wait_for_job(
          *stub, job.job_id(), [](const v1::Job& j) { return j.tiles_done() >= 2 * kTilesPerPass || is_final(j.state()); }, 120s);
      EXPECT_TRUE(two_passes && !is_final(two_passes->state())) << "the job ended before a worker could be killed";
      // Frame 1's newest preview, while it renders (or, merged meanwhile, its preview).
      const fs::path progressive = dir_ / name / "progressive.png";
      const grpc::Status fetched = test::fetch_result(*stub, job.job_id(), v1::RESULT_KIND_PROGRESSIVE, progressive, 1);
      EXPECT_TRUE(fetched.ok()) << fetched.error_message();
      if (fetched.ok()) {
        EXPECT_EQ(png_size(progressive), (std::pair{96, 64}));
      }
      up.front()->process().send_signal(SIGKILL);
    }

    const std::vector<v1::JobEvent> events = watch.get();
    EXPECT_TRUE(watch_status.ok()) << watch_status.error_message();
    EXPECT_FALSE(events.empty());
    if (events.empty()) return {};
    const v1::Job& final_job = events.back().job();
    EXPECT_EQ(final_job.state(), v1::JOB_STATE_SUCCEEDED) << final_job.failure_reason() << scheduler.process().output();
    for (int f = 1; f <= kFrames; ++f) {
      const fs::path fetched = dir_ / name / fmt::format("farm-{}.exr", f);
      const grpc::Status status = test::fetch_result(*stub, job.job_id(), v1::RESULT_KIND_EXR, fetched, f);
      EXPECT_TRUE(status.ok()) << "frame " << f << ": " << status.error_message();
      if (!status.ok()) continue;
      EXPECT_EQ(test::differing_pixels(read_exr(fetched), reference_[f]), 0) << "frame " << f;
    }
    if (cli_watch.valid()) {
      const test::CommandResult r = cli_watch.get();
      EXPECT_EQ(r.exit_code, 0) << r.output;
      // The newest preview when the job ended: the last frame's, after its last pass.
      const fs::path last = dir_ / name / "last.png";
      EXPECT_TRUE(test::fetch_result(*stub, job.job_id(), v1::RESULT_KIND_PREVIEW, last, kFrames).ok());
      EXPECT_EQ(read_whole_file(watch_preview, "png"), read_whole_file(last, "png"));
    }
    return events;
  }
};

TEST_F(FarmPassesTest, OneWorkerTwoWorkersAndAKilledWorkerGiveTheBitsOfFarmRenderAndPreviewsComeInPassOrder) {
  render_reference();
  const std::vector<int> every_pass = {0, 1, 2, 3, 4, 5, 6, 7};

  // One worker: the units go out in order, so each frame announces every pass, in order.
  const std::vector<v1::JobEvent> one = run_farm("one", 1, false);
  ASSERT_FALSE(one.empty());
  EXPECT_EQ(one.front().job().tiles_done(), 0u);
  const std::map<int, std::vector<int>> in_order = announced_passes(one);
  EXPECT_EQ(in_order, (std::map<int, std::vector<int>>{{1, every_pass}, {2, every_pass}}));
  // A frame's last pass is announced before the frame itself.
  for (int f = 1; f <= kFrames; ++f) {
    std::size_t last_pass = 0, finished = 0;
    for (std::size_t i = 0; i < one.size(); ++i) {
      if (one[i].has_pass_finished() && one[i].pass_finished().frame() == f && one[i].pass_finished().pass() == kPasses - 1) last_pass = i;
      if (one[i].has_frame_finished() && one[i].frame_finished().frame() == f) finished = i;
    }
    EXPECT_LT(last_pass, finished) << "frame " << f;
  }

  // Two workers, watched by `farm watch --preview` too: passes may complete out of order, but
  // are announced in order, each at most once, ending with the last.
  const std::vector<v1::JobEvent> two = run_farm("two", 2, false, dir_ / "watched.png");
  for (const auto& [frame, passes] : announced_passes(two)) {
    ASSERT_FALSE(passes.empty());
    EXPECT_TRUE(std::is_sorted(passes.begin(), passes.end()) &&
                std::adjacent_find(passes.begin(), passes.end()) == passes.end())
        << "frame " << frame << ": " << fmt::format("{}", fmt::join(passes, " "));
    EXPECT_EQ(passes.back(), kPasses - 1) << "frame " << frame;
  }
  EXPECT_EQ(announced_passes(two).size(), static_cast<std::size_t>(kFrames));

  // Two workers, one killed after two passes: the same bits still.
  run_farm("killed", 2, true);
}

}  // namespace
}  // namespace farm
