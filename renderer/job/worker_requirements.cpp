#include "renderer/job/worker_requirements.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>

namespace farm {

std::optional<std::string> worker_tag_problem(std::string_view tag) {
  if (tag.empty()) return "an empty tag";
  if (tag.size() > kMaxWorkerTagBytes) {
    return fmt::format("a tag of {} bytes; at most {}", tag.size(), kMaxWorkerTagBytes);
  }
  for (char c : tag) {
    const bool allowed = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                         c == '_' || c == '-';
    if (!allowed) return fmt::format("'{}': a tag is letters, digits, '.', '_' and '-'", std::string(tag.substr(0, 64)));
  }
  return std::nullopt;
}

void sort_worker_tags(std::vector<std::string>& tags) {
  std::sort(tags.begin(), tags.end());
  tags.erase(std::unique(tags.begin(), tags.end()), tags.end());
}

namespace {

// "the tag a" or "the tags a, b".
std::string tags_in_words(const std::vector<std::string>& tags) {
  return fmt::format("the tag{} {}", tags.size() == 1 ? "" : "s", fmt::join(tags, ", "));
}

}  // namespace

bool WorkerRequirements::met_by(const std::vector<std::string>& worker_tags, int threads) const {
  if (min_threads > 0 && threads < min_threads) return false;
  return std::all_of(tags.begin(), tags.end(), [&](const std::string& tag) {
    return std::find(worker_tags.begin(), worker_tags.end(), tag) != worker_tags.end();
  });
}

std::string WorkerRequirements::lacking(const std::vector<std::string>& worker_tags, int threads) const {
  std::vector<std::string> missing;
  for (const std::string& tag : tags) {
    if (std::find(worker_tags.begin(), worker_tags.end(), tag) == worker_tags.end()) missing.push_back(tag);
  }
  std::string out;
  if (!missing.empty()) out = tags_in_words(missing);
  if (min_threads > 0 && threads < min_threads) {
    if (!out.empty()) out += " and ";
    out += threads > 0 ? fmt::format("{} threads (it has {})", min_threads, threads)
                       : fmt::format("{} threads (it did not say how many it has)", min_threads);
  }
  return out;
}

std::string WorkerRequirements::describe() const {
  std::string out;
  if (!tags.empty()) out = tags_in_words(tags);
  if (min_threads > 0) out += fmt::format("{}{} threads", out.empty() ? "" : " and ", min_threads);
  return out.empty() ? "nothing" : out;
}

std::string join_worker_tags(const std::vector<std::string>& tags) { return fmt::format("{}", fmt::join(tags, ",")); }

std::vector<std::string> split_worker_tags(std::string_view joined) {
  std::vector<std::string> tags;
  while (!joined.empty()) {
    const std::size_t comma = joined.find(',');
    tags.emplace_back(joined.substr(0, comma));
    if (comma == std::string_view::npos) break;
    joined.remove_prefix(comma + 1);
  }
  return tags;
}

}  // namespace farm
