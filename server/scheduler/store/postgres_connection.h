#pragma once
// The job store's PostgreSQL connection, through libpq: a farm of several schedulers keeps its
// state in one PostgreSQL database (`--store postgresql://user@host:port/db`).
//
// Statements are written as for SQLite (`?`, `?N`) and numbered `$N` here; each kept statement is
// prepared on the server at its first run, with the types of that run's bindings (integers as
// bigint, text, bytea). Results come as text and are read back into the store's types.
//
// A connection that broke (the server restarted, the network dropped) is made again before the
// next statement, its prepared statements with it; the statement that found it broken throws
// StoreUnavailable, so that the caller retries later instead of failing a job.
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "server/common/service_error.h"
#include "server/scheduler/store/sql_connection.h"

struct pg_conn;

namespace farm {

// The store's server could not be reached, or the connection broke under a statement: UNAVAILABLE
// to a client, which may try again.
class StoreUnavailable : public ServiceError {
 public:
  explicit StoreUnavailable(const std::string& message) : ServiceError(grpc::StatusCode::UNAVAILABLE, message) {}
};

// Whether `location` names a PostgreSQL store (postgresql:// or postgres://).
bool is_postgres_url(const std::string& location);

// `sql` with SQLite's placeholders numbered as PostgreSQL's: `?N` becomes `$N`, and a bare `?`
// the next number after the largest so far (SQLite's own rule). Quoted text is left alone.
std::string postgres_placeholders(const std::string& sql);

class PostgresConnection : public SqlConnection {
 public:
  // Connects to `url` (a libpq connection URI). StoreUnavailable when the server cannot be
  // reached within its connect_timeout (10 s unless the URL says otherwise).
  explicit PostgresConnection(const std::string& url);
  ~PostgresConnection() override;
  PostgresConnection(const PostgresConnection&) = delete;
  PostgresConnection& operator=(const PostgresConnection&) = delete;

  SqlDialect dialect() const override { return SqlDialect::PostgreSQL; }
  std::string describe() const override { return described_; }
  void exec(const std::string& sql) override;
  SqlStatement& prepared(const std::string& sql) override;
  std::unique_ptr<SqlStatement> prepare_once(const std::string& sql) override;
  void begin(bool flushed) override;
  void commit() override;
  void rollback() noexcept override;

  // The live connection, made again if it broke; StoreUnavailable when that fails. For the
  // statements of this file.
  pg_conn* live();
  // LISTEN/NOTIFY, for the schedulers of one store to tell each other what happened. `notify`
  // sends each of `payloads` on `channel` in one statement; `listen` subscribes this connection
  // to `channel`, which a connection made again must do again (see generation()).
  void notify(const std::string& channel, const std::vector<std::string>& payloads);
  void listen(const std::string& channel);
  // The payloads of the notifications that arrived, waiting up to `wait` for the first one; none
  // when it passed. StoreUnavailable when the connection is lost (made again at the next call).
  std::vector<std::string> notifications(std::chrono::milliseconds wait);

  // Increases each time the connection is made again: a statement prepared on the server in an
  // earlier generation is prepared again.
  std::uint64_t generation() const { return generation_; }

 private:
  std::string url_, described_;
  pg_conn* conn_ = nullptr;
  std::uint64_t generation_ = 0;
  bool in_transaction_ = false;
  std::uint64_t next_name_ = 0;
  std::map<std::string, std::unique_ptr<SqlStatement>> statements_;
};

}  // namespace farm
