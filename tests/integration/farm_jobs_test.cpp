// Running the farm as its operator (issue #19): `farm pause`, `resume`, `priority`, `retry`,
// `delete`, `log`, `workers`, `watch` of a finished job, and the scheduler's --keep-finished, on a
// real scheduler process and the real `farm` binary. Workers are held mid-job where a test needs
// a job caught half done (FakeWorker::hold_after), so nothing depends on timing.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "renderer/image/exr_io.h"
#include "server/common/job_state.h"
#include "tests/support/background_process.h"
#include "tests/support/fake_worker.h"
#include "tests/support/farm_cli_fixture.h"
#include "tests/support/job_specs.h"
#include "tests/support/pixel_diff.h"
#include "tests/support/scheduler_client.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr auto kWait = 120s;  // bounds every wait; a healthy run takes a second or two
constexpr std::uint32_t kUnits = 16;

// The Cornell box ray traced at 64 x 64 in 16 px tiles: 16 units, one a call.
v1::JobSpec sixteen_unit_job(const std::string& name) {
  nlohmann::json job = nlohmann::json::parse(test::cornell_job_json("whitted", 64, 64, 1));
  job["name"] = name;
  job["render"]["tile_size"] = 16;
  return test::make_job_spec(job.dump(), test::cornell_assets(), "cornell.json");
}

bool is(const v1::Job& job, v1::JobState state) { return job.state() == state; }

class FarmJobsTest : public test::FarmCliFixture {
 protected:
  // A scheduler sending one unit a call, one call at a time, to a FakeWorker it probes up.
  void start(const std::vector<std::string>& extra = {}) {
    worker_ = std::make_unique<test::FakeWorker>(dir_ / "worker");
    ASSERT_FALSE(worker_->address().empty());
    std::vector<std::string> args{"--worker", worker_->address(), "--batch-ms", "0", "--tiles-per-worker", "1"};
    args.insert(args.end(), extra.begin(), extra.end());
    scheduler_ = std::make_unique<test::SchedulerProcess>(data(), args);
    ASSERT_FALSE(scheduler_->address().empty()) << scheduler_->process().output();
    stub_ = test::scheduler_stub(scheduler_->address());
    ASSERT_TRUE(test::upload_assets(*stub_, test::cornell_assets()).ok());
  }

  fs::path data() const { return dir_ / "data"; }

  std::string submit(const std::string& name, int priority = 0) {
    v1::Job job;
    const grpc::Status status = test::submit(*stub_, sixteen_unit_job(name), job, priority);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return job.job_id();
  }

  v1::Job wait_until(const std::string& id, const std::function<bool(const v1::Job&)>& done) {
    const std::optional<v1::Job> job = test::wait_for_job(*stub_, id, done, kWait);
    EXPECT_TRUE(job) << "job " << id << " did not get there";
    return job.value_or(v1::Job());
  }

  // `farm ARGS --scheduler ADDRESS`
  test::CommandResult farm_on(const std::string& args) {
    return test::run_command(farm(args + " --scheduler " + scheduler_->address()));
  }

  TileBuffer fetch_exr(const std::string& id) {
    const fs::path file = dir_ / (id + ".exr");
    const grpc::Status status = test::fetch_result(*stub_, id, v1::RESULT_KIND_EXR, file);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return status.ok() ? read_exr(file) : TileBuffer();
  }

  // Lets `n` more calls be answered, then holds the next ones until release().
  void answer_then_hold(int n) { worker_->hold_after(worker_->calls_answered() + n); }

  // Waits (bounded) until `n` calls in all have reached the worker (held ones too).
  void wait_for_calls(int n) {
    const auto until = std::chrono::steady_clock::now() + kWait;
    while (worker_->calls_arrived() < n && std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(10ms);
    }
    ASSERT_GE(worker_->calls_arrived(), n);
  }

  std::unique_ptr<test::FakeWorker> worker_;
  std::unique_ptr<test::SchedulerProcess> scheduler_;
  std::unique_ptr<v1::Scheduler::Stub> stub_;
};

