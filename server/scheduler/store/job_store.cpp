// The SQLite job store in one file (over 500 lines on purpose): the schema, its upgrade from
// older versions and every statement on it change together, and a reader checks a query against
// the schema without leaving the file.
#include "server/scheduler/store/job_store.h"

#include <fmt/format.h>
#include <google/protobuf/util/time_util.h>
#include <sqlite3.h>

#include <chrono>
#include <stdexcept>

#include "server/common/disk_full.h"

namespace farm {

namespace {

constexpr int kSchemaVersion = 6;

constexpr const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS schema_version (version INTEGER NOT NULL);
CREATE TABLE IF NOT EXISTS jobs (
  seq INTEGER PRIMARY KEY AUTOINCREMENT,
  id TEXT NOT NULL UNIQUE,
  name TEXT NOT NULL,
  spec BLOB NOT NULL,
  scene_hash TEXT NOT NULL,
  engine TEXT NOT NULL,
  width INTEGER NOT NULL,
  height INTEGER NOT NULL,
  priority INTEGER NOT NULL DEFAULT 0,
  state INTEGER NOT NULL,
  submitted_ms INTEGER NOT NULL,
  started_ms INTEGER NOT NULL DEFAULT 0,
  finished_ms INTEGER NOT NULL DEFAULT 0,
  failure_reason TEXT NOT NULL DEFAULT '',
  tiles_total INTEGER NOT NULL,
  tiles_done INTEGER NOT NULL DEFAULT 0,
  tile_failures INTEGER NOT NULL DEFAULT 0,
  tiles_rendered INTEGER NOT NULL DEFAULT 0,
  stats BLOB NOT NULL DEFAULT x'',
  validation TEXT NOT NULL DEFAULT '',
  owner TEXT NOT NULL DEFAULT '',
  frame_first INTEGER NOT NULL DEFAULT 0,
  frame_last INTEGER NOT NULL DEFAULT 0,
  frame_step INTEGER NOT NULL DEFAULT 1,
  frames_total INTEGER NOT NULL DEFAULT 1,
  frames_done INTEGER NOT NULL DEFAULT 0,
  passes INTEGER NOT NULL DEFAULT 1
);
CREATE INDEX IF NOT EXISTS jobs_by_state ON jobs (state, priority, seq);
CREATE TABLE IF NOT EXISTS tiles (
  job_seq INTEGER NOT NULL REFERENCES jobs (seq),
  idx INTEGER NOT NULL,
  x0 INTEGER NOT NULL, y0 INTEGER NOT NULL, x1 INTEGER NOT NULL, y1 INTEGER NOT NULL,
  state INTEGER NOT NULL DEFAULT 0,
  attempts INTEGER NOT NULL DEFAULT 0,
  lost_attempts INTEGER NOT NULL DEFAULT 0,
  last_error TEXT NOT NULL DEFAULT '',
  worker TEXT NOT NULL DEFAULT '',
  part INTEGER NOT NULL DEFAULT 0,
  frame INTEGER NOT NULL DEFAULT 0,
  pass INTEGER NOT NULL DEFAULT 0,
  PRIMARY KEY (job_seq, idx)
);
CREATE INDEX IF NOT EXISTS tiles_by_state ON tiles (state, job_seq, idx);
CREATE TABLE IF NOT EXISTS frames (
  job_seq INTEGER NOT NULL REFERENCES jobs (seq),
  frame INTEGER NOT NULL,
  PRIMARY KEY (job_seq, frame)
);
CREATE TABLE IF NOT EXISTS parts (
  job_seq INTEGER NOT NULL REFERENCES jobs (seq),
  part INTEGER NOT NULL,
  stats BLOB NOT NULL,
  PRIMARY KEY (job_seq, part)
);
)sql";

constexpr const char* kJobColumns =
    "seq, id, name, scene_hash, engine, width, height, priority, state, submitted_ms, started_ms, "
    "finished_ms, failure_reason, tiles_total, tiles_done, tile_failures, tiles_rendered, stats, "
    "validation, owner, frame_first, frame_last, frame_step, frames_total, frames_done, passes";

const std::string kActiveSql =
    fmt::format("({}, {})", static_cast<int>(v1::JOB_STATE_QUEUED),
                static_cast<int>(v1::JOB_STATE_RUNNING));

// The store's error for the last failed call on `db`: DiskFull (naming the database's folder)
// when SQLite found no room (SQLITE_FULL, or an I/O error for ENOSPC or EDQUOT), so that callers
// wait for space instead of failing a job; std::runtime_error otherwise.
[[noreturn]] void throw_store_error(sqlite3* db, const std::string& context) {
  const std::string message = fmt::format("job store: {}{}", context.empty() ? "" : context + ": ", sqlite3_errmsg(db));
  const int code = sqlite3_extended_errcode(db) & 0xff;
  if (code == SQLITE_FULL || (code == SQLITE_IOERR && is_disk_full_errno(sqlite3_system_errno(db)))) {
    const char* file = sqlite3_db_filename(db, "main");
    throw DiskFull(file && *file ? std::filesystem::path(file).parent_path() : std::filesystem::path("."), message);
  }
  throw std::runtime_error(message);
}

// A prepared statement from the store's cache, reset (bindings cleared) at scope exit so the next
// user finds it fresh. Preparing is most of the cost of the scheduler's small queries.
class Stmt {
 public:
  Stmt(sqlite3* db, sqlite3_stmt* s) : db_(db), s_(s) {}
  ~Stmt() {
    sqlite3_reset(s_);
    sqlite3_clear_bindings(s_);
  }
  Stmt(const Stmt&) = delete;
  Stmt& operator=(const Stmt&) = delete;

