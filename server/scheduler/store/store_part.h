#pragma once
// What every part of the job store (job_store.h) works through: the one connection, the mutex that
// serialises its use and this scheduler's id (StoreSession, which JobStore owns), and the helpers
// the parts share. Each part (JobRecords, UnitQueue, FrameRecords, SchedulerLeases, EventLog) holds
// one concern's statements; its methods take the mutex, and a `_locked` helper expects it held.
#include <google/protobuf/timestamp.pb.h>

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "proto/farm.pb.h"
#include "server/scheduler/store/sql_connection.h"
#include "server/scheduler/store/store_records.h"

namespace farm {

struct StoreSession {
  explicit StoreSession(std::unique_ptr<SqlConnection> connection) : db(std::move(connection)) {}
  std::mutex mutex;
  std::unique_ptr<SqlConnection> db;
  std::string scheduler;  // SchedulerLeases::set_scheduler, once, before any claim
};

// The commit of a claim, a unit marked done, a merge claimed or recorded: what the farm does again
// when a crash of the database server loses it (the unit is rendered again, the frame merged again),
// so its commit does not wait for the server's disk. A job's submission, and its end, do.
inline constexpr SqlTransaction::Commit kRedoable = SqlTransaction::Commit::Unflushed;

// The columns job_from_row reads, in its order.
extern const char* const kJobColumns;
// "(QUEUED, RUNNING)" as numbers, for `state IN ...`.
extern const std::string kActiveSql;
// "(QUEUED, RUNNING, WAITING)": the states a job can still leave.
extern const std::string kUnfinishedSql;

google::protobuf::Timestamp timestamp(std::int64_t ms);
// A row of `SELECT kJobColumns FROM jobs` as the wire's Job.
v1::Job job_from_row(const Query& s);
// The counters and times of `t` added to `sum` (threads: the maximum), or taken out of it again
// (threads stays).
void add_stats(v1::TileStats& sum, const v1::TileStats& t);
void subtract_stats(v1::TileStats& sum, const v1::TileStats& t);

class StorePart {
 protected:
  explicit StorePart(StoreSession& session)
      : mutex_(session.mutex), db_(session.db.get()), scheduler_(session.scheduler) {}

  v1::Job load_job_locked(const std::string& id) const;
  std::optional<v1::Job> find_job_locked(const std::string& id) const;
  // The job's seq when it is active (QUEUED or RUNNING); nullopt otherwise.
  std::optional<std::int64_t> active_seq_locked(const std::string& job_id) const;
  // Several schedulers on one PostgreSQL store: the job's row locked for the rest of the
  // transaction, so that what the transaction reads of the job and its tiles (the first queued
  // tile, the stats it adds to) no other scheduler changes before it commits. Every transaction
  // that reads before it writes a job takes it first (SQLite's BEGIN IMMEDIATE already holds the
  // whole store). False when there is no such job.
  bool lock_job_locked(std::int64_t seq);
  bool lock_job_locked(const std::string& job_id);
  // The jobs of the tiles `tiles_where` (one `?`, bound to `value`) picks, locked in seq order, as
  // every transaction that touches several jobs takes them, so that no two deadlock.
  void lock_jobs_of_tiles_locked(const std::string& tiles_where, const std::string& value);
  // The job's seq when the batch's tiles are all running on an active job.
  std::optional<std::int64_t> running_batch_locked(const std::string& job_id, std::uint32_t first,
                                                   std::uint32_t count, const std::string& worker) const;
  // A done batch of `count` tiles taken back: its stats out of the job's, its parts row gone,
  // tiles_done lowered. The caller queues its tiles again.
  void take_back_part_locked(std::int64_t seq, std::uint32_t part, std::uint32_t count);

  std::mutex& mutex_;
  SqlConnection* const db_;
  std::string& scheduler_;
};

}  // namespace farm
