#pragma once
// The tiles a scheduler's store shows running (handed to a worker, no result kept yet), read from
// its jobs.db beside the scheduler process: SQLite in WAL mode lets this reader see the last
// committed state while the scheduler writes, and across its restarts. For tests that count the
// units in flight at the moment they kill something.
#include <cstdint>
#include <filesystem>
#include <set>
#include <string>
#include <utility>

struct sqlite3;

namespace farm::test {

// (job id, tile index)
using Unit = std::pair<std::string, std::uint32_t>;

class RunningTiles {
 public:
  // Opens the store at `db` (jobs.db), which the scheduler must have created.
  explicit RunningTiles(const std::filesystem::path& db);
  ~RunningTiles();
  RunningTiles(const RunningTiles&) = delete;
  RunningTiles& operator=(const RunningTiles&) = delete;

  // The units running on the worker at `address` (the scheduler's worker ids end with it).
  std::set<Unit> on_worker(const std::string& address) const;
  // The units running on any worker.
  std::set<Unit> all() const;

 private:
  std::set<Unit> query(const std::string& address_or_empty) const;
  sqlite3* db_ = nullptr;
};

}  // namespace farm::test
