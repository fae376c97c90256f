#pragma once
// The store's schema taken back to an older version, for the upgrade tests: the statements that
// undo every version above `version` (newest first), then record it. Written once here, so that a
// new version adds its undoing in one place (store_schema.cpp makes and upgrades the schema).
#include <string>
#include <vector>

namespace farm::test {

std::vector<std::string> back_to_version(int version);

}  // namespace farm::test
