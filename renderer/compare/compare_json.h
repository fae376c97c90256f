#pragma once
// A comparison's outcome as JSON, the one shape `farm compare --json` prints and a regression
// report's summary holds: {"metric", "verdict", "summary", "figures": {name: value},
// "would_pass": {"key", "value"}}. Infinite figures are written as the strings "inf"/"-inf"
// and NaN as null, since JSON has no such numbers.
#include <nlohmann/json.hpp>

#include "renderer/compare/compare.h"

namespace farm {

nlohmann::ordered_json to_json(const CompareResult& result);
nlohmann::ordered_json json_number(double value);

}  // namespace farm
