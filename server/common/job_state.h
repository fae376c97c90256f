#pragma once
// Small facts about farm.v1 jobs that the scheduler, its store and the client all use.
#include <cstdint>
#include <string>

#include "proto/farm.pb.h"
#include "renderer/job/worker_requirements.h"

namespace farm {

// SUCCEEDED, FAILED or CANCELLED: the job will not change again.
bool is_final(v1::JobState state);
std::string to_string(v1::JobState state);  // "queued", "running", ...
// "tile 7" or "tiles 7-9", for messages about a batch.
std::string describe_units(std::uint32_t first, std::uint32_t count);
// The workers a job may run on, as its Job message carries them.
WorkerRequirements requirements_of(const v1::Job& job);
// Wall-clock time as the store and the proto keep it.
std::int64_t unix_ms_now();

}  // namespace farm
