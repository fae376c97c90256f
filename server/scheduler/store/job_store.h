#pragma once
// The scheduler's durable state: jobs and their tiles, in SQLite (WAL) under the data dir by
// default or in a PostgreSQL database (`--store postgresql://...`), both through SqlConnection.
// Every state change is one transaction, so a scheduler killed at any point reopens to a
// consistent store; opening puts tiles that were running back in the queue (their results were
// lost with the process) and keeps done tiles done (their data is on disk, written before they
// were marked).
//
// Schema (version 8; a SQLite store of version 1 to 7 is upgraded in place, a PostgreSQL store,
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
//        its units is claimed))
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
// A job's tiles (its units) are numbered frame after frame and, within a frame, pass after pass:
// idx = (k * passes + pass) * (tiles of a frame's grid) + tile, k the frame's place among the
// job's frames, so that the queue hands out a frame's passes in order.
// Tiles go out in batches: consecutive tiles of one row of one frame's grid in one pass, rendered
// by one call as the rectangle they make up, so that per-call costs are paid once per batch.
// The store is one connection behind a mutex, its statements prepared once. Any call may throw
// DiskFull (server/common/disk_full.h) when SQLite finds no room (SQLITE_FULL), or
// StoreUnavailable (store/postgres_connection.h) when the PostgreSQL server cannot be reached: its
// transaction is rolled back, so the store stays as it was and the call can be made again later.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "proto/farm.pb.h"
#include "renderer/image/tile_buffer.h"
#include "server/common/job_state.h"
#include "server/scheduler/store/sql_connection.h"

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
  std::string owner;  // who submitted it: the name of the caller's token (empty: no tokens)
  std::vector<int> frames{0};  // ascending, evenly `frame_step` apart; a still: frame 0
  int frame_step = 1;
  int passes = 1;              // sample passes of each frame (pass_count of its settings)
  std::vector<Rect> tiles;     // one frame's grid: every frame has these tiles
};

struct TileRecord {
  std::string job_id;
  std::uint32_t index = 0;
  Rect rect;
  TileState state = TileState::Queued;
  int attempts = 0;
  int lost_attempts = 0;  // renderings lost with their worker (batch_lost), not counted in attempts
  std::string last_error;
  std::string worker;
  std::uint32_t part = 0;  // done tiles: the result file that holds them (TileResults)
  int frame = 0;
  int pass = 0;
};

// A done batch of a frame: the part (TileResults) that holds it, and the sample pass it rendered.
struct FramePart {
  std::uint32_t part = 0;
  int pass = 0;
  bool operator==(const FramePart&) const = default;
};

// Tiles first .. first + count - 1 of a job, handed to a worker by claim_next_batch (now
// `running`): one row segment of the job's grid, `rect` their union.
struct TileBatch {
  std::string job_id;
  std::uint32_t first = 0;
  std::uint32_t count = 1;
  Rect rect;
  int attempts = 0;       // failed attempts before this one (a batch of more than one: 0)
  int lost_attempts = 0;  // workers lost while rendering it before (a batch of more than one: 0)
  int frame = 0;          // the frame its tiles belong to
  int pass = 0;           // the sample pass they render
  bool started_job = false;  // this claim took the job from QUEUED to RUNNING
  // When this process handed it out (the dispatcher's unit latency, unit_metrics.h).
  std::chrono::steady_clock::time_point handed_out = {};
};

// How many tiles the next batch of `job_id` may hold, given how many of its tiles are queued
// (counted only up to claim_next_batch's `count_up_to`).
using BatchSize = std::function<int(const std::string& job_id, int queued_tiles)>;

// Which jobs ListJobs returns; each part left empty keeps every job.
struct JobFilter {
  std::vector<v1::JobState> states = {};
  std::optional<std::string> owner = {};  // the name of the token that submitted it
  // A shell glob on the job's name: `*` any run, `?` any one character; case-insensitive (ASCII).
  std::string name = {};
  std::string id_prefix = {};  // the start of its id (lowercase hex)
};

// `text` matched literally by LIKE with `\` as its escape: `%`, `_` and `\` escaped.
std::string like_escaped(const std::string& text);
// `glob` as a LIKE pattern with `\` as its escape: `*` -> `%`, `?` -> `_`, and the characters LIKE
// reads as its own (`%`, `_`, `\`) escaped.
std::string like_pattern_of_glob(const std::string& glob);

// What retry_job did.
struct RetriedJob {
  bool retried = false;             // false: the job was not FAILED or CANCELLED, and is unchanged
  v1::Job job;                      // as it is now
  std::uint32_t units_queued = 0;   // units queued again
};

// A job keeps this many log entries; past them only the essential ones (append_log).
inline constexpr std::int64_t kMaxLogEntries = 10000;

// A scheduler whose lease ran out, and how many of the tiles it had handed out came back.
struct ReapedScheduler {
  std::string id;
  std::int64_t tiles_queued_again = 0;
};