  Stmt& bind(int i, std::int64_t v) { return check(sqlite3_bind_int64(s_, i, v)); }
  Stmt& bind(int i, int v) { return check(sqlite3_bind_int(s_, i, v)); }
  Stmt& bind(int i, std::uint32_t v) { return bind(i, static_cast<std::int64_t>(v)); }
  Stmt& bind(int i, const std::string& v) {
    return check(sqlite3_bind_text(s_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT));
  }
  Stmt& bind_blob(int i, const std::string& v) {
    return check(sqlite3_bind_blob(s_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT));
  }
  // True while rows come.
  bool step() {
    const int rc = sqlite3_step(s_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    throw_store_error(db_, "");
  }
  void run() {
    while (step()) {
    }
  }
  void reset() {
    sqlite3_reset(s_);
    sqlite3_clear_bindings(s_);
  }
  std::int64_t i64(int c) const { return sqlite3_column_int64(s_, c); }
  int i32(int c) const { return sqlite3_column_int(s_, c); }
  bool is_null(int c) const { return sqlite3_column_type(s_, c) == SQLITE_NULL; }
  std::string text(int c) const {
    const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(s_, c));
    return p ? std::string(p, static_cast<std::size_t>(sqlite3_column_bytes(s_, c))) : std::string();
  }
  std::string blob(int c) const {
    const auto* p = static_cast<const char*>(sqlite3_column_blob(s_, c));
    return p ? std::string(p, static_cast<std::size_t>(sqlite3_column_bytes(s_, c))) : std::string();
  }

 private:
  Stmt& check(int rc) {
    if (rc != SQLITE_OK) throw_store_error(db_, "");
    return *this;
  }
  sqlite3* db_;
  sqlite3_stmt* s_ = nullptr;
};

// BEGIN IMMEDIATE ... COMMIT, rolled back when the scope is left by an exception.
class Transaction {
 public:
  explicit Transaction(sqlite3* db) : db_(db) { exec("BEGIN IMMEDIATE"); }
  ~Transaction() {
    if (!done_) sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
  }
  void commit() {
    exec("COMMIT");
    done_ = true;
  }

 private:
  void exec(const char* sql) {
    if (sqlite3_exec(db_, sql, nullptr, nullptr, nullptr) != SQLITE_OK) throw_store_error(db_, sql);
  }
  sqlite3* db_;
  bool done_ = false;
};

google::protobuf::Timestamp timestamp(std::int64_t ms) {
  return google::protobuf::util::TimeUtil::MillisecondsToTimestamp(ms);
}

v1::Job job_from_row(const Stmt& s) {
  v1::Job job;
  job.set_job_id(s.text(1));
  job.set_name(s.text(2));
  job.set_scene_hash(s.text(3));
  job.set_engine(s.text(4));
  job.set_width(s.i32(5));
  job.set_height(s.i32(6));
  job.set_priority(s.i32(7));
  job.set_state(static_cast<v1::JobState>(s.i32(8)));
  const std::int64_t submitted = s.i64(9), started = s.i64(10), finished = s.i64(11);
  *job.mutable_submitted_at() = timestamp(submitted);
  if (started) *job.mutable_started_at() = timestamp(started);
  if (finished) *job.mutable_finished_at() = timestamp(finished);
  if (started && finished) job.set_render_seconds(static_cast<double>(finished - started) / 1e3);
  job.set_failure_reason(s.text(12));
  job.set_tiles_total(static_cast<std::uint32_t>(s.i64(13)));
  job.set_tiles_done(static_cast<std::uint32_t>(s.i64(14)));
  job.set_tile_failures(static_cast<std::uint32_t>(s.i64(15)));
  job.set_tiles_rendered(static_cast<std::uint32_t>(s.i64(16)));
  job.mutable_stats()->ParseFromString(s.blob(17));
  job.set_validation(s.text(18));
  job.set_owner(s.text(19));
  job.set_frame_first(s.i32(20));
  job.set_frame_last(s.i32(21));
  job.set_frame_step(s.i32(22));
  job.set_frames_total(static_cast<std::uint32_t>(s.i64(23)));
  job.set_frames_done(static_cast<std::uint32_t>(s.i64(24)));
  job.set_passes(static_cast<std::uint32_t>(s.i64(25)));
  return job;
}

// The counters and times of `t` taken out of `sum` again (threads, a maximum, stays).
void subtract_stats(v1::TileStats& sum, const v1::TileStats& t) {
  const auto less = [](std::uint64_t a, std::uint64_t b) { return a > b ? a - b : 0; };
  sum.set_samples(less(sum.samples(), t.samples()));
  sum.set_invalid_samples(less(sum.invalid_samples(), t.invalid_samples()));
  sum.set_fragments(less(sum.fragments(), t.fragments()));
  sum.set_rays(less(sum.rays(), t.rays()));
  sum.set_render_ms(std::max(0.0, sum.render_ms() - t.render_ms()));
  sum.set_cpu_ms(std::max(0.0, sum.cpu_ms() - t.cpu_ms()));
  sum.set_prepare_ms(std::max(0.0, sum.prepare_ms() - t.prepare_ms()));
}

void add_stats(v1::TileStats& sum, const v1::TileStats& t) {
  sum.set_samples(sum.samples() + t.samples());
  sum.set_invalid_samples(sum.invalid_samples() + t.invalid_samples());
  sum.set_fragments(sum.fragments() + t.fragments());
  sum.set_rays(sum.rays() + t.rays());
  sum.set_render_ms(sum.render_ms() + t.render_ms());
  sum.set_cpu_ms(sum.cpu_ms() + t.cpu_ms());
  sum.set_prepare_ms(sum.prepare_ms() + t.prepare_ms());
  sum.set_threads(std::max(sum.threads(), t.threads()));
}

}  // namespace

