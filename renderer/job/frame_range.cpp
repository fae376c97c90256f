#include "renderer/job/frame_range.h"

#include <fmt/format.h>

#include <charconv>

namespace farm {

std::vector<int> FrameRange::frames() const {
  std::vector<int> out;
  const int first = only ? only->first : start;
  const int last = only ? only->second : end;
  // In 64 bits: start + k * step must not wrap near the top of the range.
  for (std::int64_t f = start; f <= end; f += step) {
    if (f >= first && f <= last) out.push_back(static_cast<int>(f));
  }
  return out;
}

bool FrameRange::contains(int frame) const {
  const int first = only ? only->first : start;
  const int last = only ? only->second : end;
  return frame >= start && frame <= end && frame >= first && frame <= last && (frame - start) % step == 0;
}

namespace {

std::optional<int> frame_number(std::string_view s) {
  int v = 0;
  if (s.empty()) return std::nullopt;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size() || v < 0 || v > kMaxFrameNumber) return std::nullopt;
  return v;
}

}  // namespace

std::optional<std::pair<int, int>> parse_frame_pick(std::string_view text) {
  const std::size_t dash = text.find('-');
  if (dash == std::string_view::npos) {
    const auto f = frame_number(text);
    if (!f) return std::nullopt;
    return std::pair{*f, *f};
  }
  const auto first = frame_number(text.substr(0, dash));
  const auto last = frame_number(text.substr(dash + 1));
  if (!first || !last || *last < *first) return std::nullopt;
  return std::pair{*first, *last};
}

bool has_frame_pattern(std::string_view file_name) { return file_name.find('#') != std::string_view::npos; }

std::string frame_file_name(std::string_view pattern, int frame) {
  const std::size_t last = pattern.rfind('#');
  if (last == std::string_view::npos) return std::string(pattern);
  std::size_t first = last;
  while (first > 0 && pattern[first - 1] == '#') --first;
  const std::size_t width = last - first + 1;
  return fmt::format("{}{:0{}}{}", pattern.substr(0, first), frame, width, pattern.substr(last + 1));
}

}  // namespace farm
