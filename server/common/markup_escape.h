#pragma once
// Text for XML and HTML reports: the five special characters escaped, and control characters
// (which XML 1.0 cannot hold at all) from a message replaced; and figures as reports print them.
#include <string>
#include <string_view>

namespace farm {

std::string markup_escape(std::string_view text);
std::string format_figure(double value);  // 6 significant digits; inf, -inf, nan spelled out

}  // namespace farm
