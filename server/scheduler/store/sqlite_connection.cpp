#include "server/scheduler/store/sqlite_connection.h"

#include <fmt/format.h>
#include <sqlite3.h>

#include <stdexcept>

#include "server/common/disk_full.h"

namespace farm {

namespace {

[[noreturn]] void throw_sqlite_error(sqlite3* db, const std::string& context) {
  const std::string message = fmt::format("job store: {}{}", context.empty() ? "" : context + ": ", sqlite3_errmsg(db));
  const int code = sqlite3_extended_errcode(db) & 0xff;
  if (code == SQLITE_FULL || (code == SQLITE_IOERR && is_disk_full_errno(sqlite3_system_errno(db)))) {
    const char* file = sqlite3_db_filename(db, "main");
    throw DiskFull(file && *file ? std::filesystem::path(file).parent_path() : std::filesystem::path("."), message);
  }
  throw std::runtime_error(message);
}

class SqliteStatement : public SqlStatement {
 public:
  SqliteStatement(sqlite3* db, const std::string& sql, unsigned flags) : db_(db) {
    if (sqlite3_prepare_v3(db_, sql.c_str(), -1, flags, &s_, nullptr) != SQLITE_OK) {
      throw std::runtime_error(fmt::format("job store: {}: {}", sqlite3_errmsg(db_), sql));
    }
  }
  ~SqliteStatement() override { sqlite3_finalize(s_); }
  SqliteStatement(const SqliteStatement&) = delete;
  SqliteStatement& operator=(const SqliteStatement&) = delete;

  void bind_int(int i, std::int64_t v) override { check(sqlite3_bind_int64(s_, i, v)); }
  void bind_text(int i, const std::string& v) override {
    check(sqlite3_bind_text(s_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT));
  }
  void bind_blob(int i, const std::string& v) override {
    check(sqlite3_bind_blob(s_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT));
  }
  bool step() override {
    const int rc = sqlite3_step(s_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) {
      changes_ = sqlite3_changes64(db_);
      return false;
    }
    throw_sqlite_error(db_, "");
  }
  void reset() override {
    sqlite3_reset(s_);
    sqlite3_clear_bindings(s_);
  }
  std::int64_t column_int(int c) const override { return sqlite3_column_int64(s_, c); }
  bool column_is_null(int c) const override { return sqlite3_column_type(s_, c) == SQLITE_NULL; }
  std::string column_text(int c) const override {
    const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(s_, c));
    return p ? std::string(p, static_cast<std::size_t>(sqlite3_column_bytes(s_, c))) : std::string();
  }
  std::string column_blob(int c) const override {
    const auto* p = static_cast<const char*>(sqlite3_column_blob(s_, c));
    return p ? std::string(p, static_cast<std::size_t>(sqlite3_column_bytes(s_, c))) : std::string();
  }
  std::int64_t changes() const override { return changes_; }

 private:
  void check(int rc) {
    if (rc != SQLITE_OK) throw_sqlite_error(db_, "");
  }
  sqlite3* db_;
  sqlite3_stmt* s_ = nullptr;
  std::int64_t changes_ = 0;
};

}  // namespace

SqliteConnection::SqliteConnection(const std::filesystem::path& file) : file_(file) {
  if (sqlite3_open_v2(file.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX,
                      nullptr) != SQLITE_OK) {
    const std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    throw std::runtime_error(fmt::format("cannot open job store {}: {}", file.string(), message));
  }
  sqlite3_busy_timeout(db_, 5000);
  exec("PRAGMA journal_mode=WAL");
  // WAL + NORMAL: a committed transaction survives a process crash (kill -9); only a power loss
  // may drop the last few, which the tiles' files and a re-render would repair.
  exec("PRAGMA synchronous=NORMAL");
  exec("PRAGMA foreign_keys=ON");
}

SqliteConnection::~SqliteConnection() {
  statements_.clear();  // finalized before the close
  sqlite3_close(db_);
}

void SqliteConnection::exec(const std::string& sql) {
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, nullptr) != SQLITE_OK) throw_sqlite_error(db_, "");
}

SqlStatement& SqliteConnection::prepared(const std::string& sql) {
  if (auto it = statements_.find(sql); it != statements_.end()) return *it->second;
  auto statement = std::make_unique<SqliteStatement>(db_, sql, SQLITE_PREPARE_PERSISTENT);
  return *statements_.emplace(sql, std::move(statement)).first->second;
}

std::unique_ptr<SqlStatement> SqliteConnection::prepare_once(const std::string& sql) {
  return std::make_unique<SqliteStatement>(db_, sql, 0);
}

void SqliteConnection::begin(bool /*flushed: WAL + NORMAL never waits*/) {
  if (sqlite3_exec(db_, "BEGIN IMMEDIATE", nullptr, nullptr, nullptr) != SQLITE_OK) {
    throw_sqlite_error(db_, "BEGIN IMMEDIATE");
  }
}

void SqliteConnection::commit() {
  if (sqlite3_exec(db_, "COMMIT", nullptr, nullptr, nullptr) != SQLITE_OK) throw_sqlite_error(db_, "COMMIT");
}

void SqliteConnection::rollback() noexcept { sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr); }

}  // namespace farm
