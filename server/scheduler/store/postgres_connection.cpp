#include "server/scheduler/store/postgres_connection.h"

#include <fmt/format.h>
#include <poll.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <vector>

#include "renderer/util/utf8_text.h"
#include "server/scheduler/store/libpq_library.h"

namespace farm {

namespace {

// Type OIDs of the bindings (pg_type.dat): the store binds only these three.
constexpr Oid kInt8Oid = 20;
constexpr Oid kTextOid = 25;
constexpr Oid kByteaOid = 17;

std::string server_message(pg_conn* conn, const PGresult* result) {
  std::string message = result ? libpq().resultErrorMessage(result) : "";
  if (message.empty()) message = libpq().errorMessage(conn);
  while (!message.empty() && std::isspace(static_cast<unsigned char>(message.back()))) message.pop_back();
  return message;
}

// The failure of `result` (null: libpq could not even send): StoreUnavailable when the connection
// is gone, std::runtime_error naming the store and the statement otherwise.
[[noreturn]] void throw_postgres_error(pg_conn* conn, const PGresult* result, const std::string& where,
                                       const std::string& sql) {
  const std::string message = server_message(conn, result);
  if (libpq().status(conn) != CONNECTION_OK) {
    throw StoreUnavailable(fmt::format("job store {}: connection lost: {}", where, message));
  }
  const char* state = result ? libpq().resultErrorField(result, PG_DIAG_SQLSTATE) : nullptr;
  throw std::runtime_error(fmt::format("job store {}: {}{}: {}", where, message,
                                       state ? fmt::format(" (SQLSTATE {})", state) : "", sql));
}

struct ResultDeleter {
  void operator()(PGresult* r) const { libpq().clear(r); }
};
using Result = std::unique_ptr<PGresult, ResultDeleter>;

// `text` as a PostgreSQL text value can hold it: a NUL byte (which would end the value there) and
// bytes that are not UTF-8 (which the server refuses, failing the whole statement) become U+FFFD.
// The store's text is ours or checked UTF-8 already; a worker's error message is not, and must
// not stop its batch from being recorded.
std::string storable_text(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t length = text[i] == '\0' ? 0 : utf8_character_bytes(text, i);
    if (length > 0) {
      out.append(text, i, length);
      i += length;
    } else {
      out += "\xEF\xBF\xBD";
      ++i;
    }
  }
  return out;
}

void check(pg_conn* conn, const Result& result, const std::string& where, const std::string& sql) {
  const ExecStatusType status = result ? libpq().resultStatus(result.get()) : PGRES_FATAL_ERROR;
  if (status != PGRES_COMMAND_OK && status != PGRES_TUPLES_OK) throw_postgres_error(conn, result.get(), where, sql);
}

class PostgresStatement : public SqlStatement {
 public:
  // `name` empty: run unnamed (PQexecParams), for a statement used once.
  PostgresStatement(PostgresConnection& db, std::string sql, std::string name)
      : db_(db), sql_(postgres_placeholders(sql)), name_(std::move(name)) {}

  void bind_int(int i, std::int64_t v) override { set(i, std::to_string(v), kInt8Oid, false); }
  void bind_text(int i, const std::string& v) override { set(i, storable_text(v), kTextOid, false); }
  void bind_blob(int i, const std::string& v) override { set(i, v, kByteaOid, true); }

  bool step() override {
    if (!result_) {
      execute();
      row_ = 0;
    } else {
      ++row_;
    }
    return row_ < libpq().ntuples(result_.get());
  }
  void reset() override {
    result_.reset();
    row_ = 0;
    values_.clear();
  }
  std::int64_t column_int(int c) const override {
    const char* v = value(c);
    if (!v || !*v) return 0;
    if (*v == 't') return 1;  // booleans read as SQLite's 1 and 0
    if (*v == 'f') return 0;
    std::int64_t out = 0;
    const char* end = v + std::char_traits<char>::length(v);
    // SUM over bigint is numeric: "12" parses whole; anything else is a store bug, read as far as
    // it is an integer.
    std::from_chars(v, end, out);
    return out;
  }
  bool column_is_null(int c) const override { return libpq().getisnull(result_.get(), row_, c) != 0; }
  std::string column_text(int c) const override {
    const char* v = value(c);
    return v ? std::string(v, static_cast<std::size_t>(libpq().getlength(result_.get(), row_, c))) : std::string();
  }
  std::string column_blob(int c) const override {
    const char* v = value(c);
    if (!v) return {};
    std::size_t length = 0;
    unsigned char* bytes = libpq().unescapeBytea(reinterpret_cast<const unsigned char*>(v), &length);
    if (!bytes) throw std::runtime_error("job store: out of memory reading a bytea column");
    std::string out(reinterpret_cast<const char*>(bytes), length);
    libpq().freemem(bytes);
    return out;
  }
  std::int64_t changes() const override {
    const char* n = result_ ? libpq().cmdTuples(result_.get()) : "";
    std::int64_t out = 0;
    std::from_chars(n, n + std::char_traits<char>::length(n), out);
    return out;
  }

