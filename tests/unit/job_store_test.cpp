// The scheduler's job store: what survives a restart, the order tiles are handed out in, and how
// failed attempts end a job.
#include "server/scheduler/store/job_store.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <map>
#include <mutex>
#include <thread>

#include "tests/support/store_locations.h"
#include "tests/support/store_downgrade.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

// Each test of the fixture runs on a fresh SQLite file and on a fresh PostgreSQL database.
class JobStoreTest : public test::StoreTest {};

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

// A job's requirements travel with it, and its units are claimed only for a worker that meets
// them: an older tagged job is passed over for a worker without the tag or with too few
// threads, and nothing is claimed for one that meets no job.
TEST_P(JobStoreTest, UnitsAreClaimedOnlyForWorkersThatMeetTheirJobsRequirements) {
  JobStore store(connect());
  NewJob tagged = make_job("t", 0, 2);
  tagged.requirements = {{"big-mem"}, 4};
  const v1::Job added = store.jobs().add_job(tagged, 1000);
  ASSERT_EQ(added.required_tags_size(), 1);
  EXPECT_EQ(added.required_tags(0), "big-mem");
  EXPECT_EQ(added.min_threads(), 4);
  const auto claim = [&](const std::string& worker, WorkerOffer offer) {
    return store.units().claim_next_batch(worker, 2000, {}, 1024, {}, offer);
  };
  EXPECT_FALSE(claim("thin", {{"big-mem"}, 2})) << "too few threads";
  EXPECT_FALSE(claim("untagged", {{"course-cg"}, 8})) << "without the tag";
  EXPECT_FALSE(claim("static", {})) << "a worker that says nothing";
  store.jobs().add_job(make_job("p", 0, 1), 1001);
  const auto plain = claim("untagged", {{"course-cg"}, 8});
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain->job_id, "p");
  const auto big = claim("big", {{"big-mem", "gpu"}, 4});
  ASSERT_TRUE(big);
  EXPECT_EQ(big->job_id, "t");
  // Kept across a reopen.
  const std::optional<v1::Job> again = JobStore(connect()).jobs().get_job("t");
  ASSERT_TRUE(again);
  EXPECT_EQ(again->min_threads(), 4);
}

TEST_P(JobStoreTest, JobsAndTilesPersistAndRunningTilesAreQueuedAgainOnReopen) {
  {
    JobStore store(connect());
    const v1::Job job = store.jobs().add_job(make_job("a", 0, 3), 1000);
    EXPECT_EQ(job.state(), v1::JOB_STATE_QUEUED);
    EXPECT_EQ(job.tiles_total(), 3u);
    auto t0 = store.units().claim_next_batch("w1", 2000);
    auto t1 = store.units().claim_next_batch("w1", 2000);
    ASSERT_TRUE(t0 && t1);
    v1::TileStats stats;
    stats.set_samples(7);
    EXPECT_TRUE(store.units().batch_done("a", t0->first, 1, stats));
    EXPECT_FALSE(store.units().batch_done("a", t0->first, 1, stats));  // not running any more
    EXPECT_EQ(store.jobs().get_job("a")->state(), v1::JOB_STATE_RUNNING);
  }  // t1 was running when the "scheduler" went away
  JobStore store(connect());
  const v1::Job job = *store.jobs().get_job("a");
  EXPECT_EQ(job.tiles_done(), 1u);
  EXPECT_EQ(job.tiles_rendered(), 1u);
  EXPECT_EQ(job.stats().samples(), 7u);
  EXPECT_EQ(job.submitted_at().seconds(), 1);
  const std::vector<UnitRecord> tiles = store.units().tiles("a");
  ASSERT_EQ(tiles.size(), 3u);
  EXPECT_EQ(tiles[0].state, TileState::Done);
  EXPECT_EQ(tiles[1].state, TileState::Queued);
  EXPECT_EQ(tiles[1].attempts, 0);  // a restart is not the tile's fault
  EXPECT_EQ(store.units().claim_next_batch("w2", 3000)->first, 1u);
  EXPECT_EQ(store.units().claim_next_batch("w2", 3000)->first, 2u);
  EXPECT_FALSE(store.units().claim_next_batch("w2", 3000));
  EXPECT_EQ(store.jobs().get_spec("a")->job_json(), "{}");
}

TEST_P(JobStoreTest, TilesGoOutByPriorityThenSubmissionThenIndex) {
  JobStore store(connect());
  store.jobs().add_job(make_job("first", 0, 2), 1);
  store.jobs().add_job(make_job("second", 0, 1), 2);
  store.jobs().add_job(make_job("urgent", 5, 2), 3);
  std::vector<std::string> order;
  while (auto claim = store.units().claim_next_batch("w", 4)) {
    order.push_back(claim->job_id + ":" + std::to_string(claim->first));
  }
  EXPECT_EQ(order, (std::vector<std::string>{"urgent:0", "urgent:1", "first:0", "first:1",
                                             "second:0"}));
}

TEST_P(JobStoreTest, FailedAttemptsRequeueUntilTheLimitThenFailTheJobWithTheReason) {
  JobStore store(connect());
  store.jobs().add_job(make_job("a", 0, 2), 1);
  for (int attempt = 1; attempt <= 2; ++attempt) {
    auto claim = store.units().claim_next_batch("w", 2);
    ASSERT_TRUE(claim);
    EXPECT_EQ(claim->first, 0u);
    EXPECT_EQ(claim->attempts, attempt - 1);
    const TileFailure f = store.units().batch_failed("a", 0, 1, "worker died", 3, 3);
    EXPECT_TRUE(f.will_retry);
    EXPECT_EQ(f.job.tile_failures(), static_cast<unsigned>(attempt));
    EXPECT_EQ(store.units().tiles("a")[0].last_error, "worker died");
  }
  ASSERT_EQ(store.units().claim_next_batch("w", 2)->first, 0u);
  const TileFailure f = store.units().batch_failed("a", 0, 1, "deadline exceeded", 3, 4);
  EXPECT_FALSE(f.will_retry);
  EXPECT_EQ(f.job.state(), v1::JOB_STATE_FAILED);
  EXPECT_NE(f.job.failure_reason().find("deadline exceeded"), std::string::npos);
  EXPECT_NE(f.job.failure_reason().find("3 times"), std::string::npos);
  EXPECT_FALSE(store.units().claim_next_batch("w", 5));  // a failed job hands out nothing
  // Final states stay final.
  EXPECT_EQ(store.jobs().cancel_job("a", 6).state(), v1::JOB_STATE_FAILED);
}

TEST_P(JobStoreTest, CancelledJobHandsOutNoTilesAndIgnoresLateResults) {
  JobStore store(connect());
  store.jobs().add_job(make_job("a", 0, 3), 1);
  auto claim = store.units().claim_next_batch("w", 2);
  ASSERT_TRUE(claim);
  EXPECT_EQ(store.jobs().cancel_job("a", 3).state(), v1::JOB_STATE_CANCELLED);
  EXPECT_FALSE(store.units().claim_next_batch("w", 4));
  EXPECT_FALSE(store.units().batch_done("a", claim->first, 1, {}));
  EXPECT_EQ(store.jobs().get_job("a")->tiles_done(), 0u);
}

// A 4 x 2 grid of 16 px tiles.
NewJob grid_job(const std::string& id) {
  NewJob j = make_job(id, 0, 0);
  j.width = 64;
  j.height = 32;
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 4; ++x) j.tiles.push_back({16 * x, 16 * y, 16 * x + 16, 16 * y + 16});
  }
  return j;
}

