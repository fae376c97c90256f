#pragma once
// The two conditions that hold the scheduler's work up without being anybody's fault
// (docs/architecture.md, "The end of the job, and the failure paths"): a full disk (DiskFull,
// watched by DiskFullPause) and a store whose server is away (StoreUnavailable, watched by
// StoreOutage). Neither fails a job nor charges a worker: the work waits, and is done again once
// the condition clears. This is the one place that tells them from every other exception.
#include "server/scheduler/jobs/disk_full_pause.h"
#include "server/scheduler/store/store_outage.h"

namespace farm {

// Inside a catch block: rethrows the exception being handled when it is a setback, so that a step
// which fails its job for anything else lets a setback through to the caller that retries it.
void rethrow_if_setback();

enum class Setback { none, disk_full, store_away };

class Setbacks {
 public:
  Setbacks(DiskFullPause& pause, StoreOutage& outage) : pause_(pause), outage_(outage) {}

  // Inside a catch block: which setback the exception being handled is, reported to its watcher
  // (the pause, or the outage); Setback::none for any other exception.
  Setback report_current();
  // A store call answered: ends an outage, if there was one.
  void store_answered() { outage_.answered(); }

 private:
  DiskFullPause& pause_;
  StoreOutage& outage_;
};

}  // namespace farm