// What batch_failed did.
struct TileFailure {
  bool will_retry = false;  // false: the job is now FAILED with the reason
  v1::Job job;
};

// The connection for a store location: PostgreSQL for a postgresql:// (or postgres://) URL, else
// the SQLite file `location`. StoreUnavailable when the server cannot be reached.
std::unique_ptr<SqlConnection> connect_store(const std::string& location);

class JobStore {
 public:
  // Opens (creating) the SQLite store <file>, WAL mode; requeues running tiles.
  // std::runtime_error on SQLite errors.
  explicit JobStore(const std::filesystem::path& sqlite_file);
  // The store on `db`, its schema made or upgraded; requeues running tiles.
  explicit JobStore(std::unique_ptr<SqlConnection> db);
  ~JobStore();
  JobStore(const JobStore&) = delete;
  JobStore& operator=(const JobStore&) = delete;

  // Inserts the job (QUEUED) and its queued tiles. Returns it as v1::Job.
  v1::Job add_job(const NewJob& job, std::int64_t now_ms);

  // Where it is, for messages: the file, or the URL without a password.
  std::string describe() const;
  // Whether several schedulers may share it (PostgreSQL): they then hold leases (set_scheduler).
  bool is_shared() const { return db_->dialect() == SqlDialect::PostgreSQL; }

  std::optional<v1::Job> get_job(const std::string& id) const;
  std::optional<v1::JobSpec> get_spec(const std::string& id) const;
  // The jobs that `filter` keeps, newest first, starting below submission order `before_seq`
  // (0 = newest). Returns the jobs and the seq to continue from (0 = no more).
  std::pair<std::vector<v1::Job>, std::int64_t> list_jobs(const JobFilter& filter, int limit,
                                                         std::int64_t before_seq) const;
  std::vector<TileRecord> tiles(const std::string& id) const;
  // Jobs QUEUED or RUNNING, in submission order.
  std::vector<std::string> active_jobs() const;

  // The next queued tile of an active job (highest priority, then earliest submission, then tile
  // index) and, when `batch_size` allows more than one, the queued tiles that follow it in the
  // same grid row, never one that failed before (a tile that failed goes alone). Without
  // `batch_size`, one tile. Marks them running on `worker` and the job RUNNING (started_at set
  // on the first claim).
  // Queued tiles are counted for `batch_size` up to `count_up_to` (a count past what changes its
  // answer costs every claim as much as the queue is long).
  // Jobs for which `skip_job(job_id)` is true are passed over (the worker is kept off them).
  std::optional<TileBatch> claim_next_batch(const std::string& worker, std::int64_t now_ms,
                                            const BatchSize& batch_size = {}, int count_up_to = 1024,
                                            const std::function<bool(const std::string&)>& skip_job = {});

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
  // Several schedulers on one store (PostgreSQL). Each marks the tiles it hands out with its id
  // (set_scheduler, once, before any claim; "" until then) and the batch operations below act only
  // on tiles this store's scheduler handed out. A scheduler holds a lease in the store, renewed
  // (hold_lease) well before it runs out; when one runs out (the scheduler was killed, or lost the
  // store or its machine), any other's reap_expired queues its running tiles again with no
  // attempt counted, and a late answer to the dead one finds them running no more.
  void set_scheduler(const std::string& id);
  const std::string& scheduler() const { return scheduler_; }  // set once, before any thread asks
  void hold_lease(std::int64_t until_ms);
  // The lease given up (a scheduler that stops): its running tiles are queued again by itself.
  void drop_lease();
  // Every other scheduler whose lease ran out before `now_ms`: its running tiles queued again, its
  // claims (below) and its lease gone. One transaction.
  std::vector<ReapedScheduler> reap_expired(std::int64_t now_ms);
  // Work on a job that one scheduler must do alone, though several may find it to do: merging a
  // frame whose units are all done, ending a job whose frames are all merged. True when it is this
  // store's scheduler's (claimed now, or before); false when another holds it. A claim lasts
  // while its scheduler's lease does; a frame's, until a part of it is taken back.
  bool claim_frame_merge(const std::string& job_id, int frame);
  bool claim_job_end(const std::string& job_id);

  // Puts a running batch back in the queue without counting an attempt (a shutdown, not a failure).
  void batch_requeue(const std::string& job_id, std::uint32_t first, std::uint32_t count,
                     const std::string& worker = {});
  // Nothing `worker` rendered for a job still running is kept: its done tiles of active jobs are
  // queued again (their stats taken out of their jobs'; tiles_rendered keeps counting them) and
  // so are the tiles running on it. One transaction. Returns the done batches it took back.
  std::vector<TileBatch> quarantine_worker(const std::string& worker);

