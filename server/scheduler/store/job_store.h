#pragma once
// The scheduler's durable state: jobs and their tiles, in SQLite (WAL) under the data dir by
// default or in a PostgreSQL database (`--store postgresql://...`), both through SqlConnection.
// Every state change is one transaction, so a scheduler killed at any point reopens to a
// consistent store; opening puts tiles that were running back in the queue (their results were
// lost with the process) and keeps done tiles done (their data is on disk, written before they
// were marked).
//
// Schema (version 10; a SQLite store of version 1 to 9 is upgraded in place, a PostgreSQL store,
// which began at 6 in PostgreSQL's types, from 6):
//   schema_version(version)
//   jobs(seq INTEGER PRIMARY KEY   -- submission order
//        id TEXT UNIQUE, name, spec BLOB (farm.v1.JobSpec), scene_hash, engine, width, height,
//        priority, state (farm.v1.JobState), submitted_ms, started_ms, finished_ms (Unix ms, 0 =
//        not yet), failure_reason, tiles_total, tiles_done, tile_failures, tiles_rendered,
//        stats BLOB (farm.v1.TileStats, summed over done tiles), validation, render_seconds,
//        owner (version 3: the submitter's token name, '' without tokens), frame_first,
//        frame_last, frame_step, frames_total, frames_done (version 5: the frames it renders and
//        how many are merged; a still is frame 0 alone), passes (version 6: sample passes a
//        frame is rendered in, 1 without), paused (version 8: an operator paused it: none of
//        its units is claimed), required_tags (version 9: the worker tags it needs, comma-joined),
//        min_threads (version 9: the fewest threads a worker of it must have; 0 any),
//        max_workers, max_units_in_flight (version 10: its caps; 0 none), after_frames_seq
//        (version 10: the job it follows frame by frame; 0 none))
//   tiles(job_seq, idx, x0, y0, x1, y1, state (0 queued, 1 running, 2 done, 3 failed), attempts,
//         last_error, worker, part (done tiles: the first tile of the batch whose result file
//         holds them), lost_attempts (version 4: renderings lost with their worker, counted apart
//         from attempts), frame (version 5: the frame it is a tile of), pass (version 6: the
//         sample pass it renders), scheduler (version 7: running tiles: the scheduler that
//         handed it out); PRIMARY KEY (job_seq, idx))
//   schedulers(id TEXT PRIMARY KEY, lease_until_ms)  -- version 7: the schedulers' leases
//   claims(job_seq, what ('frame N', 'end'), scheduler; PRIMARY KEY (job_seq, what))  -- version 7:
//         who merges a frame, who ends a job
//   parts(job_seq, part, stats BLOB (farm.v1.TileStats of the batch); PRIMARY KEY (job_seq, part))
//   frames(job_seq, frame; PRIMARY KEY (job_seq, frame))  -- version 5: the frames merged
//   job_log(job_seq, n, at_ms, event BLOB (farm.v1.JobEvent); PRIMARY KEY (job_seq, n))  -- version
//         8: the job's events, numbered from 1 (append_log)
//   dependencies(job_seq, on_seq, on_id, any_end; PRIMARY KEY (job_seq, on_seq))  -- version 10:
//         the jobs a job waits for (any_end: whatever their end), kept by id when they are deleted
//   owners(owner TEXT PRIMARY KEY, pass, weight_milli)  -- version 10: fair share (owner_shares.h)
// A job's tiles (its units) are numbered frame after frame and, within a frame, pass after pass:
// idx = (k * passes + pass) * (tiles of a frame's grid) + tile, k the frame's place among the
// job's frames, so that the queue hands out a frame's passes in order.
// Tiles go out in batches: consecutive tiles of one row of one frame's grid in one pass, rendered
// by one call as the rectangle they make up, so that per-call costs are paid once per batch.
// The store is one connection behind a mutex, its statements prepared once. Any call may throw
// DiskFull (server/common/disk_full.h) when SQLite finds no room (SQLITE_FULL), or
// StoreUnavailable (store/postgres_connection.h) when the PostgreSQL server cannot be reached: its
// transaction is rolled back, so the store stays as it was and the call can be made again later.
//
// The store is split by concern (docs/architecture.md, "Stores"), each part one class over the
// shared connection: jobs() (JobRecords), units() (UnitQueue: claims and what becomes of a batch),
// frames() (FrameRecords), leases() (SchedulerLeases), log() (EventLog) and dependencies()
// (JobDependencies; fair share's rows are owner_shares.h's); the schema and its
// upgrades are store_schema.cpp's.
#include <filesystem>
#include <memory>
#include <string>

#include "server/scheduler/store/event_log.h"
#include "server/scheduler/store/frame_records.h"
#include "server/scheduler/store/job_dependencies.h"
#include "server/scheduler/store/job_records.h"
#include "server/scheduler/store/scheduler_leases.h"
#include "server/scheduler/store/store_part.h"
#include "server/scheduler/store/store_schema.h"
#include "server/scheduler/store/unit_queue.h"

namespace farm {

class JobStore {
 public:
  // Opens (creating) the SQLite store <file>, WAL mode; requeues running units.
  // std::runtime_error on SQLite errors.
  explicit JobStore(const std::filesystem::path& sqlite_file);
  // The store on `db`, its schema made or upgraded; requeues running units.
  explicit JobStore(std::unique_ptr<SqlConnection> db);
  ~JobStore();
  JobStore(const JobStore&) = delete;
  JobStore& operator=(const JobStore&) = delete;

  // Where it is, for messages: the file, or the URL without a password.
  std::string describe() const;
  // Whether several schedulers may share it (PostgreSQL): they then hold leases (leases()).
  bool is_shared() const { return session_->db->dialect() == SqlDialect::PostgreSQL; }

  JobRecords& jobs() { return jobs_; }
  const JobRecords& jobs() const { return jobs_; }
  UnitQueue& units() { return units_; }
  const UnitQueue& units() const { return units_; }
  FrameRecords& frames() { return frames_; }
  const FrameRecords& frames() const { return frames_; }
  SchedulerLeases& leases() { return leases_; }
  const SchedulerLeases& leases() const { return leases_; }
  EventLog& log() { return log_; }
  const EventLog& log() const { return log_; }
  JobDependencies& dependencies() { return dependencies_; }
  const JobDependencies& dependencies() const { return dependencies_; }

 private:
  std::unique_ptr<StoreSession> session_;  // before the parts, which hold references into it
  JobRecords jobs_;
  UnitQueue units_;
  FrameRecords frames_;
  SchedulerLeases leases_;
  EventLog log_;
  JobDependencies dependencies_;
};

}  // namespace farm
