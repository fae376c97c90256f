// Worker tags (issue #36): a job's requirements route its units to the workers that meet them,
// on a real scheduler with real registered workers, and a job no worker may take says so in its
// status instead of waiting silently.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "server/common/job_state.h"
#include "tests/support/background_process.h"
#include "tests/support/job_specs.h"
#include "tests/support/run_command.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

using namespace std::chrono_literals;

constexpr auto kWait = 120s;  // bounds every wait; a healthy run takes a second or two

// The Cornell box ray traced at 64 x 64 in 16 px tiles (16 units) with these requirements.
v1::JobSpec job_requiring(const nlohmann::json& requirements) {
  nlohmann::json job = nlohmann::json::parse(test::cornell_job_json("whitted", 64, 64, 1));
  job["render"]["tile_size"] = 16;
  job["requirements"] = requirements;
  return test::make_job_spec(job.dump(), test::cornell_assets(), "cornell.json");
}

TEST(FarmWorkerTags, ATaggedJobIsRenderedOnlyByTheTaggedWorkerAndAJobNoneMayTakeSaysSo) {
  test::TempDir dir;
  // One untagged worker (w1), then one offering big-mem, each one thread.
  test::LocalFarm farm = test::start_local_farm(dir.path(), 1, {"--batch-ms", "0"});
  ASSERT_TRUE(farm.problem.empty()) << farm.problem;
  test::WorkerProcess tagged({"--threads", "1", "--cache-dir", (dir / "w2").string(), "--scheduler", farm.address(),
                              "--tag", "big-mem,course-cg"});
  ASSERT_FALSE(tagged.address().empty()) << tagged.process().output();
  ASSERT_TRUE(tagged.process().wait_for_line("registered with the scheduler", 20s)) << tagged.process().output();
  auto stub = test::scheduler_stub(farm.address());
  ASSERT_TRUE(test::upload_assets(*stub, test::cornell_assets()).ok());

  v1::Job job;
  ASSERT_TRUE(test::submit(*stub, job_requiring({{"tags", {"big-mem"}}}), job).ok());
  ASSERT_EQ(job.required_tags_size(), 1);
  EXPECT_EQ(job.required_tags(0), "big-mem");
  const std::optional<v1::Job> done =
      test::wait_for_job(*stub, job.job_id(), [](const v1::Job& j) { return is_final(j.state()); }, kWait);
  ASSERT_TRUE(done);
  ASSERT_EQ(done->state(), v1::JOB_STATE_SUCCEEDED) << done->failure_reason();
  EXPECT_TRUE(done->unplaceable().empty());

  // Every unit on the tagged worker; the untagged one, though idle throughout, rendered none.
  grpc::ClientContext context;
  v1::ListWorkersResponse workers;
  ASSERT_TRUE(stub->ListWorkers(&context, v1::ListWorkersRequest(), &workers).ok());
  ASSERT_EQ(workers.workers_size(), 2);
  for (const v1::WorkerInfo& w : workers.workers()) {
    const bool is_tagged = w.address() == tagged.address();
    EXPECT_EQ(w.units_done(), is_tagged ? 16u : 0u) << w.address();
    const std::vector<std::string> tags(w.tags().begin(), w.tags().end());
    const std::vector<std::string> offered = {"big-mem", "course-cg"};
    EXPECT_EQ(tags, is_tagged ? offered : std::vector<std::string>()) << w.address();
  }
  const test::CommandResult table = test::run_command(test::farm_command("workers --scheduler " + farm.address()));
  EXPECT_NE(table.output.find("tags: big-mem, course-cg"), std::string::npos) << table.output;

  // Tags nobody offers, or more threads than any has: queued, never started, and saying why.
  for (const nlohmann::json& requirements : {nlohmann::json{{"tags", {"gpu"}}}, nlohmann::json{{"min_threads", 8}}}) {
    v1::Job waiting;
    ASSERT_TRUE(test::submit(*stub, job_requiring(requirements), waiting).ok());
    EXPECT_FALSE(waiting.unplaceable().empty()) << "SubmitJob's answer says it too";
    const std::optional<v1::Job> seen = test::get_job(*stub, waiting.job_id());
    ASSERT_TRUE(seen);
    EXPECT_EQ(seen->state(), v1::JOB_STATE_QUEUED);
    const std::string& why = seen->unplaceable();
    std::printf("waiting job: %s\n", why.c_str());
    EXPECT_NE(why.find("no worker may take it: it needs"), std::string::npos) << why;
    EXPECT_NE(why.find(requirements.contains("tags") ? "the tag gpu" : "8 threads"), std::string::npos) << why;
    EXPECT_NE(why.find(" lacks "), std::string::npos) << why;
    const test::CommandResult status =
        test::run_command(test::farm_command("status " + waiting.job_id() + " --scheduler " + farm.address()));
    EXPECT_NE(status.output.find("waiting: no worker may take it"), std::string::npos) << status.output;
    const test::CommandResult cancel =
        test::run_command(test::farm_command("cancel " + waiting.job_id() + " --scheduler " + farm.address()));
    EXPECT_EQ(cancel.exit_code, 0) << cancel.output;
    const std::optional<v1::Job> cancelled = test::get_job(*stub, waiting.job_id());
    ASSERT_TRUE(cancelled);
    EXPECT_EQ(cancelled->tiles_done(), 0u);
    EXPECT_TRUE(cancelled->unplaceable().empty()) << "a final job waits for nothing";
  }
}

}  // namespace
}  // namespace farm
