#pragma once
// Durations on the command line as people write them: "7d", "12h", "30m", "90s", "1.5h".
#include <chrono>
#include <string>

namespace farm {

// A number followed by one unit, s, m, h, d or w (no unit: seconds). InputError naming `flag`
// and the text for anything else, or for a value below zero or above ten years.
std::chrono::milliseconds parse_duration(const std::string& text, const std::string& flag);

}  // namespace farm
