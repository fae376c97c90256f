#include "server/scheduler/store/job_dependencies.h"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <set>

#include "server/common/failpoint.h"
#include "server/scheduler/store/owner_shares.h"

namespace farm {

namespace {

constexpr int kWaiting = v1::JOB_STATE_WAITING;
constexpr int kQueued = v1::JOB_STATE_QUEUED;
constexpr int kFailed = v1::JOB_STATE_FAILED;
constexpr int kCancelled = v1::JOB_STATE_CANCELLED;
constexpr std::size_t kMaxListedDependents = 1000;
constexpr std::size_t kMaxQuotedReason = 300;  // of a dependency's own failure, quoted in a chain

// "dependency 1a2b failed: <its reason>": why a job that needed it fails. `id` empty: a dependency
// removed from the store.
std::string dependency_failure(const std::string& what, const std::string& id, int state, const std::string& reason) {
  const std::string end = state == kFailed      ? "failed"
                          : state == kCancelled ? "was cancelled"
                                                : "is no longer in the store";
  std::string quoted = reason.substr(0, kMaxQuotedReason);
  if (quoted.size() < reason.size()) quoted += "...";
  return fmt::format("{} {} {}{}", what, id, end, quoted.empty() ? "" : ": " + quoted);
}

// The jobs `seq` waits for directly: its dependencies and the job it follows frame by frame.
std::vector<std::int64_t> waits_for(SqlConnection& db, std::int64_t seq) {
  std::vector<std::int64_t> out;
  Query s(db.prepared("SELECT on_seq FROM dependencies WHERE job_seq = ?1 UNION "
                      "SELECT after_frames_seq FROM jobs WHERE seq = ?1 AND after_frames_seq <> 0"));
  s.bind(1, seq);
  while (s.step()) out.push_back(s.i64(0));
  return out;
}

std::string id_of(SqlConnection& db, std::int64_t seq) {
  Query s(db.prepared("SELECT id FROM jobs WHERE seq = ?"));
  s.bind(1, seq);
  return s.step() ? s.text(0) : fmt::format("#{}", seq);
}

// The chain from `from` to `to` through what each waits for, as "a, which waits for b, ..."; empty
// when `to` cannot be reached. Visits each job once, so it ends on any store.
std::string path_between(SqlConnection& db, std::int64_t from, std::int64_t to) {
  std::map<std::int64_t, std::int64_t> came_from{{from, 0}};
  std::vector<std::int64_t> frontier{from};
  while (!frontier.empty() && !came_from.count(to)) {
    std::vector<std::int64_t> next;
    for (std::int64_t x : frontier) {
      for (std::int64_t y : waits_for(db, x)) {
        if (came_from.emplace(y, x).second) next.push_back(y);
      }
    }
    frontier = std::move(next);
  }
  if (!came_from.count(to) || from == to) return from == to ? id_of(db, from) : "";
  std::vector<std::int64_t> chain;
  for (std::int64_t at = to; at != 0; at = came_from[at]) chain.push_back(at);
  std::reverse(chain.begin(), chain.end());
  std::string words = id_of(db, chain.front());
  for (std::size_t i = 1; i < chain.size(); ++i) words += ", which waits for " + id_of(db, chain[i]);
  return words;
}

}  // namespace

std::vector<std::int64_t> dependency_seqs(SqlConnection& db, const std::vector<std::string>& ids) {
  std::vector<std::int64_t> seqs;
  for (const std::string& id : ids) {
    Query s(db.prepared("SELECT seq FROM jobs WHERE id = ?"));
    s.bind(1, id);
    if (!s.step()) throw DependencyError(DependencyError::Kind::UnknownJob, fmt::format("no job '{}' to wait for", id));
    seqs.push_back(s.i64(0));
  }
  return seqs;
}

void insert_dependencies(SqlConnection& db, std::int64_t seq, const std::vector<std::int64_t>& on, bool any_end) {
  for (std::int64_t d : on) {
    Query(db.prepared("INSERT INTO dependencies (job_seq, on_seq, on_id, any_end) "
                      "SELECT ?1, seq, id, ?3 FROM jobs WHERE seq = ?2 ON CONFLICT (job_seq, on_seq) DO NOTHING"))
        .bind(1, seq).bind(2, d).bind(3, any_end ? 1 : 0).run();
  }
}

void JobDependencies::describe(v1::Job& job) const {
  std::lock_guard lock(mutex_);
  std::int64_t seq = 0, frames_seq = 0;
  {
    Query s(db_->prepared("SELECT seq, after_frames_seq FROM jobs WHERE id = ?"));
    s.bind(1, job.job_id());
    if (!s.step()) return;
    seq = s.i64(0);
    frames_seq = s.i64(1);
  }
  job.clear_after();
  job.clear_after_any();
  job.clear_dependents();
  {
    Query s(db_->prepared("SELECT on_id, any_end FROM dependencies WHERE job_seq = ? ORDER BY on_seq"));
    s.bind(1, seq);
    while (s.step()) *(s.i64(1) ? job.add_after_any() : job.add_after()) = s.text(0);
  }
  job.set_after_frames(frames_seq ? id_of(*db_, frames_seq) : "");
  Query s(db_->prepared("SELECT w.id FROM dependencies x JOIN jobs w ON w.seq = x.job_seq WHERE x.on_seq = ?1 "
                        "UNION SELECT id FROM jobs WHERE after_frames_seq = ?1 ORDER BY 1 LIMIT ?2"));
  s.bind(1, seq).bind(2, static_cast<std::int64_t>(kMaxListedDependents));
  while (s.step()) job.add_dependents(s.text(0));
}

std::optional<v1::Job> JobDependencies::add(const std::string& job_id, const std::vector<std::string>& after,
                                            const std::vector<std::string>& after_any) {
  std::lock_guard lock(mutex_);
  SqlTransaction t(*db_);
  if (!lock_job_locked(job_id)) return std::nullopt;
  const std::optional<v1::Job> job = find_job_locked(job_id);
  if (!job) return std::nullopt;
  std::int64_t seq = 0;
  {
    Query s(db_->prepared("SELECT seq FROM jobs WHERE id = ?"));
    s.bind(1, job_id);
    if (s.step()) seq = s.i64(0);
  }
  const bool not_started = job->state() == v1::JOB_STATE_WAITING ||
                           (job->state() == v1::JOB_STATE_QUEUED && !job->has_started_at());
  if (!not_started) {
    throw DependencyError(DependencyError::Kind::Started,
                          fmt::format("job {} is {}: only a job none of whose units has been handed out can be given "
                                      "more jobs to wait for",
                                      job_id, to_string(job->state())));
  }
  const std::vector<std::int64_t> strict = dependency_seqs(*db_, after), any = dependency_seqs(*db_, after_any);
  std::size_t existing = 0;
  {
    Query s(db_->prepared("SELECT COUNT(*) FROM dependencies WHERE job_seq = ?"));
    s.bind(1, seq);
    if (s.step()) existing = static_cast<std::size_t>(s.i64(0));
  }
  if (existing + strict.size() + any.size() > kMaxDependencies) {
    throw DependencyError(DependencyError::Kind::TooMany,
                          fmt::format("job {} would wait for {} jobs; at most {}", job_id,
                                      existing + strict.size() + any.size(), kMaxDependencies));
  }
  for (const std::vector<std::int64_t>* list : {&strict, &any}) {
    for (std::int64_t d : *list) {
      const std::string chain = path_between(*db_, d, seq);
      if (chain.empty()) continue;
      throw DependencyError(DependencyError::Kind::Cycle,
                            d == seq ? fmt::format("job {} cannot wait for itself", job_id)
                                     : fmt::format("job {} cannot wait for {}: that would be a cycle ({}, which "
                                                   "would wait for {})",
                                                   job_id, id_of(*db_, d), chain, id_of(*db_, d)));
    }
  }
  insert_dependencies(*db_, seq, strict, false);
  insert_dependencies(*db_, seq, any, true);
  Query(db_->prepared("UPDATE jobs SET state = ? WHERE seq = ?")).bind(1, kWaiting).bind(2, seq).run();
  t.commit();
  return find_job_locked(job_id);
}

std::vector<ReleasedJob> JobDependencies::release_waiting(std::int64_t now_ms, int max_rounds) {
  std::lock_guard lock(mutex_);
  std::vector<ReleasedJob> released;
  for (int round = 0; round < max_rounds; ++round) {
    struct Change {
      std::int64_t seq;
      std::string id;
      int from;
      std::string reason;  // empty: queued
      std::string owner;
    };
    std::vector<Change> changes;
    SqlTransaction t(*db_);
    {
      // A job it needs ended badly, or is gone (deleted after it ended).
      Query s(db_->prepared("SELECT w.seq, w.id, x.on_id, COALESCE(d.state, 0), COALESCE(d.failure_reason, '') "
                            "FROM jobs w JOIN dependencies x ON x.job_seq = w.seq LEFT JOIN jobs d ON d.seq = x.on_seq "
                            "WHERE w.state = ?1 AND x.any_end = 0 AND (d.seq IS NULL OR d.state IN (?2, ?3)) "
                            "ORDER BY w.seq, x.on_seq"));
      s.bind(1, kWaiting).bind(2, kFailed).bind(3, kCancelled);
      while (s.step()) {
        if (!changes.empty() && changes.back().seq == s.i64(0)) continue;  // the first such dependency names it
        changes.push_back({s.i64(0), s.text(1), kWaiting, dependency_failure("dependency", s.text(2), s.i32(3), s.text(4)), ""});
      }
    }
    {
      // The job it follows frame by frame ended badly: its remaining frames will never be merged.
      Query s(db_->prepared("SELECT w.seq, w.id, w.state, d.id, d.state, d.failure_reason FROM jobs w "
                            "JOIN jobs d ON d.seq = w.after_frames_seq WHERE w.after_frames_seq <> 0 "
                            "AND w.state IN (?1, ?2, ?3) AND d.state IN (?4, ?5) ORDER BY w.seq"));
      s.bind(1, kWaiting).bind(2, kQueued).bind(3, static_cast<int>(v1::JOB_STATE_RUNNING)).bind(4, kFailed)
          .bind(5, kCancelled);
      while (s.step()) {
        changes.push_back({s.i64(0), s.text(1), s.i32(2),
                           dependency_failure("the job it follows frame by frame,", s.text(3) + ",", s.i32(4), s.text(5)),
                           ""});
      }
    }
    {
      // Every job it waits for ended as it needs (a deleted `after_any` one ended somehow).
      Query s(db_->prepared("SELECT w.seq, w.id, w.owner FROM jobs w WHERE w.state = ?1 AND NOT EXISTS (SELECT 1 "
                            "FROM dependencies x LEFT JOIN jobs d ON d.seq = x.on_seq WHERE x.job_seq = w.seq AND NOT "
                            "(COALESCE(d.state, 0) = ?2 OR (x.any_end = 1 AND (d.seq IS NULL OR d.state IN (?3, ?4))))) "
                            "ORDER BY w.seq"));
      s.bind(1, kWaiting).bind(2, static_cast<int>(v1::JOB_STATE_SUCCEEDED)).bind(3, kFailed).bind(4, kCancelled);
      while (s.step()) changes.push_back({s.i64(0), s.text(1), kWaiting, "", s.text(2)});
    }
    // Each changed only from the state it was read in: a scheduler sharing the store that changed
    // it first leaves nothing for this one to do, and its change is announced once.
    std::vector<std::pair<std::string, int>> done;
    std::set<std::string> owners;  // of the jobs queued
    for (const Change& c : changes) {
      if (c.reason.empty()) {
        Query u(db_->prepared("UPDATE jobs SET state = ? WHERE seq = ? AND state = ? RETURNING seq"));
        u.bind(1, kQueued).bind(2, c.seq).bind(3, c.from);
        if (!u.step()) continue;
        owners.insert(c.owner);
      } else {
        Query u(db_->prepared("UPDATE jobs SET state = ?, failure_reason = ?, finished_ms = ? WHERE seq = ? "
                              "AND state = ? RETURNING seq"));
        u.bind(1, kFailed).bind(2, c.reason).bind(3, now_ms).bind(4, c.seq).bind(5, c.from);
        if (!u.step()) continue;
      }
      done.emplace_back(c.id, c.from);
    }
    // The owners' rows last, in order, as every transaction takes them (no two deadlock).
    for (const std::string& owner : owners) enter_owner(*db_, owner, std::nullopt);
    if (!done.empty()) failpoint("dependency-release");  // the kill -9 test's point (failpoint.h)
    t.commit();
    if (done.empty()) break;
    for (const auto& [id, from] : done) released.push_back({load_job_locked(id), static_cast<v1::JobState>(from)});
  }
  return released;
}

}  // namespace farm