  // The done batches (by part) of an active job whose kept data turned out damaged at the merge:
  // their tiles are queued again without counting an attempt, their stats taken out of the job's
  // (tiles_rendered keeps counting them); the job stays active. One transaction. Returns the
  // batches it took back (none when the job is final, or a part has no done tiles).
  std::vector<TileBatch> requeue_parts(const std::string& job_id, const std::vector<std::uint32_t>& parts);

  // Frames. The job's frames whose tiles are all done and which are not merged yet: `frame`
  // alone when given (after one of its batches was done), else every such frame (a restart).
  std::vector<int> complete_frames(const std::string& job_id, std::optional<int> frame = std::nullopt) const;
  // The parts (TileResults) that hold the frame's done tiles of passes 0 .. passes - 1, in pass
  // order (then by part).
  std::vector<FramePart> frame_parts(const std::string& job_id, int frame, int passes) const;
  // How many of the frame's sample passes are done from the first on: p when every tile of
  // passes 0 .. p - 1 is done and one of pass p is not (the job's passes when all are; 0 for an
  // unknown job). A frame's progressive preview shows these.
  int complete_passes(const std::string& job_id, int frame) const;
  // The frame is merged and its files written: counted in frames_done, if the job is active and
  // the frame's tiles are all still done (false otherwise: a quarantine took some back, and the
  // frame is merged again once they are rendered again). A part taken back later (quarantine,
  // damage, room for other jobs) makes its frame unmerged again.
  bool frame_merged(const std::string& job_id, int frame);
  // Whether the frame of the job is merged (its files can be fetched).
  bool is_frame_merged(const std::string& job_id, int frame) const;

  // Final states. Each is a no-op (returns the job as it is) when the job is already final, and
  // SUCCEEDED also when not every tile is done (quarantine_worker took some back) or not every
  // frame is merged.
  v1::Job finish_job(const std::string& id, v1::JobState state, const std::string& reason,
                     const std::string& validation, std::int64_t now_ms);
  v1::Job cancel_job(const std::string& id, std::int64_t now_ms);

  // Operator actions; each returns the job as it is now, nullopt when there is no such job.
  // A paused job keeps its state, and none of its units is claimed until it is resumed; only an
  // active job is paused or resumed (a final one is returned unchanged).
  std::optional<v1::Job> set_paused(const std::string& id, bool paused);
  std::optional<v1::Job> set_priority(const std::string& id, int priority);
  // A FAILED or CANCELLED job active again: its units not done queued with no attempt counted,
  // done units and merged frames kept, its claims dropped, its failure reason cleared, not paused.
  // RUNNING when some unit is done, else QUEUED. One transaction.
  std::optional<RetriedJob> retry_job(const std::string& id);
  // A final job and every row of it (tiles, frames, parts, claims, log) gone: true; false (and
  // nothing done) when the job is active. One transaction.
  std::optional<bool> delete_job(const std::string& id);
  // How many jobs are in each state (paused ones counted in theirs), how many of the active ones
  // are paused, and how many units wait in the queue of jobs that are not: the dashboard's /metrics.
  struct Counts {
    std::map<v1::JobState, std::int64_t> jobs;
    std::int64_t paused = 0;
    std::int64_t queued_units = 0;
  };
  Counts counts() const;
  // Final jobs that finished before `ms` (Unix ms), oldest first, at most `limit`.
  std::vector<std::string> finished_before(std::int64_t ms, int limit) const;

  // The job's event log: `event` (its job the job then) appended as the next entry, at `now_ms`.
  // Past `limit` entries only an `essential` event is kept. Nothing for a job that is gone.
  void append_log(const v1::JobEvent& event, std::int64_t now_ms, bool essential,
                  std::int64_t limit = kMaxLogEntries);
  // Entries numbered above `after`, in order, at most `limit`; `more` says whether others follow.
  std::vector<v1::JobLogEntry> job_log(const std::string& id, std::uint32_t after, int limit,
                                       bool* more = nullptr) const;

 private:
  enum class AttemptKind { Failed, WorkerLost };
  // batch_failed and batch_lost: the same bookkeeping on their own count and limit.
  TileFailure count_attempt(AttemptKind kind, const std::string& job_id, std::uint32_t first, std::uint32_t count,
                            const std::string& reason, int max, std::int64_t now_ms, const std::string& worker);
  void open_sqlite();    // the schema made, or upgraded from versions 1 to 5
  void open_postgres();  // the schema made, under a lock that other schedulers wait on
  v1::Job load_job_locked(const std::string& id) const;
  std::optional<v1::Job> find_job_locked(const std::string& id) const;
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

  int stored_version();                       // the schema's; a new store's recorded as this one's
  [[noreturn]] void refuse_version(int version) const;  // a version this farm cannot read
  void upgrade_from_6(int version);           // the upgrades written for both stores
  bool claim_locked(const std::string& job_id, const std::string& what);

  mutable std::mutex mutex_;
  std::unique_ptr<SqlConnection> db_;
  std::string scheduler_;  // set_scheduler
};

}  // namespace farm
