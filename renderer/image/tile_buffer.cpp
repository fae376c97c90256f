#include "renderer/image/tile_buffer.h"

#include <algorithm>

namespace farm {

Rect Rect::intersect(const Rect& o) const {
  Rect r{std::max(x0, o.x0), std::max(y0, o.y0), std::min(x1, o.x1), std::min(y1, o.y1)};
  if (r.empty()) return Rect{};
  return r;
}

void TileBuffer::reset_for_overwrite(const Rect& rect, const AovSet& aovs) {
  rect_ = rect.empty() ? Rect{} : rect;
  aovs_ = aovs;
  stats_ = RenderStats{};
  const std::size_t n = static_cast<std::size_t>(rect_.width()) * static_cast<std::size_t>(rect_.height());
  rgba_.allocate(n);
  depth_.allocate(aovs.depth ? n : 0);
  normal_.allocate(aovs.normal ? n : 0);
  albedo_.allocate(aovs.albedo ? n : 0);
  bvh_cost_.allocate(aovs.bvh_cost ? n : 0);
  variance_.allocate(aovs.variance ? n : 0);
}

void TileBuffer::reset(const Rect& rect, const AovSet& aovs) {
  reset_for_overwrite(rect, aovs);
  std::fill(rgba_.begin(), rgba_.end(), glm::vec4(0.0f));
  std::fill(depth_.begin(), depth_.end(), kNoDepth);
  std::fill(normal_.begin(), normal_.end(), glm::vec3(0.0f));
  std::fill(albedo_.begin(), albedo_.end(), glm::vec3(0.0f));
  std::fill(bvh_cost_.begin(), bvh_cost_.end(), 0.0f);
  std::fill(variance_.begin(), variance_.end(), glm::vec3(0.0f));
}

void TileBuffer::discard_pixels() {
  const RenderStats done = stats_;
  reset_for_overwrite(Rect{}, aovs_);
  stats_ = done;
}

void TileBuffer::paste(const TileBuffer& tile) {
  const Rect overlap = rect_.intersect(tile.rect());
  if (overlap.empty()) return;
  const bool depth = aovs_.depth && tile.aovs().depth, normal = aovs_.normal && tile.aovs().normal,
             albedo = aovs_.albedo && tile.aovs().albedo,
             bvh_cost = aovs_.bvh_cost && tile.aovs().bvh_cost,
             variance = aovs_.variance && tile.aovs().variance;
  const auto width = static_cast<std::ptrdiff_t>(overlap.width());
  // Row by row: each row of the overlap is contiguous in both buffers.
  for (int y = overlap.y0; y < overlap.y1; ++y) {
    const auto from = static_cast<std::ptrdiff_t>(tile.index(overlap.x0, y));
    const auto to = static_cast<std::ptrdiff_t>(index(overlap.x0, y));
    const auto copy_row = [&](const auto& src, auto& dst) {
      std::copy_n(src.begin() + from, width, dst.begin() + to);
    };
    copy_row(tile.rgba_, rgba_);
    if (depth) copy_row(tile.depth_, depth_);
    if (normal) copy_row(tile.normal_, normal_);
    if (albedo) copy_row(tile.albedo_, albedo_);
    if (bvh_cost) copy_row(tile.bvh_cost_, bvh_cost_);
    if (variance) copy_row(tile.variance_, variance_);
  }
}

}  // namespace farm
