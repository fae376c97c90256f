#include "renderer/image/tile_buffer.h"

#include <algorithm>

namespace farm {

Rect Rect::intersect(const Rect& o) const {
  Rect r{std::max(x0, o.x0), std::max(y0, o.y0), std::min(x1, o.x1), std::min(y1, o.y1)};
  if (r.empty()) return Rect{};
  return r;
}

void TileBuffer::reset(const Rect& rect, const AovSet& aovs) {
  rect_ = rect.empty() ? Rect{} : rect;
  aovs_ = aovs;
  stats_ = RenderStats{};
  const std::size_t n = static_cast<std::size_t>(rect_.width()) * static_cast<std::size_t>(rect_.height());
  rgba_.assign(n, glm::vec4(0.0f));
  depth_.assign(aovs.depth ? n : 0, kNoDepth);
  normal_.assign(aovs.normal ? n : 0, glm::vec3(0.0f));
  albedo_.assign(aovs.albedo ? n : 0, glm::vec3(0.0f));
  bvh_cost_.assign(aovs.bvh_cost ? n : 0, 0.0f);
}

void TileBuffer::paste(const TileBuffer& tile) {
  stats_ += tile.stats();
  const Rect overlap = rect_.intersect(tile.rect());
  for (int y = overlap.y0; y < overlap.y1; ++y) {
    for (int x = overlap.x0; x < overlap.x1; ++x) {
      rgba(x, y) = tile.rgba(x, y);
      if (aovs_.depth && tile.aovs().depth) depth(x, y) = tile.depth(x, y);
      if (aovs_.normal && tile.aovs().normal) normal(x, y) = tile.normal(x, y);
      if (aovs_.albedo && tile.aovs().albedo) albedo(x, y) = tile.albedo(x, y);
      if (aovs_.bvh_cost && tile.aovs().bvh_cost) bvh_cost(x, y) = tile.bvh_cost(x, y);
    }
  }
}

}  // namespace farm
