#include "server/common/scene_hash.h"

#include <fmt/format.h>

#include <algorithm>
#include <vector>

#include "server/common/sha256.h"

namespace farm {

std::string scene_hash(const v1::JobSpec& spec) {
  // Every variable-length field is preceded by its length, so no two different specs feed the
  // hash the same bytes.
  Sha256 h;
  h.update("farm.v1.scene\n");
  h.update(fmt::format("{}\n", spec.job_json().size()));
  h.update(spec.job_json());
  h.update("\n");
  std::vector<const v1::AssetRef*> assets;
  for (const v1::AssetRef& a : spec.assets()) assets.push_back(&a);
  std::sort(assets.begin(), assets.end(),
            [](const v1::AssetRef* a, const v1::AssetRef* b) { return a->path() < b->path(); });
  for (const v1::AssetRef* a : assets) {
    h.update(fmt::format("{}\n", a->path().size()));
    h.update(a->path());
    h.update(fmt::format("\n{}\n{}\n", a->sha256(), a->size()));
  }
  return h.finish_hex();
}

}  // namespace farm
