#pragma once
// Why the scheduler cancelled a call in flight: it decides what becomes of the call's units
// (dispatcher.h) or of the spot check the call rendered (spot_check_rounds.h).

namespace farm {

enum class CancelReason { None, JobCancelled, WorkerLeft, Quarantined, Stopping };

}  // namespace farm
