#pragma once
// What became of one test of a regression suite: its verdict and figures, the files behind it,
// and whether its reference was written.
#include <filesystem>
#include <string>

#include "renderer/compare/compare.h"

namespace farm {

enum class TestStatus { passed, warned, failed, error, skipped };
std::string_view to_string(TestStatus status);  // PASS WARN FAIL ERROR SKIP

struct TestOutcome {
  std::string name;
  TestStatus status = TestStatus::error;
  CompareSettings settings;       // the comparison it was held to
  CompareResult result;           // figures (empty when it could not be compared)
  std::string message;            // the one-line reason: the metric's summary, or what went wrong
  bool reference_missing = false;
  bool reference_updated = false; // --update wrote the new image over (or as) the reference
  double seconds = 0.0;           // render and compare
  std::filesystem::path reference, new_image;                // the compared files
  std::filesystem::path reference_png, new_png, difference_png;  // for the report (may be empty)
};

}  // namespace farm
