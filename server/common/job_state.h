#pragma once
// Small facts about farm.v1 jobs that the scheduler, its store and the client all use.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "proto/farm.pb.h"
#include "renderer/job/worker_requirements.h"

namespace farm {

// Every state a job can be in, in the order a job's life goes through them.
inline constexpr v1::JobState kJobStates[] = {v1::JOB_STATE_WAITING,   v1::JOB_STATE_QUEUED, v1::JOB_STATE_RUNNING,
                                              v1::JOB_STATE_SUCCEEDED, v1::JOB_STATE_FAILED, v1::JOB_STATE_CANCELLED};

// SUCCEEDED, FAILED or CANCELLED: the job will not change again.
bool is_final(v1::JobState state);
std::string to_string(v1::JobState state);  // "queued", "running", ...
// The state to_string names `name`; nullopt for none.
std::optional<v1::JobState> job_state_named(std::string_view name);
// "waiting, queued, running, succeeded, failed, cancelled": the names, for messages and --help.
inline constexpr const char* kJobStateNames = "waiting, queued, running, succeeded, failed, cancelled";
// "tile 7" or "tiles 7-9", for messages about a batch.
std::string describe_units(std::uint32_t first, std::uint32_t count);
// The workers a job may run on, as its Job message carries them.
WorkerRequirements requirements_of(const v1::Job& job);
// The jobs it waits for, in words: "after 1a2b, 3c4d; after any end of 5e6f; frame by frame after
// 7a8b"; empty without dependencies.
std::string describe_dependencies(const v1::Job& job);
// Wall-clock time as the store and the proto keep it.
std::int64_t unix_ms_now();

}  // namespace farm
