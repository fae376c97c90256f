// The job store on PostgreSQL beyond what every store does (job_store_test.cpp runs those on
// both): SQLite's placeholders numbered as PostgreSQL's, a server that goes away under the store
// and comes back, and schedulers that open one new database at the same moment.
#include <gtest/gtest.h>
#include <libpq-fe.h>

#include <thread>

#include "server/scheduler/store/job_store.h"
#include "server/scheduler/store/postgres_connection.h"
#include "tests/support/postgres_server.h"
#include "tests/support/store_downgrade.h"
#include "tests/support/store_locations.h"

namespace farm {
namespace {

using test::one_row_job;

TEST(PostgresStoreTest, PlaceholdersAreNumberedAsSqliteNumbersThemAndQuotedTextIsLeftAlone) {
  EXPECT_EQ(postgres_placeholders("a = ? AND b = ?"), "a = $1 AND b = $2");
  EXPECT_EQ(postgres_placeholders("a = ?1 AND b = ?2 AND c = ?1"), "a = $1 AND b = $2 AND c = $1");
  // A bare ? after ?3 is 4, SQLite's rule.
  EXPECT_EQ(postgres_placeholders("a = ?3 AND b = ?"), "a = $3 AND b = $4");
  EXPECT_EQ(postgres_placeholders("a = '?' AND b = 'it''s ?' AND c = ?"), "a = '?' AND b = 'it''s ?' AND c = $1");
  EXPECT_EQ(postgres_placeholders("SELECT 1"), "SELECT 1");
}

TEST(PostgresStoreTest, AnUnreachableServerIsStoreUnavailableNamingItWithoutThePassword) {
  // A port nothing listens on: connection refused at once.
  try {
    connect_store("postgresql://farm:secret@127.0.0.1:1/farm");
    FAIL() << "connected to nothing";
  } catch (const StoreUnavailable& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("127.0.0.1:1/farm"), std::string::npos) << what;
    EXPECT_EQ(what.find("secret"), std::string::npos) << what;
  }
}

// The server stops under an open store: each call meanwhile is StoreUnavailable and changes
// nothing; once the server is back, the same store object carries on (it connects again and
// prepares its statements again) and finds everything committed before.
TEST(PostgresStoreTest, AServerThatGoesAwayIsStoreUnavailableAndTheStoreCarriesOnWhenItReturns) {
  test::StoreLocation where(SqlDialect::PostgreSQL);
  ASSERT_TRUE(where.problem().empty()) << where.problem();
  JobStore store(connect_store(where.location()));
  store.jobs().add_job(one_row_job("a", 3), 1);
  auto first = store.units().claim_next_batch("w", 2);
  ASSERT_TRUE(first);

  ASSERT_TRUE(where.server()->stop()) << where.server()->problem();
  EXPECT_THROW(store.units().batch_done("a", first->first, 1, {}, "w"), StoreUnavailable);
  EXPECT_THROW(store.units().claim_next_batch("w", 3), StoreUnavailable);
  EXPECT_THROW(store.jobs().add_job(one_row_job("b", 2), 3), StoreUnavailable);
  ASSERT_TRUE(where.server()->start()) << where.server()->problem();

  const v1::Job a = *store.jobs().get_job("a");
  EXPECT_EQ(a.state(), v1::JOB_STATE_RUNNING);
  EXPECT_EQ(a.tiles_done(), 0u);
  EXPECT_FALSE(store.jobs().get_job("b"));  // its transaction never committed
  EXPECT_TRUE(store.units().batch_done("a", first->first, 1, {}, "w"));  // still running on w
  auto second = store.units().claim_next_batch("w", 4);
  ASSERT_TRUE(second);
  EXPECT_EQ(second->first, 1u);
  EXPECT_EQ(store.jobs().get_job("a")->tiles_done(), 1u);
}

// Schedulers of one farm start together: the schema is made once, under a lock, and every one of
// them opens the store.
TEST(PostgresStoreTest, SchedulersOpeningOneNewDatabaseAtOnceMakeTheSchemaOnce) {
  test::StoreLocation where(SqlDialect::PostgreSQL);
  ASSERT_TRUE(where.problem().empty()) << where.problem();
  constexpr int kSchedulers = 4;
  std::vector<std::string> errors(kSchedulers);
  std::vector<std::thread> threads;
  for (int i = 0; i < kSchedulers; ++i) {
    threads.emplace_back([&, i] {
      try {
        JobStore store(connect_store(where.location()));
        store.jobs().add_job(one_row_job("job" + std::to_string(i), 1), 1);
      } catch (const std::exception& e) {
        errors[static_cast<std::size_t>(i)] = e.what();
      }
    });
  }
  for (std::thread& t : threads) t.join();
  for (const std::string& e : errors) EXPECT_EQ(e, "");
  JobStore store(connect_store(where.location()));
  EXPECT_EQ(store.jobs().list_jobs(JobFilter{}, 10, 0).first.size(), static_cast<std::size_t>(kSchedulers));
  PGconn* c = PQconnectdb(where.location().c_str());
  PGresult* r = PQexec(c, "SELECT COUNT(*) FROM schema_version");
  ASSERT_EQ(PQresultStatus(r), PGRES_TUPLES_OK) << PQerrorMessage(c);
  EXPECT_STREQ(PQgetvalue(r, 0, 0), "1");
  PQclear(r);
  PQfinish(c);
}

// A scheduler opens a store at this version while another is mid-transaction, writing tiles and
// jobs: the open takes no table lock, so it neither waits for that transaction nor deadlocks with
// it. (It ran the schema's "CREATE INDEX IF NOT EXISTS" before, whose share locks wait on the
// writer's: PostgreSQL ended one of two schedulers started together with "deadlock detected".)
// The opener's lock_timeout turns a wait into an error rather than a hang.
TEST(PostgresStoreTest, OpeningACurrentStoreTakesNoTableLockAWriterHolds) {
  test::StoreLocation where(SqlDialect::PostgreSQL);
  ASSERT_TRUE(where.problem().empty()) << where.problem();
  { JobStore made(connect_store(where.location())); }
  PGconn* writer = PQconnectdb(where.location().c_str());
  for (const char* sql : {"BEGIN", "UPDATE tiles SET state = state", "UPDATE jobs SET state = state"}) {
    PGresult* r = PQexec(writer, sql);
    ASSERT_EQ(PQresultStatus(r), PGRES_COMMAND_OK) << sql << ": " << PQerrorMessage(writer);
    PQclear(r);
  }
  const std::string impatient = where.location() + "?options=-c%20lock_timeout%3D5000";
  try {
    JobStore store(connect_store(impatient));
    store.jobs().add_job(one_row_job("opened", 1), 1);
    EXPECT_TRUE(store.jobs().get_job("opened"));
  } catch (const std::exception& e) {
    ADD_FAILURE() << "opening beside a writer: " << e.what();
  }
  PQfinish(writer);
}

// The first upgrade written for both stores, on PostgreSQL: a version 6 database (no scheduler
// leases) is upgraded in place, its jobs kept and its running tiles queued again.
TEST(PostgresStoreTest, AVersion6StoreIsUpgradedInPlace) {
  test::StoreLocation where(SqlDialect::PostgreSQL);
  ASSERT_TRUE(where.problem().empty()) << where.problem();
  {
    JobStore store(connect_store(where.location()));
    store.jobs().add_job(one_row_job("a", 3), 1);
    ASSERT_TRUE(store.units().claim_next_batch("w", 2));
    ASSERT_TRUE(store.units().batch_done("a", 0, 1, {}, "w"));
    ASSERT_TRUE(store.units().claim_next_batch("w", 3));  // running when the version went back
  }
  PGconn* c = PQconnectdb(where.location().c_str());
  for (const std::string& sql : test::back_to_version(6)) {
    PGresult* r = PQexec(c, sql.c_str());
    EXPECT_EQ(PQresultStatus(r), PGRES_COMMAND_OK) << sql << ": " << PQerrorMessage(c);
    PQclear(r);
  }
  JobStore store(connect_store(where.location()));
  PGresult* r = PQexec(c, "SELECT version FROM schema_version");
  ASSERT_EQ(PQresultStatus(r), PGRES_TUPLES_OK) << PQerrorMessage(c);
  EXPECT_STREQ(PQgetvalue(r, 0, 0), "10");
  PQclear(r);
  PQfinish(c);
  const std::vector<UnitRecord> tiles = store.units().tiles("a");
  ASSERT_EQ(tiles.size(), 3u);
  EXPECT_EQ(tiles[0].state, TileState::Done);
  EXPECT_EQ(tiles[1].state, TileState::Queued);
  store.leases().set_scheduler("s");
  store.leases().hold_lease(100);
  EXPECT_EQ(store.units().claim_next_batch("w", 4)->first, 1u);
}

}  // namespace
}  // namespace farm
