#pragma once
// `farm bench dispatch`: what choosing the next batch costs the scheduler as its queue grows. A
// store in a scratch folder (SQLite, as a scheduler keeps by default) is filled with queued jobs of
// one unit each, from several owners; then the claim (UnitQueue::claim_next_batch, the query
// every dispatch makes) is timed alone, each claimed unit then marked done and its job ended
// untimed, as the farm does, so that the queue shortens by a job a claim. Reported per queue
// length: the median, 99th percentile and mean claim time, and claims a second, for plain jobs and
// again with issue #36's scheduling in play (tags, dependencies, frame-by-frame, caps and weighted
// fair share among the jobs: dispatch_bench.cpp says the mix), which #36 holds within 2x of plain.
#include <string>
#include <vector>

namespace farm {

struct DispatchBenchOptions {
  std::vector<int> queued = {100, 10000};  // queue lengths, one run each
  int claims = 2000;                        // timed claims a run (at most the queue's length)
  int owners = 50;                          // the jobs' owners, round robin
};

void run_dispatch_bench(const DispatchBenchOptions& options);

}  // namespace farm
