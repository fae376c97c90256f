#pragma once
// `farm bench regress`: a regression suite run on the embedded farm (one test at a time, and
// two) and through a scheduler with two workers over loopback, taking turns; wall time per run
// and whether all three gave the same verdicts.
#include <filesystem>

namespace farm {

struct RegressBenchOptions {
  std::filesystem::path suite = "jobs/regress/engines.json";
  int repeats = 3;
  int worker_threads = 1;  // --threads of each of the two workers (1 each fills a 2-core machine)
};

void run_regress_bench(const RegressBenchOptions& options);

}  // namespace farm
