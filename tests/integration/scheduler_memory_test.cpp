// A scheduler keeps no per-job state in memory once a job has ended, and gives the heap's free
// pages back: its RSS after a burst of a thousand jobs is close to what it was once warm. Each job
// is a 64x64 raster frame of 300 Cornell boxes side by side: its spec, parsed job and merged
// frame come to about 150 KB in the scheduler while it runs, 150 MB over the burst were they
// kept (a scheduler whose RunningJobs forgot no final job ended 309 MiB above its warm level).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "tests/support/background_process.h"
#include "tests/support/job_specs.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

using namespace std::chrono_literals;

constexpr int kJobs = 1000;
constexpr int kBatch = 50;         // jobs submitted together, then waited for
constexpr long kAllowedGrowthKb = 32 * 1024;

// 300 instances of the Cornell box in a row: a job text of about 20 KB and a scene of 300 objects.
v1::JobSpec many_boxes_spec() {
  nlohmann::json job = nlohmann::json::parse(test::cornell_job_json("raster", 64, 64, 1));
  nlohmann::json& objects = job["scene"]["objects"];
  const nlohmann::json box = objects[0];
  for (int i = 1; i < 300; ++i) {
    nlohmann::json copy = box;
    copy["translate"] = {2.5 * i, 0, -1};
    objects.push_back(copy);
  }
  return test::make_job_spec(job.dump(), test::cornell_assets(), "cornell.json");
}

class SchedulerMemoryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    farm_ = test::start_local_farm(dir_.path(), 1);
    ASSERT_TRUE(farm_.problem.empty()) << farm_.problem;
    stub_ = test::scheduler_stub(farm_.address());
    ASSERT_TRUE(test::upload_assets(*stub_, test::cornell_assets()).ok());
  }

  // Submits `count` jobs at once and waits until each has SUCCEEDED.
  void run_batch(int count) {
    const v1::JobSpec spec = many_boxes_spec();
    std::vector<std::string> ids;
    for (int i = 0; i < count; ++i) {
      v1::Job job;
      const grpc::Status status = test::submit(*stub_, spec, job);
      ASSERT_TRUE(status.ok()) << status.error_message();
      ids.push_back(job.job_id());
    }
    for (const std::string& id : ids) {
      const auto job = test::wait_for_job(
          *stub_, id, [](const v1::Job& j) { return j.state() != v1::JOB_STATE_QUEUED && j.state() != v1::JOB_STATE_RUNNING; },
          120s);
      ASSERT_TRUE(job) << "job " << id << " did not end";
      ASSERT_EQ(job->state(), v1::JOB_STATE_SUCCEEDED) << job->failure_reason();
    }
  }

  // The scheduler's RSS once it has settled: the heap is trimmed when the farm falls idle, a
  // moment after the last job's state is published, so the lowest of a few looks is taken.
  long settled_rss_kb(long at_most_kb) {
    long lowest = test::proc_status(farm_.scheduler->process().pid()).vm_rss_kb;
    for (int look = 0; look < 50 && lowest > at_most_kb; ++look) {
      std::this_thread::sleep_for(100ms);
      lowest = std::min(lowest, test::proc_status(farm_.scheduler->process().pid()).vm_rss_kb);
    }
    return lowest;
  }

  test::TempDir dir_;
  test::LocalFarm farm_;
  std::unique_ptr<v1::Scheduler::Stub> stub_;
};

TEST_F(SchedulerMemoryTest, RssAfterAThousandJobsIsCloseToItsWarmLevel) {
  const long start_kb = test::proc_status(farm_.scheduler->process().pid()).vm_rss_kb;
  run_batch(kBatch);  // warm: gRPC's threads and buffers, the store's cache, the scene checked
  ASSERT_FALSE(HasFatalFailure());
  const long warm_kb = settled_rss_kb(0);
  long peak_kb = warm_kb;
  for (int done = kBatch; done < kJobs; done += kBatch) {
    run_batch(kBatch);
    ASSERT_FALSE(HasFatalFailure());
    peak_kb = std::max(peak_kb, test::proc_status(farm_.scheduler->process().pid()).vm_rss_kb);
  }
  const long end_kb = settled_rss_kb(warm_kb + kAllowedGrowthKb);
  std::printf("scheduler VmRSS: %ld kB at start, %ld kB warm (after %d jobs), %ld kB at most between "
              "batches, %ld kB after %d jobs\n",
              start_kb, warm_kb, kBatch, peak_kb, end_kb, kJobs);
  EXPECT_LE(end_kb, warm_kb + kAllowedGrowthKb)
      << "the scheduler kept " << (end_kb - warm_kb) / 1024 << " MiB more after " << kJobs << " jobs";
}

}  // namespace
}  // namespace farm
