#pragma once
// The scheduler's /metrics in Prometheus's text exposition format (version 0.0.4): jobs by state,
// the queue's depth, workers by state, units done and failed, units a second over the last
// minute, and how long a batch takes from being handed out to being kept.
#include <string>
#include <vector>

#include "proto/farm.pb.h"
#include "server/scheduler/dispatch/unit_metrics.h"
#include "server/scheduler/store/job_store.h"

namespace farm {

std::string prometheus_text(const JobRecords::Counts& counts, const std::vector<v1::WorkerInfo>& workers,
                            const UnitMetrics::Snapshot& units);

}  // namespace farm