 private:
  struct Param {
    std::string value;
    Oid type = 0;
    bool binary = false;
  };

  void set(int i, std::string v, Oid type, bool binary) {
    if (i < 1) throw std::invalid_argument("job store: bind index below 1");
    if (values_.size() < static_cast<std::size_t>(i)) values_.resize(static_cast<std::size_t>(i));
    values_[static_cast<std::size_t>(i - 1)] = {std::move(v), type, binary};
  }

  const char* value(int c) const {
    if (!result_ || row_ >= libpq().ntuples(result_.get()) || c >= libpq().nfields(result_.get())) return nullptr;
    if (libpq().getisnull(result_.get(), row_, c)) return nullptr;
    return libpq().getvalue(result_.get(), row_, c);
  }

  void execute() {
    pg_conn* conn = db_.live();
    const int n = static_cast<int>(values_.size());
    std::vector<Oid> types(values_.size());
    std::vector<const char*> values(values_.size());
    std::vector<int> lengths(values_.size()), formats(values_.size());
    for (std::size_t i = 0; i < values_.size(); ++i) {
      types[i] = values_[i].type;
      values[i] = values_[i].value.c_str();
      lengths[i] = static_cast<int>(values_[i].value.size());
      formats[i] = values_[i].binary ? 1 : 0;
    }
    if (name_.empty()) {
      result_.reset(libpq().execParams(conn, sql_.c_str(), n, types.data(), values.data(), lengths.data(), formats.data(), 0));
    } else {
      if (prepared_generation_ != db_.generation() + 1) {
        Result prepared(libpq().prepare(conn, name_.c_str(), sql_.c_str(), n, types.data()));
        check(conn, prepared, db_.describe(), sql_);
        prepared_generation_ = db_.generation() + 1;  // 0: never prepared
      }
      result_.reset(libpq().execPrepared(conn, name_.c_str(), n, values.data(), lengths.data(), formats.data(), 0));
    }
    check(conn, result_, db_.describe(), sql_);
  }

  PostgresConnection& db_;
  std::string sql_, name_;
  std::vector<Param> values_;
  Result result_;
  int row_ = 0;
  std::uint64_t prepared_generation_ = 0;
};

void ignore_notice(void*, const char*) {}

// "postgresql://user@host:port/db" of the live connection: no password, for messages and logs.
std::string describe_connection(pg_conn* conn) {
  const char* host = libpq().host(conn);
  const std::string h = host && *host ? host : "localhost";
  return fmt::format("postgresql://{}@{}:{}/{}", libpq().user(conn), h.find(':') != std::string::npos ? "[" + h + "]" : h,
                     libpq().port(conn), libpq().db(conn));
}

}  // namespace

bool is_postgres_url(const std::string& location) {
  return location.starts_with("postgresql://") || location.starts_with("postgres://");
}

std::string postgres_placeholders(const std::string& sql) {
  std::string out;
  out.reserve(sql.size() + 16);
  int largest = 0;
  bool quoted = false;
  for (std::size_t i = 0; i < sql.size(); ++i) {
    const char c = sql[i];
    if (c == '\'') quoted = !quoted;  // '' inside a literal toggles twice: still quoted
    if (quoted || c != '?') {
      out += c;
      continue;
    }
    std::size_t j = i + 1;
    while (j < sql.size() && std::isdigit(static_cast<unsigned char>(sql[j]))) ++j;
    int number = 0;
    if (j > i + 1) {
      std::from_chars(sql.data() + i + 1, sql.data() + j, number);
    } else {
      number = largest + 1;
    }
    largest = std::max(largest, number);
    out += fmt::format("${}", number);
    i = j - 1;
  }
  return out;
}

PostgresConnection::PostgresConnection(const std::string& url) : url_(url) {
  // Ours come before dbname, so that the URL's own settings win: a bounded connect, and a link
  // that stops answering noticed within about 10 s (TCP keepalives and user timeout) instead of a
  // statement waiting for ever under the store's lock. client_encoding comes after: the store
  // always sends UTF-8.
  const char* keywords[] = {"connect_timeout", "application_name", "keepalives_idle", "keepalives_interval",
                            "keepalives_count", "tcp_user_timeout", "dbname", "client_encoding", nullptr};
  const char* values[] = {"10", "farm", "5", "2", "3", "10000", url.c_str(), "UTF8", nullptr};
  conn_ = libpq().connectdbParams(keywords, values, 1);
  if (!conn_ || libpq().status(conn_) != CONNECTION_OK) {
    const std::string message = conn_ ? server_message(conn_, nullptr) : "out of memory";
    libpq().finish(conn_);
    conn_ = nullptr;
    // The URL may hold a password: name the store without it.
    const std::size_t at = url.find('@');
    const std::string where = at == std::string::npos ? url : url.substr(0, url.find("://") + 3) + "..." + url.substr(at);
    throw StoreUnavailable(fmt::format("cannot reach job store {}: {}", where, message));
  }
  libpq().setNoticeProcessor(conn_, ignore_notice, nullptr);
  described_ = describe_connection(conn_);
}

