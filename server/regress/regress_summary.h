#pragma once
// The counts a suite run ends with, and each outcome as JSON: what the console's closing line,
// the JUnit file and the HTML report's summary.json all say.
#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/regress/regress_suite.h"
#include "server/regress/test_outcome.h"

namespace farm {

struct RegressCounts {
  std::size_t passed = 0, warned = 0, failed = 0, errors = 0, skipped = 0, updated = 0;
  std::size_t created = 0;  // of `updated`: references that did not exist before
  double seconds = 0.0;
  // "3 passed, 1 failed" (+ ", 1 warned", ", 1 error", ", 2 skipped", ", 3 references written (2
  // new)"); a failure whose reference was just written counts as written, not failed.
  std::string line() const;
  // 0 when nothing failed or errored (warnings pass), or when every failure's reference was
  // just written by --update; else 1.
  int exit_code() const;
  std::size_t failed_not_updated = 0;
};

RegressCounts count_outcomes(const std::vector<TestOutcome>& outcomes);

// The figures, the thresholds of the test's metric and the threshold that would have passed.
nlohmann::ordered_json outcome_json(const TestOutcome& outcome);
nlohmann::ordered_json summary_json(const RegressSuite& suite, const std::vector<TestOutcome>& outcomes);

}  // namespace farm
