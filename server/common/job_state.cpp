#include "server/common/job_state.h"

#include <fmt/format.h>

#include <chrono>

namespace farm {

bool is_final(v1::JobState state) {
  return state == v1::JOB_STATE_SUCCEEDED || state == v1::JOB_STATE_FAILED ||
         state == v1::JOB_STATE_CANCELLED;
}

std::string describe_units(std::uint32_t first, std::uint32_t count) {
  return count > 1 ? fmt::format("units {}-{}", first, first + count - 1) : fmt::format("unit {}", first);
}

WorkerRequirements requirements_of(const v1::Job& job) {
  return {{job.required_tags().begin(), job.required_tags().end()}, job.min_threads()};
}

std::int64_t unix_ms_now() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string to_string(v1::JobState state) {
  switch (state) {
    case v1::JOB_STATE_QUEUED: return "queued";
    case v1::JOB_STATE_RUNNING: return "running";
    case v1::JOB_STATE_SUCCEEDED: return "succeeded";
    case v1::JOB_STATE_FAILED: return "failed";
    case v1::JOB_STATE_CANCELLED: return "cancelled";
    default: return "unknown";
  }
}

}  // namespace farm
