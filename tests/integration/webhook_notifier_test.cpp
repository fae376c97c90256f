// `farm scheduler --notify-url` (issue #19): a job's end is posted as JSON to a webhook, retried
// with backoff while the receiver fails, and a receiver that hangs holds nothing up. The receiver
// here is a real HTTP server (cpp-httplib) in the test process.
#include "server/scheduler/http/webhook_notifier.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <httplib.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <future>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>
#include <vector>

#include "renderer/util/input_error.h"
#include "server/common/log.h"
#include "tests/support/background_process.h"
#include "tests/support/job_specs.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

using namespace std::chrono_literals;
using json = nlohmann::json;

constexpr auto kWait = 120s;

// An HTTP server on a free port of 127.0.0.1 that records the bodies POSTed to /hook and answers
// 500 to the first `failures` of them. One made `held` answers nothing until release().
class Receiver {
 public:
  explicit Receiver(int failures, std::chrono::milliseconds hang = {}, bool held = false)
      : failures_(failures), hang_(hang), held_(held) {
    server_.Post("/hook", [this](const httplib::Request& request, httplib::Response& response) {
      if (hang_.count() > 0) std::this_thread::sleep_for(hang_);
      std::unique_lock lock(mutex_);
      ++arrived_;
      received_.notify_all();
      received_.wait(lock, [&] { return !held_; });
      ++requests_;
      if (requests_ <= failures_) {
        response.status = 500;
        return;
      }
      bodies_.push_back(json::parse(request.body));
      received_.notify_all();
    });
    port_ = server_.bind_to_any_port("127.0.0.1");
    thread_ = std::thread([this] { server_.listen_after_bind(); });
  }
  ~Receiver() {
    release();
    server_.stop();
    thread_.join();
  }
  std::string url() const { return fmt::format("http://127.0.0.1:{}/hook", port_); }
  // The bodies accepted once `n` are (bounded wait).
  std::vector<json> wait_for(std::size_t n) {
    std::unique_lock lock(mutex_);
    received_.wait_for(lock, kWait, [&] { return bodies_.size() >= n; });
    return bodies_;
  }
  int requests() {
    std::lock_guard lock(mutex_);
    return requests_;
  }
  // True once a POST has arrived (bounded wait), answered or held.
  bool wait_arrived() {
    std::unique_lock lock(mutex_);
    return received_.wait_for(lock, kWait, [&] { return arrived_ > 0; });
  }
  void release() {
    std::lock_guard lock(mutex_);
    held_ = false;
    received_.notify_all();
  }

 private:
  const int failures_;
  const std::chrono::milliseconds hang_;
  bool held_;
  int arrived_ = 0;
  httplib::Server server_;
  int port_ = 0;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable received_;
  int requests_ = 0;
  std::vector<json> bodies_;
};

v1::JobEvent job_ended(const std::string& id, v1::JobState to) {
  v1::JobEvent e;
  e.mutable_job()->set_job_id(id);
  e.mutable_job()->set_state(to);
  e.mutable_state_changed()->set_from(v1::JOB_STATE_RUNNING);
  e.mutable_state_changed()->set_to(to);
  return e;
}

TEST(WebhookNotifierTest, AJobsEndIsPostedInOrderAndRetriedUntilTheReceiverTakesIt) {
  Receiver receiver(2);  // two failures first
  auto log = make_logger("webhook-test", LogLevel::off);
  WebhookNotifier notifier(receiver.url(), "sched-1", *log, 20ms);
  v1::JobEvent progress = job_ended("a", v1::JOB_STATE_RUNNING);
  progress.mutable_state_changed()->set_from(v1::JOB_STATE_QUEUED);
  notifier.enqueue(progress);  // not an end: not posted
  notifier.enqueue(job_ended("a", v1::JOB_STATE_SUCCEEDED));
  notifier.enqueue(job_ended("b", v1::JOB_STATE_FAILED));
  const std::vector<json> bodies = receiver.wait_for(2);
  ASSERT_EQ(bodies.size(), 2u);
  EXPECT_EQ(receiver.requests(), 4);  // two refused, then one each
  EXPECT_EQ(bodies[0]["event"], "job.succeeded");
  EXPECT_EQ(bodies[0]["job"]["job_id"], "a");
  EXPECT_EQ(bodies[0]["job"]["state"], "JOB_STATE_SUCCEEDED");
  EXPECT_EQ(bodies[0]["scheduler"], "sched-1");
  EXPECT_EQ(bodies[1]["event"], "job.failed");
  EXPECT_EQ(bodies[1]["job"]["job_id"], "b");
}

