// Scheduling on a real scheduler core with workers in this process (issue #36): a chain of jobs
// whose middle fails, a job capped to one worker on a farm of three, and a job following another
// frame by frame, each checked by what the workers were asked to render and when, not by time.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>

#include "server/common/job_state.h"
#include "server/common/read_whole_file.h"
#include "server/embedded/in_process_tile_worker.h"
#include "server/scheduler/scheduler_core.h"
#include "tests/support/eventually.h"
#include "tests/support/job_specs.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

using test::eventually;

using namespace std::chrono_literals;

// An in-process worker under a name of its own, which first asks `before` about each call (a
// status other than OK is its answer, unrendered) and tells `after` when a call is rendered.
class NamedWorker final : public TileWorker {
 public:
  using Check = std::function<grpc::Status(const v1::RenderTileRequest&)>;
  using Done = std::function<void(const v1::RenderTileRequest&)>;
  NamedWorker(std::string name, const TileRendererOptions& options, Check before = {}, Done after = {})
      : name_(std::move(name)), inner_(options), before_(std::move(before)), after_(std::move(after)) {}
  grpc::Status render(const v1::RenderTileRequest& request, RenderedTiles& result,
                      std::chrono::system_clock::time_point deadline, TileCancel& cancel) override {
    if (before_) {
      if (grpc::Status status = before_(request); !status.ok()) return status;
    }
    grpc::Status status = inner_.render(request, result, deadline, cancel);
    if (after_) after_(request);
    return status;
  }
  bool probe(std::chrono::milliseconds) override { return true; }
  std::string describe() const override { return name_; }

 private:
  std::string name_;
  InProcessTileWorker inner_;
  Check before_;
  Done after_;
};

class SchedulerDependenciesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    options_.data_dir = dir_ / "farm";
    options_.log_level = LogLevel::off;
    options_.batch_target = std::chrono::milliseconds(0);  // one unit a call
    options_.max_attempts = 1;
    // No spot checks: a unit rendered again on a second worker to check the first is the
    // scheduler's own call, outside the job's caps (docs/architecture.md, "Scheduling").
    options_.remote_verify_fraction = 0.0;
    core_ = std::make_unique<SchedulerCore>(options_);
    for (const auto& [path, file] : test::cornell_assets()) core_->assets().add(read_whole_file(file, "asset"));
  }
  std::shared_ptr<NamedWorker> worker(const std::string& name, NamedWorker::Check before = {},
                                      NamedWorker::Done after = {}) {
    TileRendererOptions r;
    r.blobs_dir = dir_ / "farm" / "assets";
    r.cache_dir = dir_ / name;
    r.threads = 1;
    r.log_level = LogLevel::off;
    return std::make_shared<NamedWorker>(name, r, std::move(before), std::move(after));
  }
  // The Cornell box rasterised at 32 x 32 in 16 px tiles (4 units a frame), with `extra` merged
  // into the job file.
  v1::Job submit(const nlohmann::json& extra = nlohmann::json::object(), const QueueTerms& terms = {},
                 int priority = 0) {
    nlohmann::json job = nlohmann::json::parse(test::cornell_job_json("raster", 32, 32, 1));
    job["render"]["tile_size"] = 16;
    job.update(extra);
    if (job.contains("frames")) job["output"] = {{"image", "out/cornell.####.exr"}, {"preview", "out/cornell.####.png"}};
    return core_->submit(core_->check(test::make_job_spec(job.dump(), test::cornell_assets(), "cornell.json")), priority,
                         nullptr, {}, terms);
  }
  v1::Job job(const std::string& id) const { return *core_->get_job(id); }
  bool ended(const std::string& id) const { return is_final(job(id).state()); }

  test::TempDir dir_;
  SchedulerOptions options_;
  std::unique_ptr<SchedulerCore> core_;
};

