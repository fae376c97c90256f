#pragma once
// Whether any worker the scheduler knows may render a job with requirements, and if none, why
// (docs/architecture.md, "Scheduling"): a job that cannot be placed says so in its status
// instead of waiting silently.
#include <string>
#include <vector>

#include "renderer/job/worker_requirements.h"
#include "server/scheduler/workers/worker_registry.h"

namespace farm {

// "" when some worker of `workers` that is not quarantined meets `requirements` (one that is down
// may come back); else what the job needs and what each worker lacks, the first few named.
std::string unplaceable_reason(const WorkerRequirements& requirements, const std::vector<WorkerStatus>& workers);

}  // namespace farm
