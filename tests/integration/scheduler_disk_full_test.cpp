// A scheduler whose data dir fills up (a small tmpfs and a ballast file): it stays up and answers,
// refuses what it cannot store as RESOURCE_EXHAUSTED "disk full in <folder>", fails no job, logs
// a bounded number of lines about it, and once the ballast goes, finishes every job bit-identical
// to `farm render`. Needs root to mount the tmpfs (skipped otherwise, saying so).
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "renderer/image/exr_io.h"
#include "server/common/disk_full.h"
#include "server/common/job_state.h"
#include "tests/support/background_process.h"
#include "tests/support/farm_cli_fixture.h"
#include "tests/support/job_specs.h"
#include "tests/support/pixel_diff.h"
#include "tests/support/run_command.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"
#include "tests/support/tmpfs_mount.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr std::uint64_t kDataDirBytes = 20 << 20;  // the 20 MB tmpfs

// Lines of `log` that say the disk is full.
int disk_full_lines(const std::string& log) {
  std::istringstream in(log);
  int n = 0;
  for (std::string line; std::getline(in, line);) n += line.find("disk full") != std::string::npos;
  return n;
}

v1::JobSpec cornell(const std::string& engine, int width, int height, int spp, int tile_size,
                    std::size_t padding = 0) {
  nlohmann::json job = nlohmann::json::parse(test::cornell_job_json(engine, width, height, spp));
  job["render"]["tile_size"] = tile_size;
  // Trailing blanks: a bigger job text (and job store row) for the same job.
  return test::make_job_spec(job.dump(2) + std::string(padding, ' '), test::cornell_assets(), "cornell.json");
}

// `bytes` that no asset of the test has, in a file outside the tmpfs.
fs::path new_asset_file(const test::TempDir& dir, std::uint64_t bytes) {
  std::mt19937 random(7);
  std::string data(bytes, '\0');
  for (char& c : data) c = static_cast<char>(random());
  return dir.write("fresh-asset.bin", data);
}

class SchedulerDiskFullTest : public ::testing::Test {
 protected:
  void SetUp() override {
    mount_ = std::make_unique<test::TmpfsMount>(data_, kDataDirBytes);
    if (!mount_->mounted()) GTEST_SKIP() << "needs a tmpfs of its own: " << mount_->problem();
  }

  std::vector<v1::Job> all_jobs(v1::Scheduler::Stub& stub, grpc::Status& status) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + 30s);
    v1::ListJobsRequest request;
    request.set_page_size(1000);
    v1::ListJobsResponse response;
    status = stub.ListJobs(&context, request, &response);
    return {response.jobs().begin(), response.jobs().end()};
  }

  test::TempDir dir_;
  const fs::path data_ = dir_ / "data";
  std::unique_ptr<test::TmpfsMount> mount_;  // after dir_: unmounted before it is removed
};

