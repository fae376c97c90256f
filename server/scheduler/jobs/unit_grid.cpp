#include "server/scheduler/jobs/unit_grid.h"

#include <algorithm>

#include "renderer/render_frame.h"

namespace farm {

UnitGrid::UnitGrid(const RenderSettings& settings, int min_unit_edge)
    : width_(settings.width), height_(settings.height) {
  const int tile = std::max(1, settings.tile_size);
  // Whole tiles a side, and never past the image: a unit larger than the frame is the frame.
  const int tiles_a_side = std::max(1, (std::max(min_unit_edge, 1) + tile - 1) / tile);
  edge_ = static_cast<int>(std::min<std::int64_t>(std::int64_t{tile} * tiles_a_side,
                                                  std::max({tile, width_, height_})));
  columns_ = static_cast<std::uint32_t>((width_ + edge_ - 1) / edge_);
  rows_ = static_cast<std::uint32_t>((height_ + edge_ - 1) / edge_);
}

std::vector<Rect> UnitGrid::rects() const { return split_into_tiles(width_, height_, edge_); }

Rect UnitGrid::rect_of(std::uint32_t index) const {
  index %= std::max<std::uint32_t>(1, count());
  const int x = static_cast<int>(index % columns_) * edge_, y = static_cast<int>(index / columns_) * edge_;
  return Rect{x, y, std::min(x + edge_, width_), std::min(y + edge_, height_)};
}

}  // namespace farm
