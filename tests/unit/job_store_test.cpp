// The scheduler's job store: what survives a restart, the order tiles are handed out in, and how
// failed attempts end a job.
#include "server/job_store.h"

#include <gtest/gtest.h>

#include "tests/support/temp_dir.h"

namespace farm {
namespace {

NewJob make_job(const std::string& id, int priority, int tiles) {
  NewJob j;
  j.id = id;
  j.name = "job " + id;
  j.spec.set_job_json("{}");
  j.scene_hash = std::string(64, 'a');
  j.engine = "raster";
  j.width = 16 * tiles;
  j.height = 16;
  j.priority = priority;
  for (int i = 0; i < tiles; ++i) j.tiles.push_back({16 * i, 0, 16 * i + 16, 16});
  return j;
}

TEST(JobStoreTest, JobsAndTilesPersistAndRunningTilesAreQueuedAgainOnReopen) {
  test::TempDir dir;
  {
    JobStore store(dir / "jobs.db");
    const v1::Job job = store.add_job(make_job("a", 0, 3), 1000);
    EXPECT_EQ(job.state(), v1::JOB_STATE_QUEUED);
    EXPECT_EQ(job.tiles_total(), 3u);
    auto t0 = store.claim_next_tile("w1", 2000);
    auto t1 = store.claim_next_tile("w1", 2000);
    ASSERT_TRUE(t0 && t1);
    v1::TileStats stats;
    stats.set_samples(7);
    EXPECT_TRUE(store.tile_done("a", t0->index, stats));
    EXPECT_FALSE(store.tile_done("a", t0->index, stats));  // not running any more
    EXPECT_EQ(store.get_job("a")->state(), v1::JOB_STATE_RUNNING);
  }  // t1 was running when the "scheduler" went away
  JobStore store(dir / "jobs.db");
  const v1::Job job = *store.get_job("a");
  EXPECT_EQ(job.tiles_done(), 1u);
  EXPECT_EQ(job.tiles_rendered(), 1u);
  EXPECT_EQ(job.stats().samples(), 7u);
  EXPECT_EQ(job.submitted_at().seconds(), 1);
  const std::vector<TileRecord> tiles = store.tiles("a");
  ASSERT_EQ(tiles.size(), 3u);
  EXPECT_EQ(tiles[0].state, TileState::Done);
  EXPECT_EQ(tiles[1].state, TileState::Queued);
  EXPECT_EQ(tiles[1].attempts, 0);  // a restart is not the tile's fault
  EXPECT_EQ(store.claim_next_tile("w2", 3000)->index, 1u);
  EXPECT_EQ(store.claim_next_tile("w2", 3000)->index, 2u);
  EXPECT_FALSE(store.claim_next_tile("w2", 3000));
  EXPECT_EQ(store.get_spec("a")->job_json(), "{}");
}

TEST(JobStoreTest, TilesGoOutByPriorityThenSubmissionThenIndex) {
  test::TempDir dir;
  JobStore store(dir / "jobs.db");
  store.add_job(make_job("first", 0, 2), 1);
  store.add_job(make_job("second", 0, 1), 2);
  store.add_job(make_job("urgent", 5, 2), 3);
  std::vector<std::string> order;
  while (auto claim = store.claim_next_tile("w", 4)) {
    order.push_back(claim->job_id + ":" + std::to_string(claim->index));
  }
  EXPECT_EQ(order, (std::vector<std::string>{"urgent:0", "urgent:1", "first:0", "first:1",
                                             "second:0"}));
}

TEST(JobStoreTest, FailedAttemptsRequeueUntilTheLimitThenFailTheJobWithTheReason) {
  test::TempDir dir;
  JobStore store(dir / "jobs.db");
  store.add_job(make_job("a", 0, 2), 1);
  for (int attempt = 1; attempt <= 2; ++attempt) {
    auto claim = store.claim_next_tile("w", 2);
    ASSERT_TRUE(claim);
    EXPECT_EQ(claim->index, 0u);
    EXPECT_EQ(claim->attempts, attempt - 1);
    const TileFailure f = store.tile_failed("a", 0, "worker died", 3, 3);
    EXPECT_TRUE(f.will_retry);
    EXPECT_EQ(f.job.tile_failures(), static_cast<unsigned>(attempt));
    EXPECT_EQ(store.tiles("a")[0].last_error, "worker died");
  }
  ASSERT_EQ(store.claim_next_tile("w", 2)->index, 0u);
  const TileFailure f = store.tile_failed("a", 0, "deadline exceeded", 3, 4);
  EXPECT_FALSE(f.will_retry);
  EXPECT_EQ(f.job.state(), v1::JOB_STATE_FAILED);
  EXPECT_NE(f.job.failure_reason().find("deadline exceeded"), std::string::npos);
  EXPECT_NE(f.job.failure_reason().find("3 times"), std::string::npos);
  EXPECT_FALSE(store.claim_next_tile("w", 5));  // a failed job hands out nothing
  // Final states stay final.
  EXPECT_EQ(store.cancel_job("a", 6).state(), v1::JOB_STATE_FAILED);
}

TEST(JobStoreTest, CancelledJobHandsOutNoTilesAndIgnoresLateResults) {
  test::TempDir dir;
  JobStore store(dir / "jobs.db");
  store.add_job(make_job("a", 0, 3), 1);
  auto claim = store.claim_next_tile("w", 2);
  ASSERT_TRUE(claim);
  EXPECT_EQ(store.cancel_job("a", 3).state(), v1::JOB_STATE_CANCELLED);
  EXPECT_FALSE(store.claim_next_tile("w", 4));
  EXPECT_FALSE(store.tile_done("a", claim->index, {}));
  EXPECT_EQ(store.get_job("a")->tiles_done(), 0u);
}

TEST(JobStoreTest, ListJobsIsNewestFirstWithPagesAndStateFilter) {
  test::TempDir dir;
  JobStore store(dir / "jobs.db");
  for (int i = 0; i < 5; ++i) store.add_job(make_job(std::to_string(i), 0, 1), i);
  store.cancel_job("3", 10);
  auto [page1, next1] = store.list_jobs({}, 2, 0);
  ASSERT_EQ(page1.size(), 2u);
  EXPECT_EQ(page1[0].job_id(), "4");
  EXPECT_EQ(page1[1].job_id(), "3");
  ASSERT_NE(next1, 0);
  auto [page2, next2] = store.list_jobs({}, 10, next1);
  ASSERT_EQ(page2.size(), 3u);
  EXPECT_EQ(page2[0].job_id(), "2");
  EXPECT_EQ(next2, 0);
  auto [cancelled, none] = store.list_jobs({v1::JOB_STATE_CANCELLED}, 10, 0);
  ASSERT_EQ(cancelled.size(), 1u);
  EXPECT_EQ(cancelled[0].job_id(), "3");
}

}  // namespace
}  // namespace farm
