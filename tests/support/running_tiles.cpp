#include "tests/support/running_tiles.h"

#include <sqlite3.h>

#include <stdexcept>

namespace farm::test {

RunningTiles::RunningTiles(const std::filesystem::path& db) {
  if (sqlite3_open_v2(db.c_str(), &db_, SQLITE_OPEN_READWRITE, nullptr) != SQLITE_OK) {
    const std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    throw std::runtime_error("cannot open " + db.string() + ": " + message);
  }
  // The scheduler's transactions are short; a read waits for one rather than failing.
  sqlite3_busy_timeout(db_, 5000);
}

RunningTiles::~RunningTiles() { sqlite3_close(db_); }

std::set<Unit> RunningTiles::on_worker(const std::string& address) const { return query(address); }

std::set<Unit> RunningTiles::all() const { return query(""); }

std::set<Unit> RunningTiles::query(const std::string& address) const {
  // Worker ids are "w<N>-<address>" (WorkerRegistry::add).
  sqlite3_stmt* s = nullptr;
  const char* sql =
      "SELECT j.id, t.idx FROM tiles t JOIN jobs j ON t.job_seq = j.seq WHERE t.state = 1 "
      "AND (?1 = '' OR t.worker LIKE '%-' || ?1)";
  if (sqlite3_prepare_v2(db_, sql, -1, &s, nullptr) != SQLITE_OK) {
    throw std::runtime_error(std::string("running tiles: ") + sqlite3_errmsg(db_));
  }
  sqlite3_bind_text(s, 1, address.c_str(), -1, SQLITE_TRANSIENT);
  std::set<Unit> units;
  int rc = 0;
  while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
    units.emplace(reinterpret_cast<const char*>(sqlite3_column_text(s, 0)),
                  static_cast<std::uint32_t>(sqlite3_column_int64(s, 1)));
  }
  const std::string error = rc == SQLITE_DONE ? "" : sqlite3_errmsg(db_);
  sqlite3_finalize(s);
  if (!error.empty()) throw std::runtime_error("running tiles: " + error);
  return units;
}

}  // namespace farm::test