TEST_F(FarmJobsTest, RetryOfACancelledJobRendersOnlyItsUnitsNotDoneAndTheImageIsBitIdentical) {
  start();
  const std::string whole = submit("uninterrupted");
  ASSERT_TRUE(is(wait_until(whole, [](const v1::Job& j) { return is_final(j.state()); }), v1::JOB_STATE_SUCCEEDED));
  const TileBuffer expected = fetch_exr(whole);

  // Three units done, the fourth held on the worker when the job is cancelled.
  answer_then_hold(3);
  const std::string id = submit("interrupted");
  wait_until(id, [](const v1::Job& j) { return j.tiles_done() == 3; });
  const test::CommandResult cancelled = farm_on("cancel " + id.substr(0, 6));
  ASSERT_EQ(cancelled.exit_code, 0) << cancelled.output;
  worker_->release();
  ASSERT_EQ(test::get_job(*stub_, id)->tiles_done(), 3u);

  const test::CommandResult retried = farm_on("retry " + id);
  ASSERT_EQ(retried.exit_code, 0) << retried.output;
  EXPECT_NE(retried.output.find("13 units queued again"), std::string::npos) << retried.output;
  const v1::Job done = wait_until(id, [](const v1::Job& j) { return is_final(j.state()); });
  ASSERT_TRUE(is(done, v1::JOB_STATE_SUCCEEDED)) << done.failure_reason();
  EXPECT_EQ(done.tiles_rendered(), kUnits);  // the three kept, none rendered twice
  EXPECT_EQ(test::differing_pixels(fetch_exr(id), expected), 0);

  const test::CommandResult log = farm_on("log " + id);
  ASSERT_EQ(log.exit_code, 0) << log.output;
  for (const char* said : {"submitted: queued, 16 units", "-> cancelled", "retried: 13 units queued again, 3 kept",
                           "cancelled -> running", "frame 0 merged", "running -> succeeded"}) {
    EXPECT_NE(log.output.find(said), std::string::npos) << said << "\n" << log.output;
  }
  EXPECT_LT(log.output.find("-> cancelled"), log.output.find("retried:")) << log.output;

  // A second retry: the job is done.
  const test::CommandResult again = farm_on("retry " + id);
  EXPECT_EQ(again.exit_code, 2) << again.output;
  EXPECT_NE(again.output.find("only a failed or cancelled job can be retried"), std::string::npos) << again.output;
}

TEST_F(FarmJobsTest, PauseStopsDispatchResumeContinuesAndPriorityIsLogged) {
  start();
  // The paused job ranks first, so every unit it got would have gone before the other job's.
  // Its first unit is on the worker, held, when it is paused.
  const int received = worker_->calls_arrived();
  answer_then_hold(0);
  const std::string paused = submit("held", 10);
  wait_for_calls(received + 1);
  const test::CommandResult pause = farm_on("pause " + paused);
  ASSERT_EQ(pause.exit_code, 0) << pause.output;
  EXPECT_NE(pause.output.find("paused"), std::string::npos) << pause.output;
  worker_->release();  // the call in flight when it was paused finishes: a unit in flight is kept
  const std::uint32_t before = wait_until(paused, [](const v1::Job& j) { return j.tiles_done() == 1; }).tiles_done();

  const std::string other = submit("other");
  ASSERT_TRUE(is(wait_until(other, [](const v1::Job& j) { return is_final(j.state()); }), v1::JOB_STATE_SUCCEEDED));
  const v1::Job held = *test::get_job(*stub_, paused);
  EXPECT_TRUE(held.paused());
  EXPECT_FALSE(is_final(held.state()));
  EXPECT_EQ(held.tiles_done(), before);  // nothing of it went out while the other job rendered
  const test::CommandResult status = farm_on("status");
  EXPECT_NE(status.output.find(fmt::format("{}  {:<20}  paused", paused, "held")), std::string::npos) << status.output;

  const test::CommandResult priority = farm_on("priority " + paused.substr(0, 5) + " 3");
  ASSERT_EQ(priority.exit_code, 0) << priority.output;
  EXPECT_EQ(test::get_job(*stub_, paused)->priority(), 3);
  const test::CommandResult resume = farm_on("resume " + paused);
  ASSERT_EQ(resume.exit_code, 0) << resume.output;
  ASSERT_TRUE(is(wait_until(paused, [](const v1::Job& j) { return is_final(j.state()); }), v1::JOB_STATE_SUCCEEDED));

  const test::CommandResult log = farm_on("log " + paused);
  ASSERT_EQ(log.exit_code, 0) << log.output;
  for (const char* said : {"\n", "paused", "priority 10 -> 3", "resumed", "running -> succeeded"}) {
    EXPECT_NE(log.output.find(said), std::string::npos) << said << "\n" << log.output;
  }
  EXPECT_LT(log.output.find("paused"), log.output.find("resumed")) << log.output;
  // A final job is neither paused nor resumed.
  const test::CommandResult late = farm_on("pause " + paused);
  EXPECT_EQ(late.exit_code, 2) << late.output;
  EXPECT_NE(late.output.find("only a queued or running job can be paused"), std::string::npos) << late.output;

  // `farm watch` of a job that has ended replays its log.
  const test::CommandResult watch = farm_on("watch " + paused);
  EXPECT_EQ(watch.exit_code, 0) << watch.output;
  EXPECT_NE(watch.output.find("priority 10 -> 3"), std::string::npos) << watch.output;
  EXPECT_NE(watch.output.find("running -> succeeded"), std::string::npos) << watch.output;

  // `farm workers`: the one worker, up, with the units it rendered.
  const test::CommandResult workers = farm_on("workers --json");
  ASSERT_EQ(workers.exit_code, 0) << workers.output;
  const nlohmann::json listed = nlohmann::json::parse(workers.output);
  ASSERT_EQ(listed.size(), 1u) << workers.output;
  EXPECT_EQ(listed[0]["address"], worker_->address());
  EXPECT_EQ(listed[0]["state"], "WORKER_STATE_UP");
  EXPECT_EQ(listed[0]["units_done"], std::to_string(2 * kUnits));  // uint64 in JSON: a string
  const test::CommandResult table = farm_on("workers");
  EXPECT_NE(table.output.find(worker_->address()), std::string::npos) << table.output;
}

