#pragma once
// The front half of the sort-middle rasterizer, done once per frame and shared by every tile:
// the vertex stage (all vertices to clip, view and world space), triangle set-up (clipping,
// snapping to the fixed-point grid, orientation) and binning of the set-up triangles to square
// screen bins. A tile then only rasterizes the triangles binned to the bins it overlaps.
//
// Triangles keep their scene order inside every bin, and each pixel sees exactly the triangles
// that can cover it in that order, so depth ties resolve the same way for any tiling.
#include <cstdint>
#include <memory>
#include <vector>

#include "renderer/image/tile_buffer.h"
#include "renderer/prepared_scene.h"
#include "renderer/raster/clip_polygon.h"
#include "renderer/raster/edge_function.h"
#include "renderer/render_settings.h"
#include "renderer/thread_pool.h"

namespace farm::raster {

// Edge of a square screen bin in pixels. Small enough that a tile's bins carry few triangles
// that miss it, large enough that a typical triangle lands in one bin.
inline constexpr int kBinSize = 32;

// A vertex after the vertex stage, with its screen position when it lies in front of the camera.
struct ScreenVertex {
  ClipVertex attributes;
  FixedPoint position;
  float ndc_depth = 0.0f;
  float inv_w = 0.0f;
};

// A triangle ready to rasterize: positively oriented on the sample grid, non-degenerate.
struct ScreenTriangle {
  std::uint32_t v[3];            // indices into RasterFrame::vertices
  std::uint32_t material;        // index into RasterFrame::materials
  int x0, y0, x1, y1;            // pixels whose area it may touch, inclusive, clamped to the image
};

struct RasterFrame {
  int width = 0, height = 0;
  int bins_x = 0, bins_y = 0;
  glm::mat4 view_to_world{1.0f};
  glm::vec3 eye{0.0f};
  std::vector<ScreenVertex> vertices;
  std::vector<ScreenTriangle> triangles;
  std::vector<const Material*> materials;
  // Bin b holds triangles bin_triangles[bin_start[b] .. bin_start[b + 1]), in scene order.
  std::vector<std::uint32_t> bin_start;
  std::vector<std::uint32_t> bin_triangles;

  std::size_t input_triangles = 0;  // before clipping and culling of invisible ones

  Rect bin_rect(int bx, int by) const;
};

// Builds the frame's set-up on `pool` (or on the calling thread when null).
std::shared_ptr<const RasterFrame> build_raster_frame(const PreparedScene& scene,
                                                      const RenderSettings& settings,
                                                      ThreadPool* pool);

}  // namespace farm::raster
