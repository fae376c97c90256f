// The PostgreSQL fixture the store tests of issue #18 stand on: a real server from Debian's
// package comes up in a temporary folder, answers SQL through libpq at url(), keeps what was
// written across a stop and a start (a store that goes away and comes back), and is gone, its
// folder removed, when the fixture is.
#include <gtest/gtest.h>
#include <libpq-fe.h>

#include <filesystem>
#include <memory>
#include <string>

#include "tests/support/postgres_server.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

struct PgConnCloser {
  void operator()(PGconn* c) const { PQfinish(c); }
};
using Connection = std::unique_ptr<PGconn, PgConnCloser>;

// The first value of `sql`'s first row, or "ERROR: ..." with the server's words.
std::string query_one(PGconn* c, const std::string& sql) {
  PGresult* r = PQexec(c, sql.c_str());
  std::string out;
  const ExecStatusType status = PQresultStatus(r);
  if (status == PGRES_TUPLES_OK && PQntuples(r) > 0) {
    out = PQgetvalue(r, 0, 0);
  } else if (status != PGRES_COMMAND_OK && status != PGRES_TUPLES_OK) {
    out = std::string("ERROR: ") + PQresultErrorMessage(r);
  }
  PQclear(r);
  return out;
}

TEST(PostgresServerTest, AnswersThroughLibpqKeepsItsDataAcrossARestartAndIsGoneAfterwards) {
  std::string url;
  fs::path data;
  {
    test::PostgresServer server;
    ASSERT_TRUE(server.problem().empty()) << server.problem();
    url = server.url();
    data = server.data_dir();
    {
      Connection c(PQconnectdb(url.c_str()));
      ASSERT_EQ(PQstatus(c.get()), CONNECTION_OK) << PQerrorMessage(c.get()) << server.log();
      EXPECT_EQ(query_one(c.get(), "SELECT 40 + 2"), "42");
      EXPECT_EQ(query_one(c.get(), "SELECT current_database()"), "farm");
      EXPECT_EQ(query_one(c.get(), "CREATE TABLE kept (v TEXT)"), "");
      EXPECT_EQ(query_one(c.get(), "INSERT INTO kept VALUES ('before the restart')"), "");
    }
    ASSERT_TRUE(server.stop()) << server.problem();
    EXPECT_NE(PQping(url.c_str()), PQPING_OK) << "still answering after stop()";
    ASSERT_TRUE(server.start()) << server.problem();
    Connection c(PQconnectdb(url.c_str()));
    ASSERT_EQ(PQstatus(c.get()), CONNECTION_OK) << PQerrorMessage(c.get()) << server.log();
    EXPECT_EQ(query_one(c.get(), "SELECT v FROM kept"), "before the restart");
  }
  EXPECT_NE(PQping(url.c_str()), PQPING_OK) << "still answering after the fixture went";
  EXPECT_FALSE(fs::exists(data)) << data;
}

}  // namespace
}  // namespace farm