TEST_F(SchedulerDependenciesTest, AThreeJobChainWhoseMiddleFailsFailsTheLastNamingIt) {
  const v1::Job a = submit();
  const v1::Job b = submit(nlohmann::json::object(), {.after = {a.job_id()}});
  const v1::Job c = submit(nlohmann::json::object(), {.after = {b.job_id()}});
  EXPECT_EQ(b.state(), v1::JOB_STATE_WAITING);
  EXPECT_EQ(c.state(), v1::JOB_STATE_WAITING);
  EXPECT_EQ(std::vector<std::string>(c.after().begin(), c.after().end()), std::vector<std::string>{b.job_id()});
  // Every call for b fails on the one worker, and a job fails at its first failed attempt.
  std::atomic<int> calls_for_c{0};
  core_->add_worker(worker("w1", [&](const v1::RenderTileRequest& request) {
    if (request.job_id() == c.job_id()) ++calls_for_c;
    return request.job_id() == b.job_id() ? grpc::Status(grpc::StatusCode::INTERNAL, "b cannot be rendered")
                                          : grpc::Status::OK;
  }));
  ASSERT_TRUE(eventually([&] { return ended(c.job_id()); }, std::chrono::minutes(2)));
  EXPECT_EQ(job(a.job_id()).state(), v1::JOB_STATE_SUCCEEDED);
  EXPECT_EQ(job(b.job_id()).state(), v1::JOB_STATE_FAILED);
  const v1::Job last = job(c.job_id());
  EXPECT_EQ(last.state(), v1::JOB_STATE_FAILED);
  EXPECT_EQ(last.failure_reason().rfind("dependency " + b.job_id() + " failed: ", 0), 0u) << last.failure_reason();
  EXPECT_EQ(calls_for_c.load(), 0) << "nothing of c was handed out";
  EXPECT_EQ(last.tiles_done(), 0u);
  // The log says it: failed from waiting (logged as the change is announced, just after the store
  // has it).
  const auto failed_from_waiting = [&] {
    for (const v1::JobLogEntry& e : core_->store().log().job_log(c.job_id(), 0, 100, nullptr)) {
      const v1::JobStateChanged& change = e.event().state_changed();
      if (change.from() == v1::JOB_STATE_WAITING && change.to() == v1::JOB_STATE_FAILED) return true;
    }
    return false;
  };
  EXPECT_TRUE(eventually(failed_from_waiting));
  const v1::Job middle = job(b.job_id());
  EXPECT_EQ(std::vector<std::string>(middle.dependents().begin(), middle.dependents().end()),
            std::vector<std::string>{c.job_id()});
}

TEST_F(SchedulerDependenciesTest, AJobCappedToOneWorkerIsRenderedByOneWorkerAtATimeOfThree) {
  // 4 frames x 4 tiles = 16 units, one a call; three idle workers of one thread each.
  const v1::Job capped = submit({{"frames", {{"start", 1}, {"end", 4}}}, {"limits", {{"max_workers", 1}}}});
  EXPECT_EQ(capped.max_workers(), 1u);
  std::mutex mutex;
  std::multiset<std::string> rendering;  // the workers inside a call of the job now
  std::size_t most_at_once = 0;
  int calls = 0;
  for (const std::string name : {"w1", "w2", "w3"}) {
    core_->add_worker(worker(
        name,
        [&, name](const v1::RenderTileRequest&) {
          std::lock_guard lock(mutex);
          rendering.insert(name);
          ++calls;
          most_at_once = std::max(most_at_once, std::set<std::string>(rendering.begin(), rendering.end()).size());
          return grpc::Status::OK;
        },
        [&, name](const v1::RenderTileRequest&) {
          std::lock_guard lock(mutex);
          rendering.erase(rendering.find(name));
        }));
  }
  ASSERT_TRUE(eventually([&] { return ended(capped.job_id()); }, std::chrono::minutes(2)));
  ASSERT_EQ(job(capped.job_id()).state(), v1::JOB_STATE_SUCCEEDED) << job(capped.job_id()).failure_reason();
  EXPECT_EQ(calls, 16);
  EXPECT_EQ(most_at_once, 1u) << "the cap held it to one worker at a time";
}

TEST_F(SchedulerDependenciesTest, AFollowersFrameNeverStartsBeforeTheLeadersFrameIsMerged) {
  const v1::Job leader = submit({{"frames", {{"start", 1}, {"end", 4}}}});
  // Ahead of the leader in the queue: without the dependency its frames would go out first.
  const v1::Job follower = submit({{"frames", {{"start", 1}, {"end", 4}}}}, {.after_frames = leader.job_id()}, 1);
  EXPECT_EQ(follower.after_frames(), leader.job_id());
  std::atomic<int> follower_calls{0}, early{0};
  for (const std::string name : {"w1", "w2"}) {
    core_->add_worker(worker(name, [&](const v1::RenderTileRequest& request) {
      if (request.job_id() == follower.job_id()) {
        ++follower_calls;
        if (!core_->store().frames().is_frame_merged(leader.job_id(), request.frame())) ++early;
      }
      return grpc::Status::OK;
    }));
  }
  ASSERT_TRUE(eventually([&] { return ended(follower.job_id()) && ended(leader.job_id()); }, std::chrono::minutes(2)));
  EXPECT_EQ(job(follower.job_id()).state(), v1::JOB_STATE_SUCCEEDED) << job(follower.job_id()).failure_reason();
  EXPECT_EQ(follower_calls.load(), 16);  // one call a unit: every frame's four tiles
  EXPECT_EQ(early.load(), 0) << "a frame of the follower started before the leader's was merged";
}

}  // namespace
}  // namespace farm
