#include "server/cli/duration_option.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>

#include "renderer/util/input_error.h"

namespace farm {

std::chrono::milliseconds parse_duration(const std::string& text, const std::string& flag) {
  const auto refuse = [&] {
    return InputError(fmt::format("{} '{}': give a duration such as 90s, 30m, 12h, 7d or 2w", flag, text.substr(0, 40)));
  };
  if (text.empty() || text.size() > 32) throw refuse();
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || !std::isfinite(value) || value < 0) throw refuse();
  const std::string unit(end);
  double seconds = 0;
  if (unit.empty() || unit == "s") {
    seconds = value;
  } else if (unit == "m") {
    seconds = value * 60;
  } else if (unit == "h") {
    seconds = value * 3600;
  } else if (unit == "d") {
    seconds = value * 86400;
  } else if (unit == "w") {
    seconds = value * 7 * 86400;
  } else {
    throw refuse();
  }
  if (seconds > 10.0 * 366 * 86400) throw refuse();
  return std::chrono::milliseconds(static_cast<std::int64_t>(std::llround(seconds * 1000.0)));
}

}  // namespace farm
