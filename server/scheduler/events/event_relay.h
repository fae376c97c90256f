#pragma once
// WatchJob's events between the schedulers of one shared store (PostgreSQL LISTEN/NOTIFY): what
// one scheduler publishes for a job (a unit rendered or failed, a frame merged, a state changed)
// reaches the watchers of that job on every other scheduler, so a client may watch a job on any
// of them, whichever renders it. Each event is sent with the job's id only; a receiving
// scheduler that has watchers of the job reads the job from the store as it is then, so the
// events it passes on keep the store's order.
//
// Sending never waits on PostgreSQL: events are queued (at most kMaxQueued; the oldest dropped
// beyond) and sent by the relay's thread, many in one statement, on a connection of its own. An
// event that cannot be sent (the store away) is dropped, and a notification missed while the
// listening connection was down is lost: WatchJob looks at the job in the store itself after a
// few quiet seconds (scheduler_service.cpp), so a watcher always sees the job end.
//
// Locks: mutex_ guards the queue and is a leaf. The listening thread calls JobEvents (which reads
// the store) and `on_remote` with no lock of its own held.
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <spdlog/logger.h>

#include "proto/farm.pb.h"
#include "server/scheduler/events/job_events.h"
#include "server/scheduler/store/postgres_connection.h"

namespace farm {

// An event as one notification's payload: "ORIGIN SEQ HEX", the sending relay's random origin (so
// that it skips its own), a sequence number (PostgreSQL folds identical payloads of one
// transaction into one) and the event, the job reduced to its id, in hex. nullopt for a payload
// that is not one (a relay of another version, garbage): nothing from the channel is trusted.
struct RelayedEvent {
  std::string origin;
  v1::JobEvent event;
};
std::string encode_relayed_event(const std::string& origin, std::uint64_t seq, const v1::JobEvent& event);
std::optional<RelayedEvent> decode_relayed_event(const std::string& payload);

class EventRelay {
 public:
  static constexpr std::size_t kMaxQueued = 10000;
  static constexpr const char* kChannel = "farm_job_events";

  // Connects twice to the PostgreSQL store at `url` (StoreUnavailable when it cannot), forwards
  // what `events` publishes and publishes what the others send; `on_remote` is given each event
  // from another scheduler (a job cancelled there stops its units here).
  EventRelay(const std::string& url, JobEvents& events, spdlog::logger& log,
             std::function<void(const v1::JobEvent&)> on_remote);
  ~EventRelay();  // stop()
  EventRelay(const EventRelay&) = delete;
  EventRelay& operator=(const EventRelay&) = delete;

  // Stops both threads; events still queued are not sent. Idempotent.
  void stop();

 private:
  void forward(const v1::JobEvent& event);  // JobEvents' relay: queued for send_loop
  void send_loop();
  void listen_loop();
  bool sleep(std::chrono::milliseconds d);  // false when stopping

  JobEvents& events_;
  spdlog::logger& log_;
  std::function<void(const v1::JobEvent&)> on_remote_;
  const std::string origin_;
  std::unique_ptr<PostgresConnection> sender_, listener_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::string> queued_;  // payloads, under mutex_
  std::uint64_t next_seq_ = 0;      // under mutex_
  std::size_t dropped_ = 0;         // under mutex_: since the last warning
  bool stopping_ = false;
  std::thread send_thread_, listen_thread_;  // last: started once the rest is built
};

}  // namespace farm
