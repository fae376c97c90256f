#pragma once
// The values the job store's parts take and give (job_store.h): a new job, a unit's record, a
// batch of units, a frame's part, and what a failed batch, a retry or a reaped lease did.
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "proto/farm.pb.h"
#include "renderer/image/tile_buffer.h"
#include "renderer/job/worker_requirements.h"
#include "server/common/job_state.h"

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
  WorkerRequirements requirements;  // the workers that may render it
  JobCaps caps;                     // 0: no cap
  // Its dependencies (job ids, SubmitJobRequest.after, after_any, after_frames): with any in
  // `after` or `after_any` it is queued WAITING. Each must name a job in the store.
  std::vector<std::string> after, after_any;
  std::string after_frames;
  // Fair share: the weight of the owner's share (the tokens file's), in thousandths (1000: 1).
  std::int64_t owner_weight_milli = 1000;
};

// A dependency that cannot be recorded: no such job, too many, a cycle, or a job that has already
// started. The message names the job ids.
struct DependencyError : std::runtime_error {
  enum class Kind { UnknownJob, TooMany, Cycle, Started };
  DependencyError(Kind k, const std::string& what) : std::runtime_error(what), kind(k) {}
  Kind kind;
};

// A job whose dependencies settled it (JobDependencies::release_waiting): WAITING -> QUEUED, or
// FAILED naming the dependency; `job` as it is now.
struct ReleasedJob {
  v1::Job job;
  v1::JobState from = v1::JOB_STATE_WAITING;
};

struct UnitRecord {
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
struct UnitBatch {
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

// "tile 7" or "tiles 7-9", for messages about a batch.
inline std::string describe(const UnitBatch& batch) { return describe_units(batch.first, batch.count); }

// How many tiles the next batch of `job_id` may hold, given how many of its tiles are queued
// (counted only up to claim_next_batch's `count_up_to`).
using BatchSize = std::function<int(const std::string& job_id, int queued_tiles)>;

// What the worker a claim is for offers (its registration's tags and threads): units of a job
// whose requirements it does not meet are not claimed for it.
struct WorkerOffer {
  std::vector<std::string> tags = {};
  int threads = 0;  // 0: not known
};

// Which jobs ListJobs returns; each part left empty keeps every job.
struct JobFilter {
  std::vector<v1::JobState> states = {};
  std::optional<std::string> owner = {};  // the name of the token that submitted it
  // A shell glob on the job's name: `*` any run, `?` any one character; case-insensitive (ASCII).
  std::string name = {};
  std::string id_prefix = {};  // the start of its id (lowercase hex)
};

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

}  // namespace farm
