#pragma once
// Where a frame's units lie (docs/architecture.md 7.2: unit, tile). A unit is one tile of the
// job's grid (render.tile_size, split_into_tiles), unless the scheduler asks for units of at least
// `min_unit_edge` pixels a side (SchedulerOptions::min_unit_edge): then k x k tiles make one unit,
// k the fewest that reach it. The embedded farm of `farm render` asks for that: it has no other
// worker to balance against, and every unit costs it a row of bookkeeping (claimed, done) that a
// raster frame of a few milliseconds would otherwise spend more time on than on its pixels. The
// pixels do not change (a pixel never depends on how the frame was cut), and the worker still
// renders a unit's rectangle in sub-tiles of the job's tiles.
#include <cstdint>
#include <vector>

#include "renderer/image/tile_buffer.h"
#include "renderer/job/render_settings.h"

namespace farm {

class UnitGrid {
 public:
  UnitGrid(const RenderSettings& settings, int min_unit_edge);

  int edge() const { return edge_; }
  // Units per frame (per pass).
  std::uint32_t count() const { return columns_ * rows_; }
  // Every unit of one frame, row by row: split_into_tiles at the unit's edge.
  std::vector<Rect> rects() const;
  // Unit `index` of a job, whose units are numbered on frame after frame (and pass after pass).
  Rect rect_of(std::uint32_t index) const;
  // Its column in its row, and the units a row holds.
  std::uint32_t column_of(std::uint32_t index) const { return index % count() % columns_; }
  std::uint32_t columns() const { return columns_; }

 private:
  int width_, height_, edge_;
  std::uint32_t columns_, rows_;
};

}  // namespace farm
