// The scheduler core with workers in this process: a worker whose replies break the rules is
// quarantined, which its state shows (SchedulerCore::workers), and the job finishes on another,
// bit-identical to rendering the frame in one piece.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
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
#include "tests/support/fake_worker.h"
#include "tests/support/in_process_worker.h"
#include "tests/support/job_specs.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

using test::eventually;

using namespace std::chrono_literals;

// Renders with a TileRenderer and replies as a remote worker would (TileData, not pixels), then
// tells `lie`.
class LyingWorker final : public TileWorker {
 public:
  LyingWorker(const TileRendererOptions& options, test::Lie lie) : renderer_(options), lie_(lie) {}
  grpc::Status render(const v1::RenderTileRequest& request, RenderedTiles& result,
                      std::chrono::system_clock::time_point deadline, TileCancel&) override {
    RenderControl control;
    control.deadline = deadline;
    const grpc::Status status = renderer_.render(request, result.response, control);
    if (status.ok()) test::tell_lie(lie_, result.response);
    return status;
  }
  bool probe(std::chrono::milliseconds) override { return true; }
  std::string describe() const override { return "liar"; }

 private:
  TileRenderer renderer_;
  test::Lie lie_;
};

TEST(SchedulerQuarantineTest, AWorkerWhoseRepliesBreakTheRulesIsQuarantinedAndItsStateSaysWhy) {
  test::TempDir dir;
  const v1::JobSpec spec = test::cornell_job_spec("whitted", 48, 32, 1);
  SchedulerOptions options;
  options.data_dir = dir / "farm";
  options.log_level = LogLevel::off;
  options.exr_type = ExrPixelType::Float;
  options.batch_target = std::chrono::milliseconds(0);
  options.max_attempts = 5;
  SchedulerCore core(options);
  test::add_cornell_assets(core);
  TileRendererOptions r = test::in_process_worker_options(dir / "farm", dir / "liar", 1, LogLevel::off);
  const std::string liar = core.add_worker(std::make_shared<LyingWorker>(r, test::Lie::MissingPlane));
  const std::string id = core.submit(core.check(spec)).job_id();

  const auto state_of = [&](const std::string& worker) {
    for (const WorkerStatus& w : core.workers()) {
      if (w.id == worker) return w;
    }
    return WorkerStatus{};
  };
  ASSERT_TRUE(eventually([&] { return state_of(liar).quarantined; }));
  EXPECT_EQ(state_of(liar).address, "liar");
  EXPECT_NE(state_of(liar).quarantine_reason.find("worker liar sent a result no engine makes: its normal plane is missing"),
            std::string::npos)
      << state_of(liar).quarantine_reason;
  EXPECT_NE(core.get_job(id)->state(), v1::JOB_STATE_SUCCEEDED);
  EXPECT_EQ(core.get_job(id)->tiles_done(), 0u);

  // The same address registering again stays quarantined.
  const std::string again = core.add_worker(std::make_shared<LyingWorker>(r, test::Lie::None));
  EXPECT_TRUE(state_of(again).quarantined);
  EXPECT_EQ(state_of(again).quarantine_reason, state_of(liar).quarantine_reason);

  r.cache_dir = dir / "honest";
  core.add_worker(std::make_shared<InProcessTileWorker>(r));
  ASSERT_TRUE(eventually([&] { return is_final(core.get_job(id)->state()); }));
  ASSERT_EQ(core.get_job(id)->state(), v1::JOB_STATE_SUCCEEDED) << core.get_job(id)->failure_reason();
  EXPECT_TRUE(state_of(liar).quarantined);  // still listed, still quarantined

  const TileBuffer farm_frame = read_exr(*core.result_file(id, false));
  const Job job = parse_job(spec.job_json(), std::filesystem::path(FARM_SOURCE_DIR) / "jobs" / "cornell.json");
  const TileBuffer local = render_frame(PreparedScene(build_scene(job)), job.render);
  ASSERT_EQ(farm_frame.rect(), local.rect());
  for (int y = 0; y < local.rect().y1; ++y) {
    for (int x = 0; x < local.rect().x1; ++x) {
      ASSERT_EQ(std::memcmp(&farm_frame.rgba(x, y), &local.rgba(x, y), sizeof(glm::vec4)), 0) << x << ", " << y;
      ASSERT_EQ(std::memcmp(&farm_frame.normal(x, y), &local.normal(x, y), sizeof(glm::vec3)), 0) << x << ", " << y;
    }
  }
}

}  // namespace
}  // namespace farm
