#pragma once
// A "compare" object of a regression suite (or of one of its tests): the metric and its
// thresholds, keys as renderer/compare/compare_settings.h names them, each replacing the value it
// is laid over one by one, so a test can tighten one threshold of the suite's defaults.
#include <string_view>
#include <vector>

#include "renderer/compare/compare_settings.h"
#include "renderer/util/json_reader.h"

namespace farm {

// `base` with the keys of `object` applied; unknown keys, wrong types and out-of-range values
// are InputErrors naming the JSON path.
CompareSettings read_compare_settings(const JsonValue& object, CompareSettings base);

// The keys a compare object may hold (metric, ssim_channels and every threshold), for a caller
// whose object holds more (a rubric's "score" adds full and zero) ...
std::vector<std::string_view> compare_keys();
// ... and the same reading from an object it made with those keys among its own.
CompareSettings read_compare_settings(const JsonObject& object, CompareSettings base);

}  // namespace farm