TEST_P(JobStoreTest, BatchesAreRowSegmentsOfQueuedTilesAndATileThatFailedGoesAlone) {
  JobStore store(connect());
  store.jobs().add_job(grid_job("a"), 1);
  int asked_queued = -1;
  const BatchSize three = [&](const std::string& job_id, int queued) {
    EXPECT_EQ(job_id, "a");
    asked_queued = queued;
    return 3;
  };
  auto b0 = store.units().claim_next_batch("w", 2, three);
  ASSERT_TRUE(b0);
  EXPECT_EQ(asked_queued, 8);
  EXPECT_EQ(b0->first, 0u);
  EXPECT_EQ(b0->count, 3u);
  EXPECT_EQ(b0->rect, (Rect{0, 0, 48, 16}));
  // The row ends after one more tile: a batch that began within a row never wraps to the next.
  auto b1 = store.units().claim_next_batch("w", 2, three);
  ASSERT_TRUE(b1);
  EXPECT_EQ(asked_queued, 5);
  EXPECT_EQ(b1->first, 3u);
  EXPECT_EQ(b1->count, 1u);
  EXPECT_EQ(b1->rect, (Rect{48, 0, 64, 16}));
  // The first batch fails: its three tiles are queued again with an attempt each.
  const TileFailure f = store.units().batch_failed("a", 0, 3, "worker died", 3, 3);
  EXPECT_TRUE(f.will_retry);
  EXPECT_EQ(f.job.tile_failures(), 3u);
  // ... and now go out one by one, however many the policy allows.
  for (std::uint32_t i = 0; i < 3; ++i) {
    auto retry = store.units().claim_next_batch("w", 4, three);
    ASSERT_TRUE(retry);
    EXPECT_EQ(retry->first, i);
    EXPECT_EQ(retry->count, 1u);
    EXPECT_EQ(retry->attempts, 1);
    EXPECT_TRUE(store.units().batch_done("a", i, 1, {}));
  }
  // A batch stops before a tile that is not queued.
  EXPECT_TRUE(store.units().batch_done("a", 3, 1, {}));
  auto b2 = store.units().claim_next_batch("w", 5, [](const std::string&, int) { return 64; });
  ASSERT_TRUE(b2);
  EXPECT_EQ(b2->first, 4u);
  EXPECT_EQ(b2->count, 4u);
  v1::TileStats stats;
  stats.set_samples(4);
  EXPECT_FALSE(store.units().batch_done("a", 4, 5, stats));  // tile 8 does not exist: not all running
  EXPECT_TRUE(store.units().batch_done("a", 4, 4, stats));
  const v1::Job job = *store.jobs().get_job("a");
  EXPECT_EQ(job.tiles_done(), 8u);
  EXPECT_EQ(job.tiles_rendered(), 8u);
  EXPECT_EQ(job.stats().samples(), 4u);
  // Which result file holds each tile.
  std::vector<std::uint32_t> parts;
  for (const UnitRecord& t : store.units().tiles("a")) parts.push_back(t.part);
  EXPECT_EQ(parts, (std::vector<std::uint32_t>{0, 1, 2, 3, 4, 4, 4, 4}));
}

TEST_P(JobStoreTest, ABatchThatBeginsARowTakesWholeRowsAfterItAndNeverPartOfOne) {
  JobStore store(connect());
  store.jobs().add_job(grid_job("a"), 1);
  store.jobs().add_job(grid_job("b"), 2);
  const auto size = [](int n) { return [n](const std::string&, int) { return n; }; };
  // Six allowed: the first row's four, and not two of the second (the union would not be a
  // rectangle).
  auto a0 = store.units().claim_next_batch("w", 3, size(6), 1024, {}, {}, true);
  ASSERT_TRUE(a0);
  EXPECT_EQ(a0->first, 0u);
  EXPECT_EQ(a0->count, 4u);
  EXPECT_EQ(a0->rect, (Rect{0, 0, 64, 16}));
  auto a1 = store.units().claim_next_batch("w", 3, size(6), 1024, {}, {}, true);
  ASSERT_TRUE(a1);
  EXPECT_EQ(a1->first, 4u);
  EXPECT_EQ(a1->count, 4u);
  EXPECT_EQ(a1->rect, (Rect{0, 16, 64, 32}));
  // Eight allowed: both rows, the whole frame in one call.
  auto b = store.units().claim_next_batch("w", 4, size(8), 1024, {}, {}, true);
  ASSERT_TRUE(b);
  EXPECT_EQ(b->job_id, "b");
  EXPECT_EQ(b->first, 0u);
  EXPECT_EQ(b->count, 8u);
  EXPECT_EQ(b->rect, (Rect{0, 0, 64, 32}));
  EXPECT_TRUE(store.units().batch_done("b", 0, 8, {}));
  // Without whole rows (a farm's batches), a row at most.
  store.jobs().add_job(grid_job("c"), 3);
  auto c = store.units().claim_next_batch("w", 5, size(8));
  ASSERT_TRUE(c);
  EXPECT_EQ(c->job_id, "c");
  EXPECT_EQ(c->count, 4u);
  EXPECT_EQ(c->rect, (Rect{0, 0, 64, 16}));
  EXPECT_EQ(store.jobs().get_job("b")->tiles_done(), 8u);
}

TEST_P(JobStoreTest, ARequeuedBatchIsQueuedAgainWithoutAnAttempt) {
  JobStore store(connect());
  store.jobs().add_job(grid_job("a"), 1);
  const BatchSize two = [](const std::string&, int) { return 2; };
  auto b = store.units().claim_next_batch("w", 2, two);
  ASSERT_TRUE(b);
  store.units().batch_requeue("a", b->first, b->count);
  auto again = store.units().claim_next_batch("w", 3, two);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->first, 0u);
  EXPECT_EQ(again->count, 2u);
  EXPECT_EQ(again->attempts, 0);
}

// A data dir written by the scheduler before batches (schema 1, one file per tile) opens as is.
TEST(SqliteStoreUpgradeTest, AVersion1StoreIsUpgradedAndItsDoneTilesKeepTheirFiles) {
  test::TempDir dir;
  {
    JobStore store(dir / "jobs.db");
    store.jobs().add_job(make_job("a", 0, 3), 1);
    ASSERT_TRUE(store.units().claim_next_batch("w", 2));
    ASSERT_TRUE(store.units().claim_next_batch("w", 2));
    ASSERT_TRUE(store.units().batch_done("a", 1, 1, {}));
  }
  {
    // Back to what version 1 had: no part column, no owner.
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open((dir / "jobs.db").c_str(), &db), SQLITE_OK);
    for (const std::string& sql : test::back_to_version(1)) {
      EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
    }
    sqlite3_close(db);
  }
  JobStore store(dir / "jobs.db");
  const std::vector<UnitRecord> tiles = store.units().tiles("a");
  ASSERT_EQ(tiles.size(), 3u);
  EXPECT_EQ(tiles[1].state, TileState::Done);
  EXPECT_EQ(tiles[1].part, 1u);  // its own file, as version 1 wrote it
  EXPECT_EQ(tiles[0].state, TileState::Queued);  // was running
}

TEST(SqliteStoreUpgradeTest, AVersion2StoreIsUpgradedAndJobsGetOwners) {
  test::TempDir dir;
  {
    JobStore store(dir / "jobs.db");
    store.jobs().add_job(make_job("old", 0, 1), 1);
  }
  {
    // Back to what version 2 had: no owner column, no lost_attempts.
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open((dir / "jobs.db").c_str(), &db), SQLITE_OK);
    for (const std::string& sql : test::back_to_version(2)) {
      EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
    }
    sqlite3_close(db);
  }
  JobStore store(dir / "jobs.db");
  EXPECT_EQ(store.jobs().get_job("old")->owner(), "");
  NewJob mine = make_job("mine", 0, 1);
  mine.owner = "alice";
  store.jobs().add_job(mine, 2);
  EXPECT_EQ(store.jobs().get_job("mine")->owner(), "alice");
  EXPECT_EQ(store.jobs().list_jobs(JobFilter{.owner = std::string("alice")}, 10, 0).first.size(), 1u);
  EXPECT_EQ(store.jobs().list_jobs(JobFilter{.owner = std::string("bob")}, 10, 0).first.size(), 0u);
  EXPECT_EQ(store.jobs().list_jobs(JobFilter{}, 10, 0).first.size(), 2u);
}

