#pragma once
// Shared set-up for tests that drive the real `farm` binary: a private temp folder, the source
// tree's location, and the command-line helpers.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "tests/support/run_command.h"
#include "tests/support/temp_dir.h"

namespace farm::test {

inline const std::filesystem::path kSource = FARM_SOURCE_DIR;

class FarmCliFixture : public ::testing::Test {
 protected:
  static std::string farm(const std::string& args) { return farm_command(args); }
  TempDir dir_;
};

}  // namespace farm::test
