#pragma once
// A suite run as JUnit XML, the format CI systems (Jenkins, GitLab, GitHub's test reporters)
// read: one testsuite of testcases; a failed comparison is a <failure> with its summary and
// figures, a render that did not finish an <error>, a filtered-out test <skipped/>. Each
// testcase carries its figures and thresholds as properties, and [[ATTACHMENT|path]] lines
// (Jenkins' attachments plugin) for its images.
#include <filesystem>
#include <vector>

#include "server/regress/regress_suite.h"
#include "server/regress/test_outcome.h"

namespace farm {

void write_junit_report(const RegressSuite& suite, const std::vector<TestOutcome>& outcomes,
                        const std::filesystem::path& file);

}  // namespace farm
