// The dashboard in a real browser (issue #19): a farm of a scheduler with --http and tokens and two
// workers that register with it, one job rendering for a while, one to cancel and a paused
// animation, and tests/browser/dashboard_check.py driving Debian's chromium through Selenium over
// them. The job page's screenshot, taken while the job renders, is kept at build/test-artifacts/.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "server/common/sha256.h"
#include "tests/support/background_process.h"
#include "tests/support/job_specs.h"
#include "tests/support/run_command.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

const std::string kAdmin = "browser-admin-token-0123456789";
const std::string kWorker = "browser-worker-token-012345678";

TEST(DashboardBrowserTest, JobsJobAndWorkersPagesShowTheFarmLiveAndTheCancelButtonCancels) {
  if (!fs::exists("/usr/bin/chromium") || !fs::exists("/usr/bin/chromedriver")) {
    GTEST_SKIP() << "chromium and chromium-driver are not installed (deploy/install-deps.sh installs them)";
  }
  test::TempDir dir;
  const fs::path tokens =
      dir.write("tokens.txt", fmt::format("{} browser admin\n{} render worker\n", sha256_hex(kAdmin), sha256_hex(kWorker)));
  const fs::path worker_token = dir.write("worker-token.txt", kWorker + "\n");
  test::SchedulerProcess scheduler(dir / "data", {"--tokens", tokens.string(), "--http", "127.0.0.1:0", "--batch-ms", "0"});
  ASSERT_FALSE(scheduler.address().empty()) << scheduler.process().output();
  const std::string url = scheduler.dashboard_url();
  ASSERT_FALSE(url.empty()) << scheduler.process().output();
  std::vector<std::unique_ptr<test::WorkerProcess>> workers;
  for (const char* name : {"w1", "w2"}) {
    workers.push_back(std::make_unique<test::WorkerProcess>(std::vector<std::string>{
        "--threads", "1", "--cache-dir", (dir / name).string(), "--scheduler", scheduler.address(), "--token-file",
        worker_token.string()}));
    ASSERT_FALSE(workers.back()->address().empty());
  }

  auto stub = test::scheduler_stub(scheduler.address(), ClientIdentity{kAdmin, false, {}});
  ASSERT_TRUE(test::upload_assets(*stub, test::cornell_assets()).ok());
  // The job to watch: path traced in 16 px units on two one-thread workers, for tens of seconds;
  // the other waits behind it (lower priority) for the cancel button.
  const auto submit = [&](const std::string& name, int size, int spp, int priority, int frames = 0) {
    nlohmann::json job = nlohmann::json::parse(test::cornell_job_json("path", size, size, spp));
    job["name"] = name;
    job["render"]["tile_size"] = 16;
    if (frames > 0) {
      job["frames"] = {{"start", 1}, {"end", frames}};
      job["output"] = {{"image", "out/anim.####.exr"}, {"preview", "out/anim.####.png"}};
    }
    v1::Job submitted;
    EXPECT_TRUE(test::submit(*stub, test::make_job_spec(job.dump(), test::cornell_assets(), "cornell.json"),
                             submitted, priority)
                    .ok());
    return submitted.job_id();
  };
  const auto pause = [&](const std::string& job_id) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    v1::PauseJobRequest request;
    request.set_job_id(job_id);
    request.set_paused(true);
    v1::PauseJobResponse paused;
    return stub->PauseJob(&context, request, &paused).ok();
  };
  const std::string rendering = submit("watched", 256, 512, 1);
  // Paused, so that it is still active whenever the browser gets to its cancel button: a queued
  // job this small could otherwise be rendered by a worker the watched job leaves idle, and a
  // finished job's button is disabled.
  const std::string waiting = submit("to-cancel", 64, 4, 0);
  ASSERT_TRUE(pause(waiting));
  // An animation, paused until the browser resumes it, then first in the queue: its job page is
  // opened while its frames are being merged, and must show every frame's thumbnail in the end.
  const std::string animation = submit("animation", 32, 8, 2, 48);
  ASSERT_TRUE(pause(animation));

  const fs::path artifacts = fs::path(FARM_SOURCE_DIR) / "build" / "test-artifacts";
  fs::create_directories(artifacts);
  const fs::path screenshot = artifacts / "dashboard-job-page.png";
  const test::CommandResult r = test::run_command(fmt::format(
      "/usr/bin/python3 {} --url {} --token {} --job {} --cancel {} --animation {} --workers 2 --screenshot {}",
      test::shell_quote((fs::path(FARM_SOURCE_DIR) / "tests/browser/dashboard_check.py").string()), url, kAdmin,
      rendering, waiting, animation, test::shell_quote(screenshot.string())));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string json_line = r.output.substr(r.output.rfind('{'));
  const nlohmann::json seen = nlohmann::json::parse(json_line);
  EXPECT_TRUE(seen["ok"].get<bool>()) << r.output;
  EXPECT_TRUE(seen["image_changed"].get<bool>()) << r.output;
  EXPECT_EQ(seen["workers_up"], 2) << r.output;
  EXPECT_EQ(seen["animation_thumbnails"], 48) << r.output;
  EXPECT_LT(seen["progress"][0].get<int>(), seen["progress"][1].get<int>()) << r.output;
  EXPECT_GT(fs::file_size(screenshot), 1000u);
  // What the browser did, the scheduler did.
  EXPECT_EQ(test::get_job(*stub, waiting)->state(), v1::JOB_STATE_CANCELLED);
  EXPECT_EQ(test::get_job(*stub, animation)->state(), v1::JOB_STATE_SUCCEEDED);
  std::cout << "dashboard screenshot: " << screenshot.string() << "\n" << json_line << "\n";
}

}  // namespace
}  // namespace farm