TEST_F(FarmJobsTest, DeleteRemovesTheJobAndItsFilesAndRefusesARunningJob) {
  start();
  const std::string done = submit("done");
  ASSERT_TRUE(is(wait_until(done, [](const v1::Job& j) { return is_final(j.state()); }), v1::JOB_STATE_SUCCEEDED));
  ASSERT_TRUE(fs::exists(data() / "results" / done));

  // A cancelled job keeps its done units' files for a retry, until it is deleted.
  answer_then_hold(2);
  const std::string cancelled = submit("cancelled");
  wait_until(cancelled, [](const v1::Job& j) { return j.tiles_done() == 2; });
  const test::CommandResult running = farm_on("delete " + cancelled);
  EXPECT_EQ(running.exit_code, 2) << running.output;
  EXPECT_NE(running.output.find("cancel it first"), std::string::npos) << running.output;
  ASSERT_EQ(farm_on("cancel " + cancelled).exit_code, 0);
  worker_->release();
  ASSERT_TRUE(fs::exists(data() / "tiles" / cancelled));

  for (const std::string& id : {done, cancelled}) {
    const test::CommandResult deleted = farm_on("delete " + id.substr(0, 7));
    ASSERT_EQ(deleted.exit_code, 0) << deleted.output;
    EXPECT_NE(deleted.output.find("deleted"), std::string::npos) << deleted.output;
    EXPECT_FALSE(test::get_job(*stub_, id)) << id;
    EXPECT_FALSE(fs::exists(data() / "results" / id)) << id;
    EXPECT_FALSE(fs::exists(data() / "tiles" / id)) << id;
    EXPECT_EQ(farm_on("status " + id).exit_code, 1);  // no such job
  }
}

TEST_F(FarmJobsTest, RetentionDeletesFinishedJobsAndKeepsActiveOnes) {
  start({"--keep-finished", "1s"});
  const std::string finished = submit("finished");
  ASSERT_TRUE(is(wait_until(finished, [](const v1::Job& j) { return is_final(j.state()); }), v1::JOB_STATE_SUCCEEDED));
  answer_then_hold(0);
  const std::string active = submit("active");
  ASSERT_EQ(farm_on("pause " + active).exit_code, 0);
  worker_->release();

  // Bounded wait for the sweep (it looks every second): the finished job goes, files and all.
  const auto until = std::chrono::steady_clock::now() + kWait;
  while (test::get_job(*stub_, finished) && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(100ms);
  }
  EXPECT_FALSE(test::get_job(*stub_, finished));
  EXPECT_FALSE(fs::exists(data() / "results" / finished));
  // The paused job outlived several sweeps and is still there.
  std::this_thread::sleep_for(2500ms);
  const std::optional<v1::Job> kept = test::get_job(*stub_, active);
  ASSERT_TRUE(kept);
  EXPECT_FALSE(is_final(kept->state()));
}

