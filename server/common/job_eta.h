#pragma once
// How long a running job still takes (issue #32: no ETA anywhere): its units' measured rate
// since it started, units done over the wall time since then, applied to the units left. One
// function for `farm status`, `farm watch` and (its twin in server/web/app.js) the job page.
#include <chrono>
#include <optional>
#include <string>

#include "proto/farm.pb.h"

namespace farm {

// nullopt unless the job is running, not paused, and has a unit done to measure by.
std::optional<std::chrono::seconds> job_eta(const v1::Job& job, std::chrono::system_clock::time_point now);

// "42.0s", "3m05s", "2h10m": a span of time as the job listings show it.
std::string short_duration(double seconds);

}  // namespace farm
