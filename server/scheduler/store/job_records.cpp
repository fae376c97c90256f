#include "server/common/job_state.h"
#include "server/scheduler/store/job_records.h"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "server/scheduler/store/job_dependencies.h"
#include "server/scheduler/store/owner_shares.h"

namespace farm {

namespace {

std::string like_escaped(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '%' || c == '_' || c == '\\') out += '\\';
    out += c;
  }
  return out;
}

std::string like_pattern_of_glob(const std::string& glob) {
  std::string out;
  for (char c : glob) {
    if (c == '*') {
      out += '%';
    } else if (c == '?') {
      out += '_';
    } else {
      out += like_escaped(std::string(1, c));
    }
  }
  return out;
}

}  // namespace

v1::Job JobRecords::add_job(const NewJob& j, std::int64_t now_ms) {
  if (j.frames.empty()) throw std::invalid_argument("job store: a job with no frames");
  if (j.passes < 1) throw std::invalid_argument("job store: a job of no sample pass");
  if (j.after.size() + j.after_any.size() > kMaxDependencies) {
    throw DependencyError(DependencyError::Kind::TooMany,
                          fmt::format("a job may wait for at most {} jobs", kMaxDependencies));
  }
  std::lock_guard lock(mutex_);
  SqlTransaction t(*db_);
  // What it waits for, each checked to exist (a new job cannot close a cycle: nothing names it yet).
  const std::vector<std::int64_t> after = dependency_seqs(*db_, j.after), after_any = dependency_seqs(*db_, j.after_any);
  const std::int64_t frames_seq = j.after_frames.empty() ? 0 : dependency_seqs(*db_, {j.after_frames}).front();
  const bool waits = !after.empty() || !after_any.empty();
  std::int64_t seq = 0;
  {
    Query insert(db_->prepared(
        "INSERT INTO jobs (id, name, spec, scene_hash, engine, width, height, priority, state, submitted_ms, "
        "tiles_total, owner, frame_first, frame_last, frame_step, frames_total, passes, required_tags, min_threads, "
        "max_workers, max_units_in_flight, after_frames_seq) "
        "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?) RETURNING seq"));
    insert.bind(1, j.id).bind(2, j.name).bind_blob(3, j.spec.SerializeAsString()).bind(4, j.scene_hash)
        .bind(5, j.engine).bind(6, j.width).bind(7, j.height).bind(8, j.priority)
        .bind(9, static_cast<int>(waits ? v1::JOB_STATE_WAITING : v1::JOB_STATE_QUEUED)).bind(10, now_ms)
        .bind(11, static_cast<std::int64_t>(j.tiles.size() * j.frames.size() * static_cast<std::size_t>(j.passes)))
        .bind(12, j.owner)
        .bind(13, j.frames.front()).bind(14, j.frames.back()).bind(15, j.frame_step)
        .bind(16, static_cast<std::int64_t>(j.frames.size())).bind(17, j.passes)
        .bind(18, join_worker_tags(j.requirements.tags)).bind(19, j.requirements.min_threads)
        .bind(20, j.caps.max_workers).bind(21, j.caps.max_units_in_flight).bind(22, frames_seq);
    if (!insert.step()) throw std::runtime_error("job store: INSERT INTO jobs returned no seq");
    seq = insert.i64(0);
  }
  // The tiles go in many rows a statement: a statement each would cost a round trip each on a
  // PostgreSQL store (a 48-frame job has tens of thousands).
  struct TileRow {
    std::int64_t idx;
    Rect rect;
    int frame, pass;
  };
  std::vector<TileRow> rows;
  rows.reserve(j.tiles.size() * j.frames.size() * static_cast<std::size_t>(j.passes));
  for (int frame : j.frames) {
    for (int pass = 0; pass < j.passes; ++pass) {
      for (const Rect& r : j.tiles) rows.push_back({static_cast<std::int64_t>(rows.size()), r, frame, pass});
    }
  }
  constexpr std::size_t kRowsAStatement = 128;
  const auto insert_sql = [](std::size_t n) {
    std::string sql = "INSERT INTO tiles (job_seq, idx, x0, y0, x1, y1, frame, pass) VALUES ";
    for (std::size_t i = 0; i < n; ++i) sql += i ? ", (?, ?, ?, ?, ?, ?, ?, ?)" : "(?, ?, ?, ?, ?, ?, ?, ?)";
    return sql;
  };
  for (std::size_t at = 0; at < rows.size(); at += kRowsAStatement) {
    const std::size_t n = std::min(kRowsAStatement, rows.size() - at);
    std::unique_ptr<SqlStatement> once;  // the last, shorter statement is used once
    SqlStatement& statement = n == kRowsAStatement ? db_->prepared(insert_sql(n)) : *(once = db_->prepare_once(insert_sql(n)));
    Query insert(statement);
    for (std::size_t i = 0; i < n; ++i) {
      const TileRow& r = rows[at + i];
      const int p = static_cast<int>(i) * 8;
      insert.bind(p + 1, seq).bind(p + 2, r.idx).bind(p + 3, r.rect.x0).bind(p + 4, r.rect.y0).bind(p + 5, r.rect.x1)
          .bind(p + 6, r.rect.y1).bind(p + 7, r.frame).bind(p + 8, r.pass);
    }
    insert.run();
  }
  insert_dependencies(*db_, seq, after, false);
  insert_dependencies(*db_, seq, after_any, true);
  // Its owner's row last, as every transaction takes it (job_dependencies.cpp).
  enter_owner(*db_, j.owner, j.owner_weight_milli);
  t.commit();
  return load_job_locked(j.id);
}

