#pragma once
// The project's version: CMakeLists.txt's project(VERSION), passed in as FARM_VERSION
// (server/CMakeLists.txt, on farm_common), so that `farm --version` and the version a worker registers with
// cannot drift from it.
#include <string_view>

namespace farm {

inline constexpr std::string_view kFarmVersion = FARM_VERSION;

}  // namespace farm
