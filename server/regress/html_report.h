#pragma once
// A suite run as a self-contained HTML page that opens from disk (no scripts, no network): the
// tests that failed first, each with its status, metric figures, thresholds and the threshold
// that would have passed, and its reference, new and difference images side by side (hovering
// over the new image shows the reference in its place). summary.json beside it holds the same.
#include <filesystem>
#include <vector>

#include "server/regress/regress_suite.h"
#include "server/regress/test_outcome.h"

namespace farm {

// Writes <dir>/index.html and <dir>/summary.json; the images are under <dir>/images already.
void write_html_report(const RegressSuite& suite, const std::vector<TestOutcome>& outcomes,
                       const std::filesystem::path& dir);

}  // namespace farm
