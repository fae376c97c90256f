#include "server/scheduler/http/prometheus_text.h"

#include <fmt/format.h>

#include <map>

#include "server/common/job_state.h"

namespace farm {

namespace {

void header(std::string& out, const char* name, const char* type, const char* help) {
  out += fmt::format("# HELP {} {}\n# TYPE {} {}\n", name, help, name, type);
}

}  // namespace

std::string prometheus_text(const SchedulerMetrics& metrics) {
  const JobRecords::Counts& counts = metrics.jobs;
  const std::vector<v1::WorkerInfo>& workers = metrics.workers;
  const UnitMetrics::Snapshot& units = metrics.units;
  std::string out;
  header(out, "farm_jobs", "gauge", "Jobs in the store by state.");
  for (v1::JobState s : kJobStates) {
    const auto it = counts.jobs.find(s);
    out += fmt::format("farm_jobs{{state=\"{}\"}} {}\n", to_string(s), it == counts.jobs.end() ? 0 : it->second);
  }
  header(out, "farm_jobs_paused", "gauge", "Queued or running jobs an operator paused.");
  out += fmt::format("farm_jobs_paused {}\n", counts.paused);
  header(out, "farm_queue_depth", "gauge", "Units waiting to be handed out (of jobs not paused).");
  out += fmt::format("farm_queue_depth {}\n", counts.queued_units);

  std::map<std::string, int> by_state{{"up", 0}, {"down", 0}, {"quarantined", 0}};
  for (const v1::WorkerInfo& w : workers) {
    ++by_state[w.state() == v1::WORKER_STATE_UP            ? "up"
               : w.state() == v1::WORKER_STATE_QUARANTINED ? "quarantined"
                                                           : "down"];
  }
  header(out, "farm_workers", "gauge", "Workers by state.");
  for (const auto& [state, n] : by_state) out += fmt::format("farm_workers{{state=\"{}\"}} {}\n", state, n);

  header(out, "farm_units_done_total", "counter", "Units rendered and kept since the scheduler started.");
  out += fmt::format("farm_units_done_total {}\n", units.units_done);
  header(out, "farm_units_failed_total", "counter", "Units whose rendering failed or lost its worker.");
  out += fmt::format("farm_units_failed_total {}\n", units.units_failed);
  header(out, "farm_units_per_second", "gauge", "Units kept a second, over the last minute.");
  out += fmt::format("farm_units_per_second {}\n", units.units_per_second);

  header(out, "farm_unit_latency_seconds", "histogram",
         "Seconds from a batch of units handed out to its result kept, per batch.");
  for (std::size_t b = 0; b < units.latency_buckets.size(); ++b) {
    const std::string le = b < UnitMetrics::kBuckets ? fmt::format("{}", UnitMetrics::kLatencyBounds[b]) : "+Inf";
    out += fmt::format("farm_unit_latency_seconds_bucket{{le=\"{}\"}} {}\n", le, units.latency_buckets[b]);
  }
  out += fmt::format("farm_unit_latency_seconds_sum {}\n", units.latency_sum);
  out += fmt::format("farm_unit_latency_seconds_count {}\n", units.latency_count);
  return out;
}

}  // namespace farm
