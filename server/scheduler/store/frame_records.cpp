#include "server/common/job_state.h"
#include "server/scheduler/store/frame_records.h"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

namespace farm {

std::vector<int> FrameRecords::complete_frames(const std::string& job_id, std::optional<int> frame) const {
  std::lock_guard lock(mutex_);
  std::vector<int> out;
  const std::optional<std::int64_t> active = active_seq_locked(job_id);
  if (!active) return out;
  const std::int64_t seq = *active;
  if (frame) {
    // After each batch: one frame, unless it is merged, by seeks in tiles_by_frame (a count of its
    // tiles would read every one of them after every batch).
    Query merged(db_->prepared("SELECT 1 FROM frames WHERE job_seq = ? AND frame = ?"));
    merged.bind(1, seq).bind(2, *frame);
    if (merged.step()) return out;
    Query s(db_->prepared("SELECT EXISTS (SELECT 1 FROM tiles WHERE job_seq = ?1 AND frame = ?2), "
                         "EXISTS (SELECT 1 FROM tiles WHERE job_seq = ?1 AND frame = ?2 AND state IN (0, 1, 3))"));
    s.bind(1, seq).bind(2, *frame);
    if (s.step() && s.i64(0) == 1 && s.i64(1) == 0) out.push_back(*frame);
    return out;
  }
  // After a restart: every frame of the job, complete when none of its tiles is other than done.
  Query s(db_->prepared("SELECT t.frame FROM tiles t WHERE t.job_seq = ? AND NOT EXISTS (SELECT 1 FROM frames f "
                       "WHERE f.job_seq = t.job_seq AND f.frame = t.frame) GROUP BY t.frame "
                       "HAVING SUM(CASE WHEN t.state <> 2 THEN 1 ELSE 0 END) = 0 ORDER BY t.frame"));
  s.bind(1, seq);
  while (s.step()) out.push_back(s.i32(0));
  return out;
}

std::vector<FramePart> FrameRecords::frame_parts(const std::string& job_id, int frame, int passes) const {
  std::lock_guard lock(mutex_);
  Query s(db_->prepared("SELECT DISTINCT t.part, t.pass FROM tiles t JOIN jobs j ON t.job_seq = j.seq "
                       "WHERE j.id = ? AND t.frame = ? AND t.pass < ? AND t.state = 2 ORDER BY t.pass, t.part"));
  s.bind(1, job_id).bind(2, frame).bind(3, passes);
  std::vector<FramePart> out;
  while (s.step()) out.push_back({static_cast<std::uint32_t>(s.i64(0)), s.i32(1)});
  return out;
}

int FrameRecords::complete_passes(const std::string& job_id, int frame) const {
  std::lock_guard lock(mutex_);
  Query s(db_->prepared("SELECT j.passes, (SELECT MIN(t.pass) FROM tiles t WHERE t.job_seq = j.seq AND t.frame = ? "
                       "AND t.state != 2) FROM jobs j WHERE j.id = ?"));
  s.bind(1, frame).bind(2, job_id);
  if (!s.step()) return 0;
  return s.is_null(1) ? s.i32(0) : s.i32(1);  // no tile of it undone: every pass
}

bool FrameRecords::frame_merged(const std::string& job_id, int frame) {
  std::lock_guard lock(mutex_);
  SqlTransaction t(*db_, kRedoable);
  lock_job_locked(job_id);
  std::int64_t seq = 0;
  {
    Query s(db_->prepared(fmt::format(
                    "SELECT j.seq, SUM(CASE WHEN t.state <> 2 THEN 1 ELSE 0 END) FROM jobs j JOIN tiles t ON t.job_seq = j.seq "
                    "WHERE j.id = ? AND j.state IN {} AND t.frame = ? GROUP BY j.seq",
                    kActiveSql)));
    s.bind(1, job_id).bind(2, frame);
    if (!s.step() || s.i64(1) != 0) return false;
    seq = s.i64(0);
  }
  Query insert(db_->prepared("INSERT INTO frames (job_seq, frame) VALUES (?, ?) ON CONFLICT DO NOTHING"));
  insert.bind(1, seq).bind(2, frame).run();
  if (insert.changes() > 0) {
    Query(db_->prepared("UPDATE jobs SET frames_done = frames_done + 1 WHERE seq = ?")).bind(1, seq).run();
  }
  t.commit();
  return true;
}

bool FrameRecords::is_frame_merged(const std::string& job_id, int frame) const {
  std::lock_guard lock(mutex_);
  Query s(db_->prepared("SELECT 1 FROM frames f JOIN jobs j ON f.job_seq = j.seq WHERE j.id = ? AND f.frame = ?"));
  s.bind(1, job_id).bind(2, frame);
  return s.step();
}

}  // namespace farm
