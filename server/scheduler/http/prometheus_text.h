#pragma once
// The scheduler's /metrics in Prometheus's text exposition format (version 0.0.4): jobs by state,
// the queue's depth, workers by state, units done and failed, units a second over the last
// minute, and how long a batch takes from being handed out to being kept.
#include <string>

#include "server/scheduler/front_door.h"

namespace farm {

std::string prometheus_text(const SchedulerMetrics& metrics);

}  // namespace farm