// A store of the scheduler before lost workers were counted apart (schema 3): its tiles keep their
// failed attempts, and count lost workers from zero.
TEST(SqliteStoreUpgradeTest, AVersion3StoreIsUpgradedAndItsTilesCountLostWorkersFromZero) {
  test::TempDir dir;
  {
    JobStore store(dir / "jobs.db");
    store.jobs().add_job(make_job("a", 0, 2), 1);
    ASSERT_TRUE(store.units().claim_next_batch("w", 2));
    ASSERT_TRUE(store.units().batch_failed("a", 0, 1, "worker died", 3, 3).will_retry);
  }
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open((dir / "jobs.db").c_str(), &db), SQLITE_OK);
    for (const std::string& sql : test::back_to_version(3)) {
      EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
    }
    sqlite3_close(db);
  }
  {
    JobStore store(dir / "jobs.db");
    const std::vector<UnitRecord> tiles = store.units().tiles("a");
    ASSERT_EQ(tiles.size(), 2u);
    EXPECT_EQ(tiles[0].attempts, 1);
    EXPECT_EQ(tiles[0].lost_attempts, 0);
    ASSERT_TRUE(store.units().claim_next_batch("w", 4));
    EXPECT_TRUE(store.units().batch_lost("a", 0, 1, "worker w: UNAVAILABLE", 2, 5).will_retry);
    EXPECT_EQ(store.units().tiles("a")[0].lost_attempts, 1);
  }
  // Upgraded once: it opens as version 10 from now on.
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((dir / "jobs.db").c_str(), &db), SQLITE_OK);
  sqlite3_stmt* s = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(db, "SELECT version FROM schema_version", -1, &s, nullptr), SQLITE_OK);
  ASSERT_EQ(sqlite3_step(s), SQLITE_ROW);
  EXPECT_EQ(sqlite3_column_int(s, 0), 10);
  sqlite3_finalize(s);
  sqlite3_close(db);
}

// Version 5 renders frame ranges: every older job is a still, frame 0 alone, merged when the job
// had succeeded.
TEST(SqliteStoreUpgradeTest, AVersion4StoreIsUpgradedAndItsJobsAreStillsOfFrameZero) {
  test::TempDir dir;
  {
    JobStore store(dir / "jobs.db");
    store.jobs().add_job(make_job("done", 0, 1), 1);
    store.jobs().add_job(make_job("running", 0, 2), 2);
    ASSERT_TRUE(store.units().claim_next_batch("w", 3));
    ASSERT_TRUE(store.units().batch_done("done", 0, 1, {}));
    ASSERT_TRUE(store.frames().frame_merged("done", 0));
    ASSERT_EQ(store.jobs().finish_job("done", v1::JOB_STATE_SUCCEEDED, "", "", 4).state(), v1::JOB_STATE_SUCCEEDED);
  }
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open((dir / "jobs.db").c_str(), &db), SQLITE_OK);
    for (const std::string& sql : test::back_to_version(4)) {
      EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
    }
    sqlite3_close(db);
  }
  JobStore store(dir / "jobs.db");
  const v1::Job done = *store.jobs().get_job("done");
  EXPECT_EQ(done.frames_total(), 1u);
  EXPECT_EQ(done.frames_done(), 1u);
  EXPECT_EQ(done.frame_first(), 0);
  EXPECT_TRUE(store.frames().is_frame_merged("done", 0));
  const v1::Job running = *store.jobs().get_job("running");
  EXPECT_EQ(running.frames_done(), 0u);
  EXPECT_FALSE(store.frames().is_frame_merged("running", 0));
  EXPECT_EQ(store.units().tiles("running")[0].frame, 0);
  // It goes on as any job: its frame completes, is merged, and the job succeeds.
  for (int i = 0; i < 2; ++i) {
    auto b = store.units().claim_next_batch("w", 5);
    ASSERT_TRUE(b);
    ASSERT_TRUE(store.units().batch_done("running", b->first, 1, {}));
  }
  EXPECT_EQ(store.frames().complete_frames("running"), std::vector<int>{0});
  ASSERT_TRUE(store.frames().frame_merged("running", 0));
  EXPECT_TRUE(store.frames().complete_frames("running").empty());
  EXPECT_EQ(store.jobs().finish_job("running", v1::JOB_STATE_SUCCEEDED, "", "", 6).state(), v1::JOB_STATE_SUCCEEDED);
}

// A job of frames: tiles numbered frame after frame, batches never cross a frame, a frame is
// complete when its tiles are, and a part taken back unmerges its frame.
TEST_P(JobStoreTest, FramesCompleteOneByOneAndAPartTakenBackUnmergesItsFrame) {
  JobStore store(connect());
  NewJob job = make_job("f", 0, 2);  // two tiles a frame, in one row
  job.frames = {10, 12, 14};
  job.frame_step = 2;
  const v1::Job added = store.jobs().add_job(job, 1);
  EXPECT_EQ(added.tiles_total(), 6u);
  EXPECT_EQ(added.frames_total(), 3u);
  EXPECT_EQ(added.frame_first(), 10);
  EXPECT_EQ(added.frame_last(), 14);
  EXPECT_EQ(added.frame_step(), 2);
  const BatchSize many = [](const std::string&, int) { return 8; };
  auto first = store.units().claim_next_batch("w", 2, many);
  ASSERT_TRUE(first);
  EXPECT_EQ(first->frame, 10);
  EXPECT_EQ(first->count, 2u);  // the whole row of frame 10, not into frame 12
  EXPECT_TRUE(store.frames().complete_frames("f").empty());
  ASSERT_TRUE(store.units().batch_done("f", first->first, first->count, {}));
  EXPECT_EQ(store.frames().complete_frames("f", 10), std::vector<int>{10});
  EXPECT_TRUE(store.frames().complete_frames("f", 12).empty());
  EXPECT_EQ(store.frames().frame_parts("f", 10, 1), (std::vector<FramePart>{{0, 0}}));
  ASSERT_TRUE(store.frames().frame_merged("f", 10));
  EXPECT_EQ(store.jobs().get_job("f")->frames_done(), 1u);
  EXPECT_TRUE(store.frames().complete_frames("f").empty());
  auto second = store.units().claim_next_batch("w", 3, many);
  ASSERT_TRUE(second);
  EXPECT_EQ(second->frame, 12);
  EXPECT_EQ(second->first, 2u);
  EXPECT_FALSE(store.frames().frame_merged("f", 12));  // its tiles are not done
  // Taking frame 10's part back unmerges it: merged again once rendered again.
  EXPECT_EQ(store.units().requeue_parts("f", {0}).size(), 1u);
  EXPECT_EQ(store.jobs().get_job("f")->frames_done(), 0u);
  EXPECT_FALSE(store.frames().is_frame_merged("f", 10));
}

// A version 5 store (frames, no passes) is upgraded: its jobs are one pass each, and go on.
TEST(SqliteStoreUpgradeTest, AVersion5StoreIsUpgradedAndItsJobsAreOnePass) {
  test::TempDir dir;
  {
    JobStore store(dir / "jobs.db");
    store.jobs().add_job(make_job("running", 0, 2), 1);
  }
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open((dir / "jobs.db").c_str(), &db), SQLITE_OK);
    for (const std::string& sql : test::back_to_version(5)) {
      EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
    }
    sqlite3_close(db);
  }
  JobStore store(dir / "jobs.db");
  EXPECT_EQ(store.jobs().get_job("running")->passes(), 1u);
  EXPECT_EQ(store.units().tiles("running")[1].pass, 0);
  for (int i = 0; i < 2; ++i) {
    auto b = store.units().claim_next_batch("w", 2);
    ASSERT_TRUE(b);
    EXPECT_EQ(b->pass, 0);
    ASSERT_TRUE(store.units().batch_done("running", b->first, 1, {}));
  }
  EXPECT_EQ(store.frames().complete_passes("running", 0), 1);
  EXPECT_EQ(store.frames().complete_frames("running"), std::vector<int>{0});
}

