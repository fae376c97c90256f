#pragma once
// The job store's unit queue (job_store.h): the next batch of queued units claimed for a worker,
// and what becomes of a batch: done, failed (an attempt counted), lost with its worker, put back,
// or taken back (a quarantined worker's results, damaged parts). Each method is one transaction.
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "proto/farm.pb.h"
#include "server/scheduler/store/store_part.h"

namespace farm {

class UnitQueue : public StorePart {
 public:
  explicit UnitQueue(StoreSession& session) : StorePart(session) {}

  // A job's units, in index order (its tiles of every frame and pass).
  std::vector<UnitRecord> tiles(const std::string& id) const;

  // The next queued tile of an active job (highest priority, then the owner with the least fair
  // share so far (owner_shares.h), then earliest submission, then tile index) and, when `batch_size` allows more than one, the queued tiles that follow it in the
  // same grid row, never one that failed before (a tile that failed goes alone). Without
  // `batch_size`, one tile. Marks them running on `worker` and the job RUNNING (started_at set
  // on the first claim).
  // Queued tiles are counted for `batch_size` up to `count_up_to` (a count past what changes its
  // answer costs every claim as much as the queue is long).
  // Jobs for which `skip_job(job_id)` is true are passed over (the worker is kept off them), and
  // so are jobs whose requirements `offer` does not meet (the default offer, no tags and threads
  // not known, meets only jobs without requirements), jobs at their caps (max_units_in_flight
  // units out; max_workers other workers rendering them), and, for a job that follows another
  // frame by frame, tiles of frames that job renders and has not merged. A batch holds no more
  // units than the job's max_units_in_flight leaves room for. The claimed units are charged to
  // the job's owner. With `whole_rows`, a batch whose first unit begins a grid row may go on with
  // whole rows after it (SchedulerOptions::whole_row_batches).
  std::optional<UnitBatch> claim_next_batch(const std::string& worker, std::int64_t now_ms,
                                            const BatchSize& batch_size = {}, int count_up_to = 1024,
                                            const std::function<bool(const std::string&)>& skip_job = {},
                                            const WorkerOffer& offer = {}, bool whole_rows = false);

  // The batch operations below act only on tiles running on `worker` (the id claim_next_batch was
  // given; empty: any), so that a late answer from a worker whose tiles were taken back never
  // touches tiles another worker has claimed since.
  //
  // The batch's data is on disk (TileResults part `first`): marks its tiles done and adds its
  // stats, if they are all still running on an active job (false otherwise: the job was
  // cancelled or failed, or the tiles were requeued).
  bool batch_done(const std::string& job_id, std::uint32_t first, std::uint32_t count,
                  const v1::TileStats& stats, const std::string& worker = {});
  // Counts a failed attempt on each of the batch's tiles. Below max_attempts they are queued
  // again; at max_attempts the job FAILS with `reason`. Nothing happens (will_retry false, job as
  // it is) unless the batch is running on an active job.
  TileFailure batch_failed(const std::string& job_id, std::uint32_t first, std::uint32_t count,
                           const std::string& reason, int max_attempts, std::int64_t now_ms,
                           const std::string& worker = {});
  // The batch's worker was lost while it rendered (its process died or stopped answering), which
  // says nothing about the tiles: no attempt counts against max_attempts. A lost-worker attempt
  // is counted instead, against its own limit: below max_lost_attempts the tiles are queued
  // again; at it the job FAILS, naming the losses, so that a tile that takes down every worker it
  // is sent to cannot go round for ever. Nothing happens unless the batch is running on an active
  // job, as with batch_failed.
  TileFailure batch_lost(const std::string& job_id, std::uint32_t first, std::uint32_t count,
                         const std::string& reason, int max_lost_attempts, std::int64_t now_ms,
                         const std::string& worker = {});

  // Puts a running batch back in the queue without counting an attempt (a shutdown, not a failure).
  void batch_requeue(const std::string& job_id, std::uint32_t first, std::uint32_t count,
                     const std::string& worker = {});
  // Nothing `worker` rendered for a job still running is kept: its done tiles of active jobs are
  // queued again (their stats taken out of their jobs'; tiles_rendered keeps counting them) and
  // so are the tiles running on it. One transaction. Returns the done batches it took back.
  std::vector<UnitBatch> quarantine_worker(const std::string& worker);

  // The done batches (by part) of an active job whose kept data turned out damaged at the merge:
  // their tiles are queued again without counting an attempt, their stats taken out of the job's
  // (tiles_rendered keeps counting them); the job stays active. One transaction. Returns the
  // batches it took back (none when the job is final, or a part has no done tiles).
  std::vector<UnitBatch> requeue_parts(const std::string& job_id, const std::vector<std::uint32_t>& parts);

 private:
  enum class AttemptKind { Failed, WorkerLost };
  // batch_failed and batch_lost: the same bookkeeping on their own count and limit.
  TileFailure count_attempt(AttemptKind kind, const std::string& job_id, std::uint32_t first, std::uint32_t count,
                            const std::string& reason, int max, std::int64_t now_ms, const std::string& worker);
};

}  // namespace farm
