#pragma once
// SubmitJob validates a job by loading its models and building its scene, as `farm render` does
// before it renders. Neither loader can be interrupted, and a hostile model within every byte
// limit can still hold a thread for hours (Assimp triangulates a polygon in quadratic time) or
// expand into gigabytes. So `farm scheduler` does that work in a child process, its own binary
// run as `farm check-scene`, under a memory limit (RLIMIT_AS, set by the child on itself before
// it reads anything) and a wall-clock limit (the child is killed when it passes it). The child
// says how it went in one line on its output, which the scheduler checks before trusting it.
//
// Scenes that passed are remembered by their hash (a bounded set), so a job submitted again does
// not pay for a second process.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <string>

#include "server/common/recent_hashes.h"

namespace farm {

struct SceneBudget {
  std::uint64_t memory_bytes = std::uint64_t{8} << 30;  // address space of the checking process
  std::chrono::milliseconds time = std::chrono::seconds(120);
  int max_parallel = 0;  // checks at once; 0: half the machine's hardware threads, at least 1
};

class SceneChecker {
 public:
  // `program`: the `farm` binary (what /proc/self/exe names for `farm scheduler`).
  SceneChecker(std::filesystem::path program, SceneBudget budget);

  // Returns once the job at `job_file` (its models under `asset_root`) loaded and built within
  // the budget. Throws InputError with the loaders' message for a bad job or model, and
  // ServiceError RESOURCE_EXHAUSTED naming `display_name`, the limit and its flag when the
  // budget ran out.
  void check(const std::string& scene_hash, const std::filesystem::path& job_file,
             const std::filesystem::path& asset_root, const std::string& display_name);

 private:
  // A check holds a core for up to the budget's time: at most max_parallel_ run at once, so a
  // burst of hostile submissions cannot take every core of the scheduler's machine.
  void acquire_slot(const std::string& display_name);
  void release_slot();

  std::filesystem::path program_;
  SceneBudget budget_;
  RecentHashes passed_{4096};
  const int max_parallel_;
  std::mutex mutex_;  // guards running_
  std::condition_variable slot_freed_;
  int running_ = 0;
};

// The child's side, run by `farm check-scene`: limits its own address space to `memory_bytes`,
// loads the job and builds its scene, prints its one-line verdict and returns the exit code.
int check_scene_in_this_process(const std::filesystem::path& job_file,
                                const std::filesystem::path& asset_root, std::uint64_t memory_bytes);

}  // namespace farm