JobStore::JobStore(const std::filesystem::path& file) {
  if (sqlite3_open_v2(file.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE |
                                              SQLITE_OPEN_FULLMUTEX, nullptr) != SQLITE_OK) {
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
  exec(kSchema);
  int version = 0;
  {
    Stmt s(db_, prepared("SELECT version FROM schema_version"));
    if (s.step()) version = s.i32(0);
  }
  if (version == 0) {
    Stmt(db_, prepared("INSERT INTO schema_version (version) VALUES (?)")).bind(1, kSchemaVersion).run();
  } else if (version >= 1 && version < kSchemaVersion) {
    Transaction t(db_);
    if (version == 1) {
      // Version 1 kept one file per tile: each done tile is its own part.
      exec("ALTER TABLE tiles ADD COLUMN part INTEGER NOT NULL DEFAULT 0");
      exec("UPDATE tiles SET part = idx");
    }
    if (version <= 2) {
      // Version 3 records who submitted each job (older jobs have no owner), and adds parts
      // (kSchema made it): the stats of each batch, so that a batch thrown away is taken out of
      // its job's stats. Parts done before have none, and stay counted.
      exec("ALTER TABLE jobs ADD COLUMN owner TEXT NOT NULL DEFAULT ''");
    }
    if (version <= 3) {
      // Version 4 counts the tiles' lost workers apart from their failed attempts. Losses before
      // were counted as attempts, and stay so.
      exec("ALTER TABLE tiles ADD COLUMN lost_attempts INTEGER NOT NULL DEFAULT 0");
    }
    if (version <= 4) {
      // Version 5 renders frame ranges (the frames table kSchema made). Every older job is a
      // still: frame 0 alone, merged when the job succeeded.
      exec("ALTER TABLE tiles ADD COLUMN frame INTEGER NOT NULL DEFAULT 0");
      for (const char* column : {"frame_first INTEGER NOT NULL DEFAULT 0", "frame_last INTEGER NOT NULL DEFAULT 0",
                                 "frame_step INTEGER NOT NULL DEFAULT 1", "frames_total INTEGER NOT NULL DEFAULT 1",
                                 "frames_done INTEGER NOT NULL DEFAULT 0"}) {
        exec(fmt::format("ALTER TABLE jobs ADD COLUMN {}", column).c_str());
      }
      exec(fmt::format("UPDATE jobs SET frames_done = 1 WHERE state = {}", static_cast<int>(v1::JOB_STATE_SUCCEEDED))
               .c_str());
      exec("INSERT INTO frames (job_seq, frame) SELECT seq, 0 FROM jobs WHERE frames_done = 1");
    }
    // Version 6 renders sample passes: every older job is one pass, pass 0.
    exec("ALTER TABLE tiles ADD COLUMN pass INTEGER NOT NULL DEFAULT 0");
    exec("ALTER TABLE jobs ADD COLUMN passes INTEGER NOT NULL DEFAULT 1");
    exec(fmt::format("UPDATE schema_version SET version = {}", kSchemaVersion).c_str());
    t.commit();
  } else if (version != kSchemaVersion) {
    throw std::runtime_error(fmt::format("job store {}: schema version {}, this farm reads {}",
                                         file.string(), version, kSchemaVersion));
  }
  // After the upgrade, which adds the column in an older store: a frame's tiles, found by the
  // checks for a complete frame after every batch.
  exec("CREATE INDEX IF NOT EXISTS tiles_by_frame ON tiles (job_seq, frame, state)");
  // Tiles in flight when the last scheduler stopped: their results died with it.
  exec("UPDATE tiles SET state = 0, worker = '' WHERE state = 1");
}

JobStore::~JobStore() {
  for (auto& [sql, statement] : statements_) sqlite3_finalize(statement);
  sqlite3_close(db_);
}

void JobStore::exec(const char* sql) const {
  if (sqlite3_exec(db_, sql, nullptr, nullptr, nullptr) != SQLITE_OK) throw_store_error(db_, "");
}

sqlite3_stmt* JobStore::prepare(const std::string& sql, unsigned flags) const {
  sqlite3_stmt* statement = nullptr;
  if (sqlite3_prepare_v3(db_, sql.c_str(), -1, flags, &statement, nullptr) != SQLITE_OK) {
    throw std::runtime_error(fmt::format("job store: {}: {}", sqlite3_errmsg(db_), sql));
  }
  return statement;
}

sqlite3_stmt* JobStore::prepared(const std::string& sql) const {
  if (auto it = statements_.find(sql); it != statements_.end()) return it->second;
  sqlite3_stmt* statement = prepare(sql, SQLITE_PREPARE_PERSISTENT);
  statements_.emplace(sql, statement);
  return statement;
}

v1::Job JobStore::add_job(const NewJob& j, std::int64_t now_ms) {
  if (j.frames.empty()) throw std::invalid_argument("job store: a job with no frames");
  if (j.passes < 1) throw std::invalid_argument("job store: a job of no sample pass");
  std::lock_guard lock(mutex_);
  Transaction t(db_);
  Stmt(db_, prepared("INSERT INTO jobs (id, name, spec, scene_hash, engine, width, height, priority, "
                     "state, submitted_ms, tiles_total, owner, frame_first, frame_last, frame_step, frames_total, passes) "
                     "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)"))
      .bind(1, j.id).bind(2, j.name).bind_blob(3, j.spec.SerializeAsString()).bind(4, j.scene_hash)
      .bind(5, j.engine).bind(6, j.width).bind(7, j.height).bind(8, j.priority)
      .bind(9, static_cast<int>(v1::JOB_STATE_QUEUED)).bind(10, now_ms)
      .bind(11, static_cast<std::int64_t>(j.tiles.size() * j.frames.size() * static_cast<std::size_t>(j.passes)))
      .bind(12, j.owner)
      .bind(13, j.frames.front()).bind(14, j.frames.back()).bind(15, j.frame_step)
      .bind(16, static_cast<std::int64_t>(j.frames.size())).bind(17, j.passes)
      .run();
  const std::int64_t seq = sqlite3_last_insert_rowid(db_);
  Stmt tile(db_, prepared("INSERT INTO tiles (job_seq, idx, x0, y0, x1, y1, frame, pass) "
                          "VALUES (?, ?, ?, ?, ?, ?, ?, ?)"));
  std::int64_t idx = 0;
  for (int frame : j.frames) {
    for (int pass = 0; pass < j.passes; ++pass) {
      for (const Rect& r : j.tiles) {
        tile.reset();
        tile.bind(1, seq).bind(2, idx++).bind(3, r.x0).bind(4, r.y0).bind(5, r.x1).bind(6, r.y1).bind(7, frame)
            .bind(8, pass);
        tile.run();
      }
    }
  }
  t.commit();
  return load_job_locked(j.id);
}

v1::Job JobStore::load_job_locked(const std::string& id) const {
  std::optional<v1::Job> job = find_job_locked(id);
  if (!job) throw std::runtime_error("job store: no job " + id);
  return *job;
}

std::optional<v1::Job> JobStore::find_job_locked(const std::string& id) const {
  Stmt s(db_, prepared(fmt::format("SELECT {} FROM jobs WHERE id = ?", kJobColumns)));
  s.bind(1, id);
  if (!s.step()) return std::nullopt;
  return job_from_row(s);
}

std::optional<v1::Job> JobStore::get_job(const std::string& id) const {
  std::lock_guard lock(mutex_);
  return find_job_locked(id);
}

std::optional<v1::JobSpec> JobStore::get_spec(const std::string& id) const {
  std::lock_guard lock(mutex_);
  Stmt s(db_, prepared("SELECT spec FROM jobs WHERE id = ?"));
  s.bind(1, id);
  if (!s.step()) return std::nullopt;
  v1::JobSpec spec;
  spec.ParseFromString(s.blob(0));
  return spec;
}

std::pair<std::vector<v1::Job>, std::int64_t> JobStore::list_jobs(
    const std::vector<v1::JobState>& states, int limit, std::int64_t before_seq,
    const std::optional<std::string>& owner) const {
  std::string where = before_seq > 0 ? fmt::format("seq < {}", before_seq) : "1";
  if (!states.empty()) {
    std::string in;
    for (v1::JobState s : states) in += fmt::format("{}{}", in.empty() ? "" : ", ", static_cast<int>(s));
    where += fmt::format(" AND state IN ({})", in);
  }
  if (owner) where += " AND owner = ?2";
  std::lock_guard lock(mutex_);
  // Not cached: the text varies with the filter and the page.
  sqlite3_stmt* statement =
      prepare(fmt::format("SELECT {} FROM jobs WHERE {} ORDER BY seq DESC LIMIT ?1", kJobColumns, where), 0);
  struct Finalize {
    sqlite3_stmt* s;
    ~Finalize() { sqlite3_finalize(s); }
  } finalize{statement};
  Stmt s(db_, statement);
  s.bind(1, limit + 1);
  if (owner) s.bind(2, *owner);
  std::vector<v1::Job> jobs;
  std::int64_t last_seq = 0, next = 0;
  while (s.step()) {
    if (static_cast<int>(jobs.size()) == limit) {
      next = last_seq;
      break;
    }
    jobs.push_back(job_from_row(s));
    last_seq = s.i64(0);
  }
  return {std::move(jobs), next};
}

std::vector<TileRecord> JobStore::tiles(const std::string& id) const {
  std::lock_guard lock(mutex_);
  Stmt s(db_, prepared("SELECT t.idx, t.x0, t.y0, t.x1, t.y1, t.state, t.attempts, t.last_error, t.worker, t.part, "
                       "t.lost_attempts, t.frame, t.pass "
                       "FROM tiles t JOIN jobs j ON t.job_seq = j.seq WHERE j.id = ? ORDER BY t.idx"));
  s.bind(1, id);
  std::vector<TileRecord> out;
  while (s.step()) {
    TileRecord t;
    t.job_id = id;
    t.index = static_cast<std::uint32_t>(s.i64(0));
    t.rect = {s.i32(1), s.i32(2), s.i32(3), s.i32(4)};
    t.state = static_cast<TileState>(s.i32(5));
    t.attempts = s.i32(6);
    t.last_error = s.text(7);
    t.worker = s.text(8);
    t.part = static_cast<std::uint32_t>(s.i64(9));
    t.lost_attempts = s.i32(10);
    t.frame = s.i32(11);
    t.pass = s.i32(12);
    out.push_back(std::move(t));
  }
  return out;
}

std::vector<std::string> JobStore::active_jobs() const {
  std::lock_guard lock(mutex_);
  Stmt s(db_, prepared(fmt::format("SELECT id FROM jobs WHERE state IN {} ORDER BY seq", kActiveSql)));
  std::vector<std::string> ids;
  while (s.step()) ids.push_back(s.text(0));
  return ids;
}

std::optional<TileBatch> JobStore::claim_next_batch(const std::string& worker, std::int64_t now_ms,
                                                    const BatchSize& batch_size, int count_up_to) {
  std::lock_guard lock(mutex_);
  Transaction t(db_);
  TileBatch batch;
  std::int64_t seq = 0;
  {
    // The active jobs in queue order, each asked for its first queued tile through tiles_by_state
    // (one seek a job): a join sorted over every queued tile would cost each claim as much as the
    // queue is long, and a job of many frames queues tens of thousands.
    Stmt jobs(db_, prepared(fmt::format("SELECT seq, id FROM jobs WHERE state IN {} ORDER BY priority DESC, seq ASC",
                                        kActiveSql)));
    Stmt first(db_, prepared("SELECT idx, x0, y0, x1, y1, attempts, lost_attempts, frame, pass FROM tiles "
                             "WHERE state = 0 AND job_seq = ? ORDER BY idx LIMIT 1"));
    bool found = false;
    while (!found && jobs.step()) {
      first.reset();
      first.bind(1, jobs.i64(0));
      if (!first.step()) continue;
      found = true;
      seq = jobs.i64(0);
      batch.job_id = jobs.text(1);
      batch.first = static_cast<std::uint32_t>(first.i64(0));
      batch.rect = {first.i32(1), first.i32(2), first.i32(3), first.i32(4)};
      batch.attempts = first.i32(5);
      batch.lost_attempts = first.i32(6);
      batch.frame = first.i32(7);
      batch.pass = first.i32(8);
    }
    if (!found) return std::nullopt;
  }
  // A tile that failed before, or lost its worker, goes alone, so it cannot take fresh
  // neighbours down with it (nor a worker's loss count them all).
  if (batch_size && batch.attempts == 0 && batch.lost_attempts == 0) {
    int queued = 0;
    {
      // Counted up to count_up_to only: counting all of a long queue at every claim would cost as
      // much as the queue is long.
      Stmt count(db_, prepared("SELECT COUNT(*) FROM (SELECT 1 FROM tiles WHERE state = 0 AND job_seq = ? LIMIT ?)"));
      count.bind(1, seq).bind(2, std::max(1, count_up_to));
      if (count.step()) queued = count.i32(0);
    }
    const int wanted = batch_size(batch.job_id, queued);
    if (wanted > 1) {
      // The following tiles while they continue the same row of the frame's grid in the same pass:
      // the batch's union is then one rectangle of one frame's pass, rendered in one call.
      Stmt next(db_, prepared("SELECT idx, x0, y0, x1, y1, state, attempts + lost_attempts, frame, pass FROM tiles "
                              "WHERE job_seq = ? AND idx > ? AND idx < ? ORDER BY idx"));
      next.bind(1, seq).bind(2, batch.first).bind(3, static_cast<std::int64_t>(batch.first) + wanted);
      while (next.step()) {
        const Rect r{next.i32(1), next.i32(2), next.i32(3), next.i32(4)};
        if (next.i64(0) != batch.first + batch.count || next.i32(5) != 0 || next.i32(6) != 0 ||
            next.i32(7) != batch.frame || next.i32(8) != batch.pass || r.y0 != batch.rect.y0 ||
            r.y1 != batch.rect.y1 || r.x0 != batch.rect.x1) {
          break;
        }
        batch.rect.x1 = r.x1;
        ++batch.count;
      }
    }
  }
  Stmt(db_, prepared("UPDATE tiles SET state = 1, worker = ? WHERE job_seq = ? AND idx >= ? AND idx < ?"))
      .bind(1, worker).bind(2, seq).bind(3, batch.first).bind(4, batch.first + batch.count).run();
  Stmt(db_, prepared("UPDATE jobs SET state = ?, started_ms = CASE WHEN started_ms = 0 THEN ? ELSE "
                     "started_ms END WHERE seq = ?"))
      .bind(1, static_cast<int>(v1::JOB_STATE_RUNNING)).bind(2, now_ms).bind(3, seq).run();
  t.commit();
  return batch;
}

std::optional<std::int64_t> JobStore::running_batch_locked(const std::string& job_id, std::uint32_t first,
                                                           std::uint32_t count, const std::string& worker) const {
  Stmt find(db_, prepared(fmt::format(
                     "SELECT j.seq, COUNT(*) FROM jobs j JOIN tiles t ON t.job_seq = j.seq WHERE j.id = ? "
                     "AND j.state IN {} AND t.idx >= ? AND t.idx < ? AND t.state = 1 "
                     "AND (? = '' OR t.worker = ?) GROUP BY j.seq",
                     kActiveSql)));
  find.bind(1, job_id).bind(2, first).bind(3, static_cast<std::int64_t>(first) + count).bind(4, worker).bind(5, worker);
  if (!find.step() || find.i64(1) != count) return std::nullopt;
  return find.i64(0);
}

bool JobStore::batch_done(const std::string& job_id, std::uint32_t first, std::uint32_t count,
                          const v1::TileStats& stats, const std::string& worker) {
  std::lock_guard lock(mutex_);
  Transaction t(db_);
  const std::optional<std::int64_t> seq = running_batch_locked(job_id, first, count, worker);
  if (!seq) return false;
  v1::TileStats sum;
  {
    Stmt s(db_, prepared("SELECT stats FROM jobs WHERE seq = ?"));
    s.bind(1, *seq);
    if (s.step()) sum.ParseFromString(s.blob(0));
  }
  add_stats(sum, stats);
  Stmt(db_, prepared("UPDATE tiles SET state = 2, part = ? WHERE job_seq = ? AND idx >= ? AND idx < ?"))
      .bind(1, first).bind(2, *seq).bind(3, first).bind(4, first + count).run();
  Stmt(db_, prepared("UPDATE jobs SET tiles_done = tiles_done + ?, tiles_rendered = tiles_rendered + ?, "
                     "stats = ? WHERE seq = ?"))
      .bind(1, count).bind(2, count).bind_blob(3, sum.SerializeAsString()).bind(4, *seq).run();
  Stmt(db_, prepared("INSERT OR REPLACE INTO parts (job_seq, part, stats) VALUES (?, ?, ?)"))
      .bind(1, *seq).bind(2, first).bind_blob(3, stats.SerializeAsString()).run();
  t.commit();
  return true;
}

TileFailure JobStore::batch_failed(const std::string& job_id, std::uint32_t first, std::uint32_t count,
                                   const std::string& reason, int max_attempts, std::int64_t now_ms,
                                   const std::string& worker) {
  return count_attempt(AttemptKind::Failed, job_id, first, count, reason, max_attempts, now_ms, worker);
}

TileFailure JobStore::batch_lost(const std::string& job_id, std::uint32_t first, std::uint32_t count,
                                 const std::string& reason, int max_lost_attempts, std::int64_t now_ms,
                                 const std::string& worker) {
  return count_attempt(AttemptKind::WorkerLost, job_id, first, count, reason, max_lost_attempts, now_ms, worker);
}

TileFailure JobStore::count_attempt(AttemptKind kind, const std::string& job_id, std::uint32_t first,
                                    std::uint32_t count, const std::string& reason, int max, std::int64_t now_ms,
                                    const std::string& worker) {
  std::lock_guard lock(mutex_);
  Transaction t(db_);
  TileFailure result;
  const std::optional<std::int64_t> seq = running_batch_locked(job_id, first, count, worker);
  if (!seq) {
    result.job = load_job_locked(job_id);
    return result;
  }
  // The two counts are columns of their own, each against its own limit.
  const char* column = kind == AttemptKind::Failed ? "attempts" : "lost_attempts";
  int attempts = 0;
  {
    Stmt s(db_, prepared(fmt::format("SELECT MAX({}) FROM tiles WHERE job_seq = ? AND idx >= ? AND idx < ?", column)));
    s.bind(1, *seq).bind(2, first).bind(3, first + count);
    if (s.step()) attempts = s.i32(0) + 1;
  }
  result.will_retry = attempts < max;
  Stmt(db_, prepared(fmt::format("UPDATE tiles SET state = ?, {0} = {0} + 1, last_error = ?, worker = '' "
                                 "WHERE job_seq = ? AND idx >= ? AND idx < ?",
                                 column)))
      .bind(1, static_cast<int>(result.will_retry ? TileState::Queued : TileState::Failed))
      .bind(2, reason).bind(3, *seq).bind(4, first).bind(5, first + count).run();
  // tile_failures counts every rendering of a tile that came to nothing, whatever the cause.
  Stmt(db_, prepared("UPDATE jobs SET tile_failures = tile_failures + ? WHERE seq = ?")).bind(1, count).bind(2, *seq).run();
  if (!result.will_retry) {
    const std::string tiles = describe_tiles(first, count);
    const std::string why =
        kind == AttemptKind::Failed
            ? fmt::format("{} failed {} time{}; last error: {}", tiles, attempts, attempts == 1 ? "" : "s", reason)
            : fmt::format("{} lost {} worker{} while rendering, the most a tile may lose (the lost-worker attempts "
                          "limit): it may take down every worker it is sent to; last error: {}",
                          tiles, attempts, attempts == 1 ? "" : "s", reason);
    Stmt(db_, prepared("UPDATE jobs SET state = ?, failure_reason = ?, finished_ms = ? WHERE seq = ?"))
        .bind(1, static_cast<int>(v1::JOB_STATE_FAILED))
        .bind(2, why).bind(3, now_ms).bind(4, *seq).run();
  }
  t.commit();
  result.job = load_job_locked(job_id);
  return result;
}

void JobStore::batch_requeue(const std::string& job_id, std::uint32_t first, std::uint32_t count,
                             const std::string& worker) {
  std::lock_guard lock(mutex_);
  Stmt(db_, prepared("UPDATE tiles SET state = 0, worker = '' WHERE state = 1 AND idx >= ? AND idx < ? "
                     "AND job_seq = (SELECT seq FROM jobs WHERE id = ?) AND (? = '' OR worker = ?)"))
      .bind(1, first).bind(2, static_cast<std::int64_t>(first) + count).bind(3, job_id).bind(4, worker)
      .bind(5, worker).run();
}

std::vector<TileBatch> JobStore::quarantine_worker(const std::string& worker) {
  std::lock_guard lock(mutex_);
  Transaction t(db_);
  // The done batches first (a batch is the tiles of one part), with what they added to the job.
  std::vector<TileBatch> discarded;
  std::vector<std::int64_t> seqs;
  {
    Stmt s(db_, prepared(fmt::format(
                    "SELECT j.seq, j.id, t.part, COUNT(*), MIN(t.x0), MIN(t.y0), MAX(t.x1), MAX(t.y1) "
                    "FROM tiles t JOIN jobs j ON t.job_seq = j.seq WHERE t.worker = ? AND t.state = 2 "
                    "AND j.state IN {} GROUP BY j.seq, t.part ORDER BY j.seq, t.part",
                    kActiveSql)));
    s.bind(1, worker);
    while (s.step()) {
      TileBatch b;
      b.job_id = s.text(1);
      b.first = static_cast<std::uint32_t>(s.i64(2));
      b.count = static_cast<std::uint32_t>(s.i64(3));
      b.rect = {s.i32(4), s.i32(5), s.i32(6), s.i32(7)};
      seqs.push_back(s.i64(0));
      discarded.push_back(std::move(b));
    }
  }
  for (std::size_t i = 0; i < discarded.size(); ++i) {
    const std::int64_t seq = seqs[i];
    const TileBatch& b = discarded[i];
    Stmt(db_, prepared("UPDATE tiles SET state = 0, worker = '' WHERE job_seq = ? AND part = ? AND state = 2 AND worker = ?"))
        .bind(1, seq).bind(2, b.first).bind(3, worker).run();
    take_back_part_locked(seq, b.first, b.count);
  }
  // Its calls in flight and its results waiting for a spot check: nothing of them is kept.
  Stmt(db_, prepared(fmt::format("UPDATE tiles SET state = 0, worker = '' WHERE worker = ? AND state = 1 "
                                 "AND job_seq IN (SELECT seq FROM jobs WHERE state IN {})",
                                 kActiveSql)))
      .bind(1, worker).run();
  t.commit();
  return discarded;
}

void JobStore::take_back_part_locked(std::int64_t seq, std::uint32_t part, std::uint32_t count) {
  v1::TileStats sum, stats;
  {
    Stmt s(db_, prepared("SELECT stats FROM jobs WHERE seq = ?"));
    s.bind(1, seq);
    if (s.step()) sum.ParseFromString(s.blob(0));
  }
  {
    Stmt s(db_, prepared("SELECT stats FROM parts WHERE job_seq = ? AND part = ?"));
    s.bind(1, seq).bind(2, part);
    if (s.step()) stats.ParseFromString(s.blob(0));
  }
  subtract_stats(sum, stats);
  Stmt(db_, prepared("DELETE FROM parts WHERE job_seq = ? AND part = ?")).bind(1, seq).bind(2, part).run();
  // Its frame, if merged, is merged again once the part is rendered again.
  Stmt(db_, prepared("DELETE FROM frames WHERE job_seq = ?1 AND frame = (SELECT frame FROM tiles WHERE job_seq = ?1 "
                     "AND idx = ?2)"))
      .bind(1, seq).bind(2, part).run();
  Stmt(db_, prepared("UPDATE jobs SET frames_done = (SELECT COUNT(*) FROM frames WHERE job_seq = ?1) WHERE seq = ?1"))
      .bind(1, seq).run();
  Stmt(db_, prepared("UPDATE jobs SET tiles_done = tiles_done - ?, stats = ? WHERE seq = ?"))
      .bind(1, count).bind_blob(2, sum.SerializeAsString()).bind(3, seq).run();
}

std::vector<TileBatch> JobStore::requeue_parts(const std::string& job_id, const std::vector<std::uint32_t>& parts) {
  std::lock_guard lock(mutex_);
  Transaction t(db_);
  std::vector<TileBatch> taken;
  std::int64_t seq = 0;
  {
    Stmt s(db_, prepared(fmt::format("SELECT seq FROM jobs WHERE id = ? AND state IN {}", kActiveSql)));
    s.bind(1, job_id);
    if (!s.step()) return taken;
    seq = s.i64(0);
  }
  for (std::uint32_t part : parts) {
    TileBatch b;
    b.job_id = job_id;
    b.first = part;
    {
      Stmt s(db_, prepared("SELECT COUNT(*), MIN(x0), MIN(y0), MAX(x1), MAX(y1) FROM tiles "
                           "WHERE job_seq = ? AND part = ? AND state = 2"));
      s.bind(1, seq).bind(2, part);
      if (!s.step() || s.i64(0) == 0) continue;
      b.count = static_cast<std::uint32_t>(s.i64(0));
      b.rect = {s.i32(1), s.i32(2), s.i32(3), s.i32(4)};
    }
    Stmt(db_, prepared("UPDATE tiles SET state = 0, worker = '' WHERE job_seq = ? AND part = ? AND state = 2"))
        .bind(1, seq).bind(2, part).run();
    take_back_part_locked(seq, part, b.count);
    taken.push_back(std::move(b));
  }
  t.commit();
  return taken;
}

std::vector<int> JobStore::complete_frames(const std::string& job_id, std::optional<int> frame) const {
  std::lock_guard lock(mutex_);
  std::vector<int> out;
  std::int64_t seq = 0;
  {
    Stmt s(db_, prepared(fmt::format("SELECT seq FROM jobs WHERE id = ? AND state IN {}", kActiveSql)));
    s.bind(1, job_id);
    if (!s.step()) return out;
    seq = s.i64(0);
  }
  if (frame) {
    // After each batch: one frame, unless it is merged, by seeks in tiles_by_frame (a count of its
    // tiles would read every one of them after every batch).
    Stmt merged(db_, prepared("SELECT 1 FROM frames WHERE job_seq = ? AND frame = ?"));
    merged.bind(1, seq).bind(2, *frame);
    if (merged.step()) return out;
    Stmt s(db_, prepared("SELECT EXISTS (SELECT 1 FROM tiles WHERE job_seq = ?1 AND frame = ?2), "
                         "EXISTS (SELECT 1 FROM tiles WHERE job_seq = ?1 AND frame = ?2 AND state IN (0, 1, 3))"));
    s.bind(1, seq).bind(2, *frame);
    if (s.step() && s.i64(0) == 1 && s.i64(1) == 0) out.push_back(*frame);
    return out;
  }
  // After a restart: every frame of the job, complete when none of its tiles is other than done.
  Stmt s(db_, prepared("SELECT t.frame FROM tiles t WHERE t.job_seq = ? AND NOT EXISTS (SELECT 1 FROM frames f "
                       "WHERE f.job_seq = t.job_seq AND f.frame = t.frame) GROUP BY t.frame "
                       "HAVING SUM(t.state != 2) = 0 ORDER BY t.frame"));
  s.bind(1, seq);
  while (s.step()) out.push_back(s.i32(0));
  return out;
}

std::vector<FramePart> JobStore::frame_parts(const std::string& job_id, int frame, int passes) const {
  std::lock_guard lock(mutex_);
  Stmt s(db_, prepared("SELECT DISTINCT t.part, t.pass FROM tiles t JOIN jobs j ON t.job_seq = j.seq "
                       "WHERE j.id = ? AND t.frame = ? AND t.pass < ? AND t.state = 2 ORDER BY t.pass, t.part"));
  s.bind(1, job_id).bind(2, frame).bind(3, passes);
  std::vector<FramePart> out;
  while (s.step()) out.push_back({static_cast<std::uint32_t>(s.i64(0)), s.i32(1)});
  return out;
}

int JobStore::complete_passes(const std::string& job_id, int frame) const {
  std::lock_guard lock(mutex_);
  Stmt s(db_, prepared("SELECT j.passes, (SELECT MIN(t.pass) FROM tiles t WHERE t.job_seq = j.seq AND t.frame = ? "
                       "AND t.state != 2) FROM jobs j WHERE j.id = ?"));
  s.bind(1, frame).bind(2, job_id);
  if (!s.step()) return 0;
  return s.is_null(1) ? s.i32(0) : s.i32(1);  // no tile of it undone: every pass
}

bool JobStore::frame_merged(const std::string& job_id, int frame) {
  std::lock_guard lock(mutex_);
  Transaction t(db_);
  std::int64_t seq = 0;
  {
    Stmt s(db_, prepared(fmt::format(
                    "SELECT j.seq, SUM(t.state != 2) FROM jobs j JOIN tiles t ON t.job_seq = j.seq "
                    "WHERE j.id = ? AND j.state IN {} AND t.frame = ? GROUP BY j.seq",
                    kActiveSql)));
    s.bind(1, job_id).bind(2, frame);
    if (!s.step() || s.i64(1) != 0) return false;
    seq = s.i64(0);
  }
  Stmt insert(db_, prepared("INSERT OR IGNORE INTO frames (job_seq, frame) VALUES (?, ?)"));
  insert.bind(1, seq).bind(2, frame).run();
  if (sqlite3_changes(db_) > 0) {
    Stmt(db_, prepared("UPDATE jobs SET frames_done = frames_done + 1 WHERE seq = ?")).bind(1, seq).run();
  }
  t.commit();
  return true;
}

bool JobStore::is_frame_merged(const std::string& job_id, int frame) const {
  std::lock_guard lock(mutex_);
  Stmt s(db_, prepared("SELECT 1 FROM frames f JOIN jobs j ON f.job_seq = j.seq WHERE j.id = ? AND f.frame = ?"));
  s.bind(1, job_id).bind(2, frame);
  return s.step();
}

v1::Job JobStore::finish_job(const std::string& id, v1::JobState state, const std::string& reason,
                             const std::string& validation, std::int64_t now_ms) {
  std::lock_guard lock(mutex_);
  // SUCCEEDED only while every tile is still done: a quarantine may have taken some back while
  // the frame was being merged.
  Stmt(db_, prepared(fmt::format("UPDATE jobs SET state = ?, failure_reason = ?, validation = ?, "
                                 "finished_ms = ? WHERE id = ? AND state IN {} AND "
                                 "(? = 0 OR (tiles_done = tiles_total AND frames_done = frames_total))",
                                 kActiveSql)))
      .bind(1, static_cast<int>(state)).bind(2, reason).bind(3, validation).bind(4, now_ms)
      .bind(5, id).bind(6, state == v1::JOB_STATE_SUCCEEDED ? 1 : 0).run();
  return load_job_locked(id);
}

v1::Job JobStore::cancel_job(const std::string& id, std::int64_t now_ms) {
  std::lock_guard lock(mutex_);
  Stmt(db_, prepared(fmt::format("UPDATE jobs SET state = ?, finished_ms = ? WHERE id = ? AND state IN {}",
                                 kActiveSql)))
      .bind(1, static_cast<int>(v1::JOB_STATE_CANCELLED)).bind(2, now_ms).bind(3, id).run();
  return load_job_locked(id);
}

}  // namespace farm
