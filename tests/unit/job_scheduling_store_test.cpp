// Scheduling in the job store (issue #36), on SQLite and on PostgreSQL: dependencies (a chain, any
// end, cycles and unknown ids refused, frame by frame), per-job caps, and fair share between owners.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "server/scheduler/store/job_store.h"
#include "tests/support/store_locations.h"

namespace farm {
namespace {

class JobSchedulingStoreTest : public test::StoreTest {};

// A job of `tiles` 16 px tiles in one row, of frames `frames` (a still: frame 0).
NewJob job_of(const std::string& id, int tiles = 1, std::vector<int> frames = {0}) {
  NewJob j = test::one_row_job(id, tiles);
  j.frames = std::move(frames);
  return j;
}

// Claims the next batch for `worker` and marks it done; its job id, or "" when nothing is queued.
std::string claim_and_finish(JobStore& store, const std::string& worker = "w") {
  const std::optional<UnitBatch> b = store.units().claim_next_batch(worker, 10);
  if (!b) return "";
  EXPECT_TRUE(store.units().batch_done(b->job_id, b->first, b->count, {}, worker));
  return b->job_id;
}

// A job whose units are all done, merged and ended SUCCEEDED (as the finisher does).
void succeed(JobStore& store, const std::string& id) {
  for (int frame : store.frames().complete_frames(id)) ASSERT_TRUE(store.frames().frame_merged(id, frame));
  ASSERT_EQ(store.jobs().finish_job(id, v1::JOB_STATE_SUCCEEDED, "", "", 20).state(), v1::JOB_STATE_SUCCEEDED);
}

v1::JobState state_of(const JobStore& store, const std::string& id) { return store.jobs().get_job(id)->state(); }

// The chain: c waits for b, which waits for a. Nothing of b or c is handed out while
// they wait; a's success queues b; b's failure fails c, naming b (and b's own reason).
TEST_P(JobSchedulingStoreTest, AChainWaitsInTurnAndTheMiddlesFailureFailsTheLastNamingIt) {
  JobStore store(connect());
  store.jobs().add_job(job_of("a"), 1);
  NewJob b = job_of("b");
  b.after = {"a"};
  NewJob c = job_of("c");
  c.after = {"b"};
  EXPECT_EQ(store.jobs().add_job(b, 2).state(), v1::JOB_STATE_WAITING);
  EXPECT_EQ(store.jobs().add_job(c, 3).state(), v1::JOB_STATE_WAITING);
  EXPECT_TRUE(store.dependencies().release_waiting(4).empty()) << "a has not ended";
  EXPECT_EQ(claim_and_finish(store), "a");
  EXPECT_EQ(claim_and_finish(store), "") << "b and c wait: nothing of theirs is handed out";
  succeed(store, "a");

  std::vector<ReleasedJob> settled = store.dependencies().release_waiting(30);
  ASSERT_EQ(settled.size(), 1u);
  EXPECT_EQ(settled[0].job.job_id(), "b");
  EXPECT_EQ(settled[0].from, v1::JOB_STATE_WAITING);
  EXPECT_EQ(settled[0].job.state(), v1::JOB_STATE_QUEUED);
  EXPECT_TRUE(store.dependencies().release_waiting(31).empty()) << "settled once";
  EXPECT_EQ(state_of(store, "c"), v1::JOB_STATE_WAITING);

  const std::optional<UnitBatch> unit = store.units().claim_next_batch("w", 40);
  ASSERT_TRUE(unit);
  ASSERT_EQ(unit->job_id, "b");
  ASSERT_FALSE(store.units().batch_failed("b", unit->first, 1, "the worker ran out of memory", 1, 41, "w").will_retry);
  settled = store.dependencies().release_waiting(50);
  ASSERT_EQ(settled.size(), 1u);
  const v1::Job& failed = settled[0].job;
  EXPECT_EQ(failed.job_id(), "c");
  EXPECT_EQ(failed.state(), v1::JOB_STATE_FAILED);
  EXPECT_NE(failed.failure_reason().find("dependency b failed: unit 0 failed 1 time; last error: the worker ran out"),
            std::string::npos)
      << failed.failure_reason();

  v1::Job described = *store.jobs().get_job("b");
  store.dependencies().describe(described);
  EXPECT_EQ(std::vector<std::string>(described.after().begin(), described.after().end()), std::vector<std::string>{"a"});
  EXPECT_EQ(std::vector<std::string>(described.dependents().begin(), described.dependents().end()),
            std::vector<std::string>{"c"});
}

// after_any: a cancelled job releases its waiter; a failure runs down a whole chain in one call;
// a dependency deleted before the release fails its waiter, naming it.
TEST_P(JobSchedulingStoreTest, AfterAnyRunsWhateverTheEndAndAFailureRunsDownAChainInOneRelease) {
  JobStore store(connect());
  store.jobs().add_job(job_of("a"), 1);
  NewJob any = job_of("any");
  any.after_any = {"a"};
  NewJob b = job_of("b");
  b.after = {"a"};
  NewJob c = job_of("c");
  c.after = {"b"};
  store.jobs().add_job(any, 2);
  store.jobs().add_job(b, 3);
  store.jobs().add_job(c, 4);
  store.jobs().cancel_job("a", 5);
  const std::vector<ReleasedJob> settled = store.dependencies().release_waiting(6);
  std::map<std::string, v1::Job> by_id;
  for (const ReleasedJob& r : settled) by_id[r.job.job_id()] = r.job;
  ASSERT_EQ(by_id.size(), 3u);
  EXPECT_EQ(by_id["any"].state(), v1::JOB_STATE_QUEUED);
  EXPECT_EQ(by_id["b"].state(), v1::JOB_STATE_FAILED);
  EXPECT_EQ(by_id["b"].failure_reason(), "dependency a was cancelled");
  EXPECT_EQ(by_id["c"].failure_reason(), "dependency b failed: dependency a was cancelled");

  NewJob d = job_of("d");
  d.after = {"any"};
  store.jobs().add_job(d, 7);
  EXPECT_EQ(claim_and_finish(store), "any");
  succeed(store, "any");
  ASSERT_EQ(store.jobs().delete_job("any"), true);
  const std::vector<ReleasedJob> gone = store.dependencies().release_waiting(8);
  ASSERT_EQ(gone.size(), 1u);
  EXPECT_EQ(gone[0].job.failure_reason(), "dependency any is no longer in the store");
}

TEST_P(JobSchedulingStoreTest, UnknownIdsAndCyclesAreRefusedAndAStartedJobTakesNoMoreDependencies) {
  JobStore store(connect());
  NewJob orphan = job_of("orphan");
  orphan.after = {"nope"};
  try {
    store.jobs().add_job(orphan, 1);
    ADD_FAILURE() << "a dependency on no job was accepted";
  } catch (const DependencyError& e) {
    EXPECT_EQ(e.kind, DependencyError::Kind::UnknownJob);
    EXPECT_STREQ(e.what(), "no job 'nope' to wait for");
  }
  EXPECT_FALSE(store.jobs().get_job("orphan")) << "nothing of it is kept";

  store.jobs().add_job(job_of("a"), 2);
  NewJob b = job_of("b");
  b.after = {"a"};
  store.jobs().add_job(b, 3);
  NewJob c = job_of("c");
  c.after_frames = "b";
  store.jobs().add_job(c, 4);
  // a -> b -> c would close a cycle: c waits (frame by frame) for b, which waits for a.
  const auto refusal = [&](const std::string& job, const std::vector<std::string>& after) {
    try {
      store.dependencies().add(job, after, {});
    } catch (const DependencyError& e) {
      return std::pair{e.kind, std::string(e.what())};
    }
    return std::pair{DependencyError::Kind::UnknownJob, std::string("accepted")};
  };
  auto [kind, why] = refusal("a", {"c"});
  EXPECT_EQ(kind, DependencyError::Kind::Cycle);
  EXPECT_EQ(why, "job a cannot wait for c: that would be a cycle (c, which waits for b, which waits for a, which would wait for c)");
  EXPECT_EQ(refusal("a", {"a"}).second, "job a cannot wait for itself");
  EXPECT_EQ(refusal("a", {"zzz"}).second, "no job 'zzz' to wait for");
  EXPECT_EQ(state_of(store, "a"), v1::JOB_STATE_QUEUED) << "a refusal changes nothing";

  // A job not started may be given more; one with a unit handed out may not.
  store.jobs().add_job(job_of("d"), 5);
  const std::optional<v1::Job> d = store.dependencies().add("d", {"b"}, {"a"});
  ASSERT_TRUE(d);
  EXPECT_EQ(d->state(), v1::JOB_STATE_WAITING);
  ASSERT_EQ(store.units().claim_next_batch("w", 6)->job_id, "a");
  const auto [started, message] = refusal("a", {"d"});
  EXPECT_EQ(started, DependencyError::Kind::Started);
  EXPECT_NE(message.find("job a is running"), std::string::npos) << message;
  EXPECT_FALSE(store.dependencies().add("missing", {"a"}, {}));
}

// Frame by frame: the follower's frame N is handed out only once the leader's frame N is merged;
// a frame the leader does not render waits for nothing; the leader's failure fails the follower.
TEST_P(JobSchedulingStoreTest, AFollowersFrameIsHandedOutOnlyOnceTheLeaderMergedTheSameFrame) {
  JobStore store(connect());
  store.jobs().add_job(job_of("leader", 1, {1, 2, 3}), 1);
  NewJob follower = job_of("follower", 1, {1, 2, 3, 4});
  follower.after_frames = "leader";
  follower.priority = 1;  // first whenever it may go
  EXPECT_EQ(store.jobs().add_job(follower, 2).state(), v1::JOB_STATE_QUEUED);
  const auto claim = [&] { return store.units().claim_next_batch("w", 3); };
  std::optional<UnitBatch> b = claim();
  ASSERT_EQ(b->job_id, "follower");
  EXPECT_EQ(b->frame, 4) << "the leader renders no frame 4";
  b = claim();
  ASSERT_EQ(b->job_id, "leader");
  EXPECT_EQ(b->frame, 1);
  ASSERT_TRUE(store.units().batch_done("leader", b->first, 1, {}, "w"));
  b = claim();
  EXPECT_EQ(b->job_id, "leader") << "frame 1 is done but not merged";
  EXPECT_EQ(b->frame, 2);
  ASSERT_TRUE(store.frames().frame_merged("leader", 1));
  b = claim();
  ASSERT_EQ(b->job_id, "follower");
  EXPECT_EQ(b->frame, 1);
  b = claim();
  ASSERT_EQ(b->job_id, "leader");
  EXPECT_EQ(b->frame, 3);
  EXPECT_FALSE(claim()) << "the follower's frames 2 and 3 wait for the leader's";

  v1::Job leader = *store.jobs().get_job("leader");
  store.dependencies().describe(leader);
  EXPECT_EQ(leader.dependents_size(), 1);
  ASSERT_FALSE(store.units().batch_failed("leader", b->first, 1, "out of memory", 1, 4, "w").will_retry);
  const std::vector<ReleasedJob> settled = store.dependencies().release_waiting(5);
  ASSERT_EQ(settled.size(), 1u);
  EXPECT_EQ(settled[0].from, v1::JOB_STATE_RUNNING);
  EXPECT_EQ(settled[0].job.state(), v1::JOB_STATE_FAILED);
  EXPECT_NE(settled[0].job.failure_reason().find("the job it follows frame by frame, leader, failed: unit 2 failed"),
            std::string::npos)
      << settled[0].job.failure_reason();
}

// Caps: max_workers holds a job to the workers already on it (another worker gets other jobs),
// max_units_in_flight bounds its units out and its batches; lifting a cap lets more out.
TEST_P(JobSchedulingStoreTest, CapsHoldAJobToItsWorkersAndItsUnitsInFlight) {
  JobStore store(connect());
  NewJob one_worker = job_of("one-worker", 6);
  one_worker.caps.max_workers = 1;
  EXPECT_EQ(store.jobs().add_job(one_worker, 1).max_workers(), 1u);
  store.jobs().add_job(job_of("other", 2), 2);
  const BatchSize one = [](const std::string&, int) { return 1; };
  EXPECT_EQ(store.units().claim_next_batch("w1", 3, one)->job_id, "one-worker");
  EXPECT_EQ(store.units().claim_next_batch("w2", 3, one)->job_id, "other") << "w2 may not join one-worker";
  EXPECT_EQ(store.units().claim_next_batch("w3", 3, one)->job_id, "other");
  EXPECT_FALSE(store.units().claim_next_batch("w3", 3, one)) << "only one-worker is left, and w1 holds it";
  EXPECT_EQ(store.units().claim_next_batch("w1", 3, one)->job_id, "one-worker") << "w1 may take more of it";

  NewJob two_out = job_of("two-out", 6);
  two_out.caps.max_units_in_flight = 2;
  two_out.priority = 5;
  store.jobs().add_job(two_out, 4);
  const BatchSize eight = [](const std::string&, int) { return 8; };
  const std::optional<UnitBatch> first = store.units().claim_next_batch("w2", 5, eight);
  ASSERT_EQ(first->job_id, "two-out");
  EXPECT_EQ(first->count, 2u) << "a batch of eight cut to the cap";
  EXPECT_FALSE(store.units().claim_next_batch("w3", 5, eight)) << "two-out is at its cap, one-worker is w1's";
  ASSERT_TRUE(store.units().batch_done("two-out", first->first, 2, {}, "w2"));
  EXPECT_EQ(store.units().claim_next_batch("w2", 6, eight)->count, 2u);
  ASSERT_TRUE(store.jobs().set_caps("two-out", std::nullopt, 0));
  EXPECT_EQ(store.units().claim_next_batch("w3", 7, eight)->count, 2u) << "the rest at once, cap lifted";
}

// Fair share: A queues 50 one-unit jobs and has had 5 units when B, C and D queue one each. The
// next batches go to A (level with them, and older), then B, C, D: each within the first 4
// batches after it queued. Priority still wins across levels; an owner of weight 2 gets twice the
// units of one of weight 1 while both have work queued.
TEST_P(JobSchedulingStoreTest, FairShareServesNewOwnersWithinTheFirstBatchesAndFollowsWeights) {
  JobStore store(connect());
  const auto submit = [&](const std::string& id, const std::string& owner, int priority = 0, std::int64_t weight = 1000) {
    NewJob j = job_of(id);
    j.owner = owner;
    j.priority = priority;
    j.owner_weight_milli = weight;
    store.jobs().add_job(j, 1);
  };
  for (int i = 0; i < 50; ++i) submit(fmt::format("a{:02}", i), "A");
  for (int i = 0; i < 5; ++i) EXPECT_EQ(claim_and_finish(store)[0], 'a');
  for (const char* owner : {"B", "C", "D"}) submit(owner, owner);
  std::map<std::string, int> first_batch;
  for (int batch = 1; batch <= 10; ++batch) {
    const std::string job = claim_and_finish(store);
    if (job.size() == 1 && !first_batch.count(job)) first_batch[job] = batch;
  }
  EXPECT_EQ(first_batch, (std::map<std::string, int>{{"B", 2}, {"C", 3}, {"D", 4}}));

  submit("urgent", "A", 1);
  EXPECT_EQ(claim_and_finish(store), "urgent") << "priority wins over share";

  // Weights: V (1) and W (2) each queue 30 jobs after A's are all gone.
  while (!claim_and_finish(store).empty()) {
  }
  for (int i = 0; i < 30; ++i) {
    submit(fmt::format("v{:02}", i), "V", 0, 1000);
    submit(fmt::format("w{:02}", i), "W", 0, 2000);
  }
  std::map<char, int> units;
  for (int i = 0; i < 30; ++i) ++units[claim_and_finish(store)[0]];
  EXPECT_NEAR(units['w'], 20, 1);
  EXPECT_NEAR(units['v'], 10, 1);
}

INSTANTIATE_TEST_SUITE_P(BothStores, JobSchedulingStoreTest, ::testing::ValuesIn(test::kBothStores),
                         [](const auto& p) { return test::store_name(p.param); });

}  // namespace
}  // namespace farm
