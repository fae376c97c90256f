#pragma once
// The job store's SQLite connection: one database file (or ":memory:"), WAL mode, statements
// prepared once and kept. SQLite's "no room" (SQLITE_FULL, or an I/O error for ENOSPC or EDQUOT)
// is thrown as DiskFull naming the database's folder, so that callers wait for space instead of
// failing a job; any other error as std::runtime_error.
#include <filesystem>
#include <map>
#include <memory>
#include <string>

#include "server/scheduler/store/sql_connection.h"

struct sqlite3;

namespace farm {

class SqliteConnection : public SqlConnection {
 public:
  // Opens (creating) `file`. std::runtime_error naming it when SQLite cannot.
  explicit SqliteConnection(const std::filesystem::path& file);
  ~SqliteConnection() override;
  SqliteConnection(const SqliteConnection&) = delete;
  SqliteConnection& operator=(const SqliteConnection&) = delete;

  SqlDialect dialect() const override { return SqlDialect::SQLite; }
  std::string describe() const override { return file_.string(); }
  void exec(const std::string& sql) override;
  SqlStatement& prepared(const std::string& sql) override;
  std::unique_ptr<SqlStatement> prepare_once(const std::string& sql) override;
  void begin(bool flushed) override;
  void commit() override;
  void rollback() noexcept override;

 private:
  std::filesystem::path file_;
  sqlite3* db_ = nullptr;
  std::map<std::string, std::unique_ptr<SqlStatement>> statements_;
};

}  // namespace farm