// A job of sample passes: its units are numbered pass after pass within each frame, so the queue
// hands a frame's passes out in order; a batch never crosses a pass; complete_passes counts the
// passes done from the first on; a frame is complete when all its passes are.
// Version 7 adds the schedulers' leases: a tile running in a version 6 store names no scheduler,
// and is queued again at open.
TEST(SqliteStoreUpgradeTest, AVersion6StoreIsUpgradedAndItsRunningTilesAreQueuedAgain) {
  test::TempDir dir;
  {
    JobStore store(dir / "jobs.db");
    store.jobs().add_job(make_job("a", 0, 2), 1);
    ASSERT_TRUE(store.units().claim_next_batch("w", 2));
  }
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open((dir / "jobs.db").c_str(), &db), SQLITE_OK);
    for (const std::string& sql : [] {
           std::vector<std::string> s = test::back_to_version(6);
           s.insert(s.begin(), "UPDATE tiles SET state = 1 WHERE idx = 0");  // running at the downgrade
           return s;
         }()) {
      EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
    }
    sqlite3_close(db);
  }
  JobStore store(dir / "jobs.db");
  EXPECT_EQ(store.units().tiles("a")[0].state, TileState::Queued);
  store.leases().set_scheduler("s");
  store.leases().hold_lease(10);
  const auto b = store.units().claim_next_batch("w", 3);
  ASSERT_TRUE(b);
  EXPECT_TRUE(store.units().batch_done("a", b->first, 1, {}, "w"));
}

TEST_P(JobStoreTest, PassesAreUnitsHandedOutInPassOrderAndAFrameNeedsThemAll) {
  JobStore store(connect());
  NewJob job = make_job("p", 0, 2);  // two tiles a frame, in one row
  job.frames = {1, 2};
  job.passes = 3;
  const v1::Job added = store.jobs().add_job(job, 1);
  EXPECT_EQ(added.tiles_total(), 12u);
  EXPECT_EQ(added.passes(), 3u);
  const std::vector<UnitRecord> tiles = store.units().tiles("p");
  ASSERT_EQ(tiles.size(), 12u);
  for (std::uint32_t i = 0; i < 12; ++i) {
    EXPECT_EQ(tiles[i].frame, i < 6 ? 1 : 2) << i;
    EXPECT_EQ(tiles[i].pass, static_cast<int>(i / 2 % 3)) << i;
    EXPECT_EQ(tiles[i].rect, tiles[i % 2].rect) << i;  // every pass has the frame's grid
  }
  const BatchSize many = [](const std::string&, int) { return 8; };
  std::vector<UnitBatch> claimed;
  for (int k = 0; k < 3; ++k) {
    auto b = store.units().claim_next_batch("w", 2, many);
    ASSERT_TRUE(b);
    EXPECT_EQ(b->frame, 1);
    EXPECT_EQ(b->pass, k);
    EXPECT_EQ(b->count, 2u);  // the row of one pass, not into the next
    claimed.push_back(*b);
  }
  EXPECT_EQ(store.frames().complete_passes("p", 1), 0);
  // Pass 1 done before pass 0: no pass is complete from the first on yet.
  ASSERT_TRUE(store.units().batch_done("p", claimed[1].first, claimed[1].count, {}));
  EXPECT_EQ(store.frames().complete_passes("p", 1), 0);
  ASSERT_TRUE(store.units().batch_done("p", claimed[0].first, claimed[0].count, {}));
  EXPECT_EQ(store.frames().complete_passes("p", 1), 2);
  EXPECT_TRUE(store.frames().complete_frames("p", 1).empty());
  EXPECT_EQ(store.frames().frame_parts("p", 1, 2), (std::vector<FramePart>{{0, 0}, {2, 1}}));
  ASSERT_TRUE(store.units().batch_done("p", claimed[2].first, claimed[2].count, {}));
  EXPECT_EQ(store.frames().complete_passes("p", 1), 3);
  EXPECT_EQ(store.frames().complete_frames("p", 1), std::vector<int>{1});
  EXPECT_EQ(store.frames().frame_parts("p", 1, 3), (std::vector<FramePart>{{0, 0}, {2, 1}, {4, 2}}));
  // Taking pass 0's part back: no pass is complete from the first on again.
  EXPECT_EQ(store.units().requeue_parts("p", {0}).size(), 1u);
  EXPECT_EQ(store.frames().complete_passes("p", 1), 0);
  auto again = store.units().claim_next_batch("w", 3, many);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->first, 0u);
  EXPECT_EQ(again->pass, 0);
}

// Lost workers count against their own limit, never against max_attempts, and a tile that lost
// one goes out alone, as a failed one does.
TEST_P(JobStoreTest, LostWorkersCountApartFromAttemptsAndFailTheJobAtTheirOwnLimit) {
  JobStore store(connect());
  store.jobs().add_job(make_job("a", 0, 3), 1);
  const BatchSize three = [](const std::string&, int) { return 3; };
  const auto batch = store.units().claim_next_batch("w", 2, three);
  ASSERT_TRUE(batch);
  ASSERT_EQ(batch->count, 3u);
  EXPECT_TRUE(store.units().batch_lost("a", 0, 3, "worker w: UNAVAILABLE", 5, 3, "w").will_retry);
  // Each of the three goes out alone now.
  for (std::uint32_t i = 0; i < 3; ++i) {
    const auto claim = store.units().claim_next_batch("w", 3, three);
    ASSERT_TRUE(claim);
    EXPECT_EQ(claim->first, i);
    EXPECT_EQ(claim->count, 1u);
    EXPECT_EQ(claim->attempts, 0);
    EXPECT_EQ(claim->lost_attempts, 1);
  }
  ASSERT_TRUE(store.units().batch_done("a", 1, 1, {}, "w"));
  ASSERT_TRUE(store.units().batch_done("a", 2, 1, {}, "w"));
  // Tile 0 loses its worker again and again: well past max_attempts, and still queued.
  EXPECT_TRUE(store.units().batch_lost("a", 0, 1, "worker w: UNAVAILABLE", 5, 3, "w").will_retry);
  for (int loss = 3; loss <= 4; ++loss) {
    const auto claim = store.units().claim_next_batch("w", 4, three);
    ASSERT_TRUE(claim);
    EXPECT_EQ(claim->lost_attempts, loss - 1);
    const TileFailure f = store.units().batch_lost("a", 0, 1, "worker w: UNAVAILABLE", 5, 4, "w");
    EXPECT_TRUE(f.will_retry);
    EXPECT_EQ(f.job.state(), v1::JOB_STATE_RUNNING);
  }
  const std::vector<UnitRecord> tiles = store.units().tiles("a");
  EXPECT_EQ(tiles[0].attempts, 0);
  EXPECT_EQ(tiles[0].lost_attempts, 4);
  EXPECT_EQ(tiles[0].last_error, "worker w: UNAVAILABLE");
  // A failure the tile's worker reported counts as ever, against max_attempts.
  ASSERT_TRUE(store.units().claim_next_batch("w", 4, three));
  EXPECT_TRUE(store.units().batch_failed("a", 0, 1, "worker w: INTERNAL: boom", 2, 4, "w").will_retry);
  EXPECT_EQ(store.units().tiles("a")[0].attempts, 1);
  ASSERT_TRUE(store.units().claim_next_batch("w", 5, three));
  const TileFailure last = store.units().batch_lost("a", 0, 1, "worker w left: no heartbeat", 5, 6, "w");
  EXPECT_FALSE(last.will_retry);
  EXPECT_EQ(last.job.state(), v1::JOB_STATE_FAILED);
  EXPECT_NE(last.job.failure_reason().find("unit 0 lost 5 workers while rendering"), std::string::npos)
      << last.job.failure_reason();
  EXPECT_NE(last.job.failure_reason().find("lost-worker attempts limit"), std::string::npos);
  EXPECT_NE(last.job.failure_reason().find("no heartbeat"), std::string::npos);
  // Every rendering that came to nothing: the batch of 3, tile 0's three losses alone, its failure
  // and its last loss.
  EXPECT_EQ(last.job.tile_failures(), 3u + 3u + 1u + 1u);
  EXPECT_EQ(store.units().tiles("a")[0].state, TileState::Failed);
}

