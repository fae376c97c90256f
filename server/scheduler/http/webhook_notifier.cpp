#include "server/scheduler/http/webhook_notifier.h"

#include <fmt/format.h>
#include <httplib.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <regex>

#include "renderer/util/input_error.h"
#include "server/common/job_state.h"
#include "server/common/proto_json.h"

namespace farm {

namespace {
constexpr auto kMaxBackoff = std::chrono::seconds(60);
}  // namespace

WebhookUrl parse_webhook_url(const std::string& url) {
  static const std::regex shape(R"((https?://[A-Za-z0-9.\-]+(?::[0-9]{1,5})?|https?://\[[0-9A-Fa-f:]+\](?::[0-9]{1,5})?)(/[^\s#]*)?)");
  std::smatch m;
  if (url.size() > 2048 || !std::regex_match(url, m, shape)) {
    throw InputError(fmt::format("--notify-url '{}': give http(s)://HOST[:PORT][/PATH]", url.substr(0, 200)));
  }
  return {m[1], m[2].length() > 0 ? std::string(m[2]) : std::string("/")};
}

WebhookNotifier::WebhookNotifier(const std::string& url, std::string scheduler_id, spdlog::logger& log,
                                 std::chrono::milliseconds first_backoff, std::chrono::seconds timeout)
    : url_(parse_webhook_url(url)),
      scheduler_id_(std::move(scheduler_id)),
      log_(log),
      first_backoff_(first_backoff),
      timeout_(timeout),
      thread_([this] { loop(); }) {}

WebhookNotifier::~WebhookNotifier() { stop(); }

void WebhookNotifier::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    if (posting_) posting_->stop();  // a receiver that hangs does not hold the scheduler's exit
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void WebhookNotifier::enqueue(const v1::JobEvent& event) {
  if (!event.has_state_changed() || !is_final(event.state_changed().to())) return;
  // Written now, as the job is at its end (the store's job, not this trimmed event's).
  const std::string body = nlohmann::json{{"event", "job." + to_string(event.state_changed().to())},
                                          {"scheduler", scheduler_id_},
                                          {"job", nlohmann::json::parse(json_of(event.job()))}}
                               .dump();
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    if (queue_.size() >= kMaxQueued) {
      queue_.pop_front();
      log_.warn("--notify-url: {} notifications wait already: the oldest is dropped", kMaxQueued);
    }
    queue_.push_back(body);
  }
  wake_.notify_all();
}

bool WebhookNotifier::post(const std::string& body, std::string& problem) {
  httplib::Client client(url_.origin);
  const auto seconds = static_cast<time_t>(timeout_.count());
  client.set_connection_timeout(seconds, 0);
  client.set_read_timeout(seconds, 0);
  client.set_write_timeout(seconds, 0);
  {
    std::lock_guard lock(mutex_);
    if (stopping_) {
      problem = "stopping";
      return false;
    }
    posting_ = &client;
  }
  const httplib::Result r = client.Post(url_.path, body, "application/json");
  {
    std::lock_guard lock(mutex_);
    posting_ = nullptr;
  }
  if (!r) {
    problem = httplib::to_string(r.error());
    return false;
  }
  if (r->status < 200 || r->status > 299) {
    problem = fmt::format("HTTP {}", r->status);
    return false;
  }
  return true;
}

void WebhookNotifier::loop() {
  std::unique_lock lock(mutex_);
  while (true) {
    wake_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
    if (stopping_) {
      if (!queue_.empty()) log_.warn("--notify-url: stopping with {} notification(s) not delivered", queue_.size());
      return;
    }
    const std::string body = queue_.front();
    queue_.pop_front();
    std::chrono::milliseconds backoff = first_backoff_;
    for (int attempt = 1;; ++attempt) {
      lock.unlock();
      std::string problem;
      const bool delivered = post(body, problem);
      lock.lock();
      if (delivered) break;
      if (attempt == kMaxAttempts) {
        log_.error("--notify-url {}: gave up after {} attempts: {}", url_.shown(), attempt, problem);
        break;
      }
      log_.warn("--notify-url {}: attempt {} failed ({}); again in {} ms", url_.shown(), attempt, problem,
                backoff.count());
      if (wake_.wait_for(lock, backoff, [&] { return stopping_; })) {
        log_.warn("--notify-url: stopping with a notification not delivered");
        return;
      }
      backoff = std::min<std::chrono::milliseconds>(backoff * 2, kMaxBackoff);
    }
  }
}

}  // namespace farm