PostgresConnection::~PostgresConnection() {
  statements_.clear();
  libpq().finish(conn_);
}

pg_conn* PostgresConnection::live() {
  if (libpq().status(conn_) == CONNECTION_OK) return conn_;
  // Never made again under a transaction: its first statements went with the old connection.
  if (in_transaction_) throw StoreUnavailable(fmt::format("job store {}: connection lost", described_));
  libpq().reset(conn_);
  if (libpq().status(conn_) != CONNECTION_OK) {
    throw StoreUnavailable(fmt::format("job store {}: cannot reconnect: {}", described_, server_message(conn_, nullptr)));
  }
  libpq().setNoticeProcessor(conn_, ignore_notice, nullptr);
  ++generation_;
  return conn_;
}

void PostgresConnection::exec(const std::string& sql) {
  pg_conn* conn = live();
  Result result(libpq().exec(conn, sql.c_str()));
  check(conn, result, described_, sql);
}

SqlStatement& PostgresConnection::prepared(const std::string& sql) {
  if (auto it = statements_.find(sql); it != statements_.end()) return *it->second;
  auto statement = std::make_unique<PostgresStatement>(*this, sql, fmt::format("farm_{}", next_name_++));
  return *statements_.emplace(sql, std::move(statement)).first->second;
}

std::unique_ptr<SqlStatement> PostgresConnection::prepare_once(const std::string& sql) {
  return std::make_unique<PostgresStatement>(*this, sql, std::string());
}

void PostgresConnection::begin(bool flushed) {
  exec(flushed ? "BEGIN" : "BEGIN; SET LOCAL synchronous_commit TO OFF");
  in_transaction_ = true;
}

void PostgresConnection::commit() {
  exec("COMMIT");
  in_transaction_ = false;
}

void PostgresConnection::rollback() noexcept {
  in_transaction_ = false;
  if (libpq().status(conn_) != CONNECTION_OK) return;  // the transaction went with the connection
  libpq().clear(libpq().exec(conn_, "ROLLBACK"));
}

void PostgresConnection::notify(const std::string& channel, const std::vector<std::string>& payloads) {
  if (payloads.empty()) return;
  // One round trip for the lot: the payloads joined by newlines (which none holds) and split
  // again by the server. Notifications of one transaction arrive in the order sent.
  std::string joined;
  for (const std::string& p : payloads) {
    if (p.empty() || p.find('\n') != std::string::npos) throw std::invalid_argument("notify: empty payload or one with a newline");
    if (!joined.empty()) joined += '\n';
    joined += p;
  }
  Query(prepared("SELECT pg_notify(?1, payload) FROM unnest(string_to_array(?2, E'\\n')) AS payload"))
      .bind(1, channel)
      .bind(2, joined)
      .run();
}

void PostgresConnection::listen(const std::string& channel) {
  pg_conn* conn = live();
  char* name = libpq().escapeIdentifier(conn, channel.data(), channel.size());
  if (!name) throw std::runtime_error(fmt::format("job store {}: cannot quote channel '{}'", described_, channel));
  const std::string sql = fmt::format("LISTEN {}", name);
  libpq().freemem(name);
  exec(sql);
}

std::vector<std::string> PostgresConnection::notifications(std::chrono::milliseconds wait) {
  pg_conn* conn = live();
  std::vector<std::string> out;
  const auto drain = [&] {
    while (PGnotify* n = libpq().notifies(conn)) {
      out.emplace_back(n->extra);
      libpq().freemem(n);
    }
  };
  drain();  // those a statement's reply brought along
  if (!out.empty()) return out;
  pollfd fd{.fd = libpq().socket(conn), .events = POLLIN, .revents = 0};
  if (fd.fd < 0) throw StoreUnavailable(fmt::format("job store {}: connection lost", described_));
  if (::poll(&fd, 1, static_cast<int>(wait.count())) <= 0) return out;
  // A broken link (the server gone, keepalives unanswered) shows as readable and fails here;
  // PQstatus then says so, and live() makes the connection again.
  if (!libpq().consumeInput(conn) || libpq().status(conn) != CONNECTION_OK) {
    throw StoreUnavailable(fmt::format("job store {}: connection lost: {}", described_, server_message(conn, nullptr)));
  }
  drain();
  return out;
}

}  // namespace farm