TEST_P(JobStoreTest, ListJobsIsNewestFirstWithPagesAndStateFilter) {
  JobStore store(connect());
  for (int i = 0; i < 5; ++i) store.jobs().add_job(make_job(std::to_string(i), 0, 1), i);
  store.jobs().cancel_job("3", 10);
  auto [page1, next1] = store.jobs().list_jobs(JobFilter{}, 2, 0);
  ASSERT_EQ(page1.size(), 2u);
  EXPECT_EQ(page1[0].job_id(), "4");
  EXPECT_EQ(page1[1].job_id(), "3");
  ASSERT_NE(next1, 0);
  auto [page2, next2] = store.jobs().list_jobs(JobFilter{}, 10, next1);
  ASSERT_EQ(page2.size(), 3u);
  EXPECT_EQ(page2[0].job_id(), "2");
  EXPECT_EQ(next2, 0);
  auto [cancelled, none] = store.jobs().list_jobs(JobFilter{.states = {v1::JOB_STATE_CANCELLED}}, 10, 0);
  ASSERT_EQ(cancelled.size(), 1u);
  EXPECT_EQ(cancelled[0].job_id(), "3");
}

// A name glob (case-insensitive, `*` and `?`; LIKE's own `%` and `_` taken literally), an id
// prefix, and both with the owner, the states and the pages: the same on both stores.
TEST_P(JobStoreTest, ListJobsFiltersByNameGlobAndIdPrefix) {
  JobStore store(connect());
  const std::vector<std::pair<std::string, std::string>> jobs{
      {"ab12", "Cow turntable"}, {"ab34", "cow_still"}, {"cd56", "cornell 100%"}, {"ab78", "cowl"}, {"ef90", "c_w"}};
  int seq = 0;
  for (const auto& [id, name] : jobs) {
    NewJob j = make_job(id, 0, 1);
    j.name = name;
    j.owner = id == "ab78" ? "bob" : "alice";
    store.jobs().add_job(j, ++seq);
  }
  const auto ids = [&](const JobFilter& f, int limit = 10) {
    std::vector<std::string> out;
    for (const v1::Job& j : store.jobs().list_jobs(f, limit, 0).first) out.push_back(j.job_id());
    return out;
  };
  using V = std::vector<std::string>;
  EXPECT_EQ(ids({.name = "cow*"}), (V{"ab78", "ab34", "ab12"}));
  EXPECT_EQ(ids({.name = "COW?"}), (V{"ab78"}));
  EXPECT_EQ(ids({.name = "c_w"}), (V{"ef90"}));         // `_` is no wildcard: not "cow"
  EXPECT_EQ(ids({.name = "*100%"}), (V{"cd56"}));
  EXPECT_EQ(ids({.name = "*10%"}), (V{}));              // `%` is no wildcard either
  EXPECT_EQ(ids({.id_prefix = "ab"}), (V{"ab78", "ab34", "ab12"}));
  EXPECT_EQ(ids({.id_prefix = "ab3"}), (V{"ab34"}));
  EXPECT_EQ(ids({.id_prefix = "a_"}), (V{}));
  EXPECT_EQ(ids({.owner = std::string("alice"), .name = "cow*", .id_prefix = "ab"}), (V{"ab34", "ab12"}));
  store.jobs().cancel_job("ab12", 10);
  EXPECT_EQ(ids({.states = {v1::JOB_STATE_CANCELLED}, .name = "cow*"}), (V{"ab12"}));
  auto [first, next] = store.jobs().list_jobs({.name = "c*"}, 2, 0);
  ASSERT_EQ(first.size(), 2u);
  ASSERT_NE(next, 0);
  EXPECT_EQ(store.jobs().list_jobs({.name = "c*"}, 10, next).first.size(), 3u);  // ab34, cd56, ab12
}

}  // namespace
}  // namespace farm

namespace farm {
namespace {

// A quarantined worker's results for running jobs are not kept: its done tiles go back to the
// queue with their stats taken out, and so do the tiles it has running. Finished jobs and other
// workers' tiles are left alone.
TEST_P(JobStoreTest, QuarantiningAWorkerTakesBackWhatItRenderedForRunningJobs) {
  JobStore store(connect());
  store.jobs().add_job(make_job("a", 0, 4), 1);
  store.jobs().add_job(make_job("done", -1, 1), 1);
  v1::TileStats stats;
  stats.set_samples(10);
  stats.set_render_ms(5.0);
  const BatchSize two = [](const std::string&, int) { return 2; };
  auto liar = store.units().claim_next_batch("liar", 2, two);      // a: tiles 0 and 1
  auto honest = store.units().claim_next_batch("honest", 2);       // a: tile 2
  auto running = store.units().claim_next_batch("liar", 2);        // a: tile 3
  ASSERT_TRUE(liar && honest && running);
  ASSERT_EQ(liar->count, 2u);
  ASSERT_TRUE(store.units().batch_done("a", liar->first, liar->count, stats, "liar"));
  ASSERT_TRUE(store.units().batch_done("a", honest->first, 1, stats, "honest"));
  auto finished = store.units().claim_next_batch("liar", 3);
  ASSERT_TRUE(finished && finished->job_id == "done");
  ASSERT_TRUE(store.units().batch_done("done", 0, 1, stats, "liar"));
  ASSERT_TRUE(store.frames().frame_merged("done", 0));
  ASSERT_EQ(store.jobs().finish_job("done", v1::JOB_STATE_SUCCEEDED, "", "", 4).state(), v1::JOB_STATE_SUCCEEDED);
  EXPECT_EQ(store.jobs().get_job("a")->stats().samples(), 20u);

  const std::vector<UnitBatch> taken = store.units().quarantine_worker("liar");
  ASSERT_EQ(taken.size(), 1u);
  EXPECT_EQ(taken[0].job_id, "a");
  EXPECT_EQ(taken[0].first, 0u);
  EXPECT_EQ(taken[0].count, 2u);
  EXPECT_EQ(taken[0].rect, (Rect{0, 0, 32, 16}));
  const v1::Job a = *store.jobs().get_job("a");
  EXPECT_EQ(a.tiles_done(), 1u);
  EXPECT_EQ(a.tiles_rendered(), 3u);  // results accepted over the job's life
  EXPECT_EQ(a.stats().samples(), 10u);
  EXPECT_EQ(a.stats().render_ms(), 5.0);
  const std::vector<UnitRecord> tiles = store.units().tiles("a");
  EXPECT_EQ(tiles[0].state, TileState::Queued);
  EXPECT_EQ(tiles[1].state, TileState::Queued);
  EXPECT_EQ(tiles[2].state, TileState::Done);
  EXPECT_EQ(tiles[3].state, TileState::Queued);  // was running on the liar
  EXPECT_EQ(tiles[3].attempts, 0);
  // Its answer for tile 3, late, is refused; the finished job stays as it was.
  EXPECT_FALSE(store.units().batch_done("a", 3, 1, stats, "liar"));
  EXPECT_EQ(store.jobs().get_job("done")->tiles_done(), 1u);
  EXPECT_TRUE(store.units().quarantine_worker("liar").empty());
}

// A late answer from a worker whose tiles were taken back does not touch the worker that has
// them now; the job succeeds only while every tile is done.
TEST_P(JobStoreTest, BatchOperationsActOnlyOnTheirWorkersTilesAndSuccessNeedsEveryTileDone) {
  JobStore store(connect());
  store.jobs().add_job(make_job("a", 0, 2), 1);
  auto first = store.units().claim_next_batch("w1", 2);
  ASSERT_TRUE(first);
  store.units().batch_requeue("a", first->first, 1, "w1");
  auto again = store.units().claim_next_batch("w2", 3);
  ASSERT_TRUE(again && again->first == first->first);
  store.units().batch_requeue("a", first->first, 1, "w1");  // w1's, late: w2 keeps the tile
  EXPECT_FALSE(store.units().batch_failed("a", first->first, 1, "late", 3, 4, "w1").will_retry);
  EXPECT_EQ(store.units().tiles("a")[0].state, TileState::Running);
  EXPECT_FALSE(store.units().batch_done("a", first->first, 1, {}, "w1"));
  EXPECT_TRUE(store.units().batch_done("a", first->first, 1, {}, "w2"));
  EXPECT_EQ(store.jobs().finish_job("a", v1::JOB_STATE_SUCCEEDED, "", "", 5).state(), v1::JOB_STATE_RUNNING);
  auto last = store.units().claim_next_batch("w2", 6);
  ASSERT_TRUE(last && store.units().batch_done("a", last->first, 1, {}, "w2"));
  // Every tile done, but the frame not merged: not yet.
  EXPECT_EQ(store.jobs().finish_job("a", v1::JOB_STATE_SUCCEEDED, "", "", 7).state(), v1::JOB_STATE_RUNNING);
  ASSERT_TRUE(store.frames().frame_merged("a", 0));
  EXPECT_EQ(store.jobs().finish_job("a", v1::JOB_STATE_SUCCEEDED, "", "", 7).state(), v1::JOB_STATE_SUCCEEDED);
}

}  // namespace
}  // namespace farm

