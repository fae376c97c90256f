#include "server/scheduler/events/event_relay.h"

#include <fmt/format.h>

#include <random>
#include <vector>

#include "renderer/util/utf8_text.h"
#include "server/common/hex.h"

namespace farm {

namespace {

// A payload holds at most 8000 bytes (PostgreSQL's limit): the event's text is cut to fit.
constexpr std::size_t kMaxReasonBytes = 1000;
constexpr std::size_t kMaxPayloadBytes = 7900;
// Events sent in one statement, at most.
constexpr std::size_t kMaxBatch = 256;

std::string new_origin() {
  std::random_device random;
  return fmt::format("{:08x}{:08x}", random(), random());
}

}  // namespace

std::string encode_relayed_event(const std::string& origin, std::uint64_t seq, const v1::JobEvent& event) {
  v1::JobEvent slim = event;
  const std::string id = event.job().job_id();
  slim.clear_job();
  slim.mutable_job()->set_job_id(id);
  if (slim.has_tile_failed() && slim.tile_failed().reason().size() > kMaxReasonBytes) {
    // Cut on a UTF-8 boundary: the receiver's watchers get a string proto accepts.
    slim.mutable_tile_failed()->set_reason(utf8_prefix(slim.tile_failed().reason(), kMaxReasonBytes) + "...");
  }
  return fmt::format("{} {:x} {}", origin, seq, to_hex(slim.SerializeAsString()));
}

std::optional<RelayedEvent> decode_relayed_event(const std::string& payload) {
  const std::size_t first = payload.find(' ');
  const std::size_t second = first == std::string::npos ? first : payload.find(' ', first + 1);
  if (second == std::string::npos || first == 0) return std::nullopt;
  const std::optional<std::string> bytes = from_hex(std::string_view(payload).substr(second + 1));
  RelayedEvent out;
  out.origin = payload.substr(0, first);
  if (!bytes || !out.event.ParseFromString(*bytes) || out.event.job().job_id().empty()) return std::nullopt;
  return out;
}

EventRelay::EventRelay(const std::string& url, JobEvents& events, spdlog::logger& log,
                       std::function<void(const v1::JobEvent&)> on_remote)
    : events_(events), log_(log), on_remote_(std::move(on_remote)), origin_(new_origin()),
      sender_(std::make_unique<PostgresConnection>(url)), listener_(std::make_unique<PostgresConnection>(url)) {
  // Listening before anything is forwarded: what the others send from now on is heard.
  listener_->listen(kChannel);
  events_.relay_to([this](const v1::JobEvent& event) { forward(event); });
  send_thread_ = std::thread([this] { send_loop(); });
  listen_thread_ = std::thread([this] { listen_loop(); });
}

EventRelay::~EventRelay() { stop(); }

void EventRelay::stop() {
  events_.relay_to(nullptr);
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    stopping_ = true;
  }
  wake_.notify_all();
  if (send_thread_.joinable()) send_thread_.join();
  if (listen_thread_.joinable()) listen_thread_.join();
}

bool EventRelay::sleep(std::chrono::milliseconds d) {
  std::unique_lock lock(mutex_);
  return !wake_.wait_for(lock, d, [this] { return stopping_; });
}

void EventRelay::forward(const v1::JobEvent& event) {
  {
    std::lock_guard lock(mutex_);
    std::string payload = encode_relayed_event(origin_, next_seq_++, event);
    if (payload.size() > kMaxPayloadBytes) return;  // cannot happen with the reason cut; never sent broken
    if (queued_.size() >= kMaxQueued) {
      queued_.pop_front();
      ++dropped_;
    }
    queued_.push_back(std::move(payload));
  }
  wake_.notify_all();
}

void EventRelay::send_loop() {
  while (true) {
    std::vector<std::string> batch;
    std::size_t dropped = 0;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return stopping_ || !queued_.empty(); });
      if (stopping_) return;
      while (!queued_.empty() && batch.size() < kMaxBatch) {
        batch.push_back(std::move(queued_.front()));
        queued_.pop_front();
      }
      dropped = std::exchange(dropped_, 0);
    }
    if (dropped > 0) log_.warn("event relay: {} job events dropped (the store was away); watchers elsewhere poll", dropped);
    // Nothing may end this thread: a failure loses these events (the watchers elsewhere read the
    // store themselves) and the next batch tries again, a second later.
    try {
      sender_->notify(kChannel, batch);
      continue;
    } catch (const StoreUnavailable& e) {
      log_.debug("event relay: {} job events not sent: {}", batch.size(), e.what());
    } catch (const std::exception& e) {
      log_.error("event relay: {} job events not sent: {}", batch.size(), e.what());
    }
    if (!sleep(std::chrono::seconds(1))) return;
  }
}

void EventRelay::listen_loop() {
  std::uint64_t generation = listener_->generation();
  while (true) {
    {
      std::lock_guard lock(mutex_);
      if (stopping_) return;
    }
    std::vector<std::string> payloads;
    try {
      // A connection made again listens again; what was sent while it was down is lost.
      if (listener_->generation() != generation) {
        listener_->listen(kChannel);
        generation = listener_->generation();
        log_.info("event relay: listening again for the other schedulers' job events");
      }
      payloads = listener_->notifications(std::chrono::milliseconds(250));
    } catch (const StoreUnavailable& e) {
      log_.debug("event relay: {}", e.what());
      if (!sleep(std::chrono::seconds(1))) return;
      continue;
    } catch (const std::exception& e) {
      log_.error("event relay: {}", e.what());
      if (!sleep(std::chrono::seconds(1))) return;
      continue;
    }
    for (const std::string& payload : payloads) {
      std::optional<RelayedEvent> relayed = decode_relayed_event(payload);
      if (!relayed) {
        log_.warn("event relay: ignored a notification that is not a job event ({} bytes)", payload.size());
        continue;
      }
      if (relayed->origin == origin_) continue;
      try {
        if (on_remote_) on_remote_(relayed->event);
        events_.publish_relayed(std::move(relayed->event));
      } catch (const std::exception& e) {
        // The store away under the read: this event is lost to the watchers here, who poll.
        log_.debug("event relay: an event from another scheduler not passed on: {}", e.what());
      }
    }
  }
}

}  // namespace farm
