#pragma once
// The scheduler's durable state: jobs and their tiles in SQLite (WAL) under the data dir. Every
// state change is one transaction, so a scheduler killed at any point reopens to a consistent
// store; open() puts tiles that were running back in the queue (their results were lost with the
// process) and keeps done tiles done (their data is on disk, written before they were marked).
//
// Schema (version 1):
//   schema_version(version)
//   jobs(seq INTEGER PRIMARY KEY   -- submission order
//        id TEXT UNIQUE, name, spec BLOB (farm.v1.JobSpec), scene_hash, engine, width, height,
//        priority, state (farm.v1.JobState), submitted_ms, started_ms, finished_ms (Unix ms, 0 =
//        not yet), failure_reason, tiles_total, tiles_done, tile_failures, tiles_rendered,
//        stats BLOB (farm.v1.TileStats, summed over done tiles), validation, render_seconds)
//   tiles(job_seq, idx, x0, y0, x1, y1, state (0 queued, 1 running, 2 done, 3 failed), attempts,
//         last_error, worker; PRIMARY KEY (job_seq, idx))
// The store is one connection behind a mutex: the scheduler's writes are a few per tile.
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "proto/farm.pb.h"
#include "renderer/image/tile_buffer.h"

struct sqlite3;

namespace farm {

enum class TileState : int { Queued = 0, Running = 1, Done = 2, Failed = 3 };

struct NewJob {
  std::string id;
  std::string name;
  v1::JobSpec spec;
  std::string scene_hash;
  std::string engine;
  int width = 0, height = 0;
  int priority = 0;
  std::vector<Rect> tiles;
};

struct TileRecord {
  std::string job_id;
  std::uint32_t index = 0;
  Rect rect;
  TileState state = TileState::Queued;
  int attempts = 0;
  std::string last_error;
  std::string worker;
};

// A tile handed to a worker by claim_next_tile (now `running`).
struct TileClaim {
  std::string job_id;
  std::uint32_t index = 0;
  Rect rect;
  int attempts = 0;  // failed attempts before this one
};

// What tile_failed did.
struct TileFailure {
  bool will_retry = false;  // false: the job is now FAILED with the reason
  v1::Job job;
};

class JobStore {
 public:
  // Opens (creating) <file>, WAL mode; requeues running tiles. std::runtime_error on SQLite errors.
  explicit JobStore(const std::filesystem::path& file);
  ~JobStore();
  JobStore(const JobStore&) = delete;
  JobStore& operator=(const JobStore&) = delete;

  // Inserts the job (QUEUED) and its queued tiles. Returns it as v1::Job.
  v1::Job add_job(const NewJob& job, std::int64_t now_ms);

  std::optional<v1::Job> get_job(const std::string& id) const;
  std::optional<v1::JobSpec> get_spec(const std::string& id) const;
  // Newest first; `states` empty = all; starts below submission order `before_seq` (0 = newest).
  // Returns the jobs and the seq to continue from (0 = no more).
  std::pair<std::vector<v1::Job>, std::int64_t> list_jobs(const std::vector<v1::JobState>& states,
                                                         int limit, std::int64_t before_seq) const;
  std::vector<TileRecord> tiles(const std::string& id) const;
  // Jobs QUEUED or RUNNING, in submission order.
  std::vector<std::string> active_jobs() const;

  // The next queued tile of an active job: highest priority, then earliest submission, then tile
  // index. Marks it running on `worker` and the job RUNNING (started_at set on the first claim).
  std::optional<TileClaim> claim_next_tile(const std::string& worker, std::int64_t now_ms);

  // The tile's data is on disk: marks it done and adds its stats, if it is still running on an
  // active job (false otherwise: the job was cancelled or failed, or the tile was requeued).
  bool tile_done(const std::string& job_id, std::uint32_t index, const v1::TileStats& stats);
  // Counts a failed attempt. Below max_attempts the tile is queued again; at max_attempts the job
  // FAILS with `reason`. Nothing happens (will_retry false, job as it is) unless the tile is
  // running on an active job.
  TileFailure tile_failed(const std::string& job_id, std::uint32_t index, const std::string& reason,
                          int max_attempts, std::int64_t now_ms);
  // Puts a running tile back in the queue without counting an attempt (a shutdown, not a failure).
  void tile_requeue(const std::string& job_id, std::uint32_t index);

  // Final states. Each is a no-op (returns the job as it is) when the job is already final.
  v1::Job finish_job(const std::string& id, v1::JobState state, const std::string& reason,
                     const std::string& validation, std::int64_t now_ms);
  v1::Job cancel_job(const std::string& id, std::int64_t now_ms);

 private:
  void exec(const char* sql) const;
  v1::Job load_job_locked(const std::string& id) const;

  mutable std::mutex mutex_;
  sqlite3* db_ = nullptr;
};

bool is_final(v1::JobState state);
std::int64_t unix_ms_now();

}  // namespace farm
