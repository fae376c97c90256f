#include "server/common/job_eta.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace farm {

std::optional<std::chrono::seconds> job_eta(const v1::Job& job, std::chrono::system_clock::time_point now) {
  if (job.state() != v1::JOB_STATE_RUNNING || job.paused() || job.tiles_done() == 0 || !job.has_started_at() ||
      job.started_at().seconds() == 0 || job.tiles_done() >= job.tiles_total()) {
    return std::nullopt;
  }
  const double started = static_cast<double>(job.started_at().seconds()) + job.started_at().nanos() * 1e-9;
  const double elapsed = std::chrono::duration<double>(now.time_since_epoch()).count() - started;
  if (!(elapsed > 0.0)) return std::nullopt;
  const double per_unit = elapsed / job.tiles_done();
  const double left = per_unit * static_cast<double>(job.tiles_total() - job.tiles_done());
  return std::chrono::seconds(static_cast<long long>(std::ceil(left)));
}

std::string short_duration(double s) {
  s = std::max(0.0, s);
  const auto whole = static_cast<long long>(s);
  if (s < 60) return fmt::format("{:.1f}s", s);
  if (s < 3600) return fmt::format("{}m{:02}s", whole / 60, whole % 60);
  return fmt::format("{}h{:02}m", whole / 3600, whole / 60 % 60);
}

}  // namespace farm
