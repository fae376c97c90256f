#include "server/scheduler/workers/placement.h"

#include <fmt/format.h>

namespace farm {

std::string unplaceable_reason(const WorkerRequirements& requirements, const std::vector<WorkerStatus>& workers) {
  if (requirements.empty()) return {};
  constexpr std::size_t kNamed = 4;
  std::vector<std::string> lacks;
  std::size_t considered = 0;
  for (const WorkerStatus& w : workers) {
    if (w.quarantined) continue;
    if (requirements.met_by(w.facts.tags, w.facts.threads)) return {};
    if (lacks.size() < kNamed) lacks.push_back(fmt::format("{} lacks {}", w.id, requirements.lacking(w.facts.tags, w.facts.threads)));
    ++considered;
  }
  std::string reason = fmt::format("no worker may take it: it needs {}", requirements.describe());
  if (considered == 0) return reason + ", and no worker is registered";
  for (const std::string& l : lacks) reason += "; " + l;
  if (considered > lacks.size()) reason += fmt::format("; and {} more", considered - lacks.size());
  return reason;
}

}  // namespace farm
