#include "server/bench/regress_bench.h"

#include <fmt/format.h>

#include <chrono>
#include <stdexcept>
#include <vector>

#include "server/bench/bench_support.h"
#include "server/bench/loopback_farm.h"
#include "server/regress/regress_runner.h"

namespace farm {
namespace {

using Clock = std::chrono::steady_clock;

struct Setup {
  const char* label;
  RegressOptions options;
  std::vector<double> seconds;
  std::vector<TestStatus> verdicts;
};

}  // namespace

void run_regress_bench(const RegressBenchOptions& o) {
  const RegressSuite suite = load_regress_suite(o.suite);
  const bench::ScratchDir scratch("bench-regress");
  bench::LoopbackFarm loopback(scratch.path() / "loopback", 2, 2, 200, o.worker_threads);
  std::vector<Setup> setups(3);
  setups[0].label = "(a) embedded farm, --jobs 1";
  setups[1].label = "(b) embedded farm, --jobs 2";
  setups[1].options.jobs = 2;
  setups[2].label = "(c) scheduler + 2 workers over loopback";
  setups[2].options.scheduler = SchedulerConnection{loopback.address(), {}};
  fmt::print("farm bench regress ({}): {} ({} tests), {} workers of {} thread(s) in (c), "
             "median of {}\n",
             bench::machine_summary(), o.suite.string(), suite.tests.size(), 2,
             o.worker_threads, o.repeats);
  // Taking turns, so that a change in the shared machine's load falls on all three alike.
  for (int round = 0; round < o.repeats; ++round) {
    for (std::size_t i = 0; i < setups.size(); ++i) {
      Setup& s = setups[i];
      s.options.output_dir = scratch.path() / fmt::format("out{}", i);
      const Clock::time_point start = Clock::now();
      const std::vector<TestOutcome> outcomes = run_regress_suite(suite, s.options);
      s.seconds.push_back(std::chrono::duration<double>(Clock::now() - start).count());
      s.verdicts.clear();
      for (const TestOutcome& outcome : outcomes) s.verdicts.push_back(outcome.status);
    }
  }
  const double a = bench::median(setups[0].seconds);
  for (const Setup& s : setups) {
    const double m = bench::median(s.seconds);
    fmt::print("{:<42} {:>8.3f} s   {:.2f}x the speed of (a)\n", s.label, m, a / m);
  }
  const bool same = setups[0].verdicts == setups[1].verdicts && setups[0].verdicts == setups[2].verdicts;
  fmt::print("verdicts: {}\n", same ? "the same in all three" : "DIFFER between set-ups");
  if (!same) throw std::runtime_error("the set-ups gave different verdicts");
}

}  // namespace farm
