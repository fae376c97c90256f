#include "server/common/job_state.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

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

std::string describe_dependencies(const v1::Job& job) {
  std::vector<std::string> parts;
  if (job.after_size() > 0) parts.push_back(fmt::format("after {}", fmt::join(job.after(), ", ")));
  if (job.after_any_size() > 0) parts.push_back(fmt::format("after any end of {}", fmt::join(job.after_any(), ", ")));
  if (!job.after_frames().empty()) parts.push_back("frame by frame after " + job.after_frames());
  return fmt::format("{}", fmt::join(parts, "; "));
}

std::int64_t unix_ms_now() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::optional<v1::JobState> job_state_named(std::string_view name) {
  for (v1::JobState s : kJobStates) {
    if (to_string(s) == name) return s;
  }
  return std::nullopt;
}

std::string to_string(v1::JobState state) {
  switch (state) {
    case v1::JOB_STATE_QUEUED: return "queued";
    case v1::JOB_STATE_RUNNING: return "running";
    case v1::JOB_STATE_SUCCEEDED: return "succeeded";
    case v1::JOB_STATE_FAILED: return "failed";
    case v1::JOB_STATE_CANCELLED: return "cancelled";
    case v1::JOB_STATE_WAITING: return "waiting";
    default: return "unknown";
  }
}

}  // namespace farm
