#include "server/scheduler/jobs/dependency_release.h"

#include "server/common/job_state.h"

namespace farm {

DependencyRelease::DependencyRelease(JobStore& store, spdlog::logger& log, std::chrono::milliseconds every,
                                     std::function<void(const std::vector<ReleasedJob>&)> on_settled)
    : store_(store), log_(log), on_settled_(std::move(on_settled)), thread_(every, [this] { release(); }) {}

void DependencyRelease::release() {
  try {
    const std::vector<ReleasedJob> settled = store_.dependencies().release_waiting(unix_ms_now());
    if (!settled.empty()) on_settled_(settled);
  } catch (const std::exception& e) {
    // The store away or full: the next look tries again, and finds the same jobs.
    log_.warn("releasing jobs whose dependencies ended: {}", e.what());
  }
}

}  // namespace farm
