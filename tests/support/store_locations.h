#pragma once
// A fresh, empty job store for one test, of either kind the scheduler takes (`--store`): a SQLite
// file in a temporary folder, or a database of its own on a real PostgreSQL server
// (postgres_server.h) that the test process starts once, at the first test that asks, and stops
// at exit. Store tests are written once and run on both (INSTANTIATE_TEST_SUITE_P over
// kBothStores).
#include <gtest/gtest.h>

#include <memory>
#include <ostream>
#include <string>

#include "server/scheduler/store/job_store.h"
#include "server/scheduler/store/sql_connection.h"
#include "tests/support/temp_dir.h"

namespace farm {
// Readable in failure messages (gtest finds PrintTo by argument-dependent lookup).
void PrintTo(SqlDialect dialect, std::ostream* os);
}  // namespace farm

namespace farm::test {

class PostgresServer;

// A job of `tiles` 16x16 tiles in one row, as a store keeps it (its text is "{}"): for tests of
// the store itself, which never parse it.
NewJob one_row_job(const std::string& id, int tiles);

inline constexpr SqlDialect kBothStores[] = {SqlDialect::SQLite, SqlDialect::PostgreSQL};

// "SQLite" or "PostgreSQL", for test names.
std::string store_name(SqlDialect dialect);

class StoreLocation {
 public:
  explicit StoreLocation(SqlDialect dialect);
  // Why the store could not be made (the PostgreSQL server did not start); empty when it was.
  const std::string& problem() const { return problem_; }
  // What connect_store and `farm scheduler --store` take: a file, or a postgresql:// URL.
  const std::string& location() const { return location_; }
  // The server under a PostgreSQL store (stop and start it to take the store away); null for SQLite.
  PostgresServer* server() const { return server_; }

 private:
  TempDir dir_;
  std::string location_, problem_;
  PostgresServer* server_ = nullptr;
};

// The fixture of a store test written once for both stores (INSTANTIATE_TEST_SUITE_P over
// kBothStores): each test gets a fresh store of its parameter's kind.
class StoreTest : public ::testing::TestWithParam<SqlDialect> {
 protected:
  void SetUp() override { ASSERT_TRUE(where_.problem().empty()) << where_.problem(); }
  std::unique_ptr<SqlConnection> connect() const { return connect_store(where_.location()); }

  StoreLocation where_{GetParam()};
};

}  // namespace farm::test
