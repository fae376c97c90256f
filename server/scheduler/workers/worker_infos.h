#pragma once
// The workers as ListWorkers answers them (`farm workers`, the dashboard): each worker's state
// (up, down, backed off, quarantined, or lost a while ago, with when and why), what it said of
// itself, what it did, and what it renders now.
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "proto/farm.pb.h"
#include "server/scheduler/workers/worker_registry.h"

namespace farm {

struct WorkerActivity {
  // The calls in flight now, by worker id (Dispatcher::calls_in_flight).
  std::map<std::string, std::vector<std::string>> calls;
  // The jobs a worker is kept off (Dispatcher::blocked_jobs).
  std::function<std::vector<std::string>(const std::string& worker_id)> blocked_jobs;
};

// The registry's workers, then the ones lost lately.
std::vector<v1::WorkerInfo> worker_infos(const WorkerRegistry& registry, WorkerActivity activity);

}  // namespace farm
