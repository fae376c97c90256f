#include "server/common/job_state.h"
#include "server/scheduler/store/unit_queue.h"

#include "server/scheduler/store/owner_shares.h"

#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace farm {

std::vector<UnitRecord> UnitQueue::tiles(const std::string& id) const {
  std::lock_guard lock(mutex_);
  Query s(db_->prepared("SELECT t.idx, t.x0, t.y0, t.x1, t.y1, t.state, t.attempts, t.last_error, t.worker, t.part, "
                       "t.lost_attempts, t.frame, t.pass "
                       "FROM tiles t JOIN jobs j ON t.job_seq = j.seq WHERE j.id = ? ORDER BY t.idx"));
  s.bind(1, id);
  std::vector<UnitRecord> out;
  while (s.step()) {
    UnitRecord t;
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

std::optional<UnitBatch> UnitQueue::claim_next_batch(const std::string& worker, std::int64_t now_ms,
                                                    const BatchSize& batch_size, int count_up_to,
                                                    const std::function<bool(const std::string&)>& skip_job,
                                                    const WorkerOffer& offer, bool whole_rows) {
  std::lock_guard lock(mutex_);
  SqlTransaction t(*db_, kRedoable);
  UnitBatch batch;
  std::int64_t seq = 0;
  std::string owner;
  int room = std::numeric_limits<int>::max();  // units the job's max_units_in_flight still allows
  {
    // The active jobs in queue order (priority, then fair share: the owner served least so far,
    // owner_shares.h; then submission), each asked for its first queued tile through
    // tiles_by_state (one seek a job): a join sorted over every queued tile would cost each claim
    // as much as the queue is long, and a job of many frames queues tens of thousands.
    Query jobs(db_->prepared(fmt::format(
        "SELECT j.seq, j.id, j.required_tags, j.min_threads, j.max_workers, j.max_units_in_flight, "
        "j.after_frames_seq, j.owner FROM jobs j LEFT JOIN owners o ON o.owner = j.owner WHERE j.state IN {} "
        "AND j.paused = 0 ORDER BY j.priority DESC, COALESCE(o.pass, 0) ASC, j.seq ASC",
        kActiveSql)));
    // Whether the worker may render the job of the current row.
    const auto offer_meets = [&] {
      const std::string tags = jobs.text(2);
      const int min_threads = jobs.i32(3);
      if (tags.empty() && min_threads == 0) return true;
      return WorkerRequirements{split_worker_tags(tags), min_threads}.met_by(offer.tags, offer.threads);
    };
    Query first(db_->prepared("SELECT idx, x0, y0, x1, y1, attempts, lost_attempts, frame, pass FROM tiles "
                             "WHERE state = 0 AND job_seq = ? ORDER BY idx LIMIT 1"));
    // A job that follows another frame by frame: its first queued tile of a frame that job has
    // merged, or does not render.
    Query first_following(db_->prepared(
        "SELECT idx, x0, y0, x1, y1, attempts, lost_attempts, frame, pass FROM tiles t WHERE t.state = 0 AND "
        "t.job_seq = ?1 AND (EXISTS (SELECT 1 FROM frames f WHERE f.job_seq = ?2 AND f.frame = t.frame) OR NOT "
        "EXISTS (SELECT 1 FROM tiles d WHERE d.job_seq = ?2 AND d.frame = t.frame)) ORDER BY t.idx LIMIT 1"));
    // The job's first tile this worker may have now, read into `batch`; false for none.
    const auto first_tile = [&](std::int64_t job_seq, std::int64_t followed_seq) {
      Query& q = followed_seq ? first_following : first;
      q.reset();
      q.bind(1, job_seq);
      if (followed_seq) q.bind(2, followed_seq);
      if (!q.step()) return false;
      batch.first = static_cast<std::uint32_t>(q.i64(0));
      batch.rect = {q.i32(1), q.i32(2), q.i32(3), q.i32(4)};
      batch.attempts = q.i32(5);
      batch.lost_attempts = q.i32(6);
      batch.frame = q.i32(7);
      batch.pass = q.i32(8);
      return true;
    };
    Query out(db_->prepared("SELECT COUNT(*), COUNT(DISTINCT worker), COALESCE(SUM(CASE WHEN worker = ? THEN 1 "
                            "ELSE 0 END), 0) FROM tiles WHERE state = 1 AND job_seq = ?"));
    bool found = false;
    while (!found && jobs.step()) {
      if (!offer_meets() || (skip_job && skip_job(jobs.text(1)))) continue;
      const std::int64_t job_seq = jobs.i64(0), followed_seq = jobs.i64(6);
      if (!first_tile(job_seq, followed_seq)) continue;
      // Another scheduler may be claiming from the same job: once this one holds the job, its
      // first queued tile and its units out are read again (PostgreSQL's next statement sees
      // what the other committed).
      if (db_->dialect() == SqlDialect::PostgreSQL) {
        if (!lock_job_locked(job_seq) || !first_tile(job_seq, followed_seq)) continue;
      }
      const int max_workers = jobs.i32(4), max_units = jobs.i32(5);
      if (max_workers > 0 || max_units > 0) {
        out.reset();
        out.bind(1, worker).bind(2, job_seq);
        if (!out.step()) continue;
        const int units_out = out.i32(0), workers_on_it = out.i32(1), mine = out.i32(2);
        if (max_units > 0 && units_out >= max_units) continue;
        if (max_workers > 0 && mine == 0 && workers_on_it >= max_workers) continue;
        if (max_units > 0) room = max_units - units_out;
      }
      found = true;
      seq = job_seq;
      batch.job_id = jobs.text(1);
      owner = jobs.text(7);
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
      Query count(db_->prepared("SELECT COUNT(*) FROM (SELECT 1 FROM tiles WHERE state = 0 AND job_seq = ? LIMIT ?) AS queued"));
      count.bind(1, seq).bind(2, std::max(1, count_up_to));
      if (count.step()) queued = count.i32(0);
    }
    const int wanted = std::min(room, batch_size(batch.job_id, queued));
    if (wanted > 1) {
      // The following units of the same frame's pass while the batch stays one rectangle, rendered
      // in one call: the rest of the first unit's row of the grid, and, with `whole_rows` when the
      // batch began a row, whole rows after it (a row is taken only whole; numbered row by row, a
      // unit that starts a new row at x = 0 means the row before ended at the image's edge).
      Query next(db_->prepared("SELECT idx, x0, y0, x1, y1, state, attempts + lost_attempts, frame, pass FROM tiles "
                              "WHERE job_seq = ? AND idx > ? AND idx < ? ORDER BY idx"));
      next.bind(1, seq).bind(2, batch.first).bind(3, static_cast<std::int64_t>(batch.first) + wanted);
      whole_rows = whole_rows && batch.rect.x0 == 0;
      Rect row = batch.rect;          // the row being added
      std::uint32_t taken = batch.count;
      while (next.step()) {
        const Rect r{next.i32(1), next.i32(2), next.i32(3), next.i32(4)};
        if (next.i64(0) != batch.first + taken || next.i32(5) != 0 || next.i32(6) != 0 ||
            next.i32(7) != batch.frame || next.i32(8) != batch.pass) {
          break;
        }
        if (r.y0 == row.y0 && r.y1 == row.y1 && r.x0 == row.x1) {
          row.x1 = r.x1;
        } else if (whole_rows && r.x0 == 0 && r.y0 == row.y1 && row.x1 == batch.rect.x1) {
          row = r;  // the row before is whole (as wide as the batch's first): a new one begins
        } else {
          break;
        }
        ++taken;
        // The batch so far is a rectangle: within its first row, or ending a whole row.
        if (row.y0 == batch.rect.y0 || row.x1 == batch.rect.x1) {
          if (row.y0 == batch.rect.y0) batch.rect.x1 = row.x1;
          batch.rect.y1 = row.y1;
          batch.count = taken;
        }
      }
    }
  }
  Query(db_->prepared("UPDATE tiles SET state = 1, worker = ?, scheduler = ? WHERE job_seq = ? AND idx >= ? AND idx < ?"))
      .bind(1, worker).bind(2, scheduler_).bind(3, seq).bind(4, batch.first).bind(5, batch.first + batch.count).run();
  {
    // The job's first claim since it was queued (at its submission, or by a retry) starts it.
    Query start(db_->prepared("UPDATE jobs SET state = ?, started_ms = CASE WHEN started_ms = 0 THEN ? ELSE "
                              "started_ms END WHERE seq = ? AND state = ? RETURNING seq"));
    start.bind(1, static_cast<int>(v1::JOB_STATE_RUNNING)).bind(2, now_ms).bind(3, seq)
        .bind(4, static_cast<int>(v1::JOB_STATE_QUEUED));
    batch.started_job = start.step();
  }
  // The owner's row last, as every transaction takes it (job_dependencies.cpp).
  charge_owner(*db_, owner, batch.count);
  t.commit();
  return batch;
}

bool UnitQueue::batch_done(const std::string& job_id, std::uint32_t first, std::uint32_t count,
                          const v1::TileStats& stats, const std::string& worker) {
  std::lock_guard lock(mutex_);
  SqlTransaction t(*db_, kRedoable);
  lock_job_locked(job_id);
  const std::optional<std::int64_t> seq = running_batch_locked(job_id, first, count, worker);
  if (!seq) return false;
  v1::TileStats sum;
  {
    Query s(db_->prepared("SELECT stats FROM jobs WHERE seq = ?"));
    s.bind(1, *seq);
    if (s.step()) sum.ParseFromString(s.blob(0));
  }
  add_stats(sum, stats);
  Query(db_->prepared("UPDATE tiles SET state = 2, part = ? WHERE job_seq = ? AND idx >= ? AND idx < ?"))
      .bind(1, first).bind(2, *seq).bind(3, first).bind(4, first + count).run();
  Query(db_->prepared("UPDATE jobs SET tiles_done = tiles_done + ?, tiles_rendered = tiles_rendered + ?, "
                     "stats = ? WHERE seq = ?"))
      .bind(1, count).bind(2, count).bind_blob(3, sum.SerializeAsString()).bind(4, *seq).run();
  Query(db_->prepared("INSERT INTO parts (job_seq, part, stats) VALUES (?, ?, ?) "
                     "ON CONFLICT (job_seq, part) DO UPDATE SET stats = excluded.stats"))
      .bind(1, *seq).bind(2, first).bind_blob(3, stats.SerializeAsString()).run();
  t.commit();
  return true;
}

TileFailure UnitQueue::batch_failed(const std::string& job_id, std::uint32_t first, std::uint32_t count,
                                   const std::string& reason, int max_attempts, std::int64_t now_ms,
                                   const std::string& worker) {
  return count_attempt(AttemptKind::Failed, job_id, first, count, reason, max_attempts, now_ms, worker);
}

TileFailure UnitQueue::batch_lost(const std::string& job_id, std::uint32_t first, std::uint32_t count,
                                 const std::string& reason, int max_lost_attempts, std::int64_t now_ms,
                                 const std::string& worker) {
  return count_attempt(AttemptKind::WorkerLost, job_id, first, count, reason, max_lost_attempts, now_ms, worker);
}

TileFailure UnitQueue::count_attempt(AttemptKind kind, const std::string& job_id, std::uint32_t first,
                                    std::uint32_t count, const std::string& reason, int max, std::int64_t now_ms,
                                    const std::string& worker) {
  std::lock_guard lock(mutex_);
  SqlTransaction t(*db_);
  lock_job_locked(job_id);
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
    Query s(db_->prepared(fmt::format("SELECT MAX({}) FROM tiles WHERE job_seq = ? AND idx >= ? AND idx < ?", column)));
    s.bind(1, *seq).bind(2, first).bind(3, first + count);
    if (s.step()) attempts = s.i32(0) + 1;
  }
  result.will_retry = attempts < max;
  Query(db_->prepared(fmt::format("UPDATE tiles SET state = ?, {0} = {0} + 1, last_error = ?, worker = '', scheduler = '' "
                                 "WHERE job_seq = ? AND idx >= ? AND idx < ?",
                                 column)))
      .bind(1, static_cast<int>(result.will_retry ? TileState::Queued : TileState::Failed))
      .bind(2, reason).bind(3, *seq).bind(4, first).bind(5, first + count).run();
  // tile_failures counts every rendering of a tile that came to nothing, whatever the cause.
  Query(db_->prepared("UPDATE jobs SET tile_failures = tile_failures + ? WHERE seq = ?")).bind(1, count).bind(2, *seq).run();
  if (!result.will_retry) {
    const std::string tiles = describe_units(first, count);
    const std::string why =
        kind == AttemptKind::Failed
            ? fmt::format("{} failed {} time{}; last error: {}", tiles, attempts, attempts == 1 ? "" : "s", reason)
            : fmt::format("{} lost {} worker{} while rendering, the most a unit may lose (the lost-worker attempts "
                          "limit): it may take down every worker it is sent to; last error: {}",
                          tiles, attempts, attempts == 1 ? "" : "s", reason);
    Query(db_->prepared("UPDATE jobs SET state = ?, failure_reason = ?, finished_ms = ? WHERE seq = ?"))
        .bind(1, static_cast<int>(v1::JOB_STATE_FAILED))
        .bind(2, why).bind(3, now_ms).bind(4, *seq).run();
  }
  t.commit();
  result.job = load_job_locked(job_id);
  return result;
}

void UnitQueue::batch_requeue(const std::string& job_id, std::uint32_t first, std::uint32_t count,
                             const std::string& worker) {
  std::lock_guard lock(mutex_);
  Query(db_->prepared("UPDATE tiles SET state = 0, worker = '', scheduler = '' WHERE state = 1 AND idx >= ? "
                     "AND idx < ? AND job_seq = (SELECT seq FROM jobs WHERE id = ?) AND (? = '' OR worker = ?) "
                     "AND scheduler = ?"))
      .bind(1, first).bind(2, static_cast<std::int64_t>(first) + count).bind(3, job_id).bind(4, worker)
      .bind(5, worker).bind(6, scheduler_).run();
}

std::vector<UnitBatch> UnitQueue::quarantine_worker(const std::string& worker) {
  std::lock_guard lock(mutex_);
  SqlTransaction t(*db_);
  lock_jobs_of_tiles_locked("worker = ? AND state IN (1, 2)", worker);  // every job it touches
  // The done batches first (a batch is the tiles of one part), with what they added to the job.
  std::vector<UnitBatch> discarded;
  std::vector<std::int64_t> seqs;
  {
    Query s(db_->prepared(fmt::format(
                    "SELECT j.seq, j.id, t.part, COUNT(*), MIN(t.x0), MIN(t.y0), MAX(t.x1), MAX(t.y1) "
                    "FROM tiles t JOIN jobs j ON t.job_seq = j.seq WHERE t.worker = ? AND t.state = 2 "
                    "AND j.state IN {} GROUP BY j.seq, t.part ORDER BY j.seq, t.part",
                    kActiveSql)));
    s.bind(1, worker);
    while (s.step()) {
      UnitBatch b;
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
    const UnitBatch& b = discarded[i];
    Query(db_->prepared("UPDATE tiles SET state = 0, worker = '' WHERE job_seq = ? AND part = ? AND state = 2 AND worker = ?"))
        .bind(1, seq).bind(2, b.first).bind(3, worker).run();
    take_back_part_locked(seq, b.first, b.count);
  }
  // Its calls in flight and its results waiting for a spot check: nothing of them is kept.
  Query(db_->prepared(fmt::format("UPDATE tiles SET state = 0, worker = '', scheduler = '' WHERE worker = ? "
                                 "AND state = 1 AND scheduler = ? AND job_seq IN (SELECT seq FROM jobs WHERE state IN {})",
                                 kActiveSql)))
      .bind(1, worker).bind(2, scheduler_).run();
  t.commit();
  return discarded;
}

std::vector<UnitBatch> UnitQueue::requeue_parts(const std::string& job_id, const std::vector<std::uint32_t>& parts) {
  std::lock_guard lock(mutex_);
  SqlTransaction t(*db_);
  lock_job_locked(job_id);
  std::vector<UnitBatch> taken;
  const std::optional<std::int64_t> active = active_seq_locked(job_id);
  if (!active) return taken;
  const std::int64_t seq = *active;
  for (std::uint32_t part : parts) {
    UnitBatch b;
    b.job_id = job_id;
    b.first = part;
    {
      Query s(db_->prepared("SELECT COUNT(*), MIN(x0), MIN(y0), MAX(x1), MAX(y1) FROM tiles "
                           "WHERE job_seq = ? AND part = ? AND state = 2"));
      s.bind(1, seq).bind(2, part);
      if (!s.step() || s.i64(0) == 0) continue;
      b.count = static_cast<std::uint32_t>(s.i64(0));
      b.rect = {s.i32(1), s.i32(2), s.i32(3), s.i32(4)};
    }
    Query(db_->prepared("UPDATE tiles SET state = 0, worker = '' WHERE job_seq = ? AND part = ? AND state = 2"))
        .bind(1, seq).bind(2, part).run();
    take_back_part_locked(seq, part, b.count);
    taken.push_back(std::move(b));
  }
  t.commit();
  return taken;
}

}  // namespace farm
