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
NewJob queued_job(int index, int owners, bool in_play = false) {
  NewJob job;
  job.id = fmt::format("bench-{:06d}", index);
  job.name = job.id;
  job.spec.set_job_json("{}");
  job.scene_hash = std::string(64, 'a');
  job.engine = "raster";
  job.width = job.height = 16;
  job.owner = fmt::format("owner-{:02d}", index % std::max(1, owners));
  job.tiles = {{0, 0, 16, 16}};
  if (!in_play) return job;
  // Issue #36's scheduling in play: of every ten jobs, one needs a tag the worker lacks (passed
  // over at every claim), one waits for the job two before it (released as that one ends), one
  // follows the job three before it frame by frame, one is capped to one worker and one unit out;
  // the owners' fair-share weights are 1, 1.5 and 2.
  job.owner_weight_milli = 1000 + 500 * (index % std::max(1, owners) % 3);
  switch (index % 10) {
    case 1: job.requirements.tags = {"gpu"}; break;
    case 2: job.after = {queued_job(index - 2, owners).id}; break;
    case 3: job.after_frames = queued_job(index - 3, owners).id; break;
    case 4: job.caps = {1, 1}; break;
    default: break;
  }
  return job;
}

// A job the bench worker (tag "cpu") may never take.
bool needs_a_gpu(const std::string& id) { return std::stoi(id.substr(6)) % 10 == 1; }

struct ClaimTimes {
  double fill_seconds = 0.0;
  std::vector<double> claim_ms;
};

ClaimTimes time_claims(int queued, int claims, int owners, bool in_play) {
  bench::ScratchDir dir("dispatch-bench");
  JobStore store(dir.path() / "jobs.db");
  ClaimTimes times;
  const Clock::time_point fill = Clock::now();
  for (int i = 0; i < queued; ++i) store.jobs().add_job(queued_job(i, owners, in_play), 1000 + i);
  times.fill_seconds = bench::seconds_since(fill);
  const std::int64_t now_ms = 1000 + queued;
  // With scheduling in play, the jobs that need a GPU are never claimed.
  int claimable = queued;
  for (int i = 0; in_play && i < queued; ++i) claimable -= needs_a_gpu(queued_job(i, owners).id) ? 1 : 0;
  for (int i = 0; i < std::min(claims, claimable); ++i) {
    const Clock::time_point start = Clock::now();
    const std::optional<UnitBatch> batch =
        store.units().claim_next_batch("bench-worker", now_ms, {}, 1024, {}, WorkerOffer{{"cpu"}, 4});
    times.claim_ms.push_back(bench::ms_since(start));
    // Equal priorities and the owners round robin: the queue hands jobs out in submission order,
    // each once (with scheduling in play, none the worker may not take).
    const std::string expected = queued_job(i, owners).id;
    if (in_play ? !batch || needs_a_gpu(batch->job_id) : !batch || batch->job_id != expected) {
      throw std::runtime_error(fmt::format("claim {} of a queue of {} gave {}, not {}", i + 1, queued,
                                           batch ? batch->job_id : "nothing", expected));
    }
    // What the farm does next, untimed: the unit's result is in, the job ends.
    if (!store.units().batch_done(batch->job_id, batch->first, batch->count, v1::TileStats{}, "bench-worker")) {
      throw std::runtime_error("a claimed unit could not be marked done");
    }
    if (!store.frames().frame_merged(batch->job_id, 0)) throw std::runtime_error("a done frame could not be merged");
    store.jobs().finish_job(batch->job_id, v1::JOB_STATE_SUCCEEDED, "", "", now_ms);
    if (in_play) store.dependencies().release_waiting(now_ms);
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
  fmt::print("plain: every job any worker may take; in play: of every ten, one needs a tag the worker lacks, one waits "
             "for another job, one follows another frame by frame, one is capped (fair-share weights 1, 1.5, 2)\n");
  fmt::print("{:>8} {:>8} {:>8} {:>10} {:>12} {:>12} {:>12} {:>10}\n", "queued", "jobs", "claims", "fill s", "median ms",
             "p99 ms", "mean ms", "claims/s");
  for (int queued : o.queued) {
    double plain_median = 0.0;
    for (const bool in_play : {false, true}) {
      const ClaimTimes t = time_claims(queued, o.claims, o.owners, in_play);
      double total = 0.0;
      for (double ms : t.claim_ms) total += ms;
      const double mean = t.claim_ms.empty() ? 0.0 : total / static_cast<double>(t.claim_ms.size());
      const double median = bench::median(t.claim_ms);
      fmt::print("{:>8} {:>8} {:>8} {:>10.2f} {:>12.3f} {:>12.3f} {:>12.3f} {:>10.0f}{}\n", queued,
                 in_play ? "in play" : "plain", t.claim_ms.size(), t.fill_seconds, median, percentile(t.claim_ms, 0.99),
                 mean, mean > 0.0 ? 1000.0 / mean : 0.0,
                 in_play && plain_median > 0.0 ? fmt::format("   {:.2f}x plain's median", median / plain_median) : "");
      if (!in_play) plain_median = median;
    }
  }
}

}  // namespace farm
