#include "tests/support/store_locations.h"

#include <fmt/format.h>
#include <libpq-fe.h>

#include <atomic>
#include <memory>

#include "tests/support/postgres_server.h"

namespace farm {
void PrintTo(SqlDialect dialect, std::ostream* os) { *os << test::store_name(dialect); }
}  // namespace farm

namespace farm::test {

namespace {

// One server for the test process: starting one costs about half a second, a database nothing.
PostgresServer& shared_server() {
  static const std::unique_ptr<PostgresServer> server = std::make_unique<PostgresServer>();
  return *server;
}

// `url` (…/farm) naming database `name` instead.
std::string with_database(const std::string& url, const std::string& name) {
  return url.substr(0, url.rfind('/') + 1) + name;
}

}  // namespace

std::string store_name(SqlDialect dialect) { return dialect == SqlDialect::SQLite ? "SQLite" : "PostgreSQL"; }

StoreLocation::StoreLocation(SqlDialect dialect) {
  if (dialect == SqlDialect::SQLite) {
    location_ = (dir_ / "jobs.db").string();
    return;
  }
  PostgresServer& server = shared_server();
  if (!server.problem().empty()) {
    problem_ = "PostgreSQL did not start: " + server.problem();
    return;
  }
  server_ = &server;
  static std::atomic<int> next{0};
  const std::string name = fmt::format("store_{}", next++);
  PGconn* c = PQconnectdb(server.url().c_str());
  PGresult* r = PQexec(c, fmt::format("CREATE DATABASE {}", name).c_str());
  if (PQresultStatus(r) != PGRES_COMMAND_OK) problem_ = fmt::format("CREATE DATABASE {}: {}", name, PQerrorMessage(c));
  PQclear(r);
  PQfinish(c);
  location_ = with_database(server.url(), name);
}

NewJob one_row_job(const std::string& id, int tiles) {
  NewJob j;
  j.id = id;
  j.name = id;
  j.spec.set_job_json("{}");
  j.scene_hash = std::string(64, 'a');
  j.engine = "raster";
  j.width = 16 * tiles;
  j.height = 16;
  for (int i = 0; i < tiles; ++i) j.tiles.push_back({16 * i, 0, 16 * i + 16, 16});
  return j;
}

}  // namespace farm::test
