#pragma once
// Where a job may run on a farm (docs/architecture.md, "Scheduling"): the worker tags it needs
// (all of them) and the fewest threads a worker must have. The job file's `requirements`; `farm
// render` reads and ignores them, a scheduler hands the job's units only to workers that meet
// them. A worker's tags are `farm worker --tag`s, spelled as job tags are.
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace farm {

inline constexpr std::size_t kMaxWorkerTags = 16;      // on a job, and on a worker
inline constexpr std::size_t kMaxWorkerTagBytes = 64;
inline constexpr int kMaxRequiredThreads = 1024;

// What is wrong with `tag` as a worker tag (1 to 64 of A-Z a-z 0-9 . _ -), or nothing.
std::optional<std::string> worker_tag_problem(std::string_view tag);
// `tags` sorted, each once: how jobs and workers keep them.
void sort_worker_tags(std::vector<std::string>& tags);

struct WorkerRequirements {
  std::vector<std::string> tags;  // sorted, each once
  int min_threads = 0;            // 0: any worker

  bool empty() const { return tags.empty() && min_threads == 0; }
  // Whether a worker with `worker_tags` and `threads` (0: not known, which meets no minimum)
  // may render the job.
  bool met_by(const std::vector<std::string>& worker_tags, int threads) const;
  // What a worker with those lacks, in words ("the tag big-mem", "8 threads (it has 2)"); empty
  // when it lacks nothing.
  std::string lacking(const std::vector<std::string>& worker_tags, int threads) const;
  // The requirements in words ("the tags big-mem, gpu and 8 threads").
  std::string describe() const;
  bool operator==(const WorkerRequirements&) const = default;
};

// How much of a farm a job may hold at once (the job file's `limits`; docs/architecture.md,
// "Scheduling"): a studio farm's machine limit. 0: no cap.
inline constexpr int kMaxJobCap = 1'000'000;
struct JobCaps {
  int max_workers = 0;          // workers rendering its units at once
  int max_units_in_flight = 0;  // its units handed out and not yet back
  bool operator==(const JobCaps&) const = default;
};

// Tags as the store keeps them: joined by commas (tags hold none), and split back.
std::string join_worker_tags(const std::vector<std::string>& tags);
std::vector<std::string> split_worker_tags(std::string_view joined);

}  // namespace farm
