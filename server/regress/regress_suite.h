#pragma once
// A regression suite file (JSON, version 1; jobs/regress/README.md): jobs to render, each with
// a reference image and a comparison. Read strictly, like job files: every error names the file
// and the JSON path.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "renderer/compare/compare_settings.h"
#include "server/client/render_overrides.h"

namespace farm {

struct RegressTest {
  std::string name;                 // unique in the suite; [A-Za-z0-9._-], names its files
  std::filesystem::path job;        // absolute
  RenderOverrides render;           // the suite's "render" keys for this test
  CompareSettings compare;          // the suite's defaults with the test's keys laid over
  std::filesystem::path reference;  // absolute; inside the suite's folder
};

struct RegressSuite {
  std::filesystem::path file;        // the suite file, absolute
  std::string name;
  std::filesystem::path folder;      // the suite file's folder (references must lie inside)
  std::filesystem::path asset_root;  // models the jobs read must lie inside
  std::vector<RegressTest> tests;
};

// Reads and validates `file`: unknown keys, wrong types, missing job files, duplicate or unsafe
// test names and references outside the suite's folder are InputErrors.
RegressSuite load_regress_suite(const std::filesystem::path& file);

}  // namespace farm