std::optional<v1::Job> JobRecords::get_job(const std::string& id) const {
  std::lock_guard lock(mutex_);
  return find_job_locked(id);
}

std::optional<v1::JobSpec> JobRecords::get_spec(const std::string& id) const {
  std::lock_guard lock(mutex_);
  Query s(db_->prepared("SELECT spec FROM jobs WHERE id = ?"));
  s.bind(1, id);
  if (!s.step()) return std::nullopt;
  v1::JobSpec spec;
  spec.ParseFromString(s.blob(0));
  return spec;
}

std::pair<std::vector<v1::Job>, std::int64_t> JobRecords::list_jobs(const JobFilter& filter, int limit,
                                                                  std::int64_t before_seq) const {
  std::string where = before_seq > 0 ? fmt::format("seq < {}", before_seq) : "1 = 1";
  if (!filter.states.empty()) {
    std::string in;
    for (v1::JobState s : filter.states) in += fmt::format("{}{}", in.empty() ? "" : ", ", static_cast<int>(s));
    where += fmt::format(" AND state IN ({})", in);
  }
  // The texts are bound, never written into the statement, and numbered in the order they
  // appear. LIKE is case-insensitive on SQLite and not on PostgreSQL: both sides lowered.
  std::vector<std::string> texts;
  const auto bound = [&](std::string text) {
    texts.push_back(std::move(text));
    return fmt::format("?{}", texts.size() + 1);
  };
  if (filter.owner) where += " AND owner = " + bound(*filter.owner);
  if (!filter.name.empty()) {
    where += fmt::format(" AND lower(name) LIKE lower({}) ESCAPE '\\'", bound(like_pattern_of_glob(filter.name)));
  }
  if (!filter.id_prefix.empty()) {
    where += fmt::format(" AND id LIKE {} ESCAPE '\\'", bound(like_escaped(filter.id_prefix) + "%"));
  }
  std::lock_guard lock(mutex_);
  // Not cached: the text varies with the filter and the page.
  const std::unique_ptr<SqlStatement> statement =
      db_->prepare_once(fmt::format("SELECT {} FROM jobs WHERE {} ORDER BY seq DESC LIMIT ?1", kJobColumns, where));
  Query s(*statement);
  s.bind(1, limit + 1);
  for (std::size_t i = 0; i < texts.size(); ++i) s.bind(static_cast<int>(i) + 2, texts[i]);
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

std::vector<std::string> JobRecords::active_jobs() const {
  std::lock_guard lock(mutex_);
  Query s(db_->prepared(fmt::format("SELECT id FROM jobs WHERE state IN {} ORDER BY seq", kActiveSql)));
  std::vector<std::string> ids;
  while (s.step()) ids.push_back(s.text(0));
  return ids;
}

v1::Job JobRecords::finish_job(const std::string& id, v1::JobState state, const std::string& reason,
                             const std::string& validation, std::int64_t now_ms) {
  std::lock_guard lock(mutex_);
  // SUCCEEDED only while every tile is still done: a quarantine may have taken some back while
  // the frame was being merged.
  Query(db_->prepared(fmt::format("UPDATE jobs SET state = ?, failure_reason = ?, validation = ?, "
                                 "finished_ms = ? WHERE id = ? AND state IN {} AND "
                                 "(? = 0 OR (tiles_done = tiles_total AND frames_done = frames_total))",
                                 kActiveSql)))
      .bind(1, static_cast<int>(state)).bind(2, reason).bind(3, validation).bind(4, now_ms)
      .bind(5, id).bind(6, state == v1::JOB_STATE_SUCCEEDED ? 1 : 0).run();
  return load_job_locked(id);
}

v1::Job JobRecords::cancel_job(const std::string& id, std::int64_t now_ms) {
  std::lock_guard lock(mutex_);
  Query(db_->prepared(fmt::format("UPDATE jobs SET state = ?, finished_ms = ? WHERE id = ? AND state IN {}",
                                 kUnfinishedSql)))
      .bind(1, static_cast<int>(v1::JOB_STATE_CANCELLED)).bind(2, now_ms).bind(3, id).run();
  return load_job_locked(id);
}

std::optional<v1::Job> JobRecords::set_paused(const std::string& id, bool paused) {
  std::lock_guard lock(mutex_);
  Query(db_->prepared(fmt::format("UPDATE jobs SET paused = ? WHERE id = ? AND state IN {}", kUnfinishedSql)))
      .bind(1, paused ? 1 : 0).bind(2, id).run();
  return find_job_locked(id);
}

std::optional<v1::Job> JobRecords::set_priority(const std::string& id, int priority) {
  std::lock_guard lock(mutex_);
  Query(db_->prepared("UPDATE jobs SET priority = ? WHERE id = ?")).bind(1, priority).bind(2, id).run();
  return find_job_locked(id);
}

std::optional<v1::Job> JobRecords::set_caps(const std::string& id, std::optional<int> max_workers,
                                            std::optional<int> max_units_in_flight) {
  std::lock_guard lock(mutex_);
  if (max_workers) {
    Query(db_->prepared(fmt::format("UPDATE jobs SET max_workers = ? WHERE id = ? AND state IN {}", kUnfinishedSql)))
        .bind(1, *max_workers).bind(2, id).run();
  }
  if (max_units_in_flight) {
    Query(db_->prepared(fmt::format("UPDATE jobs SET max_units_in_flight = ? WHERE id = ? AND state IN {}",
                                    kUnfinishedSql)))
        .bind(1, *max_units_in_flight).bind(2, id).run();
  }
  return find_job_locked(id);
}

std::optional<RetriedJob> JobRecords::retry_job(const std::string& id) {
  std::lock_guard lock(mutex_);
  SqlTransaction t(*db_);
  lock_job_locked(id);
  std::optional<v1::Job> job = find_job_locked(id);
  if (!job) return std::nullopt;
  RetriedJob out;
  if (job->state() != v1::JOB_STATE_FAILED && job->state() != v1::JOB_STATE_CANCELLED) {
    out.job = std::move(*job);
    return out;
  }
  std::int64_t seq = 0;
  {
    Query s(db_->prepared("SELECT seq FROM jobs WHERE id = ?"));
    s.bind(1, id);
    if (!s.step()) return std::nullopt;
    seq = s.i64(0);
  }
  // Every unit not done goes back with a clean slate: failed ones, queued ones, and the ones the
  // cancel found running (their calls were stopped). Done units and merged frames stay.
  Query requeue(db_->prepared("UPDATE tiles SET state = 0, attempts = 0, lost_attempts = 0, worker = '', "
                              "scheduler = '' WHERE job_seq = ? AND state <> 2"));
  requeue.bind(1, seq).run();
  out.units_queued = static_cast<std::uint32_t>(requeue.changes());
  // Who merges a frame or ends the job is decided again, by whichever scheduler gets there.
  Query(db_->prepared("DELETE FROM claims WHERE job_seq = ?")).bind(1, seq).run();
  // A job with dependencies waits again for them to settle it (release_waiting): one that failed
  // because a dependency did runs once that has been retried and has succeeded.
  Query(db_->prepared("UPDATE jobs SET state = CASE WHEN EXISTS (SELECT 1 FROM dependencies WHERE job_seq = ?1) THEN ?2 "
                      "WHEN tiles_done > 0 THEN ?3 ELSE ?4 END, finished_ms = 0, "
                      "failure_reason = '', validation = '', paused = 0 WHERE seq = ?1"))
      .bind(1, seq).bind(2, static_cast<int>(v1::JOB_STATE_WAITING)).bind(3, static_cast<int>(v1::JOB_STATE_RUNNING))
      .bind(4, static_cast<int>(v1::JOB_STATE_QUEUED)).run();
  t.commit();
  out.job = load_job_locked(id);
  out.retried = true;
  return out;
}

std::optional<bool> JobRecords::delete_job(const std::string& id) {
  std::lock_guard lock(mutex_);
  SqlTransaction t(*db_);
  lock_job_locked(id);
  std::int64_t seq = 0;
  {
    Query s(db_->prepared("SELECT seq, state FROM jobs WHERE id = ?"));
    s.bind(1, id);
    if (!s.step()) return std::nullopt;
    if (!is_final(static_cast<v1::JobState>(s.i32(1)))) return false;
    seq = s.i64(0);
  }
  // The rows that name the job first: they reference it.
  // Rows of jobs that wait for it stay: they name it, and find it gone (release_waiting).
  for (const char* table : {"tiles", "frames", "claims", "parts", "job_log", "dependencies"}) {
    Query(db_->prepared(fmt::format("DELETE FROM {} WHERE job_seq = ?", table))).bind(1, seq).run();
  }
  Query(db_->prepared("DELETE FROM jobs WHERE seq = ?")).bind(1, seq).run();
  t.commit();
  return true;
}

JobRecords::Counts JobRecords::counts() const {
  std::lock_guard lock(mutex_);
  Counts c;
  {
    Query s(db_->prepared("SELECT state, COUNT(*), SUM(CASE WHEN paused <> 0 THEN 1 ELSE 0 END) FROM jobs GROUP BY state"));
    while (s.step()) {
      c.jobs[static_cast<v1::JobState>(s.i32(0))] = s.i64(1);
      if (is_final(static_cast<v1::JobState>(s.i32(0)))) continue;
      c.paused += s.i64(2);
    }
  }
  // Through tiles_by_state: the queued units, then their jobs' state.
  Query q(db_->prepared(fmt::format("SELECT COUNT(*) FROM tiles t JOIN jobs j ON t.job_seq = j.seq WHERE t.state = 0 "
                                    "AND j.state IN {} AND j.paused = 0",
                                    kActiveSql)));
  if (q.step()) c.queued_units = q.i64(0);
  return c;
}

std::vector<std::string> JobRecords::finished_before(std::int64_t ms, int limit) const {
  std::lock_guard lock(mutex_);
  Query s(db_->prepared(fmt::format("SELECT id FROM jobs WHERE state NOT IN {} AND finished_ms > 0 AND finished_ms < ? "
                                    "ORDER BY seq LIMIT ?",
                                    kActiveSql)));
  s.bind(1, ms).bind(2, limit);
  std::vector<std::string> ids;
  while (s.step()) ids.push_back(s.text(0));
  return ids;
}

}  // namespace farm
