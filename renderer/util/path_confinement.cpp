#include "renderer/util/path_confinement.h"

namespace farm {

namespace fs = std::filesystem;

bool lies_within(const fs::path& resolved_root, const fs::path& resolved_path) {
  auto pi = resolved_path.begin();
  for (auto ri = resolved_root.begin(); ri != resolved_root.end(); ++ri, ++pi) {
    if (ri->empty()) continue;  // a trailing separator
    if (pi == resolved_path.end() || *ri != *pi) return false;
  }
  return true;
}

std::optional<fs::path> resolve_within(const fs::path& resolved_root, const fs::path& path) {
  std::error_code ec;
  fs::path resolved = fs::weakly_canonical(path, ec);
  if (ec || !lies_within(resolved_root, resolved)) return std::nullopt;
  return resolved;
}

}  // namespace farm