TEST(WebhookNotifierTest, AReceiverThatHangsHoldsNothingUpAndTheQueueIsBounded) {
  Receiver receiver(0, 2s);  // answers nothing for two seconds a request
  auto log = make_logger("webhook-test", LogLevel::off);
  WebhookNotifier notifier(receiver.url(), "sched-1", *log, 20ms);
  // Each enqueue returns while the first POST hangs: three thousand of them (a blocking one
  // would hold this test, and the scheduler's events with it, until the test's timeout).
  for (int i = 0; i < 3000; ++i) notifier.enqueue(job_ended(fmt::format("j{}", i), v1::JOB_STATE_SUCCEEDED));
  notifier.stop();  // what waits is dropped, not posted for ever
  EXPECT_LE(receiver.requests(), 1);
}

TEST(WebhookNotifierTest, StopCutsOffAPostTheReceiverHolds) {
  Receiver receiver(0, {}, true);
  auto log = make_logger("webhook-test", LogLevel::off);
  // Timeouts far beyond the test's wait: only cutting the POST off lets stop() return in time.
  WebhookNotifier notifier(receiver.url(), "sched-1", *log, 20ms, std::chrono::hours(1));
  notifier.enqueue(job_ended("a", v1::JOB_STATE_SUCCEEDED));
  ASSERT_TRUE(receiver.wait_arrived());
  auto stopped = std::async(std::launch::async, [&] { notifier.stop(); });
  const bool in_time = stopped.wait_for(kWait) == std::future_status::ready;
  receiver.release();  // lets a stop() that failed to cut it off end too, so the test ends
  EXPECT_TRUE(in_time) << "stop() waited for the held POST";
}

TEST(WebhookNotifierTest, OnlyHttpUrlsWithAHostAreTaken) {
  EXPECT_EQ(parse_webhook_url("https://ci.example:8443/hooks/farm").origin, "https://ci.example:8443");
  EXPECT_EQ(parse_webhook_url("https://ci.example:8443/hooks/farm").path, "/hooks/farm");
  EXPECT_EQ(parse_webhook_url("http://127.0.0.1").path, "/");
  EXPECT_EQ(parse_webhook_url("https://chat.example/hooks/T0/SECRET").shown(), "https://chat.example/...");
  EXPECT_EQ(parse_webhook_url("http://127.0.0.1:9").shown(), "http://127.0.0.1:9");
  for (const char* bad : {"ftp://x/y", "http://", "file:///etc/passwd", "http://a b/", "ci.example/hook"}) {
    EXPECT_THROW(parse_webhook_url(bad), InputError) << bad;
  }
}

TEST(WebhookNotifierTest, ASchedulerPostsTheEndsOfItsJobs) {
  Receiver receiver(1);
  test::TempDir dir;
  test::WorkerProcess worker({"--threads", "1", "--cache-dir", (dir / "w1").string()});
  ASSERT_FALSE(worker.address().empty());
  test::SchedulerProcess scheduler(dir / "data", {"--worker", worker.address(), "--notify-url", receiver.url()});
  ASSERT_FALSE(scheduler.address().empty()) << scheduler.process().output();
  auto stub = test::scheduler_stub(scheduler.address());
  ASSERT_TRUE(test::upload_assets(*stub, test::cornell_assets()).ok());
  v1::Job job;
  ASSERT_TRUE(test::submit(*stub, test::cornell_job_spec("raster", 32, 32, 1), job).ok());
  const std::vector<json> bodies = receiver.wait_for(1);
  ASSERT_EQ(bodies.size(), 1u) << scheduler.process().output();
  EXPECT_EQ(bodies[0]["event"], "job.succeeded");
  EXPECT_EQ(bodies[0]["job"]["job_id"], job.job_id());
  EXPECT_EQ(bodies[0]["job"]["tiles_done"], bodies[0]["job"]["tiles_total"]);
}

}  // namespace
}  // namespace farm