TEST_F(SchedulerDiskFullTest, AFullDataDirPausesDispatchFailsNoJobAndEveryJobFinishesOnceThereIsRoom) {
  test::SchedulerProcess scheduler(data_, {});
  ASSERT_FALSE(scheduler.address().empty()) << scheduler.process().output();
  const auto stub = test::scheduler_stub(scheduler.address());
  ASSERT_TRUE(test::upload_assets(*stub, test::cornell_assets()).ok());

  // 22 jobs queued while no worker runs, then room left for a few of them only: the disk fills
  // while they render.
  const v1::JobSpec spec = cornell("path", 64, 64, 2, 16);
  std::vector<std::string> ids;
  for (int i = 0; i < 22; ++i) {
    v1::Job job;
    const grpc::Status status = test::submit(*stub, spec, job);
    ASSERT_TRUE(status.ok()) << status.error_message();
    ids.push_back(job.job_id());
  }
  mount_->fill(data_ / "ballast", 1 << 20);
  test::WorkerProcess worker(
      {"--threads", "2", "--cache-dir", (dir_ / "w1").string(), "--scheduler", scheduler.address()});
  ASSERT_FALSE(worker.address().empty()) << worker.process().output();
  ASSERT_TRUE(worker.process().wait_for_line("registered with the scheduler", 20s)) << worker.process().output();

  // Full, mid-run: some jobs wait for room.
  ASSERT_TRUE(scheduler.process().wait_for_line("disk full in", 120s)) << scheduler.process().output();
  grpc::Status listed;
  int unfinished = 0;
  for (const v1::Job& job : all_jobs(*stub, listed)) unfinished += job.state() != v1::JOB_STATE_SUCCEEDED;
  EXPECT_GT(unfinished, 0);
  const fs::path big = new_asset_file(dir_, free_bytes(data_).value_or(0) + (256 << 10));
  const grpc::Status upload = test::upload_assets(*stub, {{"big.bin", big}});
  EXPECT_EQ(upload.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << upload.error_message();
  EXPECT_NE(upload.error_message().find("disk full"), std::string::npos) << upload.error_message();
  EXPECT_NE(upload.error_message().find((data_ / "assets").string()), std::string::npos) << upload.error_message();
  // The disk stays full a while: the scheduler neither spins nor fails anything meanwhile.
  std::this_thread::sleep_for(5s);
  for (const v1::Job& job : all_jobs(*stub, listed)) {
    EXPECT_NE(job.state(), v1::JOB_STATE_FAILED) << job.job_id() << ": " << job.failure_reason();
  }
  EXPECT_TRUE(listed.ok()) << listed.error_message();
  EXPECT_FALSE(scheduler.process().wait_exit(0ms)) << scheduler.process().output();
  EXPECT_LT(disk_full_lines(scheduler.process().output()), 20) << scheduler.process().output().substr(0, 4000);

  // Room again: every job ends, as `farm render` renders it, and none counted a failed attempt.
  fs::remove(data_ / "ballast");
  const fs::path job_dir = dir_ / "job";
  fs::create_directories(job_dir / "assets");
  for (const auto& [path, file] : test::cornell_assets()) fs::copy_file(file, job_dir / path);
  std::ofstream(job_dir / "cornell.json") << spec.job_json();
  const fs::path local = dir_ / "local.exr";
  const test::CommandResult r = test::run_command(test::farm_command(
      "render " + test::shell_quote((job_dir / "cornell.json").string()) + " --quiet --out " +
      test::shell_quote(local.string()) + " --preview none"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const TileBuffer expected = read_exr(local);
  for (const std::string& id : ids) {
    const auto job = test::wait_for_job(
        *stub, id, [](const v1::Job& j) { return is_final(j.state()); }, 180s);
    ASSERT_TRUE(job) << id << " never ended\n" << scheduler.process().output().substr(0, 4000);
    ASSERT_EQ(job->state(), v1::JOB_STATE_SUCCEEDED) << id << ": " << job->failure_reason();
    EXPECT_EQ(job->tile_failures(), 0u) << id;
    const fs::path exr = dir_ / (id + ".exr");
    const grpc::Status fetched = test::fetch_result(*stub, id, v1::RESULT_KIND_EXR, exr);
    ASSERT_TRUE(fetched.ok()) << fetched.error_message();
    EXPECT_EQ(test::differing_pixels(read_exr(exr), expected), 0) << id;
  }
  EXPECT_LT(disk_full_lines(scheduler.process().output()), 20) << scheduler.process().output().substr(0, 4000);
  EXPECT_FALSE(scheduler.process().wait_exit(0ms));
}

TEST_F(SchedulerDiskFullTest, AFullJobStoreRefusesASubmitAsDiskFullAndTakesItOnceThereIsRoom) {
  test::SchedulerProcess scheduler(data_, {});
  ASSERT_FALSE(scheduler.address().empty()) << scheduler.process().output();
  const auto stub = test::scheduler_stub(scheduler.address());
  ASSERT_TRUE(test::upload_assets(*stub, test::cornell_assets()).ok());
  // A job text of a megabyte: each job adds that much to the store's write-ahead log. The first
  // also lays the scene out, so the second needs room in the store alone.
  const v1::JobSpec spec = cornell("raster", 32, 32, 1, 16, 1 << 20);
  v1::Job first;
  const grpc::Status submitted = test::submit(*stub, spec, first);
  ASSERT_TRUE(submitted.ok()) << submitted.error_message();

  mount_->fill(data_ / "ballast", 0);
  v1::Job refused;
  const grpc::Status full = test::submit(*stub, spec, refused);
  EXPECT_EQ(full.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << full.error_message();
  EXPECT_NE(full.error_message().find("disk full in " + data_.string() + ":"), std::string::npos)
      << full.error_message();
  EXPECT_NE(full.error_message().find("job store"), std::string::npos) << full.error_message();
  // Still up and answering; the refused job left nothing behind.
  const auto still = test::get_job(*stub, first.job_id());
  ASSERT_TRUE(still) << scheduler.process().output();
  EXPECT_EQ(still->state(), v1::JOB_STATE_QUEUED);
  grpc::Status listed;
  EXPECT_EQ(all_jobs(*stub, listed).size(), 1u);
  EXPECT_TRUE(listed.ok()) << listed.error_message();

  fs::remove(data_ / "ballast");
  v1::Job second;
  const grpc::Status again = test::submit(*stub, spec, second);
  EXPECT_TRUE(again.ok()) << again.error_message();
  EXPECT_FALSE(scheduler.process().wait_exit(0ms)) << scheduler.process().output();
}

// The worker's disk, not the scheduler's: its cache cannot take the job's files. It answers
// RESOURCE_EXHAUSTED "disk full", which counts no attempt against the job; once its disk has
// room the job finishes.
TEST(WorkerDiskFullTest, AWorkerWithAFullCacheCountsNoAttemptAndTheJobFinishesOnceItHasRoom) {
  test::TempDir dir;
  const fs::path cache = dir / "w1";
  test::TmpfsMount mount(cache, 4 << 20);
  if (!mount.mounted()) GTEST_SKIP() << "needs a tmpfs of its own: " << mount.problem();
  test::SchedulerProcess scheduler(dir / "data", {});
  ASSERT_FALSE(scheduler.address().empty()) << scheduler.process().output();
  const auto stub = test::scheduler_stub(scheduler.address());
  ASSERT_TRUE(test::upload_assets(*stub, test::cornell_assets()).ok());
  test::WorkerProcess worker({"--threads", "1", "--cache-dir", cache.string(), "--scheduler", scheduler.address()});
  ASSERT_FALSE(worker.address().empty()) << worker.process().output();
  ASSERT_TRUE(worker.process().wait_for_line("registered with the scheduler", 20s)) << worker.process().output();
  mount.fill(cache / "ballast", 0);

  v1::Job job;
  const grpc::Status submitted = test::submit(*stub, cornell("raster", 32, 32, 1, 16), job);
  ASSERT_TRUE(submitted.ok()) << submitted.error_message();
  ASSERT_TRUE(scheduler.process().wait_for_line("disk full in " + cache.string(), 60s))
      << scheduler.process().output();
  const auto meanwhile = test::get_job(*stub, job.job_id());
  ASSERT_TRUE(meanwhile);
  EXPECT_FALSE(is_final(meanwhile->state())) << meanwhile->failure_reason();
  EXPECT_EQ(meanwhile->tile_failures(), 0u);

  fs::remove(cache / "ballast");
  const auto done = test::wait_for_job(*stub, job.job_id(), [](const v1::Job& j) { return is_final(j.state()); }, 120s);
  ASSERT_TRUE(done) << scheduler.process().output();
  EXPECT_EQ(done->state(), v1::JOB_STATE_SUCCEEDED) << done->failure_reason();
  EXPECT_EQ(done->tile_failures(), 0u);
  EXPECT_LT(disk_full_lines(scheduler.process().output()), 20) << scheduler.process().output().substr(0, 4000);
}

}  // namespace
}  // namespace farm
