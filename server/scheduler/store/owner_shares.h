#pragma once
// Fair share between owners (docs/architecture.md, "Scheduling"): among active jobs of equal
// priority, units go to the owner who has had the least of them, weighted by the owner's share
// (the tokens file's weight). Each owner has a pass (the owners table): the units claimed for them
// so far, each counted as 1000000 / weight_milli, so that an owner of weight 2 advances half as
// fast. The claim orders jobs by priority, then their owner's pass, then submission
// (UnitQueue::claim_next_batch). An owner whose jobs enter the queue (submitted, or released by
// their dependencies) starts level with the least-served owner already there, never below: an
// idle owner banks no credit, and a busy one keeps no debt once everyone else has caught up.
// These run inside the caller's transaction, on the store's connection, under its mutex.
#include <cstdint>
#include <optional>
#include <string>

#include "server/scheduler/store/sql_connection.h"

namespace farm {

// One unit at weight 1 (1000 thousandths) advances a pass by this much.
inline constexpr std::int64_t kPassPerUnit = 1000;

// The owner's row made, or its weight replaced (when given) and its pass raised to the least pass
// of the owners with active jobs.
void enter_owner(SqlConnection& db, const std::string& owner, std::optional<std::int64_t> weight_milli);
// `units` just claimed for the owner's job.
void charge_owner(SqlConnection& db, const std::string& owner, std::int64_t units);

}  // namespace farm
