#pragma once
// `farm scheduler --notify-url URL`: when a job ends (succeeded, failed or cancelled) the scheduler
// POSTs a JSON event to URL (a CI's or a chat's webhook):
//   {"event": "job.succeeded" | "job.failed" | "job.cancelled", "scheduler": ID, "job": <farm.v1.Job>}
// from a thread of its own, so that a slow or dead receiver never holds dispatch: the job's end is
// queued (bounded: the oldest goes when kMaxQueued wait) and posted with retries, 1 s doubling to
// 60 s between them, kMaxAttempts in all, while a 2xx has not answered. Only the ends this
// scheduler saw happen are posted (not those relayed from others of a shared store), so each end
// is posted once. http:// and https:// (OpenSSL, the system's CAs).
//
// Lock: WebhookNotifier::mutex_ guards the queue, stopping_ and posting_: JobEvents calls
// enqueue() under its own lock, and nothing of ours is taken under this one (stop() cuts the POST
// under way off under it: httplib's own socket lock, a leaf).
#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <string>
#include <thread>

#include <spdlog/logger.h>

#include "proto/farm.pb.h"

namespace httplib {
class Client;
}

namespace farm {

// A webhook's address, split as an HTTP client takes it. InputError for anything but
// http(s)://HOST[:PORT][/PATH].
struct WebhookUrl {
  std::string origin;  // "https://ci.example:8443"
  std::string path;    // "/hooks/farm" ("/" when none)
  // What logs and messages show: the origin only, as a chat's webhook keeps its secret in the path.
  std::string shown() const { return path == "/" ? origin : origin + "/..."; }
};
WebhookUrl parse_webhook_url(const std::string& url);

class WebhookNotifier {
 public:
  static constexpr std::size_t kMaxQueued = 1000;
  static constexpr int kMaxAttempts = 8;

  // `timeout` bounds connecting, and each read and write of a POST.
  WebhookNotifier(const std::string& url, std::string scheduler_id, spdlog::logger& log,
                  std::chrono::milliseconds first_backoff = std::chrono::seconds(1),
                  std::chrono::seconds timeout = std::chrono::seconds(10));
  ~WebhookNotifier();  // stop()
  WebhookNotifier(const WebhookNotifier&) = delete;
  WebhookNotifier& operator=(const WebhookNotifier&) = delete;

  // Called with every event this scheduler publishes; queues the job's end, if it is one. Never
  // blocks.
  void enqueue(const v1::JobEvent& event);
  // Stops posting: a POST under way is cut off, and what is not yet delivered is dropped (and
  // logged). Idempotent.
  void stop();

 private:
  void loop();
  // One POST; true on a 2xx. `problem` says what went wrong otherwise.
  bool post(const std::string& body, std::string& problem);

  const WebhookUrl url_;
  const std::string scheduler_id_;
  spdlog::logger& log_;
  const std::chrono::milliseconds first_backoff_;
  const std::chrono::seconds timeout_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::string> queue_;  // bodies to post, oldest first
  bool stopping_ = false;
  httplib::Client* posting_ = nullptr;  // the POST under way, which stop() cuts off
  std::thread thread_;
};

}  // namespace farm
