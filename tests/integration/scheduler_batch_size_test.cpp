// How the dispatcher sizes its batches from what workers report (SchedulerCore::measured).
#include <gtest/gtest.h>

#include <chrono>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>

#include "server/embedded/in_process_tile_worker.h"
#include "server/scheduler/scheduler_core.h"
#include "server/scheduler/store/job_store.h"
#include "server/scheduler/workers/tile_worker.h"
#include "tests/support/in_process_worker.h"
#include "tests/support/job_specs.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

// A real in-process worker whose calls report a second of wall time per tile, as a worker would
// whose threads wait for cores taken by others; `report_cpu` keeps or drops the CPU time.
class CrowdedWorker final : public TileWorker {
 public:
  CrowdedWorker(const TileRendererOptions& options, bool report_cpu) : inner_(options), report_cpu_(report_cpu) {}
  grpc::Status render(const v1::RenderTileRequest& request, RenderedTiles& result,
                      std::chrono::system_clock::time_point deadline, TileCancel& cancel) override {
    grpc::Status status = inner_.render(request, result, deadline, cancel);
    v1::RenderTileResponse& response = result.response;
    const v1::TileRect& r = request.rect();
    const int tiles = std::max(1, (r.x1() - r.x0()) / 8);  // the test's batches are row segments of 8 px tiles
    response.mutable_stats()->set_render_ms(1000.0 * tiles);
    if (!report_cpu_) response.mutable_stats()->clear_cpu_ms();
    return status;
  }
  bool probe(std::chrono::milliseconds) override { return true; }
  std::string describe() const override { return "crowded"; }

 private:
  InProcessTileWorker inner_;
  bool report_cpu_;
};

std::size_t calls_for_job(bool report_cpu) {
  test::TempDir dir;
  nlohmann::json job = nlohmann::json::parse(test::cornell_job_json("raster", 96, 64, 1));
  job["render"]["tile_size"] = 8;  // a grid of 12 x 8 cheap tiles
  const v1::JobSpec spec = test::make_job_spec(job.dump(), test::cornell_assets(), "cornell.json");
  std::string id;
  {
    SchedulerOptions options;
    options.data_dir = dir / "farm";
    options.log_level = LogLevel::warn;
    options.batch_target = std::chrono::milliseconds(200);
    SchedulerCore core(options);
    test::add_cornell_assets(core);
    core.add_worker(std::make_shared<CrowdedWorker>(test::in_process_worker_options(dir / "farm", dir / "worker", 2),
                                                    report_cpu));
    id = core.submit(core.check(spec)).job_id();
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (core.get_job(id)->state() != v1::JOB_STATE_SUCCEEDED && std::chrono::steady_clock::now() < give_up) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    EXPECT_EQ(core.get_job(id)->state(), v1::JOB_STATE_SUCCEEDED);
  }
  std::set<std::uint32_t> parts;
  for (const UnitRecord& t : JobStore(dir / "farm" / "jobs.db").units().tiles(id)) parts.insert(t.part);
  return parts.size();
}

TEST(SchedulerBatchSizeTest, BatchesFollowTheWorkersCpuTimeNotItsWallTime) {
  // Tiles of about a millisecond of CPU: batched although each call claims a second a tile.
  EXPECT_LT(calls_for_job(true), 48u);
}

TEST(SchedulerBatchSizeTest, AWorkerThatReportsNoCpuTimeIsSizedByItsWallTime) {
  // A second a tile against a 200 ms target: one tile a call.
  EXPECT_EQ(calls_for_job(false), 96u);
}

}  // namespace
}  // namespace farm