TEST(FarmJobsLostWorkerTest, TheLogNamesAKilledWorkerAndARetryOnAnotherFinishesTheJob) {
  test::TempDir dir;
  // One registered worker, killed while it renders; a job may lose only one.
  test::LocalFarm farm = test::start_local_farm(dir.path(), 1, {"--max-lost-worker-attempts", "1", "--batch-ms", "0"});
  ASSERT_TRUE(farm.problem.empty()) << farm.problem;
  auto stub = test::scheduler_stub(farm.address());
  ASSERT_TRUE(test::upload_assets(*stub, test::cornell_assets()).ok());
  // Slow enough units (path traced, 64 samples) that the worker is rendering when it is killed.
  nlohmann::json job = nlohmann::json::parse(test::cornell_job_json("path", 64, 64, 64));
  job["render"]["tile_size"] = 16;
  v1::Job submitted;
  ASSERT_TRUE(test::submit(*stub, test::make_job_spec(job.dump(), test::cornell_assets(), "cornell.json"), submitted).ok());
  const std::string id = submitted.job_id();

  const test::CommandResult workers = test::run_command(test::farm_command("workers --json --scheduler " + farm.address()));
  ASSERT_EQ(workers.exit_code, 0) << workers.output;
  const nlohmann::json listed = nlohmann::json::parse(workers.output);
  ASSERT_EQ(listed.size(), 1u);
  EXPECT_TRUE(listed[0]["registered"].get<bool>());
  EXPECT_EQ(listed[0]["threads"], 1);
  EXPECT_NE(listed[0]["engines"].dump().find("path"), std::string::npos) << workers.output;
  const std::string address = listed[0]["address"];

  ASSERT_TRUE(test::wait_for_job(*stub, id, [](const v1::Job& j) { return j.tiles_done() >= 1; }, kWait));
  farm.workers[0]->process().send_signal(SIGKILL);
  const std::optional<v1::Job> failed = test::wait_for_job(*stub, id, [](const v1::Job& j) { return is_final(j.state()); }, kWait);
  ASSERT_TRUE(failed);
  ASSERT_EQ(failed->state(), v1::JOB_STATE_FAILED);
  EXPECT_LT(failed->tiles_done(), kUnits);

  const test::CommandResult log = test::run_command(test::farm_command("log " + id + " --scheduler " + farm.address()));
  ASSERT_EQ(log.exit_code, 0) << log.output;
  EXPECT_NE(log.output.find("failed on " + address), std::string::npos) << log.output;
  EXPECT_NE(log.output.find("-> failed"), std::string::npos) << log.output;

  // farm workers lists it as lost, with when and why, rather than dropping it (issue #32).
  nlohmann::json lost;
  const auto listed_lost = [&] {
    const test::CommandResult r = test::run_command(test::farm_command("workers --json --scheduler " + farm.address()));
    if (r.exit_code != 0) return false;
    for (const nlohmann::json& w : nlohmann::json::parse(r.output)) {
      if (w["address"] == address && w["state"] == "WORKER_STATE_LOST") lost = w;
    }
    return lost.is_object();
  };
  const auto until = std::chrono::steady_clock::now() + kWait;
  while (!listed_lost() && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(100ms);
  ASSERT_TRUE(lost.is_object()) << "the killed worker is not listed as lost";
  EXPECT_TRUE(lost.contains("lost_at")) << lost.dump();
  EXPECT_NE(lost["lost_reason"].get<std::string>().find("heartbeat"), std::string::npos) << lost.dump();
  const test::CommandResult table = test::run_command(test::farm_command("workers --scheduler " + farm.address()));
  EXPECT_NE(table.output.find("lost"), std::string::npos) << table.output;

  // Another worker joins; the retry renders what was not done.
  test::WorkerProcess second({"--scheduler", farm.address(), "--threads", "1", "--cache-dir", (dir.path() / "w9").string()});
  ASSERT_FALSE(second.address().empty());
  const test::CommandResult retried =
      test::run_command(test::farm_command("retry " + id + " --scheduler " + farm.address()));
  ASSERT_EQ(retried.exit_code, 0) << retried.output;
  const std::optional<v1::Job> done = test::wait_for_job(*stub, id, [](const v1::Job& j) { return is_final(j.state()); }, kWait);
  ASSERT_TRUE(done);
  EXPECT_EQ(done->state(), v1::JOB_STATE_SUCCEEDED) << done->failure_reason();
}

}  // namespace
}  // namespace farm
