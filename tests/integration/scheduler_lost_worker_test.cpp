// The scheduler core with workers in this process that are lost while they render: a call that
// ends UNAVAILABLE (what a worker's crash looks like from the scheduler) or a worker removed for
// missed heartbeats counts no attempt against --max-attempts, so a tile caught in flight by more
// losses than that still renders; but the losses are counted against their own limit
// (--max-lost-worker-attempts), so a tile that takes down every worker it is sent to fails its
// job, which says why. Every wait is bounded; nothing asserts on wall-clock time.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <nlohmann/json.hpp>
#include <thread>

#include "renderer/accel/prepared_scene.h"
#include "renderer/image/exr_io.h"
#include "renderer/job/job.h"
#include "renderer/job/scene_builder.h"
#include "renderer/render_frame.h"
#include "server/common/job_state.h"
#include "server/embedded/in_process_tile_worker.h"
#include "server/scheduler/scheduler_core.h"
#include "tests/support/eventually.h"
#include "tests/support/in_process_worker.h"
#include "tests/support/job_specs.h"
#include "tests/support/pixel_diff.h"
#include "tests/support/run_command.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

using test::eventually;

using namespace std::chrono_literals;

// A worker whose process dies under its first `losses` calls (every call when negative): they end
// UNAVAILABLE unrendered, as a call does when the connection to a crashed worker goes. The calls
// after those render honestly. Its health check answers, as a restarted worker's would.
class CrashingWorker final : public TileWorker {
 public:
  CrashingWorker(std::shared_ptr<TileWorker> renderer, int losses, std::string name)
      : renderer_(std::move(renderer)), losses_(losses), name_(std::move(name)) {}
  grpc::Status render(const v1::RenderTileRequest& request, RenderedTiles& result,
                      std::chrono::system_clock::time_point deadline, TileCancel& cancel) override {
    if (const int left = losses_.load(); left != 0) {
      if (left > 0) --losses_;
      ++lost_;
      return {grpc::StatusCode::UNAVAILABLE, "Socket closed"};
    }
    return renderer_->render(request, result, deadline, cancel);
  }
  bool probe(std::chrono::milliseconds) override { return true; }
  std::string describe() const override { return name_; }
  int calls_lost() const { return lost_.load(); }

 private:
  std::shared_ptr<TileWorker> renderer_;
  std::atomic<int> losses_;
  std::atomic<int> lost_{0};
  std::string name_;
};

// A worker that stops answering (SIGSTOP, a hung machine): each call waits until the scheduler
// cancels it, which it does when the worker is removed for missing its heartbeats.
class StoppedWorker final : public TileWorker {
 public:
  grpc::Status render(const v1::RenderTileRequest&, RenderedTiles&, std::chrono::system_clock::time_point deadline,
                      TileCancel& cancel) override {
    ++calls_;
    while (!cancel.cancelled()) {
      if (std::chrono::system_clock::now() > deadline) return {grpc::StatusCode::DEADLINE_EXCEEDED, "deadline"};
      std::this_thread::sleep_for(2ms);
    }
    return {grpc::StatusCode::CANCELLED, "cancelled"};
  }
  bool probe(std::chrono::milliseconds) override { return true; }
  std::string describe() const override { return "stopped"; }
  int calls() const { return calls_.load(); }

 private:
  std::atomic<int> calls_{0};
};

class SchedulerLostWorkerTest : public ::testing::Test {
 protected:
  SchedulerOptions options() const {
    SchedulerOptions o;
    o.data_dir = dir_ / "farm";
    o.log_level = LogLevel::off;
    o.exr_type = ExrPixelType::Float;
    o.batch_target = 0ms;
    // A lost worker is probed again after this: short, so that many losses take little time.
    o.probe_interval = 5ms;
    return o;
  }

  // One tile: every call of the job renders the same unit.
  static v1::JobSpec one_tile_job() {
    nlohmann::json job = nlohmann::json::parse(test::cornell_job_json("raster", 32, 32, 1));
    job["render"]["tile_size"] = 32;
    return test::make_job_spec(job.dump(2), test::cornell_assets(), "cornell.json");
  }

  std::shared_ptr<TileWorker> honest_renderer(const std::string& name) const {
    return std::make_shared<InProcessTileWorker>(
        test::in_process_worker_options(dir_ / "farm", dir_ / name, 1, LogLevel::off));
  }

  static bool final_job(SchedulerCore& core, const std::string& id) {
    const std::optional<v1::Job> job = core.get_job(id);
    return job && is_final(job->state());
  }

  test::TempDir dir_;
};