namespace farm {
namespace {

// A batch whose result file turned out damaged at the merge goes back to the queue in one step:
// its tiles queued without an attempt, its stats out of the job's, the job still running; a final
// job is left alone.
TEST_P(JobStoreTest, RequeuedPartsAreQueuedAgainWithoutAnAttemptAndTheJobStaysActive) {
  JobStore store(connect());
  store.jobs().add_job(make_job("a", 0, 3), 1);
  v1::TileStats stats;
  stats.set_samples(10);
  const BatchSize two = [](const std::string&, int) { return 2; };
  auto first = store.units().claim_next_batch("w", 2, two);  // tiles 0 and 1
  auto last = store.units().claim_next_batch("w", 2);        // tile 2
  ASSERT_TRUE(first && last);
  ASSERT_TRUE(store.units().batch_done("a", first->first, first->count, stats, "w"));
  ASSERT_TRUE(store.units().batch_done("a", last->first, last->count, stats, "w"));
  ASSERT_EQ(store.jobs().get_job("a")->tiles_done(), 3u);

  const std::vector<UnitBatch> taken = store.units().requeue_parts("a", {0, 99});
  ASSERT_EQ(taken.size(), 1u);  // part 99 holds no done tiles
  EXPECT_EQ(taken[0].first, 0u);
  EXPECT_EQ(taken[0].count, 2u);
  EXPECT_EQ(taken[0].rect, (Rect{0, 0, 32, 16}));
  const v1::Job a = *store.jobs().get_job("a");
  EXPECT_EQ(a.state(), v1::JOB_STATE_RUNNING);
  EXPECT_EQ(a.tiles_done(), 1u);
  EXPECT_EQ(a.tiles_rendered(), 3u);
  EXPECT_EQ(a.stats().samples(), 10u);
  const std::vector<UnitRecord> tiles = store.units().tiles("a");
  EXPECT_EQ(tiles[0].state, TileState::Queued);
  EXPECT_EQ(tiles[0].attempts, 0);
  EXPECT_EQ(tiles[1].state, TileState::Queued);
  EXPECT_EQ(tiles[2].state, TileState::Done);
  // Not SUCCEEDED while they are queued; rendered again, the job can finish.
  EXPECT_EQ(store.jobs().finish_job("a", v1::JOB_STATE_SUCCEEDED, "", "", 3).state(), v1::JOB_STATE_RUNNING);
  auto again = store.units().claim_next_batch("w", 4, two);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->first, 0u);
  EXPECT_EQ(again->count, 2u);
  ASSERT_TRUE(store.units().batch_done("a", again->first, again->count, stats, "w"));
  ASSERT_TRUE(store.frames().frame_merged("a", 0));
  EXPECT_EQ(store.jobs().finish_job("a", v1::JOB_STATE_SUCCEEDED, "", "", 5).state(), v1::JOB_STATE_SUCCEEDED);
  EXPECT_TRUE(store.units().requeue_parts("a", {0}).empty());
  EXPECT_EQ(store.jobs().get_job("a")->tiles_done(), 3u);
}

// Tiles go in 128 rows a statement: a job of 140 (a full statement and a short one) keeps every
// tile, in unit order, with its frame, pass and rectangle.
TEST_P(JobStoreTest, AJobOfManyUnitsKeepsEveryTileInUnitOrder) {
  JobStore store(connect());
  NewJob j = make_job("many", 0, 10);
  j.frames = {3, 5, 7, 9, 11, 13, 15};
  j.frame_step = 2;
  j.passes = 2;
  const v1::Job job = store.jobs().add_job(j, 1);
  EXPECT_EQ(job.tiles_total(), 140u);
  EXPECT_EQ(job.frames_total(), 7u);
  const std::vector<UnitRecord> tiles = store.units().tiles("many");
  ASSERT_EQ(tiles.size(), 140u);
  for (std::uint32_t i = 0; i < tiles.size(); ++i) {
    EXPECT_EQ(tiles[i].index, i);
    EXPECT_EQ(tiles[i].frame, j.frames[i / 20]) << i;
    EXPECT_EQ(tiles[i].pass, static_cast<int>(i / 10 % 2)) << i;
    EXPECT_EQ(tiles[i].rect, j.tiles[i % 10]) << i;
    EXPECT_EQ(tiles[i].state, TileState::Queued);
  }
}

// Names, reasons and blobs go through either store as they are: quotes, question marks (the
// placeholders' character) and bytes that are not text.
TEST_P(JobStoreTest, TextAndBlobsRoundTripWhateverTheyHold) {
  JobStore store(connect());
  NewJob j = make_job("q?'1", 0, 1);
  j.name = "it's a \"job\" ? $1 ?2 -- not a comment";
  j.owner = "ünïcødé";
  std::string bytes;
  for (int b = 0; b < 256; ++b) bytes += static_cast<char>(b);
  j.spec.set_job_json(bytes.substr(32, 90));  // printable
  j.spec.add_assets()->set_sha256(std::string(64, 'f'));
  store.jobs().add_job(j, 1);
  const v1::Job job = *store.jobs().get_job("q?'1");
  EXPECT_EQ(job.name(), j.name);
  EXPECT_EQ(job.owner(), j.owner);
  EXPECT_EQ(store.jobs().get_spec("q?'1")->SerializeAsString(), j.spec.SerializeAsString());
  auto b = store.units().claim_next_batch("w'?", 2);
  ASSERT_TRUE(b);
  v1::TileStats stats;
  stats.set_samples(1ull << 40);  // past 32 bits
  ASSERT_TRUE(store.units().batch_done("q?'1", b->first, 1, stats, "w'?"));
  EXPECT_EQ(store.jobs().get_job("q?'1")->stats().samples(), 1ull << 40);
  EXPECT_EQ(store.units().tiles("q?'1")[0].worker, "w'?");
}

// A worker's error message is whatever bytes it sent: a NUL, bytes that are not UTF-8. It is
// recorded (PostgreSQL, whose text holds neither, keeps U+FFFD in their place) and the batch's
// attempt counted: no message can keep a batch running for ever.
TEST_P(JobStoreTest, AnErrorMessageOfAnyBytesIsRecordedAndItsAttemptCounted) {
  JobStore store(connect());
  store.jobs().add_job(make_job("a", 0, 1), 1);
  auto b = store.units().claim_next_batch("w", 2);
  ASSERT_TRUE(b);
  const std::string reason("bad \0 bytes \xff\xc0\x80 end", 19);
  const TileFailure failure = store.units().batch_failed("a", b->first, 1, reason, 3, 3, "w");
  EXPECT_TRUE(failure.will_retry);
  const UnitRecord tile = store.units().tiles("a")[0];
  EXPECT_EQ(tile.state, TileState::Queued);
  EXPECT_EQ(tile.attempts, 1);
  if (GetParam() == SqlDialect::SQLite) {
    EXPECT_EQ(tile.last_error, reason);
  } else {
    EXPECT_EQ(tile.last_error, "bad \xEF\xBF\xBD bytes \xEF\xBF\xBD\xEF\xBF\xBD\xEF\xBF\xBD end");
  }
}

// Several schedulers on one store: four claimers on two connections take batches from three jobs
// at once and mark them done. No tile goes to two of them, none is left, and every job's counts
// and stats add up (no update of one claimer lost under another's).
TEST_P(JobStoreTest, ClaimersOnSeveralConnectionsNeverShareATileAndLoseNoCount) {
  constexpr int kJobs = 3, kTiles = 40;
  {
    JobStore store(connect());
    for (int j = 0; j < kJobs; ++j) store.jobs().add_job(make_job(fmt::format("j{}", j), 0, kTiles), 1);
  }
  JobStore a(connect()), b(connect());
  std::mutex mutex;
  std::map<std::pair<std::string, std::uint32_t>, int> claimed;  // (job, tile) -> claims
  std::vector<std::string> errors;
  const auto claimer = [&](JobStore& store, const std::string& worker) {
    try {
      while (const std::optional<UnitBatch> batch =
                 store.units().claim_next_batch(worker, 2, [](const std::string&, int) { return 3; })) {
        {
          std::lock_guard lock(mutex);
          for (std::uint32_t i = 0; i < batch->count; ++i) ++claimed[{batch->job_id, batch->first + i}];
        }
        v1::TileStats stats;
        stats.set_samples(batch->count);
        if (!store.units().batch_done(batch->job_id, batch->first, batch->count, stats, worker)) {
          throw std::runtime_error(worker + ": a batch it claimed was not running on it");
        }
      }
    } catch (const std::exception& e) {
      std::lock_guard lock(mutex);
      errors.push_back(e.what());
    }
  };
  std::vector<std::thread> threads;
  threads.emplace_back(claimer, std::ref(a), "a1");
  threads.emplace_back(claimer, std::ref(a), "a2");
  threads.emplace_back(claimer, std::ref(b), "b1");
  threads.emplace_back(claimer, std::ref(b), "b2");
  for (std::thread& t : threads) t.join();
  EXPECT_TRUE(errors.empty()) << errors.front();
  EXPECT_EQ(claimed.size(), static_cast<std::size_t>(kJobs * kTiles));
  int shared = 0;
  for (const auto& [tile, claims] : claimed) shared += claims > 1 ? 1 : 0;
  EXPECT_EQ(shared, 0);
  for (int j = 0; j < kJobs; ++j) {
    const v1::Job job = *a.jobs().get_job(fmt::format("j{}", j));
    EXPECT_EQ(job.tiles_done(), static_cast<std::uint32_t>(kTiles));
    EXPECT_EQ(job.tiles_rendered(), static_cast<std::uint32_t>(kTiles));
    EXPECT_EQ(job.stats().samples(), static_cast<std::uint64_t>(kTiles));
  }
}

// Two schedulers on one store, each handing out tiles to a worker both call "w1". When the first
// one's lease runs out, the second queues its running tiles again (no attempt counted) and the
// first one's late answer is refused; the second's own tiles are never touched, nor is a lease
// still running.
TEST_P(JobStoreTest, AnExpiredSchedulersTilesComeBackWithoutAnAttemptAndItsLateAnswerIsRefused) {
  JobStore a(connect()), b(connect());
  a.leases().set_scheduler("a");
  b.leases().set_scheduler("b");
  a.jobs().add_job(make_job("j", 0, 4), 1);
  a.leases().hold_lease(1000);
  b.leases().hold_lease(5000);
  const auto a1 = a.units().claim_next_batch("w1", 10);
  const auto a2 = a.units().claim_next_batch("w1", 10);
  const auto b1 = b.units().claim_next_batch("w1", 10);
  ASSERT_TRUE(a1 && a2 && b1);
  EXPECT_FALSE(b.units().batch_done("j", a1->first, 1, {}, "w1"));  // not b's to mark
  EXPECT_TRUE(b.leases().reap_expired(999).empty());                 // a's lease still runs
  const std::vector<ReapedScheduler> reaped = b.leases().reap_expired(1001);
  ASSERT_EQ(reaped.size(), 1u);
  EXPECT_EQ(reaped[0].id, "a");
  EXPECT_EQ(reaped[0].tiles_queued_again, 2);
  EXPECT_TRUE(a.leases().reap_expired(1001).empty());  // gone with the first reaping
  std::vector<UnitRecord> tiles = b.units().tiles("j");
  EXPECT_EQ(tiles[a1->first].state, TileState::Queued);
  EXPECT_EQ(tiles[a2->first].state, TileState::Queued);
  EXPECT_EQ(tiles[a1->first].attempts + tiles[a1->first].lost_attempts, 0);
  EXPECT_EQ(tiles[b1->first].state, TileState::Running);
  EXPECT_FALSE(a.units().batch_done("j", a1->first, 1, {}, "w1"));  // the late answer
  EXPECT_TRUE(b.units().batch_done("j", b1->first, 1, {}, "w1"));
  // b renders the rest; a scheduler never reaps itself, whatever its lease says.
  EXPECT_TRUE(b.leases().reap_expired(999999).empty());
  while (const auto next = b.units().claim_next_batch("w1", 20)) ASSERT_TRUE(b.units().batch_done("j", next->first, 1, {}, "w1"));
  EXPECT_EQ(b.jobs().get_job("j")->tiles_done(), 4u);
  EXPECT_EQ(b.jobs().get_job("j")->tiles_rendered(), 4u);
}

// Two schedulers find the same frame complete, or the same job's frames all merged: one claims
// the merge (or the end), the other leaves it. A claim is its holder's again and again, is freed
// when a part of its frame is taken back, and dies with its holder's lease.
TEST_P(JobStoreTest, OneSchedulerClaimsEachMergeAndEndAndAClaimDiesWithItsLease) {
  JobStore a(connect()), b(connect());
  a.leases().set_scheduler("a");
  b.leases().set_scheduler("b");
  a.leases().hold_lease(1000);
  b.leases().hold_lease(5000);
  a.jobs().add_job(make_job("j", 0, 2), 1);
  EXPECT_TRUE(a.leases().claim_frame_merge("j", 0));
  EXPECT_FALSE(b.leases().claim_frame_merge("j", 0));
  EXPECT_TRUE(a.leases().claim_frame_merge("j", 0));  // still a's
  EXPECT_TRUE(b.leases().claim_frame_merge("j", 1));  // another frame, another claim
  EXPECT_TRUE(b.leases().claim_job_end("j"));
  EXPECT_FALSE(a.leases().claim_job_end("j"));
  EXPECT_FALSE(a.leases().claim_frame_merge("nothing", 0));  // no such job: nobody's

  // Frame 0's units done by a, then its part taken back: the merge is anybody's again.
  const auto t0 = a.units().claim_next_batch("w", 2), t1 = a.units().claim_next_batch("w", 2);
  ASSERT_TRUE(t0 && t1);
  ASSERT_TRUE(a.units().batch_done("j", t0->first, 1, {}, "w"));
  ASSERT_TRUE(a.units().batch_done("j", t1->first, 1, {}, "w"));
  ASSERT_EQ(a.units().requeue_parts("j", {t0->first}).size(), 1u);
  EXPECT_TRUE(b.leases().claim_frame_merge("j", 0));

  // a's lease runs out: what it held goes with it.
  EXPECT_TRUE(a.leases().claim_frame_merge("j", 2));
  EXPECT_FALSE(b.leases().claim_frame_merge("j", 2));
  ASSERT_EQ(b.leases().reap_expired(2000).size(), 1u);
  EXPECT_TRUE(b.leases().claim_frame_merge("j", 2));
}

// ---- Operator actions (issue #19) ----------------------------------------------------------------

TEST_P(JobStoreTest, APausedJobHandsOutNothingUntilResumedAndPriorityReordersTheQueue) {
  JobStore store(connect());
  store.jobs().add_job(make_job("a", 5, 3), 1);
  store.jobs().add_job(make_job("b", 0, 3), 2);
  EXPECT_TRUE(store.jobs().set_paused("a", true)->paused());
  EXPECT_TRUE(store.jobs().get_job("a")->paused());
  EXPECT_EQ(store.units().claim_next_batch("w", 3)->job_id, "b");  // a ranks first, but is paused
  EXPECT_FALSE(store.jobs().set_paused("a", false)->paused());
  EXPECT_EQ(store.units().claim_next_batch("w", 4)->job_id, "a");
  EXPECT_EQ(store.jobs().set_priority("b", 9)->priority(), 9);
  EXPECT_EQ(store.units().claim_next_batch("w", 5)->job_id, "b");  // now above a
  EXPECT_FALSE(store.jobs().set_paused("none", true));
  EXPECT_FALSE(store.jobs().set_priority("none", 1));
  // A final job is not paused: nothing would ever resume it.
  store.jobs().cancel_job("b", 6);
  EXPECT_FALSE(store.jobs().set_paused("b", true)->paused());
}

TEST_P(JobStoreTest, RetryQueuesTheUnitsNotDoneWithNoAttemptsAndKeepsTheDoneOnes) {
  JobStore store(connect());
  store.jobs().add_job(make_job("a", 0, 4), 1);
  const std::optional<UnitBatch> first = store.units().claim_next_batch("w", 2);
  ASSERT_TRUE(first);
  EXPECT_EQ(first->first, 0u);
  EXPECT_TRUE(first->started_job);  // the claim that started it says so, and only that one
  ASSERT_TRUE(store.units().batch_done("a", 0, 1, {}, "w"));
  const std::optional<UnitBatch> second = store.units().claim_next_batch("w", 3);
  ASSERT_TRUE(second);
  EXPECT_EQ(second->first, 1u);
  EXPECT_FALSE(second->started_job);
  ASSERT_EQ(store.units().claim_next_batch("w", 4)->first, 2u);  // running when the job fails
  const TileFailure f = store.units().batch_failed("a", 1, 1, "boom", 1, 5, "w");
  ASSERT_EQ(f.job.state(), v1::JOB_STATE_FAILED);

  const std::optional<RetriedJob> r = store.jobs().retry_job("a");
  ASSERT_TRUE(r && r->retried);
  EXPECT_EQ(r->units_queued, 3u);  // the failed one, the running one, the queued one
  EXPECT_EQ(r->job.state(), v1::JOB_STATE_RUNNING);  // a unit is done
  EXPECT_EQ(r->job.failure_reason(), "");
  EXPECT_EQ(r->job.tiles_done(), 1u);
  EXPECT_FALSE(r->job.has_finished_at());
  const std::vector<UnitRecord> tiles = store.units().tiles("a");
  EXPECT_EQ(tiles[0].state, TileState::Done);
  for (int i = 1; i < 4; ++i) {
    EXPECT_EQ(tiles[i].state, TileState::Queued) << i;
    EXPECT_EQ(tiles[i].attempts, 0) << i;
  }
  // Only those are handed out, and the job can succeed.
  for (std::uint32_t i = 1; i < 4; ++i) {
    const auto b = store.units().claim_next_batch("w", 6);
    ASSERT_TRUE(b);
    EXPECT_EQ(b->first, i);
    EXPECT_FALSE(b->started_job);  // retried with a unit done: running already
    ASSERT_TRUE(store.units().batch_done("a", i, 1, {}, "w"));
  }
  EXPECT_FALSE(store.units().claim_next_batch("w", 7));
  ASSERT_TRUE(store.frames().frame_merged("a", 0));
  EXPECT_EQ(store.jobs().finish_job("a", v1::JOB_STATE_SUCCEEDED, "", "", 8).state(), v1::JOB_STATE_SUCCEEDED);
  EXPECT_EQ(store.jobs().get_job("a")->tiles_rendered(), 4u);  // none rendered twice

  // Only a failed or cancelled job is retried.
  const std::optional<RetriedJob> again = store.jobs().retry_job("a");
  ASSERT_TRUE(again);
  EXPECT_FALSE(again->retried);
  EXPECT_EQ(again->job.state(), v1::JOB_STATE_SUCCEEDED);
  store.jobs().add_job(make_job("b", 0, 1), 9);
  EXPECT_FALSE(store.jobs().retry_job("b")->retried);
  EXPECT_FALSE(store.jobs().retry_job("none"));
  store.jobs().cancel_job("b", 10);
  EXPECT_EQ(store.jobs().retry_job("b")->job.state(), v1::JOB_STATE_QUEUED);  // nothing done: queued
  const std::optional<UnitBatch> restarted = store.units().claim_next_batch("w", 11);
  ASSERT_TRUE(restarted);
  EXPECT_EQ(restarted->job_id, "b");
  EXPECT_TRUE(restarted->started_job);
  EXPECT_EQ(store.jobs().get_job("b")->state(), v1::JOB_STATE_RUNNING);
}

TEST_P(JobStoreTest, DeleteRemovesAFinalJobWithEveryRowOfItAndRefusesAnActiveOne) {
  JobStore store(connect());
  store.jobs().add_job(make_job("a", 0, 2), 1);
  store.jobs().add_job(make_job("b", 0, 1), 2);
  EXPECT_EQ(store.jobs().delete_job("a"), std::optional<bool>(false));  // queued: cancel it first
  ASSERT_TRUE(store.units().claim_next_batch("w", 3));
  ASSERT_TRUE(store.units().batch_done("a", 0, 1, {}, "w"));
  v1::JobEvent e;
  *e.mutable_job() = *store.jobs().get_job("a");
  e.mutable_updated()->set_change("paused");
  store.log().append_log(e, 4, true);
  store.jobs().cancel_job("a", 10);
  EXPECT_TRUE(store.jobs().finished_before(10, 100).empty());
  EXPECT_EQ(store.jobs().finished_before(11, 100), std::vector<std::string>{"a"});

  EXPECT_EQ(store.jobs().delete_job("a"), std::optional<bool>(true));
  EXPECT_FALSE(store.jobs().get_job("a"));
  EXPECT_TRUE(store.units().tiles("a").empty());
  EXPECT_TRUE(store.log().job_log("a", 0, 10).empty());
  EXPECT_FALSE(store.jobs().delete_job("a"));  // gone
  EXPECT_TRUE(store.jobs().finished_before(11, 100).empty());
  // The other job is untouched, and a new one reuses nothing of the old.
  EXPECT_EQ(store.units().claim_next_batch("w", 11)->job_id, "b");
  store.jobs().add_job(make_job("a", 0, 2), 12);
  EXPECT_EQ(store.jobs().get_job("a")->tiles_done(), 0u);
  EXPECT_TRUE(store.log().job_log("a", 0, 10).empty());
}

TEST_P(JobStoreTest, TheLogKeepsEventsInOrderInPagesAndPastItsLimitOnlyTheEssentialOnes) {
  JobStore store(connect());
  store.jobs().add_job(make_job("a", 0, 1), 1);
  v1::JobEvent e;
  *e.mutable_job() = *store.jobs().get_job("a");
  for (int frame = 0; frame < 4; ++frame) {
    e.mutable_frame_finished()->set_frame(frame);
    store.log().append_log(e, 100 + frame, false, 3);  // the fourth is past the limit
  }
  e.mutable_updated()->set_change("resumed");
  store.log().append_log(e, 200, true, 3);  // essential: kept all the same
  v1::JobEvent other = e;
  other.mutable_job()->set_job_id("none");
  store.log().append_log(other, 300, true, 3);  // no such job: nothing

  bool more = false;
  const std::vector<v1::JobLogEntry> first = store.log().job_log("a", 0, 2, &more);
  ASSERT_EQ(first.size(), 2u);
  EXPECT_TRUE(more);
  EXPECT_EQ(first[0].number(), 1u);
  EXPECT_EQ(first[0].event().frame_finished().frame(), 0);
  EXPECT_EQ(first[1].event().frame_finished().frame(), 1);
  EXPECT_EQ(first[1].at().seconds() * 1000 + first[1].at().nanos() / 1000000, 101);
  const std::vector<v1::JobLogEntry> rest = store.log().job_log("a", first.back().number(), 10, &more);
  EXPECT_FALSE(more);
  ASSERT_EQ(rest.size(), 2u);
  EXPECT_EQ(rest[0].event().frame_finished().frame(), 2);
  EXPECT_EQ(rest[1].number(), 4u);
  EXPECT_EQ(rest[1].event().updated().change(), "resumed");
}

INSTANTIATE_TEST_SUITE_P(BothStores, JobStoreTest, ::testing::ValuesIn(test::kBothStores),
                         [](const auto& p) { return test::store_name(p.param); });

}  // namespace
}  // namespace farm
