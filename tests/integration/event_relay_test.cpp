// WatchJob's events between the schedulers of one PostgreSQL store (event_relay.h): the payload's
// form, and two relays on a real server passing a job's events to each other's watchers, also
// after the server went away and came back.
#include <gtest/gtest.h>

#include <chrono>

#include "server/common/log.h"
#include "server/scheduler/events/event_relay.h"
#include "server/scheduler/store/job_store.h"
#include "tests/support/postgres_server.h"
#include "tests/support/store_locations.h"

namespace farm {
namespace {

using namespace std::chrono_literals;

v1::JobEvent tile_finished(const std::string& job_id, std::uint32_t tile) {
  v1::JobEvent event;
  event.mutable_job()->set_job_id(job_id);
  event.mutable_job()->set_name("a job whose name is not sent");
  event.mutable_tile_finished()->set_tile_index(tile);
  event.mutable_tile_finished()->set_tile_count(1);
  event.mutable_tile_finished()->set_worker("w1");
  return event;
}

TEST(EventRelayTest, AnEventTravelsAsItsJobIdAndWhatHappened) {
  const std::string payload = encode_relayed_event("0123abcd0123abcd", 42, tile_finished("job7", 3));
  EXPECT_TRUE(payload.starts_with("0123abcd0123abcd 2a ")) << payload;
  const std::optional<RelayedEvent> back = decode_relayed_event(payload);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->origin, "0123abcd0123abcd");
  EXPECT_EQ(back->event.job().job_id(), "job7");
  EXPECT_EQ(back->event.job().name(), "");  // the receiver reads the job from the store
  EXPECT_EQ(back->event.tile_finished().tile_index(), 3u);
  EXPECT_EQ(back->event.tile_finished().worker(), "w1");
}

TEST(EventRelayTest, APayloadThatIsNotAnEventIsRefused) {
  for (const std::string bad : {"", "origin", "origin 1", "origin 1 zz", "origin 1 abc", "origin 1 0a0b0c",
                                " 1 0a", "origin 1 " /* no job id */}) {
    EXPECT_FALSE(decode_relayed_event(bad)) << "'" << bad << "'";
  }
}

TEST(EventRelayTest, ALongFailureReasonIsCutToFitOneNotificationAsUtf8) {
  v1::JobEvent event;
  event.mutable_job()->set_job_id("job7");
  std::string reason;
  while (reason.size() < 20000) reason += "é";  // two bytes each: a cut may fall inside one
  event.mutable_tile_failed()->set_reason(reason);
  const std::string payload = encode_relayed_event("o", 1, event);
  EXPECT_LT(payload.size(), 8000u);  // PostgreSQL's limit on a payload
  const std::optional<RelayedEvent> back = decode_relayed_event(payload);
  ASSERT_TRUE(back);  // parsing checks the string is UTF-8
  EXPECT_TRUE(back->event.tile_failed().reason().ends_with("é..."));
  EXPECT_LT(back->event.tile_failed().reason().size(), 1100u);
}

// Two schedulers' halves on one database: a store, its events and a relay each.
struct Scheduler {
  explicit Scheduler(const std::string& url)
      : store(connect_store(url)), events(store),
        relay(url, events, *log, [this](const v1::JobEvent& e) { heard.push(e); }) {}
  std::shared_ptr<spdlog::logger> log = make_logger("relay-test", LogLevel::warn);
  JobStore store;
  JobEvents events;
  JobEventQueue heard;  // every event from the other, watched or not
  EventRelay relay;
};

TEST(EventRelayTest, OneSchedulersEventsReachTheOthersWatchersWithTheJobAsStored) {
  test::StoreLocation where(SqlDialect::PostgreSQL);
  ASSERT_TRUE(where.problem().empty()) << where.problem();
  Scheduler a(where.location()), b(where.location());
  a.store.jobs().add_job(test::one_row_job("job1", 2), 1);
  auto on_a = std::make_shared<JobEventQueue>();
  auto on_b = std::make_shared<JobEventQueue>();
  a.events.subscribe("job1", on_a);
  b.events.subscribe("job1", on_b);

  a.events.publish("job1", [](v1::JobEvent& e) { *e.mutable_tile_finished() = tile_finished("job1", 1).tile_finished(); });
  v1::JobEvent got;
  ASSERT_TRUE(on_b->pop(got, 10s));
  EXPECT_EQ(got.job().job_id(), "job1");
  EXPECT_EQ(got.job().name(), "job1");  // read from the store by b
  EXPECT_EQ(got.job().tiles_total(), 2u);
  EXPECT_EQ(got.tile_finished().tile_index(), 1u);
  ASSERT_TRUE(a.heard.pop(got, 0ms) == false);  // a does not hear its own
  ASSERT_TRUE(on_a->pop(got, 1s));              // its watcher has it once, from a itself
  EXPECT_FALSE(on_a->pop(got, 1s));

  // A state change goes as far as the store has it now.
  v1::Job cancelled = b.store.jobs().cancel_job("job1", 2);
  b.events.publish_state(cancelled, v1::JOB_STATE_QUEUED);
  ASSERT_TRUE(on_a->pop(got, 10s));
  ASSERT_TRUE(got.has_state_changed());
  EXPECT_EQ(got.state_changed().from(), v1::JOB_STATE_QUEUED);
  EXPECT_EQ(got.state_changed().to(), v1::JOB_STATE_CANCELLED);
  EXPECT_EQ(got.job().state(), v1::JOB_STATE_CANCELLED);
  ASSERT_TRUE(a.heard.pop(got, 1s));  // and a's own hook is told (its calls in flight stop)
  EXPECT_EQ(got.state_changed().to(), v1::JOB_STATE_CANCELLED);
}

// The server restarts: both relays connect again and listen again; events sent while it was away
// are lost (WatchJob polls for those), the ones after reach the other side.
TEST(EventRelayTest, RelaysCarryOnAfterTheServerWentAwayAndCameBack) {
  test::StoreLocation where(SqlDialect::PostgreSQL);
  ASSERT_TRUE(where.problem().empty()) << where.problem();
  Scheduler a(where.location()), b(where.location());
  a.store.jobs().add_job(test::one_row_job("job1", 2), 1);
  auto on_b = std::make_shared<JobEventQueue>();
  b.events.subscribe("job1", on_b);
  ASSERT_TRUE(where.server()->stop()) << where.server()->problem();
  ASSERT_TRUE(where.server()->start()) << where.server()->problem();

  v1::JobEvent got;
  bool arrived = false;
  for (std::uint32_t tile = 0; tile < 60 && !arrived; ++tile) {
    try {
      a.events.publish("job1", [&](v1::JobEvent& e) { *e.mutable_tile_finished() = tile_finished("job1", tile).tile_finished(); });
    } catch (const StoreUnavailable&) {
      // a's store finds its connection broken at its first statement, and makes it again at the next
    }
    arrived = on_b->pop(got, 1s);
  }
  ASSERT_TRUE(arrived) << where.server()->log();
  EXPECT_TRUE(got.has_tile_finished());
  EXPECT_EQ(got.job().name(), "job1");
}

}  // namespace
}  // namespace farm
