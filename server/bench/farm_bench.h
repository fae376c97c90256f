#pragma once
// `farm bench farm`: what the farm's machinery costs. The Cornell box path traced at 512x512
// through (a) `farm render` (the embedded farm), (b) a `farm scheduler` and one `farm worker`
// over loopback, (c) the scheduler and two workers; then many tiny jobs submitted back to back to
// (b) for jobs/s and submit latency, checking that none is lost: on SQLite, and beside it on the
// PostgreSQL store given (`--store`) with one scheduler and with two.
#include <filesystem>
#include <string>

namespace farm {

struct FarmBenchOptions {
  std::filesystem::path job = "jobs/cornell_path.json";
  int width = 512, height = 512;
  int spp = 16;
  int repeats = 7;       // renders per configuration; the median is reported
  int tiny_jobs = 200;
  int tiles_per_worker = 2;  // the scheduler's --tiles-per-worker
  int batch_ms = 200;        // the scheduler's --batch-ms, for all three set-ups
  int two_worker_threads = 0;  // --threads of each worker in (c); 0 = all cores each
  std::string store;           // a postgresql:// URL: the tiny jobs on it too; empty: SQLite only
};

void run_farm_bench(const FarmBenchOptions& options);

}  // namespace farm
