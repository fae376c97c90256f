#pragma once
// Runs a regression suite: renders every selected test's job on a farm (the embedded one, or a
// scheduler's), compares each new image with its reference as it arrives, writes the images a
// report shows, and with --update writes new references.
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "server/client/scheduler_connection.h"
#include "server/regress/regress_suite.h"
#include "server/regress/test_outcome.h"

namespace farm {

enum class ReferenceUpdate { none, failed, all };  // failed: failed and missing references

struct RegressOptions {
  std::vector<std::string> filters;      // glob patterns on test names; none: every test
  ReferenceUpdate update = ReferenceUpdate::none;
  int jobs = 1;                          // embedded farm: tests rendered at a time
  int threads = 0;                       // embedded farm: render threads (0: all cores)
  std::optional<SchedulerConnection> scheduler;  // render on this scheduler instead (all jobs submitted up front)
  std::filesystem::path output_dir;      // new images, report images: <output>/images
};

struct RegressEvents {
  std::function<void(const TestOutcome&)> finished;            // a test's outcome, as soon as it is known
  std::function<void(std::size_t done, std::size_t total)> progress;
};

// The outcome of every test, in suite order (filtered-out tests as skipped). Events are called
// from one thread at a time.
std::vector<TestOutcome> run_regress_suite(const RegressSuite& suite, const RegressOptions& options,
                                           const RegressEvents& events = {});

// True when `name` matches the shell-style glob `pattern` (* ? and [...]).
bool glob_matches(const std::string& pattern, const std::string& name);

}  // namespace farm