TEST_F(SchedulerLostWorkerTest, ATileWhoseWorkerCrashesMoreOftenThanMaxAttemptsStillSucceeds) {
  SchedulerOptions o = options();
  ASSERT_EQ(o.max_attempts, 3);  // the default
  SchedulerCore core(o);
  test::add_cornell_assets(core);
  constexpr int kLosses = 5;  // more than max_attempts, fewer than max_lost_worker_attempts
  ASSERT_LT(kLosses, o.max_lost_worker_attempts);
  auto crashing = std::make_shared<CrashingWorker>(honest_renderer("w"), kLosses, "crashing");
  core.add_worker(crashing);
  const v1::JobSpec spec = one_tile_job();
  const std::string id = core.submit(core.check(spec)).job_id();

  ASSERT_TRUE(eventually([&] { return final_job(core, id); }));
  const v1::Job job = *core.get_job(id);
  ASSERT_EQ(job.state(), v1::JOB_STATE_SUCCEEDED) << job.failure_reason();
  EXPECT_EQ(crashing->calls_lost(), kLosses);
  EXPECT_EQ(job.tile_failures(), static_cast<unsigned>(kLosses));  // every lost rendering, still shown
  const std::vector<UnitRecord> tiles = core.store().units().tiles(id);
  ASSERT_EQ(tiles.size(), 1u);
  EXPECT_EQ(tiles[0].attempts, 0);  // none counted against --max-attempts
  EXPECT_EQ(tiles[0].lost_attempts, kLosses);

  const Job parsed = parse_job(spec.job_json(), std::filesystem::path(FARM_SOURCE_DIR) / "jobs" / "cornell.json");
  const TileBuffer local = render_frame(PreparedScene(build_scene(parsed)), parsed.render);
  EXPECT_EQ(test::differing_pixels(read_exr(*core.result_file(id, false)), local), 0);
}

TEST_F(SchedulerLostWorkerTest, ATileWhoseWorkersStopAndAreDroppedMoreOftenThanMaxAttemptsStillSucceeds) {
  SchedulerCore core(options());
  test::add_cornell_assets(core);
  const std::string id = core.submit(core.check(one_tile_job())).job_id();
  // Four workers in turn take the tile and stop answering; each is dropped as the heartbeat
  // monitor drops a silent one, which cancels its call.
  constexpr int kStops = 4;
  for (int i = 0; i < kStops; ++i) {
    auto stopped = std::make_shared<StoppedWorker>();
    const std::string worker_id = core.add_worker(stopped, true);
    ASSERT_TRUE(eventually([&] { return stopped->calls() >= 1; })) << "stop " << i;
    core.remove_worker(worker_id, "no heartbeat for 3000 ms");
    // Back in the queue, or (were the loss counted as an attempt) failed for good.
    ASSERT_TRUE(eventually([&] {
      const std::vector<UnitRecord> tiles = core.store().units().tiles(id);
      return !tiles.empty() && tiles[0].state != TileState::Running;
    })) << "stop " << i;
    ASSERT_EQ(core.store().units().tiles(id)[0].state, TileState::Queued)
        << "stop " << i << ": " << core.get_job(id)->failure_reason();
  }
  core.add_worker(honest_renderer("honest"));
  ASSERT_TRUE(eventually([&] { return final_job(core, id); }));
  const v1::Job job = *core.get_job(id);
  ASSERT_EQ(job.state(), v1::JOB_STATE_SUCCEEDED) << job.failure_reason();
  const std::vector<UnitRecord> tiles = core.store().units().tiles(id);
  ASSERT_EQ(tiles.size(), 1u);
  EXPECT_EQ(tiles[0].attempts, 0);
  EXPECT_EQ(tiles[0].lost_attempts, kStops);
}

TEST_F(SchedulerLostWorkerTest, ATileThatCrashesEveryWorkerFailsItsJobAtTheLostWorkerLimitSayingSo) {
  SchedulerOptions o = options();
  o.max_lost_worker_attempts = 4;
  SchedulerCore core(o);
  test::add_cornell_assets(core);
  auto first = std::make_shared<CrashingWorker>(honest_renderer("a"), -1, "crashing-a");
  auto second = std::make_shared<CrashingWorker>(honest_renderer("b"), -1, "crashing-b");
  core.add_worker(first);
  core.add_worker(second);
  const std::string id = core.submit(core.check(one_tile_job())).job_id();

  ASSERT_TRUE(eventually([&] { return final_job(core, id); }));
  const v1::Job job = *core.get_job(id);
  ASSERT_EQ(job.state(), v1::JOB_STATE_FAILED);
  EXPECT_NE(job.failure_reason().find("unit 0 lost 4 workers while rendering"), std::string::npos)
      << job.failure_reason();
  EXPECT_NE(job.failure_reason().find("lost-worker attempts limit"), std::string::npos) << job.failure_reason();
  EXPECT_NE(job.failure_reason().find("UNAVAILABLE: Socket closed"), std::string::npos) << job.failure_reason();
  EXPECT_EQ(first->calls_lost() + second->calls_lost(), 4);  // and no call after the job failed
  const std::vector<UnitRecord> tiles = core.store().units().tiles(id);
  ASSERT_EQ(tiles.size(), 1u);
  EXPECT_EQ(tiles[0].attempts, 0);
  EXPECT_EQ(tiles[0].lost_attempts, 4);
  EXPECT_EQ(tiles[0].state, TileState::Failed);
}

TEST(SchedulerLostWorkerFlagTest, FarmSchedulerHelpDocumentsTheLostWorkerLimit) {
  const test::CommandResult r = test::run_command(test::farm_command("scheduler --help"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("--max-lost-worker-attempts"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace farm
