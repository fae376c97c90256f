#pragma once
// The narrow SQL interface the job store is written against, with two implementations: SQLite
// (sqlite_connection.h, the embedded default) and PostgreSQL through libpq (postgres_connection.h,
// a farm of several schedulers). The store's statements are written once, in the SQL both accept,
// with SQLite's placeholders (`?` and `?N`); the PostgreSQL side numbers them as `$N`. What the two
// cannot share (the schema's types, its upgrades, row locks) asks `dialect()`.
//
// A connection is not thread-safe: the store calls it under its own mutex.
#include <cstdint>
#include <memory>
#include <string>

namespace farm {

enum class SqlDialect { SQLite, PostgreSQL };

// One statement: bind its parameters (1-based), then step through its rows (columns 0-based).
class SqlStatement {
 public:
  virtual ~SqlStatement() = default;
  virtual void bind_int(int index, std::int64_t value) = 0;
  virtual void bind_text(int index, const std::string& value) = 0;
  virtual void bind_blob(int index, const std::string& value) = 0;
  // Runs the statement on the first call; true while a row is there to read.
  virtual bool step() = 0;
  // Forgets the rows and the bindings: the statement can be bound and run again.
  virtual void reset() = 0;
  virtual std::int64_t column_int(int column) const = 0;
  virtual bool column_is_null(int column) const = 0;
  virtual std::string column_text(int column) const = 0;
  virtual std::string column_blob(int column) const = 0;
  // Rows the last run inserted, updated or deleted.
  virtual std::int64_t changes() const = 0;
};

class SqlConnection {
 public:
  virtual ~SqlConnection() = default;
  virtual SqlDialect dialect() const = 0;
  // Where the store is, for messages: a file, or a URL without its password.
  virtual std::string describe() const = 0;
  // Statements without parameters, several separated by semicolons.
  virtual void exec(const std::string& sql) = 0;
  // A statement prepared once and kept for the connection's life (the store's fixed queries).
  virtual SqlStatement& prepared(const std::string& sql) = 0;
  // A statement for one use (text that varies with a filter).
  virtual std::unique_ptr<SqlStatement> prepare_once(const std::string& sql) = 0;
  // A transaction that takes the store's write lock at once (SQLite's BEGIN IMMEDIATE), so that
  // two writers never deadlock half-way. `flushed`: its commit waits until the server has it on
  // disk; false for what a crash of the database server may lose, the farm repairing it by
  // rendering again (PostgreSQL's synchronous_commit off for it; SQLite in WAL mode with
  // synchronous=NORMAL never waits for the disk at commit anyway).
  virtual void begin(bool flushed = true) = 0;
  virtual void commit() = 0;
  virtual void rollback() noexcept = 0;
};

// A statement in use: fluent binds, and reset on scope exit so that the next user of a kept
// statement finds it fresh.
class Query {
 public:
  explicit Query(SqlStatement& s) : s_(s) {}
  ~Query() { s_.reset(); }
  Query(const Query&) = delete;
  Query& operator=(const Query&) = delete;

  Query& bind(int i, std::int64_t v) { s_.bind_int(i, v); return *this; }
  Query& bind(int i, int v) { s_.bind_int(i, v); return *this; }
  Query& bind(int i, std::uint32_t v) { s_.bind_int(i, static_cast<std::int64_t>(v)); return *this; }
  Query& bind(int i, const std::string& v) { s_.bind_text(i, v); return *this; }
  Query& bind_blob(int i, const std::string& v) { s_.bind_blob(i, v); return *this; }
  bool step() { return s_.step(); }
  void run() {
    while (step()) {
    }
  }
  void reset() { s_.reset(); }
  std::int64_t changes() const { return s_.changes(); }
  std::int64_t i64(int c) const { return s_.column_int(c); }
  int i32(int c) const { return static_cast<int>(s_.column_int(c)); }
  bool is_null(int c) const { return s_.column_is_null(c); }
  std::string text(int c) const { return s_.column_text(c); }
  std::string blob(int c) const { return s_.column_blob(c); }

 private:
  SqlStatement& s_;
};

// begin() ... commit(), rolled back when the scope is left by an exception.
class SqlTransaction {
 public:
  enum class Commit { Flushed, Unflushed };  // SqlConnection::begin's `flushed`
  explicit SqlTransaction(SqlConnection& db, Commit commit = Commit::Flushed) : db_(db) {
    db_.begin(commit == Commit::Flushed);
  }
  ~SqlTransaction() {
    if (!done_) db_.rollback();
  }
  SqlTransaction(const SqlTransaction&) = delete;
  SqlTransaction& operator=(const SqlTransaction&) = delete;
  void commit() {
    db_.commit();
    done_ = true;
  }

 private:
  SqlConnection& db_;
  bool done_ = false;
};

}  // namespace farm
