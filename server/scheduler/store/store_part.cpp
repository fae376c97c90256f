#include "server/scheduler/store/store_part.h"

#include <fmt/format.h>
#include <google/protobuf/util/time_util.h>

#include <algorithm>
#include <stdexcept>

namespace farm {

const char* const kJobColumns =
    "seq, id, name, scene_hash, engine, width, height, priority, state, submitted_ms, started_ms, "
    "finished_ms, failure_reason, tiles_total, tiles_done, tile_failures, tiles_rendered, stats, "
    "validation, owner, frame_first, frame_last, frame_step, frames_total, frames_done, passes, paused, "
    "required_tags, min_threads, max_workers, max_units_in_flight";

const std::string kActiveSql =
    fmt::format("({}, {})", static_cast<int>(v1::JOB_STATE_QUEUED),
                static_cast<int>(v1::JOB_STATE_RUNNING));
const std::string kUnfinishedSql =
    fmt::format("({}, {}, {})", static_cast<int>(v1::JOB_STATE_QUEUED), static_cast<int>(v1::JOB_STATE_RUNNING),
                static_cast<int>(v1::JOB_STATE_WAITING));

google::protobuf::Timestamp timestamp(std::int64_t ms) {
  return google::protobuf::util::TimeUtil::MillisecondsToTimestamp(ms);
}

v1::Job job_from_row(const Query& s) {
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
  job.set_paused(s.i64(26) != 0);
  for (std::string& tag : split_worker_tags(s.text(27))) job.add_required_tags(std::move(tag));
  job.set_min_threads(s.i32(28));
  job.set_max_workers(static_cast<std::uint32_t>(s.i64(29)));
  job.set_max_units_in_flight(static_cast<std::uint32_t>(s.i64(30)));
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


v1::Job StorePart::load_job_locked(const std::string& id) const {
  std::optional<v1::Job> job = find_job_locked(id);
  if (!job) throw std::runtime_error("job store: no job " + id);
  return *job;
}

std::optional<v1::Job> StorePart::find_job_locked(const std::string& id) const {
  Query s(db_->prepared(fmt::format("SELECT {} FROM jobs WHERE id = ?", kJobColumns)));
  s.bind(1, id);
  if (!s.step()) return std::nullopt;
  return job_from_row(s);
}

bool StorePart::lock_job_locked(std::int64_t seq) {
  if (db_->dialect() != SqlDialect::PostgreSQL) return true;  // BEGIN IMMEDIATE holds the whole store
  Query s(db_->prepared("SELECT seq FROM jobs WHERE seq = ? FOR UPDATE"));
  s.bind(1, seq);
  return s.step();
}

void StorePart::lock_jobs_of_tiles_locked(const std::string& tiles_where, const std::string& value) {
  if (db_->dialect() != SqlDialect::PostgreSQL) return;
  std::vector<std::int64_t> jobs;
  {
    Query s(db_->prepared(fmt::format("SELECT DISTINCT job_seq FROM tiles WHERE {} ORDER BY job_seq", tiles_where)));
    s.bind(1, value);
    while (s.step()) jobs.push_back(s.i64(0));
  }
  for (std::int64_t seq : jobs) lock_job_locked(seq);
}

bool StorePart::lock_job_locked(const std::string& job_id) {
  if (db_->dialect() != SqlDialect::PostgreSQL) return true;
  Query s(db_->prepared("SELECT seq FROM jobs WHERE id = ? FOR UPDATE"));
  s.bind(1, job_id);
  return s.step();
}

std::optional<std::int64_t> StorePart::running_batch_locked(const std::string& job_id, std::uint32_t first,
                                                           std::uint32_t count, const std::string& worker) const {
  Query find(db_->prepared(fmt::format(
                     "SELECT j.seq, COUNT(*) FROM jobs j JOIN tiles t ON t.job_seq = j.seq WHERE j.id = ? "
                     "AND j.state IN {} AND t.idx >= ? AND t.idx < ? AND t.state = 1 "
                     "AND (? = '' OR t.worker = ?) AND t.scheduler = ? GROUP BY j.seq",
                     kActiveSql)));
  find.bind(1, job_id).bind(2, first).bind(3, static_cast<std::int64_t>(first) + count).bind(4, worker).bind(5, worker)
      .bind(6, scheduler_);
  if (!find.step() || find.i64(1) != count) return std::nullopt;
  return find.i64(0);
}

void StorePart::take_back_part_locked(std::int64_t seq, std::uint32_t part, std::uint32_t count) {
  v1::TileStats sum, stats;
  {
    Query s(db_->prepared("SELECT stats FROM jobs WHERE seq = ?"));
    s.bind(1, seq);
    if (s.step()) sum.ParseFromString(s.blob(0));
  }
  {
    Query s(db_->prepared("SELECT stats FROM parts WHERE job_seq = ? AND part = ?"));
    s.bind(1, seq).bind(2, part);
    if (s.step()) stats.ParseFromString(s.blob(0));
  }
  subtract_stats(sum, stats);
  Query(db_->prepared("DELETE FROM parts WHERE job_seq = ? AND part = ?")).bind(1, seq).bind(2, part).run();
  // Its frame, if merged, is merged again once the part is rendered again, by whichever
  // scheduler claims it then.
  Query(db_->prepared("DELETE FROM frames WHERE job_seq = ?1 AND frame = (SELECT frame FROM tiles WHERE job_seq = ?1 "
                     "AND idx = ?2)"))
      .bind(1, seq).bind(2, part).run();
  Query(db_->prepared("DELETE FROM claims WHERE job_seq = ?1 AND what = 'frame ' || (SELECT frame FROM tiles "
                      "WHERE job_seq = ?1 AND idx = ?2)"))
      .bind(1, seq).bind(2, part).run();
  Query(db_->prepared("UPDATE jobs SET frames_done = (SELECT COUNT(*) FROM frames WHERE job_seq = ?1) WHERE seq = ?1"))
      .bind(1, seq).run();
  Query(db_->prepared("UPDATE jobs SET tiles_done = tiles_done - ?, stats = ? WHERE seq = ?"))
      .bind(1, count).bind_blob(2, sum.SerializeAsString()).bind(3, seq).run();
}

std::optional<std::int64_t> StorePart::active_seq_locked(const std::string& job_id) const {
  Query s(db_->prepared(fmt::format("SELECT seq FROM jobs WHERE id = ? AND state IN {}", kActiveSql)));
  s.bind(1, job_id);
  if (!s.step()) return std::nullopt;
  return s.i64(0);
}

}  // namespace farm
