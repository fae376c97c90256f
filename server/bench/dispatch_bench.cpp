#include "server/bench/dispatch_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "server/bench/bench_support.h"
#include "server/scheduler/store/job_store.h"

namespace farm {
namespace {

using Clock = std::chrono::steady_clock;

// A queued job of one 16x16 unit, as a submission would store it (the scheduler reads nothing
// else of a job to choose among them).
NewJob queued_job(int index, int owners) {
  NewJob job;
  job.id = fmt::format("bench-{:06d}", index);
  job.name = job.id;
  job.spec.set_job_json("{}");
  job.scene_hash = std::string(64, 'a');
  job.engine = "raster";
  job.width = job.height = 16;
  job.owner = fmt::format("owner-{:02d}", index % std::max(1, owners));
  job.tiles = {{0, 0, 16, 16}};
  return job;
}

struct ClaimTimes {
  double fill_seconds = 0.0;
  std::vector<double> claim_ms;
};

ClaimTimes time_claims(int queued, int claims, int owners) {
  bench::ScratchDir dir("dispatch-bench");
  JobStore store(dir.path() / "jobs.db");
  ClaimTimes times;
  const Clock::time_point fill = Clock::now();
  for (int i = 0; i < queued; ++i) store.jobs().add_job(queued_job(i, owners), 1000 + i);
  times.fill_seconds = bench::seconds_since(fill);
  const std::int64_t now_ms = 1000 + queued;
  for (int i = 0; i < std::min(claims, queued); ++i) {
    const Clock::time_point start = Clock::now();
    const std::optional<UnitBatch> batch = store.units().claim_next_batch("bench-worker", now_ms);
    times.claim_ms.push_back(bench::ms_since(start));
    // Equal priorities: the queue hands jobs out in submission order, each once.
    const std::string expected = queued_job(i, owners).id;
    if (!batch || batch->job_id != expected) {
      throw std::runtime_error(fmt::format("claim {} of a queue of {} gave {}, not {}", i + 1, queued,
                                           batch ? batch->job_id : "nothing", expected));
    }
    // What the farm does next, untimed: the unit's result is in, the job ends.
    if (!store.units().batch_done(batch->job_id, batch->first, batch->count, v1::TileStats{}, "bench-worker")) {
      throw std::runtime_error("a claimed unit could not be marked done");
    }
    store.jobs().finish_job(batch->job_id, v1::JOB_STATE_SUCCEEDED, "", "", now_ms);
  }
  return times;
}

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double rank = std::ceil(p * static_cast<double>(values.size()));
  const std::size_t k = std::min(values.size() - 1, static_cast<std::size_t>(std::max(1.0, rank)) - 1);
  return values[k];
}

}  // namespace

void run_dispatch_bench(const DispatchBenchOptions& o) {
  fmt::print("claims of the next batch from a SQLite store of queued one-unit jobs of {} owners, {} timed claims a "
             "queue (each unit then done and its job ended, untimed)\n",
             o.owners, o.claims);
  fmt::print("{:>8} {:>8} {:>10} {:>12} {:>12} {:>12} {:>10}\n", "queued", "claims", "fill s", "median ms", "p99 ms",
             "mean ms", "claims/s");
  for (int queued : o.queued) {
    const ClaimTimes t = time_claims(queued, o.claims, o.owners);
    double total = 0.0;
    for (double ms : t.claim_ms) total += ms;
    const double mean = t.claim_ms.empty() ? 0.0 : total / static_cast<double>(t.claim_ms.size());
    fmt::print("{:>8} {:>8} {:>10.2f} {:>12.3f} {:>12.3f} {:>12.3f} {:>10.0f}\n", queued, t.claim_ms.size(), t.fill_seconds,
               bench::median(t.claim_ms), percentile(t.claim_ms, 0.99), mean, mean > 0.0 ? 1000.0 / mean : 0.0);
  }
}

}  // namespace farm
