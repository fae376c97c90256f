#include "server/scheduler/jobs/retention.h"

#include <algorithm>

#include "server/common/job_state.h"

namespace farm {

RetentionSweeper::RetentionSweeper(std::chrono::milliseconds keep, spdlog::logger& log,
                                   std::function<std::size_t(std::int64_t)> sweep)
    : keep_(keep),
      log_(log),
      sweep_(std::move(sweep)),
      thread_(std::clamp<std::chrono::milliseconds>(keep / 10, std::chrono::seconds(1), std::chrono::minutes(10)),
              [this] { sweep_once(); }) {}

void RetentionSweeper::sweep_once() {
  try {
    const std::size_t removed = sweep_(unix_ms_now() - keep_.count());
    if (removed > 0) {
      log_.info("retention: {} job{} that ended over {} s ago deleted with their files", removed,
                removed == 1 ? "" : "s", keep_.count() / 1000);
    }
  } catch (const std::exception& e) {
    // The store away or full: the next round tries again.
    log_.warn("retention: {}", e.what());
  }
}

}  // namespace farm
